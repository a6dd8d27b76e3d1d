"""What a command imports: the heavy packages a command does not use stay
unimported (each costs every command and every study worker its import
time: numba 0.36 s, scipy.fft 0.25 s, colour-science's plotting package and
pyplot 0.7 s, measured on this project's 2-core machine); and
colour-science's plotting, left out of the first import, still works when
something reads from it."""

from __future__ import annotations

import json
import subprocess
import sys

from conftest import REPO

_PROBE = """
import contextlib, io, json, sys
from cfa_mitsuba import cli
with contextlib.redirect_stdout(io.StringIO()):
    try:
        cli.main({argv!r})
    except SystemExit:
        pass
print(json.dumps(sorted(m for m in {names!r} if m in sys.modules)))
"""


def _printed_json(code: str):
    """What ``code``, run in a fresh interpreter, prints as JSON on its last line."""
    proc = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _imported_by(argv, names) -> list[str]:
    return _printed_json(_PROBE.format(argv=list(argv), names=list(names)))


def test_listing_and_help_import_no_compiler_fft_or_plotting():
    heavy = ("numba", "scipy.fft", "matplotlib", "colour", "mitsuba")
    assert _imported_by(["list", "cfas"], heavy) == []
    assert _imported_by(["capture", "--help"], heavy) == []


def test_colour_science_comes_without_its_plotting_until_it_is_read():
    code = (
        "import sys, json\n"
        "from cfa_mitsuba import spectra\n"
        "y = spectra.cmfs_xyz()[:, 1]\n"
        "before = ['matplotlib.pyplot' in sys.modules, type(sys.modules['colour.plotting']).__name__]\n"
        "import colour\n"
        "from colour.plotting import plot_single_sd\n"
        "after = ['matplotlib.pyplot' in sys.modules, type(colour.plotting).__name__, callable(plot_single_sd)]\n"
        "print(json.dumps([before, after, float(y.max())]))\n")
    before, after, y_max = _printed_json(code)
    assert before == [False, "_ImportedOnUse"]
    assert after == [True, "module", True]
    assert 0.9 < y_max <= 1.0  # ybar peaks at 1 near 555 nm: the data came through
