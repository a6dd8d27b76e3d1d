"""Stage 1 of the gradient-corrected demosaics ('laplacian',
'adaptive-laplacian', and POCS's starting point): the reference channel
estimated at every pixel, non-adaptively (:func:`reference_laplacian`:
Malvar-He-Cutler's green kernel on Bayer, generalised) or along the
directions in which the reference has samples (:func:`reference_adaptive`:
Hamilton-Adams' green on Bayer, generalised).  :mod:`.laplacian` states the
formulas and holds stage 2 (the colour differences) and the methods.
"""

from __future__ import annotations

__all__ = ["MHC_ALPHA", "Reference", "reference_for", "reference_stencils", "reference_laplacian",
           "reference_adaptive"]

from dataclasses import dataclass

import numpy as np

from ..errors import CfaMitsubaError
from ._memo import LastImage
from .mosaic import (
    Mosaic,
    Stencil,
    apply_stencils,
    evaluate_stencil,
    diamond_stencil,
    directional_samples,
    extend,
    phase_view,
    tent_stencil,
)

#: Malvar-He-Cutler's gain for the green step (alpha = 1/2).
MHC_ALPHA = 0.5


@dataclass(frozen=True)
class Reference:
    """The detail carrier of the cross-channel methods.

    channel : index of the reference channel, or None for a luminance.
    weights : (C,) weights summing to 1 (one-hot for a channel).
    """

    channel: int | None
    weights: tuple[float, ...]


def reference_for(cfa, mosaic: Mosaic, reference=None, luminance_weights=None) -> Reference:
    """Choose the reference: ``reference`` = a channel name, 'luminance',
    or None for automatic (the unique densest channel, else luminance).

    ``luminance_weights``: (C,) or {channel: weight}; by default from the
    CFA's spectral sensitivities (:func:`cfa_mitsuba.isp.colour_matrix.luminance_weights`).
    """
    n = len(mosaic.channels)
    if reference is None:
        dens = mosaic.densities
        top = np.flatnonzero(dens >= dens.max() - 1e-12)
        if top.size == 1:
            reference = mosaic.channels[int(top[0])]
        else:
            reference = "luminance"
    if reference != "luminance":
        if reference not in mosaic.channels:
            raise CfaMitsubaError(
                f"reference {reference!r} is not a channel of the CFA ({', '.join(mosaic.channels)}) nor 'luminance'"
            )
        c = mosaic.channels.index(reference)
        w = np.zeros(n)
        w[c] = 1.0
        return Reference(c, tuple(w.tolist()))
    if luminance_weights is None:
        from .colour_matrix import cfa_luminance_weights

        w = cfa_luminance_weights(cfa)
    elif isinstance(luminance_weights, dict):
        unknown = set(luminance_weights) - set(mosaic.channels)
        if unknown:
            raise CfaMitsubaError(f"luminance weight for unknown channel {sorted(unknown)[0]!r}")
        w = np.array([float(luminance_weights.get(c, 0.0)) for c in mosaic.channels])
    else:
        w = np.asarray(luminance_weights, dtype=np.float64).reshape(-1)
        if w.size != n:
            raise CfaMitsubaError(f"luminance_weights needs {n} values (one per channel), got {w.size}")
    if not np.all(np.isfinite(w)) or abs(w.sum()) < 1e-12:
        raise CfaMitsubaError("luminance_weights must be finite with a non-zero sum")
    return Reference(None, tuple((w / w.sum()).tolist()))


def _check_gains(alpha: float, chroma_gain: float) -> None:
    for name, v in (("alpha", alpha), ("chroma_gain", chroma_gain)):
        if not (isinstance(v, (int, float)) and np.isfinite(v) and 0 <= v <= 2):
            raise CfaMitsubaError(f"{name} must be a number in 0..2, got {v!r}")


# --- stage 1: the reference -----------------------------------------------------


def _correction(mosaic: Mosaic, ref: Reference, alpha: float, i: int, j: int) -> dict:
    """Taps of the gradient correction a(p) (y(p) - NC'_k(p)) at phase
    (i, j): a(p) = sum over the missing channels c of w_c 4 alpha
    m2(NC_c) / m2(NC'_k) (module doc)."""
    k = int(mosaic.index[i, j])
    dia = diamond_stencil(mosaic, k, i, j)
    gain = sum(wc * 4.0 * alpha * tent_stencil(mosaic, c, i, j).second_moment / dia.second_moment
               for c, wc in enumerate(ref.weights) if wc != 0.0 and c != k)
    taps = {(0, 0): gain}
    for q, w in zip(dia.offsets, dia.weights):
        taps[q] = -gain * w
    return taps


def _stencil(taps: dict) -> Stencil:
    offs = tuple(q for q in taps if taps[q] != 0.0)
    return Stencil(offs, tuple(taps[q] for q in offs))


def reference_stencils(mosaic: Mosaic, ref: Reference, alpha: float) -> dict:
    """Per-phase stencils of the non-adaptive reference estimate (every
    phase where it is not simply the observed sample)."""
    out = {}
    for (i, j), k in np.ndenumerate(mosaic.index):
        if ref.channel == k:
            continue
        taps = _correction(mosaic, ref, alpha, i, j)
        for c, wc in enumerate(ref.weights):
            if wc == 0.0:
                continue
            if c == k:
                taps[(0, 0)] = taps.get((0, 0), 0.0) + wc
                continue
            st = tent_stencil(mosaic, c, i, j)
            for q, w in zip(st.offsets, st.weights):
                taps[q] = taps.get(q, 0.0) + wc * w
        out[(i, j)] = _stencil(taps)
    return out


def _stencil_radius(stencils: dict) -> int:
    return max((s.radius for s in stencils.values()), default=0)


def reference_laplacian(raw: np.ndarray, mosaic: Mosaic, ref: Reference, alpha: float) -> np.ndarray:
    """(H, W) non-adaptive reference estimate."""
    stencils = reference_stencils(mosaic, ref, alpha)
    ext, ph, pw = extend(raw, mosaic, _stencil_radius(stencils))
    out = raw.copy()  # the reference channel's own samples stay
    return apply_stencils(ext, ph, pw, raw.shape, mosaic.tile_shape, stencils, out)


def _lin(v_plus, v_minus, tp: int, tm: int):
    """Linear interpolation at 0 between values at tp > 0 and tm < 0."""
    if tp == -tm:
        return 0.5 * (v_plus + v_minus)
    return (-tm * v_plus + tp * v_minus) / (tp - tm)


def _check_weighting(weighting) -> None:
    if weighting not in ("soft", "hard"):
        raise CfaMitsubaError(f"weighting must be 'soft' or 'hard', got {weighting!r}")


def mosaic_rms(raw) -> float:
    """The mosaic's RMS, sqrt(mean(raw^2)), in the mosaic's unit."""
    return float(np.sqrt(np.mean(raw * raw)))


def window_rms(raw) -> dict:
    """A window's ``mosaic_rms`` keyword: the whole mosaic's RMS (the
    methods' ``window_options``, study/roi.py)."""
    return {"mosaic_rms": mosaic_rms(raw)}


def _eps(raw, rms: float | None = None) -> float:
    """Regulariser of the soft weights: 1e-3 of the mosaic's RMS (so the
    method is scale-invariant); ``rms``: the RMS of the whole mosaic when
    ``raw`` is a window of it (the same eps, so the window's values are the
    whole's)."""
    return 1e-3 * (mosaic_rms(raw) if rms is None else float(rms)) + np.finfo(float).tiny


def _choose(estimates: list, costs: list, weighting: str, eps: float):
    """Combine directional estimates by their costs: 'hard' keeps the one
    of least cost (exact ties averaged: Hamilton-Adams), 'soft' weights
    each by 1 / (cost + eps)."""
    cost = np.stack(costs)
    if weighting == "soft":
        w = 1.0 / (cost + eps)
    else:
        w = (cost <= cost.min(axis=0)).astype(cost.dtype)
    return np.einsum("d...,d...->...", np.stack(estimates), w) / w.sum(axis=0)


def reference_adaptive(raw: np.ndarray, mosaic: Mosaic, ref: Reference, alpha: float,
                       weighting: str = "soft", mosaic_rms: float | None = None) -> np.ndarray:
    """(H, W) edge-directed reference estimate (Hamilton-Adams generalised;
    the non-adaptive one for a luminance reference).

    Along each direction d in which the reference has samples on both sides
    (t+ > 0 > t-): ``lin_ref + correction``.  The correction is the centre
    channel's directional second difference, ``a_d (y - lin_k)``, when its
    own samples along d are close (s+ <= 2 t+ and -s- <= -2 t-, as on Bayer
    where t = 1, s = 2) or the reference's samples along d are at unequal
    distances (t+ != -t-: rgb2's vertical); otherwise the non-directional
    gradient correction of 'laplacian' (a second difference over a span
    wider than the interpolation's measures a different scale: measured
    worse on rgb5, rgbw2, rgb1 and rgb2).  With unequal distances and no
    own sample along d, no correction: the 2-D correction compensates the
    2-D stencil's blur, which the line interpolation does not have, and
    adding it sharpened rgb2 past the ideal sensor and made false colour on
    the chirp (docs/isp.md).  The cost is ``|ref(t+) - ref(t-)| +
    2 |y - lin_k|`` (the second term omitted where k has no sample along d).
    With fewer than two directions, the non-adaptive estimate.

    Read-only: kept for the next call on an equal mosaic with the same
    arguments, which 'pocs' makes after 'adaptive-laplacian'
    (:class:`~._memo.LastImage`).
    """
    return _LAST_REFERENCE.get((mosaic, ref, float(alpha), weighting, mosaic_rms), raw,
                               lambda: _reference_adaptive(raw, mosaic, ref, alpha, weighting, mosaic_rms))


#: the last mosaic's edge-directed reference (:func:`reference_adaptive`)
_LAST_REFERENCE = LastImage()


def _reference_adaptive(raw, mosaic, ref, alpha, weighting, rms=None):
    if ref.channel is None:
        return reference_laplacian(raw, mosaic, ref, alpha)
    th, tw = mosaic.tile_shape
    limit = max(th, tw)
    r = ref.channel
    fallback = reference_stencils(mosaic, ref, alpha)
    ext, ph, pw = extend(raw, mosaic, max(limit, _stencil_radius(fallback)))
    out = raw.copy()
    shape, tile = raw.shape, mosaic.tile_shape
    eps = _eps(raw, rms)
    for (i, j), k in np.ndenumerate(mosaic.index):
        if k == r:
            continue
        dirs = directional_samples(mosaic, r, i, j, limit)
        if len(dirs) < 2:
            apply_stencils(ext, ph, pw, shape, tile, {(i, j): fallback[(i, j)]}, out)
            continue
        own = {d: (sp, sm) for d, sp, sm in directional_samples(mosaic, int(k), i, j, limit)}

        def at(t, d):
            return phase_view(ext, ph, pw, shape, tile, i, j, t * d[0], t * d[1])

        y0 = at(0, (0, 0))
        corr = None
        est, cost = [], []
        for d, tp, tm in dirs:
            a1, a2 = at(tp, d), at(tm, d)
            c = np.abs(a1 - a2)
            sp, sm = own.get(d, (None, None))
            curv = None if sp is None else y0 - _lin(at(sp, d), at(sm, d), sp, sm)
            # Reference samples at unequal distances along d (rgb2's G at +2 and
            # -1 vertically) make lin_ref a different interpolation from the 2-D
            # stencil the non-directional correction compensates: adding it would
            # add the cross-direction curvature (measured: MTF50 1.11 x the ideal
            # sensor's, false colour at 0.17 cy/px on the chirp).  There the
            # directional second difference is used, or none.
            asymmetric = tp != -tm
            if curv is not None and ((sp <= 2 * tp and -sm <= -2 * tm) or asymmetric):
                e = _lin(a1, a2, tp, tm) + (4.0 * alpha * (tp * -tm) / (sp * -sm)) * curv
            elif asymmetric:
                e = _lin(a1, a2, tp, tm)
            else:
                if corr is None:
                    corr = evaluate_stencil(ext, ph, pw, shape, tile, i, j,
                                            _stencil(_correction(mosaic, ref, alpha, i, j)))
                e = _lin(a1, a2, tp, tm) + corr
            if curv is not None:
                c = c + 2.0 * np.abs(curv)
            est.append(e)
            cost.append(c)
        out[i::th, j::tw] = _choose(est, cost, weighting, eps)
    return out
