"""``$CFA_MITSUBA_WORKERS``: the local worker processes of a study, a design
search and a report's drawing when neither ``--workers`` nor the config
says (the suite runs with it at 1: tests/conftest.py); a bad value is one
clear line before any work."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

import tiny_study
from conftest import REPO, assert_one_line_error
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.report import report_workers
from cfa_mitsuba.study.executors import LocalExecutor, _cpu_count, default_workers
from cfa_mitsuba.study.sizing import resolve_workers


def test_the_variable_sets_the_default_and_an_explicit_count_wins(monkeypatch):
    monkeypatch.delenv("CFA_MITSUBA_WORKERS", raising=False)
    assert default_workers() == min(2, _cpu_count()) == LocalExecutor().workers
    monkeypatch.setenv("CFA_MITSUBA_WORKERS", "3")
    assert default_workers() == 3 and LocalExecutor().workers == 3
    assert resolve_workers(None, None, print) == 3
    assert resolve_workers(None, 1, print) == 1 and resolve_workers(2, 1, print) == 2  # config, then --workers
    assert report_workers(None) == min(3, _cpu_count()) and report_workers(1) == 1


@pytest.mark.parametrize("value", ["0", "-1", "two", "1.5", " "])
def test_a_bad_value_is_refused_naming_the_variable(monkeypatch, value):
    monkeypatch.setenv("CFA_MITSUBA_WORKERS", value)
    if not value.strip():  # blank: not set
        assert default_workers() == min(2, _cpu_count())
        return
    with pytest.raises(CfaMitsubaError, match=r"\$CFA_MITSUBA_WORKERS must be a whole number >= 1"):
        default_workers()


def test_the_study_command_refuses_a_bad_value_before_any_work(tmp_path):
    config = tmp_path / "tiny.toml"
    config.write_text(tiny_study.TINY + tiny_study.NO_REPORT)
    env = {**os.environ, "CFA_MITSUBA_WORKERS": "many"}
    proc = subprocess.run([sys.executable, "-m", "cfa_mitsuba", "study", str(config), "--out", str(tmp_path / "out")],
                          cwd=REPO, env=env, capture_output=True, text=True, timeout=300)
    assert_one_line_error(proc, "CFA_MITSUBA_WORKERS", "'many'")
    assert not (tmp_path / "out").exists()
