"""MATLAB's ``conv2(x, u * v', 'same')`` for a separable kernel, as two
compiled passes (Numba): down the columns with ``u``, then along the rows
with ``v``, zeros outside the image, MATLAB's alignment (the full
convolution's central part from index ``floor(m / 2)``, for odd and even
lengths alike).

Written by hand for speed only: HaarPSI's and MDSI's kernels (the 2 x 2
mean, the 3 x 3 Prewitt, the 4 x 4 and 8 x 8 Haar filters) are all outer
products of two vectors, and ndimage's 2-D direct convolution or an FFT
took 4.7-28 ms a filtering of a 636 x 720 image (1.3-3.6 ms here), where these passes add whole
rows (down the columns) or shifted copies of one zero-extended row (along
the rows), which the compiler vectorises.  The sums are the same products
in another order, within about 1e-15 relative of the 2-D convolution
(tests/test_fast_paths.py).
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ..io.jit_cache import tolerate_cache_write_errors

tolerate_cache_write_errors()  # the kernel cache is a write that may fail (a full disk): io/jit_cache.py


@nb.njit(cache=True, nogil=True)
def _columns(x, u, out):  # pragma: no cover - compiled
    h, w = x.shape
    m = u.shape[0]
    s = m // 2
    for i in range(h):
        o = out[i]
        for j in range(w):
            o[j] = 0.0
        for k in range(m):
            r = i + s - k
            if 0 <= r < h:
                uk = u[k]
                src = x[r]
                for j in range(w):
                    o[j] += src[j] * uk


@nb.njit(cache=True, nogil=True)
def _rows(x, v, out):  # pragma: no cover - compiled
    h, w = x.shape
    m = v.shape[0]
    s = m // 2
    buf = np.zeros(w + 2 * m, dtype=x.dtype)  # one row with m zeros each side
    for i in range(h):
        src = x[i]
        for j in range(w):
            buf[m + j] = src[j]
        o = out[i]
        for j in range(w):
            o[j] = 0.0
        for k in range(m):
            a = buf[m + s - k:m + s - k + w]  # out[j] += x[j + s - k] v[k]
            vk = v[k]
            for j in range(w):
                o[j] += a[j] * vk


def separable_factors(kernel: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """(u, v) with ``np.outer(u, v)`` equal to the 2-D ``kernel`` bit for
    bit, or None when no such pair is found (the kernel is not an exact
    outer product)."""
    k = np.asarray(kernel, dtype=np.float64)
    if k.ndim != 2 or not k.size or not np.all(np.isfinite(k)):
        return None
    i, j = np.unravel_index(int(np.argmax(np.abs(k))), k.shape)
    if k[i, j] == 0.0:
        return None
    u, v = k[:, j] / k[i, j], k[i, :].copy()
    return (u, v) if np.array_equal(np.outer(u, v), k) else None


def conv2_same_separable(x: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """MATLAB ``conv2(x, np.outer(u, v), 'same')`` of a 2-D float64 ``x``."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    tmp = np.empty_like(x)
    out = np.empty_like(x)
    if x.size:
        _columns(x, np.ascontiguousarray(u, dtype=np.float64), tmp)
        _rows(tmp, np.ascontiguousarray(v, dtype=np.float64), out)
    return out
