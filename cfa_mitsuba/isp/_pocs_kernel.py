"""The end of one POCS projection round for one channel in one compiled
pass (Numba): the detail projection's sum, the observation projection and
the squared change, where numpy made five whole-image passes (add, the
strided copy of each observed phase, subtract, square, mean).

Written by hand for speed only.  The channel's new values are the same
IEEE operations as before (reference + detail, or the mosaic where the
channel is observed), so the demosaic's output is bit for bit the same
(tests/isp/test_pocs.py); only the sum of squared changes, which decides when
to stop, is added in another order (a difference of about 1e-16 relative).

:func:`lowpass_project` does a whole round for a detail threshold of 0 row
by row: the low-pass of the channel's difference from the reference (the
sums of :mod:`.column_filter`'s two passes) and the projection, without
writing the low-passed image out (4-8 % of a POCS demosaic on the puppy's
size; tests/isp/test_pocs.py checks the same channel), and without the
difference image it filters: its rows are made in a ring of rows as the
pass needs them (1.30 -> 1.18 ms a round on the puppy's size).  Its sum of
squared changes is each row's sum in eight interleaved partial sums, then
the rows' sums in order (1.15 -> 0.93 ms a round): it differs from the
running sum by rounding (about 1e-13 relative on the puppy's size), so a
stop could differ only where the change came within that of the
tolerance; the paper study's values are all the same (docs/study.md).
"""

from __future__ import annotations

import numba as nb
import numpy as np

from .column_filter import _extend
from .mosaic import tile_across
from ..io.jit_cache import tolerate_cache_write_errors

tolerate_cache_write_errors()  # the kernel cache is a write that may fail (a full disk): io/jit_cache.py


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _project(x, ref, detail, raw, observed):  # pragma: no cover - compiled
    th = observed.shape[0]  # observed: the tile mask repeated across the width, (th, W)
    total = 0.0
    for r in range(x.shape[0]):
        seen = observed[r % th]
        for c in range(x.shape[1]):
            if seen[c]:
                v = raw[r, c]
            else:
                v = ref[r, c] + detail[r, c]
            step = v - x[r, c]
            total += step * step
            x[r, c] = v
    return total


def project(x: np.ndarray, ref: np.ndarray, detail: np.ndarray, raw: np.ndarray, observed: np.ndarray) -> float:
    """Replace the channel ``x`` (H, W, changed in place) by ``ref +
    detail``, except where the tile mask ``observed`` (th, tw bool) says the
    channel is sampled, where it takes ``raw``; returns the sum of the
    squared changes."""
    return float(_project(x, ref, detail, raw, tile_across(np.asarray(observed, dtype=np.bool_), x.shape[1])))


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _difference_row(x, ref, j, out):  # pragma: no cover - compiled
    xj, rj = x[j], ref[j]
    for c in range(out.shape[0]):
        out[c] = xj[c] - rj[c]


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _lowpass_project(x, ref, raw, observed, k, ring, colbuf, rowbuf, squares):  # pragma: no cover - compiled
    h, w = x.shape
    r = k.shape[0] // 2
    m = ring.shape[0]  # 2 r + 1 rows of d = x - ref: row j in slot j % m
    centre = k[r]
    th = observed.shape[0]
    total = 0.0
    # Row i's column pass reads d's rows i - r .. i + r (their mirror images at the ends are rows in
    # that range too), so row j of d is made before x's row j changes (rows 0..r first, row i + r
    # just before row i's pass) and its slot is taken again only by row j + m, after row j + r.
    for j in range(min(r, h - 1) + 1):
        _difference_row(x, ref, j, ring[j % m])
    for i in range(h):
        if 0 < i and i + r < h:
            _difference_row(x, ref, i + r, ring[(i + r) % m])
        # the column pass at row i (column_filter._column_pass's sums), into colbuf's middle
        src = ring[i % m]
        for j in range(w):
            colbuf[r + j] = src[j] * centre
        for t in range(r, 0, -1):
            a = ring[_extend(i - t, h, 0) % m]
            b = ring[_extend(i + t, h, 0) % m]
            kt = k[r - t]
            for j in range(w):
                colbuf[r + j] += (a[j] + b[j]) * kt
        for j in range(r):  # the row's mirror extension (column_filter._row_pass's)
            colbuf[j] = colbuf[r + _extend(j - r, w, 0)]
            colbuf[r + w + j] = colbuf[r + _extend(w + j, w, 0)]
        mid = colbuf[r:r + w]
        for j in range(w):
            rowbuf[j] = mid[j] * centre
        for t in range(r, 0, -1):
            kt = k[r - t]
            a = colbuf[r - t:r - t + w]
            b = colbuf[r + t:r + t + w]
            for j in range(w):
                rowbuf[j] += (a[j] + b[j]) * kt
        seen = observed[i % th]  # then the projection of row i (_project's)
        xr, refr, rawr = x[i], ref[i], raw[i]
        for j in range(w):
            v = rawr[j] if seen[j] else refr[j] + rowbuf[j]
            step = v - xr[j]
            squares[j] = step * step
            xr[j] = v
        total += _sum8(squares)
    return total


@nb.njit(inline="always")
def _sum8(a):
    """The sum of ``a`` in eight interleaved partial sums (they vectorise;
    one running sum is a chain of dependent additions, a third of the
    round's time on the puppy's size)."""
    s0 = s1 = s2 = s3 = s4 = s5 = s6 = s7 = 0.0
    n = a.shape[0]
    j = 0
    while j + 8 <= n:
        s0 += a[j]
        s1 += a[j + 1]
        s2 += a[j + 2]
        s3 += a[j + 3]
        s4 += a[j + 4]
        s5 += a[j + 5]
        s6 += a[j + 6]
        s7 += a[j + 7]
        j += 8
    while j < n:
        s0 += a[j]
        j += 1
    return ((s0 + s1) + (s2 + s3)) + ((s4 + s5) + (s6 + s7))


def lowpass_project(x: np.ndarray, ref: np.ndarray, raw: np.ndarray, observed: np.ndarray, k: np.ndarray) -> float:
    """One channel's whole projection round for a detail threshold of 0, in
    one pass over the rows: the low-pass ``P(d)`` of ``d = x - ref`` (the
    symmetric kernel ``k`` down the columns, then along the rows, both with
    'mirror' extension: ``correlate_columns`` then ``correlate_along_rows``,
    the same sums) and :func:`project` of ``ref + P(d)``, without writing
    ``d`` or ``P(d)`` out (``d``'s rows live in a ring of 2 r + 1 rows,
    made in ``raw``'s precision as numpy's subtraction into such an array
    made them).  ``x`` is changed in place; returns the sum of the squared
    changes."""
    r = k.shape[0] // 2
    dtype = raw.dtype
    ring = np.empty((2 * r + 1, x.shape[1]), dtype=dtype)
    colbuf = np.empty(x.shape[1] + 2 * r, dtype=dtype)
    rowbuf = np.empty(x.shape[1], dtype=dtype)
    squares = np.empty(x.shape[1], dtype=np.float64)
    return float(_lowpass_project(x, ref, raw, tile_across(np.asarray(observed, dtype=np.bool_), x.shape[1]),
                                  np.ascontiguousarray(k, dtype=dtype), ring, colbuf, rowbuf, squares))
