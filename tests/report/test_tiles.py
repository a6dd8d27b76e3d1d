"""The "CFAs by family" figure (report/tiles.py) draws Table 3's numbers:
each bar's label is the CFA's mean score for that demosaic in scores.csv,
the cell Table 3 prints, so a bound is scored by the one rule
(study/censored.py) in both.  Issue 46 found the figure scoring the mean
values again on its own (Bayer 0.40 against Table 3's 0.368)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from cfa_mitsuba.report.results import load_results
from cfa_mitsuba.report.tiles import tiles_by_family

REPO = Path(__file__).resolve().parents[2]


def test_every_bar_is_the_table_3_cell():
    import matplotlib.pyplot as plt

    res = load_results(REPO / "docs" / "example-report")
    fig = tiles_by_family(res)
    ax = fig.figure.axes[0]
    labels = [t.get_text() for t in ax.texts]
    scores = pd.read_csv(REPO / "docs" / "example-report" / "scores.csv")
    cells = scores[scores["luminance"] == res.primary_luminance].drop_duplicates(["cfa", "demosaic"])
    # the bars in drawing order: family by family, CFA by CFA, demosaic by demosaic
    bars = [t for t in labels if t.replace(".", "", 1).isdigit()]
    expected = sorted(f"{v:.2f}" for v in cells["mean_score"])
    assert sorted(bars) == expected
    bayer = cells[cells["cfa"] == "bayer"].set_index("demosaic")["mean_score"]
    widths = sorted(round(p.get_width() / 4.0, 9) for p in ax.patches if abs(p.get_height() - 0.17) < 0.01)
    assert all(round(v, 9) in widths for v in bayer)
    plt.close(fig.figure)
