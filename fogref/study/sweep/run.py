"""Running a sweep on Dask: the client, the cluster, resume, and the result files.

Engine: Dask distributed.  By default a ``LocalCluster`` of one single-threaded
worker process per core; ``--scheduler tcp://HOST:8786`` uses an existing cluster
(the same code path).  A configuration that raises is retried ``retries`` times
and, if it still fails, recorded with its error; the others carry on.  An
interrupted sweep resumes: configurations whose result file exists are not run
again (``retry_failed`` re-runs the recorded failures; a malformed result file is
set aside with a one-line warning and run again).

Before any work, every output (table, ``sweep.json``, plots, ``configs/``, the
workers' log) is compared by resolved path with every input (the sweep file, the
scenes and the files they load): no output may replace an input.  Ctrl-C stops
the cluster and raises :class:`SweepInterrupted` (a ``KeyboardInterrupt``) whose
one line names the log file that holds the workers' output.
"""

from __future__ import annotations

import functools
import json
import os
import time
import traceback
from pathlib import Path

from tqdm import tqdm

from fogref import cluster
from fogref import params as P
from fogref.atomic import write_text_atomic
from fogref.errors import FogrefError
from fogref.study.sweep.design import build_configs, scene_input_files
from fogref.study.sweep.spec import SweepSpec, load_sweep
from fogref.study.sweep.table import plot_files, read_result, set_aside_result, write_table
from fogref.study.sweep.task import run_config

__all__ = ["WORKER_LOG", "SweepInterrupted", "run_sweep"]

#: The file in the output folder that receives the LocalCluster workers' own output (tracebacks at Ctrl-C).
WORKER_LOG = "sweep-workers.log"
_SOURCE = "fogref sweep"


class SweepInterrupted(KeyboardInterrupt):
    """Ctrl-C during a sweep: the cluster is stopped; the message names the workers' log."""


def _same(a: Path, b: Path) -> bool:
    return os.path.realpath(a) == os.path.realpath(b)


def _inside(a: Path, folder: Path) -> bool:
    return Path(os.path.realpath(a)).is_relative_to(os.path.realpath(folder))


def check_outputs(spec: SweepSpec, configs: list[dict]) -> None:
    """Refuse a sweep whose outputs would replace one of its inputs (resolved paths, symlinks followed).

    Outputs: ``sweep.json``, the table (CSV, Parquet), the plots, anything in ``configs/`` and the
    workers' log.  Inputs: the sweep file, every scene and every file each configuration's scene loads.
    """
    out = Path(spec.out)
    files = {
        out / "sweep.json": "the resolved design",
        out / f"{spec.table}.csv": "the table (CSV)",
        out / f"{spec.table}.parquet": "the table (Parquet)",
        out / WORKER_LOG: "the workers' log",
    }
    files.update({f: "a plot" for f in plot_files(spec, out / "plots")})
    inputs = {Path(spec.path): "the sweep file"}
    seen = set()
    for cfg in (c for c in configs if "scene" in c):  # a closed-form sweep has no scene
        key = (cfg["scene"], json.dumps(cfg["overrides"], sort_keys=True))
        if key in seen:
            continue
        seen.add(key)
        inputs.setdefault(Path(cfg["scene"]), "a scene")
        for f in scene_input_files(cfg["scene"], cfg["overrides"]):
            inputs.setdefault(f, f"a file {Path(cfg['scene']).name} loads")
    for i, what_in in inputs.items():
        hit = next(((o, w) for o, w in files.items() if _same(o, i)), None)
        if hit is None and _inside(i, out / "configs"):
            hit = (out / "configs", "the per-configuration results")
        if hit is not None:
            raise FogrefError(
                f"{spec.path}: output {hit[0]} ({hit[1]}) would replace the input {i} "
                f"({what_in}); choose another [sweep] out or [outputs] table"
            )


def _todo(configs: list[dict], cdir: Path, retry_failed: bool) -> list[dict]:
    """The configurations to run: no valid result yet (a malformed one is set aside), or a failure
    with ``retry_failed``."""
    todo = []
    for cfg in configs:
        f = cdir / f"{cfg['id']}.json"
        prev, why = read_result(f, cfg)
        if prev is None and why != "missing":
            set_aside_result(f, why)
        if prev is not None and (prev["status"] != "error" or not retry_failed):
            continue
        todo.append(cfg)
    return todo


def _run(client, todo, configs, spec, threads, cdir, progress) -> int:
    """Submit ``todo``, write each result as it arrives; returns the number of failures."""
    from dask.distributed import as_completed

    failed = 0
    futures = {
        client.submit(
            run_config, cfg, threads, key=f"fogref-sweep-{cfg['id']}", retries=spec.retries, pure=False
        ): cfg
        for cfg in todo
    }
    with tqdm(
        total=len(configs),
        initial=len(configs) - len(todo),
        unit="config",
        disable=not progress,
        desc=spec.name,
    ) as bar:
        for fut in as_completed(futures):
            cfg = futures[fut]
            try:
                result = {**fut.result(), "status": "ok"}
            except Exception as e:  # the task's own error, after Dask's retries
                failed += 1
                tb = "".join(traceback.format_exception_only(type(e), e)).strip()
                result = {"id": cfg["id"], "status": "error", "error": tb}
            write_text_atomic(
                cdir / f"{cfg['id']}.json",
                json.dumps({**result, "config": cfg}, indent=1, default=str) + "\n",
            )
            bar.update(1)
    return failed


def _map_on(client, f, jobs: list[tuple]) -> list:
    """``[f(*job) for job in jobs]``, computed on the Dask ``client``'s workers."""
    return client.gather(client.map(f, *zip(*jobs), pure=False)) if jobs else []


def run_sweep(
    sweep_path,
    scheduler: str | None = None,
    n_workers: int | None = None,
    progress: bool = True,
    retry_failed: bool = False,
    drjit_threads: int | None = None,
) -> dict:
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
        Workers of the local cluster, >= 1 (ignored with ``scheduler``).
    progress : bool
        Show a tqdm progress bar over configurations.
    retry_failed : bool
        Re-run configurations whose result file records an error.
    drjit_threads : int, optional
        Dr.Jit threads per worker process, >= 1 (default: cores / workers for a local
        cluster, Dr.Jit's own default on an existing one).

    Returns
    -------
    dict
        ``{"table": csv path, "parquet": path, "rows": n, "configs": n, "ran": n,
        "failed": n, "wall_seconds": s, "plots": [paths]}``; ``wall_seconds``: from the cluster's
        start to the last configuration's result (the table and plots after it not included).

    Raises
    ------
    FogrefError
        One line, before any work: a malformed sweep file (:func:`load_sweep`), an
        output that would replace an input, a bad ``scheduler`` address or worker count.
    SweepInterrupted
        On Ctrl-C, after the cluster is stopped; its message names the workers' log.
    """
    scheduler = cluster.check_scheduler(scheduler, _SOURCE)
    n_workers = cluster.check_workers(n_workers, _SOURCE)
    if drjit_threads is not None:
        drjit_threads = P.integer(drjit_threads, "--drjit-threads", source=_SOURCE, lo=1, hi=4096)
    spec = load_sweep(sweep_path)
    configs = build_configs(spec)
    check_outputs(spec, configs)
    out = Path(spec.out)
    cdir = out / "configs"
    cdir.mkdir(parents=True, exist_ok=True)
    if spec.cache is not None:
        spec.cache.mkdir(parents=True, exist_ok=True)
    todo = _todo(configs, cdir, retry_failed)
    write_text_atomic(
        out / "sweep.json",
        json.dumps(
            {
                "sweep": str(spec.path),
                "name": spec.name,
                "design": spec.design,
                "parameters": spec.parameters,
                "models": spec.models,
                "spp": spec.spp,
                "seed": spec.seed,
                "seed_policy": spec.seed_policy,
                "configs": [{"id": c["id"], "scene": c.get("scene"), "values": c["values"]} for c in configs],
            },
            indent=2,
            default=str,
        )
        + "\n",
    )
    t0 = time.perf_counter()
    failed, info = 0, None
    if todo:
        log = out / WORKER_LOG
        client = local = None
        # every Ctrl-C or SIGTERM raises at once and is remembered: one that a library swallowed
        # while the configurations ran still ends the sweep as interrupted
        with cluster.Interrupt() as stop, stop.urgent():
            try:
                client, local, threads = cluster.connect(scheduler, n_workers, log, _SOURCE)
                failed = _run(client, todo, configs, spec, drjit_threads or threads, cdir, progress)
                if stop.requested:
                    raise KeyboardInterrupt
                wall = time.perf_counter() - t0
                # the table here, its figures drawn on the workers side by side (they have matplotlib
                # loaded already); the PNGs come back and are written here
                try:
                    info = write_table(spec, configs, functools.partial(_map_on, client))
                except Exception:
                    cluster.stop(client, local, log)
                    raise
            except KeyboardInterrupt:
                if client is not None:
                    cluster.stop(client, local, log)
                done = sum(read_result(cdir / f"{c['id']}.json", c)[0] is not None for c in configs)
                where = f"; the workers' output is in {log}" if scheduler is None else ""
                raise SweepInterrupted(
                    f"fogref sweep: interrupted with {done} of {len(configs)} configurations "
                    f"done; the cluster is stopped{where}; run the same command again to resume"
                ) from None
        cluster.stop(client, local, log)
    if info is None:  # nothing ran: no cluster
        wall = time.perf_counter() - t0
        info = write_table(spec, configs)
    return {**info, "configs": len(configs), "ran": len(todo), "failed": failed, "wall_seconds": wall}
