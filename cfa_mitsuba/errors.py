"""Errors that reach the user.

Every problem a user can cause (a bad argument, a file that cannot be read or
written, a scene Mitsuba cannot render correctly, an impossible config) is
raised as :class:`CfaMitsubaError` with a one-line message that names the
problem.  The command line prints that line and exits with status 2; Python
callers can catch it (it is a :class:`ValueError`).  Anything else that
escapes is a bug and keeps its traceback.
"""

from __future__ import annotations

__all__ = ["CfaMitsubaError", "require", "require_finite", "one_line"]

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


def one_line(exc, limit: int | None = None) -> str:
    """An exception's (or any object's) message as one line: every run of
    whitespace, newlines included, becomes one space; cut to ``limit``
    characters when given; an exception with no message gives its type's
    name, so a one-line error never ends in an empty reason.

    >>> one_line(OSError("cannot read\\n  the file"))
    'cannot read the file'
    >>> one_line(KeyError())
    'KeyError'
    """
    text = " ".join(str(exc).split())
    if limit is not None:
        text = text[:limit]
    return text or (type(exc).__name__ if isinstance(exc, BaseException) else "")
