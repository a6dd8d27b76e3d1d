"""The render cache: spectral EXRs keyed by a hash of what determines them.

Lives outside any output directory (``~/.cache/cfa-mitsuba``, or
``$CFA_MITSUBA_CACHE``) so that separate studies share renders (DESIGN.md).
Entries are written atomically (temporary file + rename), so a reader never
sees half a file and an interrupted render leaves nothing a later run would
trust.  While one process renders a key it holds an exclusive ``fcntl`` lock
on that key, so concurrent processes (Dask workers, parallel CLI calls) wait
for it and then reuse its file instead of rendering the same thing twice.
"""

from __future__ import annotations

__all__ = ["CACHE_ENV", "default_cache_dir", "hash_key", "RenderCache"]

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


class RenderCache:
    """A directory of cached spectral renders.

    ``root`` defaults to :func:`default_cache_dir`.  Entries are
    ``root/renders/<key[:2]>/<key>.exr`` (our spectral EXR, metadata in its
    header); locks are ``root/locks/<key>.lock``.
    """

    def __init__(self, root=None):
        self.root = Path(root) if root is not None else default_cache_dir()

    def path(self, key: str) -> Path:
        return self.root / "renders" / key[:2] / f"{key}.exr"

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
        entry counts as absent (it will be rendered again and replaced)."""
        from .exr import read_spectral_exr

        p = self.path(key)
        if not p.is_file():
            return None
        try:
            return read_spectral_exr(p)
        except CfaMitsubaError as exc:
            sys.stderr.write(f"cfa-mitsuba: ignoring unreadable cache entry {p}: {exc}\n")
            return None

    def store(self, key: str, image: SpectralImage) -> Path:
        from .exr import write_spectral_exr

        p = self.path(key)
        self._ensure(p.parent)
        return write_spectral_exr(p, image, preview=False)

    @contextlib.contextmanager
    def lock(self, key: str):
        """Hold an exclusive lock on ``key`` (blocks while another process
        holds it)."""
        d = self._ensure(self.root / "locks")
        with open(d / f"{key}.lock", "a+") as fh:
            fcntl.flock(fh.fileno(), fcntl.LOCK_EX)
            try:
                yield
            finally:
                fcntl.flock(fh.fileno(), fcntl.LOCK_UN)

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
