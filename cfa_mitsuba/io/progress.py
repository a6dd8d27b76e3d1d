"""Progress on a terminal (tqdm) and the quiet switch of the long commands
(issue 50: design, report, parity, convergence, sensor emva, render of a
user scene, study).

A bar is drawn on stderr only when stderr is a terminal (tqdm's
``disable=None``), so logs, pipes and tests get no carriage-return noise;
``--quiet`` turns bars and log lines off, and the command prints only its
result path(s) on stdout.
"""

from __future__ import annotations

__all__ = ["progress_bar", "stderr_log"]

import sys


def progress_bar(total=None, desc: str = "", *, enabled: bool = True, unit: str = "step"):
    """A tqdm bar on stderr: shown on a terminal when ``enabled``, never
    otherwise (``update``, ``set_postfix_str`` and ``close`` work either way)."""
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit=unit, file=sys.stderr, disable=None if enabled else True,
                dynamic_ncols=True, leave=False)


def stderr_log(quiet: bool = False):
    """A log callable: each line to stderr through tqdm (so a bar on the
    terminal stays below it), or nothing when ``quiet``."""
    if quiet:
        return lambda msg: None
    from tqdm import tqdm

    return lambda msg: tqdm.write(str(msg), file=sys.stderr)
