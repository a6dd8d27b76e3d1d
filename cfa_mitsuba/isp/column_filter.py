"""Correlation of an image with a symmetric 1-D kernel down its columns and
along its rows, as compiled loops (Numba):
``scipy.ndimage.correlate1d(x, k, axis=0 | 1, mode=...)`` for 'mirror' and
'reflect' extension, bit for bit.

Written by hand for speed only.  ndimage walks each column with a stride of
a row, and along a row it sums every output's taps in turn; these loops add
whole rows (down the columns) or whole shifted copies of one extended row
(along the rows), which the compiler vectorises: 4-5x faster down the
columns and about 3x along the rows on a camera image
(benchmarks/bench_demosaic.py times POCS, which spends its filtering here).
Both make ndimage's own sums in ndimage's own order (for a symmetric kernel:
the centre tap times the sample, then, from the outermost pair inwards, the
pair's sum times its weight), so the results are identical
(tests/isp/test_column_filter.py asserts equality).  A float32 image is
filtered in float32 (the kernel rounded to float32, the sums in float32:
twice the SIMD lanes and half the memory traffic), within float32 rounding
of ndimage, which sums in float64 whatever the input; every other input is
filtered in float64.  POCS's projections
(isp/pocs.py) and SSIM's Gaussian windows (metrics/ssim.py) spend most of
their filtering time in these passes.
"""

from __future__ import annotations

__all__ = ["correlate_columns", "correlate_along_rows"]

import numba as nb
import numpy as np

from ..io.jit_cache import tolerate_cache_write_errors

tolerate_cache_write_errors()  # the kernel cache is a write that may fail (a full disk): io/jit_cache.py

_MODES = {"mirror": 0, "reflect": 1}


@nb.njit(inline="always")
def _extend(i, n, mode):
    """Row index i folded into 0..n-1: 'mirror' reflects about the end
    samples (d c b | a b c d | c b a), 'reflect' about the edges
    (d c b a | a b c d | d c b a)."""
    if mode == 0:
        if n == 1:
            return 0
        period = 2 * n - 2
        i = i % period
        return period - i if i >= n else i
    period = 2 * n
    i = i % period
    return period - 1 - i if i >= n else i


@nb.njit(cache=True, nogil=True)
def _column_pass(x, k, mode, out):  # pragma: no cover - compiled
    h, w = x.shape
    r = k.shape[0] // 2
    centre = k[r]
    for i in range(h):
        o = out[i]
        src = x[i]
        for j in range(w):
            o[j] = src[j] * centre
        for t in range(r, 0, -1):
            a = x[_extend(i - t, h, mode)]
            b = x[_extend(i + t, h, mode)]
            kt = k[r - t]
            for j in range(w):
                o[j] += (a[j] + b[j]) * kt


@nb.njit(cache=True, nogil=True)
def _row_pass(x, k, mode, out):  # pragma: no cover - compiled
    h, w = x.shape
    r = k.shape[0] // 2
    centre = k[r]
    buf = np.empty(w + 2 * r, dtype=x.dtype)  # one row, extended by r at each end
    for i in range(h):
        src = x[i]
        for j in range(w):
            buf[r + j] = src[j]
        for j in range(r):
            buf[j] = src[_extend(j - r, w, mode)]
            buf[r + w + j] = src[_extend(w + j, w, mode)]
        o = out[i]
        mid = buf[r:r + w]
        for j in range(w):
            o[j] = mid[j] * centre
        for t in range(r, 0, -1):
            kt = k[r - t]
            a = buf[r - t:r - t + w]  # slices, not offset indices: the loop then vectorises
            b = buf[r + t:r + t + w]
            for j in range(w):
                o[j] += (a[j] + b[j]) * kt


def _correlate(kernel, name: str, x, k, out, mode: str) -> np.ndarray:
    """Check the arguments (one error naming ``name``) and run the compiled pass ``kernel``."""
    x = np.asarray(x)
    if x.dtype != np.float32:
        x = np.asarray(x, dtype=np.float64)
    k = np.ascontiguousarray(k, dtype=x.dtype)
    if x.ndim != 2 or k.ndim != 1 or k.size % 2 == 0 or not np.array_equal(k, k[::-1]):
        raise ValueError(f"{name} needs a 2-D image and a symmetric 1-D kernel of odd length, "
                         f"got {x.shape} and {k.shape}")
    if mode not in _MODES:
        raise ValueError(f"{name}: mode must be 'mirror' or 'reflect', got {mode!r}")
    if out is None:
        out = np.empty(x.shape, dtype=x.dtype)
    elif np.shares_memory(out, x):
        raise ValueError(f"{name}: out must not share memory with the input")
    if x.size:
        kernel(x, k, _MODES[mode], out)
    return out


def correlate_along_rows(x: np.ndarray, k: np.ndarray, out: np.ndarray | None = None, *,
                         mode: str = "mirror") -> np.ndarray:
    """``ndimage.correlate1d(x, k, axis=1, mode=mode, output=out)`` for a
    2-D float64 ``x`` (a float32 ``x`` is filtered and returned in float32)
    and a symmetric 1-D kernel ``k`` of odd length (origin 0), ``mode``
    'mirror' or 'reflect'.  ``out`` (optional) must not
    share memory with ``x``."""
    return _correlate(_row_pass, "correlate_along_rows", x, k, out, mode)


def correlate_columns(x: np.ndarray, k: np.ndarray, out: np.ndarray | None = None, *,
                      mode: str = "mirror") -> np.ndarray:
    """``ndimage.correlate1d(x, k, axis=0, ...)``, otherwise as
    :func:`correlate_along_rows`."""
    return _correlate(_column_pass, "correlate_columns", x, k, out, mode)
