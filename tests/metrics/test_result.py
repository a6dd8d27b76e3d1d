"""summarise_array's order statistics (metrics/_result.py) against numpy's
np.median and np.percentile(95), which they stand in for: the same bits."""

import numpy as np
import pytest

from cfa_mitsuba.metrics._result import median_and_p95, summarise_array


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 19, 20, 21, 40, 41, 1000, 1001, 388_800])
def test_median_and_p95_equal_numpy_bit_for_bit(n):
    rng = np.random.default_rng(n)
    for values in (rng.gamma(2.0, 1.5, n), rng.normal(0, 1e3, n), np.round(rng.random(n) * 5)):  # ties too
        median, p95 = median_and_p95(values.copy())
        assert median == float(np.median(values)) and p95 == float(np.percentile(values, 95)), n


def test_every_fraction_of_the_interpolation():
    # (n - 1) x 0.95 takes fractions on both sides of 1/2, where numpy's lerp changes formula
    rng = np.random.default_rng(1)
    fractions = set()
    for n in range(2, 400):
        values = rng.normal(0, 1, n) * 10.0 ** rng.integers(-3, 4)
        fractions.add(round((n - 1) * 0.95 % 1, 2))
        assert median_and_p95(values) == (float(np.median(values)), float(np.percentile(values, 95))), n
    assert min(fractions) < 0.1 and max(fractions) > 0.9


def test_summary_ignores_non_finite_values_and_leaves_the_input_alone():
    rng = np.random.default_rng(3)
    a = rng.random((30, 40))
    before = a.copy()
    clean = summarise_array(a)
    np.testing.assert_array_equal(a, before)
    finite = a.ravel()
    assert clean == {"shape": [30, 40], "mean": float(finite.mean()), "median": float(np.median(finite)),
                     "p95": float(np.percentile(finite, 95)), "min": float(finite.min()), "max": float(finite.max())}
    a[3, 4], a[5, 6], a[7, 8] = np.nan, np.inf, -np.inf
    got = summarise_array(a)
    kept = a[np.isfinite(a)]
    assert got["median"] == float(np.median(kept)) and got["mean"] == float(kept.mean()) and got["shape"] == [30, 40]
    assert summarise_array(np.full((2, 2), np.nan)) == {"shape": [2, 2], "n": 0}
    huge = np.array([1e308, 1e308, 1.0])  # a sum that overflows: every value is still finite
    assert summarise_array(huge)["max"] == 1e308 and summarise_array(huge)["median"] == 1e308
