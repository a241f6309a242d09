"""Where a large fogpath render's time goes: one option changed at a time, timed side by side.

The default scene (``scenes/valley.xml``) at ``--case WxHxSPP`` is rendered with ``mi.render``
and a fogpath integrator made for each row (``mi.load_dict``, the scene's ``max_depth`` 16,
``pixel_exact`` on as the render driver has it, one option changed from the defaults), and
with the lanes per pass (:data:`fogref_plugins.passes.MAX_LANES`) changed.  Each row is called
once first (tracing and compile, reported apart), then the rows are timed round-robin
``--repeats`` times (median of the steady times).  Last, ``fogref.render.render.render`` of
the same case runs under cProfile once (after a warm-up call), to show where the driver's time
beyond ``mi.render`` goes on the host.

    python benchmarks/gpu_attribution.py --variant cuda_ad_rgb --case 1920x1080x64 --out DIR

Writes ``DIR/gpu_attribution.{md,json}`` and ``DIR/render_profile.txt``.  Made for a lent GPU
machine (``scripts/gpu_bench.sh``); ``--variant llvm_ad_rgb --case 64x36x4`` runs it here.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import json
import pstats
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "valley.xml"

#: row name -> (fogpath options changed from the defaults, lanes per pass or None: the back end's)
ROWS = {
    "defaults": ({}, None),
    "aovs off (radiance only)": ({"aovs": False}, None),
    "freeze off (traced each call)": ({"freeze": False}, None),
    "forced_split off": ({"forced_split": False}, None),
    "one sun-sampled segment": ({"sun_sampling_rays": 1}, None),
    "max_depth 2 (single scattering)": ({"max_depth": 2}, None),
    "lanes per pass 2^22": ({}, 1 << 22),
    "lanes per pass 2^24": ({}, 1 << 24),
    "lanes per pass 2^26": ({}, 1 << 26),
}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--variant", default="cuda_ad_rgb")
    ap.add_argument("--case", default="1920x1080x64", help="WxHxSPP")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks"))
    args = ap.parse_args(argv)
    w, h, spp = (int(x) for x in args.case.split("x"))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    import fogref

    fogref.set_variant(args.variant)
    import drjit as dr
    import mitsuba as mi
    import numpy as np
    from fogref_plugins import passes

    import fogref.render.render as R
    from fogref.render.load import load_scene

    scene, _ = load_scene(SCENE, {"res": w, "resy": h})
    backend = "cuda" if args.variant.startswith("cuda") else "llvm"
    default_lanes = passes.MAX_LANES[backend]
    integrators = {}
    for name, (opts, _) in ROWS.items():
        integrators[name] = mi.load_dict(
            {"type": "fogpath", "max_depth": 16, "pixel_exact": True, **opts}, parallel=False
        )

    def timed(name, seed):
        opts, lanes = ROWS[name]
        passes.MAX_LANES[backend] = lanes or default_lanes
        try:
            dr.flush_malloc_cache()
            t0 = time.perf_counter()
            img = np.asarray(mi.render(scene, integrator=integrators[name], spp=spp, seed=seed))
            dr.sync_thread()
            dt = time.perf_counter() - t0
        finally:
            passes.MAX_LANES[backend] = default_lanes
        if not np.isfinite(img).all():
            raise RuntimeError(f"{name}: non-finite pixels")
        return dt, float(img[..., :3].mean())

    res = {name: {"first_s": None, "steady_s": [], "mean": None} for name in ROWS}
    for name in ROWS:
        res[name]["first_s"], res[name]["mean"] = timed(name, 0)
        print(f"first  {name:34s} {res[name]['first_s']:7.2f} s", flush=True)
    for r in range(args.repeats):
        names = list(ROWS)
        names = names[r % len(names) :] + names[: r % len(names)]
        for name in names:
            dt, _ = timed(name, 1 + r)
            res[name]["steady_s"].append(dt)
            print(f"rep {r}  {name:34s} {dt:7.2f} s", flush=True)

    tmp = Path(tempfile.mkdtemp())
    kw = dict(spp=spp, seed=0, overrides={"res": w, "resy": h}, progress=False, resume=False, png=False)
    R.render(SCENE, tmp / "warm.exr", **kw)
    prof = cProfile.Profile()
    t0 = time.perf_counter()
    prof.enable()
    R.render(SCENE, tmp / "prof.exr", **kw)
    prof.disable()
    t_render = time.perf_counter() - t0
    text = io.StringIO()
    pstats.Stats(prof, stream=text).sort_stats("cumulative").print_stats(40)
    (out / "render_profile.txt").write_text(f"render() {args.case}: {t_render:.2f} s\n" + text.getvalue())

    base = statistics.median(res["defaults"]["steady_s"])
    lines = [
        f"# Where a fogpath render's time goes ({args.variant}, {w}x{h}, {spp} spp)",
        "",
        f"Command: `python {' '.join(sys.argv)}`; Mitsuba {mi.__version__}, Dr.Jit {dr.__version__}.",
        f"Lanes per pass by default: {default_lanes}. `render()` of the same case: {t_render:.2f} s "
        "(profile in render_profile.txt).",
        "",
        "| row | first call [s] | steady [s] median [min, max] | / defaults | mean RGB (linear) |",
        "|---|---|---|---|---|",
    ]
    for name, r in res.items():
        m = statistics.median(r["steady_s"])
        lines.append(
            f"| {name} | {r['first_s']:.2f} | {m:.2f} [{min(r['steady_s']):.2f}, {max(r['steady_s']):.2f}] "
            f"| {m / base:.2f}x | {r['mean']:.4f} |"
        )
    (out / "gpu_attribution.md").write_text("\n".join(lines) + "\n")
    (out / "gpu_attribution.json").write_text(
        json.dumps({"case": args.case, "rows": res, "render_s": t_render})
    )
    print("\n".join(lines))


if __name__ == "__main__":
    main()
