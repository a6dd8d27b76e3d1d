"""The edge-directed step of 'adaptive-laplacian''s colour differences
(:func:`~cfa_mitsuba.isp.laplacian.colour_differences`) for one gap phase
in one compiled pass (Numba), where numpy made about ten whole-phase
temporaries per direction, then stacked them and combined them.

Written by hand for speed only.  Each output is the same IEEE operations in
the same order as the numpy version: per direction the linear
interpolations, the detail, the estimate and its cost; then the weights,
the weighted sum and the weights' sum over the directions in order, and
their quotient.  Every constant is rounded to the image's precision first,
as numpy rounds a Python number for a float32 array, except the soft
weights' regulariser, a float64 number that numpy keeps (the soft weights
and their sums are float64 there too, and so here), so the demosaic is
bit for bit the same (tests/test_fast_paths.py compares every CFA and
precision with the numpy steps).
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ..io.jit_cache import tolerate_cache_write_errors

tolerate_cache_write_errors()  # the kernel cache is a write that may fail (a full disk): io/jit_cache.py


@nb.njit(inline="always")
def _lin(v_plus, v_minus, tp, tm, half, ftp, fntm, span, symmetric):
    if symmetric:
        return half * (v_plus + v_minus)
    return (fntm * v_plus + ftp * v_minus) / span


@nb.njit(cache=True, nogil=True)
def _phase(ext_y, ext_r, ref0, r0, c0, th, tw, steps, consts, numbers, eps, soft, out):  # pragma: no cover - compiled
    # steps: (D, 4) int (dr, dc, tp, tm); consts: (D, 4) of the image's type (-tm, tp, tp - tm, 0.5);
    # numbers: of the image's type (0, 1, 2, g); eps: float64
    n_dir = steps.shape[0]
    zero, one, two, g = numbers[0], numbers[1], numbers[2], numbers[3]
    est = np.empty(n_dir, dtype=ext_y.dtype)
    cost = np.empty(n_dir, dtype=ext_y.dtype)
    for a in range(out.shape[0]):
        r = r0 + a * th
        for b in range(out.shape[1]):
            c = c0 + b * tw
            base = ref0[a, b]
            for d in range(n_dir):
                dr, dc, tp, tm = steps[d, 0], steps[d, 1], steps[d, 2], steps[d, 3]
                fntm, ftp, span, half = consts[d, 0], consts[d, 1], consts[d, 2], consts[d, 3]
                symmetric = tp == -tm
                y1 = ext_y[r + tp * dr, c + tp * dc]
                y2 = ext_y[r + tm * dr, c + tm * dc]
                detail = base - _lin(ext_r[r + tp * dr, c + tp * dc], ext_r[r + tm * dr, c + tm * dc],
                                     tp, tm, half, ftp, fntm, span, symmetric)
                est[d] = _lin(y1, y2, tp, tm, half, ftp, fntm, span, symmetric) + g * detail
                cost[d] = np.abs(y1 - y2) + two * np.abs(detail)
            if soft:  # in float64: the regulariser is a float64 number, which numpy does not round
                w = 1.0 / (np.float64(cost[0]) + eps)
                num = np.float64(est[0]) * w
                den = w
                for d in range(1, n_dir):
                    w = 1.0 / (np.float64(cost[d]) + eps)
                    num = num + np.float64(est[d]) * w
                    den = den + w
                out[a, b] = num / den
            else:
                low = cost[0]
                for d in range(1, n_dir):
                    low = min(low, cost[d])
                w = one if cost[0] <= low else zero
                num = est[0] * w
                den = w
                for d in range(1, n_dir):
                    w = one if cost[d] <= low else zero
                    num = num + est[d] * w
                    den = den + w
                out[a, b] = num / den


def directional_phase(ext_y, ext_r, ref0, r0: int, c0: int, tile, dirs, g: float, eps: float, soft: bool,
                      out: np.ndarray) -> np.ndarray:
    """Fill ``out`` (a phase's (h, w) view) with the combined directional
    estimates at extended pixels (r0 + a th, c0 + b tw): ``dirs`` the
    ((dr, dc), t_plus, t_minus) of :func:`~cfa_mitsuba.isp.mosaic.directional_samples`,
    ``ref0`` the reference at the phase, ``g`` the chroma gain, ``eps`` the
    soft weights' regulariser."""
    dtype = ext_y.dtype
    steps = np.array([(d[0], d[1], tp, tm) for d, tp, tm in dirs], dtype=np.int64)
    consts = np.array([(-tm, tp, tp - tm, 0.5) for _, tp, tm in dirs], dtype=np.float64).astype(dtype)
    numbers = np.array([0.0, 1.0, 2.0, g], dtype=np.float64).astype(dtype)
    _phase(ext_y, ext_r, ref0, int(r0), int(c0), int(tile[0]), int(tile[1]), steps, consts, numbers, float(eps),
           bool(soft), out)
    return out
