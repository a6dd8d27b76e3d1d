"""Where a study's tasks run: local processes (default) or a Dask cluster.

Both are ``concurrent.futures``-style (DESIGN.md, scale-out): the runner
submits plain functions with plain arguments and collects results as they
complete.

* :class:`LocalExecutor`: a process pool of ``workers`` processes started
  with 'spawn' (a forked copy of a process that has initialised Dr.Jit's
  LLVM back end is not safe), each capped to its share of the cores; with
  one worker the tasks run in this process (no pool, easiest to debug).
  A worker is recycled (ends, and a fresh one takes its place) after
  ``max_tasks`` tasks or once its resident memory passes ``max_memory``:
  Mitsuba keeps memory over many scene loads in one process (mitsuba3
  issues 1890, 190), so a run of a million captures must not live in one
  process (benchmarks/bench_recycling.py: worker memory over 2,000
  renders).  Results do not depend on it: every task is seeded.
* :class:`DaskExecutor`: a ``dask.distributed`` client on a scheduler
  address; plain ``dask worker`` processes started with no options work,
  because every task caps Dr.Jit's threads itself (:func:`thread_budget`).
  Failed tasks (a worker killed mid-task, or restarted by its nanny past
  its ``--memory-limit``) are retried elsewhere.  Dask workers are
  recycled by Dask's own options (``dask worker --lifetime 1h
  --lifetime-stagger 5m --lifetime-restart``, ``--memory-limit``;
  docs/study.md), not by this module.

Dr.Jit ignores OMP_NUM_THREADS, so the cap travels as the environment
variable ``CFA_MITSUBA_THREADS``, which the render stage applies with
``drjit.set_thread_count`` before rendering.
"""

from __future__ import annotations

__all__ = ["LocalExecutor", "DaskExecutor", "make_executor", "thread_budget", "check_scheduler_address",
           "WORKERS_ENV", "default_workers"]

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


#: Set to a whole number >= 1: the local worker processes of a study, a
#: design search and a report's drawing when neither ``--workers`` nor the
#: config's ``workers`` says (the test suite sets 1: its two pytest workers
#: already fill a 2-core machine, and each extra process costs its imports).
WORKERS_ENV = "CFA_MITSUBA_WORKERS"


def default_workers() -> int:
    """The local worker processes when nothing else says: ``$CFA_MITSUBA_WORKERS``,
    else 2 capped at the cores."""
    raw = os.environ.get(WORKERS_ENV, "").strip()
    if not raw:
        return min(2, _cpu_count())
    if not raw.isdigit() or int(raw) < 1:
        raise CfaMitsubaError(f"${WORKERS_ENV} must be a whole number >= 1, got {raw!r}")
    return int(raw)


def thread_budget(workers_on_node: int) -> int:
    """Threads one of ``workers_on_node`` workers may use on this machine."""
    return max(1, _cpu_count() // max(1, int(workers_on_node)))


#: A local worker is recycled after this many tasks unless told otherwise (a
#: study's ordinary run sends each worker far fewer; a long one is renewed).
DEFAULT_WORKER_MAX_TASKS = 1000
#: ... or once its resident memory passes this share of the memory available
#: per worker (Dask's nanny pauses a worker at the same share, 0.8).
DEFAULT_WORKER_MEMORY_SHARE = 0.8


def _rss_bytes() -> int:
    """This process's resident memory now (bytes; /proc/self/statm on Linux,
    else the peak, which errs towards recycling)."""
    try:
        with open("/proc/self/statm", "rb") as fh:  # a kernel file: always a regular, tiny file
            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        import resource

        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


class _Recycle:
    """The pool's per-worker task limit, extended by a memory ceiling.

    ``concurrent.futures`` ends a worker after ``max_tasks_per_child`` tasks
    (Python >= 3.11) and starts a fresh one in its place; its worker loop
    decides with ``num_tasks >= max_tasks`` as each task starts
    (``concurrent/futures/process.py``, ``_process_worker``).  An object of
    this class stands in for that number: the comparison is also true once
    the worker's resident memory has passed ``max_memory`` bytes, so the
    worker ends after the task it is starting (at most one task past the
    ceiling).  tests/study/test_worker_recycling.py holds the pool to it."""

    def __init__(self, max_tasks: int, max_memory: int | None):
        self.max_tasks, self.max_memory = int(max_tasks), max_memory

    def __le__(self, num_tasks: int) -> bool:  # `num_tasks >= max_tasks`, reflected
        return num_tasks >= self.max_tasks or (self.max_memory is not None and _rss_bytes() > self.max_memory)


def _recycling_pool(recycle: _Recycle, **kwargs):
    """A process pool whose workers end at their :class:`_Recycle` limit and
    are always replaced.

    The standard pool can deadlock with ``max_tasks_per_child``: it decides
    whether to start a replacement from a semaphore that counts finished
    tasks, not idle workers, so with a backlog it may start none once every
    worker has reached its limit (CPython gh-115634, present in 3.11 to
    3.15.0b3, fixed upstream in gh-140900 by the rule used here).  Here a
    worker that ends is replaced whenever the pool is below its size.  The
    class is made on ``concurrent.futures.ProcessPoolExecutor`` as it is
    when called (a test's stand-in for a pool that cannot start included)."""

    class RecyclingPool(cf.ProcessPoolExecutor):
        def _adjust_process_count(self):
            while len(self._processes) < self._max_workers:
                self._spawn_process()

    pool = RecyclingPool(max_tasks_per_child=recycle.max_tasks, **kwargs)
    pool._max_tasks_per_child = recycle  # read by each worker as it starts a task (class _Recycle)
    return pool


def _in_worker(fn: Callable, item):
    """``fn(item)`` and the process that ran it (so recycling can be counted)."""
    return os.getpid(), fn(item)


def _init_worker(threads: int, parent_pid: int | None = None, death_signal: bool = False) -> None:
    os.environ["CFA_MITSUBA_THREADS"] = str(threads)
    if parent_pid is not None:  # issue 27: a worker ends when the study does, even on SIGKILL (study.shutdown)
        from .shutdown import watch_parent

        watch_parent(parent_pid, death_signal=death_signal)


class LocalExecutor:
    """Local processes.  ``map_unordered(fn, items)`` yields ``(item, result)``
    as tasks finish; an exception in a task propagates (with its item)."""

    description: str

    def __init__(self, workers: int | None = None, *, max_tasks: int | None = None, max_memory: int | None = None):
        n = int(workers) if workers else default_workers()
        if n < 1:
            raise CfaMitsubaError(f"--workers must be at least 1, got {workers}")
        self.workers = n
        self.threads = thread_budget(n)
        self.max_tasks = int(max_tasks) if max_tasks else DEFAULT_WORKER_MAX_TASKS
        if max_memory is None:
            from ..io.limits import available_memory_bytes

            have = available_memory_bytes()[0]
            max_memory = int(DEFAULT_WORKER_MEMORY_SHARE * have / n) if have else None
        self.max_memory = max_memory
        self.worker_pids: set[int] = set()  # every worker process that ran a task
        self._pool = None
        self._saved_env: dict = {}
        self.description = f"{n} local process{'es' if n > 1 else ''}, {self.threads} thread(s) each"

    def __enter__(self):
        if self.workers > 1:
            for var in _THREAD_ENV + ("CFA_MITSUBA_THREADS",):
                self._saved_env[var] = os.environ.get(var)
                os.environ[var] = str(self.threads)
            self._pool = _recycling_pool(
                _Recycle(self.max_tasks, self.max_memory),
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

    @property
    def recycled(self) -> int:
        """How many times a worker was replaced by a fresh one so far."""
        return max(0, len(self.worker_pids) - self.workers)

    def map_unordered(self, fn: Callable, items: Iterable) -> Iterator:
        items = list(items)
        if self._pool is None:
            for item in items:
                yield item, fn(item)
            return
        futures = {self._pool.submit(_in_worker, fn, item): item for item in items}
        try:
            for fut in cf.as_completed(futures):
                pid, result = fut.result()
                self.worker_pids.add(pid)
                yield futures[fut], result
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


def make_executor(*, workers: int | None = None, scheduler: str | None = None, max_tasks: int | None = None,
                  max_memory: int | None = None):
    """A Dask executor for a scheduler address, else local processes
    (recycled after ``max_tasks`` tasks or past ``max_memory`` bytes)."""
    if scheduler:
        return DaskExecutor(scheduler)
    return LocalExecutor(workers, max_tasks=max_tasks, max_memory=max_memory)
