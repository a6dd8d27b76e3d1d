"""The suite's one Dask cluster fixture: a real scheduler and two plain
`dask worker` processes on loopback, for the tests that run a study on
Dask (tests/study/test_runner.py, tests/study/test_dask_failures.py)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest


@pytest.fixture
def dask_cluster(tmp_path, request):
    """A real scheduler and two plain `dask worker` processes on loopback
    (indirect parameters: more `dask worker` options, tests/study/test_dask_failures.py)."""
    worker_options = list(getattr(request, "param", ()))
    env = dict(os.environ)
    sched_file = tmp_path / "scheduler.json"
    procs = [subprocess.Popen(
        [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0",
         "--no-dashboard", "--scheduler-file", str(sched_file)],
        env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)]
    try:
        while not sched_file.exists():  # a scheduler that never starts is a hang: pytest-timeout ends it
            assert procs[0].poll() is None, "the scheduler exited"
            time.sleep(0.1)
        address = json.loads(sched_file.read_text())["address"]
        for _ in range(2):  # no options: the default nanny, threads and memory limit
            procs.append(subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address,
                                           *worker_options], env=env, cwd=tmp_path, stdout=subprocess.DEVNULL,
                                          stderr=subprocess.DEVNULL, start_new_session=True))
        from distributed import Client

        with Client(address, timeout=300) as client:  # hang guards: a cluster starts in seconds
            client.wait_for_workers(2, timeout=300)
        yield address, procs
    finally:
        for p in procs[::-1]:
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
        for p in procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
