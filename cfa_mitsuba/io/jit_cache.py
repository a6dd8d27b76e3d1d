"""Numba's cache of compiled kernels is a write like any other.

The project's loops are compiled by numba with ``cache=True``: the first
call compiles them and writes the machine code beside the module
(``__pycache__/*.nbi``, ``*.nbc``), later processes load it.  Numba lets
an error of that write end the call (on Linux it passes every ``OSError``
on; ``numba.core.caching.Cache._guard_against_spurious_io_errors`` only
forgives EACCES on Windows), so on a full disk, under a file-size limit
(``ulimit -f``) or on a read-only installation a capture ended in
"File too large" from a file the user never named.  The cache only saves
compile time: a kernel whose cache cannot be written runs uncompiled-from-
cache, compiled in this process, and nothing half written is left (numba
writes through a temporary file it removes on error).
"""

from __future__ import annotations

__all__ = ["tolerate_cache_write_errors"]


def tolerate_cache_write_errors() -> None:
    """Make numba's cache writes that fail with an ``OSError`` skip the
    cache instead of ending the call (idempotent; call before the first
    compile, in each module with ``cache=True`` kernels)."""
    from numba.core import caching

    if getattr(caching.FunctionCache, "_cfa_mitsuba_tolerant", False):
        return
    save = caching.FunctionCache.save_overload

    def save_overload(self, sig, data):
        try:
            save(self, sig, data)
        except OSError:  # a full disk, the file-size limit, a read-only install: run without the cache
            pass

    caching.FunctionCache.save_overload = save_overload
    caching.FunctionCache._cfa_mitsuba_tolerant = True
