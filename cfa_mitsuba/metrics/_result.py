"""The value a metric returns: a float that carries its unit and details."""

from __future__ import annotations

__all__ = ["MetricResult"]

import math

import numpy as np


class MetricResult(float):
    """A metric's headline number, with its unit and the details behind it.

    It *is* the headline value (a ``float`` subclass), so ``float(r)``,
    arithmetic and comparisons work directly; ``r.details`` keeps what plots
    and reports need (maps, per-patch values, curves, flags).

    Attributes
    ----------
    name : the metric's CLI name (``'delta-e'``, ``'mtf'``, ...).
    unit : unit of the headline value (``'dE00'``, ``'cy/px'``, ``'cy/deg'``, ...).
    details : dict of further results; arrays stay numpy arrays.

    Examples
    --------
    >>> r = MetricResult(0.25, name="mtf", unit="cy/px", details={"nyquist": 0.5})
    >>> float(r), r.unit, r > 0.2
    (0.25, 'cy/px', True)
    >>> r.to_dict()["value"]
    0.25
    """

    name: str
    unit: str
    details: dict

    def __new__(cls, value, *, name: str = "", unit: str = "", details: dict | None = None):
        obj = super().__new__(cls, float(value))
        obj.name = name
        obj.unit = unit
        obj.details = dict(details or {})
        return obj

    @property
    def value(self) -> float:
        """The headline number as a plain ``float``."""
        return float(self)

    def __repr__(self) -> str:
        return f"MetricResult({self.name}={float(self)!r} {self.unit})".replace(" )", ")")

    def __reduce__(self):  # pickle (process pools): keep the attributes
        return (_rebuild, (float(self), self.name, self.unit, self.details))

    def to_dict(self, *, max_list: int = 4096) -> dict:
        """A JSON-able dict: ``metric``, ``value``, ``unit`` and the details.

        Maps (arrays of two or more dimensions with more than 1024 values)
        are summarised as ``{shape, mean, median, p95, min, max}``; smaller
        arrays (per-patch tables) and 1-D arrays up to ``max_list`` values
        (curves) become lists; longer ones are summarised.
        Non-finite floats become ``None`` so the result is strict JSON.
        """
        out = {"metric": self.name, "value": _jsonable(float(self), max_list), "unit": self.unit}
        for key, val in self.details.items():
            out[key] = _jsonable(val, max_list)
        return out


def _rebuild(value, name, unit, details):
    return MetricResult(value, name=name, unit=unit, details=details)


def median_and_p95(values: np.ndarray) -> tuple[float, float]:
    """``np.median(values)`` and ``np.percentile(values, 95)`` of a 1-D
    finite float64 array from one partition where numpy makes two (a
    S-CIELAB map spent 15 ms of its 100 in them, measured): numpy's own
    formulas, so the same bits (tests/metrics/test_result.py checks
    equality): the middle value or the mean of the middle pair, and the
    'linear' method's interpolation between the order statistics either side
    of (n - 1) x 0.95, from the upper one where the fraction is at least 1/2
    (numpy's ``_lerp``)."""
    n = values.size
    if n < 2:
        return float(np.median(values)), float(np.percentile(values, 95))
    mid = n // 2
    vi = (n - 1) * 0.95
    lo = int(math.floor(vi))  # lo + 1 <= n - 1: vi < n - 1
    part = np.partition(values, sorted({mid - 1 + n % 2, mid, lo, lo + 1}))
    median = part[mid] if n % 2 else (part[mid - 1] + part[mid]) / 2.0
    a, b, t = part[lo], part[lo + 1], vi - lo
    d = b - a
    p95 = b - d * (1.0 - t) if t >= 0.5 else a + d * t
    return float(median), float(p95)


def summarise_array(arr, *, order_statistics: bool = True) -> dict:
    """Shape and order statistics of an array (NaNs ignored); with
    ``order_statistics`` False, ``median`` and ``p95`` are None (no partial
    sort)."""
    a = np.asarray(arr, dtype=np.float64)
    flat = a.ravel()
    finite = flat if np.isfinite(flat.sum()) else flat[np.isfinite(flat)]  # a finite sum: every value finite
    if finite.size == 0:
        return {"shape": list(a.shape), "n": 0}
    median, p95 = median_and_p95(finite) if order_statistics else (None, None)
    return {
        "shape": list(a.shape),
        "mean": float(finite.mean()),
        "median": median,
        "p95": p95,
        "min": float(finite.min()),
        "max": float(finite.max()),
    }


def _jsonable(val, max_list):
    if isinstance(val, MetricResult):
        return val.to_dict(max_list=max_list)
    if isinstance(val, dict):
        return {str(k): _jsonable(v, max_list) for k, v in val.items()}
    if isinstance(val, (list, tuple)):
        return [_jsonable(v, max_list) for v in val]
    if isinstance(val, np.ndarray):
        if (val.ndim >= 2 and val.size > 1024) or val.size > max_list:
            return summarise_array(val)
        return [_jsonable(v, max_list) for v in val.tolist()]
    if isinstance(val, (np.bool_, bool)):
        return bool(val)
    if isinstance(val, (np.integer,)):
        return int(val)
    if isinstance(val, (float, np.floating)):
        f = float(val)
        return f if math.isfinite(f) else None
    return val
