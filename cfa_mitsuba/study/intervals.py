"""Uncertainty of a study's numbers: realisations of every value over
render seeds and sensor-noise seeds, their mean and 95 % interval, and rank
intervals from paired comparisons.

**Realisations.**  A value of metrics.csv is the mean over ``n = R x S``
realisations: ``R`` render seeds (``render_seeds``: independent Monte-Carlo
renders of a path-traced scene; 1 for a chart, whose render is
deterministic) crossed with ``S`` sensor-noise seeds (``seeds``).
Realisation ``k = r S + s`` uses render seed ``r`` and a sensor seed of its
own; the same ``k`` means the same render and the same sensor seed for every
CFA (study/tasks.py, ``realisation_seeds``), so realisations pair across CFAs.

**The interval of a mean** (:func:`nested_interval`).  Realisations that
share a render are not independent (the render's noise is common to them),
so the interval is that of a nested (two-stage) design (Montgomery, *Design
and Analysis of Experiments*, 8th ed., s. 14.1): with one render (R = 1),
or one realisation per render (S = 1), the realisations are independent and
the interval is the Student-t one,

    mean +- t(0.975, n - 1) s / sqrt(n)

(s the sample standard deviation; with n = 1 the interval is the value
itself and ``n`` says so).  With R > 1 and S > 1 the render seed is the unit
when the renders differ: the interval is the t interval of the R
render-seed means (t(0.975, R - 1)).  When the F test of the between-render
mean square against the within-render one does not find render noise at the
0.25 level, the two are pooled and the n realisations are used as
independent (Bancroft's "sometimes pool" rule: T. A. Bancroft 1944, Ann.
Math. Statist. 15:190-204; the 0.25 level is the one Bancroft and Paull
1950, Ann. Math. Statist. 21:539-556, recommend).  With few render seeds
(R = 2: t(0.975, 1) = 12.7) a value whose renders visibly differ gets a
wide interval: two renders say little about render noise.

The sensor-noise-only half width (:func:`sensor_half_width`) is the t half
width of the within-render (pooled) standard deviation, what the interval
would be if the render were fixed; metrics.csv carries it beside the full
interval so the share of render noise can be read.

**Paired comparisons** (:func:`paired_difference`,
:func:`paired_rank_interval`).  Two CFAs are compared through the
per-realisation differences of their values (same render seed, same sensor
seed), with the interval above applied to those differences: noise common
to both (the render's above all) cancels.  A CFA ranks at best one below
every CFA that is better than it with a difference interval wholly above 0,
and at worst just above every CFA it beats that way; a difference interval
containing 0 is a tie.  :func:`rank_interval` is the older rule on marginal
intervals (two intervals that do not overlap), kept for tables that only
have the marginal intervals.
"""

from __future__ import annotations

__all__ = ["CONFIDENCE", "POOL_LEVEL", "t_interval", "nested_interval", "sensor_half_width", "aggregate",
           "rank_interval", "paired_difference", "paired_rank_interval"]

import functools

import numpy as np

#: Two-sided confidence of every interval.
CONFIDENCE = 0.95
#: Significance level of the preliminary F test that decides whether the
#: realisations of different renders may be pooled (Bancroft 1944; Paull 1950).
POOL_LEVEL = 0.25


@functools.lru_cache(maxsize=None)
def _t_quantile(df: int) -> float:
    """t(0.5 + CONFIDENCE / 2, df): the same few degrees of freedom come back
    for every value of a study (scipy's ppf costs about 0.2 ms a call, and a
    paper study's tables make some 30,000 of them)."""
    from scipy.stats import t

    return float(t.ppf(0.5 + CONFIDENCE / 2, df))


@functools.lru_cache(maxsize=None)
def _f_quantile(df_between: int, df_within: int) -> float:
    """F(1 - POOL_LEVEL; df_between, df_within), kept as :func:`_t_quantile`."""
    from scipy.stats import f

    return float(f.ppf(1 - POOL_LEVEL, df_between, df_within))


def t_interval(values) -> tuple[float, float, float, float, int]:
    """(mean, ci_low, ci_high, std, n) of finite ``values`` (Student-t, 95 %)."""
    v = np.asarray(values, dtype=np.float64)
    v = v[np.isfinite(v)]
    n = int(v.size)
    if n == 0:
        return (np.nan, np.nan, np.nan, np.nan, 0)
    mean = float(v.mean())
    if n == 1:
        return (mean, mean, mean, 0.0, 1)
    sd = float(v.std(ddof=1))
    half = _t_quantile(n - 1) * sd / np.sqrt(n)
    return (mean, float(mean - half), float(mean + half), sd, n)


def _split(values, groups):
    """(finite values, their group labels) as arrays."""
    v = np.asarray(values, dtype=np.float64)
    gr = np.zeros(v.shape, dtype=np.int64) if groups is None else np.asarray(groups)
    keep = np.isfinite(v)
    return v[keep], gr[keep]


def _within(v, gr):
    """(group means, pooled within-group variance, its degrees of freedom)."""
    labels = list(dict.fromkeys(gr.tolist()))
    means = np.array([v[gr == g].mean() for g in labels])
    ss = sum(float(((v[gr == g] - m) ** 2).sum()) for g, m in zip(labels, means))
    df_w = int(v.size - len(labels))
    return means, (ss / df_w if df_w > 0 else np.nan), df_w


def nested_interval(values, groups=None) -> tuple[float, float, float, float, int]:
    """(mean, ci_low, ci_high, std, n) of finite ``values`` whose realisations
    share renders by ``groups`` (the render seed of each; None: one render).

    The module docstring gives the rule: the t interval of all values when
    there is one group or one value per group, or when the F test finds no
    render noise at the :data:`POOL_LEVEL`; else the t interval of the group
    means (R - 1 degrees of freedom).  ``std`` is that of the values used.

    Examples
    --------
    >>> [round(x, 3) for x in nested_interval([1.0, 1.2, 3.0, 3.2], [0, 0, 1, 1])[1:3]]  # renders differ: t(1), 2 means
    [-10.606, 14.806]
    >>> [round(x, 3) for x in nested_interval([1.0, 1.2, 1.1, 1.0], [0, 0, 1, 1])[1:3]]  # pooled: t(3) on 4 values
    [0.923, 1.227]
    """
    v, gr = _split(values, groups)
    n = int(v.size)
    labels = set(gr.tolist())
    if len(labels) <= 1 or len(labels) == n:
        return t_interval(v)
    means, ms_w, df_w = _within(v, gr)
    r = means.size
    sizes = np.array([np.sum(gr == g) for g in dict.fromkeys(gr.tolist())])
    ms_b = float(np.sum(sizes * (means - v.mean()) ** 2) / (r - 1))  # between-render mean square
    if ms_w > 0:
        pool = ms_b / ms_w < _f_quantile(r - 1, df_w)
    else:  # no spread within a render: pool only if the renders agree too
        pool = ms_b <= 0
    if pool:
        return t_interval(v)
    _, lo, hi, sd, _ = t_interval(means)
    mean = float(v.mean())
    shift = mean - float(means.mean())  # unequal group sizes: centre the interval on the mean of all values
    return (mean, lo + shift, hi + shift, sd, n)


def sensor_half_width(values, groups=None) -> float:
    """The 95 % half width from sensor noise alone: t(0.975, n - R) times the
    pooled within-render standard deviation over sqrt(n) (with one render,
    the half width of :func:`t_interval`); 0 with one value per render (a
    noiseless capture), NaN without any finite value.

    >>> round(sensor_half_width([1.0, 1.2, 3.0, 3.2], [0, 0, 1, 1]), 4)
    0.3042
    """
    v, gr = _split(values, groups)
    if v.size == 0:
        return float("nan")
    _, ms_w, df_w = _within(v, gr)
    if df_w == 0:
        return 0.0
    return _t_quantile(df_w) * float(np.sqrt(ms_w / v.size))


def aggregate(df, keys: list[str], column: str = "value", prefix: str = "", groups: str | None = None):
    """One row per ``keys`` group: the mean of ``column`` (named ``prefix +
    column``) and its ``ci_low``, ``ci_high``, ``std``, ``n`` (prefixed).

    ``groups``: a column naming each realisation's render seed; the
    interval is then :func:`nested_interval`'s (no such column: one render)."""
    import pandas as pd

    rows = []
    has_groups = groups is not None and groups in df.columns
    for k, g in df.groupby(keys, sort=False, dropna=False):
        mean, lo, hi, sd, n = nested_interval(g[column], g[groups] if has_groups else None)
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


def paired_difference(a, b, groups=None) -> tuple[float, float, float, int]:
    """(mean, ci_low, ci_high, n) of the per-realisation differences ``a - b``
    (realisations paired by position: the same render seed and sensor seed),
    with :func:`nested_interval`'s rule; realisations where either is not
    finite are left out.

    >>> [round(x, 6) for x in paired_difference([1.0, 2.0, 3.0], [0.9, 1.9, 2.9])[:3]]  # marginals overlap, not this
    [0.1, 0.1, 0.1]
    """
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    gr = np.zeros(a.shape, dtype=np.int64) if groups is None else np.asarray(groups)
    keep = np.isfinite(a) & np.isfinite(b)
    mean, lo, hi, _, n = nested_interval(a[keep] - b[keep], gr[keep])
    return mean, lo, hi, n


def paired_rank_interval(values, groups=None, *, higher_is_better: bool = True):
    """(rank, best rank, worst rank) of each item (1 = best) from paired comparisons.

    ``values``: (items, realisations), realisation ``k`` of every item from
    the same render seed and sensor seed (NaN where an item lacks one);
    ``groups``: each realisation's render seed.  ``rank`` ranks the means
    ('min' for equal means); item i's best rank is one more than the number
    of items whose paired difference with i lies wholly on the better side
    of 0, its worst rank the number of items minus those it beats that way.

    Examples
    --------
    >>> v = [[1.00, 2.00, 3.00], [0.95, 1.95, 2.95], [0.0, 1.0, 2.0]]
    >>> [x.tolist() for x in paired_rank_interval(v)]  # marginal intervals all overlap; differences are exact
    [[1, 2, 3], [1, 2, 3], [1, 2, 3]]
    """
    x = np.atleast_2d(np.asarray(values, dtype=np.float64))
    if not higher_is_better:
        x = -x
    n = x.shape[0]
    with np.errstate(all="ignore"):
        m = np.array([np.nanmean(row) if np.isfinite(row).any() else np.nan for row in x])
    above = np.zeros((n, n), dtype=bool)  # above[i, j]: i better than j, the difference interval above 0
    for i in range(n):
        for j in range(i + 1, n):
            _, lo, hi, k = paired_difference(x[i], x[j], groups)
            if k == 0:
                continue
            above[i, j], above[j, i] = lo > 0, hi < 0
    rank = np.array([1 + int(np.sum(m > m[i])) for i in range(n)])
    best = 1 + above.sum(axis=0)
    worst = n - above.sum(axis=1)
    return rank, best, worst
