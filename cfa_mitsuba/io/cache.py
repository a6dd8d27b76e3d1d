"""The render cache: spectral EXRs keyed by a hash of what determines them.

Lives outside any output directory (``~/.cache/cfa-mitsuba``, or
``$CFA_MITSUBA_CACHE``) so that separate studies share renders (DESIGN.md).
Entries are written atomically (temporary file + rename), so a reader never
sees half a file and an interrupted render leaves nothing a later run would
trust.  While one process renders a key it holds an exclusive ``fcntl`` lock
on that key, so concurrent processes (Dask workers, parallel CLI calls) wait
for it and then reuse its file instead of rendering the same thing twice.

Every entry carries the SHA-256 of its bytes in a file beside it
(``<key>.sha256``, written before the entry itself, so a reader that sees
the entry sees its checksum), verified on every reuse: an entry changed
after it was written (a flipped bit, an edited header, a truncated copy)
is not trusted but rendered again, with one notice line on stderr.  An
entry without a checksum (written by an older version) is rendered again
the same way.
"""

from __future__ import annotations

__all__ = ["CACHE_ENV", "default_cache_dir", "hash_key", "file_digest", "RenderCache"]

import contextlib
import fcntl
import hashlib
import json
import os
import sys
from pathlib import Path
from typing import Callable

from ..errors import CfaMitsubaError
from ..values import SpectralImage
from .sidecar import json_default

#: Environment variable overriding the cache location.
CACHE_ENV = "CFA_MITSUBA_CACHE"


def default_cache_dir() -> Path:
    """``$CFA_MITSUBA_CACHE`` if set, else ``~/.cache/cfa-mitsuba``."""
    env = os.environ.get(CACHE_ENV, "").strip()
    return Path(env).expanduser() if env else Path.home() / ".cache" / "cfa-mitsuba"


def hash_key(fields: dict) -> str:
    """SHA-256 (hex, 32 characters) of ``fields`` as canonical JSON (sorted
    keys, no whitespace), so equal settings give equal keys on any machine."""
    text = json.dumps(fields, sort_keys=True, separators=(",", ":"), default=json_default)
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def file_digest(path) -> str:
    """SHA-256 (hex) of a regular file's bytes (io/guard.py: a FIFO or
    device refused, never read)."""
    from .guard import open_regular

    h = hashlib.sha256()
    with open_regular(path, "render cache entry") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _present(path: Path, what: str, fd: int | None = None) -> bool:
    """Whether ``path`` (or the open descriptor ``fd``) is there: False when
    absent (a dangling link too), True for a regular file, else one line
    naming the real path, what is there and what to do."""
    import stat

    from .guard import _kind

    try:
        st = os.fstat(fd) if fd is not None else os.stat(path)
    except FileNotFoundError:
        return False
    except OSError as exc:
        raise CfaMitsubaError(f"cannot read {what} {str(path)!r}: {exc.strerror}") from None
    if not stat.S_ISREG(st.st_mode):
        raise CfaMitsubaError(f"{what} {str(path)!r} is {_kind(st.st_mode)}, not a regular file: remove it "
                              "(the cache makes it again)")
    return True


class RenderCache:
    """A directory of cached spectral renders.

    ``root`` defaults to :func:`default_cache_dir`.  Entries are
    ``root/renders/<key[:2]>/<key>.exr`` (our spectral EXR, metadata in its
    header) with its checksum ``<key>.sha256`` beside it; locks are
    ``root/locks/<key>.lock``.
    """

    def __init__(self, root=None):
        self.root = Path(root) if root is not None else default_cache_dir()
        self._noticed: set[tuple[str, str]] = set()  # (entry, why) already said once

    def path(self, key: str) -> Path:
        return self.root / "renders" / key[:2] / f"{key}.exr"

    def checksum_path(self, key: str) -> Path:
        return self.path(key).with_suffix(".sha256")

    def _verified(self, key: str) -> bool:
        """Whether the entry's bytes still have the checksum recorded when
        it was written (a notice line when not).  A checksum that is not a
        regular file (a FIFO would block the read, /dev/zero never end, a
        folder cannot be replaced) is refused in one line naming it."""
        from .guard import read_text

        p = self.path(key)
        recorded = None
        if _present(self.checksum_path(key), "render cache checksum"):
            try:  # the one bounded reader: a 64-character hex line, nothing more is trusted
                recorded = read_text(self.checksum_path(key), "render cache checksum", limit=1024).strip()
            except CfaMitsubaError:  # too long or not text: a damaged checksum, rendered again
                recorded = None
        if recorded is None:
            why = "has no checksum (written by an older version, or interrupted)"
        else:
            try:
                actual = file_digest(p)
            except OSError as exc:
                actual, why = None, f"cannot be read ({exc.strerror})"
            if actual == recorded:
                return True
            if actual is not None:
                why = "does not match the checksum recorded when it was written (changed since)"
        if (str(p), why) not in self._noticed:  # get_or_create looks twice (before and under the lock)
            self._noticed.add((str(p), why))
            sys.stderr.write(f"cfa-mitsuba: cache entry {p} {why}: rendering it again\n")
        return False

    def _ensure(self, directory: Path) -> Path:
        try:
            directory.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise CfaMitsubaError(
                f"cannot create the render cache {str(directory)!r}: {exc.strerror} "
                f"(set {CACHE_ENV} to a writable directory, or render with --no-cache)"
            ) from None
        if not os.access(directory, os.W_OK | os.X_OK):
            raise CfaMitsubaError(
                f"the render cache {str(directory)!r} is not writable "
                f"(set {CACHE_ENV} to a writable directory, or render with --no-cache)"
            )
        return directory

    def load(self, key: str) -> SpectralImage | None:
        """The cached image for ``key``, or None if absent.  An unreadable
        entry, or one whose bytes fail their checksum, counts as absent (it
        will be rendered again and replaced)."""
        from .exr import read_spectral_exr

        p = self.path(key)
        if not _present(p, "render cache entry") or not self._verified(key):
            return None
        try:
            return read_spectral_exr(p)
        except CfaMitsubaError as exc:
            sys.stderr.write(f"cfa-mitsuba: ignoring unreadable cache entry {p}: {exc}\n")
            return None

    def store(self, key: str, image: SpectralImage) -> Path:
        """Write the entry and its checksum: the EXR to a temporary name,
        its checksum (atomically), then the EXR renamed into place."""
        from .atomic import atomic_output
        from .exr import write_spectral_exr

        p = self.path(key)
        self._ensure(p.parent)
        with atomic_output(p) as tmp_exr:
            write_spectral_exr(tmp_exr, image, preview=False)
            with atomic_output(self.checksum_path(key)) as tmp_sum:
                tmp_sum.write_text(file_digest(tmp_exr) + "\n", encoding="ascii")
        return p

    @contextlib.contextmanager
    def lock(self, key: str):
        """Hold an exclusive lock on ``key`` (blocks while another process
        holds it).  The lock file is opened without blocking and must be a
        regular file: a folder or FIFO in its place is refused in one line
        naming it."""
        path = self._ensure(self.root / "locks") / f"{key}.lock"
        _present(path, "render cache lock")  # a folder, FIFO or device: one line naming it
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NONBLOCK | os.O_CLOEXEC, 0o666)
        except OSError as exc:
            raise CfaMitsubaError(f"cannot open the render cache lock {str(path)!r}: {exc.strerror}") from None
        try:
            _present(path, "render cache lock", fd)  # swapped for something else since the check
            fcntl.flock(fd, fcntl.LOCK_EX)
            try:
                yield
            finally:
                fcntl.flock(fd, fcntl.LOCK_UN)
        finally:
            os.close(fd)

    def get_or_create(self, key: str, make: Callable[[], SpectralImage]) -> tuple[SpectralImage, bool]:
        """Return ``(image, reused)``: the cached image for ``key``, or
        ``make()``'s result after storing it.  Concurrent callers with the
        same key render it once; the others wait and reuse the file."""
        hit = self.load(key)
        if hit is not None:
            return hit, True
        with self.lock(key):
            hit = self.load(key)  # another process may have finished meanwhile
            if hit is not None:
                return hit, True
            image = make()
            self.store(key, image)
            return image, False
