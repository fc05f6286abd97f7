"""Local worker processes for sweeps: started warm, and only when they pay for themselves.

A fresh Python process must import numpy, scipy and numba and load the compiled kernels
before its first point: seconds, more than a small sweep costs in all. Where the operating
system can fork (Linux), the workers are therefore forked from the sweep's driver after it has
solved the statics and loaded the kernels (:func:`~cablesim.analyses.sweep.run_sweep` warms
them up on the case itself), so each worker starts in milliseconds with everything in memory.
Elsewhere they are started by loky, and each loads the kernels once, when it starts.

:func:`choose_workers` decides how many: one (no pool) unless the estimated work of the sweep
exceeds what starting the pool costs by a margin.

Workers ignore Ctrl-C and SIGTERM (the driver handles both and ends its workers), and end by
themselves when the driver dies (:func:`end_with_parent`).
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import threading
import time
from concurrent.futures import FIRST_COMPLETED, wait

from ..errors import CablesimError

#: Seconds a forked worker costs to start (measured: under 0.05 s), and a loky one (it imports
#: the package and loads the kernels: 3-8 s on a shared 2-core machine).
START_COST = {"fork": 0.05, "loky": 5.0}
#: Parallel work must exceed this multiple of the pool's start cost to be worth a pool.
MARGIN = 4.0

#: The context of each running sweep, by key: a forked worker inherits it; a loky worker
#: receives it once, through its initializer.
_CONTEXTS: dict[str, object] = {}
_WATCHDOG: list[int] = []
_IN_WORKER: list[bool] = []


def start_method() -> str:
    """``"fork"`` where the platform forks safely (Linux), else ``"loky"``."""
    return "fork" if hasattr(os, "fork") and os.uname().sysname == "Linux" else "loky"


def cores() -> int:
    """Processors this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def check_jobs(jobs: int) -> None:
    """Refuse a ``--jobs`` that is not a number of processes (1 to four per core) or -1."""
    most = max(64, 4 * (os.cpu_count() or 1))
    if jobs == 0 or jobs < -1 or jobs > most:
        raise CablesimError(f"--jobs must be a number of processes from 1 to {most} (four per core), or -1 for "
                            f"all cores; got {jobs}.")


def choose_workers(requested: int, work_seconds: float, points: int, method: str | None = None) -> int:
    """How many worker processes a sweep uses (1: none, the points run in the driver).

    Parameters
    ----------
    requested : int
        ``--jobs``: a number of processes, or -1 for as many as there are cores.
    work_seconds : float
        Estimated CPU seconds of all the points (see :func:`~cablesim.analyses.sweep.run_sweep`).
    points : int
        Points that can run at once.
    method : str, optional
        ``"fork"`` or ``"loky"`` (default: :func:`start_method`).

    Returns
    -------
    int
        ``j = min(requested, points)`` (-1: the cores) if the saving ``work (1 - 1/j)``
        exceeds :data:`MARGIN` times the start cost of the workers, else 1.
    """
    method = method or start_method()
    most = cores() if requested == -1 else int(requested)
    j = max(1, min(most, points))
    if j <= 1:
        return 1
    start = START_COST[method] * (1 if method == "fork" else j)  # forks are quick; loky starts run side by side
    return j if work_seconds * (1.0 - 1.0 / j) > MARGIN * start else 1


def end_with_parent(parent: int, interval: float = 0.5) -> None:
    """In a worker: exit as soon as the sweep's driver ``parent`` is gone.

    A worker whose driver was killed would otherwise finish its point (minutes, for a long cap)
    with nobody to report to. A daemon thread watches the parent process id; the compiled time
    loop returns to Python many times a second, so the thread gets its turn.
    """
    if _WATCHDOG or parent <= 0 or os.getpid() == parent:
        return
    if os.getppid() != parent:
        os._exit(1)  # the driver died while this worker was starting
    _WATCHDOG.append(parent)

    def watch():
        while True:
            time.sleep(interval)
            if os.getppid() != parent:
                os._exit(1)

    threading.Thread(target=watch, name="cablesim-end-with-parent", daemon=True).start()


def _worker_start(parent: int, key: str | None = None, context=None) -> None:
    """Initializer of every worker: signals to the driver, the watchdog, the sweep's context."""
    _IN_WORKER.append(True)
    _WATCHDOG.clear()  # a forked worker inherits the list, not the thread
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_IGN)
    end_with_parent(parent)
    if context is not None:
        _CONTEXTS[key] = context
        warm = getattr(context, "warm_up", None)
        if warm is not None:
            warm()  # a loky worker loads the kernels now, not in its first point


def context(key: str):
    """The context of sweep ``key`` in this process."""
    return _CONTEXTS[key]


class WorkerPool:
    """``workers`` processes running ``func(key, job)`` for the sweep whose context is stored
    under ``key``. Use as a context manager; :meth:`map_unordered` yields results as they come.
    Leaving the context (also by an exception or an interruption) ends every worker."""

    def __init__(self, workers: int, key: str, ctx, method: str | None = None):
        self.workers, self.key, self.method = workers, key, method or start_method()
        self._executor = None
        _CONTEXTS[key] = ctx
        parent = os.getpid()
        if self.method == "fork":
            from concurrent.futures import ProcessPoolExecutor

            self._executor = ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("fork"),
                                                 initializer=_worker_start, initargs=(parent,))
        else:
            from joblib.externals.loky import get_reusable_executor

            self._executor = get_reusable_executor(workers, initializer=_worker_start,
                                                   initargs=(parent, key, ctx), reuse=False)

    def __enter__(self):
        return self

    def map_unordered(self, func, jobs):
        """``func(key, job)`` for every job, yielded in the order they finish."""
        pending = {self._executor.submit(func, self.key, job) for job in jobs}
        while pending:
            done, pending = wait(pending, return_when=FIRST_COMPLETED)
            for future in done:
                yield future.result()

    def close(self, kill: bool = False) -> None:
        """Stop the workers: at once (``kill``), else once they are idle."""
        ex, self._executor = self._executor, None
        if ex is None:
            return
        procs = list(getattr(ex, "_processes", {}).values()) if kill else []
        ex.shutdown(wait=not kill, cancel_futures=True)
        for p in procs:  # workers ignore SIGTERM (the driver handles it): end them for good
            try:
                p.kill()
            except (OSError, AttributeError):
                pass
        for p in procs:
            p.join(timeout=5)

    def __exit__(self, exc_type, exc, tb):
        self.close(kill=exc_type is not None)
        _CONTEXTS.pop(self.key, None)
        return False
