"""The sweep file: ``SWEEP.toml`` read and validated into a :class:`SweepSpec`, one table at a time.

The schema is in :mod:`fogref.study.sweep`'s docstring.  :func:`load_sweep` reads
the TOML and hands each table to its reader (``[sweep]``, ``[render]``,
``[[models]]``, ``[design]``, ``[parameters.*]``, ``[execution]``, ``[outputs]``);
every reader raises one :class:`~fogref.errors.FogrefError` line naming the file,
the table or key and the allowed values.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from fogref.errors import FogrefError
from fogref.models.resolve import resolve_model
from fogref.render.scene_defaults import declared

try:
    import tomllib  # Python >= 3.11
except ImportError:  # pragma: no cover
    import tomli as tomllib  # type: ignore[no-redef]

__all__ = ["DESIGN_KINDS", "SEED_POLICIES", "SweepSpec", "as_str", "load_sweep"]

DESIGN_KINDS = ("grid", "list", "random", "lhs")
SEED_POLICIES = ("fixed", "per_config")
_TOP_KEYS = {"sweep", "render", "design", "parameters", "models", "execution", "outputs"}
_MODEL_KEYS = ("from_scene", "label", "name", "params")
_PARAMETER_KEYS = ("log", "num", "range", "scale", "target", "values")


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


def _number(path, key, v, what):
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise _err(path, key, f"{what} must be a finite number, got {v!r}")
    return float(v)


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
        raise _err(path, name, f"unknown key(s) {sorted(bad)}; allowed: {sorted(allowed)}")
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
        scene_paths.append(p)
    out = base / sw["out"] if "out" in sw and not Path(sw["out"]).is_absolute() else Path(sw.get("out", base))
    return {"name": str(sw.get("name", path.stem)), "scenes": scene_paths, "out": out,
            "cache": Path(sw.get("cache", "out/sweep_cache"))}


def _read_render(path: Path, doc: dict) -> dict:
    """``[render]``: spp, seed, seed_policy, pixel_filter and the fixed ``$default`` overrides (as text)."""
    rd = _table(path, doc, "render", ("spp", "seed", "seed_policy", "overrides", "pixel_filter"))
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
    return {"spp": spp, "seed": seed, "seed_policy": policy,
            "pixel_filter": str(rd.get("pixel_filter", "centre")),
            "overrides": {k: as_str(v) for k, v in overrides.items()}}


def _read_model(path: Path, i: int, m, labels: set) -> dict:
    key = f"models][{i}"
    if not isinstance(m, dict) or "name" not in m:
        raise _err(path, key, "each [[models]] entry needs a 'name' "
                              "(a model: \"ue4\", \"my_pkg.fog:MyFog\", ...)")
    bad = set(m) - set(_MODEL_KEYS)
    if bad:
        raise _err(path, key, f"unknown key(s) {sorted(bad)}; allowed: {list(_MODEL_KEYS)}")
    try:
        resolve_model(m["name"])
    except FogrefError as e:
        raise _err(path, key, str(e)) from None
    # "my_pkg.fog:MyFog" is labelled "MyFog" (a label has no '.')
    label = str(m.get("label", str(m["name"]).rpartition(":")[2]))
    if label in labels or "." in label:
        raise _err(path, key, f"model label '{label}' must be unique and contain no '.'")
    params = m.get("params", {})
    if not isinstance(params, dict):
        raise _err(path, key, "params must be a table")
    return {"name": m["name"], "label": label, "from_scene": bool(m.get("from_scene", True)),
            "params": params}


def _read_models(path: Path, doc: dict) -> list[dict]:
    """``[[models]]``: at least one; each name resolvable, each label unique."""
    models = doc.get("models", [])
    if not isinstance(models, list) or not models:
        raise _err(path, "models", "need at least one [[models]] entry with a 'name'")
    out: list[dict] = []
    for i, m in enumerate(models):
        out.append(_read_model(path, i, m, {x["label"] for x in out}))
    return out


def _read_design(path: Path, doc: dict) -> dict:
    """``[design]``: kind (grid, list, random, lhs), n (random and lhs), seed."""
    dz = _table(path, doc, "design", ("kind", "n", "seed"))
    kind = dz.get("kind", "grid")
    if kind not in DESIGN_KINDS:
        raise _err(path, "design", f"kind '{kind}' unknown; allowed: {list(DESIGN_KINDS)}")
    n = dz.get("n")
    if kind in ("random", "lhs") and (not isinstance(n, int) or n < 1):
        raise _err(path, "design", f"kind '{kind}' needs n = a positive integer (number of configurations)")
    return {"kind": kind, "n": n, "seed": int(dz.get("seed", 0))}


def _parameter_target(path: Path, key: str, target: str, scene_names: set, labels: set) -> dict:
    """A scene ``$default`` every scene declares, or ``<model label>.<parameter>``."""
    if "." in target:
        mlabel, mparam = target.split(".", 1)
        if mlabel not in labels:
            raise _err(path, key, f"'{target}': model label '{mlabel}' is not a [[models]] label; "
                       f"allowed: {sorted(labels)}")
        return {"kind": "model", "model": mlabel, "target": mparam}
    if target not in scene_names:
        raise _err(path, key, f"'{target}' is not a $default of every scene; allowed: {sorted(scene_names)}")
    return {"kind": "scene", "target": target}


def _parameter_values(path: Path, key: str, spec: dict, design_kind: str) -> dict:
    """``values`` (a list), or ``range`` [low, high] with ``log`` (and ``num`` points on a grid or list)."""
    if "values" in spec:
        vals = spec["values"]
        if not isinstance(vals, list) or not vals:
            raise _err(path, key, "values must be a non-empty list")
        return {"values": vals}
    if "range" not in spec:
        raise _err(path, key, "give 'values' (a list) or 'range' ([low, high])")
    r = spec["range"]
    if not (isinstance(r, list) and len(r) == 2):
        raise _err(path, key, f"range must be [low, high], got {r!r}")
    lo, hi = (_number(path, key, x, "range bounds") for x in r)
    if not lo < hi or (spec.get("log") and lo <= 0):
        raise _err(path, key, f"range [{lo}, {hi}] needs low < high (and low > 0 with log = true)")
    out = {"range": [lo, hi], "log": bool(spec.get("log", False))}
    if design_kind in ("grid", "list"):
        num = spec.get("num")
        if not isinstance(num, int) or num < 1:
            raise _err(path, key, f"a range in a '{design_kind}' design needs num = number of points")
        out["values"] = _spaced(lo, hi, num, out["log"])
    return out


def _read_parameter(path: Path, label: str, spec, scene_names: set, labels: set, design_kind: str) -> dict:
    key = f"parameters.{label}"
    if not isinstance(spec, dict):
        raise _err(path, key, "must be a table with 'values' or 'range'")
    bad = set(spec) - set(_PARAMETER_KEYS)
    if bad:
        raise _err(path, key, f"unknown key(s) {sorted(bad)}; allowed: {list(_PARAMETER_KEYS)}")
    ps = _parameter_target(path, key, str(spec.get("target", label)), scene_names, labels)
    ps["scale"] = _number(path, key, spec.get("scale", 1.0), "scale")
    ps.update(_parameter_values(path, key, spec, design_kind))
    if ps["scale"] != 1.0:
        for v in ps.get("values", []):
            _number(path, key, v, "a scaled value")
    return ps


def _read_parameters(path: Path, doc: dict, scenes: list[Path], labels: set, design_kind: str) -> dict:
    """``[parameters.LABEL]``: what each swept parameter sets and its values; ``list`` designs
    need equally long value lists."""
    params = doc.get("parameters", {})
    if not isinstance(params, dict):
        raise _err(path, "parameters", "must be a table of [parameters.NAME] tables")
    scene_names = set.intersection(*(set(declared(p)) for p in scenes)) if scenes else set()
    out = {label: _read_parameter(path, label, spec, scene_names, labels, design_kind)
           for label, spec in params.items()}
    if design_kind == "list":
        lens = {len(p["values"]) for p in out.values()}
        if len(lens) > 1:
            raise _err(path, "design",
                       f"kind 'list' zips the parameters' values: their lengths differ ({sorted(lens)})")
    return out


def _read_execution(path: Path, doc: dict) -> dict:
    """``[execution]``: Dask retries of a failing configuration."""
    retries = _table(path, doc, "execution", ("retries",)).get("retries", 1)
    if not isinstance(retries, int) or retries < 0:
        raise _err(path, "execution", f"retries must be an integer >= 0, got {retries!r}")
    return {"retries": retries}


def _read_outputs(path: Path, doc: dict) -> dict:
    """``[outputs]``: table name, plots, plotted metrics, Unreal budget columns."""
    ou = _table(path, doc, "outputs", ("table", "plots", "plot_metrics", "budget"))
    return {"table": str(ou.get("table", "results")), "plots": bool(ou.get("plots", True)),
            "plot_metrics": ou.get("plot_metrics"), "budget": bool(ou.get("budget", False))}


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
        Naming the file, the key and the allowed values for anything malformed: an
        unknown table or key, a scene that does not exist, a parameter that is not a
        ``$default`` of every scene (the message lists them) or not ``<model>.<name>``
        of a listed model, an unknown design kind or seed policy, an unknown model name.
    """
    path = Path(path)
    doc = _read_toml(path)
    sweep = _read_sweep(path, doc)
    render = _read_render(path, doc)
    models = _read_models(path, doc)
    design = _read_design(path, doc)
    parameters = _read_parameters(path, doc, sweep["scenes"], {m["label"] for m in models}, design["kind"])
    return SweepSpec(path=path, **sweep, **render, parameters=parameters, design=design, models=models,
                     **_read_execution(path, doc), **_read_outputs(path, doc))
