"""POCS demosaicing: alternating projections onto the observation and
detail constraint sets (Gunturk, Altunbasak, Mersereau 2002), any CFA.

Sets, for every channel c but the reference:

* observation: c equals the mosaic at its own samples;
* detail: each high-pass subband of c (LH, HL, HH of an undecimated
  filterbank, analysis h0 = [1 2 1]/4, h1 = [1 -2 1]/4, synthesis
  g0 = [-1 2 6 2 -1]/8, g1 = [1 2 -6 2 1]/8, further levels with the filters
  dilated by 2, as in ISETCam's Pocs.m) lies within +-T of the reference's.

Because the filterbank reconstructs perfectly and is linear, projecting
onto the detail set with T = 0 is ``c <- ref + P(c - ref)``, P the
filterbank's low-pass path (a separable 7-tap filter for one level, 19 for
two): one filtering per channel and iteration.  T > 0 clips the subbands of
c - ref explicitly.

Steps (generalised; research/cfa-demosaic.md s. 3.4):

1. Initialise the reference by the edge-directed step of
   'adaptive-laplacian' (Hamilton-Adams classifiers on Bayer; the luminance
   estimate of 'laplacian' when no channel is densest), the other channels
   by bilinear.
2. Optionally (``update_reference``; off, as in ISETCam, because it measured
   0.5 dB worse on the photographs) update the reference at each other
   channel's sites with that channel's detail (Gunturk's green update).
3. Iterate: detail projection, then observation projection, until the RMS
   change of an iteration falls below ``tolerance`` times the mosaic's RMS,
   or ``iterations`` are done (10 by default, as ISETCam).  With a
   luminance reference, the luminance is re-formed from the channels after
   every iteration, so all channels converge to shared detail.

Levels: one when every channel has at least 1/6 of the pixels, two when one
is sparser (the Kodak RGBW tiles), see :func:`_levels`.

Differs from ISETCam: any CFA (ISETCam falls back to bilinear off Bayer),
no 1-pixel shift for GRBG/GBRG/BGGR, borders by a phase-preserving mirror
rather than a 3-pixel bilinear frame, no clipping of negative values.

Written by hand: colour-demosaicing has no POCS, and no library generalises
it to arbitrary CFAs.

References
----------
B. K. Gunturk, Y. Altunbasak, R. M. Mersereau, "Color plane interpolation
using alternating projections", IEEE Trans. Image Processing 11(9),
997-1013 (2002).
"""

from __future__ import annotations

__all__ = ["pocs", "lowpass_kernel"]

import functools

import numpy as np
from scipy import ndimage

from ..errors import CfaMitsubaError
from .bilinear import bilinear_image
from .demosaic import AccuracyBar, DemosaicMethod
from .laplacian_reference import MHC_ALPHA, reference_adaptive, reference_for, window_rms
from .mosaic import geometry

_H0 = np.array([1.0, 2.0, 1.0]) / 4.0
_H1 = np.array([1.0, -2.0, 1.0]) / 4.0
_G0 = np.array([-1.0, 2.0, 6.0, 2.0, -1.0]) / 8.0
_G1 = np.array([1.0, 2.0, -6.0, 2.0, 1.0]) / 8.0


def _dilate(k: np.ndarray, factor: int) -> np.ndarray:
    out = np.zeros((len(k) - 1) * factor + 1)
    out[::factor] = k
    return out


@functools.lru_cache(maxsize=8)
def lowpass_kernel(levels: int = 2) -> np.ndarray:
    """The 1-D kernel of the filterbank's low-pass path (analysis then
    synthesis of the approximation band through ``levels`` levels); unit
    DC gain, symmetric (19 taps for two levels)."""
    k = np.array([1.0])
    for level in range(levels):
        f = 2 ** level
        k = np.convolve(k, np.convolve(_dilate(_H0, f), _dilate(_G0, f)))
    k.flags.writeable = False
    return k


def _filter(x, k, axis):
    return ndimage.correlate1d(x, k, axis=axis, mode="mirror")


def _subbands(x, level, levels, t):
    f = 2 ** level
    h0, h1, g0, g1 = (_dilate(k, f) for k in (_H0, _H1, _G0, _G1))
    lo, hi = _filter(x, h0, 0), _filter(x, h1, 0)
    ll = _filter(lo, h0, 1)
    ll = _subbands(ll, level + 1, levels, t) if level + 1 < levels else ll
    bands = (
        (ll, g0, g0),
        (np.clip(_filter(lo, h1, 1), -t, t), g0, g1),
        (np.clip(_filter(hi, h0, 1), -t, t), g1, g0),
        (np.clip(_filter(hi, h1, 1), -t, t), g1, g1),
    )
    return sum(_filter(_filter(b, gr, 0), gc, 1) for b, gr, gc in bands)


def _update_reference(refimg, raw, mosaic, c: int) -> None:
    """Gunturk's step 2 at the samples of channel ``c``: the reference
    there becomes ``y + P_c(ref - y)``, P_c the one-level low-pass dilated
    to c's sample spacing (round(1 / sqrt(density)), 2 for Bayer's R and B,
    where this is the paper's filtering of the downsampled planes) and
    evaluated as a normalised convolution over c's samples only."""
    th, tw = mosaic.tile_shape
    spacing = max(1, int(round(1.0 / np.sqrt(mosaic.densities[c]))))
    k = _dilate(lowpass_kernel(1), spacing)
    m = mosaic.masks(raw.shape)[c].astype(raw.dtype)
    num = _filter(_filter((refimg - raw) * m, k, 0), k, 1)
    den = _filter(_filter(m, k, 0), k, 1)
    for i, j in mosaic.phases(c):
        refimg[i::th, j::tw] = raw[i::th, j::tw] + num[i::th, j::tw] / den[i::th, j::tw]


def _levels(mosaic, levels) -> int:
    """Filterbank levels: ``levels``, or for 'auto' 1 when every channel has
    at least 1/6 of the pixels and 2 when one is sparser.  The low-pass of
    a colour difference must stay below the sparsest channel's sampling
    rate: measured on scikit-image's photographs, Bayer gains 0.7 dB from
    2 levels to 1, the Kodak RGBW tiles (R and B at 1/8) lose 0.9 dB."""
    if levels == "auto":
        return 1 if mosaic.densities.min() >= 1 / 6 - 1e-9 else 2
    if levels not in (1, 2, 3):
        raise CfaMitsubaError(f"levels must be 1, 2, 3 or 'auto', got {levels!r}")
    return int(levels)


def pocs(raw, cfa, *, iterations: int = 10, tolerance: float = 1e-3, threshold: float = 0.0, levels="auto",
         update_reference: bool = False, alpha: float = MHC_ALPHA, reference=None, luminance_weights=None,
         info: dict | None = None, mosaic_rms: float | None = None):
    """Alternating-projections demosaic (Gunturk et al. 2002), any CFA.

    Parameters
    ----------
    raw : (H, W) float64 white-balanced mosaic (white balance matters: the
        channels share the reference's detail at its amplitude).
    cfa : CFA (``pattern``, ``channels``).
    iterations : at most this many projection rounds (default 10).
    tolerance : stop early once an iteration changes the channels by less
        than this RMS, relative to the mosaic's RMS (default 1e-3).
    threshold : T of the detail set, in the mosaic's unit (0: copy the
        reference's detail, the paper's recommendation).
    levels : filterbank levels, 1, 2 or 3, or 'auto' (default: 1 unless a
        channel has less than 1/6 of the pixels, then 2; ISETCam uses 2).
    update_reference : Gunturk's step 2: the reference at each other
        channel's sites becomes ``y + P_c(ref - y)`` (default off, as
        ISETCam; measured 0.5 dB worse on Bayer photographs).
    alpha, reference, luminance_weights : as for 'adaptive-laplacian',
        which initialises the reference.
    info : a dict to receive ``iterations`` (done) and ``change`` (last
        relative RMS change).
    mosaic_rms : the whole mosaic's RMS when ``raw`` is a window of it
        (the edge-directed reference's eps, as 'adaptive-laplacian').

    Returns
    -------
    (H, W, C) float64 in ``cfa.channels`` order.

    Examples
    --------
    >>> import numpy as np
    >>> from cfa_mitsuba.isp import demosaic
    >>> info = {}
    >>> out = demosaic(np.full((8, 8), 0.25), "rgbw3", "pocs", info=info)
    >>> float(np.abs(out - 0.25).max()), info["iterations"]
    (0.0, 1)
    """
    if not (isinstance(iterations, (int, np.integer)) and 0 <= iterations <= 1000):
        raise CfaMitsubaError(f"iterations must be an integer in 0..1000, got {iterations!r}")
    for name, v in (("tolerance", tolerance), ("threshold", threshold)):
        if not (isinstance(v, (int, float)) and np.isfinite(v) and v >= 0):
            raise CfaMitsubaError(f"{name} must be a finite number >= 0, got {v!r}")
    mosaic = geometry(cfa)
    levels = _levels(mosaic, levels)
    ref = reference_for(cfa, mosaic, reference, luminance_weights)
    n = len(mosaic.channels)
    shape = raw.shape
    # both made by 'bilinear' and 'adaptive-laplacian' just before on the same mosaic, in a study (._memo)
    x = np.moveaxis(bilinear_image(raw, mosaic), -1, 0).copy()  # (C, H, W), C order
    others = [c for c in range(n) if c != ref.channel]
    w = np.asarray(ref.weights, dtype=raw.dtype)
    refimg = reference_adaptive(raw, mosaic, ref, alpha, mosaic_rms=mosaic_rms)
    if ref.channel is not None:
        if update_reference:
            refimg = refimg.copy()
            for c in others:
                _update_reference(refimg, raw, mosaic, c)
        x[ref.channel] = refimg
    scale = max(float(np.sqrt(np.mean(raw * raw))), np.finfo(float).tiny)
    done, change = 0, 0.0
    observed = {c: mosaic.index == c for c in others}  # (th, tw): where each channel is sampled
    d = np.empty(shape, raw.dtype) if threshold else None  # reused: no allocation per pass
    k = lowpass_kernel(levels).astype(raw.dtype)  # a float32 mosaic is filtered in float32
    # here, not at import: Numba takes a third of a second to load
    from ._pocs_kernel import lowpass_project, project

    for _ in range(iterations):
        change = 0.0
        for c in others:
            # the detail projection ref + P(x_c - ref) (module doc: for T = 0, P is the low-pass path;
            # T > 0 clips the subbands), then the observations, in one pass into x_c
            if threshold == 0.0:
                # the difference, the low-pass (ndimage.correlate1d(axis=0, then 1, mode="mirror")'s
                # sums) and the projection row by row, d and P(d) never written out
                # (._pocs_kernel.lowpass_project)
                total = lowpass_project(x[c], refimg, raw, observed[c], k)
            else:
                np.subtract(x[c], refimg, out=d)
                total = project(x[c], refimg, _subbands(d, 0, levels, threshold), raw, observed[c])
            change = max(change, float(np.sqrt(total / raw.size)) / scale)
        done += 1
        if ref.channel is None:
            refimg = np.tensordot(w, x, axes=1)
        if change < tolerance:
            break
    if info is not None:
        info.update(iterations=done, change=change)
    return np.moveaxis(x, 0, -1)


def support_radius(cfa, options: dict) -> int | None:
    """How far (px) an output pixel reads the mosaic: the start's reach (the
    bilinear estimates', the edge-directed reference's) plus, per
    iteration, the low-pass path's half-length (3 px at one level, 9 at
    two): iterations x half-length, so 10 iterations at one level (Bayer)
    reach 30 px past the start.  None (the whole mosaic) when the early stop can
    end the loop (``tolerance`` > 0: the change it compares is the whole
    image's, so a window could stop after another number of passes), when
    the detail set clips subbands (``threshold`` > 0: not bounded here), the
    reference is updated (``update_reference``) or is the luminance (no
    single densest channel: each pass's ``np.tensordot`` goes to BLAS, whose
    sums are rounded differently on images of another width, measured).
    """
    if options.get("tolerance", 1e-3) > 0 or options.get("threshold", 0.0) != 0 or options.get("update_reference"):
        return None
    from .bilinear import support_radius as bilinear_reach
    from .laplacian import support_radius as laplacian_reach

    mosaic = geometry(cfa)
    if reference_for(cfa, mosaic, options.get("reference"), options.get("luminance_weights")).channel is None:
        return None
    half = (len(lowpass_kernel(_levels(mosaic, options.get("levels", "auto")))) - 1) // 2
    start = max(bilinear_reach(cfa, options), laplacian_reach(cfa, options, adaptive=True))
    return int(start + int(options.get("iterations", 10)) * half)


#: This module's method (registered by :func:`.demosaic.collect_demosaics`).
DEMOSAICS = (DemosaicMethod(name="pocs", function=pocs, order=4, support=support_radius, window_options=window_rms,
                            accuracy=AccuracyBar(ramp_margin_px=16),  # its low-pass spreads the border's fold
                            description="alternating projections onto observation and detail sets (Gunturk et al. "
                                        "2002)"),)
