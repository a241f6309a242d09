"""Where fogpath's time goes: ablations measured side by side with stock volpath.

    .venv/bin/python benchmarks/profile_fogpath.py [--quick]

Runs, interleaved (median of repeats), on each benchmark scene at 96x54:

``fogpath``         as shipped (RGB + 20 AOV channels: T, Tsurface, single, multiple,
                    G-buffer);
``fogpath_noaov``   the same integrator with ``aovs`` false (radiance only: no
                    camera-ray transmittance, no split, no G-buffer, no extra
                    film channels);
``volpath_hf``, ``grid64``  stock volpath (see ``_scenes.py``).

and one render of each with Dr.Jit's kernel history (main-kernel execution time,
host time = Python tracing + launch, kernel operation count).  Writes
``reports/benchmarks/profile_fogpath.{json,md}``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import _scenes as S
from _common import ROOT, kernel_profile, machine_info, median, mi, np, timed_render


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks"))
    args = ap.parse_args(argv)
    res_px, spp, reps = ((32, 18), 16, 3) if args.quick else ((96, 54), 256, 3)
    t0 = time.perf_counter()
    out = {
        "config": {
            "command": "python benchmarks/profile_fogpath.py" + (" --quick" if args.quick else ""),
            "res": list(res_px),
            "spp": spp,
            "repeats": reps,
            "max_depth": 8,
            "machine": machine_info(),
        },
        "scenes": {},
    }
    for name in S.SCENES:
        sc = {
            "fogpath": S.build(mi, name, "fogpath", res=res_px),
            "fogpath_noaov": S.build(mi, name, "fogpath", res=res_px, integrator_over={"aovs": False}),
        }
        for method in ("volpath_hf", "grid64"):
            if method in S.methods_for(name):  # grids need a bounded fog
                sc[method] = S.build(mi, name, method, res=res_px)
        names = list(sc)
        first = {n: timed_render(sc[n], 1, 1)[1] for n in names}
        times = {n: [] for n in names}
        means = {n: [] for n in names}
        for r in range(reps):
            for n in names[r % len(names) :] + names[: r % len(names)]:
                img, t = timed_render(sc[n], spp, 10 + r)
                times[n].append(t)
                means[n].append(float(img.mean()))
        prof = {n: kernel_profile(sc[n], spp, 99) for n in names}
        out["scenes"][name] = {
            n: {
                "first_call_s": first[n],
                "times_s": times[n],
                "steady_s": median(times[n]),
                "ns_per_sample_pixel": median(times[n]) / (spp * res_px[0] * res_px[1]) * 1e9,
                "image_mean": float(np.mean(means[n])),
                "profile": prof[n],
            }
            for n in names
        }
        print(name, {n: round(median(times[n]), 3) for n in names}, flush=True)
    out["config"]["total_s"] = time.perf_counter() - t0
    o = Path(args.out)
    o.mkdir(parents=True, exist_ok=True)
    (o / "profile_fogpath.json").write_text(json.dumps(out, indent=1))
    L = [
        "# Where fogpath's time goes\n",
        f"Command: `{out['config']['command']}`; {res_px[0]}x{res_px[1]}, {spp} spp, max_depth 8, median of "
        f"{reps} interleaved repeats; {out['config']['machine']['cpu']}, "
        f"{out['config']['machine']['cores']} shared cores.\n",
        "| scene | method | steady [s] | ns/sample/pixel | main kernel exec [s] | host (trace+launch) [s] "
        "| kernel ops | vs fogpath |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, d in out["scenes"].items():
        base = d["fogpath"]["steady_s"]
        for n, v in d.items():
            p = v["profile"]
            L.append(
                f"| {name} | {n} | {v['steady_s']:.3f} | {v['ns_per_sample_pixel']:.0f} | "
                f"{p['exec_s_main_kernel']:.3f} | {p['host_overhead_s']:.3f} | {p['main_kernel_ops']} | "
                f"{v['steady_s'] / base:.2f} |"
            )
    (o / "profile_fogpath.md").write_text("\n".join(L) + "\n")
    print(f"done in {out['config']['total_s']:.0f} s", flush=True)


if __name__ == "__main__":
    main()
