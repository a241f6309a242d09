"""``fogref sweep SWEEP.toml``: a declarative error study over many configurations, on Dask.

A sweep is a TOML file: the scenes, the parameters to vary (any ``$default`` of
the scene, or a model parameter), the design (grid, zipped lists, seeded random or
Latin hypercube), the models to compare, the sample count and seed policy, and the
outputs.  Each *configuration* (one scene + one set of parameter values) is one
Dask task: it renders the ground truth, or reuses it from a content-addressed
cache, then runs every model against it (``compare`` with figures off) and returns
one row per model.  The rows are gathered into one tidy table (CSV + Parquet) with
plots of each metric against each swept parameter beside it.

Example ``SWEEP.toml``::

    [sweep]
    name = "unreal_sun_falloff_g"
    scenes = ["scenes/valley.xml"]     # relative to the TOML file, else to the working directory
    out = "."                          # output folder (relative to the TOML file; default: its folder)
    cache = "out/sweep_cache"          # ground-truth cache (relative to the working directory)

    [render]
    spp = 16
    seed = 0
    seed_policy = "fixed"              # or "per_config": seed derived from the config's values
    overrides = { res = 64, resy = 36 } # fixed $defaults for every configuration

    [design]
    kind = "grid"                      # "grid" | "list" | "random" | "lhs"
    # n = 48; seed = 0                 # random / lhs only

    [parameters.sun_elevation]         # a scene $default ...
    values = [2, 8, 20, 45]
    [parameters.FogHeightFalloff]      # ... under a label: falloff = 0.0693147 * value
    target = "falloff"
    scale = 0.0693147
    values = [0.1, 0.2, 0.4, 0.8]
    [parameters."ue4.start_distance"]  # a model parameter: "<model label>.<parameter>"
    range = [0, 100]                   # random / lhs: uniform in range (log = true: log-uniform)

    [[models]]
    name = "ue4"                       # a model name (built-in, "my_pkg.fog:MyFog" or an entry
                                       # point of group fogref.models); label defaults to the name
                                       # (its Class part for "module:Class")
    from_scene = true                  # parameters from the truth's physical fog, like --from-scene
    params = {}                        # then these override them

    [execution]
    retries = 1                        # Dask retries of a failing configuration

    [outputs]
    table = "results"                  # results.csv, results.parquet
    plots = true                       # plots/<metric>_vs_<parameter>.png
    plot_metrics = ["final.all.rmse", "final.all.relmse"]   # default: every final.all.* metric
    budget = false                     # true: Unreal's error budget for every "ue4" model (one extra
                                       # render per configuration: the scene without its sun)

Output folder::

    results.csv, results.parquet   one row per configuration x model
    configs/<config id>.json       one result per configuration (written atomically; resume reads them)
    plots/*.png                    each plotted metric against each swept parameter
    sweep.json                     the resolved design and the command

Engine: Dask distributed.  By default a ``LocalCluster`` of one single-threaded
worker process per core; ``--scheduler tcp://HOST:8786`` uses an existing cluster
(the same code path).  Each worker process imports Mitsuba and sets its variant
once (:func:`_worker_setup`) and keeps Dr.Jit's compiled kernels across its tasks.
A configuration that raises is retried ``retries`` times and, if it still fails,
recorded with its error (rows with ``status = "error"``); the others carry on.
An interrupted sweep resumes: configurations whose result file exists are not
run again (``--retry-failed`` re-runs the recorded failures).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import itertools
import json
import logging
import math
import os
import socket
import tempfile
import time
import traceback
import xml.etree.ElementTree as ET
from pathlib import Path

from fogref.atomic import save_figure_atomic, write_text_atomic
from fogref.errors import FogrefError

try:
    import tomllib  # Python >= 3.11
except ImportError:  # pragma: no cover
    import tomli as tomllib  # type: ignore[no-redef]

__all__ = ["SweepSpec", "design_points", "load_sweep", "run_config", "run_sweep"]

DESIGN_KINDS = ("grid", "list", "random", "lhs")
SEED_POLICIES = ("fixed", "per_config")
_TOP_KEYS = {"sweep", "render", "design", "parameters", "models", "execution", "outputs"}


# ---------------------------------------------------------------- adapters (one line to fix on a rename)


def _render_cached(scene, cache: Path, *, spp, seed, overrides, pixel_filter) -> tuple[Path, bool]:
    """fogref's one render cache (:func:`fogref.render.cache.render_cached`): ``(path, was_cached)``."""
    from fogref.render.cache import render_cached

    return render_cached(scene, spp, seed, overrides, cache_dir=cache, pixel_filter=pixel_filter)


def _truth_path(scene, cache: Path, *, spp, seed, overrides, pixel_filter) -> Path:
    """Where the render cache keeps (or will keep) this truth."""
    from fogref.render.cache import truth_path

    return truth_path(scene, spp, seed, overrides, cache_dir=cache, pixel_filter=pixel_filter)


def _build_model(name: str, params: dict, scene_params: dict | None):
    """A model by name (built-in, ``module:Class`` or entry point), from the truth's physical
    parameters (``scene_params``) + ``params`` (:func:`fogref.mapping.build.build_model`)."""
    from fogref.mapping.build import build_model

    return build_model(name, params, scene_params)


def _check_model_name(name: str) -> None:
    from fogref.models.resolve import resolve_model

    resolve_model(name)


def _compare(exr, model, out_dir) -> dict:
    """``fogref.compare.compare`` with figures off; returns its report dict."""
    from fogref.compare import compare

    return compare(exr, model, out_dir, figures=False)


def _truth_header(exr) -> dict:
    """Header attributes of a ground-truth EXR."""
    from fogref.exrio import read_exr

    return read_exr(exr)[1]


# ---------------------------------------------------------------- the spec


class SweepSpec:
    """A validated sweep: what :func:`load_sweep` returns.

    Attributes
    ----------
    path : Path
        The TOML file.
    name : str
        The sweep's name.
    scenes : list of Path
        Scene files.
    out, cache : Path
        Output folder and ground-truth cache folder.
    spp, seed : int
        Samples per pixel; base seed.
    seed_policy : str
        ``"fixed"`` or ``"per_config"``.
    pixel_filter : str
        Passed to the render driver.
    overrides : dict
        Fixed scene ``$defaults`` (strings).
    parameters : dict
        label -> parameter spec (``target``, ``kind`` ``scene``/``model``, ``model``,
        ``scale``, ``values`` or ``range``/``log``/``num``).
    design : dict
        ``kind``, ``n``, ``seed``.
    models : list of dict
        ``name``, ``label``, ``from_scene``, ``params``.
    retries : int
        Dask retries per configuration.
    table : str
        Table base name.  plots : bool.  plot_metrics : list of str or None.
    """

    def __init__(self, **kw):
        self.__dict__.update(kw)


def _err(path, key, msg) -> FogrefError:
    return FogrefError(f"{path}: [{key}]: {msg}" if key else f"{path}: {msg}")


def _scene_defaults(scene: Path) -> dict:
    try:
        root = ET.parse(scene).getroot()
    except ET.ParseError as e:
        raise FogrefError(f"{scene}: malformed XML ({e})") from None
    return {d.get("name"): d.get("value") for d in root.iter("default")}


def _as_str(v) -> str:
    """A TOML value as an XML ``$default`` string (lists -> ``"a, b, c"``)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (list, tuple)):
        return ", ".join(_as_str(x) for x in v)
    if isinstance(v, float):
        return repr(v)
    return str(v)


def _resolve(base: Path, p: str) -> Path:
    q = Path(p)
    if q.is_absolute():
        return q
    return base / q if (base / q).exists() else q


def _number(path, key, v, what):
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise _err(path, key, f"{what} must be a finite number, got {v!r}")
    return float(v)


def load_sweep(path) -> SweepSpec:
    """Read and validate a sweep TOML file.

    Parameters
    ----------
    path : str or Path
        The ``SWEEP.toml`` (schema in the module docstring).

    Returns
    -------
    SweepSpec

    Raises
    ------
    FogrefError
        Naming the file, the key and the allowed values for anything malformed: an
        unknown table or key, a scene that does not exist, a parameter that is not a
        ``$default`` of every scene (the message lists them) or not ``<model>.<name>``
        of a listed model, an unknown design kind or seed policy, an unknown model name.
    """
    path = Path(path)
    if not path.is_file():
        raise FogrefError(f"{path}: no such sweep file")
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as e:
        raise FogrefError(f"{path}: not valid TOML ({e})") from None
    unknown = set(doc) - _TOP_KEYS
    if unknown:
        raise _err(path, None, f"unknown table(s) {sorted(unknown)}; allowed: {sorted(_TOP_KEYS)}")
    base = path.parent

    def table(name, allowed):
        t = doc.get(name, {})
        if not isinstance(t, dict):
            raise _err(path, name, "must be a table")
        bad = set(t) - set(allowed)
        if bad:
            raise _err(path, name, f"unknown key(s) {sorted(bad)}; allowed: {sorted(allowed)}")
        return t

    sw = table("sweep", ("name", "scenes", "out", "cache"))
    scenes = sw.get("scenes")
    if isinstance(scenes, str):
        scenes = [scenes]
    if not scenes or not all(isinstance(s, str) for s in scenes):
        raise _err(path, "sweep", "'scenes' must be a non-empty list of scene file paths")
    scene_paths = []
    for s in scenes:
        p = _resolve(base, s)
        if not p.is_file():
            raise _err(path, "sweep", f"scene '{s}' not found (relative to {base} or the working directory)")
        scene_paths.append(p)
    out = base / sw["out"] if "out" in sw and not Path(sw["out"]).is_absolute() else Path(sw.get("out", base))
    cache = Path(sw.get("cache", "out/sweep_cache"))

    rd = table("render", ("spp", "seed", "seed_policy", "overrides", "pixel_filter"))
    spp, seed = rd.get("spp", 16), rd.get("seed", 0)
    if not isinstance(spp, int) or isinstance(spp, bool) or not 1 <= spp <= 1 << 20:
        raise _err(path, "render", f"spp must be an integer in [1, 1048576], got {spp!r}")
    if not isinstance(seed, int) or isinstance(seed, bool) or not 0 <= seed < 1 << 31:
        raise _err(path, "render", f"seed must be an integer in [0, 2^31), got {seed!r}")
    policy = rd.get("seed_policy", "fixed")
    if policy not in SEED_POLICIES:
        raise _err(path, "render", f"seed_policy '{policy}' unknown; allowed: {list(SEED_POLICIES)}")
    overrides = rd.get("overrides", {})
    if not isinstance(overrides, dict):
        raise _err(path, "render", "overrides must be a table of $default = value")
    overrides = {k: _as_str(v) for k, v in overrides.items()}

    models = doc.get("models", [])
    if not isinstance(models, list) or not models:
        raise _err(path, "models", "need at least one [[models]] entry with a 'name'")
    mspecs, labels = [], set()
    for i, m in enumerate(models):
        key = f"models][{i}"
        if not isinstance(m, dict) or "name" not in m:
            raise _err(path, key, "each [[models]] entry needs a 'name' (a model: \"ue4\", \"my_pkg.fog:MyFog\", ...)")
        bad = set(m) - {"name", "label", "from_scene", "params"}
        if bad:
            raise _err(path, key, f"unknown key(s) {sorted(bad)}; allowed: ['from_scene', 'label', 'name', 'params']")
        try:
            _check_model_name(m["name"])
        except FogrefError as e:
            raise _err(path, key, str(e)) from None
        # "my_pkg.fog:MyFog" is labelled "MyFog" (a label has no '.')
        label = str(m.get("label", str(m["name"]).rpartition(":")[2]))
        if label in labels or "." in label:
            raise _err(path, key, f"model label '{label}' must be unique and contain no '.'")
        labels.add(label)
        params = m.get("params", {})
        if not isinstance(params, dict):
            raise _err(path, key, "params must be a table")
        mspecs.append({"name": m["name"], "label": label, "from_scene": bool(m.get("from_scene", True)),
                       "params": params})

    dz = table("design", ("kind", "n", "seed"))
    kind = dz.get("kind", "grid")
    if kind not in DESIGN_KINDS:
        raise _err(path, "design", f"kind '{kind}' unknown; allowed: {list(DESIGN_KINDS)}")
    n = dz.get("n")
    if kind in ("random", "lhs") and (not isinstance(n, int) or n < 1):
        raise _err(path, "design", f"kind '{kind}' needs n = a positive integer (number of configurations)")
    design = {"kind": kind, "n": n, "seed": int(dz.get("seed", 0))}

    params = doc.get("parameters", {})
    if not isinstance(params, dict):
        raise _err(path, "parameters", "must be a table of [parameters.NAME] tables")
    scene_defaults = [_scene_defaults(p) for p in scene_paths]
    common = set.intersection(*(set(d) for d in scene_defaults)) if scene_defaults else set()
    pspecs = {}
    for label, spec in params.items():
        key = f"parameters.{label}"
        if not isinstance(spec, dict):
            raise _err(path, key, "must be a table with 'values' or 'range'")
        bad = set(spec) - {"values", "range", "log", "num", "target", "scale"}
        if bad:
            raise _err(path, key, f"unknown key(s) {sorted(bad)}; allowed: "
                       "['log', 'num', 'range', 'scale', 'target', 'values']")
        target = str(spec.get("target", label))
        if "." in target:
            mlabel, mparam = target.split(".", 1)
            if mlabel not in labels:
                raise _err(path, key, f"'{target}': model label '{mlabel}' is not a [[models]] label; "
                           f"allowed: {sorted(labels)}")
            ps = {"kind": "model", "model": mlabel, "target": mparam}
        else:
            if target not in common:
                raise _err(path, key, f"'{target}' is not a $default of every scene; allowed: {sorted(common)}")
            ps = {"kind": "scene", "target": target}
        ps["scale"] = _number(path, key, spec.get("scale", 1.0), "scale")
        if "values" in spec:
            vals = spec["values"]
            if not isinstance(vals, list) or not vals:
                raise _err(path, key, "values must be a non-empty list")
            ps["values"] = vals
        elif "range" in spec:
            r = spec["range"]
            if not (isinstance(r, list) and len(r) == 2):
                raise _err(path, key, f"range must be [low, high], got {r!r}")
            lo, hi = (_number(path, key, x, "range bounds") for x in r)
            if not lo < hi or (spec.get("log") and lo <= 0):
                raise _err(path, key, f"range [{lo}, {hi}] needs low < high (and low > 0 with log = true)")
            ps["range"], ps["log"] = [lo, hi], bool(spec.get("log", False))
            if kind in ("grid", "list"):
                num = spec.get("num")
                if not isinstance(num, int) or num < 1:
                    raise _err(path, key, f"a range in a '{kind}' design needs num = number of points")
                ps["values"] = _spaced(lo, hi, num, ps["log"])
        else:
            raise _err(path, key, "give 'values' (a list) or 'range' ([low, high])")
        if ps["scale"] != 1.0:
            for v in ps.get("values", []):
                _number(path, key, v, "a scaled value")
        pspecs[label] = ps
    if kind == "list":
        lens = {len(p["values"]) for p in pspecs.values()}
        if len(lens) > 1:
            raise _err(path, "design", f"kind 'list' zips the parameters' values: their lengths differ ({sorted(lens)})")

    ex = table("execution", ("retries",))
    retries = ex.get("retries", 1)
    if not isinstance(retries, int) or retries < 0:
        raise _err(path, "execution", f"retries must be an integer >= 0, got {retries!r}")
    ou = table("outputs", ("table", "plots", "plot_metrics", "budget"))
    return SweepSpec(path=path, name=str(sw.get("name", path.stem)), scenes=scene_paths, out=out, cache=cache,
                     spp=spp, seed=seed, seed_policy=policy, pixel_filter=str(rd.get("pixel_filter", "centre")),
                     overrides=overrides, parameters=pspecs, design=design, models=mspecs, retries=retries,
                     table=str(ou.get("table", "results")), plots=bool(ou.get("plots", True)),
                     plot_metrics=ou.get("plot_metrics"), budget=bool(ou.get("budget", False)))


def _spaced(lo, hi, num, log):
    import numpy as np

    v = np.geomspace(lo, hi, num) if log else np.linspace(lo, hi, num)
    return [float(x) for x in v]


# ---------------------------------------------------------------- the design


def design_points(spec: SweepSpec) -> list[dict]:
    """The parameter values of every configuration (one dict label -> value each).

    ``grid``: the Cartesian product of the parameters' values (the first parameter
    varies slowest); ``list``: the values zipped; ``random``: ``n`` points, uniform
    (log-uniform with ``log = true``) in each ``range`` or uniform over ``values``;
    ``lhs``: ``n`` points of a Latin hypercube (``scipy.stats.qmc.LatinHypercube``,
    seeded by ``design.seed``) mapped the same way.  No parameters: one point ``{}``.
    """
    import numpy as np

    ps = spec.parameters
    labels = list(ps)
    if not labels:
        return [{}]
    kind = spec.design["kind"]
    if kind == "grid":
        return [dict(zip(labels, combo)) for combo in itertools.product(*(ps[k]["values"] for k in labels))]
    if kind == "list":
        return [dict(zip(labels, combo)) for combo in zip(*(ps[k]["values"] for k in labels))]
    n = spec.design["n"]
    if kind == "random":
        u = np.random.default_rng(spec.design["seed"]).random((n, len(labels)))
    else:
        from scipy.stats import qmc

        u = qmc.LatinHypercube(d=len(labels), seed=spec.design["seed"]).random(n)
    points = []
    for row in u:
        pt = {}
        for k, x in zip(labels, row):
            p = ps[k]
            if "range" in p:
                lo, hi = p["range"]
                pt[k] = float(math.exp(math.log(lo) + x * (math.log(hi) - math.log(lo))) if p["log"]
                              else lo + x * (hi - lo))
            else:
                pt[k] = p["values"][min(int(x * len(p["values"])), len(p["values"]) - 1)]
        points.append(pt)
    return points


def _hash(obj, n=16) -> str:
    return hashlib.sha256(json.dumps(obj, sort_keys=True, default=str).encode()).hexdigest()[:n]


def _file_sha256(path) -> str:
    """The SHA-256 the render driver records for scene files (one definition)."""
    from fogref.render.render import file_sha256

    return file_sha256(path)


def build_configs(spec: SweepSpec) -> list[dict]:
    """Every configuration as a self-contained, JSON-ready task description.

    Each holds ``id`` (a hash of everything the task does), the scene path and its
    content hash, the swept ``values``, the scene ``overrides`` (fixed + swept,
    strings), the models with their parameters, spp, seed and the truth's cache path.
    """
    import fogref

    out = []
    for scene in spec.scenes:
        scene_sha = _file_sha256(scene)
        for pt in design_points(spec):
            overrides = dict(spec.overrides)
            model_params = {m["label"]: dict(m["params"]) for m in spec.models}
            for label, v in pt.items():
                p = spec.parameters[label]
                value = v * p["scale"] if p["scale"] != 1.0 else v
                if p["kind"] == "scene":
                    overrides[p["target"]] = _as_str(value)
                else:
                    model_params[p["model"]][p["target"]] = value
            seed = spec.seed if spec.seed_policy == "fixed" else int(
                _hash({"seed": spec.seed, "scene": scene_sha, "overrides": overrides}, 8), 16) & 0x7FFFFFFF
            truth = _truth_path(scene, spec.cache, spp=spec.spp, seed=seed, overrides=overrides,
                                pixel_filter=spec.pixel_filter)
            models = [{**m, "params": model_params[m["label"]]} for m in spec.models]
            cfg = {"scene": str(scene), "scene_sha256": scene_sha, "values": pt, "overrides": overrides,
                   "models": models, "spp": spec.spp, "seed": seed, "pixel_filter": spec.pixel_filter,
                   "truth": str(truth), "budget": bool(getattr(spec, "budget", False))}
            cfg["id"] = _hash({k: cfg[k] for k in ("scene_sha256", "overrides", "models", "spp", "seed",
                                                   "pixel_filter")} | {"fogref": fogref.__version__}
                            | ({"budget": True} if cfg["budget"] else {}))
            out.append(cfg)
    return out


# ---------------------------------------------------------------- the task (runs on a worker)


@functools.lru_cache(maxsize=None)
def _worker_setup(drjit_threads: int | None = None) -> dict:
    """Once per worker process: import fogref, set the Mitsuba variant, size Dr.Jit's pool.

    Cached, so every later task in the same process reuses Mitsuba and Dr.Jit's
    compiled kernels.  Returns the process's versions.
    """
    import fogref

    variant = fogref.set_variant(None)
    import drjit as dr
    import mitsuba as mi

    if drjit_threads:
        dr.set_thread_count(int(drjit_threads))
    return {"fogref_version": fogref.__version__, "mitsuba_version": mi.__version__, "variant": variant,
            "pid": os.getpid(), "host": socket.gethostname()}


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
    """Run one configuration: render (or reuse) its truth, compare every model.

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
    env = _worker_setup(drjit_threads)
    truth = Path(cfg["truth"])
    t0 = time.perf_counter()
    with _truth_lock(f"fogref-truth-{truth.stem}"):  # configurations sharing a truth render it once
        truth, cached = _render_cached(cfg["scene"], truth.parent, spp=cfg["spp"], seed=cfg["seed"],
                                       overrides=cfg["overrides"], pixel_filter=cfg["pixel_filter"])
    wall_render = time.perf_counter() - t0
    header = _truth_header(truth)
    rs = header.get("fogref.render_seconds")
    render_seconds = float(rs.get("total", wall_render)) if isinstance(rs, dict) else float(rs or wall_render)
    prov = {"truth_path": str(truth), "truth_sha256": _file_sha256(truth), "truth_cached": cached,
            "render_seconds": render_seconds, "worker_host": env["host"], "worker_pid": env["pid"],
            "fogref_version": env["fogref_version"], "mitsuba_version": env["mitsuba_version"],
            "variant": header.get("fogref.variant", env["variant"])}
    scene_params = header.get("fogref.params")
    rows = []
    with tempfile.TemporaryDirectory(prefix="fogref-sweep-") as tmp:
        for m in cfg["models"]:
            tc = time.perf_counter()
            model = _build_model(m["name"], m["params"], scene_params if m["from_scene"] else None)
            report = _compare(truth, model, Path(tmp) / m["label"])
            row = {"model": m["label"], "model_name": m["name"],
                   "model_parameters": json.dumps(report.get("model", {}).get("parameters"), sort_keys=True,
                                                  default=str),
                   "compare_seconds": time.perf_counter() - tc}
            metrics: dict = {}
            _flatten("", report.get("metrics", {}), metrics)
            row.update(metrics)
            if cfg.get("budget") and m["name"] == "ue4":
                row.update(_budget_columns(cfg, truth, model))
            rows.append(row)
    return {"id": cfg["id"], "provenance": prov, "rows": rows}


def _budget_columns(cfg: dict, truth_path: Path, model) -> dict:
    """Unreal's error budget (:mod:`fogref.study.budget`) of one configuration as table columns.

    Renders (or takes from the cache) the scene without its sun at the truth's spp,
    seed and overrides, fits the cosine lobe like ``fogref study``, builds the chain
    ``S_0 .. S_9`` against ``model``'s parameters and returns, per step,
    ``budget.<step>.share`` (of the total squared error; they sum to 1),
    ``budget.<step>.rmse`` and its ``rmse_stderr`` (from the truths' stderr channels),
    plus ``budget.total.rmse``.  The second-seed noise of ``fogref study`` is not
    computed (it would double the renders).
    """
    from fogref.gbuffer import load_truth
    from fogref.mapping import PhysicalScene, fit_unreal
    from fogref.study import budget as B
    from fogref.study.unreal import overrides_used_by, sunless_scene

    nosun = sunless_scene(Path(cfg["scene"]), truth_path.parent / "scenes" / cfg["scene_sha256"][:16])
    sky_key = _file_sha256(nosun)[:24]
    with _truth_lock(f"fogref-truth-{sky_key}"):
        sky_path, _ = _render_cached(nosun, truth_path.parent, spp=cfg["spp"], seed=cfg["seed"],
                                     overrides=overrides_used_by(nosun, cfg["overrides"]),
                                     pixel_filter=cfg["pixel_filter"])
    truth, sky = load_truth(truth_path), load_truth(sky_path)
    pf = PhysicalScene.from_params(truth.params)
    lobe = fit_unreal(pf, sun_attenuation=False, fit_start=False)
    S = B.chain(truth, sky.single, pf, lobe.params, model.params)
    res = B.attribute(S, truth.hit, truth.surface_valid,
                      B.chain_noise(truth, sky.stderr["single"], lobe.params, model.params))
    cols = {"budget.total.rmse": res["total"]["rmse"]["all"], "budget.sky_only_truth": str(sky_path)}
    for st in res["steps"]:
        cols[f"budget.{st['key']}.share"] = st["share"]
        cols[f"budget.{st['key']}.rmse"] = st["rmse"]["all"]
        for k in ("rmse_stderr", "rmse_debiased"):
            if k in st:
                cols[f"budget.{st['key']}.{k}"] = st[k]
    return cols


# ---------------------------------------------------------------- the client


def _rows_of(cfg: dict, result: dict) -> list[dict]:
    """Table rows of one configuration's result file."""
    base = {"config_id": cfg["id"], "scene": Path(cfg["scene"]).name, "scene_path": cfg["scene"],
            "scene_sha256": cfg["scene_sha256"], **{k: v for k, v in cfg["values"].items()},
            "overrides": json.dumps(cfg["overrides"], sort_keys=True), "spp": cfg["spp"], "seed": cfg["seed"]}
    for k, v in list(base.items()):
        if isinstance(v, (list, dict)):
            base[k] = json.dumps(v)
    if result.get("status") == "error":
        return [{**base, "model": m["label"], "model_name": m["name"], "status": "error",
                 "error": result["error"], "truth_path": cfg["truth"]} for m in cfg["models"]]
    return [{**base, **result["provenance"], "status": "ok", "error": "", **row} for row in result["rows"]]


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
            with tqdm(total=len(configs), initial=len(configs) - len(todo), unit="config", disable=not progress,
                      desc=spec.name) as bar:
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


def write_table(spec: SweepSpec, configs: list[dict]) -> dict:
    """Gather the per-configuration result files into the CSV + Parquet table and the plots."""
    import pandas as pd

    out = Path(spec.out)
    rows = []
    for cfg in configs:
        f = out / "configs" / f"{cfg['id']}.json"
        if f.is_file():
            rows.extend(_rows_of(cfg, json.loads(f.read_text())))
    df = pd.DataFrame(rows)
    csv, pq = out / f"{spec.table}.csv", out / f"{spec.table}.parquet"
    write_text_atomic(csv, df.to_csv(index=False))
    from fogref.atomic import atomic_write

    atomic_write(pq, lambda tmp: df.to_parquet(tmp, index=False))
    plots = plot_table(df, spec, out / "plots") if spec.plots and len(df) else []
    return {"table": csv, "parquet": pq, "rows": len(df), "plots": plots}


def _noise_column(df, metric: str) -> str | None:
    for suffix in ("_noise", "_stderr", ".noise", ".stderr", "_mc_noise"):
        if metric + suffix in df.columns:
            return metric + suffix
    return None


def plot_table(df, spec: SweepSpec, plot_dir: Path) -> list[Path]:
    """One figure per (metric, swept parameter): every configuration as a point, the
    mean over the other parameters as a line, one colour per model; error bars from
    the metric's Monte Carlo noise column when the table has one.  Returns the paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = df[df["status"] == "ok"] if "status" in df.columns else df
    if ok.empty:
        return []
    default = ("final.all.rmse", "final.all.rmse_debiased", "final.all.relmse", "final.all.delta_e2000_mean", "final.all.flip_mean",
               "inscatter.all.rmse", "transmittance.all.rmse")
    metrics = [m for m in (spec.plot_metrics or default) if m in ok.columns]
    paths = []
    for param in spec.parameters:
        if param not in ok.columns:
            continue
        numeric = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in ok[param])
        for metric in metrics:
            fig, ax = plt.subplots(figsize=(5.2, 3.6))
            for model, g in ok.groupby("model"):
                x = g[param] if numeric else g[param].astype(str)
                noise = _noise_column(ok, metric)
                if noise:
                    ax.errorbar(x, g[metric], yerr=2 * g[noise], fmt="o", ms=3, alpha=0.4, capsize=2)
                else:
                    ax.plot(x, g[metric], "o", ms=3, alpha=0.4)
                mean = g.groupby(param)[metric].mean()
                ax.plot(mean.index if numeric else mean.index.astype(str), mean.values, "-", lw=1.8,
                        label=f"{model} (mean over other parameters)")
            ax.set_xlabel(param)
            ax.set_ylabel(metric)
            if (ok[metric] > 0).all() and ok[metric].max() > 20 * ok[metric].min():
                ax.set_yscale("log")
            ax.legend(fontsize=7)
            ax.set_title(f"{spec.name}: {metric} vs {param}", fontsize=9)
            paths.append(save_figure_atomic(fig, plot_dir / f"{metric}_vs_{param}.png"))
            plt.close(fig)
    return paths
