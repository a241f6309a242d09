"""The sweep's design: every configuration's parameter values, and each configuration as a task.

:func:`design_points` lays the swept parameters out (grid, zipped lists, seeded
random, Latin hypercube); :func:`build_configs` turns each point of each scene
into a self-contained, JSON-ready task whose ``id`` hashes everything it does (the
scene's bytes, the overrides, the models, spp, seed, pixel filter, fogref's
version), so a finished configuration is recognised on resume.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math

import numpy as np

from fogref._version import __version__
from fogref.render.cache import truth_path
from fogref.render.render import file_sha256
from fogref.study.sweep.spec import SweepSpec, as_str

__all__ = ["build_configs", "design_points"]


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


def build_configs(spec: SweepSpec) -> list[dict]:
    """Every configuration as a self-contained, JSON-ready task description.

    Each holds ``id`` (a hash of everything the task does), the scene path and its
    content hash, the swept ``values``, the scene ``overrides`` (fixed + swept,
    strings), the models with their parameters, spp, seed and the truth's cache path.
    """
    out = []
    for scene in spec.scenes:
        scene_sha = file_sha256(scene)
        for pt in design_points(spec):
            overrides = dict(spec.overrides)
            model_params = {m["label"]: dict(m["params"]) for m in spec.models}
            for label, v in pt.items():
                p = spec.parameters[label]
                value = v * p["scale"] if p["scale"] != 1.0 else v
                if p["kind"] == "scene":
                    overrides[p["target"]] = as_str(value)
                else:
                    model_params[p["model"]][p["target"]] = value
            seed = spec.seed if spec.seed_policy == "fixed" else int(
                _hash({"seed": spec.seed, "scene": scene_sha, "overrides": overrides}, 8), 16) & 0x7FFFFFFF
            truth = truth_path(scene, spec.spp, seed, overrides, cache_dir=spec.cache,
                               pixel_filter=spec.pixel_filter)
            models = [{**m, "params": model_params[m["label"]]} for m in spec.models]
            cfg = {"scene": str(scene), "scene_sha256": scene_sha, "values": pt, "overrides": overrides,
                   "models": models, "spp": spec.spp, "seed": seed, "pixel_filter": spec.pixel_filter,
                   "truth": str(truth), "budget": bool(getattr(spec, "budget", False))}
            cfg["id"] = _hash({k: cfg[k] for k in ("scene_sha256", "overrides", "models", "spp", "seed",
                                                   "pixel_filter")} | {"fogref": __version__}
                            | ({"budget": True} if cfg["budget"] else {}))
            out.append(cfg)
    return out
