"""The Dask cluster of ``fogref sweep`` and ``fogref render``: check, connect, log, stop.

One code path for both commands (Dask distributed): ``--scheduler ADDRESS`` connects to a
running scheduler; otherwise a ``LocalCluster`` of ``--workers`` single-threaded worker
processes (default: one per core) is started, its workers' own output going to a log file,
and closed at the end.  A second Ctrl-C while the cluster closes is ignored, so the close
finishes.  Importing this module does no work (Dask is imported when a cluster is made).
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import signal
import sys
import threading
from pathlib import Path

from fogref import params as P
from fogref.errors import ParameterError

__all__ = [
    "ADDRESS",
    "WORKER_TIMEOUT",
    "WORKER_UNSET_ENV",
    "check_worker_timeout",
    "Interrupt",
    "check_scheduler",
    "check_workers",
    "connect",
    "main_thread",
    "stderr_to",
    "stop",
]

#: Variables that Dask's nanny sets in every worker process by default
#: (``distributed.nanny.pre-spawn-environ``) and a LocalCluster here starts its workers without.
#: ``MALLOC_TRIM_THRESHOLD_=65536`` turns off glibc's adaptive mmap threshold: every array over 128 KiB
#: is then mapped, faulted in and unmapped again, and the Unreal fit took 1.5x the CPU
#: (``reports/benchmarks/sweep_speed.md``).  A variable the user set is kept.
WORKER_UNSET_ENV = ("MALLOC_TRIM_THRESHOLD_",)

#: A Dask scheduler address: ``tcp://HOST:PORT`` (or another Dask protocol: tls, inproc, ucx, ws, wss),
#: or ``HOST:PORT``.
ADDRESS = re.compile(r"^(?:(?:tcp|tls|inproc|ucx|ws|wss)://\S+|[A-Za-z0-9_.\-\[\]:]+:\d{1,5})$")


def check_scheduler(scheduler, source: str, name: str = "--scheduler") -> str | None:
    """``scheduler`` (None, or a Dask scheduler address, stripped), else a one-line ParameterError.

    >>> check_scheduler("tcp://127.0.0.1:8786", "fogref render")
    'tcp://127.0.0.1:8786'
    >>> check_scheduler("nowhere", "fogref render")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: fogref render: parameter '--scheduler': 'nowhere' is not a Dask ...
    """
    if scheduler is None:
        return None
    if not (isinstance(scheduler, str) and ADDRESS.match(scheduler.strip())):
        raise ParameterError(
            source,
            name,
            f"{scheduler!r} is not a Dask scheduler address [PROTOCOL://]HOST[:PORT] (a protocol or a "
            "port is needed, e.g. tcp://127.0.0.1:8786)",
        )
    return scheduler.strip()


def check_workers(n_workers, source: str) -> int | None:
    """``n_workers`` (None, or a worker count in [1, 4096]), else a one-line ParameterError.

    >>> check_workers(2, "fogref render")
    2
    """
    if n_workers is None:
        return None
    return P.integer(n_workers, "--workers", source=source, lo=1, hi=4096)


class Interrupt:
    """Ctrl-C and SIGTERM while rendering.

    The first one sets :attr:`requested` (a render stops after the current pass, checkpointed;
    a sweep after the configurations running); a second one raises KeyboardInterrupt now, except
    inside :meth:`deferred` (a checkpoint write), where it waits until the block ends; inside
    :meth:`urgent` (a cluster starting) the first one raises at once.  :attr:`requested` stays
    set, so a caller that sees its work end normally still knows that it was interrupted.
    Outside the main thread signals are left alone.
    """

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self):
        self.requested = False
        self._pending = False
        self._deferring = 0
        self._urgent = 0
        self._previous = {}

    def __enter__(self):
        for s in self.SIGNALS:
            try:
                self._previous[s] = signal.signal(s, self._handle)
            except ValueError:  # not the main thread: leave signals alone
                break
        return self

    def _handle(self, signum, frame):
        if not self.requested and not self._urgent:
            self.requested = True
        elif self._deferring:
            self._pending = True
        else:
            self.requested = True
            raise KeyboardInterrupt

    @contextlib.contextmanager
    def deferred(self):
        """A block that a second signal does not cut: it is raised when the block ends."""
        self._deferring += 1
        try:
            yield
        finally:
            self._deferring -= 1
        if self._pending and not self._deferring:
            self._pending = False
            raise KeyboardInterrupt

    @contextlib.contextmanager
    def urgent(self):
        """A block that the first signal interrupts at once (a LocalCluster starting its workers,
        a wait for a scheduler's workers): KeyboardInterrupt, also when it came just before."""
        if self.requested:
            raise KeyboardInterrupt
        self._urgent += 1
        try:
            yield
        finally:
            self._urgent -= 1

    def __exit__(self, *exc):
        for s, previous in self._previous.items():
            if previous is not None:  # None: a handler installed outside Python, which cannot be restored
                signal.signal(s, previous)
        return False


@contextlib.contextmanager
def stderr_to(log: Path):
    """Send file descriptor 2 (this process and the processes it starts meanwhile) to ``log``."""
    log.parent.mkdir(parents=True, exist_ok=True)
    sys.stderr.flush()
    saved = os.dup(2)
    fd = os.open(log, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
    try:
        os.dup2(fd, 2)
        yield
    finally:
        sys.stderr.flush()
        os.dup2(saved, 2)
        os.close(saved)
        os.close(fd)


#: Seconds to wait for a running scheduler's first worker (``--worker-timeout``).
WORKER_TIMEOUT = 600.0


def check_worker_timeout(seconds, source: str) -> float:
    """``seconds`` to wait for a scheduler's first worker, in (0, 1e6] s, else a one-line ParameterError.

    >>> check_worker_timeout(30, "fogref render")
    30.0
    """
    return P.number(seconds, "--worker-timeout", source=source, lo=0.0, hi=1e6, lo_open=True, unit="s")


def _wait_for_a_worker(client, scheduler: str, timeout: float, source: str) -> None:
    """Return once ``client``'s scheduler has a worker; say that it waits (stderr) when it has none
    yet; a one-line ParameterError after ``timeout`` seconds without one."""
    try:
        client.wait_for_workers(1, timeout=0.5)
        return
    except TimeoutError:
        pass
    print(
        f"{source}: waiting for a worker to join the scheduler {scheduler} (up to {timeout:g} s, "
        "--worker-timeout)",
        file=sys.stderr,
        flush=True,
    )
    try:
        client.wait_for_workers(1, timeout=timeout)
    except TimeoutError:
        with contextlib.suppress(Exception):
            client.close(timeout=10)
        raise ParameterError(
            source,
            "--scheduler",
            f"no worker joined {scheduler} in {timeout:g} s (--worker-timeout); start workers with "
            f"'dask worker {scheduler}'",
        ) from None


def connect(
    scheduler: str | None,
    n_workers: int | None,
    log: Path,
    source: str,
    worker_timeout: float = WORKER_TIMEOUT,
):
    """A Dask client: on ``scheduler`` (an address) or on a new LocalCluster of ``n_workers``
    (default: one per core) single-threaded worker processes whose output goes to ``log``.

    Returns ``(client, cluster or None, Dr.Jit threads per worker or None)``: cores / workers
    on a LocalCluster, None (Dr.Jit's own default) on an existing cluster.  An unreachable
    scheduler, or one that has no worker after ``worker_timeout`` seconds, is a one-line
    ParameterError naming ``source``.  More workers than cores is a warning (stderr).
    """
    from dask import config as dask_config
    from dask.distributed import Client, LocalCluster

    if scheduler:
        try:
            client = Client(scheduler, timeout="30s")
        except (OSError, ValueError, TypeError) as e:
            why = str(e).splitlines()[0] if str(e) else type(e).__name__
            raise ParameterError(source, "--scheduler", f"cannot connect to {scheduler} ({why})") from None
        _wait_for_a_worker(client, scheduler, worker_timeout, source)
        return client, None, None
    cores = os.cpu_count() or 1
    n = n_workers or cores
    if n > cores:
        print(
            f"{source}: warning: --workers {n} on {cores} cores: the workers share the cores (no faster "
            f"than {cores}), and starting them takes a while",
            file=sys.stderr,
        )
    # the workers' own "Compute Failed" logs are silenced: the callers report failures themselves;
    # the workers start without the MALLOC_TRIM_THRESHOLD_ the nanny sets by default (WORKER_UNSET_ENV)
    unset = {f"distributed.nanny.pre-spawn-environ.{k}": None for k in WORKER_UNSET_ENV}
    with stderr_to(log), dask_config.set(unset):
        cluster = LocalCluster(
            n_workers=n,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.CRITICAL,
        )
    return Client(cluster), cluster, max(1, cores // n)


def main_thread() -> bool:
    """Whether this is the main thread (the only one where signal handlers can be set)."""
    return threading.current_thread() is threading.main_thread()


def stop(client, cluster, log: Path) -> None:
    """Close the client and the cluster (when it is ours: not None), their output to ``log``, a
    second Ctrl-C ignored meanwhile."""
    old = signal.signal(signal.SIGINT, signal.SIG_IGN) if main_thread() else None
    try:
        with stderr_to(log) if cluster is not None else contextlib.nullcontext():
            with contextlib.suppress(Exception):
                client.close(timeout=10)
            if cluster is not None:
                with contextlib.suppress(Exception):
                    cluster.close(timeout=10)
    finally:
        if old is not None:
            signal.signal(signal.SIGINT, old)
