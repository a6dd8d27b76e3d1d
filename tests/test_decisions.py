"""The decision rule (cfa_mitsuba/study/decisions.py): a CFA is the winner only
when its rank interval is exactly 1, otherwise every CFA whose rank interval
contains 1 is named as tied."""

from __future__ import annotations

import pandas as pd
import pytest

from cfa_mitsuba.report.decision_panel import summary_cards, sweep_lines
from cfa_mitsuba.study.decisions import decide, decisions_table


@pytest.mark.parametrize("scores, lows, highs, top, verdict", [
    ([0.9, 0.5, 0.4], [0.88, 0.45, 0.35], [0.92, 0.55, 0.45], ["a"], "winner"),        # separated
    ([0.9, 0.85, 0.5], [0.80, 0.80, 0.45], [0.95, 0.90, 0.55], ["a", "b"], "tie"),      # overlapping
    ([0.9, 0.85, 0.5], [0.85, 0.80, 0.45], [0.95, 0.85, 0.55], ["a", "b"], "tie"),      # touching ends overlap
    ([0.5, 0.9, 0.85], [0.45, 0.80, 0.80], [0.55, 0.95, 0.90], ["b", "c"], "tie"),      # order of input kept out
    ([0.6, 0.6], [0.6, 0.6], [0.6, 0.6], ["a", "b"], "tie"),                            # one realisation, equal
])
def test_decide(scores, lows, highs, top, verdict):
    got_top, got_verdict, detail = decide(["a", "b", "c"][:len(scores)], scores, lows, highs)
    assert got_top == top and got_verdict == verdict
    for name in top:
        assert name in detail


def _scores(rows):
    return pd.DataFrame([dict(cfa=c, luminance=100, demosaic=d, mean_score=m, mean_score_ci_low=m - h,
                              mean_score_ci_high=m + h, total_score=t, total_score_ci_low=t - th,
                              total_score_ci_high=t + th, total_rank_best=b, total_rank_worst=w)
                         for c, d, m, h, t, th, b, w in rows])


def test_overall_row_and_cards_follow_the_rule():
    s = _scores([("bayer", "bilinear", 0.60, 0.01, 0.60, 0.02, 1, 2), ("rgb4", "bilinear", 0.59, 0.01, 0.59, 0.02, 1, 2),
                 ("cmy1", "bilinear", 0.30, 0.01, 0.30, 0.01, 3, 3)])
    every = pd.DataFrame(columns=["cfa", "metric", "realisation", "score"])
    d = decisions_table(s, every)
    overall = d[d["aspect"] == "overall"].iloc[0]
    assert overall["cfas"] == "bayer rgb4" and overall["verdict"] == "tie"
    assert set(d[d["aspect"] != "overall"]["verdict"]) == {"unmeasured"}
    cards = summary_cards(s, 100, ["bilinear"])
    assert cards[0][0] == "Tied first overall" and cards[0][1] == "bayer, rgb4"
    s2 = _scores([("bayer", "bilinear", 0.60, 0.01, 0.60, 0.005, 1, 1), ("rgb4", "bilinear", 0.50, 0.01, 0.50, 0.005, 2, 2)])
    assert summary_cards(s2, 100, ["bilinear"])[0][:2] == ("Best CFA overall", "bayer")


def test_aspect_rows_from_realisations():
    every = pd.DataFrame([dict(cfa=c, metric="mtf", realisation=r, score=v)
                          for c, vals in (("bayer", (0.80, 0.81, 0.82)), ("rgb4", (0.50, 0.51, 0.52)))
                          for r, v in enumerate(vals)])
    s = _scores([("bayer", "bilinear", 0.60, 0.01, 0.60, 0.02, 1, 1), ("rgb4", "bilinear", 0.59, 0.01, 0.50, 0.02, 2, 2)])
    d = decisions_table(s, every).set_index("aspect")
    assert d.loc["sharpness", "cfas"] == "bayer" and d.loc["sharpness", "verdict"] == "winner"
    assert d.loc["colour", "verdict"] == "unmeasured"


def test_sweep_line_reads_the_config_as_written():
    cfg = {"sweeps": [{"scenes": ["puppy"], "metrics": ["scielab", "ssim"], "values": {"luminance": [12.0, 100.0]}}]}
    assert sweep_lines(cfg, str.upper) == ["SCIELAB, SSIM on puppy at luminance 12, 100 cd/m²"]
    assert "None" not in sweep_lines({"sweeps": [{"scenes": ["x"], "values": {"f_number": [2.8, 4]}}]}, str)[0]


def test_low_light_level_passes_over_levels_where_every_cfa_clips_to_the_bound():
    """At 0.3 cd/m^2 every CFA's S-CIELAB and SSIM lie past the range's worst end (all score 0: a
    tie that says nothing); the low-light decision is taken at 1 cd/m^2, the lowest level at which
    the scores differ, and the detail names the level passed over."""
    from cfa_mitsuba.study.decisions import _lowlight, write_decisions  # noqa: F401

    ranges = {"scielab": (10.0, 0.0), "ssim": (0.0, 1.0)}
    rows = []
    for lum, vals in ((0.3, {"bayer": (20.0, -0.1), "rgbw1": (25.0, -0.2)}),
                      (1.0, {"bayer": (8.0, 0.30), "rgbw1": (5.0, 0.50)}),
                      (100.0, {"bayer": (2.0, 0.90), "rgbw1": (2.5, 0.88)})):
        for cfa, (sc, ss) in vals.items():
            for r in range(3):
                for metric, v, unit in (("scielab", sc + 0.01 * r, "dE00"), ("ssim", ss + 0.001 * r, "")):
                    rows.append(dict(scene="puppy", cfa=cfa, demosaic="bilinear", luminance=lum, metric=metric,
                                     value=v, unit=unit, realisation=r, base=lum == 100.0))
    low, lum, skipped = _lowlight(pd.DataFrame(rows), ranges, True, {"scielab", "ssim"})
    assert lum == 1.0 and skipped == (0.3,)
    assert set(low["luminance"]) == {1.0} and low.groupby("cfa")["score"].mean()["rgbw1"] > 0
    s = _scores([("bayer", "bilinear", 0.60, 0.01, 0.60, 0.02, 1, 1), ("rgbw1", "bilinear", 0.5, 0.01, 0.5, 0.02, 2, 2)])
    d = decisions_table(s, pd.DataFrame(columns=["cfa", "metric", "realisation", "score"]), low, lum, skipped)
    row = d.set_index("aspect").loc["low light"]
    assert row["cfas"] == "rgbw1" and row["verdict"] == "winner"
    assert "at 1 cd/m^2 (the lowest level at which the CFAs' scores differ; at 0.3 cd/m^2 every CFA" in row["detail"]
    # no level differs: the lowest is kept (a tie, said as such)
    flat = pd.DataFrame([r for r in rows if r["luminance"] != 1.0])
    low2, lum2, skipped2 = _lowlight(flat, ranges, True, {"scielab", "ssim"})
    assert lum2 == 0.3 and skipped2 == ()
