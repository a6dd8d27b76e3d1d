"""The last steps of one channel of :func:`~cfa_mitsuba.isp.laplacian.colour_differences`
in one compiled pass (Numba): ``g`` times the reference added back at the
channel's gaps and the mosaic's own samples at its sites, where numpy made
one strided read-modify-write per gap phase and one strided copy per site
phase of the (H, W, C) image (up to 16 phases on the Kodak-style tiles, the
larger part of the function's own 8 ms on the puppy's size; here 0.5 ms a
channel, the sites a row mask, both values made and one kept).

Written by hand for speed only.  Each value is the same IEEE operation as
numpy's: ``g`` is rounded to the image's precision first, as numpy rounds
a Python number for a float32 array, then ``plane + g * ref`` in that
precision (no fused multiply-add: Numba does not contract without
fastmath), and a site takes the mosaic's sample as it is
(tests/test_fast_paths.py compares the Laplacian methods with the numpy
steps for every CFA and precision).
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ..io.jit_cache import tolerate_cache_write_errors

tolerate_cache_write_errors()  # the kernel cache is a write that may fail (a full disk): io/jit_cache.py


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _gaps_and_sites(out, c, refimg, raw, sites, g):  # pragma: no cover - compiled
    h, w = raw.shape
    th = sites.shape[0]
    for r in range(h):
        site, ref_row, raw_row, out_row = sites[r % th], refimg[r], raw[r], out[r]
        for col in range(w):  # both made, one kept: no branch in the loop
            gap = out_row[col, c] + g * ref_row[col]
            out_row[col, c] = raw_row[col] if site[col] else gap


def gaps_and_sites(out: np.ndarray, c: int, refimg: np.ndarray, raw: np.ndarray, index: np.ndarray, g: float) -> bool:
    """In place on channel ``c`` of ``out`` (H, W, C): ``+= g * refimg`` at
    the gaps, ``= raw`` at the sites (``index`` the tile's channels); False
    (nothing done) unless the four arrays share one float type and ``out``
    is C-contiguous: the caller does it with numpy then."""
    dtype = out.dtype
    if (dtype not in (np.float32, np.float64) or refimg.dtype != dtype or raw.dtype != dtype
            or not out.flags.c_contiguous or out.ndim != 3):
        return False
    from .mosaic import tile_across

    sites = tile_across(np.asarray(index) == c, raw.shape[1])
    _gaps_and_sites(out, int(c), np.ascontiguousarray(refimg), np.ascontiguousarray(raw), sites, dtype.type(g))
    return True
