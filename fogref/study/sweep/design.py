"""The sweep's design: every configuration's parameter values, and each configuration as a task.

:func:`design_points` lays the swept parameters out (grid, zipped lists, seeded
random, Latin hypercube); :func:`build_configs` turns each point of each scene
into a self-contained, JSON-ready task whose ``id`` hashes everything it does (the
bytes of the scene and of every file it loads, the overrides, the models, spp, seed,
pixel filter, fogref's version), so a finished configuration is recognised on resume
and an edited mesh, envmap or texture means a fresh one.  A design is sized
(:func:`~fogref.study.sweep.spec.design_size`) before any point of it is built.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
from pathlib import Path

import numpy as np

from fogref._version import __version__
from fogref.errors import FogrefError, ParameterError
from fogref.render.cache import truth_path
from fogref.scene.inputs import file_sha256, inputs_digest, scene_inputs
from fogref.study.sweep.spec import MAX_CONFIGS, SweepSpec, as_str, design_size

__all__ = ["build_configs", "design_points", "scene_input_files"]


def scene_input_files(scene_path, overrides: dict | None = None) -> list[Path]:
    """The files a scene loads (meshes, envmaps, textures, included XML), without the scene itself:
    :func:`fogref.scene.inputs.scene_inputs` with ``overrides`` applied.

    Raises FogrefError naming the scene element and the file when a loaded file does not exist.
    """
    return [i.path for i in _existing_inputs(scene_path, overrides)[1:]]


def _existing_inputs(scene_path, overrides: dict | None) -> list:
    found = scene_inputs(scene_path, overrides)
    for i in found:
        if not i.exists:
            raise FogrefError(f"{i.source}: no such file {i.path}")
    return found


def _scene_inputs_digest(scene_path, overrides: dict | None = None) -> str:
    """SHA-256 over the scene XML and every file it loads (:func:`fogref.scene.inputs.inputs_digest`):
    the one place the sweep's configuration id and truth folder learn a scene's inputs."""
    return inputs_digest(scene_path, overrides, inputs=_existing_inputs(scene_path, overrides))


def _sized(spec: SweepSpec, scenes: int = 1) -> int:
    """The design's size, refused above its limit before anything is built."""
    limit = spec.design.get("max_configs", MAX_CONFIGS)
    size = design_size(spec.design["kind"], spec.parameters, spec.design.get("n"), scenes)
    if size > limit:
        raise ParameterError(
            f"{spec.path}: [design]",
            "size",
            f"the design has {size:.4g} configurations; "
            f"the limit is {limit} (raise it with [design] max_configs = N)",
        )
    return size


def design_points(spec: SweepSpec) -> list[dict]:
    """The parameter values of every configuration (one dict label -> value each).

    ``grid``: the Cartesian product of the parameters' values (the first parameter
    varies slowest); ``list``: the values zipped; ``random``: ``n`` points, uniform
    (log-uniform with ``log = true``) in each ``range`` or uniform over ``values``;
    ``lhs``: ``n`` points of a Latin hypercube (``scipy.stats.qmc.LatinHypercube``,
    seeded by ``design.seed``) mapped the same way.  No parameters: one point ``{}``.
    """
    ps = spec.parameters
    labels = list(ps)
    if not labels:
        return [{}]
    _sized(spec)
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
                pt[k] = float(
                    math.exp(math.log(lo) + x * (math.log(hi) - math.log(lo)))
                    if p["log"]
                    else lo + x * (hi - lo)
                )
            else:
                pt[k] = p["values"][min(int(x * len(p["values"])), len(p["values"]) - 1)]
        points.append(pt)
    return points


def _hash(obj, n=16) -> str:
    return hashlib.sha256(json.dumps(obj, sort_keys=True, default=str).encode()).hexdigest()[:n]


#: What a render configuration's ``id`` hashes (with fogref's version, ``budget`` when set and
#: ``perceptual`` when false).
_ID_KEYS = ("scene_sha256", "inputs_sha256", "overrides", "models", "spp", "seed", "pixel_filter")


def build_configs(spec: SweepSpec) -> list[dict]:
    """Every configuration as a self-contained, JSON-ready task description.

    Each holds ``id`` (a hash of everything the task does), the scene path, its
    content hash and the hash of every file it loads (``inputs_sha256``), the swept
    ``values``, the scene ``overrides`` (fixed + swept, strings), the models with
    their parameters, spp, seed and the truth's cache path (in a folder of the
    inputs' hash, so an edited mesh is never served an old truth).
    """
    if spec.kind == "ue_pathtracer":
        return [_closed_form_config(spec, pt) for pt in design_points(spec)]
    _sized(spec, len(spec.scenes))
    out = []
    points = design_points(spec)
    for scene in spec.scenes:
        scene_sha = file_sha256(scene)
        digests: dict = {}
        for pt in points:
            overrides = dict(spec.overrides)
            model_params = {m["label"]: dict(m["params"]) for m in spec.models}
            for label, v in pt.items():
                p = spec.parameters[label]
                value = v * p["scale"] if p["scale"] != 1.0 else v
                if p["kind"] == "scene":
                    overrides[p["target"]] = as_str(value)
                else:
                    model_params[p["model"]][p["target"]] = value
            seed = (
                spec.seed
                if spec.seed_policy == "fixed"
                else int(_hash({"seed": spec.seed, "scene": scene_sha, "overrides": overrides}, 8), 16)
                & 0x7FFFFFFF
            )
            key = json.dumps(overrides, sort_keys=True)
            if key not in digests:
                digests[key] = _scene_inputs_digest(scene, overrides)
            inputs = digests[key]
            cache = Path(spec.cache) / inputs[:16]
            truth = truth_path(
                scene, spec.spp, seed, overrides, cache_dir=cache, pixel_filter=spec.pixel_filter
            )
            models = [{**m, "params": model_params[m["label"]]} for m in spec.models]
            cfg = {
                "scene": str(scene),
                "scene_sha256": scene_sha,
                "inputs_sha256": inputs,
                "values": pt,
                "overrides": overrides,
                "models": models,
                "spp": spec.spp,
                "seed": seed,
                "pixel_filter": spec.pixel_filter,
                "truth": str(truth),
                "budget": bool(getattr(spec, "budget", False)),
                "perceptual": bool(getattr(spec, "perceptual", True)),
            }
            # a configuration's id changes with what its result holds; the defaults keep earlier ids
            budget = {"budget": True} if cfg["budget"] else {}
            perceptual = {} if cfg["perceptual"] else {"perceptual": False}
            cfg["id"] = _hash({k: cfg[k] for k in _ID_KEYS} | {"fogref": __version__} | budget | perceptual)
            out.append(cfg)
    return out


def _closed_form_config(spec: SweepSpec, point: dict) -> dict:
    """A ``ue_pathtracer`` configuration: its values, the editor values they set, ``closed_form``."""
    ps = spec.parameters
    settings = {ps[k]["target"]: v * ps[k]["scale"] if ps[k]["scale"] != 1.0 else v for k, v in point.items()}
    cf = spec.closed_form
    key = _hash({"settings": settings, "closed_form": cf, "fogref": __version__})
    return {"id": key, "values": point, "settings": settings, "closed_form": cf, "models": spec.models}
