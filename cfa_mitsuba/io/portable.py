"""Paths as a result records them: relative to the folder the result is
written to, so a committed result does not carry the layout of the machine
that made it (``/tmp/d-dyes/cfas/...``) and a moved results folder stays
consistent.

A path under the output folder becomes ``cfas/x.toml``; one elsewhere
becomes the relative route to it (``../../configs/paper.toml``), which
``Path(out_dir) / recorded`` resolves on the machine that wrote it.  A
command line keeps its words and has every absolute path among them made
relative the same way.  Hand-written: ``os.path.relpath`` does the work,
this only says where it applies.
"""

from __future__ import annotations

__all__ = ["relative_path", "relative_command", "ABSOLUTE_PATH"]

import os
import re
import shlex
from pathlib import Path

#: An absolute POSIX path of at least two components, or a Windows drive
#: path, standing on its own (after a space, quote, '=', ',', ':' or '('), as
#: it appears in a CSV cell, a JSON string or a command line.  Units such
#: as cd/m^2 or e-/s do not match: a letter stands before their slash.
ABSOLUTE_PATH = re.compile(r"(?:^|(?<=[\s\"'=,:(\[]))(?:/[A-Za-z0-9_.~+-]+){2,}|(?:^|(?<=[\s\"'=,(\[]))[A-Za-z]:[\\/]")


def relative_path(path, base) -> str:
    """``path`` relative to the folder ``base`` (POSIX separators); a
    relative ``path`` is taken as it stands (relative to the current
    folder) and made relative to ``base`` too.

    Examples
    --------
    >>> relative_path("/tmp/d-dyes/cfas/a.toml", "/tmp/d-dyes")
    'cfas/a.toml'
    >>> relative_path("/work/repo/configs/paper.toml", "/work/repo/docs/example-report")
    '../../configs/paper.toml'
    """
    p = os.path.abspath(os.fspath(path))
    b = os.path.abspath(os.fspath(base))
    return Path(os.path.relpath(p, b)).as_posix()


def relative_command(words, base) -> str:
    """A command line (a list of words) as one string, every word that is an
    absolute path made relative to ``base`` (:func:`relative_path`).

    >>> relative_command(["bench.py", "--keep", "/tmp/k", "--json", "/tmp/k/x.json"], "/tmp/k")
    'bench.py --keep . --json x.json'
    """
    out = []
    for w in words:
        w = str(w)
        if os.path.isabs(w):
            w = relative_path(w, base)
        elif "=" in w and os.path.isabs(w.split("=", 1)[1]):
            k, v = w.split("=", 1)
            w = f"{k}={relative_path(v, base)}"
        out.append(shlex.quote(w) if w and any(c.isspace() for c in w) else w)
    return " ".join(out)
