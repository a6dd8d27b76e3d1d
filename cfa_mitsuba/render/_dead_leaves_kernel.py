"""The dead-leaves chart's compiled disc painter (numba), in a module of its
own so that importing the render package does not import numba: only
drawing a chart does (:func:`.dead_leaves.disc_labels`)."""

from __future__ import annotations

__all__ = ["paint_discs"]

import math

import numba as nb

from ..io.jit_cache import tolerate_cache_write_errors

tolerate_cache_write_errors()  # the kernel cache is a write that may fail (a full disk): io/jit_cache.py


@nb.njit(cache=True)
def paint_discs(labels, cx, cy, r, colour, cell, start_uncovered):  # pragma: no cover - compiled
    """Paint discs front to back on the cell grid ``labels`` (-1: bare):
    each takes the bare cells whose centres it covers.  Returns (the bare
    cells left, the discs used)."""
    n_y, n_x = labels.shape
    bare = start_uncovered
    for d in range(cx.size):
        if bare == 0:
            return bare, d
        x_lo = max(int(math.floor((cx[d] - r[d]) / cell)), 0)
        x_hi = min(int(math.ceil((cx[d] + r[d]) / cell)), n_x)
        y_lo = max(int(math.floor((cy[d] - r[d]) / cell)), 0)
        y_hi = min(int(math.ceil((cy[d] + r[d]) / cell)), n_y)
        r2 = r[d] * r[d]
        for i in range(y_lo, y_hi):
            dy = (i + 0.5) * cell - cy[d]
            for j in range(x_lo, x_hi):
                if labels[i, j] < 0:
                    dx = (j + 0.5) * cell - cx[d]
                    if dx * dx + dy * dy <= r2:
                        labels[i, j] = colour[d]
                        bare -= 1
    return bare, cx.size
