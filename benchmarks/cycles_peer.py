"""Blender Cycles as a measured peer: equal-error time of fogref (fogpath) vs Cycles.

    .venv/bin/python benchmarks/cycles_peer.py --quick     # ~5 min on 2 cores
    .venv/bin/python benchmarks/cycles_peer.py             # full (~30 min on 2 cores)
    .venv/bin/python benchmarks/cycles_peer.py --check     # image alignment only

An optional benchmark, not a test.  Cycles comes from PyPI's ``bpy`` (``pip install
'fogref[cycles]'``, Python 3.11); its wheel pins numpy 1.26, so it usually lives in a
venv of its own: ``--bpy-python PATH`` or ``$FOGREF_BPY_PYTHON`` names that
interpreter, which runs ``benchmarks/_cycles_worker.py`` (Blender is driven over a
pipe; this process runs Mitsuba).

Two matched 64x36 scenes (``tests/render_scenes.py``: exponential height fog
sigma_t = 0.03 exp(-0.06 y) /m, albedo 0.9, HG g = 0.5 in the box [-60, 60] x [-1, 40] x
[-60, 60] m, sun E = (2, 1.9, 1.7) W/m^2, constant sky (0.2, 0.3, 0.5), diffuse ground),
``open`` (no occluder) and ``box`` (one 8 x 12 x 8 m block).  Measured, per scene:

* a fogpath reference (``--ref-spp``, 8 chunks, its per-pixel variance subtracted);
* per renderer, a ladder of spp x repeats: RMSE against the reference vs the steady wall
  time (median over repeats; Mitsuba's first call per spp compiles, Cycles' first call
  loads and syncs: both are timed apart and kept out of the ladder);
* one-time costs: Mitsuba's scene load and first call (LLVM compile or kernel-cache
  load); Cycles' ``import bpy``, scene build, first render (device + sync + BVH +
  volume set-up) and a render without persistent data (sync + BVH every call);
* variance per sample and time per sample (slope of steady time over spp);
* Cycles' bias: the image mean of all its runs minus the reference, with the standard
  error from the spread of runs, and fogpath's own (it should be 0 within noise);
* the equal-error time ratio Cycles / fogref (> 1: fogref faster), interpolated log-log
  on the ladders at each Cycles ladder RMSE, and asymptotically from
  (time per sample x variance per sample); its noise from the spread over repeats.

Writes ``reports/benchmarks/cycles.{md,json}``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
WORKER = HERE / "_cycles_worker.py"
BASE = dict(
    origin=[0, 4, -20],
    target=[0, 6, 30],
    fov=70,
    fog=dict(sigma_t=0.03, albedo=0.9, g=0.5, layers=[(1.0, 0.06, 0.0)]),
    bounds=([-60.0, -1.0, -60.0], [60.0, 40.0, 60.0]),
    sun_dir=[-0.3, -0.45, -0.84],
    sun=[2.0, 1.9, 1.7],
    sky=[0.2, 0.3, 0.5],
    ground=(150, [0.3, 0.3, 0.25]),
    rock=[0.5, 0.4, 0.3],
    boxes=[],
    spheres=[],
)
SCENES = {"open": dict(BASE), "box": dict(BASE, boxes=[((4, 6, 4), 0, (5, 6, 25))])}
NO_BPY = (
    "cycles_peer: bpy is not installed; install it (pip install 'fogref[cycles]', Python 3.11) in a venv "
    "and pass --bpy-python PATH or set FOGREF_BPY_PYTHON."
)


def find_bpy_python(arg: str | None) -> str:
    """The first interpreter among --bpy-python, $FOGREF_BPY_PYTHON, this one that imports bpy."""
    for py in (arg, os.environ.get("FOGREF_BPY_PYTHON"), sys.executable):
        if py and subprocess.run([py, "-c", "import bpy"], capture_output=True).returncode == 0:
            return py
    raise SystemExit(NO_BPY)


class Cycles:
    """One Blender process holding one scene; ``render`` returns (rgb float64 image, wall s)."""

    def __init__(self, py, spec, res, max_depth, threads):
        self.dir = tempfile.mkdtemp(prefix="cycles_peer_")
        self.exr = os.path.join(self.dir, "out.exr")
        self.p = subprocess.Popen(
            [py, str(WORKER)], stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True
        )
        cfg = {"spec": spec, "res": list(res), "max_depth": max_depth, "threads": threads, "exr": self.exr}
        self.info = self._ask(cfg)

    def _ask(self, d):
        assert self.p.stdin and self.p.stdout
        self.p.stdin.write(json.dumps(d) + "\n")
        self.p.stdin.flush()
        for line in self.p.stdout:
            if line.startswith("@@CY "):
                return json.loads(line[5:])
        raise RuntimeError("the Cycles worker ended without answering")

    def render(self, spp, seed, persistent=True):
        from fogref.exrio import read_exr, rgb

        wall = self._ask({"spp": spp, "seed": seed, "persistent": persistent})["wall_s"]
        return rgb(read_exr(self.exr)[0]).astype("float64"), wall

    def close(self):
        if self.p.stdin:
            self.p.stdin.write('{"quit": true}\n')
            self.p.stdin.close()
        self.p.wait(timeout=60)


def mitsuba_scene(mi, S, spec, res, max_depth):
    """fogpath + heightfog (bounded), the same camera / lights / shapes (y up)."""
    T = mi.ScalarTransform4f()
    d = {
        "type": "scene",
        "integrator": {"type": "fogpath", "max_depth": max_depth},
        "sensor": {
            "type": "perspective",
            "fov": spec["fov"],
            "fov_axis": "x",
            "near_clip": 1e-4,
            "far_clip": 1e7,
            "to_world": T.look_at(origin=spec["origin"], target=spec["target"], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": res[0], "height": res[1], "rfilter": {"type": "box"}},
            "sampler": {"type": "independent"},
            "medium": mi.load_dict(S.heightfog_dict(mi, spec)),
        },
        "ground": {
            "type": "rectangle",
            "to_world": T.rotate([1, 0, 0], -90).scale(spec["ground"][0]),
            "bsdf": S._diffuse(spec["ground"][1]),
        },
        "sun": {"type": "directional", "direction": spec["sun_dir"], "irradiance": S._rgb(spec["sun"])},
        "sky": {"type": "constant", "radiance": S._rgb(spec["sky"])},
    }
    for i, (s, ang, t) in enumerate(spec["boxes"]):
        d[f"box{i}"] = {
            "type": "cube",
            "to_world": T.translate(list(t)).rotate([0, 1, 0], ang).scale(list(s)),
            "bsdf": S._diffuse(spec["rock"]),
        }
    return mi.load_dict(d, optimize=False)
