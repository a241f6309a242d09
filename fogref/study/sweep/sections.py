"""The readers of a sweep file's tables other than ``[parameters.*]``: ``[sweep]``,
``[render]``, ``[[models]]``, ``[design]``, ``[execution]`` and ``[outputs]``, and those of the
closed-form kind (``[sweep] kind = "ue_pathtracer"``): ``[fixed]``, ``[sun]`` and ``[views]``.

Each takes the file's path and the parsed TOML and returns the validated fields of
:class:`~fogref.study.sweep.spec.SweepSpec` it holds; the schema is in
:mod:`fogref.study.sweep`'s docstring.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from fogref import params as P
from fogref.errors import FogrefError, ParameterError, did_you_mean
from fogref.mapping.unreal_pathtracer import UEPathTracerSettings, settings_from
from fogref.models.resolve import resolve_model
from fogref.models.ue4 import UE4FogParams
from fogref.render.render import PIXEL_FILTERS
from fogref.study.plot_units import is_perceptual
from fogref.study.sweep.values import as_str, toml_bool, toml_error, toml_int, toml_num, toml_src, toml_table

DESIGN_KINDS = ("grid", "list", "random", "lhs")
#: The editor values (name -> default) of a ``ue_pathtracer`` sweep's one "model": the fields
#: of :class:`~fogref.models.ue4.UE4FogParams` and ``fogref.mapping.unreal_pathtracer.UEPathTracerSettings``.
UE_PATHTRACER_FIELDS = {
    f.name: f.default for c in (UE4FogParams, UEPathTracerSettings) for f in dataclasses.fields(c) if f.init
}
SEED_POLICIES = ("fixed", "per_config")


_MODEL_KEYS = ("from_scene", "label", "name", "params")
#: The most configurations a sweep may have unless its ``[design] max_configs`` says more.
MAX_CONFIGS = 100_000


def _resolve(base: Path, p: str) -> Path:
    q = Path(p)
    if q.is_absolute():
        return q
    return base / q if (base / q).exists() else q


def read_sweep(path: Path, doc: dict) -> dict:
    """``[sweep]``: name, scene paths (relative to the TOML file, else the working directory), out, cache."""
    base = path.parent
    sw = toml_table(path, doc, "sweep", ("name", "kind", "scenes", "out", "cache"))
    scenes = sw.get("scenes")
    if isinstance(scenes, str):
        scenes = [scenes]
    if not scenes or not all(isinstance(s, str) for s in scenes):
        raise toml_error(path, "sweep", "'scenes' must be a non-empty list of scene file paths")
    scene_paths = []
    for s in scenes:
        p = _resolve(base, s)
        if not p.is_file():
            raise toml_error(
                path, "sweep", f"scene '{s}' not found (relative to {base} or the working directory)"
            )
        if any(p.resolve() == q.resolve() for q in scene_paths):
            raise ParameterError(toml_src(path, "sweep"), "scenes", f"'{s}' is listed twice")
        scene_paths.append(p)
    return {
        **_name_and_out(path, sw),
        "scenes": scene_paths,
        "cache": Path(sw.get("cache", "out/sweep_cache")),
    }


def _name_and_out(path: Path, sw: dict) -> dict:
    """``[sweep]``'s name (default: the file's stem) and output folder (default: the file's)."""
    for k in ("out", "cache"):
        if k in sw:
            P.path(sw[k], k, source=toml_src(path, "sweep"))
    if "name" in sw and not (isinstance(sw["name"], str) and sw["name"].strip()):
        raise ParameterError(toml_src(path, "sweep"), "name", f"{sw['name']!r} is not a non-empty string")
    base = path.parent
    out = base / sw["out"] if "out" in sw and not Path(sw["out"]).is_absolute() else Path(sw.get("out", base))
    return {"name": str(sw.get("name", path.stem)), "out": out}


def ue_settings(path: Path, key: str, values: dict, value=None) -> None:
    """Refuse, naming the table ``key`` (and the swept ``value``), editor values that the settings
    themselves refuse (:func:`~fogref.mapping.unreal_pathtracer.settings_from`)."""
    try:
        settings_from(**values)
    except (FogrefError, TypeError, ValueError) as e:
        why = str(e).splitlines()[0]
        raise toml_error(path, key, why if value is None else f"value {value!r} refused: {why}") from None


def read_closed_form(path: Path, doc: dict) -> dict:
    """A ``ue_pathtracer`` sweep's ``[sweep]`` (name, out, ``threshold`` > 0, default 0.01),
    ``[fixed]`` (editor values of :data:`UE_PATHTRACER_FIELDS`; ``camera``: 3 numbers [m, y-up]),
    ``[sun]`` (``direction``: toward the sun, y-up, not zero; absent: no sun) and ``[views]``
    (``n_dirs``, ``ss_n_dirs`` in [1, 1e6]; ``distances``, ``ss_distances``: ``[start, stop, count]``
    of a geometric series [m], 0 < start <= stop, a whole count >= 1; ``ground`` [m] or absent),
    as the dict :func:`fogref.study.ue_pathtracer.closed_form_row` takes, under ``closed_form``."""
    sw = toml_table(path, doc, "sweep", ("name", "kind", "out", "threshold"))
    thr = toml_num(sw.get("threshold", 0.01), "threshold", toml_src(path, "sweep"), lo=0.0, lo_open=True)
    fixed = dict(toml_table(path, doc, "fixed", (*UE_PATHTRACER_FIELDS, "camera")))
    cam = fixed.get("camera", [0.0, 2.0, 0.0])
    fixed["camera"] = list(P.vector(cam, "camera", source=toml_src(path, "fixed")))
    ue_settings(path, "fixed", {k: v for k, v in fixed.items() if k != "camera"})
    sun = toml_table(path, doc, "sun", ("direction",)).get("direction")
    if sun is not None and not any(sun := list(P.vector(sun, "direction", source=toml_src(path, "sun")))):
        raise ParameterError(toml_src(path, "sun"), "direction", "[0, 0, 0] has no direction")
    vw = toml_table(path, doc, "views", ("n_dirs", "distances", "ss_n_dirs", "ss_distances", "ground"))
    vs = toml_src(path, "views")
    views = {"ground": None if vw.get("ground") is None else toml_num(vw["ground"], "ground", vs)}
    for k, n, d in (("", 400, [10.0, 2e4, 12]), ("ss_", 64, [30.0, 1e4, 6])):
        views[k + "n_dirs"] = toml_int(vw.get(k + "n_dirs", n), k + "n_dirs", vs, lo=1, hi=1_000_000)
        lo, hi, count = P.vector(vw.get(k + "distances", d), k + "distances", source=vs)
        if not (0 < lo <= hi and count == int(count) >= 1):
            raise ParameterError(vs, k + "distances", f"{[lo, hi, count]}: 0 < start <= stop, count >= 1")
        views[k + "distances"] = [lo, hi, int(count)]
    cf = {"fixed": fixed, "sun": sun, "views": views, "threshold": thr}
    return {**_name_and_out(path, sw), "closed_form": cf}


def read_render(path: Path, doc: dict) -> dict:
    """``[render]``: spp, seed, seed_policy, pixel_filter and the fixed ``$default`` overrides (as text)."""
    rd = toml_table(path, doc, "render", ("spp", "seed", "seed_policy", "overrides", "pixel_filter"))
    src = toml_src(path, "render")
    spp = toml_int(rd.get("spp", 16), "spp", src, lo=1, hi=1 << 20)
    seed = toml_int(rd.get("seed", 0), "seed", src, lo=0, hi=(1 << 31) - 1)
    policy = P.choice(rd.get("seed_policy", "fixed"), "seed_policy", SEED_POLICIES, src)
    pixel_filter = P.choice(rd.get("pixel_filter", "centre"), "pixel_filter", PIXEL_FILTERS, src)
    overrides = rd.get("overrides", {})
    if not isinstance(overrides, dict):
        raise toml_error(path, "render", "overrides must be a table of $default = value")
    for k, v in overrides.items():
        if isinstance(v, dict):
            raise ParameterError(src, f"overrides.{k}", f"{v!r} is not a value (a number, list or string)")
    return {
        "spp": spp,
        "seed": seed,
        "seed_policy": policy,
        "pixel_filter": pixel_filter,
        "overrides": {k: as_str(v) for k, v in overrides.items()},
    }


def _model_fields(path: Path, key: str, name: str) -> dict:
    """The model's parameters: name -> default (its ``Params`` dataclass), or ``{}`` if it has none."""
    try:
        cls = resolve_model(name)
    except FogrefError as e:
        raise toml_error(path, key, str(e)) from None
    pc = getattr(cls, "Params", None)
    if not (isinstance(pc, type) and dataclasses.is_dataclass(pc)):
        return {}
    return {f.name: f.default for f in dataclasses.fields(pc) if f.init}


def model_value(v, name: str, src: str, default):
    """A model parameter's value: a number where the model's default is a number, else as given."""
    if isinstance(default, (int, float)) and not isinstance(default, bool):
        return toml_num(v, name, src)
    if isinstance(default, bool):
        return toml_bool(v, name, src)
    return v


def model_param_name(name: str, fields: dict, src: str, model: str) -> str:
    """``name`` if the model has that parameter, else a ParameterError with did-you-mean."""
    if fields and name not in fields:
        raise ParameterError(
            src,
            name,
            f"model '{model}' has no parameter '{name}'"
            f"{did_you_mean(name, list(fields))}; it has: {', '.join(fields)}",
        )
    return name


def _read_model(path: Path, i: int, m, labels: set) -> dict:
    key = f"models][{i}"
    if not isinstance(m, dict) or "name" not in m:
        raise toml_error(
            path, key, 'each [[models]] entry needs a \'name\' (a model: "ue4", "my_pkg.fog:MyFog", ...)'
        )
    bad = set(m) - set(_MODEL_KEYS)
    if bad:
        raise toml_error(path, key, f"unknown key(s) {sorted(bad)}; allowed: {list(_MODEL_KEYS)}")
    if not isinstance(m["name"], str):
        raise ParameterError(toml_src(path, key), "name", f"{m['name']!r} is not a model name (a string)")
    fields = _model_fields(path, key, m["name"])
    # "my_pkg.fog:MyFog" is labelled "MyFog" (a label has no '.')
    label = str(m.get("label", str(m["name"]).rpartition(":")[2]))
    if label in labels or "." in label:
        raise toml_error(path, key, f"model label '{label}' must be unique and contain no '.'")
    params = m.get("params", {})
    if not isinstance(params, dict):
        raise toml_error(path, key, "params must be a table")
    src = toml_src(path, f"models] '{label}' [params")
    params = {
        k: model_value(v, model_param_name(k, fields, src, m["name"]), src, fields.get(k))
        for k, v in params.items()
    }
    return {
        "name": m["name"],
        "label": label,
        "from_scene": toml_bool(m.get("from_scene", True), "from_scene", toml_src(path, key)),
        "params": params,
        "fields": fields,
    }


def read_models(path: Path, doc: dict) -> list[dict]:
    """``[[models]]``: at least one; each name resolvable, each label unique, each parameter the model's."""
    models = doc.get("models", [])
    if not isinstance(models, list) or not models:
        raise toml_error(path, "models", "need at least one [[models]] entry with a 'name'")
    out: list[dict] = []
    for i, m in enumerate(models):
        out.append(_read_model(path, i, m, {x["label"] for x in out}))
    return out


def read_design(path: Path, doc: dict) -> dict:
    """``[design]``: kind (grid, list, random, lhs), n (random and lhs), seed, max_configs."""
    dz = toml_table(path, doc, "design", ("kind", "n", "seed", "max_configs"))
    src = toml_src(path, "design")
    kind = P.choice(dz.get("kind", "grid"), "kind", DESIGN_KINDS, src)
    limit = toml_int(dz.get("max_configs", MAX_CONFIGS), "max_configs", src, lo=1)
    n = dz.get("n")
    if kind in ("random", "lhs"):
        if n is None:
            raise ParameterError(
                src, "n", f"kind '{kind}' needs n = the number of configurations, in [1, {limit}]"
            )
        n = toml_int(n, "n", src, lo=1, hi=limit)
    return {
        "kind": kind,
        "n": n,
        "seed": toml_int(dz.get("seed", 0), "seed", src, lo=0, hi=(1 << 32) - 1),
        "max_configs": limit,
    }


def read_execution(path: Path, doc: dict) -> dict:
    """``[execution]``: Dask retries of a failing configuration."""
    retries = toml_table(path, doc, "execution", ("retries",)).get("retries", 1)
    return {"retries": toml_int(retries, "retries", toml_src(path, "execution"), lo=0, hi=100)}


def read_outputs(path: Path, doc: dict, out: Path) -> dict:
    """``[outputs]``: table name (inside the output folder), plots, plotted metrics, Unreal budget columns,
    the perceptual metrics (ΔE2000, FLIP: computed unless ``perceptual = false``)."""
    ou = toml_table(path, doc, "outputs", ("table", "plots", "plot_metrics", "budget", "perceptual"))
    src = toml_src(path, "outputs")
    table = ou.get("table", "results")
    if not isinstance(table, str) or not table.strip():
        raise ParameterError(src, "table", f"{table!r} is not a file name")
    root = out.resolve()
    where = (root / table).resolve()
    if Path(table).is_absolute() or not where.is_relative_to(root) or where == root:
        raise ParameterError(
            src,
            "table",
            f"'{table}' leaves the output folder {out}: "
            'give a name inside it, like "results" or "tables/results"',
        )
    metrics = ou.get("plot_metrics")
    if metrics is not None and not (isinstance(metrics, list) and all(isinstance(x, str) for x in metrics)):
        raise ParameterError(src, "plot_metrics", f"{metrics!r} is not a list of metric names")
    perceptual = toml_bool(ou.get("perceptual", True), "perceptual", src)
    left_out = [m for m in metrics or () if not perceptual and is_perceptual(m)]
    if left_out:
        raise ParameterError(
            src,
            "plot_metrics",
            f"{', '.join(left_out)} cannot be plotted with perceptual = false (ΔE2000 and FLIP are not "
            "computed); drop them or set perceptual = true",
        )
    return {
        "table": table,
        "plots": toml_bool(ou.get("plots", True), "plots", src),
        "plot_metrics": metrics,
        "budget": toml_bool(ou.get("budget", False), "budget", src),
        "perceptual": perceptual,
    }
