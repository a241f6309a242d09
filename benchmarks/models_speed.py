"""Game-model evaluation time on a 1920x1080 G-buffer, and the Unreal model's
specialisations (directional inscattering off, second layer off) against its
general path, side by side.  Writes reports/benchmarks/models_speed.{json,md}.

    python benchmarks/models_speed.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import statistics
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def gbuffer(w=1920, h=1080, seed=0):
    """Camera at 2 m; points on a ground plane and on the sky dome (SKY_DISTANCE), y-up metres."""
    from fogref.models.base import SKY_DISTANCE

    rng = np.random.default_rng(seed)
    cam = np.array([0.0, 2.0, 0.0])
    az = rng.uniform(-0.6, 0.6, (h, w))
    el = np.linspace(0.35, -0.3, h)[:, None] + rng.normal(0, 1e-3, (h, w))
    d = np.stack([np.sin(az) * np.cos(el), np.sin(el), np.cos(az) * np.cos(el)], -1)
    t = np.where(d[..., 1] < -1e-3, -cam[1] / np.minimum(d[..., 1], -1e-3), SKY_DISTANCE)
    return cam, cam + d * t[..., None]


def timeit(fn, repeats):
    fn()  # warm-up
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts)


def main():
    from fogref.models import get
    from fogref.models.ue4 import SecondFogData

    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args()
    cam, wp = gbuffer()
    out = {"gbuffer": [1920, 1080], "repeats": a.repeats, "models": {}, "ue4_specialisations": {}}
    for name in ("ue4", "unity", "altitude", "box", "hdrp", "filament"):
        cls = get(name)
        m = cls()
        for prec in ("float32", "float64"):
            out["models"][f"{name}/{prec}"] = timeit(lambda: m.evaluate(cam, wp, prec), a.repeats)
    U = get("ue4")
    base = U.Params()
    general = dataclasses.replace(
        base, SecondFogData=SecondFogData(FogDensity=0.01, FogHeightFalloff=0.1, FogHeightOffset=500.0)
    ).with_sun([0.4, 0.14, 0.9])
    variants = {
        "general (2 layers + directional)": general,
        "directional off": dataclasses.replace(general, InscatteringLightDirection=None),
        "second layer off": dataclasses.replace(general, SecondFogData=SecondFogData(FogDensity=0.0)),
        "both off": dataclasses.replace(
            general, InscatteringLightDirection=None, SecondFogData=SecondFogData(FogDensity=0.0)
        ),
    }
    for prec in ("float32", "float64"):
        times = {k: [] for k in variants}
        for _ in range(a.repeats):  # interleaved
            for k, p in variants.items():
                m = U(p)
                t0 = time.perf_counter()
                m.evaluate(cam, wp, prec)
                times[k].append(time.perf_counter() - t0)
        g = statistics.median(times["general (2 layers + directional)"])
        out["ue4_specialisations"][prec] = {
            k: {"seconds": statistics.median(v), "speedup": g / statistics.median(v)}
            for k, v in times.items()
        }
    d = ROOT / "reports" / "benchmarks"
    d.mkdir(parents=True, exist_ok=True)
    (d / "models_speed.json").write_text(json.dumps(out, indent=2))
    lines = [
        "# Game-model speed (1920x1080 G-buffer, numpy, median of runs)",
        "",
        "| model | float32 [s] | float64 [s] |",
        "|---|---|---|",
    ]
    for name in ("ue4", "unity", "altitude", "box", "hdrp", "filament"):
        lines.append(
            f"| {name} | {out['models'][name + '/float32']:.3f} | {out['models'][name + '/float64']:.3f} |"
        )
    lines += [
        "",
        "## Unreal specialisations (interleaved, same G-buffer)",
        "",
        "| variant | float32 [s] | speed-up | float64 [s] | speed-up |",
        "|---|---|---|---|---|",
    ]
    for k in variants:
        a32, a64 = out["ue4_specialisations"]["float32"][k], out["ue4_specialisations"]["float64"][k]
        lines.append(
            f"| {k} | {a32['seconds']:.3f} | {a32['speedup']:.2f}x | {a64['seconds']:.3f} | "
            f"{a64['speedup']:.2f}x |"
        )
    (d / "models_speed.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
