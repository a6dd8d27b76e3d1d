"""Where a study's tasks run: local processes (default) or a Dask cluster.

Both are ``concurrent.futures``-style (DESIGN.md, scale-out): the runner
submits plain functions with plain arguments and collects results as they
complete.

* :class:`LocalExecutor`: a process pool of ``workers`` processes started
  with 'spawn' (a forked copy of a process that has initialised Dr.Jit's
  LLVM back end is not safe), each capped to its share of the cores; with
  one worker the tasks run in this process (no pool, easiest to debug).
* :class:`DaskExecutor`: a ``dask.distributed`` client on a scheduler
  address; plain ``dask worker`` processes started with no options work,
  because every task caps Dr.Jit's threads itself (:func:`thread_budget`).
  Failed tasks (a worker killed mid-task) are retried elsewhere.

Dr.Jit ignores OMP_NUM_THREADS, so the cap travels as the environment
variable ``CFA_MITSUBA_THREADS``, which the render stage applies with
``drjit.set_thread_count`` before rendering.
"""

from __future__ import annotations

__all__ = ["LocalExecutor", "DaskExecutor", "make_executor", "thread_budget", "check_scheduler_address"]

import concurrent.futures as cf
import multiprocessing
import os
import threading
from typing import Callable, Iterable, Iterator

from ..errors import CfaMitsubaError

#: Environment variables that cap the thread pools of numeric libraries in a
#: worker; set for the pool's lifetime only.
_THREAD_ENV = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def _cpu_count() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def thread_budget(workers_on_node: int) -> int:
    """Threads one of ``workers_on_node`` workers may use on this machine."""
    return max(1, _cpu_count() // max(1, int(workers_on_node)))


def _init_worker(threads: int, parent_pid: int | None = None, death_signal: bool = False) -> None:
    os.environ["CFA_MITSUBA_THREADS"] = str(threads)
    if parent_pid is not None:  # issue 27: a worker ends when the study does, even on SIGKILL (study.shutdown)
        from .shutdown import watch_parent

        watch_parent(parent_pid, death_signal=death_signal)


class LocalExecutor:
    """Local processes.  ``map_unordered(fn, items)`` yields ``(item, result)``
    as tasks finish; an exception in a task propagates (with its item)."""

    description: str

    def __init__(self, workers: int | None = None):
        n = int(workers) if workers else min(2, _cpu_count())
        if n < 1:
            raise CfaMitsubaError(f"--workers must be at least 1, got {workers}")
        self.workers = n
        self.threads = thread_budget(n)
        self._pool = None
        self._saved_env: dict = {}
        self.description = f"{n} local process{'es' if n > 1 else ''}, {self.threads} thread(s) each"

    def __enter__(self):
        if self.workers > 1:
            for var in _THREAD_ENV + ("CFA_MITSUBA_THREADS",):
                self._saved_env[var] = os.environ.get(var)
                os.environ[var] = str(self.threads)
            self._pool = cf.ProcessPoolExecutor(
                max_workers=self.workers, mp_context=multiprocessing.get_context("spawn"),
                initializer=_init_worker,
                initargs=(self.threads, os.getpid(), threading.current_thread() is threading.main_thread()),
            )
        else:
            self._saved_env["CFA_MITSUBA_THREADS"] = os.environ.get("CFA_MITSUBA_THREADS")
            os.environ["CFA_MITSUBA_THREADS"] = str(self.threads)
        return self

    def __exit__(self, exc_type, exc, tb):
        if self._pool is not None:
            if exc_type is None:
                self._pool.shutdown(wait=True)
            else:
                # Ctrl-C, SIGTERM, an error: stop the workers now, running tasks
                # included (what finished is saved; a rerun does the rest).
                from .shutdown import stop_pool

                stop_pool(self._pool)
            self._pool = None
        for var, val in self._saved_env.items():
            if val is None:
                os.environ.pop(var, None)
            else:
                os.environ[var] = val
        return False

    def map_unordered(self, fn: Callable, items: Iterable) -> Iterator:
        items = list(items)
        if self._pool is None:
            for item in items:
                yield item, fn(item)
            return
        futures = {self._pool.submit(fn, item): item for item in items}
        try:
            for fut in cf.as_completed(futures):
                yield futures[fut], fut.result()
        finally:
            for fut in futures:
                fut.cancel()


def _dask_call(fn: Callable, item, processes_per_host: dict):
    """Run ``fn(item)`` on a Dask worker with Dr.Jit capped to this worker
    process's share of its node: the node's cores divided by the worker
    processes on that node.  Renders inside one process are serialised
    (study.tasks), so renders never oversubscribe a node however many
    threads each worker runs."""
    try:
        from distributed import get_worker

        host = get_worker().address.rsplit(":", 1)[0]
        procs = processes_per_host.get(host, 1)
    except (ImportError, ValueError):
        procs = 1
    os.environ["CFA_MITSUBA_THREADS"] = str(thread_budget(procs))
    return fn(item)


#: The schemes of a Dask scheduler address (distributed.comm's registered backends).
_DASK_SCHEMES = ("tcp", "tls", "ws", "wss", "ucx", "inproc")


def check_scheduler_address(address: str) -> str:
    """``address`` if it has the form of a Dask scheduler address
    (``tcp://HOST:PORT``, ``HOST:PORT``, or another of
    :data:`_DASK_SCHEMES`), else one line naming the expected form (a
    malformed one was a ValueError traceback from inside the client)."""
    from distributed.comm.addressing import parse_address, parse_host_port

    expected = (f"--scheduler {address!r}: expected a Dask scheduler address such as tcp://HOST:PORT or HOST:PORT "
                "(the scheduler prints its address when it starts)")
    text = str(address).strip()
    try:
        scheme, loc = parse_address(text, strict=False)
        if scheme not in _DASK_SCHEMES or not loc or any(c.isspace() for c in text):
            raise ValueError(scheme)
        if scheme != "inproc":
            host, port = parse_host_port(loc)
            if not host or not 0 < int(port) < 65536:
                raise ValueError(loc)
    except (ValueError, TypeError):
        raise CfaMitsubaError(expected) from None
    return text


class DaskExecutor:
    """A Dask cluster reached at ``address`` (``tcp://HOST:PORT``)."""

    description: str

    def __init__(self, address: str, *, retries: int = 3, timeout_s: float = 30.0):
        try:
            from distributed import Client
        except ImportError:  # pragma: no cover - installed by the dask/test extras
            raise CfaMitsubaError("--scheduler needs dask.distributed: pip install 'cfa-mitsuba[dask]'") from None
        address = check_scheduler_address(address)
        self.address = address
        self.retries = retries
        self.timeout_s = timeout_s
        self._Client = Client
        self.client = None
        self.workers = 0  # known once connected
        self.description = f"Dask cluster at {address}"

    def __enter__(self):
        try:
            self.client = self._Client(self.address, timeout=self.timeout_s)
        except (OSError, TimeoutError, ValueError) as exc:
            raise CfaMitsubaError(f"cannot reach the Dask scheduler at {self.address}: {exc}") from None
        info = self.client.scheduler_info()
        workers = info.get("workers", {})
        if not workers:
            self.client.wait_for_workers(1, timeout=self.timeout_s)
            workers = self.client.scheduler_info().get("workers", {})
        # Worker processes per host: they share the host's cores.
        self._procs: dict[str, int] = {}
        for addr in workers:
            host = addr.rsplit(":", 1)[0]
            self._procs[host] = self._procs.get(host, 0) + 1
        n = len(workers)
        self.workers = n
        self.description = f"Dask cluster at {self.address} ({n} worker{'s' if n != 1 else ''})"
        return self

    def __exit__(self, exc_type, exc, tb):
        if self.client is not None:
            self.client.close()
            self.client = None
        return False

    def map_unordered(self, fn: Callable, items: Iterable) -> Iterator:
        from distributed import as_completed

        items = list(items)
        futures = {}
        for item in items:
            fut = self.client.submit(_dask_call, fn, item, self._procs, pure=False, retries=self.retries)
            futures[fut] = item
        try:
            for fut in as_completed(futures):
                yield futures[fut], fut.result()
        finally:
            for fut in futures:
                fut.cancel()


def make_executor(*, workers: int | None = None, scheduler: str | None = None):
    """A Dask executor for a scheduler address, else local processes."""
    if scheduler:
        return DaskExecutor(scheduler)
    return LocalExecutor(workers)
