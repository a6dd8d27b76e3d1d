"""Errors that reach the user.

Every problem a user can cause (a bad argument, a file that cannot be read or
written, a scene Mitsuba cannot render correctly, an impossible config) is
raised as :class:`CfaMitsubaError` with a one-line message that names the
problem.  The command line prints that line and exits with status 2; Python
callers can catch it (it is a :class:`ValueError`).  Anything else that
escapes is a bug and keeps its traceback.
"""

from __future__ import annotations

__all__ = ["CfaMitsubaError", "require", "require_finite"]

import numpy as np


class CfaMitsubaError(ValueError):
    """A user-facing error: bad input, with a one-line message naming it."""


def require(condition: bool, message: str) -> None:
    """Raise :class:`CfaMitsubaError` with ``message`` unless ``condition``."""
    if not condition:
        raise CfaMitsubaError(message)


def require_finite(array, what: str) -> np.ndarray:
    """Return ``array`` as a float64 array, refusing NaN or infinite values.

    ``what`` names the array in the error, e.g. ``"reference image"``.
    """
    arr = np.asarray(array, dtype=np.float64)
    if not np.all(np.isfinite(arr)):
        bad = int(np.size(arr) - np.count_nonzero(np.isfinite(arr)))
        raise CfaMitsubaError(f"{what} contains {bad} NaN or infinite value(s)")
    return arr
