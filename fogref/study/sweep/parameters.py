"""The reader of a sweep file's ``[parameters.LABEL]`` tables, and the checks across tables.

Each swept parameter's target (a scene ``$default`` or ``<model label>.<parameter>``) and
values (a list, or a range with ``log`` and ``num``); then, across the file: one label per
target, nothing both swept and fixed, the design's size (:func:`design_size`, before
anything is built) and every value against the scenes' own checks
(:func:`fogref.render.load.describe_scene`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from fogref.errors import FogrefError, ParameterError, did_you_mean
from fogref.render.load import describe_scene
from fogref.scene.defaults import declared
from fogref.study.sweep.sections import model_param_name, model_value
from fogref.study.sweep.values import as_str, toml_bool, toml_error, toml_int, toml_num, toml_src

_PARAMETER_KEYS = ("log", "num", "range", "scale", "target", "values")


def _spaced(lo, hi, num, log):
    v = np.geomspace(lo, hi, num) if log else np.linspace(lo, hi, num)
    return [float(x) for x in v]


def _parameter_target(path: Path, key: str, target, scene_names: set, models: dict) -> dict:
    """A scene ``$default`` every scene declares, or ``<model label>.<parameter>`` of a listed model."""
    src = toml_src(path, key)
    if not isinstance(target, str) or not target:
        raise ParameterError(src, "target", f"{target!r} is not a $default or '<model>.<parameter>' name")
    if "." in target:
        mlabel, mparam = target.split(".", 1)
        if mlabel not in models:
            raise toml_error(
                path,
                key,
                f"'{target}': model label '{mlabel}' is not a [[models]] label; "
                f"allowed: {sorted(models)}{did_you_mean(mlabel, list(models))}",
            )
        model_param_name(mparam, models[mlabel]["fields"], src, models[mlabel]["name"])
        return {"kind": "model", "model": mlabel, "target": mparam}
    if target not in scene_names:
        raise toml_error(
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
                toml_src(path, key),
                what,
                f"{v!r} is given twice ({vals!r}); "
                "each value must be distinct (a repeated value repeats the same render)",
            )
        seen[k] = v


def _parameter_values(path: Path, key: str, spec: dict, design: dict) -> dict:
    """``values`` (a list of distinct values), or ``range`` [low, high] with ``log`` (and ``num`` points
    on a grid or list)."""
    src = toml_src(path, key)
    kind = design["kind"]
    if "values" in spec:
        vals = spec["values"]
        if not isinstance(vals, list) or not vals:
            raise toml_error(path, key, "values must be a non-empty list")
        if any(isinstance(v, dict) for v in vals):
            raise ParameterError(src, "values", f"{vals!r}: each value must be a number, list or string")
        if kind != "list":  # a zipped list may repeat one parameter's value; its rows are checked later
            _distinct(path, key, vals, "values")
        return {"values": vals}
    if "range" not in spec:
        raise toml_error(path, key, "give 'values' (a list) or 'range' ([low, high])")
    r = spec["range"]
    if not (isinstance(r, list) and len(r) == 2):
        raise toml_error(path, key, f"range must be [low, high], got {r!r}")
    lo, hi = (toml_num(x, "range", src) for x in r)
    log = toml_bool(spec.get("log", False), "log", src)
    if not lo < hi or (log and lo <= 0):
        raise ParameterError(src, "range", f"[{lo}, {hi}] needs low < high (and low > 0 with log = true)")
    out = {"range": [lo, hi], "log": log}
    if kind in ("grid", "list"):
        if "num" not in spec:
            raise toml_error(path, key, f"a range in a '{kind}' design needs num = number of points")
        num = toml_int(spec["num"], "num", src, lo=1, hi=design["max_configs"])
        out["values"] = _spaced(lo, hi, num, log)
    return out


def _read_parameter(path: Path, label: str, spec, scene_names: set, models: dict, design: dict) -> dict:
    key = f"parameters.{label}"
    if not isinstance(spec, dict):
        raise toml_error(path, key, "must be a table with 'values' or 'range'")
    bad = set(spec) - set(_PARAMETER_KEYS)
    if bad:
        raise toml_error(
            path,
            key,
            f"unknown key(s) {sorted(bad)}{did_you_mean(sorted(bad)[0], _PARAMETER_KEYS)}; "
            f"allowed: {list(_PARAMETER_KEYS)}",
        )
    ps = _parameter_target(path, key, spec.get("target", label), scene_names, models)
    src = toml_src(path, key)
    ps["scale"] = toml_num(spec.get("scale", 1.0), "scale", src)
    if ps["scale"] == 0:
        raise ParameterError(src, "scale", "0 maps every value to 0: must be a finite number other than 0")
    ps.update(_parameter_values(path, key, spec, design))
    if ps["scale"] != 1.0:
        for v in ps.get("values", []):
            toml_num(v, "values", src)
    if ps["kind"] == "model":
        default = models[ps["model"]]["fields"].get(ps["target"])
        for v in ps.get("values", ps.get("range", [])):
            model_value(v, "values", src, default)
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
                toml_src(path, f"parameters.{label}"),
                "target",
                f"'{t}' is also swept by [parameters.{seen[t]}]: two labels of one "
                "parameter would record values the render never used; keep one",
            )
        seen[t] = label
        if p["kind"] == "scene" and p["target"] in overrides:
            raise ParameterError(
                toml_src(path, f"parameters.{label}"),
                "target",
                f"'{t}' is swept here and fixed in [render].overrides; remove one",
            )
        if p["kind"] == "model" and p["target"] in models[p["model"]]["params"]:
            raise ParameterError(
                toml_src(path, f"parameters.{label}"),
                "target",
                f"'{t}' is swept here and fixed in the [[models]] '{p['model']}' params; remove one",
            )


def _check_size(path: Path, design: dict, params: dict, scenes: list) -> int:
    """Refuse a design larger than ``[design] max_configs``, before anything is built; list rows distinct."""
    kind = design["kind"]
    if kind == "list" and params:
        lens = {len(p["values"]) for p in params.values()}
        if len(lens) > 1:
            raise toml_error(
                path,
                "design",
                f"kind 'list' zips the parameters' values: their lengths differ ({sorted(lens)})",
            )
    size = design_size(kind, params, design["n"], len(scenes))
    limit = design["max_configs"]
    if size > limit:
        raise ParameterError(
            toml_src(path, "design"),
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
    own checks (:func:`fogref.render.load.describe_scene`: the ``$default`` kinds, the resolution, the
    medium's physical ranges), so a value that cannot render is refused here, naming the TOML key."""
    for scene in scenes:
        try:
            describe_scene(scene, overrides)
        except FogrefError as e:
            raise toml_error(path, "render", f"overrides: {str(e).splitlines()[0]}") from None
        for label, p in params.items():
            if p["kind"] != "scene":
                continue
            vals = p.get("values") or p["range"]
            for v in {as_str(x): x for x in vals}.values():
                value = v * p["scale"] if p["scale"] != 1.0 else v
                try:
                    describe_scene(scene, {**overrides, p["target"]: as_str(value)})
                except FogrefError as e:
                    raise toml_error(
                        path, f"parameters.{label}", f"value {v!r} refused: {str(e).splitlines()[0]}"
                    ) from None


def read_parameters(
    path: Path, doc: dict, scenes: list[Path], models: list, design: dict, overrides: dict
) -> dict:
    """``[parameters.LABEL]``: what each swept parameter sets and its values, checked
    (see :func:`load_sweep`)."""
    params = doc.get("parameters", {})
    if not isinstance(params, dict):
        raise toml_error(path, "parameters", "must be a table of [parameters.NAME] tables")
    scene_names = set.intersection(*(set(declared(p)) for p in scenes)) if scenes else set()
    by_label = {m["label"]: m for m in models}
    out = {
        label: _read_parameter(path, label, spec, scene_names, by_label, design)
        for label, spec in params.items()
    }
    _check_targets(path, out, overrides, by_label)
    _check_size(path, design, out, scenes or [None])
    _check_scene_values(path, scenes, overrides, out)
    return out
