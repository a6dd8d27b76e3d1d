"""Every small file the project reads goes through the one bounded,
regular-file reader (cfa_mitsuba/io/guard.py): a config, CFA, sensor file
or parity case given as a FIFO or a link to /dev/zero, and the JSON and
CSV files of a finished study, are refused in one line or skipped as
unreadable, never read for ever (issue 51, item 2)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from cli_limits import HANG_S, assert_error_last, run_limited
from conftest import REPO


def _special(path, kind):
    if kind == "fifo":
        os.mkfifo(path)
    else:
        path.symlink_to("/dev/zero")
    return path


@pytest.fixture(scope="module")
def exr(tmp_path_factory):
    out = tmp_path_factory.mktemp("exr")
    proc = run_limited("render", "macbeth", "--width", 30, "--height", 20, "--out", out, cache=out / "cache")
    assert proc.returncode == 0, proc.stderr
    return out / "macbeth.exr"


@pytest.mark.parametrize("kind,word", [("fifo", "FIFO"), ("dev-zero", "character device")])
@pytest.mark.parametrize("flag,what", [("--cfa", "CFA file"), ("--sensor", "sensor file")])
def test_capture_refuses_a_special_cfa_or_sensor_file(exr, tmp_path, kind, word, flag, what):
    f = _special(tmp_path / "mine.toml", kind)
    proc = run_limited("capture", exr, flag, f, "--out", tmp_path / "raw.npz")
    assert_error_last(proc, word, str(f))
    assert not (tmp_path / "raw.npz").exists()


@pytest.mark.parametrize("kind,word", [("fifo", "FIFO"), ("dev-zero", "character device")])
def test_study_and_parity_refuse_a_special_config_or_case(tmp_path, kind, word):
    config = _special(tmp_path / "study.toml", kind)
    assert_error_last(run_limited("study", config, "--out", tmp_path / "s"), "config file", word)
    case = _special(tmp_path / "case.toml", kind) if kind == "fifo" else config
    assert_error_last(run_limited("parity", case), "parity case", word)


def _load_in_child(root):
    """load_results(root) in a child process (a hang fails, not stalls, the test)."""
    code = ("import sys; from cfa_mitsuba.report.results import load_results; r = load_results(sys.argv[1]); "
            "print(sorted(r.ranges), r.config.get('name'), r.timing)")
    return subprocess.run([sys.executable, "-c", code, str(root)], capture_output=True, text=True, cwd=REPO,
                          timeout=HANG_S)


def test_a_finished_studys_json_and_csv_files_are_read_through_the_reader(tmp_path):
    root = tmp_path / "results"
    root.mkdir()
    (root / "metrics.csv").write_text("scene,cfa,demosaic,luminance,metric,value,unit\n"
                                      "macbeth,bayer,bilinear,100,delta-e,2.5,dE00\n"
                                      "macbeth,rgb4,bilinear,100,delta-e,3.5,dE00\n")
    for name in ("config.json", "ranges.json", "timing.json"):
        _special(root / name, "fifo")
    _special(root / "scores.csv", "fifo")
    proc = _load_in_child(root)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split()[-2:] == ["None", "None"], proc.stdout  # unreadable: read as absent
    (root / "ranges.json").unlink()
    (root / "ranges.json").write_text("[" * 100_000)  # nested past any parser
    proc = _load_in_child(root)
    assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stderr
    (root / "metrics.csv").unlink()
    _special(root / "metrics.csv", "fifo")
    proc = _load_in_child(root)
    assert proc.returncode == 1 and "metrics table" in proc.stderr and "FIFO" in proc.stderr, proc.stderr
