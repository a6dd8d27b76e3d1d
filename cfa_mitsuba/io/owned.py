"""Files the project wrote into a folder, so a rebuild deletes only those.

A report rebuild must drop figures of CFAs no longer in the results, but a
results folder is the user's: it may hold their own PNGs, or be a folder
that was never a report's (a study once named ``../../x`` wrote into one).
So each build records the names it wrote in a manifest
(:data:`MANIFEST`) beside them, and the next build deletes a file only when
that manifest lists it and it is not written again.  A file the project did
not record is never deleted.
"""

from __future__ import annotations

__all__ = ["MANIFEST", "prune_written", "record_written"]

import json
from pathlib import Path

from .atomic import atomic_output

#: The manifest's file name (hidden, one per folder).
MANIFEST = ".cfa-mitsuba-written.json"


def _recorded(folder: Path) -> set[str]:
    from .guard import read_json

    if not (folder / MANIFEST).exists():
        return set()
    try:  # the bounded reader: a FIFO or a nested bomb in its place is no manifest
        names = read_json(folder / MANIFEST, "manifest")
    except (OSError, ValueError):  # CfaMitsubaError is a ValueError
        return set()
    if not isinstance(names, list):
        return set()
    # plain names only: a manifest can never point outside its folder
    return {n for n in names if isinstance(n, str) and n and Path(n).name == n and n not in (".", "..", MANIFEST)}


def prune_written(folder, keep) -> list[Path]:
    """Delete the files of ``folder`` that an earlier build recorded writing
    and that are not in ``keep`` (names); returns what was deleted."""
    folder = Path(folder)
    gone = []
    for name in sorted(_recorded(folder) - set(keep)):
        p = folder / name
        if p.is_file() or p.is_symlink():
            p.unlink()
            gone.append(p)
    return gone


def record_written(folder, names) -> Path:
    """Record ``names`` as the files the project wrote into ``folder``."""
    path = Path(folder) / MANIFEST
    with atomic_output(path) as tmp:
        tmp.write_text(json.dumps(sorted(set(names))))
    return path
