"""The end of one POCS projection round for one channel in one compiled
pass (Numba): the detail projection's sum, the observation projection and
the squared change, where numpy made five whole-image passes (add, the
strided copy of each observed phase, subtract, square, mean).

Written by hand for speed only.  The channel's new values are the same
IEEE operations as before (reference + detail, or the mosaic where the
channel is observed), so the demosaic's output is bit for bit the same
(tests/test_pocs_kernel.py); only the sum of squared changes, which decides when
to stop, is added in another order (a difference of about 1e-16 relative).
"""

from __future__ import annotations

import numba as nb
import numpy as np


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
    observed = np.asarray(observed, dtype=np.bool_)
    reps = -(-x.shape[1] // observed.shape[1])
    return float(_project(x, ref, detail, raw, np.ascontiguousarray(np.tile(observed, (1, reps))[:, :x.shape[1]])))
