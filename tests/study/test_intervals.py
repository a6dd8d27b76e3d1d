"""The interval and rank logic on its own (study/intervals.py): Student-t
intervals for 1, 2 and 10 realisations against the printed t quantiles, and
rank intervals in both directions, for separated, overlapping and touching
intervals.  A rank rule that compares one CFA's lower bound with another's
mean, or forgets the direction, fails here."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from cfa_mitsuba.study.intervals import aggregate, rank_interval, t_interval

#: Two-sided 95 % Student-t quantiles t(0.975, df) from printed tables
#: (an independent source: not scipy).
T975 = {1: 12.706, 9: 2.262}


def test_one_realisation_is_a_point_with_n_1():
    assert t_interval([3.5]) == (3.5, 3.5, 3.5, 0.0, 1)


def test_no_finite_value_gives_nan_and_n_0():
    mean, lo, hi, sd, n = t_interval([np.nan, np.inf])
    assert n == 0 and all(math.isnan(v) for v in (mean, lo, hi, sd))


def test_two_realisations_use_t_with_one_degree_of_freedom():
    mean, lo, hi, sd, n = t_interval([1.0, 3.0])
    assert (mean, sd, n) == (2.0, pytest.approx(math.sqrt(2.0)), 2)
    half = T975[1] * math.sqrt(2.0) / math.sqrt(2.0)
    assert (lo, hi) == (pytest.approx(2.0 - half, abs=2e-3), pytest.approx(2.0 + half, abs=2e-3))


def test_ten_realisations_use_t_with_nine_degrees_of_freedom():
    v = np.arange(10.0)
    mean, lo, hi, sd, n = t_interval(v)
    sd_hand = math.sqrt(sum((x - 4.5) ** 2 for x in v) / 9)
    half = T975[9] * sd_hand / math.sqrt(10)
    assert (mean, n) == (4.5, 10) and sd == pytest.approx(sd_hand)
    assert lo == pytest.approx(4.5 - half, abs=1e-3) and hi == pytest.approx(4.5 + half, abs=1e-3)


def test_non_finite_values_are_left_out():
    assert t_interval([1.0, np.nan, 3.0])[4] == 2


def test_aggregate_groups_and_names_its_columns():
    df = pd.DataFrame({"cfa": ["a", "a", "b", "b", "b"], "value": [1.0, 3.0, 5.0, 5.0, 5.0]})
    out = aggregate(df, ["cfa"], "value", prefix="s_").set_index("cfa")
    assert list(out.columns) == ["s_value", "s_ci_low", "s_ci_high", "s_std", "s_n"]
    assert out.loc["a", "s_value"] == 2.0 and out.loc["b", "s_n"] == 3
    assert out.loc["b", "s_ci_low"] == out.loc["b", "s_ci_high"] == 5.0  # no spread, no width


@pytest.mark.parametrize("higher_is_better", [True, False])
def test_separated_intervals_give_strict_ranks(higher_is_better):
    means, lows, highs = [3.0, 2.0, 1.0], [2.9, 1.9, 0.9], [3.1, 2.1, 1.1]
    rank, best, worst = rank_interval(means, lows, highs, higher_is_better=higher_is_better)
    expect = [1, 2, 3] if higher_is_better else [3, 2, 1]
    assert rank.tolist() == best.tolist() == worst.tolist() == expect


@pytest.mark.parametrize("higher_is_better", [True, False])
def test_overlapping_intervals_tie(higher_is_better):
    # a and b overlap; c is separated from both
    means, lows, highs = [3.0, 2.8, 1.0], [2.7, 2.5, 0.9], [3.3, 3.1, 1.1]
    rank, best, worst = rank_interval(means, lows, highs, higher_is_better=higher_is_better)
    if higher_is_better:
        assert rank.tolist() == [1, 2, 3]
        assert best.tolist() == [1, 1, 3] and worst.tolist() == [2, 2, 3]
    else:
        assert rank.tolist() == [3, 2, 1]
        assert best.tolist() == [2, 2, 1] and worst.tolist() == [3, 3, 1]


def test_an_interval_that_reaches_past_a_mean_but_not_the_interval_still_ties():
    """b's upper bound (2.95) lies below a's mean (3.0) but above a's lower
    bound (2.9): the intervals overlap, so they tie.  A rule comparing a
    bound with the other's mean would call a strictly first."""
    rank, best, worst = rank_interval([3.0, 2.0], [2.9, 1.05], [3.1, 2.95])
    assert best.tolist() == [1, 1] and worst.tolist() == [2, 2]


def test_touching_intervals_tie_and_point_values_rank_strictly():
    _, best, worst = rank_interval([2.0, 1.0], [1.5, 1.0], [2.5, 1.5])  # touch at 1.5
    assert best.tolist() == [1, 1] and worst.tolist() == [2, 2]
    rank, best, worst = rank_interval([2.0, 1.0], [2.0, 1.0], [2.0, 1.0])  # one realisation each
    assert best.tolist() == worst.tolist() == rank.tolist() == [1, 2]


def test_equal_means_share_the_better_rank():
    rank, _, _ = rank_interval([1.0, 1.0, 0.5], [0.9, 0.9, 0.4], [1.1, 1.1, 0.6])
    assert rank.tolist() == [1, 1, 3]
