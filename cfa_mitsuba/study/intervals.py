"""Uncertainty of a study's numbers: several noise realisations of every
capture, their mean and 95 % interval, and rank intervals.

Each value of metrics.csv is the mean over ``n`` realisations (the noise
seeds of one camera; the render and everything else fixed) with the
two-sided 95 % Student-t interval of that mean,

    mean +- t(0.975, n - 1) s / sqrt(n)

(s the sample standard deviation; with n = 1 the interval is the value
itself and ``n`` says so).  Scores are computed per realisation and
averaged the same way, so a CFA's mean score carries its own interval.

Rank intervals follow from the score intervals: a CFA ranks at best one
below every CFA whose interval lies wholly above its own, and at worst just
above every CFA whose interval lies wholly below; CFAs whose intervals
overlap are tied (their rank intervals overlap).
"""

from __future__ import annotations

__all__ = ["CONFIDENCE", "t_interval", "aggregate", "rank_interval"]

import numpy as np

#: Two-sided confidence of every interval.
CONFIDENCE = 0.95


def t_interval(values) -> tuple[float, float, float, float, int]:
    """(mean, ci_low, ci_high, std, n) of finite ``values`` (Student-t, 95 %)."""
    from scipy.stats import t

    v = np.asarray(values, dtype=np.float64)
    v = v[np.isfinite(v)]
    n = int(v.size)
    if n == 0:
        return (np.nan, np.nan, np.nan, np.nan, 0)
    mean = float(v.mean())
    if n == 1:
        return (mean, mean, mean, 0.0, 1)
    sd = float(v.std(ddof=1))
    half = float(t.ppf(0.5 + CONFIDENCE / 2, n - 1)) * sd / np.sqrt(n)
    return (mean, mean - half, mean + half, sd, n)


def aggregate(df, keys: list[str], column: str = "value", prefix: str = ""):
    """One row per ``keys`` group: the mean of ``column`` (named ``prefix +
    column``) and its ``ci_low``, ``ci_high``, ``std``, ``n`` (prefixed)."""
    import pandas as pd

    rows = []
    for k, g in df.groupby(keys, sort=False, dropna=False):
        mean, lo, hi, sd, n = t_interval(g[column])
        # pandas gives a 1-tuple for a one-key list in some versions and the bare key in others
        rows.append((*(k if isinstance(k, tuple) else (k,)), mean, lo, hi, sd, n))
    cols = [f"{prefix}{column}", f"{prefix}ci_low", f"{prefix}ci_high", f"{prefix}std", f"{prefix}n"]
    return pd.DataFrame(rows, columns=[*keys, *cols])


def rank_interval(means, lows, highs, *, higher_is_better: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rank, best rank, worst rank) of each item (1 = best).

    ``rank`` ranks the means ('min' for equal means); the interval counts
    the items whose interval lies wholly on the better side (best rank is
    one more than that) and those not wholly on the worse side (the worst
    rank).

    Examples
    --------
    >>> r, lo, hi = rank_interval([0.9, 0.85, 0.5], [0.88, 0.80, 0.45], [0.92, 0.89, 0.55])
    >>> r.tolist(), lo.tolist(), hi.tolist()
    ([1, 2, 3], [1, 1, 3], [2, 2, 3])
    """
    m = np.asarray(means, dtype=np.float64)
    lo = np.asarray(lows, dtype=np.float64)
    hi = np.asarray(highs, dtype=np.float64)
    if not higher_is_better:
        m, lo, hi = -m, -hi, -lo
    n = m.size
    rank = np.array([1 + int(np.sum(m > m[i])) for i in range(n)])
    best = np.array([1 + int(np.sum(lo > hi[i])) for i in range(n)])
    worst = np.array([n - int(np.sum(hi < lo[i])) for i in range(n)])
    return rank, best, worst
