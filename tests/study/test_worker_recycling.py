"""Local workers are recycled after a stated number of tasks or past a
memory ceiling (issue 51, item 13), without the standard pool's deadlock
(CPython gh-115634), and a study's tables do not depend on it."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

from conftest import REPO

#: Runs a LocalExecutor in a child process (a deadlocked pool fails the test
#: in a minute instead of stalling it) and prints results, processes, recycles.
_CHILD = """
import operator, sys
from cfa_mitsuba.study.executors import LocalExecutor
if __name__ == "__main__":
    kw = eval(sys.argv[1])
    with LocalExecutor(2, **kw) as ex:
        out = sorted(r for _, r in ex.map_unordered(operator.neg, range(12)))
    print(out == [-i for i in range(11, -1, -1)], len(ex.worker_pids), ex.recycled)
"""


def _pool(**kw):
    proc = subprocess.run([sys.executable, "-c", _CHILD, repr(kw)], cwd=REPO, capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    ok, pids, recycled = proc.stdout.split()
    return ok == "True", int(pids), int(recycled)


def test_a_worker_is_replaced_after_its_tasks_and_the_backlog_finishes():
    """12 tasks, 2 workers of 3 tasks each: 4 worker processes, every result
    back (the standard pool, max_tasks_per_child=3, hangs here)."""
    assert _pool(max_tasks=3) == (True, 4, 2)


def test_a_worker_past_its_memory_ceiling_is_replaced():
    """A ceiling of one byte: every worker is past it as its first task
    starts, so each ends after that task."""
    assert _pool(max_memory=1) == (True, 12, 10)
    ok, pids, recycled = _pool(max_memory=1 << 40)  # a ceiling no worker reaches: the first workers do everything
    assert ok and pids <= 2 and recycled == 0


def test_a_study_with_recycled_workers_gives_the_same_tables(tmp_path):
    config = tmp_path / "small.toml"
    config.write_text('name = "small"\nseed = 1\nseeds = 2\nscenes = ["macbeth"]\n'
                      'cfas = ["bayer", "rgb4", "cmy1", "rgbw1"]\ndemosaics = ["bilinear"]\nluminances = [100]\n'
                      "[render.macbeth]\nwidth = 120\nheight = 106\n[output]\nreport = false\n")

    def study(out, *extra):
        proc = subprocess.run([sys.executable, "-m", "cfa_mitsuba", "study", str(config), "--out", str(out), *extra],
                              cwd=REPO, capture_output=True, text=True, timeout=900)
        assert proc.returncode == 0, proc.stderr
        return proc.stderr

    plain = study(tmp_path / "plain", "--workers", "1")  # the tables do not depend on the workers (test_runner.py)
    assert "recycled" not in plain
    # four tasks on two workers, each worker ended after one task: renewed at least twice
    log = study(tmp_path / "recycled", "--workers", "2", "--worker-max-tasks", "1")
    m = re.search(r"workers recycled (\d+) time\(s\) \(after 1 tasks", log)
    assert m and int(m.group(1)) >= 2, log
    for name in ("metrics.csv", "scores.csv", "metrics_realisations.csv"):
        assert (tmp_path / "plain" / name).read_bytes() == (tmp_path / "recycled" / name).read_bytes(), name


@pytest.mark.parametrize("text,expect", [('worker_max_tasks = 50\nworker_max_memory = "2G"\n', (50, 2 << 30)),
                                         ("worker_max_memory = 1000000\n", (None, 1_000_000))])
def test_the_config_states_the_recycling(tmp_path, text, expect):
    from cfa_mitsuba.study.config import load_config

    f = tmp_path / "c.toml"
    f.write_text('scenes = ["macbeth"]\ncfas = ["bayer"]\ndemosaics = ["bilinear"]\n' + text)
    c = load_config(f)
    assert (c.worker_max_tasks, c.worker_max_memory) == expect


@pytest.mark.parametrize("text,match", [("worker_max_tasks = 0\n", "worker_max_tasks"),
                                        ('worker_max_memory = "lots"\n', "worker_max_memory"),
                                        ("worker_max_memory = true\n", "worker_max_memory")])
def test_bad_recycling_settings_are_refused(tmp_path, text, match):
    from cfa_mitsuba.errors import CfaMitsubaError
    from cfa_mitsuba.study.config import load_config

    f = tmp_path / "c.toml"
    f.write_text('scenes = ["macbeth"]\ncfas = ["bayer"]\ndemosaics = ["bilinear"]\n' + text)
    with pytest.raises(CfaMitsubaError, match=match):
        load_config(f)
