"""Variance components of a study's values: sensor noise within a render,
render noise between renders, and the render component pooled over the
values of one scene and level.

A value of a path-traced scene is the mean of ``n`` realisations spread over
``R`` renders (render seeds) with about ``S = n / R`` sensor seeds each.  Its
variance has two components (the one-way random-effects model, Montgomery,
*Design and Analysis of Experiments*, 8th ed., s. 13.1 and 14.1),

    var(mean) = sigma_r^2 sum(n_i^2) / n^2 + sigma_s^2 / n,

``sigma_s^2`` the sensor (within-render) variance and ``sigma_r^2`` the
render (between-render) variance; with equal ``n_i = S`` the first term is
``sigma_r^2 / R``.  ``sigma_s^2`` is the value's own within-render mean
square ``MS_w`` (``n - R`` degrees of freedom).  ``sigma_r^2`` is not
estimated from the value alone: with R = 2 renders its own estimate has
one degree of freedom, so an interval built on it jumps by an order of
magnitude with the draw of one render (issue 46 measured a median 8.7x
and up to 35x the sensor-only width on 19 % of the paper study's puppy
values, 0.85x on the others).  Render noise is a property of the render
(its samples per pixel and the scene), shared by every CFA and demosaic
that sees it, so the render component is pooled over the values of one
scene, level and metric (:func:`pool_render`): the ANOVA (method of
moments) estimate

    sigma_r^2 = max(0, (mean MS_b - mean MS_w) / n0),

the mean squares averaged over the pooled values with their degrees of
freedom as weights and ``n0 = (n - sum n_i^2 / n) / (R - 1)`` (``S`` when
balanced), with Satterthwaite's degrees of freedom for the difference of
mean squares (Satterthwaite 1946, Biometrics Bull. 2:110-114).  The
interval of one value then uses Satterthwaite's degrees of freedom for the
sum of its two terms.  A value's interval is never narrower than its
sensor-only one (the render term is at least 0) and is wider by the pooled
render component only, which changes with the pool, not with one value's
two renders.

The same model serves any per-realisation quantity: a metric's value, a
paired difference of two CFAs (the pool then runs over the pairs of one
comparison), a score, a mean score or a total.
"""

from __future__ import annotations

__all__ = ["CONFIDENCE", "Cell", "RenderPool", "cell", "pool_render", "cell_interval", "t_quantile", "NO_POOL"]

import functools
import math
from dataclasses import dataclass

import numpy as np

#: Two-sided confidence of every interval of the project.
CONFIDENCE = 0.95


@dataclass(frozen=True)
class Cell:
    """One value's realisations summarised: ``n`` finite realisations,
    ``mean``, ``sd`` (their sample standard deviation), ``renders`` (R),
    ``ms_within``/``df_within`` (the pooled within-render mean square and
    its n - R degrees of freedom), ``ms_between``/``df_between`` (between
    renders, R - 1), ``n0`` (effective realisations per render) and
    ``render_weight`` (sum n_i^2 / n^2: 1/R when balanced)."""

    n: int
    mean: float
    sd: float
    renders: int
    ms_within: float
    df_within: int
    ms_between: float
    df_between: int
    n0: float
    render_weight: float

    @property
    def nested(self) -> bool:
        """Whether both components can be told apart: several renders with several realisations each."""
        return self.renders > 1 and self.n > self.renders


@dataclass(frozen=True)
class RenderPool:
    """The pooled render component: ``variance`` (sigma_r^2, >= 0, in the
    values' units squared), its Satterthwaite degrees of freedom ``df`` and
    how many values it pools (``cells``)."""

    variance: float
    df: float
    cells: int


#: No render component (a chart, or no value to pool).
NO_POOL = RenderPool(0.0, math.inf, 0)


@functools.lru_cache(maxsize=4096)
def _t_quantile(df: float) -> float:
    """t(0.975, df) (df rounded to 0.01: the same few come back for every value;
    scipy's ppf costs about 0.2 ms a call, and a paper study's tables make
    some 30,000 intervals)."""
    from scipy.stats import t

    return float(t.ppf(0.5 + CONFIDENCE / 2, df))


def t_quantile(df: float) -> float:
    """The two-sided 95 % Student-t quantile for ``df`` degrees of freedom (inf: normal)."""
    if not math.isfinite(df):
        from scipy.stats import norm

        return float(norm.ppf(0.5 + CONFIDENCE / 2))
    return _t_quantile(round(float(df), 2))


def cell(values, groups=None) -> Cell:
    """The :class:`Cell` of one value's realisations (``groups``: each one's
    render seed; None: one render); non-finite realisations are left out.

    >>> c = cell([1.0, 1.2, 3.0, 3.2], [0, 0, 1, 1])
    >>> c.renders, round(c.ms_within, 3), round(c.ms_between, 3), c.n0
    (2, 0.02, 4.0, 2.0)
    """
    v = np.asarray(values, dtype=np.float64)
    gr = np.zeros(v.shape, dtype=np.int64) if groups is None else np.asarray(groups)
    keep = np.isfinite(v)
    v, gr = v[keep], gr[keep]
    n = int(v.size)
    if n == 0:
        nan = float("nan")
        return Cell(0, nan, nan, 0, nan, 0, nan, 0, nan, nan)
    labels, inverse = np.unique(gr, return_inverse=True)
    sizes = np.bincount(inverse).astype(np.float64)
    means = np.bincount(inverse, weights=v) / sizes
    mean = float(v.mean())
    r = int(labels.size)
    ss_w = float(((v - means[inverse]) ** 2).sum())
    df_w = n - r
    ms_w = ss_w / df_w if df_w > 0 else float("nan")
    df_b = r - 1
    ms_b = float((sizes * (means - mean) ** 2).sum() / df_b) if df_b > 0 else float("nan")
    n0 = float((n - (sizes ** 2).sum() / n) / df_b) if df_b > 0 else float(n)
    sd = float(v.std(ddof=1)) if n > 1 else 0.0
    return Cell(n, mean, sd, r, ms_w, df_w, ms_b, df_b, n0, float((sizes ** 2).sum() / n ** 2))


def pool_render(cells) -> RenderPool:
    """The render component pooled over ``cells`` (module docstring): the
    mean squares averaged with their degrees of freedom as weights; cells
    that cannot separate the components (one render, one realisation per
    render) take no part; :data:`NO_POOL` when none can.

    >>> p = pool_render([cell([1.0, 1.2, 3.0, 3.2], [0, 0, 1, 1]), cell([1.0, 1.2, 1.1, 1.3], [0, 0, 1, 1])])
    >>> round(p.variance, 4), p.cells
    (0.9925, 2)
    """
    use = [c for c in cells if c.nested and np.isfinite(c.ms_within) and np.isfinite(c.ms_between)]
    if not use:
        return NO_POOL
    df_b = float(sum(c.df_between for c in use))
    df_w = float(sum(c.df_within for c in use))
    ms_b = sum(c.df_between * c.ms_between for c in use) / df_b
    ms_w = sum(c.df_within * c.ms_within for c in use) / df_w
    n0 = sum(c.df_between * c.n0 for c in use) / df_b
    est = (ms_b - ms_w) / n0
    if est <= 0:
        return RenderPool(0.0, math.inf, len(use))
    denom = ms_b ** 2 / df_b + ms_w ** 2 / df_w
    return RenderPool(float(est), float((ms_b - ms_w) ** 2 / denom) if denom > 0 else math.inf, len(use))


def cell_interval(c: Cell, pool: RenderPool | None = None) -> tuple[float, float, float, float, int]:
    """(mean, ci_low, ci_high, sd, n): the 95 % interval of a value's mean.

    One render, or one realisation per render: the Student-t interval of the
    realisations (they are independent).  Several renders with several
    realisations each: ``pool``'s render variance times ``render_weight``
    plus ``MS_w / n``, with Satterthwaite's degrees of freedom (and never
    narrower than the sensor-only half width); ``pool``
    None takes the value's own estimate (:func:`pool_render` of it alone:
    one degree of freedom for R = 2, as wide as the render means' t interval
    when the renders differ)."""
    if c.n == 0:
        nan = float("nan")
        return (nan, nan, nan, nan, 0)
    if c.n == 1:
        return (c.mean, c.mean, c.mean, 0.0, 1)
    if not c.nested:
        half = t_quantile(c.n - 1) * c.sd / math.sqrt(c.n)
        return (c.mean, c.mean - half, c.mean + half, c.sd, c.n)
    if pool is None:
        pool = pool_render([c])
    a = pool.variance * c.render_weight
    b = c.ms_within / c.n
    var = a + b
    if var <= 0:
        return (c.mean, c.mean, c.mean, c.sd, c.n)
    denom = (a ** 2 / pool.df if math.isfinite(pool.df) and pool.df > 0 else 0.0) + b ** 2 / c.df_within
    df = var ** 2 / denom if denom > 0 else math.inf
    # never narrower than the sensor-only interval (Satterthwaite's df can exceed the within df when the
    # pooled render term, known to many df, is a large share: the t quantile then falls a little)
    half = max(t_quantile(max(df, 1.0)) * math.sqrt(var), t_quantile(c.df_within) * math.sqrt(b))
    return (c.mean, c.mean - half, c.mean + half, c.sd, c.n)
