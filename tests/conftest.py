"""Shared test fixtures.

Renders go to one cache per test session (shared by the xdist workers, safe
because cache writes are atomic), never to the user's ~/.cache.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
#: ../shared/reference beside the checkout (CI clones main next to shared/).
REFERENCE = REPO.parent / "shared" / "reference"


def pytest_configure(config):
    if "CFA_MITSUBA_CACHE" not in os.environ:
        factory = config._tmp_path_factory if hasattr(config, "_tmp_path_factory") else None
        base = Path(factory.getbasetemp()).parent if factory else Path("/tmp")
        os.environ["CFA_MITSUBA_CACHE"] = str(base / "cfa-mitsuba-test-cache")


@pytest.fixture(scope="session")
def reference_dir() -> Path:
    if not REFERENCE.is_dir():
        pytest.fail(f"reference data not found at {REFERENCE} (shared/ must sit beside the checkout)")
    return REFERENCE


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
