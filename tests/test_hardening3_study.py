"""Hardening, round three (issue 27), the study's items: a stopped study
stops every process it started and resumes (1); untrusted resume files are
recomputed with one notice (8).

A small study (one Macbeth render, six CFAs, two workers) runs once
uninterrupted; every stopped or damaged run must end, when run again, with
byte-identical tables.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import REPO

SMALL = """\
name = "small"
seed = 1
seeds = 2
scenes = ["macbeth"]
cfas = ["bayer", "rgb4", "cmy1", "rgbw1", "rgb1", "rgb2"]
demosaics = ["bilinear", "pocs"]
luminances = [100]
[render.macbeth]
width = 120
height = 106
[output]
report = false
"""


def _cmd(config: Path, out: Path, *extra) -> list[str]:
    return [sys.executable, "-m", "cfa_mitsuba", "study", str(config), "--out", str(out), "--quiet", *map(str, extra)]


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    d = tmp_path_factory.mktemp("small")
    config = d / "small.toml"
    config.write_text(SMALL)
    out = d / "reference"
    proc = subprocess.run(_cmd(config, out, "--workers", 2), cwd=REPO, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return config, out


def _parents() -> dict[int, int]:
    """{pid: parent pid} of every process, from /proc (Linux)."""
    out = {}
    for name in os.listdir("/proc"):
        if name.isdigit():
            try:
                stat = Path(f"/proc/{name}/stat").read_text()
            except OSError:
                continue
            out[int(name)] = int(stat.rsplit(")", 1)[1].split()[1])
    return out


def _descendants(root: int) -> set[int]:
    parents, found, frontier = _parents(), set(), {root}
    while frontier:
        frontier = {pid for pid, ppid in parents.items() if ppid in frontier} - found
        found |= frontier
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"  # a zombie has ended; only its parent's bookkeeping is left


def _tables(out: Path) -> dict[str, bytes]:
    return {n: (out / n).read_bytes() for n in ("metrics.csv", "scores.csv", "metrics_realisations.csv")}


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL], ids=["SIGTERM", "SIGKILL"])
def test_a_stopped_study_leaves_no_process_and_resumes(small, tmp_path, sig):
    config, reference = small
    out = tmp_path / "stopped"
    log = open(tmp_path / "stderr.txt", "w")  # not a pipe: a leaked worker would hold it open forever
    proc = subprocess.Popen(_cmd(config, out, "--workers", 2), cwd=REPO, stdout=subprocess.DEVNULL, stderr=log)
    children: set[int] = set()
    try:
        t0 = time.time()
        while not (out / ".work").is_dir() or not any((out / ".work").glob("*.json")):  # evaluating
            assert proc.poll() is None, (tmp_path / "stderr.txt").read_text()
            assert time.time() - t0 < 240, "no task finished"
            time.sleep(0.05)
        children = _descendants(proc.pid)
        assert len(children) >= 3, children  # two pool workers and multiprocessing's resource tracker
        proc.send_signal(sig)  # the main process only, as a CI timeout or the OOM killer does
        proc.wait(timeout=60)
        time.sleep(5.0)
        left = sorted(pid for pid in children if _alive(pid))
        assert not left, f"alive 5 s after {sig.name}: " + "; ".join(
            Path(f"/proc/{p}/cmdline").read_text().replace("\0", " ")[:100] for p in left)
    finally:
        log.close()
        for pid in children:  # never leave a leaked worker behind a failed test
            if _alive(pid):
                os.kill(pid, signal.SIGKILL)
    assert proc.returncode == -sig
    assert not (out / "metrics.csv").exists()
    finished = len(list((out / ".work").glob("*.json")))
    again = subprocess.run(_cmd(config, out, "--workers", 2), cwd=REPO, capture_output=True, text=True)
    assert again.returncode == 0, again.stderr
    m = re.search(r"(\d+) task\(s\) run, (\d+) reused", again.stderr)
    assert m and int(m.group(2)) == finished and int(m.group(1)) == 6 - finished, again.stderr
    assert _tables(out) == _tables(reference)


DAMAGE = {
    "a string": json.dumps("not a result"),
    "a list": json.dumps([1, 2, 3]),
    "NaN": "NaN",
    "100,000-deep array": "[" * 100_000 + "]" * 100_000,
    "rows of strings": json.dumps({"rows": ["x"], "timing": {}}),
    "not JSON": "{\"rows\": [",
}


def test_untrusted_resume_files_are_recomputed_with_one_notice(small, tmp_path):
    config, reference = small
    out = tmp_path / "damaged"
    first = subprocess.run(_cmd(config, out, "--workers", 1), cwd=REPO, capture_output=True, text=True)
    assert first.returncode == 0, first.stderr
    files = sorted((out / ".work").glob("*.json"))
    assert len(files) == 6
    for f, text in zip(files, DAMAGE.values()):
        f.write_text(text)
    again = subprocess.run(_cmd(config, out, "--workers", 1), cwd=REPO, capture_output=True, text=True)
    assert again.returncode == 0, again.stderr
    assert "Traceback" not in again.stderr
    notices = [line for line in again.stderr.splitlines() if "could not be trusted" in line]
    assert len(notices) == 1 and "6 saved task result(s)" in notices[0], again.stderr
    assert "6 task(s) run, 0 reused" in again.stderr
    assert _tables(out) == _tables(reference)
    # and the rewritten files are trusted by the next run
    third = subprocess.run(_cmd(config, out, "--workers", 1), cwd=REPO, capture_output=True, text=True)
    assert third.returncode == 0 and "0 task(s) run, 6 reused" in third.stderr, third.stderr
