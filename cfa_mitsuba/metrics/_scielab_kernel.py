"""The input of S-CIELAB's single-precision filtering in one compiled pass
(Numba): the difference test - reference, its opponent transform, the cast
to float32 and the symmetric extension, written straight into the
transform's zero-padded buffer, where numpy made five passes (subtract,
matrix product, cast, move the channel axis first, pad) and the transform a
sixth (its zero padding).

Written by hand for speed only.  Each opponent value is the matrix row's
three products summed left to right in float64, then rounded to float32
once; numpy's matrix product may sum in another order, so a value can
differ in its last float64 bit before that rounding (and, rarely, in its
last float32 bit after): far inside the single-precision bound that
tests/metrics/test_scielab.py checks.
"""

from __future__ import annotations

__all__ = ["opponent_difference_padded"]

import numba as nb
import numpy as np

from ..io.jit_cache import tolerate_cache_write_errors

tolerate_cache_write_errors()  # the kernel cache is a write that may fail (a full disk): io/jit_cache.py


@nb.njit(inline="always")
def _fold(i, n):
    """Index i folded into 0..n-1 by symmetric extension (d c b a | a b c d |
    d c b a): numpy's ``pad(mode='symmetric')``, repeated where the
    extension is longer than the image."""
    period = 2 * n
    i = i % period
    return period - 1 - i if i >= n else i


@nb.njit(inline="always")
def _put(test, ref, m, out, r, c, rr, cc):
    dx = test[r, c, 0] - ref[r, c, 0]
    dy = test[r, c, 1] - ref[r, c, 1]
    dz = test[r, c, 2] - ref[r, c, 2]
    for k in range(3):
        out[k, rr, cc] = m[k, 0] * dx + m[k, 1] * dy + m[k, 2] * dz


@nb.njit(cache=True, nogil=True)
def _fill(test, ref, m, half, out):  # pragma: no cover - compiled
    h, w = test.shape[0], test.shape[1]
    cols = np.empty(w + 2 * half, dtype=np.int64)  # folded once, not per pixel (an integer modulo each)
    for cc in range(cols.shape[0]):
        cols[cc] = _fold(cc - half, w)
    for rr in range(h + 2 * half):
        r = _fold(rr - half, h)
        for cc in range(half):
            _put(test, ref, m, out, r, cols[cc], rr, cc)
        for cc in range(half, half + w):  # the image's own columns, in order: a loop the compiler vectorises
            _put(test, ref, m, out, r, cc - half, rr, cc)
        for cc in range(half + w, w + 2 * half):
            _put(test, ref, m, out, r, cols[cc], rr, cc)


def opponent_difference_padded(test: np.ndarray, ref: np.ndarray, matrix: np.ndarray, half: int,
                               fshape: tuple[int, int]) -> np.ndarray:
    """(3, fh, fw) float32: ``matrix @ (test - ref)`` per pixel of the
    (H, W, 3) images, as planes, extended symmetrically by ``half`` pixels on
    every side and zero beyond (H + 2 half, W + 2 half) up to ``fshape``."""
    test = np.asarray(test, dtype=np.float64)
    ref = np.asarray(ref, dtype=np.float64)
    h, w = test.shape[:2]
    if ref.shape != test.shape or test.ndim != 3 or test.shape[2] != 3:
        raise ValueError(f"opponent_difference_padded: images {test.shape} and {ref.shape} must be the same (H, W, 3)")
    if fshape[0] < h + 2 * half or fshape[1] < w + 2 * half:
        raise ValueError(f"opponent_difference_padded: {fshape} is smaller than the extended image")
    out = np.empty((3, *fshape), dtype=np.float32)
    eh, ew = h + 2 * half, w + 2 * half  # _fill writes this corner; the rest is the transform's zero padding
    out[:, eh:] = 0.0
    out[:, :eh, ew:] = 0.0
    if h and w:
        _fill(test, ref, np.ascontiguousarray(matrix, dtype=np.float64), int(half), out)
    return out
