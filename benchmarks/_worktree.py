"""Another commit checked out beside this tree, for the benchmarks that
compare two trees in one run (bench_study.py, bench_task.py,
bench_startup.py)."""

from __future__ import annotations

import contextlib
import subprocess
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


@contextlib.contextmanager
def checked_out(rev: str):
    """The folder of a detached git worktree of this repository at ``rev``,
    in a temporary folder; the worktree is removed on leaving, after an
    error or an interrupt too (a registered worktree left behind would make
    git refuse the next one's folder)."""
    with tempfile.TemporaryDirectory(prefix="bench_tree_") as tmp:
        where = Path(tmp) / "tree"
        subprocess.run(["git", "-C", str(REPO), "worktree", "add", "--detach", "-q", str(where), rev], check=True,
                       capture_output=True, text=True)
        try:
            yield where
        finally:
            subprocess.run(["git", "-C", str(REPO), "worktree", "remove", "--force", str(where)], capture_output=True)
