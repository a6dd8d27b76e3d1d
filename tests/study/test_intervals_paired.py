"""Intervals over render seeds x sensor seeds and rank intervals from paired
comparisons (study/intervals.py: nested_interval, sensor_half_width,
paired_difference, paired_rank_interval; study/ranking.py, decisions.py).

t quantiles are printed-table values (an independent source, not scipy);
every expected interval is computed by hand from them.  Rules that would
compare a bound with a mean, pool renders that differ, or rank on marginal
intervals where the paired differences separate, fail here."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from cfa_mitsuba.study.intervals import (nested_interval, paired_difference, paired_rank_interval, rank_interval,
                                         sensor_half_width, t_interval)

#: Two-sided 95 % Student-t quantiles t(0.975, df), printed tables.
T975 = {1: 12.706, 2: 4.303, 4: 2.776, 5: 2.571, 9: 2.262, 19: 2.093}


def _sd(v):
    v = np.asarray(v, dtype=float)
    return math.sqrt(((v - v.mean()) ** 2).sum() / (v.size - 1))


# ------------------------------------------------------------ one value


def test_one_render_is_the_plain_t_interval():
    v = [1.0, 1.3, 0.8]
    assert nested_interval(v) == t_interval(v) == nested_interval(v, [0, 0, 0])


def test_one_realisation_per_render_is_the_plain_t_interval():
    """S = 1 (a noiseless capture, or one sensor seed): the renders are the
    independent units; the interval is t over them."""
    v = [1.0, 1.3, 0.8, 1.1]
    assert nested_interval(v, [0, 1, 2, 3]) == t_interval(v)


def test_renders_that_differ_make_the_render_seed_the_unit():
    """R = 2, S = 3; the renders differ by 2.0 against a within spread of
    0.1: the interval is t(0.975, 1) on the two render means."""
    v = [1.0, 1.1, 1.2, 3.0, 3.1, 3.2]
    mean, lo, hi, _, n = nested_interval(v, [0, 0, 0, 1, 1, 1])
    means = [1.1, 3.1]
    half = T975[1] * _sd(means) / math.sqrt(2)
    assert n == 6 and mean == pytest.approx(2.1)
    assert (lo, hi) == (pytest.approx(2.1 - half, abs=2e-3), pytest.approx(2.1 + half, abs=2e-3))
    # pooling the six as independent would give t(5): far narrower, and wrong
    assert hi - 2.1 > 3 * T975[5] * _sd(v) / math.sqrt(6)


def test_renders_that_agree_leave_the_sensor_variance_alone():
    """The renders' means agree better than the within spread predicts: no
    render component (its estimate is negative, set to 0), the interval is
    the sensor-only one, t(0.975, n - R) on the within-render mean square."""
    v = [1.0, 1.2, 1.1, 1.1, 1.0, 1.2]
    mean, lo, hi, _, n = nested_interval(v, [0, 0, 0, 1, 1, 1])
    ms_w = (0.02 + 0.02) / 4  # within-render sums of squares 0.02 and 0.02, 6 - 2 df
    half = T975[4] * math.sqrt(ms_w / 6)
    assert n == 6 and (lo, hi) == (pytest.approx(1.1 - half, abs=1e-3), pytest.approx(1.1 + half, abs=1e-3))
    assert hi - mean == pytest.approx(sensor_half_width(v, [0, 0, 0, 1, 1, 1]))


def test_ten_realisations_over_two_renders():
    """R = 2, S = 5, renders apart: t(1) on the 2 means, wider than the
    sensor-only half width t(0.975, 8) s_within / sqrt(10)."""
    rng = np.random.default_rng(3)
    a, b = 5.0 + 0.01 * rng.standard_normal(5), 6.0 + 0.01 * rng.standard_normal(5)
    v, g = np.r_[a, b], [0] * 5 + [1] * 5
    mean, lo, hi, _, n = nested_interval(v, g)
    half = T975[1] * _sd([a.mean(), b.mean()]) / math.sqrt(2)
    assert n == 10 and hi - mean == pytest.approx(half, rel=1e-3)
    s_within = math.sqrt((((a - a.mean()) ** 2).sum() + ((b - b.mean()) ** 2).sum()) / 8)
    assert sensor_half_width(v, g) == pytest.approx(2.306 * s_within / math.sqrt(10), rel=1e-3)  # t(0.975, 8)
    assert sensor_half_width(v, g) < 0.01 * (hi - mean)


def test_sensor_half_width_by_hand():
    v, g = [1.0, 1.2, 1.4, 3.0, 3.1, 3.2], [0, 0, 0, 1, 1, 1]
    s_within = math.sqrt((0.08 + 0.02) / 4)  # within-render sums of squares 0.08 and 0.02, 6 - 2 df
    assert sensor_half_width(v, g) == pytest.approx(T975[4] * s_within / math.sqrt(6), rel=1e-3)
    assert sensor_half_width([2.0, 4.0]) == pytest.approx(T975[1] * _sd([2.0, 4.0]) / math.sqrt(2), rel=1e-3)
    assert sensor_half_width([1.0, 2.0], [0, 1]) == 0.0  # one value per render: no sensor noise seen
    assert math.isnan(sensor_half_width([np.nan]))


def test_non_finite_realisations_are_left_out_with_their_group():
    mean, lo, hi, _, n = nested_interval([1.0, np.nan, 3.0, 3.0], [0, 0, 1, 1])
    assert n == 3 and math.isfinite(lo) and lo <= mean <= hi


# ---------------------------------------------------------- paired comparisons


def test_paired_difference_separates_where_the_marginal_intervals_overlap():
    """Two CFAs on three renders that differ a lot (common noise): their
    marginal intervals overlap, the per-realisation difference is always
    0.1 and its interval excludes 0."""
    a, b = np.array([1.00, 2.00, 3.01]), np.array([0.90, 1.90, 2.90])
    ta, tb = t_interval(a), t_interval(b)
    assert ta[1] < tb[2]  # marginal overlap
    _, best, _ = rank_interval([ta[0], tb[0]], [ta[1], tb[1]], [ta[2], tb[2]])
    assert best.tolist() == [1, 1]  # the marginal rule ties them
    mean, lo, hi, n = paired_difference(a, b)
    assert n == 3 and lo > 0 and mean == pytest.approx(0.1033, abs=1e-4)
    rank, best, worst = paired_rank_interval([a, b])
    assert best.tolist() == worst.tolist() == rank.tolist() == [1, 2]


@pytest.mark.parametrize("higher_is_better", [True, False])
def test_paired_ranks_in_both_directions(higher_is_better):
    """a > b > c in every realisation by 0.5 (separated); a and d differ by
    about +-0.1 alternately (overlapping: tied), d's mean 0.005 below a's."""
    base = np.array([1.0, 4.0, 2.0, 3.0])
    a = base + 1.0
    d = a + np.array([0.1, -0.1, 0.1, -0.12])
    b, c = base + 0.5, base
    rank, best, worst = paired_rank_interval([a, b, c, d], higher_is_better=higher_is_better)
    if higher_is_better:
        assert rank.tolist() == [1, 3, 4, 2]
        assert best.tolist() == [1, 3, 4, 1] and worst.tolist() == [2, 3, 4, 2]
    else:
        assert rank.tolist() == [4, 2, 1, 3]
        assert best.tolist() == [3, 2, 1, 3] and worst.tolist() == [4, 2, 1, 4]


def test_one_realisation_ranks_strictly_and_ties_only_equal_values():
    rank, best, worst = paired_rank_interval([[2.0], [1.0], [1.0]])
    assert rank.tolist() == [1, 2, 2]
    assert best.tolist() == [1, 2, 2] and worst.tolist() == [1, 3, 3]


def test_two_realisations_use_t_with_one_degree_of_freedom():
    """Differences 0.1 and 0.3: mean 0.2, half width 12.706 x 0.1414 / 1.414
    = 1.27: the interval contains 0, a tie; with differences 0.20 and 0.21
    it does not."""
    _, lo, hi, n = paired_difference([1.1, 2.3], [1.0, 2.0])
    assert n == 2 and lo == pytest.approx(0.2 - T975[1] * 0.1, abs=2e-3) and lo < 0 < hi
    assert paired_rank_interval([[1.1, 2.3], [1.0, 2.0]])[1].tolist() == [1, 1]
    assert paired_rank_interval([[1.20, 2.21], [1.0, 2.0]])[1].tolist() == [1, 2]


def test_ten_realisations():
    rng = np.random.default_rng(7)
    common = rng.standard_normal(10)  # the render's noise, common to both CFAs
    a, b = common + 0.05 + 0.01 * rng.standard_normal(10), common + 0.01 * rng.standard_normal(10)
    d = a - b
    mean, lo, hi, n = paired_difference(a, b)
    half = T975[9] * _sd(d) / math.sqrt(10)
    assert n == 10 and (lo, hi) == (pytest.approx(d.mean() - half, abs=1e-4), pytest.approx(d.mean() + half, abs=1e-4))
    assert lo > 0  # separated although each CFA's own interval is about +-0.7 wide
    assert t_interval(a)[1] < t_interval(b)[2]


def test_paired_differences_follow_the_render_seeds():
    """Realisations 0-2 on render 0, 3-5 on render 1: differences that
    depend on the render (0.1 on one, 0.5 on the other) are judged on the
    two render means with t(1), a tie; as six independent values they
    would separate."""
    a = np.array([1.10, 1.11, 1.09, 2.50, 2.51, 2.49])
    b = np.array([1.00, 1.01, 0.99, 2.00, 2.01, 1.99])
    g = [0, 0, 0, 1, 1, 1]
    assert paired_difference(a, b)[1] > 0  # ignoring the renders: separated
    assert paired_difference(a, b, g)[1] < 0 < paired_difference(a, b, g)[2]
    assert paired_rank_interval([a, b], g)[1].tolist() == [1, 1]


def test_missing_realisations_pair_on_the_common_ones():
    _, lo, _, n = paired_difference([1.0, np.nan, 3.0, 4.0], [0.5, 1.5, 2.5, 3.5])
    assert n == 3 and lo == pytest.approx(0.5)


#: Issue 46's intransitive case: S-CIELAB (dE00, lower is better) with POCS at 100 cd/m^2 in the
#: committed paper study, realisations 0-5 (render seeds 0, 0, 0, 1, 1, 1): under the per-value pre-test
#: Bayer < RGB4 and RGB4 < CMY3 were separated while Bayer against CMY3 was not.
ISSUE_46 = {"bayer": [1.029251, 1.031316, 1.030345, 1.024185, 1.028792, 1.016865],
            "rgb4": [1.034875, 1.049457, 1.043438, 1.045609, 1.045015, 1.031553],
            "cmy3": [1.067585, 1.063734, 1.063027, 1.061477, 1.071789, 1.079069]}


def _is_transitive(best, worst):
    """Rank intervals of one order: whenever i is surely above j (i's worst
    rank above j's best) and j above k, i is surely above k."""
    n = len(best)
    above = [[worst[i] < best[j] for j in range(n)] for i in range(n)]
    return all(not (above[i][j] and above[j][k]) or above[i][k]
               for i in range(n) for j in range(n) for k in range(n))


def test_rank_intervals_of_the_issue_case_are_transitive():
    g = [0, 0, 0, 1, 1, 1]
    _, best, worst = paired_rank_interval(list(ISSUE_46.values()), g, higher_is_better=False)
    assert _is_transitive(best.tolist(), worst.tolist())
    # the separations the issue found, given as the relation: the closure adds Bayer above CMY3
    from cfa_mitsuba.study.intervals import above_closure

    above = np.zeros((3, 3), dtype=bool)
    above[0, 1] = above[1, 2] = True  # bayer above rgb4, rgb4 above cmy3
    closed = above_closure(above)
    assert closed[0, 2] and not closed[2, 0] and closed.sum() == 3


def test_separations_are_closed_under_transitivity():
    """a above b and b above c on every realisation they share, but a and c
    share only three realisations, too few for their own interval to
    separate them: the ranks still put a above c (a, b, c ranks 1, 2, 3)."""
    a = np.array([3.0, 3.1, 2.9, 3.05, np.nan, np.nan, np.nan])
    b = np.array([2.0, 2.1, 1.9, 2.05, 2.0, 2.1, 1.95])
    c = np.array([np.nan, 0.0, 2.0, 0.6, 1.0, 1.1, 0.95])
    assert paired_difference(a, b)[1] > 0 and paired_difference(b, c)[1] > 0
    assert paired_difference(a, c)[1] < 0  # on its own, a against c is a tie
    rank, best, worst = paired_rank_interval([a, b, c])
    assert best.tolist() == worst.tolist() == [1, 2, 3]


# -------------------------------------------------------- mutated rules fail


def _paired_mutant(values):
    """The mutation to catch: a CFA counted better when the difference
    interval's lower bound exceeds the *other CFA's mean difference* (0)
    measured against its mean, i.e. separated whenever the mean difference
    is positive."""
    x = np.asarray(values, dtype=float)
    n = x.shape[0]
    above = np.array([[i != j and (x[i] - x[j]).mean() > 0 for j in range(n)] for i in range(n)])
    return 1 + above.sum(axis=0), n - above.sum(axis=1)


def test_a_paired_rule_on_the_mean_difference_fails():
    a, d = np.array([2.0, 5.0, 3.0, 4.0]), np.array([1.7, 5.3, 2.7, 4.35])
    _, best, worst = paired_rank_interval([a, d])
    assert best.tolist() == [1, 1] and worst.tolist() == [2, 2]
    assert _paired_mutant([a, d])[0].tolist() != best.tolist()


def _rank_interval_mutant(means, lows, highs):
    """rank_interval with one CFA's lower bound compared with another's mean."""
    m, lo, hi = (np.asarray(v, dtype=float) for v in (means, lows, highs))
    n = m.size
    best = np.array([1 + int(np.sum(lo > m[i])) for i in range(n)])
    worst = np.array([n - int(np.sum(m < lo[i])) for i in range(n)])
    return best, worst


def test_a_rank_interval_comparing_a_lower_bound_with_a_mean_fails():
    """The case of tests/study/test_intervals.py (b's top above a's bottom, below
    a's mean): the rule ties them, the mutant ranks a strictly first."""
    case = ([3.0, 2.0], [2.9, 1.05], [3.1, 2.95])
    _, best, worst = rank_interval(*case)
    mb, mw = _rank_interval_mutant(*case)
    assert best.tolist() == [1, 1] and worst.tolist() == [2, 2]
    assert (mb.tolist(), mw.tolist()) != (best.tolist(), worst.tolist())


# ------------------------------------------------------ scores and decisions


def _every(values_by_cfa, renders):
    """Scored rows of one metric per realisation, render seed per realisation."""
    return pd.DataFrame([dict(scene="puppy", cfa=c, demosaic="bilinear", luminance=100.0, metric="ssim", value=v,
                              unit="", realisation=k, render_seed=renders[k])
                         for c, vals in values_by_cfa.items() for k, v in enumerate(vals)])


def test_scores_rank_by_paired_differences():
    """Marginal score intervals overlap (render noise common to both CFAs);
    the paired differences separate: Table 3's ranks are strict."""
    from cfa_mitsuba.study.ranking import score_realisations
    from cfa_mitsuba.study.scoring import ScoreRange

    renders = [0, 0, 1, 1]
    rows = _every({"bayer": [0.80, 0.81, 0.60, 0.61], "rgbw1": [0.78, 0.79, 0.58, 0.59]}, renders)
    s = score_realisations(rows, {"ssim": ScoreRange(0.0, 1.0, ("",))}).set_index("cfa")
    assert s.loc["bayer", "score_ci_low"] < s.loc["rgbw1", "score_ci_high"]  # marginal intervals overlap
    assert s.loc["bayer", "total_rank_best"] == s.loc["bayer", "total_rank_worst"] == 1
    assert s.loc["rgbw1", "total_rank_best"] == s.loc["rgbw1", "metric_rank_best"] == 2
    assert s.loc["bayer", "demosaic_rank_worst"] == 1


def test_decision_aspects_use_paired_ranks():
    """Marginal intervals overlap (the renders move both CFAs together); the
    paired differences separate them: sharpness names bayer (its lead, 0.1
    in score, is past the practical difference of 5 % of an 80 cy/mm MTF50
    over an 80-wide range, 0.05)."""
    from cfa_mitsuba.study.decisions import score_outcome
    from cfa_mitsuba.study.scoring import ScoreRange

    every = pd.DataFrame([dict(cfa=c, demosaic="bilinear", metric="mtf", realisation=k, render_seed=k // 2,
                               score=v, raw_score=v, value=30 + 80 * v, unit="cy/mm")
                          for c, vals in (("bayer", (0.80, 0.81, 0.50, 0.52)), ("rgb4", (0.70, 0.70, 0.41, 0.42)))
                          for k, v in enumerate(vals)])
    out = score_outcome(every, {"mtf": ScoreRange(30.0, 110.0)}, ("mtf",))
    assert out.cfas == ["bayer"] and out.verdict == "winner"


def test_policy_summary_takes_a_policy_s_scores_only_when_its_ranges_are_theirs():
    """write_tables hands policy_summary the study's own per-realisation
    scores: the tables are the same as when it scores them itself, and a
    table made under other ranges (a config's override) is not taken."""
    from cfa_mitsuba.study.ranking import policy_ranges, policy_summary, score_realisations
    from cfa_mitsuba.study.scoring import ScoreRange

    renders = [0, 0, 1, 1]
    rows = _every({"bayer": [0.80, 0.81, 0.60, 0.61], "rgbw1": [0.78, 0.79, 0.58, 0.59],
                   "cmy1": [0.70, 0.74, 0.55, 0.50]}, renders)
    means = rows.groupby(["scene", "cfa", "demosaic", "luminance", "metric", "unit"], sort=False)["value"].mean()
    means = means.reset_index()
    paper, ideal = {"ssim": ScoreRange(0.0, 1.0, ("",))}, {"ssim": 1.0}
    plain = policy_summary(means, paper, ideal, realisations=rows)
    ranges, constant = policy_ranges("ideal", means, paper, ideal)
    own = score_realisations(rows, ranges, constant=constant)
    reused = policy_summary(means, paper, ideal, realisations=rows, scored=(ranges, constant, own))
    for a, b in zip(plain, reused):
        pd.testing.assert_frame_equal(a, b)
    # a table scored under other ranges: its totals would show if it were taken
    other = score_realisations(rows, {"ssim": ScoreRange(0.5, 0.9, ("",))}, constant=constant)
    wrong = policy_summary(means, paper, ideal, realisations=rows,
                           scored=({"ssim": ScoreRange(0.5, 0.9, ("",))}, constant, other))
    pd.testing.assert_frame_equal(wrong[1], plain[1])
    # the mutant that takes any table it is given fails that check
    forced = policy_summary(means, paper, ideal, realisations=rows, scored=(ranges, constant, other))
    assert not forced[1].equals(plain[1])
