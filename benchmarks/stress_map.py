"""Sweep the stress domain on a grid; write the worst relative error per function.

    .venv/bin/python benchmarks/stress_map.py

Writes ``reports/stress/media_errors.json`` (worst relative error against mpmath
per function and back end, and the inputs where it occurs) and
``reports/stress/media_errors.png``.  Reference: the closed forms evaluated in
mpmath at 50 digits (``tests/test_media_stress.py``).  Errors are measured where
the true value lies in [1e-30, 1e30] (optical depth) / finite (distances).
"""

from __future__ import annotations

import itertools
import json
import math
import pathlib
import sys

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT))

import matplotlib  # noqa: E402

import fogref  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import mpmath as mp  # noqa: E402
from drjit.llvm import Float  # noqa: E402
from test_media_stress import mp_exp_depth, mp_exp_sample  # noqa: E402

from fogref.media import NP, ExpLayer, drjit_ops  # noqa: E402

fogref.ensure_llvm()  # Dr.Jit's LLVM back end needs LLVM >= 16; before the first array
D32 = drjit_ops(Float)
FALLOFF = [0.0, 1e-6, 1e-3, 0.1, 10.0]
HEIGHT = [-1e4, -10.0, 0.0, 50.0, 1e3, 1e6]
DY = [0.0, 1e-7, -1e-7, 0.3, -0.3, 1.0, -1.0]
DIST = [1e-4, 1.0, 1e3, 1e7, math.inf]


def run(ops, dt, b, oy, dy, t, fn):
    layer = ExpLayer(1.0, b, 0.0)
    arr = (lambda v: np.asarray(v, dt)) if ops is NP else (lambda v: Float(np.asarray(v, dt)))
    v = getattr(layer, fn)(ops, arr(oy), arr(dy), arr(t))
    return np.asarray(v.numpy() if hasattr(v, "numpy") else v, np.float64)


def main():
    b_, oy_, dy_, t_ = map(np.array, zip(*itertools.product(FALLOFF, HEIGHT, DY, DIST)))
    res = {}
    for name, ops, dt in (("float64", NP, np.float64), ("float32", D32, np.float32)):
        oy = oy_.astype(dt).astype(float)
        dy = dy_.astype(dt).astype(float)
        t = np.where(np.isinf(t_), ops.largest, t_).astype(dt).astype(float)
        # optical depth, per falloff (the layer's parameter)
        worst = {"depth": (0.0, None), "sample": (0.0, None), "sun_depth": (0.0, None)}
        nonfinite = 0
        for b in FALLOFF:
            m = b_ == b
            tau = run(ops, dt, b, oy[m], dy[m], t[m], "depth")
            nonfinite += int(np.sum(~np.isfinite(tau)))
            for i, (o, d, tt) in enumerate(zip(oy[m], dy[m], t_[m])):
                ref = mp_exp_depth(1.0, b, 0.0, o, d, tt if math.isinf(tt) else t[m][i])
                if ref != mp.inf and 1e-30 < ref < 1e30:
                    e = float(abs(tau[i] - ref) / ref)
                    if e > worst["depth"][0]:
                        worst["depth"] = (e, dict(falloff=b, oy=o, dy=d, t=tt))
            # free flight at s = half the depth (capped)
            s = np.minimum(np.where(tau > 0, 0.5 * tau, 1.0), 1e6).astype(dt).astype(float)
            ts = run(ops, dt, b, oy[m], dy[m], s, "sample")
            nonfinite += int(np.sum(~np.isfinite(ts)))
            for i, (o, d) in enumerate(zip(oy[m], dy[m])):
                ref = mp_exp_sample(1.0, b, 0.0, o, d, s[i])
                if ref != mp.inf and 1e-30 < ref < 1e30 and ts[i] < 1e37:
                    e = float(abs(ts[i] - ref) / ref)
                    if e > worst["sample"][0]:
                        worst["sample"] = (e, dict(falloff=b, oy=o, dy=d, s=s[i]))
            # sun depth: vertical and grazing sun
            for wy in (1.0, 0.05, 1e-6):
                wy32 = float(np.asarray(wy, dt))
                ts2 = run(ops, dt, b, oy[m], np.full(m.sum(), wy32), np.full(m.sum(), ops.largest), "depth")
                for i, o in enumerate(oy[m]):
                    ref = mp_exp_depth(1.0, b, 0.0, o, wy32, math.inf)
                    if ref != mp.inf and 1e-30 < ref < 1e30:
                        e = float(abs(ts2[i] - ref) / ref)
                        if e > worst["sun_depth"][0]:
                            worst["sun_depth"] = (e, dict(falloff=b, oy=o, wy=wy32))
        res[name] = {k: {"worst_rel_error": v[0], "at": v[1]} for k, v in worst.items()}
        res[name]["nonfinite_outputs"] = nonfinite
    out = ROOT / "reports" / "stress"
    out.mkdir(parents=True, exist_ok=True)
    (out / "media_errors.json").write_text(json.dumps(res, indent=2, default=float))
    fig, ax = plt.subplots(figsize=(6, 3.5))
    fns = ["depth", "sample", "sun_depth"]
    for j, name in enumerate(res):
        vals = [max(res[name][f]["worst_rel_error"], 1e-17) for f in fns]
        ax.bar(np.arange(3) + 0.4 * j, vals, 0.4, label=name)
    ax.set_yscale("log")
    ax.set_xticks(np.arange(3) + 0.2, fns)
    ax.set_ylabel("worst relative error vs mpmath")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "media_errors.png", dpi=100)
    print(json.dumps(res, indent=2, default=float))


if __name__ == "__main__":
    main()
