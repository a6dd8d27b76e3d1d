"""The decision rule (cfa_mitsuba/study/decisions.py, lowlight.py,
alternatives.py): a CFA is the winner only when its rank interval is exactly
1 and its lead is at least the practical difference; otherwise the CFAs
that can rank first are a tie, or the leader and those within the practical
difference are equivalent; nothing is decided from clipped scores; and each
decision says which reasonable alternative would change it."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from cfa_mitsuba.report.decision_panel import summary_cards, sweep_lines
from cfa_mitsuba.study.alternatives import ScoringSetup, score_alternatives
from cfa_mitsuba.study.decisions import CLIPPED_LIMIT, decide, decisions_table, practical_threshold, score_outcome
from cfa_mitsuba.study.scoring import ScoreRange


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


@pytest.mark.parametrize("higher_is_better", [True, False])
def test_a_separated_lead_below_the_practical_difference_is_equivalent(higher_is_better):
    """a leads b by 0.04 and c by 0.30, each separated; with a practical
    difference of 0.1 a is not a winner: a and b are equivalent, c is not."""
    sign = 1 if higher_is_better else -1
    s = [sign * 0.90, sign * 0.86, sign * 0.60]
    lo, hi = [v - 0.005 for v in s], [v + 0.005 for v in s]
    top, verdict, detail = decide(["a", "b", "c"], s, lo, hi, practical=0.1, higher_is_better=higher_is_better)
    assert (top, verdict) == (["a", "b"], "equivalent")
    assert "0.040" in detail and "0.100" in detail
    assert decide(["a", "b", "c"], s, lo, hi, practical=0.04, higher_is_better=higher_is_better)[:2] == (["a"], "winner")


def test_practical_threshold_by_hand():
    """One practical difference on one of the metrics, averaged over them:
    dE00 0.8 over a 4-wide range (0.2), MTF50 5 % of 80 cy/mm over a 40-wide
    range (0.1): (0.2 + 0.1) / 2 / 2."""
    rows = pd.DataFrame({"metric": ["delta-e", "mtf", "mtf"], "value": [2.0, 70.0, 90.0],
                         "unit": ["dE00", "cy/mm", "cy/mm"]})
    ranges = {"delta-e": ScoreRange(4.0, 0.0), "mtf": ScoreRange(60.0, 100.0)}
    assert practical_threshold(rows, ranges) == pytest.approx((0.2 + 0.1) / 4)


def _realisations(values, metric="mtf", unit="cy/mm", censored=None, demosaic="bilinear", scene="slanted-edge"):
    """Per-realisation metric rows: {cfa: [values]} (one render)."""
    return pd.DataFrame([dict(scene=scene, cfa=c, demosaic=demosaic, luminance=100.0, metric=metric, value=v,
                              unit=unit, realisation=k, render_seed=0,
                              censored=bool(censored and censored.get(c, [False] * 9)[k]))
                         for c, vals in values.items() for k, v in enumerate(vals)])


def _means(real):
    return real.groupby(["scene", "cfa", "demosaic", "luminance", "metric", "unit"], sort=False)["value"].mean() \
        .reset_index()


def test_nothing_is_decided_from_clipped_scores():
    """Every CFA's MTF50 past the range's best end: each score clips to 1;
    the rank intervals would separate the raw values, but more than 10 % of
    the scores are clipped, so no CFA is named."""
    real = _realisations({"a": [130.0, 131.0, 129.0], "b": [120.0, 121.0, 119.0]})
    setup = ScoringSetup({"mtf": ScoreRange(30.0, 110.0)}, {}, "paper")
    ranges, constant = setup.ranges("paper", _means(real))
    out = score_outcome(setup.every(real, ranges, constant), ranges, ("mtf",))
    assert out.verdict == "clipped" and out.answer == "" and out.clipped_share == 1.0 > CLIPPED_LIMIT


def test_a_decision_names_the_alternative_that_changes_it():
    """Two metrics; a wins on the mean, b wins once ssim is left out: the
    overall row is not robust and its depends_on names 'without ssim'."""
    mtf = _realisations({"a": [80.0, 80.5, 79.5], "b": [90.0, 90.5, 89.5], "c": [60.0, 60.2, 59.8]})
    ssim = _realisations({"a": [0.99, 0.991, 0.989], "b": [0.80, 0.801, 0.799], "c": [0.70, 0.71, 0.69]},
                         metric="ssim", unit="", scene="puppy")
    real = pd.concat([mtf, ssim], ignore_index=True)
    setup = ScoringSetup({"mtf": ScoreRange(30.0, 110.0), "ssim": ScoreRange(0.0, 1.0)}, {}, "paper")
    d = decisions_table(score_alternatives(setup, real, _means(real)), None, 100.0).set_index("aspect")
    row = d.loc["overall"]
    assert row["cfas"].split()[0] == "a" and row["verdict"] == "winner"
    assert not row["robust"] and "without ssim" in row["depends_on"].split("; ")
    assert "without ssim: b" in row["detail"]
    assert d.loc["sharpness", "cfas"].split()[0] == "b"


def test_the_moire_convention_is_an_alternative_when_a_value_is_a_bound():
    """a's MSP is a bound in every realisation, b measured at 18 cy/deg:
    with the bound scored at the midpoint (21.05) or at the bound (24) a
    leads by more than the practical difference; at the best measured
    value (b's 18.1) a ties b: depends_on says so."""
    top = 24.0
    real = _realisations({"a": [top] * 3, "b": [18.0, 18.1, 17.9], "c": [5.0, 5.1, 4.9]}, metric="moire",
                         unit="cy/deg", censored={"a": [True] * 3}, scene="chirp")
    setup = ScoringSetup({"moire": ScoreRange(2.0, top)}, {}, "paper")
    alts = score_alternatives(setup, real, _means(real))
    assert [a.label for a in alts] == ["", "ranges: study", "ranges: ideal", "censored at the bound",
                                       "censored at best measured"]
    d = decisions_table(alts, None, 100.0).set_index("aspect")
    row = d.loc["moire"]
    assert row["cfas"] == "a" and row["verdict"] == "winner"
    assert "censored at best measured" in row["depends_on"] and "censored at the bound" not in row["depends_on"]


def _snr_rows():
    """ysnr on the gray bar at 1, 10, 100 cd/m^2: a reaches YSNR 10 at about
    3 cd/m^2, b at about 30 (a full stop and more), three realisations."""
    rows = []
    for cfa, k in (("a", 10 / np.sqrt(3.0)), ("b", 10 / np.sqrt(30.0))):
        for lum in (1.0, 10.0, 100.0):
            for r in range(3):
                rows.append(dict(scene="gray-bar", cfa=cfa, demosaic="bilinear", luminance=lum, metric="ysnr",
                                 value=k * np.sqrt(lum) * (1 + 0.01 * (r - 1)), unit="", realisation=r,
                                 render_seed=0, base=lum == 100.0))
    return rows


def test_low_light_is_decided_on_snr10_and_on_values_not_clipped_scores():
    """At 1 cd/m^2 every S-CIELAB is past the range's worst end (every score
    clips to 0), but the values differ: the row decides on the values and
    says how many scores clip; SNR10 decides the low-light row."""
    rows = _snr_rows()
    for cfa, v in (("a", 30.0), ("b", 20.0)):
        for lum, val in ((1.0, v), (100.0, 2.0)):
            for r in range(3):
                rows.append(dict(scene="puppy", cfa=cfa, demosaic="bilinear", luminance=lum, metric="scielab",
                                 value=val + 0.01 * r, unit="dE00", realisation=r, render_seed=0, base=lum == 100.0))
    real = pd.DataFrame(rows)
    d = decisions_table([], real, 100.0, {"scielab": ScoreRange(10.0, 0.0)}).set_index("aspect")
    snr = d.loc["low light"]
    assert snr["cfas"] == "a" and snr["verdict"] == "winner" and snr["quantity"].startswith("SNR10")
    sc = d.loc["low light: scielab"]
    assert sc["cfas"] == "b" and sc["verdict"] == "winner" and sc["luminance"] == 1.0
    assert sc["clipped_share"] == 1.0 and "values" in sc["quantity"]
    # the low-light row knows the picture disagrees with SNR10 at that level
    assert not snr["robust"] and snr["depends_on"] == "scielab at 1 cd/m^2"


def test_overall_interval_is_table_3s_and_demosaic_rows_share_its_model():
    """The overall row is recomputed from the realisations, and gives Table
    3's total score, interval and rank interval (scores.csv); with two
    demosaics whose scores are the same realisation by realisation, the
    total's interval is each demosaic row's (one model, not one 10x narrower)."""
    from cfa_mitsuba.study.ranking import score_realisations

    rng = np.random.default_rng(4)
    rows = []
    for cfa, level in (("a", 80.0), ("b", 70.0), ("c", 60.0)):
        vals = level + rng.normal(0, 1.0, 6)
        for dem in ("bilinear", "pocs"):
            rows.append(_realisations({cfa: vals}, demosaic=dem))
    real = pd.concat(rows, ignore_index=True)
    setup = ScoringSetup({"mtf": ScoreRange(30.0, 110.0)}, {}, "paper")
    alts = score_alternatives(setup, real, _means(real))
    d = decisions_table(alts, None, 100.0).set_index("aspect")
    s = score_realisations(None, alts[0].ranges, every=alts[0].every).drop_duplicates(["cfa", "demosaic"])
    tot = s.drop_duplicates("cfa").set_index("cfa")
    assert f"a {tot.loc['a', 'total_score']:.3f} [{tot.loc['a', 'total_score_ci_low']:.3f}, " \
           f"{tot.loc['a', 'total_score_ci_high']:.3f}]" in d.loc["overall", "detail"]
    per = s.set_index(["cfa", "demosaic"])
    for cfa in "abc":
        width = tot.loc[cfa, "total_score_ci_high"] - tot.loc[cfa, "total_score_ci_low"]
        for dem in ("bilinear", "pocs"):
            assert width == pytest.approx(per.loc[(cfa, dem), "mean_score_ci_high"]
                                          - per.loc[(cfa, dem), "mean_score_ci_low"])


def _scores(rows):
    return pd.DataFrame([dict(cfa=c, luminance=100, demosaic=d, mean_score=m, mean_score_ci_low=m - h,
                              mean_score_ci_high=m + h, total_score=t, total_score_ci_low=t - th,
                              total_score_ci_high=t + th, total_rank_best=b, total_rank_worst=w)
                         for c, d, m, h, t, th, b, w in rows])


def test_cards_follow_the_decisions_when_the_study_has_them():
    s = _scores([("bayer", "bilinear", 0.60, 0.01, 0.60, 0.005, 1, 1), ("rgb4", "bilinear", 0.59, 0.01, 0.59, 0.005, 2, 2)])
    decisions = pd.DataFrame([dict(aspect="overall", cfas="bayer rgb4", verdict="equivalent", robust=True,
                                   depends_on="", detail="")])
    card = summary_cards(s, 100, ["bilinear"], decisions)[0]
    assert card[0] == "Equivalent first overall" and card[1] == "bayer, rgb4"
    decisions.loc[0, ["cfas", "verdict", "robust", "depends_on"]] = ["bayer", "winner", False, "without moire"]
    card = summary_cards(s, 100, ["bilinear"], decisions)[0]
    assert card[:2] == ("Best CFA overall", "bayer") and "depends on: without moire" in card[2]
    # an older results folder without decisions.csv: the rank intervals alone
    assert summary_cards(s, 100, ["bilinear"])[0][:2] == ("Best CFA overall", "bayer")


def test_sweep_line_reads_the_config_as_written():
    cfg = {"sweeps": [{"scenes": ["puppy"], "metrics": ["scielab", "ssim"], "values": {"luminance": [12.0, 100.0]}}]}
    assert sweep_lines(cfg, str.upper) == ["SCIELAB, SSIM on puppy at luminance 12, 100 cd/m²"]
    assert "None" not in sweep_lines({"sweeps": [{"scenes": ["x"], "values": {"f_number": [2.8, 4]}}]}, str)[0]
