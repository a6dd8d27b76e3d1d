"""Censored values: one rule for a metric value that is a bound (an MSP with
no moire up to the chirp's top frequency), in metrics.csv, in the scores and
wherever a value is printed.

**What a bound is.**  The camera showed no moire up to the chirp's top
frequency, so its MSP is *at least* that frequency (right-censored, a lower
bound on the value); the ideal sensor's value is that frequency too.  Every
realisation says whether its value is a bound (metrics_realisations.csv's
``censored``).

**metrics.csv** (:func:`summarise`).  ``censored_count`` is the number of a
value's realisations that are bounds.  With none, ``value`` is the mean and
the interval :mod:`.variance`'s.  With some, the mean of bounds and
measurements is neither (issue 46: RGB5 bilinear measured moire at 6.35
cy/deg in 4 of 6 realisations and a bound of 24.38 in 2, and was printed
as ">= 12.36"), so ``value`` is the Kaplan-Meier median (Kaplan & Meier
1958, J. Amer. Statist. Assoc. 53:457-481: the smallest measured value at
which the product-limit estimate of P(value > v) falls to 0.5 or below; a
bound counts as "above" every measured value not larger than it), and the
interval is the distribution-free one of a median, the order statistics
x(k) and x(n + 1 - k) with the largest k whose binomial coverage is at
least 95 % (Conover, *Practical Nonparametric Statistics*, 3rd ed., s. 3.2;
with n < 6 no k reaches 95 % and the interval is the whole range, whose
coverage 1 - 2^(1-n) is less).  ``censored`` is True only when every
realisation is a bound: then the value is that bound and is printed as
">= value"; otherwise it is a measurement (the median is a measured value
whenever fewer than half the realisations are bounds) printed with "k of n
realisations bounds", never as a bound.  When half or more are bounds the
Kaplan-Meier median is not reached: ``value`` is the smallest bound and
``censored`` stays False (some realisations measured moire), printed with
its count.

**Scores** (:func:`values_for_scoring`).  Each realisation is scored on its
own; a bound is scored by one of three conventions, the study's being
``midpoint`` (:data:`DEFAULT_CONVENTION`):

- ``midpoint``: the midpoint between the best measured value of the same
  metric in the study (at the same luminance) and the range's best end: it
  scores above every measured value, as a bound at the top must, and below
  the ideal's 1, by half the gap the chart cannot resolve;
- ``bound``: the bound itself, as if measured (the chirp's top, the ideal's
  value: score 1);
- ``best measured``: the best measured value (the least a bound can be
  worth: it is at least that good).

When no value of the metric is measured the metric is left as it is (every
CFA then has the same bound, the metric cannot rank them, and the range
policy drops it as constant).  scores.csv keeps metrics.csv's ``value``,
``censored`` and ``censored_count``; only ``score`` follows the convention.
decisions.csv says whether a decision changes under the other two
(``depends_on``: ``censored at the bound``, ``censored at best measured``).
"""

from __future__ import annotations

__all__ = ["CONVENTIONS", "DEFAULT_CONVENTION", "convention_label", "is_bound", "km_median", "summarise",
           "values_for_scoring", "bound_text", "apply_rule", "row_text"]

import math

import numpy as np

#: How a bound is scored (module docstring), the study's first.
CONVENTIONS = ("midpoint", "bound", "best measured")
DEFAULT_CONVENTION = "midpoint"


def convention_label(convention: str) -> str:
    """The words decisions.csv's ``depends_on`` uses for a convention."""
    return {"midpoint": "censored at the midpoint", "bound": "censored at the bound",
            "best measured": "censored at best measured"}[convention]


def is_bound(column):
    """A boolean array of a ``censored`` column as written (True/False, 1/0, text)."""
    import pandas as pd

    s = pd.Series(column)
    return s.fillna(False).astype(str).str.lower().isin(("true", "1", "1.0")).to_numpy()


def km_median(values, bounds) -> tuple[float, bool]:
    """(median, reached) of right-censored ``values`` (``bounds``: True where
    the value is a lower bound) by the Kaplan-Meier product-limit estimate.

    ``reached`` False: half or more of the realisations are bounds above the
    last measured value, so the median is only known to be at least the
    smallest such bound (returned).

    Examples
    --------
    >>> km_median([6.35, 6.35, 24.38, 6.35, 24.38, 6.35], [0, 0, 1, 0, 1, 0])  # 2 of 6 bounds
    (6.35, True)
    >>> km_median([5.0, 24.38, 24.38, 24.38], [0, 1, 1, 1])
    (24.38, False)
    >>> km_median([1.0, 2.0, 3.0, 4.0], [0, 0, 0, 0])  # no bound: the lower median
    (2.0, True)
    """
    v = np.asarray(values, dtype=np.float64)
    b = np.asarray(bounds, dtype=bool)
    keep = np.isfinite(v)
    v, b = v[keep], b[keep]
    if v.size == 0:
        return float("nan"), False
    # measured before bound at equal values: a bound at v says the value is above v
    order = np.lexsort((b, v))
    v, b = v[order], b[order]
    at_risk, surv = v.size, 1.0
    for x, bound in zip(v, b):
        if not bound:
            surv *= 1.0 - 1.0 / at_risk
            if surv <= 0.5 + 1e-12:
                return float(x), True
        at_risk -= 1
    return float(v[b].min()) if b.any() else float(v.max()), False


def _order_interval(sorted_values) -> tuple[float, float]:
    """(x(k), x(n + 1 - k)): the distribution-free 95 % interval of a median,
    k the largest with P(k <= B <= n - k) >= 0.95 for B ~ Binomial(n, 1/2)."""
    n = len(sorted_values)

    def coverage(k):  # P(k <= B <= n - k), exact
        return sum(math.comb(n, j) for j in range(k, n - k + 1)) / 2.0 ** n

    k = 1
    while k + 1 <= n // 2 and coverage(k + 1) >= 0.95:
        k += 1
    return float(sorted_values[k - 1]), float(sorted_values[n - k])


def summarise(values, bounds) -> dict:
    """metrics.csv's fields of one value with bounds among its realisations
    (module docstring): ``value``, ``ci_low``, ``ci_high``, ``censored``
    (every realisation a bound), ``censored_count``.

    >>> summarise([6.35, 6.35, 24.38, 6.35, 24.38, 6.35], [0, 0, 1, 0, 1, 0])
    {'value': 6.35, 'ci_low': 6.35, 'ci_high': 24.38, 'censored': False, 'censored_count': 2}
    """
    v = np.asarray(values, dtype=np.float64)
    b = np.asarray(bounds, dtype=bool)
    keep = np.isfinite(v)
    v, b = v[keep], b[keep]
    count = int(b.sum())
    if v.size and count == v.size:
        lo = float(v.min())
        return {"value": lo, "ci_low": lo, "ci_high": float(v.max()), "censored": True, "censored_count": count}
    median, _ = km_median(v, b)
    lo, hi = _order_interval(np.sort(v)) if v.size else (math.nan, math.nan)
    return {"value": median, "ci_low": min(lo, median), "ci_high": max(hi, median), "censored": False,
            "censored_count": count}


def bound_text(value: float, decimals: int, censored, count, n, unit: str = "") -> str:
    """How a value is printed under the rule: ``>= v`` only when every
    realisation is a bound; ``v (k of n realisations bounds)`` when some
    are; the plain number otherwise."""
    u = f" {unit}" if unit else ""
    text = f"{value:.{decimals}f}"
    k = int(count) if count is not None and not (isinstance(count, float) and math.isnan(count)) else 0
    if bool(censored) and (not n or k >= int(n)):
        return f">= {text}{u}"
    if k:
        return f"{text}{u} ({k} of {int(n)} realisations bounds)"
    return f"{text}{u}"


def values_for_scoring(rows, ranges: dict, convention: str = DEFAULT_CONVENTION):
    """A copy of ``rows`` (per realisation: scene, cfa, demosaic, luminance,
    metric, value, censored, ...) whose bounds are replaced by the value the
    ``convention`` scores them at; rows without a ``censored`` column are
    returned as they are.

    >>> import pandas as pd
    >>> from cfa_mitsuba.study.scoring import ScoreRange
    >>> rows = pd.DataFrame({"metric": ["moire"] * 3, "luminance": [100] * 3, "value": [4.0, 6.0, 24.0],
    ...                      "censored": [False, False, True]})
    >>> [values_for_scoring(rows, {"moire": ScoreRange(2.0, 24.0, ())}, c)["value"].tolist()[2] for c in CONVENTIONS]
    [15.0, 24.0, 6.0]
    """
    if convention not in CONVENTIONS:
        from ..errors import CfaMitsubaError

        raise CfaMitsubaError(f"unknown convention for censored values {convention!r} "
                              f"(expected one of: {', '.join(CONVENTIONS)})")
    if "censored" not in rows.columns:
        return rows
    out = rows.copy()
    bound = is_bound(out["censored"])
    if not bound.any() or convention == "bound":
        return out
    for (metric, lum), g in out[bound].groupby(["metric", "luminance"], sort=False):
        r = ranges.get(metric)
        measured = out[(out["metric"] == metric) & (out["luminance"] == lum) & ~bound]["value"].astype(float)
        if r is None or measured.empty:
            continue
        best_end = float(r.best)
        higher = best_end > float(r.worst)
        best_measured = float(measured.max() if higher else measured.min())
        if convention == "best measured":
            out.loc[g.index, "value"] = best_measured
        else:
            out.loc[g.index, "value"] = 0.5 * (best_measured + best_end) if np.isfinite(best_measured) else best_end
    return out


def apply_rule(metrics, realisations):
    """metrics.csv read under this module's rule: a table written before
    ``censored_count`` existed gets it from ``realisations``
    (metrics_realisations.csv), and its values with bounds among their
    realisations are summarised again (an old ``value`` is the mean of
    bounds and measurements; its ``censored`` said "any").  A table that
    has the column, or no realisations to read, is returned as it is."""
    if metrics is None or "censored_count" in metrics.columns or realisations is None or not len(realisations):
        return metrics
    if "censored" not in realisations.columns:
        return metrics.assign(censored=False, censored_count=0)
    skip = {"value", "ci_low", "ci_high", "n", "unit", "censored", "realisation", "render_seed", "std"}
    keys = [c for c in metrics.columns if c in realisations.columns and c not in skip
            and c not in ("exposure_s", "analog_gain", "digital_gain", "clipped_fraction", "render_seeds",
                          "sensor_half_width")]
    real = realisations.assign(_bound=is_bound(realisations["censored"]))
    out = metrics.copy()
    out["censored"] = False
    out["censored_count"] = 0
    with_bounds = real[real.groupby(keys, sort=False, dropna=False)["_bound"].transform("any")]
    if with_bounds.empty:
        return out
    index = out.set_index(keys).index
    for key, g in with_bounds.groupby(keys, sort=False, dropna=False):
        at = index.get_indexer([key])[0]
        if at >= 0:
            for col, v in summarise(g["value"].to_numpy(float), g["_bound"].to_numpy(bool)).items():
                out.loc[out.index[at], col] = v
    out["censored"] = out["censored"].astype(bool)
    out["censored_count"] = out["censored_count"].astype(int)
    return out


def row_text(row, decimals: int, unit: str = "") -> str:
    """:func:`bound_text` of a metrics.csv row (a mapping or a namedtuple)."""
    get = row.get if hasattr(row, "get") else (lambda k, d=None: getattr(row, k, d))
    n = get("n", None)
    return bound_text(float(get("value")), decimals, is_bound([get("censored", False)])[0],
                      get("censored_count", None), None if n is None or n != n else int(n), unit)
