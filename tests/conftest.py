"""Shared test fixtures.

Renders go to a fresh cache for each test run (shared by that run's xdist
workers, safe because cache writes are atomic), never to the user's
~/.cache nor to a cache that a previous run or another checkout filled: a
render that a code or data change should have invalidated cannot pass on a
warm cache.  ``CFA_MITSUBA_TEST_CACHE=DIR`` reuses DIR on purpose (a
developer's quick reruns).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


@pytest.hookimpl(trylast=True)  # after the tmp_path plugin has set up its factory
def pytest_configure(config):
    if hasattr(config, "workerinput"):
        return  # an xdist worker: the controller set the cache before starting it
    # a study, design or report that names no worker count runs in its own process: pytest's two workers
    # already fill the 2-core machine, and two more processes per study only added their imports (a tiny
    # study: 3.6 s of CPU in one process, 8.1 s with two workers); tests of the pools pass --workers
    os.environ["CFA_MITSUBA_WORKERS"] = "1"
    chosen = os.environ.get("CFA_MITSUBA_TEST_CACHE", "").strip()
    if chosen:
        os.environ["CFA_MITSUBA_CACHE"] = chosen
        return
    # this run's own temporary directory (pytest-of-USER/pytest-N: new for every run)
    base = Path(config._tmp_path_factory.getbasetemp())
    os.environ["CFA_MITSUBA_CACHE"] = str(base / "cfa-mitsuba-test-cache")


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """A skipped test is a failed one: the suite promises no skips on any machine that ran
    ./setup.sh (tests/test_suite_rules.py keeps skip and xfail out of the sources)."""
    outcome = yield
    report = outcome.get_result()
    if report.skipped:
        report.outcome = "failed"
        report.longrepr = f"skipped, which this suite does not allow: {report.longrepr}"


def _loopback_only(connect):
    """``socket.connect`` that refuses any address but loopback and local sockets: the suite
    needs no network (Dask's test cluster runs on 127.0.0.1)."""
    import ipaddress
    import socket

    def guarded(self, address, *args):
        if self.family in (socket.AF_INET, socket.AF_INET6):
            host = address[0]
            try:
                local = ipaddress.ip_address(host).is_loopback
            except ValueError:
                local = host == "localhost"
            if not local:
                raise OSError(f"a test tried to reach {host!r}: the suite uses no network")
        return connect(self, address, *args)

    return guarded


def pytest_sessionstart(session):
    import socket

    socket.socket.connect = _loopback_only(socket.socket.connect)
    socket.socket.connect_ex = _loopback_only(socket.socket.connect_ex)


def run_cli(*args, check_rc=None):
    """Run ``cfa-mitsuba ARGS`` in a subprocess; returns CompletedProcess."""
    import subprocess

    proc = subprocess.run(
        [sys.executable, "-m", "cfa_mitsuba", *map(str, args)],
        capture_output=True, text=True, cwd=REPO,
    )
    if check_rc is not None:
        assert proc.returncode == check_rc, (proc.returncode, proc.stdout, proc.stderr)
    return proc


def assert_one_line_error(proc, *needles):
    """Exit 2, one line on stderr naming the problem, no traceback."""
    assert proc.returncode == 2, (proc.returncode, proc.stdout, proc.stderr)
    lines = [l for l in proc.stderr.splitlines() if l.strip()]
    assert len(lines) == 1, proc.stderr
    assert "Traceback" not in proc.stderr
    for n in needles:
        assert n.lower() in lines[0].lower(), (n, lines[0])
