"""Atomic file output: write to a temporary file beside the target, then
rename, so that an interrupted or failed write never leaves a file a later
run would trust (DESIGN.md, scale-out decision)."""

from __future__ import annotations

__all__ = ["atomic_output", "check_writable_dir", "WriteError", "write_error"]

import contextlib
import errno
import os
import tempfile
from pathlib import Path

from ..errors import CfaMitsubaError

# The process's umask, read once at import (reading it means setting it, so
# not on every write, where another thread could be creating a file).
_UMASK = os.umask(0o022)
os.umask(_UMASK)


def check_writable_dir(directory, *, create: bool = True) -> Path:
    """Return ``directory`` as a Path, creating it if asked; refuse it with a
    one-line error if it is a file or cannot be written."""
    d = Path(directory)
    if d.exists() and not d.is_dir():
        raise CfaMitsubaError(f"output directory {str(d)!r} is a file")
    if not d.exists():
        if not create:
            raise CfaMitsubaError(f"output directory {str(d)!r} does not exist")
        try:
            d.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise CfaMitsubaError(f"cannot create output directory {str(d)!r}: {exc.strerror}") from None
    if not os.access(d, os.W_OK | os.X_OK):
        raise CfaMitsubaError(f"output directory {str(d)!r} is not writable")
    return d


class WriteError(CfaMitsubaError, OSError):
    """A file could not be written: ``path`` (the file the user or the
    project named, never a temporary ``.part``) and ``cause`` (why: "No
    space left on device", "it is a directory").  A user's error (one line,
    exit 2) and still an :class:`OSError` for callers that catch those."""

    def __init__(self, path, cause: str):
        self.path, self.cause = Path(path), cause
        super().__init__(f"cannot write {str(path)!r}: {cause}")


#: What the system's word for a write failure leaves unsaid (errno -> hint).
_HINTS = {errno.EFBIG: " (the file-size limit, ulimit -f, or the file system's largest file)",
          errno.ENOSPC: " (the disk is full)", errno.EDQUOT: " (the disk quota is used up)"}


def write_error(target, exc: BaseException) -> WriteError:
    """The :class:`WriteError` of ``exc`` (an OSError, or a writer library's
    error carrying one) raised while writing ``target``."""
    if isinstance(exc, IsADirectoryError) or (isinstance(exc, OSError) and Path(target).is_dir()):
        return WriteError(target, "it is a directory; remove it or write elsewhere")
    if isinstance(exc, OSError):
        return WriteError(target, f"{exc.strerror or exc}{_HINTS.get(exc.errno, '')}")
    # a C++ writer's message (OpenEXR: 'Failed to write pixel data to image file "X". File too large.'):
    # its last sentence is the system's word for the cause
    from .guard import _text

    text = _text(exc)
    cause = text.rsplit('". ', 1)[-1].rstrip(".") if '". ' in text else text[:200]
    hint = next((h for code, h in _HINTS.items() if cause == os.strerror(code)), "")
    return WriteError(target, cause + hint)


@contextlib.contextmanager
def atomic_output(path, *, suffix: str | None = None):
    """Context manager yielding a temporary path in the target's directory.

    Write the file there; on normal exit it is renamed onto ``path`` (atomic
    on POSIX within one filesystem), on any exception it is removed and the
    target is left untouched.  ``suffix`` (default: the target's) keeps
    writers that look at the extension happy.  A write that fails (a full
    disk, the file-size limit, a folder where the file should go) is one
    :class:`WriteError` naming ``path``, never the temporary file.
    """
    target = Path(path)
    check_writable_dir(target.parent if str(target.parent) else ".", create=True)
    fd, tmp = tempfile.mkstemp(
        prefix=f".{target.name}.", suffix=(suffix if suffix is not None else target.suffix) + ".part",
        dir=target.parent if str(target.parent) else ".",
    )
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        # mkstemp creates the file 0600; give it the permissions an ordinary
        # open() would (0666 less the umask), so others (e.g. Dask workers
        # sharing a render cache) can read it.
        os.chmod(tmp_path, 0o666 & ~_UMASK)
        os.replace(tmp_path, target)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            tmp_path.unlink()
        if isinstance(exc, WriteError) and exc.path == tmp_path:  # a nested writer's: name our target
            raise WriteError(target, exc.cause) from None
        if isinstance(exc, OSError):
            raise write_error(target, exc) from None
        raise
