"""Demosaicing: the registry of methods and the checked entry point.

``demosaic(raw, cfa, method, **options)`` takes a white-balanced mosaic
(2-D float, any H x W at least one tile, partial tiles allowed at the
borders) and returns (H, W, C) in ``cfa.channels`` order.  It applies no
gains of its own and keeps every observed sample as it was.

A method is one registry record (:class:`DemosaicMethod`): a function
``f(raw, cfa, **options)`` that receives the checked float64 mosaic and a
CFA (``pattern``, ``channels``) and returns (H, W, C), and what the rest of
the program needs to know of it: whether it is linear in the mosaic (the
design proxy predicts a linear method's noise and sharpness exactly from its
impulse responses) and the accuracy it promises on smooth images
(:class:`AccuracyBar`; none for a baseline such as nearest neighbour).  A
method of the package is one module of ``isp/`` declaring ``DEMOSAICS =
(DemosaicMethod(...), ...)`` beside its function (:func:`collect_demosaics`
registers them when the package loads); a user's or a test's is added with
:func:`register_demosaic`.
"""

from __future__ import annotations

__all__ = ["demosaic", "register_demosaic", "list_demosaics", "get_demosaic", "get_demosaic_record", "DemosaicMethod",
           "AccuracyBar", "collect_demosaics", "unregister_demosaic", "demosaic_parameters", "PRECISIONS"]

import inspect
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..errors import CfaMitsubaError
from .mosaic import geometry


@dataclass(frozen=True)
class AccuracyBar:
    """What a method promises on smooth, white-balanced achromatic content,
    where every channel equals the scene (the generic demosaic tests hold
    each method that declares a bar to it, on every CFA).

    smooth_max, smooth_mean : the largest and the mean error inside (6 px
        from the borders) on a smooth image of modulation 0.2 (periods of
        96 and 112 px plus a ramp), on layouts without same-colour blocks.
    border_max : the largest error anywhere, the borders included.
    block_max, block_mean, block_border_max : the same per unit of block
        size b on the block layouts (b x b same-colour blocks: their
        clustered samples make every method's error first order in the slope).
    uneven_max, uneven_mean, uneven_border_max : the same on the other
        layouts whose channels' samples sit unevenly around a pixel (sparse
        colour, same-colour quadrants, runs along diagonals: bilinear
        interpolation misses a linear ramp there, so the error is first
        order in the slope too; tests/registry_checks.py tells them apart).
    ramp_margin_px : a linear ramp is exact (to 1e-9) this far from the
        borders on Bayer.
    """

    smooth_max: float = 4e-3
    smooth_mean: float = 1.5e-3
    border_max: float = 0.05
    block_max: float = 0.015
    block_mean: float = 2e-3
    block_border_max: float = 0.03
    uneven_max: float = 0.02
    uneven_mean: float = 4e-3
    uneven_border_max: float = 0.1
    ramp_margin_px: int = 3


@dataclass(frozen=True, kw_only=True)
class DemosaicMethod:
    """A demosaicing method: its declaration in its module (``DEMOSAICS``)
    and its record in the registry.

    name, function, description : the method.
    order : its place in listings (the paper's four first).
    linear : whether the output is linear in the mosaic (the design proxy
        reads its noise gains and edge response off its impulse responses;
        a nonlinear method is predicted by the Laplacian's, its linear core).
    accuracy : the :class:`AccuracyBar` it meets on smooth images, or None
        for a baseline that promises none (nearest neighbour).
    support : ``support(cfa, options) -> int | None``: how far (pixels, in
        each direction) an output pixel reads the mosaic under ``options``
        (the method's keywords), so that a window of the mosaic widened by
        this margin demosaics the window's interior exactly as the whole
        mosaic does (a study's regions of interest, study/roi.py); None (the
        default, or returned): the output depends on the whole mosaic, or
        on more than the method can bound, and it is always demosaiced whole.
    window_options : ``window_options(mosaic) -> dict``: the keywords a
        window of ``mosaic`` (as the method receives it) needs to match the
        whole (the whole mosaic's statistics, e.g. its RMS); None: none.
    """

    name: str
    function: Callable
    description: str
    order: int = 1000
    linear: bool = False
    accuracy: AccuracyBar | None = None
    support: Callable | None = None
    window_options: Callable | None = None


_REGISTRY: dict[str, DemosaicMethod] = {}


def collect_demosaics(package: str) -> None:
    """Register the ``DEMOSAICS`` declared by every module of ``package``,
    in their ``order`` (done once by ``cfa_mitsuba.isp``)."""
    from .declared import declared_records

    for m in declared_records(package, "DEMOSAICS"):
        if m.name not in _REGISTRY:
            register_demosaic(m.name, m.function, description=m.description, linear=m.linear, accuracy=m.accuracy,
                              support=m.support, window_options=m.window_options)


def register_demosaic(name: str, function: Callable | None = None, *, description: str = "", linear: bool = False,
                      accuracy: AccuracyBar | None = None, replace: bool = False, support: Callable | None = None,
                      window_options: Callable | None = None):
    """Add a demosaicing method under ``name``.

    ``function(raw, cfa, **options) -> (H, W, C)``; ``raw`` is a checked 2-D
    float64 mosaic, ``cfa`` has ``pattern`` and ``channels``.  ``linear`` and
    ``accuracy`` as :class:`DemosaicMethod`'s (default: nonlinear, no
    accuracy bar), ``support`` and ``window_options`` as its (default: the
    output depends on the whole mosaic).  Usable as a decorator (``@register_demosaic("mine",
    description="...")``).

    Examples
    --------
    >>> import numpy as np
    >>> from cfa_mitsuba.isp import register_demosaic, demosaic
    >>> def nearest(raw, cfa):  # copies each channel's sample from its tile
    ...     return demosaic(raw, cfa, "bilinear")
    >>> _ = register_demosaic("example-nearest", nearest, description="example", replace=True)
    >>> demosaic(np.ones((4, 4)), "bayer", "example-nearest").shape
    (4, 4, 3)
    """

    def add(fn: Callable) -> Callable:
        if not callable(fn):
            raise CfaMitsubaError(f"demosaic method {name!r} must be callable")
        if name in _REGISTRY and not replace:
            raise CfaMitsubaError(f"a demosaicing method named {name!r} is already registered")
        desc = description or (inspect.getdoc(fn) or "").split("\n", 1)[0]
        _REGISTRY[name] = DemosaicMethod(name=name, function=fn, description=desc, linear=bool(linear),
                                         accuracy=accuracy, support=support, window_options=window_options)
        return fn

    return add(function) if function is not None else add


def unregister_demosaic(name: str) -> None:
    """Remove a registered method (a test's toy one)."""
    _REGISTRY.pop(name, None)


def list_demosaics() -> list[tuple[str, str]]:
    """(name, one-line description) of every registered method."""
    return [(e.name, e.description) for e in _REGISTRY.values()]


def get_demosaic_record(name: str) -> DemosaicMethod:
    """The :class:`DemosaicMethod` registered under ``name``."""
    if name not in _REGISTRY:
        raise CfaMitsubaError(f"unknown demosaicing method {name!r} (known: {', '.join(_REGISTRY)})")
    return _REGISTRY[name]


def get_demosaic(name: str) -> Callable:
    """The function registered under ``name``."""
    return get_demosaic_record(name).function


#: Keywords the processing fills for a method (its luminance reference, the
#: channels' luminance weights, an info dict, the whole mosaic's RMS for a
#: window of it): not options a user sets.
SUPPLIED_KEYWORDS = frozenset({"reference", "luminance_weights", "info", "mosaic_rms"})


def demosaic_parameters(name: str) -> dict:
    """{option: inspect.Parameter}: the keyword options of a method that a
    study (``[demosaics.<name>]``) or the command line may set."""
    fn = get_demosaic(name)
    return {k: p for k, p in inspect.signature(fn).parameters.items()
            if p.kind is inspect.Parameter.KEYWORD_ONLY and k not in SUPPLIED_KEYWORDS}


def resolve_cfa(cfa):
    """A CFA object from a CFA or a registered name."""
    if isinstance(cfa, str):
        from ..sensor import get_cfa

        return get_cfa(cfa)
    if not (hasattr(cfa, "pattern") and hasattr(cfa, "channels")):
        raise CfaMitsubaError(f"expected a CFA or a CFA name, got {type(cfa).__name__}")
    return cfa


def check_mosaic(raw, cfa) -> np.ndarray:
    """The mosaic as float64 (H, W), or a one-line error: not 2-D, smaller
    than the tile, non-numeric, NaN or infinite."""
    arr = np.asarray(raw)
    if arr.dtype.kind not in "biuf":
        raise CfaMitsubaError(f"mosaic must be numeric, got dtype {arr.dtype}")
    if arr.ndim != 2:
        raise CfaMitsubaError(
            f"mosaic must be 2-D (H, W) for a CFA, got shape {arr.shape}"
            + (" (a 3-channel image is the ideal sensor's XYZ: it needs no demosaicing)" if arr.ndim == 3 else "")
        )
    th, tw = np.asarray(cfa.pattern).shape
    if arr.shape[0] < th or arr.shape[1] < tw:
        raise CfaMitsubaError(
            f"mosaic of {arr.shape[0]} x {arr.shape[1]} pixels is smaller than the CFA tile ({th} x {tw})"
        )
    arr = np.asarray(arr, dtype=np.float64)
    finite = np.isfinite(arr)
    if not finite.all():
        bad = int(arr.size - np.count_nonzero(finite))
        raise CfaMitsubaError(f"mosaic contains {bad} NaN or infinite value(s)")
    return arr


#: ``precision`` -> the floating-point type a demosaicing method computes in
PRECISIONS = {"double": np.float64, "single": np.float32}


def check_precision(precision) -> type:
    """The dtype of a demosaicing ``precision`` ('double' or 'single'), or a one-line error."""
    if not isinstance(precision, str) or precision not in PRECISIONS:
        raise CfaMitsubaError(f"unknown demosaic precision {precision!r} (expected 'double' or 'single')")
    return PRECISIONS[precision]


def demosaic(raw, cfa, method: str = "bilinear", *, precision: str = "double", **options) -> np.ndarray:
    """Demosaic a white-balanced mosaic.

    Parameters
    ----------
    raw : (H, W) array, a white-balanced mosaic (any linear unit; each
        channel's response to the scene white should be equal, see
        :func:`cfa_mitsuba.isp.white_balance`).  H, W at least the tile;
        partial tiles at the borders are fine.  ``raw[0, 0]`` carries
        ``cfa.pattern[0, 0]``.
    cfa : a :class:`~cfa_mitsuba.sensor.cfa.CFA` or a registered CFA name.
    method : a registered method (``cfa-mitsuba list demosaics``):
        'bilinear', 'laplacian', 'adaptive-laplacian', 'pocs', or a user's.
    **options : method options, e.g. ``iterations=`` and ``tolerance=`` for
        'pocs', ``alpha=`` and ``chroma_gain=`` for the Laplacian methods,
        ``reference=`` and ``luminance_weights=`` for every method but
        'bilinear'.  An option a method does not take is an error.
    precision : 'double' (default) or 'single': the method computes in
        float32 from the mosaic rounded to float32 (the built-in methods
        keep float32 throughout: half the memory traffic and twice the SIMD
        lanes; the estimates within a few float32 roundings of the mosaic's
        range, tests/isp/test_demosaic_precision.py).  The result is
        float64 either way, and the observed samples are the mosaic's own
        float64 values.  A study demosaics in 'single' unless its ``[isp]
        demosaic_precision`` says otherwise (docs/study.md).

    Returns
    -------
    (H, W, C) float64 in ``cfa.channels`` order, in the unit of ``raw``;
    observed samples unchanged.  No clipping: an all-zero mosaic gives
    zeros, a uniform (e.g. saturated) mosaic gives that constant in every
    channel, and gradient-corrected methods may overshoot slightly below 0
    or above the input range at sharp edges (as real ISPs do before their
    final clip).

    Examples
    --------
    >>> import numpy as np
    >>> from cfa_mitsuba.isp import demosaic
    >>> demosaic(np.full((6, 6), 0.5), "rgbw2", "laplacian")[2, 3].round(12).tolist()
    [0.5, 0.5, 0.5, 0.5]
    """
    dtype = check_precision(precision)
    cfa = resolve_cfa(cfa)
    fn = get_demosaic(method)
    arr = check_mosaic(raw, cfa)
    try:
        inspect.signature(fn).bind(arr, cfa, **options)
    except TypeError as exc:
        raise CfaMitsubaError(f"demosaicing method {method!r}: {exc}") from None
    est = np.asarray(fn(arr if dtype is np.float64 else arr.astype(dtype), cfa, **options))
    shape = (*arr.shape, len(cfa.channels))
    if est.shape != shape:
        raise CfaMitsubaError(f"demosaicing method {method!r} returned shape {est.shape}, expected {shape}")
    mosaic = geometry(cfa)
    # observed samples are data, never estimates: the widening to float64, the samples and the
    # finiteness check in one compiled pass (._finish_kernel, the same values), numpy otherwise
    from ._finish_kernel import finish

    done = finish(est, arr, mosaic.index)
    if done is None:
        out = np.asarray(est, dtype=np.float64)
        th, tw = mosaic.tile_shape
        for (i, j), c in np.ndenumerate(mosaic.index):
            out[i::th, j::tw, c] = arr[i::th, j::tw]
        finite = bool(np.all(np.isfinite(out)))
    else:
        out, finite = done
    if not finite:
        raise CfaMitsubaError(f"demosaicing method {method!r} produced NaN or infinite values")
    return out
