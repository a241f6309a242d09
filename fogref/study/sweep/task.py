"""The sweep's task: one configuration on a Dask worker (render or reuse its truth, compare every model).

:func:`run_config` runs in a worker process: it sets Mitsuba up once per process
(:func:`_worker_setup`, so Dr.Jit's compiled kernels are kept across tasks),
renders the configuration's ground truth through fogref's render cache under a
cluster-wide lock (configurations sharing a truth render it once), compares every
model (:func:`~fogref.compare.report.compare_metrics`: the metrics, no report files) and
returns one row of flattened metrics per model.
"""

from __future__ import annotations

import contextlib
import functools
import json
import os
import socket
import time
from pathlib import Path

from fogref._version import __version__
from fogref.compare.report import compare_metrics
from fogref.mapping import PhysicalScene, fit_unreal
from fogref.mapping.build import build_model
from fogref.render.cache import render_cached
from fogref.render.variant import set_variant
from fogref.scene.defaults import overrides_used_by
from fogref.scene.edit import sunless_scene
from fogref.scene.inputs import file_sha256
from fogref.study import budget as B
from fogref.study.ue_pathtracer import closed_form_row

__all__ = ["run_config"]


@functools.lru_cache(maxsize=None)
def _worker_setup(drjit_threads: int | None = None) -> dict:
    """Once per worker process: import fogref, set the Mitsuba variant, size Dr.Jit's pool.

    Cached, so every later task in the same process reuses Mitsuba and Dr.Jit's
    compiled kernels.  Returns the process's versions.
    """
    variant = set_variant(None)
    import drjit as dr
    import mitsuba as mi

    if drjit_threads:
        dr.set_thread_count(int(drjit_threads))
    return {
        "fogref_version": __version__,
        "mitsuba_version": mi.__version__,
        "variant": variant,
        "pid": os.getpid(),
        "host": socket.gethostname(),
    }


def _truth_lock(name: str):
    """A cluster-wide lock (``distributed.Lock``) inside a Dask worker; no lock elsewhere."""
    try:
        from distributed import Lock, get_worker

        get_worker()
        return Lock(name)
    except (ImportError, ValueError):
        return contextlib.nullcontext()


def _flatten(prefix: str, obj, out: dict) -> None:
    if isinstance(obj, dict):
        for k, v in obj.items():
            _flatten(f"{prefix}.{k}" if prefix else str(k), v, out)
    elif isinstance(obj, (int, float)) and not isinstance(obj, bool):
        out[prefix] = float(obj)


def run_config(cfg: dict, drjit_threads: int | None = None) -> dict:
    """Run one configuration: render (or reuse) its truth, compare every model (closed form: one row).

    Parameters
    ----------
    cfg : dict
        One entry of :func:`build_configs`.
    drjit_threads : int, optional
        Dr.Jit worker threads of this process (set once per process).

    Returns
    -------
    dict
        ``{"id", "provenance": {...}, "rows": [one dict per model]}``; each row holds
        the model's label, name and parameters (JSON) and every metric of the
        comparison report flattened to ``<part>.<region>.<metric>`` (with the
        Monte Carlo noise entries that ``compare`` reports beside them).

    Raises
    ------
    Exception
        Whatever the render or a comparison raises (Dask retries the task, then the
        client records the error).
    """
    if "closed_form" in cfg:  # nothing to render
        row = {"model": "ue_pathtracer", **closed_form_row(cfg["settings"], cfg["closed_form"])}
        return {"id": cfg["id"], "provenance": {"fogref_version": __version__}, "rows": [row]}
    env = _worker_setup(drjit_threads)
    truth = Path(cfg["truth"])
    t0 = time.perf_counter()
    with _truth_lock(f"fogref-truth-{truth.stem}"):  # configurations sharing a truth render it once
        truth_data, cached = render_cached(
            cfg["scene"],
            cfg["spp"],
            cfg["seed"],
            cfg["overrides"],
            cache_dir=truth.parent,
            pixel_filter=cfg["pixel_filter"],
        )
    wall_render = time.perf_counter() - t0
    truth = Path(truth_data.path)  # read once: its header here, its pixels for every model's compare
    header = truth_data.attrs
    rs = header.get("fogref.render_seconds")
    render_seconds = float(rs.get("total", wall_render)) if isinstance(rs, dict) else float(rs or wall_render)
    prov = {
        "truth_path": str(truth),
        "truth_sha256": file_sha256(truth),
        "truth_cached": cached,
        "render_seconds": render_seconds,
        "worker_host": env["host"],
        "worker_pid": env["pid"],
        "fogref_version": env["fogref_version"],
        "mitsuba_version": env["mitsuba_version"],
        "variant": header.get("fogref.variant", env["variant"]),
    }
    scene_params = header.get("fogref.params")
    rows = []
    for m in cfg["models"]:
        tc = time.perf_counter()
        model = build_model(m["name"], m["params"], scene_params if m["from_scene"] else None)
        # compare's metrics (its report files are not kept), the perceptual ones unless left out
        report = compare_metrics(truth_data, model, perceptual=cfg.get("perceptual", True))
        row = {
            "model": m["label"],
            "model_name": m["name"],
            "model_parameters": json.dumps(
                report.get("model", {}).get("parameters"), sort_keys=True, default=str
            ),
            "compare_seconds": time.perf_counter() - tc,
        }
        metrics: dict = {}
        _flatten("", report.get("metrics", {}), metrics)
        row.update(metrics)
        if cfg.get("budget") and m["name"] == "ue4":
            row.update(_budget_columns(cfg, truth_data, model))
        rows.append(row)
    return {"id": cfg["id"], "provenance": prov, "rows": rows}


def _budget_columns(cfg: dict, truth, model) -> dict:
    """Unreal's error budget (:mod:`fogref.study.budget`) of one configuration as table columns.

    Renders (or takes from the cache) the scene without its sun at the truth's spp,
    seed and overrides, fits the cosine lobe like ``fogref study``, builds the chain
    ``S_0 .. S_9`` against ``model``'s parameters and returns, per step,
    ``budget.<step>.share`` (of the total squared error; they sum to 1),
    ``budget.<step>.rmse`` and its ``rmse_stderr`` (from the truths' stderr channels),
    plus ``budget.total.rmse``.  The second-seed noise of ``fogref study`` is not
    computed (it would double the renders).
    """
    truth_path = Path(truth.path)
    nosun = sunless_scene(Path(cfg["scene"]), truth_path.parent / "scenes" / cfg["scene_sha256"][:16])
    sky_key = file_sha256(nosun)[:24]
    with _truth_lock(f"fogref-truth-{sky_key}"):
        sky_overrides = overrides_used_by(nosun, cfg["overrides"])
        sky, _ = render_cached(
            nosun,
            cfg["spp"],
            cfg["seed"],
            sky_overrides,
            cache_dir=truth_path.parent,
            pixel_filter=cfg["pixel_filter"],
        )
    pf = PhysicalScene.from_params(truth.params)
    lobe = fit_unreal(pf, sun_attenuation=False, fit_start=False)
    S = B.chain(truth, sky.single, pf, lobe.params, model.params)
    res = B.attribute(
        S,
        truth.hit,
        truth.surface_valid,
        B.chain_noise(truth, sky.stderr["single"], lobe.params, model.params),
    )
    cols = {"budget.total.rmse": res["total"]["rmse"]["all"], "budget.sky_only_truth": str(sky.path)}
    for st in res["steps"]:
        cols[f"budget.{st['key']}.share"] = st["share"]
        cols[f"budget.{st['key']}.rmse"] = st["rmse"]["all"]
        for k in ("rmse_stderr", "rmse_debiased"):
            if k in st:
                cols[f"budget.{st['key']}.{k}"] = st[k]
    return cols
