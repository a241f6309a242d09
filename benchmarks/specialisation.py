"""Speed-ups from fogpath's trace-time specialisation.

    .venv/bin/python benchmarks/specialisation.py [--quick]

``fogpath`` decides in Python, while it traces, which code the scene needs: no sun
(no delta-emitter handling), no sky, one exponential layer instead of two (one
closed-form inversion per free flight), albedo 0 (no medium vertices at all:
transmittance only), max_depth 2 (single scattering: the loop ends after one
bounce).  This script times each specialised scene against the *general* scene,
side by side (interleaved, median of repeats, same resolution and spp), on the
two-layer benchmark scene of ``benchmarks/_scenes.py``:

general (``G``)
    two layers, the second with a tiny but non-zero density (1e-6, so the
    two-layer code runs but the image is that of one layer), sun + sky, albedo 0.9,
    max_depth 16.
specialised
    ``G`` with one feature removed.  Removing a feature changes the image (and the
    path lengths), so two more numbers are given: the time per sample per pixel,
    and, where it exists, an *inert* twin of the general scene that keeps the code
    but not the effect (sun irradiance 0, sky radiance 0, albedo 1e-6), whose image
    equals the specialised one: ``inert / specialised`` is the speed-up from the
    code alone.

Writes ``reports/benchmarks/specialisation.{json,md}``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import _scenes as S
from _common import ROOT, kernel_profile, machine_info, median, mi, np, timed_render

BASE = "two_layer"
GENERAL = dict(
    fog_over={"albedo": 0.9, "layers": [(1.0, 0.04, 0.0), (1e-6, 0.002, 200.0)]},
    max_depth=16,
    sun=True,
    sky=True,
)


def variant(**kw):
    d = {k: (dict(v) if isinstance(v, dict) else v) for k, v in GENERAL.items()}
    for k, v in kw.items():
        if k == "fog_over":
            d["fog_over"].update(v)
        else:
            d[k] = v
    return d


# (feature, specialised, inert general twin or None)
CASES = [
    ("no sun", variant(sun=False), "sun irradiance 0"),
    ("no sky", variant(sky=False), "sky radiance 0"),
    ("one layer", variant(fog_over={"layers": [(1.0, 0.04, 0.0)]}), None),  # G itself is the inert twin
    ("albedo 0", variant(fog_over={"albedo": 0.0}), "albedo 1e-6"),
    ("max_depth 2", variant(max_depth=2), None),
]


def build(cfg, res, inert=None):
    spec = S.scene_spec(BASE)
    if inert == "sun irradiance 0":
        spec["sun"] = [0.0, 0.0, 0.0]
    if inert == "sky radiance 0":
        spec["sky"] = [0.0, 0.0, 0.0]
    fog_over = dict(cfg["fog_over"])
    if inert == "albedo 1e-6":
        fog_over["albedo"] = 1e-6
    orig = S.scene_spec
    S.scene_spec = lambda name: spec
    try:
        return S.build(
            mi,
            BASE,
            "fogpath",
            res=res,
            max_depth=cfg["max_depth"],
            sun=cfg["sun"],
            sky=cfg["sky"],
            fog_over=fog_over,
        )
    finally:
        S.scene_spec = orig


def measure(scenes: dict, spp, reps, seed0):
    """Interleaved steady times (median) and mean images of several scenes."""
    names = list(scenes)
    first = {}
    for n in names:
        _, first[n] = timed_render(scenes[n], 1, seed0)
    times = {n: [] for n in names}
    imgs = {n: [] for n in names}
    for r in range(reps):
        order = names[r % len(names) :] + names[: r % len(names)]
        for n in order:
            img, t = timed_render(scenes[n], spp, seed0 + 100 * r + names.index(n) + 1)
            times[n].append(t)
            imgs[n].append(img)
    return {
        n: {
            "first_call_s": first[n],
            "times_s": times[n],
            "steady_s": median(times[n]),
            "mean": float(np.mean(imgs[n])),
        }
        for n in names
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks"))
    args = ap.parse_args(argv)
    res_px, spp, reps = ((32, 18), 16, 3) if args.quick else ((96, 54), 64, 5)
    n_samples = res_px[0] * res_px[1] * spp
    t0 = time.perf_counter()
    gen = build(GENERAL, res_px)
    rows = []
    for i, (feature, cfg, inert) in enumerate(CASES):
        scenes = {"general": gen, "specialised": build(cfg, res_px)}
        if inert:
            scenes["inert"] = build(GENERAL, res_px, inert=inert)
        m = measure(scenes, spp, reps, 1000 * (i + 1))
        prof = {n: kernel_profile(sc, spp, 4242) for n, sc in scenes.items()}
        row = {
            "feature": feature,
            "inert_twin": inert or ("general (density2 = 1e-6)" if feature == "one layer" else None),
            "spp": spp,
            "res": list(res_px),
            "repeats": reps,
        }
        for n, d in m.items():
            d["ns_per_sample_pixel"] = d["steady_s"] / n_samples * 1e9
            d["main_kernel_ops"] = prof[n]["main_kernel_ops"]
            d["main_kernel_exec_s"] = prof[n]["exec_s_main_kernel"]
            d["host_overhead_s"] = prof[n]["host_overhead_s"]
            row[n] = d
        row["speedup_vs_general"] = m["general"]["steady_s"] / m["specialised"]["steady_s"]
        if "inert" in m:
            row["speedup_code_only"] = m["inert"]["steady_s"] / m["specialised"]["steady_s"]
        elif feature == "one layer":
            row["speedup_code_only"] = row["speedup_vs_general"]
        row["image_mean_change"] = m["specialised"]["mean"] / m["general"]["mean"] - 1.0
        rows.append(row)
        print(
            f"{feature:12s} general {m['general']['steady_s']:.3f}s  specialised "
            f"{m['specialised']['steady_s']:.3f}s  x{row['speedup_vs_general']:.2f}"
            + (f"  inert {m['inert']['steady_s']:.3f}s" if "inert" in m else ""),
            flush=True,
        )
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    res = {
        "config": {
            "command": "python benchmarks/specialisation.py" + (" --quick" if args.quick else ""),
            "scene": BASE,
            "general": {k: v for k, v in GENERAL.items()},
            "res": list(res_px),
            "spp": spp,
            "repeats": reps,
            "machine": machine_info(),
            "total_s": time.perf_counter() - t0,
        },
        "cases": rows,
    }
    (out / "specialisation.json").write_text(json.dumps(res, indent=1, default=str))
    L = [
        "# fogpath trace-time specialisation: speed-ups\n",
        f"Command: `{res['config']['command']}`; scene `{BASE}` ({res_px[0]}x{res_px[1]}, {spp} spp, median "
        f"of {reps} interleaved repeats); machine: {res['config']['machine']['cpu']}, "
        f"{res['config']['machine']['cores']} shared cores.\n",
        "General scene G: two layers (second density 1e-6), sun + sky, albedo 0.9, max_depth 16. "
        "Each row removes one feature. *Inert*: G with the feature's code kept but its effect "
        "zeroed (same image as the specialised scene), so `inert / specialised` isolates the code's cost.\n",
        "| feature removed | G steady [s] | specialised [s] | speed-up vs G | inert twin | inert [s] | "
        "speed-up, code only | ns/sample/pixel G -> spec. | kernel ops G -> spec. | image mean change |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        g, s = r["general"], r["specialised"]
        it = r.get("inert")
        L.append(
            f"| {r['feature']} | {g['steady_s']:.3f} | {s['steady_s']:.3f} | "
            f"**{r['speedup_vs_general']:.2f}x** | {r['inert_twin'] or '-'} | {it['steady_s']:.3f} | "
            if it
            else f"| {r['feature']} | {g['steady_s']:.3f} | {s['steady_s']:.3f} | "
            f"**{r['speedup_vs_general']:.2f}x** | {r['inert_twin'] or '-'} | - | "
        )
        L[-1] += f"{r['speedup_code_only']:.2f}x | " if "speedup_code_only" in r else "- | "
        L[-1] += (
            f"{g['ns_per_sample_pixel']:.0f} -> {s['ns_per_sample_pixel']:.0f} | "
            f"{g['main_kernel_ops']} -> {s['main_kernel_ops']} | {r['image_mean_change']:+.1%} |"
        )
    (out / "specialisation.md").write_text("\n".join(L) + "\n")
    print(f"done in {time.perf_counter() - t0:.0f} s -> {out}", flush=True)


if __name__ == "__main__":
    main()
