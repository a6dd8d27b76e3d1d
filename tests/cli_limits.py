"""Helpers of the tests that run the command line under hostile conditions
(special files, resource limits, a private render cache): one subprocess
with its own environment, resource limits and a time limit, so a hang
fails the test instead of stalling the run."""

from __future__ import annotations

import os
import resource
import subprocess
import sys

from conftest import REPO

#: What a command may take before it counts as hung (the probe's bound).
HANG_S = 60


def run_limited(*args, cache=None, env=None, limits=(), timeout=HANG_S, cwd=REPO):
    """``cfa-mitsuba ARGS`` in a subprocess with ``CFA_MITSUBA_CACHE=cache``
    (when given), ``env`` added, and ``limits`` ((resource.RLIMIT_*, bytes)
    pairs) set in the child; raises ``subprocess.TimeoutExpired`` past
    ``timeout`` s."""
    full = dict(os.environ, **(env or {}))
    if cache is not None:
        full["CFA_MITSUBA_CACHE"] = str(cache)

    def set_limits():
        for which, value in limits:
            resource.setrlimit(which, (value, value))

    return subprocess.run([sys.executable, "-m", "cfa_mitsuba", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, env=full, preexec_fn=set_limits if limits else None, timeout=timeout)


def assert_error_last(proc, *needles):
    """Exit 2, no traceback, exactly one ``error:`` line on stderr and it is
    the last (notices such as the Mitsuba variant may come before it), naming
    each of ``needles`` (case-insensitive)."""
    assert proc.returncode == 2, (proc.returncode, proc.stdout, proc.stderr)
    assert "Traceback" not in proc.stderr, proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    errors = [ln for ln in lines if " error: " in ln]
    assert len(errors) == 1 and lines[-1] == errors[0], proc.stderr
    for n in needles:
        assert n.lower() in errors[0].lower(), (n, errors[0])
    return errors[0]
