"""A study's saved task results (``.work/<task>.json``) when something else
stands in their place: a FIFO, a link to /dev/zero, a folder.  Each is the
ordinary untrusted state: its task runs again, with one notice, and the
study finishes with the same tables (issue 51, items 2 and 3)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

import tiny_study
from conftest import REPO
from cfa_mitsuba.study.resume import load_finished

TINY = tiny_study.TINY + tiny_study.NO_REPORT


def _result():
    return {"rows": [{"metric": "delta-e", "value": 1.5}], "timing": {"capture_s": 0.1}}


@pytest.mark.parametrize("kind", ["fifo", "dev-zero", "folder"])
def test_a_special_file_in_place_of_a_task_result_is_recomputed(tmp_path, kind):
    import json

    work = tmp_path / ".work"
    work.mkdir()
    (work / "good.json").write_text(json.dumps(_result()))
    bad = work / "bad.json"
    if kind == "fifo":
        os.mkfifo(bad)
    elif kind == "dev-zero":
        bad.symlink_to("/dev/zero")
    else:
        bad.mkdir()
        (bad / "x.json").write_text("{}")
    notices = []
    done = load_finished(work, ["good", "bad"], notices.append)
    assert list(done) == ["good"]
    assert len(notices) == 1 and "bad.json" in notices[0] and "recomputed" in notices[0], notices
    assert not bad.exists() and not bad.is_symlink(), "its place is cleared for the new result"


def _study(config, out):
    return subprocess.run([sys.executable, "-m", "cfa_mitsuba", "study", str(config), "--out", str(out),
                           "--workers", "1"], capture_output=True, text=True, cwd=REPO, timeout=600)


def test_a_study_whose_task_result_became_a_folder_resumes_with_one_notice(tmp_path):
    config = tmp_path / "tiny.toml"
    config.write_text(TINY)
    out = tmp_path / "out"
    first = _study(config, out)
    assert first.returncode == 0, first.stderr
    reference = (out / "metrics.csv").read_bytes()
    task = sorted((out / ".work").glob("*.json"))[0]
    task.unlink()
    task.mkdir()
    (out / "metrics.csv").unlink()
    again = _study(config, out)
    assert again.returncode == 0, again.stderr
    assert ".part" not in again.stderr
    notices = [ln for ln in again.stderr.splitlines() if "could not be trusted" in ln]
    assert len(notices) == 1 and task.name in notices[0] and "directory" in notices[0], again.stderr
    assert "1 task(s) run, 1 reused" in again.stderr, again.stderr
    assert task.is_file() and (out / "metrics.csv").read_bytes() == reference
