"""A one-entry memo of an image made from a mosaic, for the steps that two
demosaicing methods share.

A study demosaics each capture by several methods in a row: 'bilinear',
'laplacian', 'adaptive-laplacian', 'pocs' (the paper's four).  POCS starts
from the other channels' bilinear estimates and from the edge-directed
reference of 'adaptive-laplacian', which were just made from the same
mosaic.  A :class:`LastImage` keeps the last one it made, with a copy of the
mosaic it came from; a call with an equal key and a mosaic equal value for
value gets it back instead of computing it again (the same bits: the same
function of the same numbers).

One entry per memo and process: the memory is one mosaic and one result,
and nothing is kept where the two together pass :data:`MAX_BYTES` (a
full-size sensor's mosaic is computed afresh rather than held twice).  The
entry is replaced whole, so threads sharing it see either the old or the new
one, never a mixture.
"""

from __future__ import annotations

__all__ = ["LastImage", "clear_all"]

import weakref
from typing import Callable

import numpy as np

#: the most a memo keeps (mosaic and result together, bytes): 64 MB, a
#: 4-channel image of about 1.7 Mpx (the paper's 0.46 Mpx images take 18 MB),
#: so the two memos add at most 128 MB to a worker
MAX_BYTES = 64 * 2**20

#: every memo made, so that a benchmark can time a method on its own (:func:`clear_all`)
_ALL: "weakref.WeakSet[LastImage]" = weakref.WeakSet()


def clear_all() -> None:
    """Empty every :class:`LastImage`: the next call of each method computes
    everything itself (benchmarks/bench_demosaic.py times each method this
    way; repeated calls on one mosaic would otherwise time a copy)."""
    for memo in list(_ALL):
        memo.clear()


class LastImage:
    """The last image a function made, with the mosaic and key it came from."""

    def __init__(self) -> None:
        self._entry: tuple | None = None
        _ALL.add(self)

    def get(self, key, raw: np.ndarray, make: Callable[[], np.ndarray]) -> np.ndarray:
        """``make()``, or the kept result when ``key`` equals the last call's
        and ``raw`` equals its mosaic (shape, dtype and every value; NaN
        never equals, so it recomputes).  ``make`` returns a new array, which
        is kept as it is (no copy) and made read-only: copy it before
        changing it (one too big to keep, over :data:`MAX_BYTES`, is returned
        writeable and not kept)."""
        entry = self._entry
        if (entry is not None and entry[0] == key and entry[1].shape == raw.shape and entry[1].dtype == raw.dtype
                and np.array_equal(entry[1], raw)):
            return entry[2]
        self._entry = None  # a failing make() leaves nothing stale behind
        result = np.asarray(make())
        if raw.nbytes + result.nbytes > MAX_BYTES:  # too big to hold twice: not kept
            return result
        if np.may_share_memory(result, raw):  # kept as made, unless it is (part of) the caller's mosaic
            result = result.copy()
        result.flags.writeable = False
        kept = np.array(raw, copy=True)
        kept.flags.writeable = False
        self._entry = (key, kept, result)
        return result

    def clear(self) -> None:
        self._entry = None
