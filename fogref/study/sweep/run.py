"""Running a sweep on Dask: the client, the cluster, resume, and the result files.

Engine: Dask distributed.  By default a ``LocalCluster`` of one single-threaded
worker process per core; ``--scheduler tcp://HOST:8786`` uses an existing cluster
(the same code path).  A configuration that raises is retried ``retries`` times
and, if it still fails, recorded with its error; the others carry on.  An
interrupted sweep resumes: configurations whose result file exists are not run
again (``retry_failed`` re-runs the recorded failures).
"""

from __future__ import annotations

import json
import logging
import os
import time
import traceback
from pathlib import Path

from fogref.atomic import write_text_atomic
from fogref.errors import FogrefError
from fogref.study.sweep.design import build_configs
from fogref.study.sweep.spec import load_sweep
from fogref.study.sweep.table import write_table
from fogref.study.sweep.task import run_config

__all__ = ["run_sweep"]


def _connect(scheduler: str | None, n_workers: int | None):
    """A Dask client: on ``scheduler`` (an address) or on a new LocalCluster.

    Returns ``(client, cluster or None, drjit_threads per worker or None)``.
    """
    from dask.distributed import Client, LocalCluster

    if scheduler:
        try:
            return Client(scheduler, timeout="30s"), None, None
        except OSError as e:
            raise FogrefError(f"--scheduler {scheduler}: cannot connect ({e})") from None
    cores = os.cpu_count() or 1
    n = n_workers or cores
    # the workers' own "Compute Failed" logs are silenced: failures are recorded in the table
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                           silence_logs=logging.CRITICAL)
    return Client(cluster), cluster, max(1, cores // n)


def run_sweep(sweep_path, scheduler: str | None = None, n_workers: int | None = None, progress: bool = True,
              retry_failed: bool = False, drjit_threads: int | None = None) -> dict:
    """Run a sweep; write its table, per-configuration results and plots.

    Parameters
    ----------
    sweep_path : str or Path
        The ``SWEEP.toml``.
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:8786``); ``None`` starts a
        ``LocalCluster`` of ``n_workers`` single-threaded processes (default: one
        per core) and closes it at the end.
    n_workers : int, optional
        Workers of the local cluster (ignored with ``scheduler``).
    progress : bool
        Show a tqdm progress bar over configurations.
    retry_failed : bool
        Re-run configurations whose result file records an error.
    drjit_threads : int, optional
        Dr.Jit threads per worker process (default: cores / workers for a local
        cluster, Dr.Jit's own default on an existing one).

    Returns
    -------
    dict
        ``{"table": csv path, "parquet": path, "rows": n, "configs": n, "ran": n,
        "failed": n, "wall_seconds": s, "plots": [paths]}``.
    """
    spec = load_sweep(sweep_path)
    configs = build_configs(spec)
    out = Path(spec.out)
    cdir = out / "configs"
    cdir.mkdir(parents=True, exist_ok=True)
    spec.cache.mkdir(parents=True, exist_ok=True)
    todo = []
    for cfg in configs:
        f = cdir / f"{cfg['id']}.json"
        if f.is_file():
            try:
                prev = json.loads(f.read_text())
                if prev.get("status") != "error" or not retry_failed:
                    continue
            except ValueError:
                pass
        todo.append(cfg)
    write_text_atomic(out / "sweep.json", json.dumps(
        {"sweep": str(spec.path), "name": spec.name, "design": spec.design, "parameters": spec.parameters,
         "models": spec.models, "spp": spec.spp, "seed": spec.seed, "seed_policy": spec.seed_policy,
         "configs": [{"id": c["id"], "scene": c["scene"], "values": c["values"]} for c in configs]},
        indent=2, default=str) + "\n")
    t0 = time.perf_counter()
    failed = 0
    if todo:
        from dask.distributed import as_completed
        from tqdm import tqdm

        client, cluster, threads = _connect(scheduler, n_workers)
        threads = drjit_threads or threads
        try:
            futures = {client.submit(run_config, cfg, threads, key=f"fogref-sweep-{cfg['id']}",
                                     retries=spec.retries, pure=False): cfg for cfg in todo}
            with tqdm(total=len(configs), initial=len(configs) - len(todo), unit="config",
                      disable=not progress, desc=spec.name) as bar:
                for fut in as_completed(futures):
                    cfg = futures[fut]
                    try:
                        result = {**fut.result(), "status": "ok"}
                    except Exception as e:  # the task's own error, after Dask's retries
                        failed += 1
                        tb = "".join(traceback.format_exception_only(type(e), e)).strip()
                        result = {"id": cfg["id"], "status": "error", "error": tb}
                    write_text_atomic(cdir / f"{cfg['id']}.json",
                                      json.dumps({**result, "config": cfg}, indent=1, default=str) + "\n")
                    bar.update(1)
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    wall = time.perf_counter() - t0
    info = write_table(spec, configs)
    return {**info, "configs": len(configs), "ran": len(todo), "failed": failed, "wall_seconds": wall}
