"""A stopped study stops everything it started.

A study's local pool workers are separate processes; without care they
outlive the main process when it is stopped (a CI timeout's SIGTERM, an OOM
killer's SIGKILL), blocked forever on a queue no one will write to.  Three
mechanisms, from the most to the least graceful:

* **SIGTERM** to the main process (:func:`terminate_cleanly`) raises
  :class:`Terminated` in the main thread, so the executor's ``with`` block
  ends and :func:`stop_pool` terminates the workers; the main process then
  dies of SIGTERM as it would have (exit status 143 in a shell).  Finished
  tasks are already saved under ``.work/``, so a rerun resumes.
* **SIGKILL** cannot be caught: each worker asks the kernel to kill it when
  its parent dies (Linux ``prctl(PR_SET_PDEATHSIG, SIGKILL)``, man 2 prctl,
  set in the worker's initializer: :func:`watch_parent`).
* Elsewhere, or if the death signal was lost (a parent that died before the
  worker started), a daemon thread in each worker polls its parent's pid
  every :data:`WATCH_PERIOD_S` and exits when the parent has gone.

multiprocessing's resource tracker exits by itself once no process holds
its pipe, that is once the main process and the workers are gone.
"""

from __future__ import annotations

__all__ = ["Terminated", "terminate_cleanly", "watch_parent", "stop_pool", "WATCH_PERIOD_S"]

import contextlib
import os
import signal
import sys
import threading
import time

#: How often a worker checks that its parent is alive (s): a worker outlives
#: a killed study by at most this long where the kernel's death signal is
#: not available.
WATCH_PERIOD_S = 0.5
#: linux/prctl.h
_PR_SET_PDEATHSIG = 1


class Terminated(KeyboardInterrupt):
    """SIGTERM received: unwinds like Ctrl-C, so every ``with`` block
    (the executor, atomic writes) cleans up."""


def _raise_terminated(signum, frame):
    raise Terminated(f"signal {signum}")


@contextlib.contextmanager
def terminate_cleanly(log=None):
    """Within the block, SIGTERM raises :class:`Terminated` (in the main
    thread only: Python delivers signals there).  When it does, the block's
    cleanup runs and the process then dies of SIGTERM with the default
    action, as an unhandled SIGTERM would have killed it."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    except Terminated:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        if log is not None:
            log("stopped by SIGTERM: the workers were stopped; finished tasks are kept (run again to resume)")
        sys.stderr.flush()
        os.kill(os.getpid(), signal.SIGTERM)
        raise  # pragma: no cover - not reached: the default action ends the process
    finally:
        signal.signal(signal.SIGTERM, previous)


def _set_parent_death_signal() -> None:
    """Ask Linux to SIGKILL this process when the thread that started it exits."""
    if not sys.platform.startswith("linux"):
        return
    import ctypes

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
    except (OSError, AttributeError):  # pragma: no cover - a libc without prctl: the watchdog remains
        pass


def _watchdog(parent_pid: int) -> None:
    while True:
        time.sleep(WATCH_PERIOD_S)
        if os.getppid() != parent_pid:
            os._exit(1)  # the study is gone: nothing to report to, nothing to clean


def watch_parent(parent_pid: int, *, death_signal: bool = True) -> None:
    """In a worker process: end it when ``parent_pid`` (the study) dies.

    ``death_signal``: also use Linux's parent-death signal; only safe when
    the thread that starts the workers lives as long as the study (the main
    thread), since the kernel sends it when that *thread* exits."""
    if death_signal:
        _set_parent_death_signal()
    if os.getppid() != parent_pid:  # the parent died before the death signal was armed
        os._exit(1)
    threading.Thread(target=_watchdog, args=(parent_pid,), name="cfa-mitsuba-parent-watch", daemon=True).start()


def stop_pool(pool, *, grace_s: float = 3.0) -> None:
    """Stop a ``ProcessPoolExecutor`` now: cancel queued work and terminate
    its workers (a task mid-way is lost, its result was never saved; the
    rerun does it).  ``shutdown`` alone waits for running tasks, which may
    take minutes."""
    # ProcessPoolExecutor has no public handle on its processes before 3.14 (terminate_workers)
    procs = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        if p.is_alive():
            p.terminate()
    deadline = time.monotonic() + grace_s
    for p in procs:
        p.join(max(0.0, deadline - time.monotonic()))
        if p.is_alive():
            p.kill()
            p.join(1.0)
