"""Trustworthy numbers, measured: the figures behind the ground truth's guarantees.

Writes ``reports/validation/README.md`` and ``validation.json``:

1. **Image-mean bias** of fogpath, with 95 % confidence intervals from the spread
   of independent renders: the white furnace (exact answer 1) in bounded fog,
   and fogpath against stock ``volpath`` (own seeds) on the bounded, zero-falloff
   fog where the box-clipping bug made fogpath 0.25 % dark (sky only: 0.44 %).
2. **Opaque horizon**: ``surface``, its coverage and Unreal's composite at
   FogMaxOpacity 0.9 on a scene whose fog is opaque toward the horizon.
3. **Exact geometry**: Unreal's transmittance (exact extinction mapping) against
   ``T`` at every pixel of the default scene, silhouettes included; ``T`` from the
   camera origin against a float64 formula; the farthest surface hit.

Run: ``.venv/bin/python benchmarks/validation_report.py [--quick]`` (about 10 min on 2 cores).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))


def ci95(x):
    x = np.asarray(x, dtype=np.float64)
    se = x.std(ddof=1) / np.sqrt(len(x))
    return float(x.mean()), float(1.96 * se)


def bias_section(mi, runs: int) -> dict:
    from render_scenes import base_scene, heightfog
    from stats import image_means
    from test_render_bias import CASES, OCCLUDED_ON, furnace

    out = {"furnace": {}, "stock": {}}
    for i, (case, (origin, fog, _)) in enumerate(CASES.items()):
        scene = furnace(mi, origin, fog, **OCCLUDED_ON.get(case, {}))
        m = image_means(mi, scene, n_runs=runs, spp=512, seed0=9000 + 1000 * i)
        mean, half = ci95(m - 1.0)
        out["furnace"][case] = {"bias": mean, "ci95": half, "runs": runs, "spp": 512, "pixels": "16x12"}
    for label, sun in (("sun + sky", True), ("sky only", False)):
        means = {}
        for integ, seed0 in (("fogpath", 20000), ("volpath", 40000)):
            d = base_scene(
                mi,
                {"type": integ, "max_depth": 8, "rr_depth": 100},
                heightfog(mi, falloff=0.0),
                res=(16, 12),
                sun=sun,
            )
            if integ == "fogpath":
                d["integrator"]["aovs"] = False
            means[integ] = image_means(
                mi, mi.load_dict(d, parallel=False), n_runs=runs, spp=1024, seed0=seed0
            )
        a, b = means["fogpath"], means["volpath"]
        diff = a.mean() / b.mean() - 1
        se = np.sqrt(a.var(ddof=1) / len(a) + b.var(ddof=1) / len(b)) / b.mean()
        out["stock"][label] = {
            "fogpath_vs_volpath": float(diff),
            "ci95": float(1.96 * se),
            "runs": runs,
            "spp": 1024,
            "pixels": "16x12",
        }
    return out


def opaque_section(tmp: Path) -> dict:
    from fogref.compare import compare
    from fogref.gbuffer import load_truth
    from fogref.mapping import PhysicalScene, from_physical
    from fogref.render.render import render

    exr = render(
        ROOT / "scenes/open_plane.xml",
        tmp / "opaque.exr",
        spp=16,
        progress=False,
        png=False,
        overrides={"res": 64, "resy": 36, "sigma_t": 0.02, "falloff": 0.05},
    )
    t = load_truth(exr)
    model = from_physical("ue4", PhysicalScene.from_params(t.params))
    model = type(model)(dataclasses.replace(model.params, FogMaxOpacity=0.9))
    rep = compare(exr, model, tmp / "opaque_report", figures=False)
    final = rep["metrics"]["final"]["all"]
    return {
        "T_min": float(t.transmittance.min()),
        "surface_max": float(t.surface.max()),
        "surface_min": float(t.surface.min()),
        "undefined_pixels": int((~t.surface_valid).sum()),
        "pixels": int(t.surface_valid.size),
        "ue4_maxopacity_0.9_final_rmse": final.get("rmse"),
        "ue4_final_rmse_noise_floor": final.get("rmse_noise_floor"),
    }


def geometry_section(tmp: Path, valley_exr: Path | None) -> dict:
    from test_render_camera import exp_layer_depth, pinhole

    from fogref.gbuffer import load_truth
    from fogref.mapping import PhysicalScene, from_physical
    from fogref.render.render import render

    if valley_exr is None:
        valley_exr = render(ROOT / "scenes/valley.xml", tmp / "valley.exr", spp=4, progress=False, png=False)
    v = load_truth(valley_exr)
    model = from_physical("ue4", PhysicalScene.from_params(v.params))
    res = model.evaluate(v.camera, v.world_positions(1e5), precision="float64")
    dT = np.abs(np.broadcast_to(np.asarray(res.transmittance), v.transmittance.shape) - v.transmittance)
    edge = np.zeros_like(v.hit)
    edge[:, 1:] |= v.hit[:, 1:] != v.hit[:, :-1]
    edge[1:, :] |= v.hit[1:, :] != v.hit[:-1, :]
    med = v.params["medium"]
    D = np.where(v.hit, v.distance, np.inf)
    T64 = np.exp(
        -float(med["sigma_t"])
        * exp_layer_depth(
            v.camera[1], v.view[..., 1], D, float(med["falloff"]), float(med.get("height", 0.0))
        )
    )
    rel = np.abs(v.transmittance[..., 1] - T64) / np.maximum(T64, 1e-30)
    far = render(
        ROOT / "scenes/open_plane.xml",
        tmp / "far.exr",
        spp=1,
        progress=False,
        png=False,
        overrides={"res": 64, "resy": 36, "camera_origin": "0, 300, 0", "camera_target": "0.3, 299.9, 1"},
    )
    f = load_truth(far)
    d = pinhole([0, 300, 0], [0.3, 299.9, 1], [0, 1, 0], 90, 64, 36)
    return {
        "valley": str(valley_exr),
        "valley_spp": v.spp,
        "ue4_T_max_abs_error_surface": float(dT[v.hit].max()),
        "ue4_T_max_abs_error_silhouettes": float(dT[edge & v.hit].max()),
        "ue4_T_rmse_all": float(np.sqrt((dT**2).mean())),
        "silhouette_pixels": int(edge.sum()),
        "T_vs_float64_max_rel_error": float(rel[T64 > 1e-6].max()),
        "farthest_hit_m": float(f.distance[f.hit].max()),
        "view_vs_pinhole_max": float(np.abs(f.view - d).max()),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="fewer renders (for a smoke run)")
    ap.add_argument("--valley", default=None, help="a default-scene truth to check (default: render one)")
    ap.add_argument("--out", default=str(ROOT / "reports/validation"))
    a = ap.parse_args(argv)
    import fogref

    fogref.set_variant("llvm_ad_rgb")
    import mitsuba as mi

    t0 = time.time()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        result = {
            "bias": bias_section(mi, 12 if a.quick else 90),
            "opaque_horizon": opaque_section(tmp),
            "geometry": geometry_section(tmp, Path(a.valley) if a.valley else None),
            "command": "python benchmarks/validation_report.py" + (" --quick" if a.quick else ""),
            "seconds": time.time() - t0,
        }
    from fogref.atomic import write_text_atomic

    out = Path(a.out)
    write_text_atomic(out / "validation.json", json.dumps(result, indent=2))
    write_text_atomic(out / "README.md", markdown(result))
    print(markdown(result))
    return 0


def markdown(r: dict) -> str:
    b, o, g = r["bias"], r["opaque_horizon"], r["geometry"]
    lines = [
        "# Validation: the numbers behind the ground truth",
        "",
        f"Made by `{r['command']}` ({r['seconds'] / 60:.1f} min on a 2-core CPU).",
        "",
        "## Image-mean bias (95 % confidence intervals from the spread of independent renders)",
        "",
        "| oracle | case | relative bias | renders x spp |",
        "|---|---|---|---|",
    ]
    for case, v in b["furnace"].items():
        lines.append(
            f"| white furnace (exact 1) | {case} | {v['bias']:+.4%} ± {v['ci95']:.4%} | "
            f"{v['runs']} x {v['spp']} |"
        )
    for case, v in b["stock"].items():
        lines.append(
            f"| stock volpath + heightfog (own seeds) | bounded, zero falloff, {case} | "
            f"{v['fogpath_vs_volpath']:+.4%} ± {v['ci95']:.4%} | {v['runs']} x {v['spp']} each |"
        )
    lines += [
        "",
        "Before the fix the same furnace cases were 1.2 % (camera inside the box) and 31 % (outside) "
        "dark, and fogpath was 0.23-0.25 % darker than volpath on the bounded scene (0.44 % sky only).",
        "",
        "## Opaque fog toward the horizon (open plane, sigma_t 0.02 /m, falloff 0.05 /m, 64x36, 16 spp)",
        "",
        f"* smallest T: {o['T_min']:.3g}; `surface` in [{o['surface_min']:.3g}, {o['surface_max']:.3g}] "
        f"(bounded by the sky and the sunlit ground); undefined (no sample reached it) at "
        f"{o['undefined_pixels']} of {o['pixels']} pixels, excluded from composites and counted.",
        f"* Unreal composited at FogMaxOpacity 0.9: final RMSE {o['ue4_maxopacity_0.9_final_rmse']:.4g} "
        f"(noise floor {o['ue4_final_rmse_noise_floor']:.2g}); it was 3.8e19 when surface = Tsurface/T.",
        "",
        "## Exact geometry (pixel-exact truth)",
        "",
        "* Unreal's transmittance with the exact extinction mapping vs `T`, default scene "
        f"({g['valley_spp']} spp): max |ΔT| {g['ue4_T_max_abs_error_surface']:.2g} over surface pixels, "
        f"{g['ue4_T_max_abs_error_silhouettes']:.2g} on the {g['silhouette_pixels']} silhouette pixels, "
        f"RMSE {g['ue4_T_rmse_all']:.2g} over all pixels (was 0.0077, max 0.12, box-filtered).",
        f"* `T` from the camera origin vs an independent float64 formula: max relative error "
        f"{g['T_vs_float64_max_rel_error']:.2g} (the near clip cost 7e-5 on the two-layer scene).",
        f"* Farthest surface hit: {g['farthest_hit_m'] / 1000:.1f} km (Mitsuba's far clip stopped at 10 km); "
        f"view directions vs a float64 pinhole: {g['view_vs_pinhole_max']:.1g}.",
        "",
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    raise SystemExit(main())
