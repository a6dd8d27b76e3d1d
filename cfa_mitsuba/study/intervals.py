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
share a render are not independent (the render's noise is common to them):
the interval is that of the variance-components model of
:mod:`.variance`, the sensor variance the value's own within-render mean
square, the render variance pooled over the values of one scene and
level (:func:`aggregate`'s ``pool_by``; one value alone uses its own
estimate).  With one render (R = 1), or one realisation per render
(S = 1), the realisations are independent and the interval is the
Student-t one,

    mean +- t(0.975, n - 1) s / sqrt(n)

(s the sample standard deviation; with n = 1 the interval is the value
itself and ``n`` says so).  An earlier rule chose per value between the
t interval of the R render means and the pooled realisations by an F
test at the 0.25 level; with two renders that choice turned on one draw
and moved the width by an order of magnitude (issue 46), so it is gone.

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
containing 0 is a tie.  The render component of the differences is pooled
over the pairs of one comparison, and "better than" is made transitive
(its closure: A above B and B above C put A above C), so the rank
intervals are those of one order.  :func:`rank_interval` is the older rule on marginal
intervals (two intervals that do not overlap), kept for tables that only
have the marginal intervals.
"""

from __future__ import annotations

__all__ = ["CONFIDENCE", "t_interval", "nested_interval", "sensor_half_width", "aggregate",
           "rank_interval", "paired_difference", "paired_rank_interval", "difference_pool", "above_closure"]

import numpy as np

from .variance import CONFIDENCE, cell, cell_interval, pool_render, t_quantile


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
    half = t_quantile(n - 1) * sd / np.sqrt(n)
    return (mean, float(mean - half), float(mean + half), sd, n)


def nested_interval(values, groups=None, pool=None) -> tuple[float, float, float, float, int]:
    """(mean, ci_low, ci_high, std, n) of finite ``values`` whose realisations
    share renders by ``groups`` (the render seed of each; None: one render).

    The module docstring gives the rule (:func:`.variance.cell_interval`):
    the t interval of all values when there is one group or one value per
    group; else the sensor variance of the value plus ``pool``'s render
    variance (a :class:`.variance.RenderPool`; None: the value's own
    estimate).  ``std`` is the sample standard deviation of the values.

    Examples
    --------
    >>> [round(x, 3) for x in nested_interval([1.0, 1.2, 3.0, 3.2], [0, 0, 1, 1])[1:3]]  # renders differ
    [-10.606, 14.806]
    >>> [round(x, 3) for x in nested_interval([1.0, 1.2, 1.1, 1.0], [0, 0, 1, 1])[1:3]]  # no render component
    [0.834, 1.316]
    """
    return cell_interval(cell(values, groups), pool)


def sensor_half_width(values, groups=None) -> float:
    """The 95 % half width from sensor noise alone: t(0.975, n - R) times the
    pooled within-render standard deviation over sqrt(n) (with one render,
    the half width of :func:`t_interval`); 0 with one value per render (a
    noiseless capture), NaN without any finite value.

    >>> round(sensor_half_width([1.0, 1.2, 3.0, 3.2], [0, 0, 1, 1]), 4)
    0.3042
    """
    c = cell(values, groups)
    if c.n == 0:
        return float("nan")
    if c.df_within == 0:
        return 0.0
    return t_quantile(c.df_within) * float(np.sqrt(c.ms_within / c.n))


def aggregate(df, keys: list[str], column: str = "value", prefix: str = "", groups: str | None = None,
              pool_by: list[str] | None = None):
    """One row per ``keys`` group: the mean of ``column`` (named ``prefix +
    column``) and its ``ci_low``, ``ci_high``, ``std``, ``n`` (prefixed).

    ``groups``: a column naming each realisation's render seed; the
    interval is then :func:`nested_interval`'s (no such column: one
    render).  ``pool_by``: the columns (a subset of ``keys``) whose groups
    share one pooled render component (:func:`.variance.pool_render`: the
    values of one scene, level and metric); None: each value its own."""
    import pandas as pd

    has_groups = groups is not None and groups in df.columns
    keyed, cells = [], []
    for k, g in df.groupby(keys, sort=False, dropna=False):
        # pandas gives a 1-tuple for a one-key list in some versions and the bare key in others
        k = k if isinstance(k, tuple) else (k,)
        keyed.append(k)
        cells.append(cell(g[column].to_numpy(dtype=float), g[groups].to_numpy() if has_groups else None))
    pools = [None] * len(cells)
    if pool_by is not None and has_groups:
        idx = [keys.index(c) for c in pool_by]
        by: dict = {}
        for i, k in enumerate(keyed):
            by.setdefault(tuple(k[j] for j in idx), []).append(i)
        for members in by.values():
            p = pool_render([cells[i] for i in members])
            for i in members:
                pools[i] = p
    rows = [(*k, *cell_interval(c, p)) for k, c, p in zip(keyed, cells, pools)]
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


def paired_difference(a, b, groups=None, pool=None) -> tuple[float, float, float, int]:
    """(mean, ci_low, ci_high, n) of the per-realisation differences ``a - b``
    (realisations paired by position: the same render seed and sensor seed),
    with :func:`nested_interval`'s rule (``pool``: the render component of
    the comparison's differences, :func:`difference_pool`); realisations
    where either is not finite are left out.

    >>> [round(x, 6) for x in paired_difference([1.0, 2.0, 3.0], [0.9, 1.9, 2.9])[:3]]  # marginals overlap, not this
    [0.1, 0.1, 0.1]
    """
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    gr = np.zeros(a.shape, dtype=np.int64) if groups is None else np.asarray(groups)
    keep = np.isfinite(a) & np.isfinite(b)
    mean, lo, hi, _, n = nested_interval(a[keep] - b[keep], gr[keep], pool)
    return mean, lo, hi, n


def difference_pool(values, groups=None):
    """The render component of the paired differences of every pair of rows
    of ``values`` (items x realisations), pooled (:func:`.variance.pool_render`):
    the one estimate every comparison of a ranking uses."""
    x = np.atleast_2d(np.asarray(values, dtype=np.float64))
    gr = np.zeros(x.shape[1], dtype=np.int64) if groups is None else np.asarray(groups)
    cells = []
    for i in range(x.shape[0]):
        for j in range(i + 1, x.shape[0]):
            keep = np.isfinite(x[i]) & np.isfinite(x[j])
            if keep.any():
                cells.append(cell(x[i][keep] - x[j][keep], gr[keep]))
    return pool_render(cells)


def above_closure(above: np.ndarray) -> np.ndarray:
    """The transitive closure of a "separated, better than" relation
    (``above[i, j]``: i better than j): A above B and B above C put A above
    C (Warshall's algorithm).  Separations follow the mean differences,
    which are transitive, so the closure has no cycle; it only adds what
    two separations already imply.

    >>> above_closure(np.array([[0, 1, 0], [0, 0, 1], [0, 0, 0]], dtype=bool)).astype(int).tolist()
    [[0, 1, 1], [0, 0, 1], [0, 0, 0]]
    """
    out = np.array(above, dtype=bool)
    for k in range(out.shape[0]):
        out |= out[:, [k]] & out[[k], :]
    np.fill_diagonal(out, False)
    return out


def paired_rank_interval(values, groups=None, *, higher_is_better: bool = True):
    """(rank, best rank, worst rank) of each item (1 = best) from paired comparisons.

    ``values``: (items, realisations), realisation ``k`` of every item from
    the same render seed and sensor seed (NaN where an item lacks one);
    ``groups``: each realisation's render seed.  ``rank`` ranks the means
    ('min' for equal means); item i's best rank is one more than the number
    of items better than it, its worst rank the number of items minus those
    it is better than, "better" meaning a paired difference whose 95 %
    interval lies wholly on the better side of 0 (the render component
    pooled over every pair: :func:`difference_pool`), closed under
    transitivity (:func:`above_closure`).

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
    pool = difference_pool(x, groups)
    above = np.zeros((n, n), dtype=bool)  # above[i, j]: i better than j, the difference interval above 0
    for i in range(n):
        for j in range(i + 1, n):
            _, lo, hi, k = paired_difference(x[i], x[j], groups, pool)
            if k == 0:
                continue
            above[i, j], above[j, i] = lo > 0, hi < 0
    above = above_closure(above)
    rank = np.array([1 + int(np.sum(m > m[i])) for i in range(n)])
    best = 1 + above.sum(axis=0)
    worst = n - above.sum(axis=1)
    return rank, best, worst
