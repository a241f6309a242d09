"""The sweep file: ``SWEEP.toml`` read and validated into a :class:`SweepSpec`, one table at a time.

The schema is in :mod:`fogref.study.sweep`'s docstring.  :func:`load_sweep` reads
the TOML and hands each table to its reader (``[sweep]``, ``[render]``,
``[[models]]``, ``[design]``, ``[parameters.*]``, ``[execution]``, ``[outputs]``);
every reader raises one :class:`~fogref.errors.FogrefError` line naming the file,
the table or key and the allowed values.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from fogref import params as P
from fogref.errors import FogrefError, ParameterError, did_you_mean
from fogref.models.resolve import resolve_model
from fogref.render.render import PIXEL_FILTERS
from fogref.render.scene import describe_scene
from fogref.render.scene_defaults import declared

try:
    import tomllib  # Python >= 3.11
except ImportError:  # pragma: no cover
    import tomli as tomllib  # type: ignore[no-redef]

__all__ = ["DESIGN_KINDS", "MAX_CONFIGS", "SEED_POLICIES", "SweepSpec", "as_str", "design_size", "load_sweep"]

DESIGN_KINDS = ("grid", "list", "random", "lhs")
SEED_POLICIES = ("fixed", "per_config")
_TOP_KEYS = {"sweep", "render", "design", "parameters", "models", "execution", "outputs"}
_MODEL_KEYS = ("from_scene", "label", "name", "params")
_PARAMETER_KEYS = ("log", "num", "range", "scale", "target", "values")
#: The most configurations a sweep may have unless its ``[design] max_configs`` says more.
MAX_CONFIGS = 100_000


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
        ``kind``, ``n``, ``seed``, ``max_configs`` (the size limit, default :data:`MAX_CONFIGS`).
    models : list of dict
        ``name``, ``label``, ``from_scene``, ``params``.
    retries : int
        Dask retries per configuration.
    table : str
        Table base name.  plots : bool.  plot_metrics : list of str or None.
    budget : bool
        Unreal's error budget for every "ue4" model.
    """

    def __init__(self, **kw):
        self.__dict__.update(kw)


def _err(path, key, msg) -> FogrefError:
    return FogrefError(f"{path}: [{key}]: {msg}" if key else f"{path}: {msg}")


def as_str(v) -> str:
    """A TOML value as an XML ``$default`` string (lists -> ``"a, b, c"``).

    >>> as_str([1, 2.5, True]), as_str(0.1)
    ('1, 2.5, true', '0.1')
    """
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (list, tuple)):
        return ", ".join(as_str(x) for x in v)
    if isinstance(v, float):
        return repr(v)
    return str(v)


def _resolve(base: Path, p: str) -> Path:
    q = Path(p)
    if q.is_absolute():
        return q
    return base / q if (base / q).exists() else q


def _src(path, key) -> str:
    """The source named in a ParameterError: ``"SWEEP.toml: [render]"``."""
    return f"{path}: [{key}]"


def _typed(v, name: str, src: str, what: str = "a number"):
    """``v`` unless it is a TOML string or boolean where a number is expected
    (``seed = "x"``, ``n = true``)."""
    if isinstance(v, (str, bool)):
        raise ParameterError(src, name, f"{v!r} is not {what} (write a TOML number, without quotes)")
    return v


def _num(v, name: str, src: str, **kw) -> float:
    """A TOML number through :func:`fogref.params.number`."""
    return P.number(_typed(v, name, src), name, source=src, **kw)


def _int(v, name: str, src: str, **kw) -> int:
    """A TOML integer through :func:`fogref.params.integer`."""
    return P.integer(_typed(v, name, src, "an integer"), name, source=src, **kw)


def _bool(v, name: str, src: str) -> bool:
    if not isinstance(v, bool):
        raise ParameterError(src, name, f"{v!r} is not true or false")
    return v


def _spaced(lo, hi, num, log):
    v = np.geomspace(lo, hi, num) if log else np.linspace(lo, hi, num)
    return [float(x) for x in v]


def _read_toml(path: Path) -> dict:
    if not path.is_file():
        raise FogrefError(f"{path}: no such sweep file")
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as e:
        raise FogrefError(f"{path}: not valid TOML ({e})") from None
    unknown = set(doc) - _TOP_KEYS
    if unknown:
        raise _err(path, None, f"unknown table(s) {sorted(unknown)}; allowed: {sorted(_TOP_KEYS)}")
    return doc


def _table(path: Path, doc: dict, name: str, allowed) -> dict:
    t = doc.get(name, {})
    if not isinstance(t, dict):
        raise _err(path, name, "must be a table")
    bad = set(t) - set(allowed)
    if bad:
        raise _err(
            path,
            name,
            f"unknown key(s) {sorted(bad)}{did_you_mean(sorted(bad)[0], allowed)}; "
            f"allowed: {sorted(allowed)}",
        )
    return t


def _read_sweep(path: Path, doc: dict) -> dict:
    """``[sweep]``: name, scene paths (relative to the TOML file, else the working directory), out, cache."""
    base = path.parent
    sw = _table(path, doc, "sweep", ("name", "scenes", "out", "cache"))
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
        if any(p.resolve() == q.resolve() for q in scene_paths):
            raise ParameterError(_src(path, "sweep"), "scenes", f"'{s}' is listed twice")
        scene_paths.append(p)
    for k in ("out", "cache"):
        if k in sw:
            P.path(sw[k], k, source=_src(path, "sweep"))
    if "name" in sw and not (isinstance(sw["name"], str) and sw["name"].strip()):
        raise ParameterError(_src(path, "sweep"), "name", f"{sw['name']!r} is not a non-empty string")
    out = base / sw["out"] if "out" in sw and not Path(sw["out"]).is_absolute() else Path(sw.get("out", base))
    return {
        "name": str(sw.get("name", path.stem)),
        "scenes": scene_paths,
        "out": out,
        "cache": Path(sw.get("cache", "out/sweep_cache")),
    }


def _read_render(path: Path, doc: dict) -> dict:
    """``[render]``: spp, seed, seed_policy, pixel_filter and the fixed ``$default`` overrides (as text)."""
    rd = _table(path, doc, "render", ("spp", "seed", "seed_policy", "overrides", "pixel_filter"))
    src = _src(path, "render")
    spp = _int(rd.get("spp", 16), "spp", src, lo=1, hi=1 << 20)
    seed = _int(rd.get("seed", 0), "seed", src, lo=0, hi=(1 << 31) - 1)
    policy = P.choice(rd.get("seed_policy", "fixed"), "seed_policy", SEED_POLICIES, src)
    pixel_filter = P.choice(rd.get("pixel_filter", "centre"), "pixel_filter", PIXEL_FILTERS, src)
    overrides = rd.get("overrides", {})
    if not isinstance(overrides, dict):
        raise _err(path, "render", "overrides must be a table of $default = value")
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
        raise _err(path, key, str(e)) from None
    pc = getattr(cls, "Params", None)
    if not (isinstance(pc, type) and dataclasses.is_dataclass(pc)):
        return {}
    return {f.name: f.default for f in dataclasses.fields(pc) if f.init}


def _model_value(v, name: str, src: str, default):
    """A model parameter's value: a number where the model's default is a number, else as given."""
    if isinstance(default, (int, float)) and not isinstance(default, bool):
        return _num(v, name, src)
    if isinstance(default, bool):
        return _bool(v, name, src)
    return v


def _model_param_name(name: str, fields: dict, src: str, model: str) -> str:
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
        raise _err(
            path, key, 'each [[models]] entry needs a \'name\' (a model: "ue4", "my_pkg.fog:MyFog", ...)'
        )
    bad = set(m) - set(_MODEL_KEYS)
    if bad:
        raise _err(path, key, f"unknown key(s) {sorted(bad)}; allowed: {list(_MODEL_KEYS)}")
    if not isinstance(m["name"], str):
        raise ParameterError(_src(path, key), "name", f"{m['name']!r} is not a model name (a string)")
    fields = _model_fields(path, key, m["name"])
    # "my_pkg.fog:MyFog" is labelled "MyFog" (a label has no '.')
    label = str(m.get("label", str(m["name"]).rpartition(":")[2]))
    if label in labels or "." in label:
        raise _err(path, key, f"model label '{label}' must be unique and contain no '.'")
    params = m.get("params", {})
    if not isinstance(params, dict):
        raise _err(path, key, "params must be a table")
    src = _src(path, f"models] '{label}' [params")
    params = {
        k: _model_value(v, _model_param_name(k, fields, src, m["name"]), src, fields.get(k))
        for k, v in params.items()
    }
    return {
        "name": m["name"],
        "label": label,
        "from_scene": _bool(m.get("from_scene", True), "from_scene", _src(path, key)),
        "params": params,
        "fields": fields,
    }


def _read_models(path: Path, doc: dict) -> list[dict]:
    """``[[models]]``: at least one; each name resolvable, each label unique, each parameter the model's."""
    models = doc.get("models", [])
    if not isinstance(models, list) or not models:
        raise _err(path, "models", "need at least one [[models]] entry with a 'name'")
    out: list[dict] = []
    for i, m in enumerate(models):
        out.append(_read_model(path, i, m, {x["label"] for x in out}))
    return out


def _read_design(path: Path, doc: dict) -> dict:
    """``[design]``: kind (grid, list, random, lhs), n (random and lhs), seed, max_configs."""
    dz = _table(path, doc, "design", ("kind", "n", "seed", "max_configs"))
    src = _src(path, "design")
    kind = P.choice(dz.get("kind", "grid"), "kind", DESIGN_KINDS, src)
    limit = _int(dz.get("max_configs", MAX_CONFIGS), "max_configs", src, lo=1)
    n = dz.get("n")
    if kind in ("random", "lhs"):
        if n is None:
            raise ParameterError(
                src, "n", f"kind '{kind}' needs n = the number of configurations, in [1, {limit}]"
            )
        n = _int(n, "n", src, lo=1, hi=limit)
    return {
        "kind": kind,
        "n": n,
        "seed": _int(dz.get("seed", 0), "seed", src, lo=0, hi=(1 << 32) - 1),
        "max_configs": limit,
    }


def _parameter_target(path: Path, key: str, target, scene_names: set, models: dict) -> dict:
    """A scene ``$default`` every scene declares, or ``<model label>.<parameter>`` of a listed model."""
    src = _src(path, key)
    if not isinstance(target, str) or not target:
        raise ParameterError(src, "target", f"{target!r} is not a $default or '<model>.<parameter>' name")
    if "." in target:
        mlabel, mparam = target.split(".", 1)
        if mlabel not in models:
            raise _err(
                path,
                key,
                f"'{target}': model label '{mlabel}' is not a [[models]] label; "
                f"allowed: {sorted(models)}{did_you_mean(mlabel, list(models))}",
            )
        _model_param_name(mparam, models[mlabel]["fields"], src, models[mlabel]["name"])
        return {"kind": "model", "model": mlabel, "target": mparam}
    if target not in scene_names:
        raise _err(
            path,
            key,
            f"'{target}' is not a $default of every scene{did_you_mean(target, scene_names)}; "
            f"allowed: {sorted(scene_names)}",
        )
    return {"kind": "scene", "target": target}


def _distinct(path: Path, key: str, vals: list, what: str) -> None:
    """Refuse a value given twice: two configurations would be the same render."""
    seen: dict = {}
    for v in vals:
        k = as_str(v)
        if k in seen:
            raise ParameterError(
                _src(path, key),
                what,
                f"{v!r} is given twice ({vals!r}); "
                "each value must be distinct (a repeated value repeats the same render)",
            )
        seen[k] = v


def _parameter_values(path: Path, key: str, spec: dict, design: dict) -> dict:
    """``values`` (a list of distinct values), or ``range`` [low, high] with ``log`` (and ``num`` points
    on a grid or list)."""
    src = _src(path, key)
    kind = design["kind"]
    if "values" in spec:
        vals = spec["values"]
        if not isinstance(vals, list) or not vals:
            raise _err(path, key, "values must be a non-empty list")
        if any(isinstance(v, dict) for v in vals):
            raise ParameterError(src, "values", f"{vals!r}: each value must be a number, list or string")
        if kind != "list":  # a zipped list may repeat one parameter's value; its rows are checked later
            _distinct(path, key, vals, "values")
        return {"values": vals}
    if "range" not in spec:
        raise _err(path, key, "give 'values' (a list) or 'range' ([low, high])")
    r = spec["range"]
    if not (isinstance(r, list) and len(r) == 2):
        raise _err(path, key, f"range must be [low, high], got {r!r}")
    lo, hi = (_num(x, "range", src) for x in r)
    log = _bool(spec.get("log", False), "log", src)
    if not lo < hi or (log and lo <= 0):
        raise ParameterError(src, "range", f"[{lo}, {hi}] needs low < high (and low > 0 with log = true)")
    out = {"range": [lo, hi], "log": log}
    if kind in ("grid", "list"):
        if "num" not in spec:
            raise _err(path, key, f"a range in a '{kind}' design needs num = number of points")
        num = _int(spec["num"], "num", src, lo=1, hi=design["max_configs"])
        out["values"] = _spaced(lo, hi, num, log)
    return out


def _read_parameter(path: Path, label: str, spec, scene_names: set, models: dict, design: dict) -> dict:
    key = f"parameters.{label}"
    if not isinstance(spec, dict):
        raise _err(path, key, "must be a table with 'values' or 'range'")
    bad = set(spec) - set(_PARAMETER_KEYS)
    if bad:
        raise _err(
            path,
            key,
            f"unknown key(s) {sorted(bad)}{did_you_mean(sorted(bad)[0], _PARAMETER_KEYS)}; "
            f"allowed: {list(_PARAMETER_KEYS)}",
        )
    ps = _parameter_target(path, key, spec.get("target", label), scene_names, models)
    src = _src(path, key)
    ps["scale"] = _num(spec.get("scale", 1.0), "scale", src)
    if ps["scale"] == 0:
        raise ParameterError(src, "scale", "0 maps every value to 0: must be a finite number other than 0")
    ps.update(_parameter_values(path, key, spec, design))
    if ps["scale"] != 1.0:
        for v in ps.get("values", []):
            _num(v, "values", src)
    if ps["kind"] == "model":
        default = models[ps["model"]]["fields"].get(ps["target"])
        for v in ps.get("values", ps.get("range", [])):
            _model_value(v, "values", src, default)
    return ps


def design_size(kind: str, parameters: dict, n=None, scenes: int = 1) -> int:
    """The number of configurations a design has, from the parameters' value counts (nothing built).

    >>> design_size("grid", {"a": {"values": [1, 2, 3]}, "b": {"values": [1, 2]}}, scenes=2)
    12
    >>> design_size("lhs", {"a": {"range": [0, 1]}}, n=48)
    48
    """
    if not parameters:
        return scenes
    if kind == "grid":
        return scenes * math.prod(len(p["values"]) for p in parameters.values())
    if kind == "list":
        return scenes * len(next(iter(parameters.values()))["values"])
    return scenes * int(n)


def _check_targets(path: Path, params: dict, overrides: dict, models: dict) -> None:
    """One label per target, and a swept target is not also fixed (``[render].overrides`` or a model's
    ``params``): the table would name a value the render never used."""
    seen: dict = {}
    for label, p in params.items():
        t = p["target"] if p["kind"] == "scene" else f"{p['model']}.{p['target']}"
        if t in seen:
            raise ParameterError(
                _src(path, f"parameters.{label}"),
                "target",
                f"'{t}' is also swept by [parameters.{seen[t]}]: two labels of one "
                "parameter would record values the render never used; keep one",
            )
        seen[t] = label
        if p["kind"] == "scene" and p["target"] in overrides:
            raise ParameterError(
                _src(path, f"parameters.{label}"),
                "target",
                f"'{t}' is swept here and fixed in [render].overrides; remove one",
            )
        if p["kind"] == "model" and p["target"] in models[p["model"]]["params"]:
            raise ParameterError(
                _src(path, f"parameters.{label}"),
                "target",
                f"'{t}' is swept here and fixed in the [[models]] '{p['model']}' params; remove one",
            )


def _check_size(path: Path, design: dict, params: dict, scenes: list) -> int:
    """Refuse a design larger than ``[design] max_configs``, before anything is built; list rows distinct."""
    kind = design["kind"]
    if kind == "list" and params:
        lens = {len(p["values"]) for p in params.values()}
        if len(lens) > 1:
            raise _err(
                path,
                "design",
                f"kind 'list' zips the parameters' values: their lengths differ ({sorted(lens)})",
            )
    size = design_size(kind, params, design["n"], len(scenes))
    limit = design["max_configs"]
    if size > limit:
        raise ParameterError(
            _src(path, "design"),
            "size",
            f"the {kind} design has {size:.4g} configurations ({len(scenes)} scene(s)); "
            f"the limit is {limit} (raise it with [design] max_configs = N)",
        )
    if kind == "list" and params:
        _distinct(
            path,
            "design",
            [[as_str(v) for v in row] for row in zip(*(p["values"] for p in params.values()))],
            "list rows",
        )
    return size


def _check_scene_values(path: Path, scenes: list, overrides: dict, params: dict) -> None:
    """Every fixed override, and every swept scene value (a range: its ends) on its own, against each scene's
    own checks (:func:`fogref.render.scene.describe_scene`: the ``$default`` kinds, the resolution, the
    medium's physical ranges), so a value that cannot render is refused here, naming the TOML key."""
    for scene in scenes:
        try:
            describe_scene(scene, overrides)
        except FogrefError as e:
            raise _err(path, "render", f"overrides: {str(e).splitlines()[0]}") from None
        for label, p in params.items():
            if p["kind"] != "scene":
                continue
            vals = p.get("values") or p["range"]
            for v in {as_str(x): x for x in vals}.values():
                value = v * p["scale"] if p["scale"] != 1.0 else v
                try:
                    describe_scene(scene, {**overrides, p["target"]: as_str(value)})
                except FogrefError as e:
                    raise _err(
                        path, f"parameters.{label}", f"value {v!r} refused: {str(e).splitlines()[0]}"
                    ) from None


def _read_parameters(
    path: Path, doc: dict, scenes: list[Path], models: list, design: dict, overrides: dict
) -> dict:
    """``[parameters.LABEL]``: what each swept parameter sets and its values, checked
    (see :func:`load_sweep`)."""
    params = doc.get("parameters", {})
    if not isinstance(params, dict):
        raise _err(path, "parameters", "must be a table of [parameters.NAME] tables")
    scene_names = set.intersection(*(set(declared(p)) for p in scenes)) if scenes else set()
    by_label = {m["label"]: m for m in models}
    out = {
        label: _read_parameter(path, label, spec, scene_names, by_label, design)
        for label, spec in params.items()
    }
    _check_targets(path, out, overrides, by_label)
    _check_size(path, design, out, scenes)
    _check_scene_values(path, scenes, overrides, out)
    return out


def _read_execution(path: Path, doc: dict) -> dict:
    """``[execution]``: Dask retries of a failing configuration."""
    retries = _table(path, doc, "execution", ("retries",)).get("retries", 1)
    return {"retries": _int(retries, "retries", _src(path, "execution"), lo=0, hi=100)}


def _read_outputs(path: Path, doc: dict, out: Path) -> dict:
    """``[outputs]``: table name (inside the output folder), plots, plotted metrics, Unreal budget columns."""
    ou = _table(path, doc, "outputs", ("table", "plots", "plot_metrics", "budget"))
    src = _src(path, "outputs")
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
    return {
        "table": table,
        "plots": _bool(ou.get("plots", True), "plots", src),
        "plot_metrics": metrics,
        "budget": _bool(ou.get("budget", False), "budget", src),
    }


def load_sweep(path) -> SweepSpec:
    """Read and validate a sweep TOML file.

    Parameters
    ----------
    path : str or Path
        The ``SWEEP.toml`` (schema in :mod:`fogref.study.sweep`'s docstring).

    Returns
    -------
    SweepSpec

    Raises
    ------
    FogrefError
        One line naming the file, the key and the allowed values for anything malformed
        (values pass through :mod:`fogref.params`): an unknown table or key, a scene that
        does not exist, a parameter that is not a ``$default`` of every scene or not
        ``<model>.<parameter>`` of a listed model (did-you-mean), a value the scene or its
        medium refuses (the medium's own ranges), a repeated value, two labels of one
        target, a target both swept and fixed, a design larger than ``[design]
        max_configs`` (default :data:`MAX_CONFIGS`; sized before anything is built), a
        table path outside the output folder, an unknown design kind, seed policy,
        pixel filter or model.
    """
    path = Path(path)
    doc = _read_toml(path)
    sweep = _read_sweep(path, doc)
    render = _read_render(path, doc)
    models = _read_models(path, doc)
    design = _read_design(path, doc)
    parameters = _read_parameters(path, doc, sweep["scenes"], models, design, render["overrides"])
    for m in models:
        del m["fields"]
    return SweepSpec(
        path=path,
        **sweep,
        **render,
        parameters=parameters,
        design=design,
        models=models,
        **_read_execution(path, doc),
        **_read_outputs(path, doc, sweep["out"]),
    )
