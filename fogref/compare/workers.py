"""A report's figures on worker processes, one per core.

A ``fogref compare`` report's ten figures are independent, and each is matplotlib laying it out in
Python, on one core (threads would not help): 0.2-0.4 s a figure at any image size.
:func:`run_jobs` runs such jobs side by side in worker processes forked from Python's fork
server, which :func:`start_workers` starts early with :data:`WORKER_IMPORTS` imported, so that
the imports take another core while the caller reads the truth and computes the error maps.  A
job's result is the same wherever it runs (``tests/test_compare_report.py``).  The error maps
stay in the caller's process: FLIP's C++ already runs on every core at large sizes, and workers
measured no faster for them (``reports/benchmarks/compare_speed.md``).

Like every :mod:`multiprocessing` child, a worker imports the main module first: a script that asks
for more than one process needs its ``if __name__ == "__main__":`` guard.  The Python API's default
is therefore one process (the caller's); ``fogref compare`` uses every core.
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from multiprocessing import forkserver
from typing import TypeVar

from fogref.cores import usable_cores
from fogref.errors import FogrefError

__all__ = ["WORKER_IMPORTS", "check_processes", "run_jobs", "start_workers"]

T = TypeVar("T")

#: What Python's fork server imports before it forks a worker: what the figures need.
WORKER_IMPORTS = ("fogref.compare.plots", "matplotlib.figure", "matplotlib.backends.backend_agg")


def check_processes(processes) -> int | None:
    """``processes`` if it is None (every core) or an integer >= 1; FogrefError naming it otherwise.

    >>> check_processes(None), check_processes(2)
    (None, 2)
    """
    if processes is None or (
        isinstance(processes, int) and not isinstance(processes, bool) and processes >= 1
    ):
        return processes
    raise FogrefError(f"processes: {processes!r} must be an integer >= 1, or None (every core)")


def start_workers(processes: int | None = 1):
    """The :mod:`multiprocessing` context in which :func:`run_jobs` starts its workers for
    ``processes`` (None: :func:`~fogref.cores.usable_cores`), or None where it runs the jobs in
    this process: one process, or a daemonic process (a Dask worker, which may not start children).

    Where there is one, it is Python's fork server (``spawn`` on systems without one), started
    here if it is not running, with :data:`WORKER_IMPORTS` to import.

    >>> start_workers(1) is None
    True
    """
    n = usable_cores() if processes is None else int(processes)
    if n <= 1 or multiprocessing.current_process().daemon:
        return None
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(list(WORKER_IMPORTS))
    forkserver.ensure_running()
    return context


def run_jobs(jobs: Sequence[Callable[[], T]], processes: int | None = 1) -> list[T]:
    """Call each job (a picklable callable without arguments, such as a :func:`functools.partial`
    of a module-level function) and return the results in the jobs' order.

    ``processes`` (None: every core): above 1 the jobs run in at most this many worker processes,
    at most one per job, started in :func:`start_workers`' context, while this process waits; one
    job too, so that this process need not import what it needs (matplotlib: 0.5 s).
    Where that context is None, or a worker dies (killed, out of memory), the jobs left run in
    this process.  An exception a job raises is raised here.

    >>> import math
    >>> from functools import partial
    >>> run_jobs([partial(math.sqrt, 4.0), partial(math.hypot, 3.0, 4.0)])
    [2.0, 5.0]
    """
    jobs = list(jobs)
    workers = usable_cores() if processes is None else int(processes)
    n = min(len(jobs), workers)
    context = start_workers(workers) if workers > 1 and jobs else None
    if context is None:
        return [job() for job in jobs]
    done: dict[int, T] = {}
    try:
        with ProcessPoolExecutor(n, mp_context=context) as pool:
            futures = [pool.submit(job) for job in jobs]
            for i, future in enumerate(futures):
                done[i] = future.result()
    except BrokenProcessPool:  # a worker died: what it had not returned runs here
        pass
    return [done[i] if i in done else jobs[i]() for i in range(len(jobs))]
