"""study/scoring.py: eq. 8 normalisation, mean scores and ranks."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.metrics import NATURAL, get_metric, scored_metrics
from cfa_mitsuba.study.scoring import DEFAULT_RANGES, ScoreRange, default_ranges, msp_range_cpd, normalise, rank_table, score

#: The scored metrics (the paper's eight, from their records): each on a scene of its kind, in its unit.
SCORED = scored_metrics()
SCENE = {m: "puppy" if get_metric(m).scenes[0] == NATURAL else get_metric(m).scenes[0] for m in SCORED}
UNIT = {m: get_metric(m).unit for m in SCORED}
_RANGES = default_ranges()
# Per CFA: values at the best end, the middle, and the worst end of the paper's ranges.
VALUES = {
    "good": {m: _RANGES[m].best for m in SCORED},
    "mid": {m: 0.5 * (_RANGES[m].best + _RANGES[m].worst) for m in SCORED},
    "bad": {m: _RANGES[m].worst for m in SCORED},
}


def table(values=VALUES, demosaics=("bilinear", "pocs"), luminance=100.0):
    rows = []
    for d in demosaics:
        for cfa, vals in values.items():
            for m, v in vals.items():
                rows.append(dict(scene=SCENE[m], cfa=cfa, demosaic=d, luminance=luminance, metric=m, value=v, unit=UNIT[m]))
    return pd.DataFrame(rows)


def test_paper_ranges_are_the_defaults():
    r = DEFAULT_RANGES
    assert (r["delta-e"].worst, r["delta-e"].best) == (6.0, 2.2)
    assert (r["scielab"].worst, r["scielab"].best) == (9.5, 2.5)
    assert (r["achromatic"].worst, r["achromatic"].best) == (1.0, 0.5)
    assert (r["mdsi"].worst, r["mdsi"].best) == (0.5, 0.0)
    assert (r["ssim"].worst, r["ssim"].best) == (0.0, 1.0)
    assert (r["mtf"].worst, r["mtf"].best) == (30.0, 110.0)
    assert (r["haarpsi"].worst, r["haarpsi"].best) == (0.0, 1.0)
    # MSP: 0.04..0.30 cy/px (the paper's 20..150 px of 500) at our chirp's 25 px/deg
    assert (r["moire"].worst, r["moire"].best) == (1.0, 7.5)
    assert (msp_range_cpd(50).worst, msp_range_cpd(50).best) == (2.0, 15.0)
    # MTF range moved to another pitch: the same cy/px scores the same
    r28 = default_ranges(pixel_pitch_um=2.8)["mtf"]
    assert r28.normalise(70.0 * 2.2 / 2.8) == pytest.approx(DEFAULT_RANGES["mtf"].normalise(70.0))


def test_eq8_scores_means_and_ranks():
    s = score(table())
    by = s.set_index(["cfa", "demosaic", "metric"])["score"]
    assert np.allclose(by.xs("good", level="cfa"), 1.0)
    assert np.allclose(by.xs("mid", level="cfa"), 0.5)
    assert np.allclose(by.xs("bad", level="cfa"), 0.0)
    per = s.drop_duplicates(["cfa", "demosaic"]).set_index(["cfa", "demosaic"])
    assert per.loc[("good", "pocs"), "mean_score"] == pytest.approx(1.0)
    assert per.loc[("mid", "bilinear"), "n_metrics"] == len(SCORED)
    assert per.loc[("good", "bilinear"), "demosaic_rank"] == 1 and per.loc[("bad", "pocs"), "demosaic_rank"] == 3
    assert per.loc[("mid", "pocs"), "total_rank"] == 2
    assert set(s.loc[(s.cfa == "good"), "metric_rank"]) == {1}


def test_hand_computed_score_clipped_by_default_with_raw_score_kept():
    t = table()
    t.loc[(t.cfa == "good") & (t.metric == "delta-e"), "value"] = 1.44  # better than the range's best
    s = normalise(t)
    row = s[(s.cfa == "good") & (s.metric == "delta-e")].iloc[0]
    assert row["raw_score"] == pytest.approx((6.0 - 1.44) / (6.0 - 2.2)) and row["raw_score"] > 1.0
    assert row["score"] == 1.0 and row["out_of_range"]
    assert s["out_of_range"].sum() == 2  # the same row for both demosaics
    unclipped = normalise(t, clip=False)
    assert unclipped["score"].max() == pytest.approx((6.0 - 1.44) / (6.0 - 2.2))


def test_ranges_are_configurable_and_units_checked():
    t = table()
    s = normalise(t, {"ssim": (0.5, 1.0), "moire": msp_range_cpd(25.0)})
    assert s.loc[(s.cfa == "mid") & (s.metric == "ssim"), "score"].iloc[0] == pytest.approx(0.0)
    t2 = t.copy()
    t2.loc[t2.metric == "mtf", "unit"] = "cy/px"
    with pytest.raises(CfaMitsubaError, match="cy/px"):
        normalise(t2)
    ok = normalise(t2, {"mtf": ScoreRange(0.066, 0.242, ("cy/px",))})
    assert np.isfinite(ok["score"]).all()


def test_bad_tables_are_refused():
    t = table()
    with pytest.raises(CfaMitsubaError, match="lacks column"):
        score(t.drop(columns=["unit"]))
    bad = t.copy()
    bad.loc[0, "value"] = np.nan
    with pytest.raises(CfaMitsubaError, match="finite"):
        score(bad)
    with pytest.raises(CfaMitsubaError, match="duplicate"):
        score(pd.concat([t, t.iloc[:1]]))
    unknown = t.copy()
    unknown.loc[0, "metric"] = "psnr"
    with pytest.raises(CfaMitsubaError, match="psnr"):
        score(unknown)
    with pytest.raises(CfaMitsubaError):
        ScoreRange(1.0, 1.0)


def test_rank_table_is_table_3_and_fig_17():
    s = score(pd.concat([table(), table(luminance=12.0)]))
    with pytest.raises(CfaMitsubaError, match="luminance"):
        rank_table(s)
    wide = rank_table(s, luminance=100.0)
    assert list(wide.index) == ["bilinear", "pocs", "total"] and set(wide.columns) == set(VALUES)
    assert wide.loc["total", "mid"] == pytest.approx(0.5)
    ranks = rank_table(s, luminance=100.0, value="demosaic_rank")
    assert ranks.loc["total", "good"] == 1
