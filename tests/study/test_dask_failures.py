"""A study on a real Dask cluster (the suite's ``dask_cluster``: a scheduler
and two `dask worker` processes, each with a nanny) when a worker fails:
one that exceeds its memory limit is restarted by its nanny and its task
retried, not lost; workers recycled by Dask's lifetime options lose
nothing either.  Each ends with tables byte-identical to a local run
(issue 51, items 12 and 13).  The killed-worker case is
tests/test_study_run.py's."""

from __future__ import annotations

import os
import subprocess
import sys

import cloudpickle
import numpy as np
import pytest
from distributed import Client, WorkerPlugin

from conftest import REPO
from dask_cluster import dask_cluster  # noqa: F401 (the suite's one Dask cluster fixture)

SMALL = """\
name = "small"
seed = 1
seeds = 2
scenes = ["macbeth"]
cfas = ["bayer", "rgb4", "cmy1", "rgbw1"]
demosaics = ["bilinear", "laplacian"]
luminances = [10, 30, 100, 300]
[render.macbeth]
width = 120
height = 106
[output]
report = false
"""
#: A worker's memory limit, and what the balloon below holds on top of what the worker already holds.
LIMIT = "1.5GB"
BALLOON_BYTES = 1_600_000_000


def _study(config, out, *extra):
    return subprocess.run([sys.executable, "-m", "cfa_mitsuba", "study", str(config), "--out", str(out), "--quiet",
                           *map(str, extra)], cwd=REPO, capture_output=True, text=True, timeout=900)


@pytest.fixture(scope="module")
def local_run(tmp_path_factory):
    config = tmp_path_factory.mktemp("small") / "small.toml"
    config.write_text(SMALL)
    proc = _study(config, config.parent / "local", "--workers", 2)
    assert proc.returncode == 0, proc.stderr
    return config, config.parent / "local"


def _first_in_cluster(marker: str) -> bool:
    """Whether this worker process is the first to get here: it creates
    ``marker`` (atomically; the other workers find it made) and writes its
    pid there."""
    try:
        fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    except FileExistsError:
        return False
    os.write(fd, str(os.getpid()).encode())
    os.close(fd)
    return True


class Balloon(WorkerPlugin):
    """On the first task any worker starts (once per cluster: a marker file
    decides), hold ``nbytes`` of touched memory in that worker process, so
    its nanny finds it past its memory limit and restarts it mid-task."""

    def __init__(self, marker: str, nbytes: int):
        self.marker, self.nbytes, self.held = marker, nbytes, None

    def transition(self, key, start, finish, **kwargs):
        if finish != "executing" or self.held is not None:
            return
        if not _first_in_cluster(self.marker):
            return  # the balloon went up once already (this may be the restarted worker)
        self.held = np.ones(self.nbytes // 8)  # every page written: resident


class EndOfLifetime(WorkerPlugin):
    """When the first task anywhere in the cluster has finished (a marker
    file decides, once per cluster), end that worker's lifetime as
    ``--lifetime`` does when it lapses: ``Worker.close_gracefully`` with the
    lifetime's reason, which retires the worker from the scheduler (its
    tasks move) and, with ``--lifetime-restart``, has its nanny start a
    fresh one."""

    def __init__(self, marker: str):
        self.marker, self.worker = marker, None

    def setup(self, worker):
        self.worker = worker

    def transition(self, key, start, finish, **kwargs):
        if finish != "memory" or self.worker is None:
            return
        if not _first_in_cluster(self.marker):
            return
        self.worker.io_loop.add_callback(self.worker.close_gracefully, reason="worker-lifetime-reached")


cloudpickle.register_pickle_by_value(sys.modules[__name__])  # the workers cannot import this test module


def _worker_pids(address):
    with Client(address, timeout=60) as c:
        c.wait_for_workers(2, timeout=120)
        return set(c.run(os.getpid).values())


def _same_tables(a, b):
    for name in ("metrics.csv", "scores.csv", "metrics_realisations.csv"):
        assert (a / name).read_bytes() == (b / name).read_bytes(), name


@pytest.mark.parametrize("dask_cluster", [("--memory-limit", LIMIT, "--nthreads", "1")], indirect=True)
def test_a_worker_past_its_memory_limit_is_restarted_and_its_task_retried(local_run, dask_cluster, tmp_path):
    config, local = local_run
    address, _ = dask_cluster
    marker = tmp_path / "ballooned"
    with Client(address, timeout=60) as c:
        c.register_plugin(Balloon(str(marker), BALLOON_BYTES), name="balloon")
    before = _worker_pids(address)
    proc = _study(config, tmp_path / "dask", "--scheduler", address)
    assert proc.returncode == 0, proc.stderr
    assert marker.is_file(), "no worker went past its limit"
    ballooned = int(marker.read_text())
    after = _worker_pids(address)
    assert ballooned in before and ballooned not in after and len(after) == 2, (ballooned, before, after)
    _same_tables(tmp_path / "dask", local)


@pytest.mark.parametrize("dask_cluster", [("--lifetime", "1h", "--lifetime-restart", "--nthreads", "1")],
                         indirect=True)
def test_workers_recycled_by_their_lifetime_lose_nothing(local_run, dask_cluster, tmp_path):
    """Dask's worker lifetime (docs/study.md) retires a worker mid-study and
    its nanny starts a fresh one (``--lifetime-restart``): nothing lost, the
    same tables.  The retirement is the lifetime's own call, made by
    :class:`EndOfLifetime` on the first finished task, so it falls while the
    study runs on any machine (a short ``--lifetime`` raced the study: over
    before the first retirement on a fast machine, workers retired before
    their first task on a loaded one)."""
    config, local = local_run
    address, _ = dask_cluster
    marker = tmp_path / "retired"
    with Client(address, timeout=60) as c:
        c.register_plugin(EndOfLifetime(str(marker)), name="end-of-lifetime")
    before = _worker_pids(address)
    proc = _study(config, tmp_path / "dask", "--scheduler", address)
    assert proc.returncode == 0, proc.stderr
    assert marker.is_file(), "no worker reached the end of its lifetime"
    retired = int(marker.read_text())
    after = _worker_pids(address)  # the nanny's fresh worker among them
    assert retired in before and retired not in after and len(after) == 2, (retired, before, after)
    _same_tables(tmp_path / "dask", local)
