"""Continuation splitting on the camera ray against fogpath's defaults: bias and equal-time
error of multiple scattering on the ladder's scenes.

    nice -n 19 .venv/bin/python benchmarks/ms_splitting.py --renders 32   # 96x54, 16 spp x 32 renders
    nice -n 19 .venv/bin/python benchmarks/ms_splitting.py --res 48 27    # under heavy load

The methods are ``fogpath_knobs`` (``benchmarks/_fogpath_knobs.py``) with ``ms_split``: fogpath
traces the camera ray's depth-0 stage (hit, G-buffer, the sun's sampled single scattering, the
surface's light) once per sample and then **one** continuation (a forced collision with its
light sample, the choice between the surface and the medium branch, the path from depth 1);
``split<K>`` (K = 2, 3, 4) traces ``K`` continuations per camera ray, each weighted ``1/K``;
``branch<K>`` traces ``K`` continuations and draws no branch: on a camera ray that hits a
surface one continues the surface branch (weight 1) and ``K - 1`` the medium branch (weight
``1/(K - 1)`` each; on a ray to the sky all ``K``), so the ``1/q``, ``1/(1 - q)`` weights of the
branch choice are gone (forced splitting carried on past depth 0); ``single<K>`` and
``stddev<K>`` trace ``N`` of them, ``K`` on average over the pass, at most
``4 K``, ``N - 1`` in proportion to an estimate of the continuation's contribution from the
depth-0 stage (splitting driven by the expected contribution, as in Vorba & Krivanek, "Adjoint-
driven Russian roulette and splitting in light transport simulation", ACM TOG 35(4), 2016, with
the closed-form single scattering in place of their adjoint estimate): ``single``, the camera
ray's sampled sun single scattering; ``stddev``, the continuation's standard deviation estimated
from it and the branch probability (Neyman allocation: N proportional to the standard
deviation minimises the summed variance at a fixed number of continuations;
``FogPathKnobs._split_weights``).  For each scene every method renders ``--renders`` images of
``--spp`` samples with its own seeds, interleaved (the order rotates every render), and from
their spread:

* **bias**: each method's image mean (over pixels and RGB) against fogpath's, the difference's
  z-score (standard error from the spread of the renders' means), and the chi^2 per pixel of
  the pooled images (~1 when they agree), beside the same statistic between two halves of
  fogpath's own renders;
* **variance per sample** of the final image and of its ``multiple`` part, summed over pixels
  and RGB, as ratios fogpath / method (> 1: less variance);
* **equal-time efficiency ratio** ``(var x time)_fogpath / (var x time)_method`` (> 1: the
  method reaches the same RMSE sooner), time the median wall time of a steady render, and the
  same with the median CPU time of the process (all threads; less disturbed by other processes
  on a shared machine), each with a 95 % bootstrap interval over the renders (the first render,
  which traces and compiles, is reported apart).

Writes ``reports/benchmarks/ms_splitting.{json,md}`` (atomically).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import _scenes as S
from _common import ROOT, chi2_per_pixel, dr, final_and_multiple_channels, machine_info, median, mi, np

from fogref.atomic import write_text_atomic

#: method -> fogpath_knobs parameters (fogpath: none, its defaults)
METHODS = {
    "fogpath": {},
    "split2": {"ms_split": 2},
    "split3": {"ms_split": 3},
    "split4": {"ms_split": 4},
    "branch2": {"ms_split": 2, "ms_split_by": "branch"},
    "branch3": {"ms_split": 3, "ms_split_by": "branch"},
    "single2": {"ms_split": 2, "ms_split_by": "single"},
    "stddev2": {"ms_split": 2, "ms_split_by": "stddev"},
}
BASE = "fogpath"


def _timed(scene, spp, seed, channels):
    """(float64 image of ``channels``, wall seconds, CPU seconds of this process, all its threads)
    of one ``mi.render`` with ``dr.sync_thread()`` inside the clocks.  The CPU time is the cost
    measure that other processes on a shared machine disturb least."""
    w0, c0 = time.perf_counter(), time.process_time()
    img = mi.render(scene, spp=spp, seed=seed)
    dr.eval(img)
    dr.sync_thread()
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    return np.array(img, dtype=np.float64)[..., channels], wall, cpu


def _stats(imgs, times, cpus, spp):
    """(variance per sample of final and multiple, summed over pixels and RGB; median wall time,
    median CPU time)."""
    a = np.stack(imgs)
    v = a.var(axis=0, ddof=1) * spp
    return float(v[..., :3].sum()), float(v[..., 3:].sum()), median(times), median(cpus)


def run_scene(name, args, rng):
    methods = {m: METHODS[m] for m in args.methods}
    scenes = {
        m: S.build(mi, name, "fogpath", res=args.res, max_depth=args.max_depth, integrator_over=o)
        for m, o in methods.items()
    }
    ch = final_and_multiple_channels()
    first = {}
    for m in methods:  # tracing and compilation outside the steady timings
        first[m] = _timed(scenes[m], args.spp, 7, ch)[1]
    imgs = {m: [] for m in methods}
    times = {m: [] for m in methods}
    cpus = {m: [] for m in methods}
    seed = {m: args.seed + 1000 + 100_000 * i for i, m in enumerate(methods)}
    order = list(methods)
    for r in range(args.renders):
        k = r % len(order)
        for m in order[k:] + order[:k]:
            img, t, cpu = _timed(scenes[m], args.spp, seed[m] + r, ch)
            if not np.isfinite(img).all():
                raise SystemExit(f"ms_splitting: {name}/{m} render {r} has NaN or Inf")
            imgs[m].append(img)
            times[m].append(t)
            cpus[m].append(cpu)
    out = {}
    for m in methods:
        a = np.stack(imgs[m])
        means = a[..., :3].mean(axis=(1, 2, 3))
        vf, vm, t, cpu = _stats(imgs[m], times[m], cpus[m], args.spp)
        out[m] = {
            "params": methods[m],
            "image_mean": float(means.mean()),
            "image_mean_se": float(means.std(ddof=1) / np.sqrt(len(means))),
            "var_final": vf,
            "var_multiple": vm,
            "time_s": t,
            "time_iqr_s": [float(np.percentile(times[m], 25)), float(np.percentile(times[m], 75))],
            "cpu_s": cpu,
            "cpu_iqr_s": [float(np.percentile(cpus[m], 25)), float(np.percentile(cpus[m], 75))],
            "first_render_s": first[m],
        }
    n, h = args.renders, args.renders // 2
    pa = np.stack(imgs[BASE])[..., :3]
    d = out[BASE]
    out["chi2_per_pixel_null"] = chi2_per_pixel(pa[:h], pa[h : 2 * h])
    comp = {}
    for m in methods:
        if m == BASE:
            continue
        g = out[m]
        diff = g["image_mean"] - d["image_mean"]
        se = float(np.hypot(g["image_mean_se"], d["image_mean_se"]))
        boot = []
        for _ in range(args.boot):
            ia, ib = rng.integers(0, n, n), rng.integers(0, n, n)
            sa = _stats(*[[x[BASE][i] for i in ia] for x in (imgs, times, cpus)], args.spp)
            sb = _stats(*[[x[m][i] for i in ib] for x in (imgs, times, cpus)], args.spp)
            if min(sa) > 0 and min(sb) > 0:  # a resample of one repeated render has no spread
                boot.append(
                    (
                        sa[0] * sa[2] / (sb[0] * sb[2]),
                        sa[1] / sb[1],
                        sa[0] / sb[0],
                        sa[0] * sa[3] / (sb[0] * sb[3]),
                    )
                )
        boot = np.array(boot)
        ci = lambda k: [float(np.percentile(boot[:, k], 2.5)), float(np.percentile(boot[:, k], 97.5))]  # noqa: E731,B023
        c = comp[m] = {
            "mean_diff_rel": diff / d["image_mean"],
            "z": diff / se if se > 0 else 0.0,
            "smallest_detectable_rel": 2.8 * se / d["image_mean"],
            "chi2_per_pixel": chi2_per_pixel(pa, np.stack(imgs[m])[..., :3]),
            "efficiency_ratio": d["var_final"] * d["time_s"] / (g["var_final"] * g["time_s"]),
            "efficiency_ratio_ci95": ci(0),
            "multiple_var_ratio": d["var_multiple"] / g["var_multiple"],
            "multiple_var_ratio_ci95": ci(1),
            "final_var_ratio": d["var_final"] / g["var_final"],
            "final_var_ratio_ci95": ci(2),
            "time_ratio": g["time_s"] / d["time_s"],
            "cpu_ratio": g["cpu_s"] / d["cpu_s"],
            "efficiency_ratio_cpu": d["var_final"] * d["cpu_s"] / (g["var_final"] * g["cpu_s"]),
            "efficiency_ratio_cpu_ci95": ci(3),
        }
        print(
            f"[{name}] {m}: z {c['z']:+.2f}, chi2/px {c['chi2_per_pixel']:.3f}, var final "
            f"x{c['final_var_ratio']:.3f} multiple x{c['multiple_var_ratio']:.3f}, "
            f"time x{c['time_ratio']:.3f}, "
            f"efficiency {c['efficiency_ratio']:.3f} {c['efficiency_ratio_ci95']}, cpu x{c['cpu_ratio']:.3f} "
            f"efficiency (cpu) {c['efficiency_ratio_cpu']:.3f} {c['efficiency_ratio_cpu_ci95']}",
            flush=True,
        )
    out["comparison"] = comp
    return out


def _ci(x):
    return f"[{x[0]:.3f}, {x[1]:.3f}]"


def write_md(res, args) -> str:
    m = res["machine"]
    methods = [k for k in res["scenes"][next(iter(res["scenes"]))]["comparison"]]
    lines = [
        "# Continuation splitting on the camera ray (benchmark only)",
        "",
        f"Command: `nice -n 19 .venv/bin/python benchmarks/ms_splitting.py {res['argv']}`  ",
        f"Machine: {m['cpu']}, {m['cores']} cores (shared), mitsuba {m['mitsuba']}, drjit {m['drjit']}, "
        f"`{m['variant']}`; load average (1 min) {res['load_start'][0]:.1f} at the start, "
        f"{res['load_end'][0]:.1f} at the end "
        f"(5 min: {res['load_start'][1]:.1f}, {res['load_end'][1]:.1f}).  ",
        f"Images {res['res'][0]}x{res['res'][1]}, max_depth {res['max_depth']}; per scene and method "
        f"{res['renders']} renders of {res['spp']} spp with their own seeds, the methods interleaved "
        f"(order rotated every render). Total run {res['total_s']:.0f} s.",
        "",
        "Methods (`fogpath_knobs`, `benchmarks/_fogpath_knobs.py`, `FogPathKnobs._split_sample`): the "
        "camera ray's depth-0 stage once per sample, then N continuations (forced collision, its light "
        "sample, branch choice, path from depth 1), each weighted 1/N, on a wavefront of N x the "
        "samples with a PCG32 stream each. "
        + "; ".join(f"`{k}`: `{v}`" for k, v in METHODS.items() if k in methods or k == BASE)
        + " (`branch`: no branch drawn; on a ray that hits a surface one continuation takes the surface "
        "branch at weight 1, the others the medium branch at 1/(N - 1); `ms_split_by` `single` / "
        "`stddev`: N - 1 in proportion to the camera ray's sampled sun single "
        "scattering s / to the continuation's estimated standard deviation, s sqrt((T + m) / m) on rays "
        "that hit a surface, m = albedo (1 - T); mean N = ms_split over the pass, N <= 4 ms_split).",
        "",
        "## Bias: each method against fogpath",
        "",
        "| scene | method | image mean | rel. diff | z | smallest detectable rel. diff | chi2 / pixel "
        "(fogpath halves) |",
        "|---|---|---|---|---|---|---|",
    ]
    for s, r in res["scenes"].items():
        d = r[BASE]
        lines.append(
            f"| {s} | fogpath | {d['image_mean']:.5f} ± {d['image_mean_se']:.5f} | | | | "
            f"({r['chi2_per_pixel_null']:.3f}) |"
        )
        for k in methods:
            g, c = r[k], r["comparison"][k]
            lines.append(
                f"| {s} | {k} | {g['image_mean']:.5f} ± {g['image_mean_se']:.5f} | "
                f"{c['mean_diff_rel']:+.2e} | "
                f"{c['z']:+.2f} | {c['smallest_detectable_rel']:.1e} | {c['chi2_per_pixel']:.3f} |"
            )
    lines += [
        "",
        "± is the standard error of the mean from the spread of the renders' means; |z| < 1.96 at 95 % "
        "confidence; the smallest detectable relative difference is 2.8 standard errors (95 % confidence, "
        "80 % power). chi2 / pixel = mean over pixels and RGB of (difference of the pooled means)^2 / "
        "(its variance from the spread), ~1 when the two agree (above 1 also from heavy-tailed samples); "
        "in brackets the same statistic between the two halves of fogpath's renders (no bias by "
        "construction).",
        "",
        "## Variance and equal-time efficiency",
        "",
        "| scene | method | var/sample final | var/sample multiple | final var ratio [95% CI] | multiple var "
        "ratio [95% CI] | wall [s] (IQR) | CPU [s] (IQR) | first render [s] | efficiency, wall [95% CI] "
        "| efficiency, CPU [95% CI] |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for s, r in res["scenes"].items():
        d = r[BASE]
        lines.append(
            f"| {s} | fogpath | {d['var_final']:.4g} | {d['var_multiple']:.4g} | | | {d['time_s']:.3f} "
            f"({d['time_iqr_s'][0]:.3f}-{d['time_iqr_s'][1]:.3f}) | {d['cpu_s']:.3f} "
            f"({d['cpu_iqr_s'][0]:.3f}-{d['cpu_iqr_s'][1]:.3f}) | {d['first_render_s']:.2f} | | |"
        )
        for k in methods:
            g, c = r[k], r["comparison"][k]
            lines.append(
                f"| {s} | {k} | {g['var_final']:.4g} | {g['var_multiple']:.4g} | {c['final_var_ratio']:.3f} "
                f"{_ci(c['final_var_ratio_ci95'])} | {c['multiple_var_ratio']:.3f} "
                f"{_ci(c['multiple_var_ratio_ci95'])} "
                f"| {g['time_s']:.3f} ({g['time_iqr_s'][0]:.3f}-{g['time_iqr_s'][1]:.3f}) | {g['cpu_s']:.3f} "
                f"({g['cpu_iqr_s'][0]:.3f}-{g['cpu_iqr_s'][1]:.3f}) | "
                f"{g['first_render_s']:.2f} | "
                f"{c['efficiency_ratio']:.3f} {_ci(c['efficiency_ratio_ci95'])} | "
                f"{c['efficiency_ratio_cpu']:.3f} {_ci(c['efficiency_ratio_cpu_ci95'])} |"
            )
    lines += [
        "",
        "Ratios are fogpath / method: > 1 means the method has less variance per sample (or, for the "
        "efficiency ratios, reaches the same RMSE at less cost: `(var x median time)` of fogpath over the "
        "method's, with the wall time or the process's CPU time). Variance per sample (one camera ray) "
        "summed over pixels and RGB (linear sRGB radiance, squared); wall: median wall time of one steady "
        "render [s]; CPU: median CPU time of this process (all its threads) for one render [s], the cost "
        "that other processes on the shared machine disturb least; IQR over the renders; first render: "
        "wall time with tracing and compilation (the kernel cache may hold the kernels). 95 % intervals "
        f"from {res['boot']} bootstrap resamples of the renders (the time's noise included).",
        "",
    ]
    if res.get("reading"):
        lines += ["## Verdict", "", res["reading"], ""]
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", nargs="*", default=list(S.SCENES))
    ap.add_argument("--methods", nargs="*", default=list(METHODS), choices=list(METHODS))
    ap.add_argument("--res", type=int, nargs=2, default=(96, 54), metavar=("W", "H"))
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--renders", type=int, default=32)
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--boot", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=0, help="added to every render's seed (a confirmation run)")
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks"))
    ap.add_argument("--name", default="ms_splitting")
    ap.add_argument("--reading", default=None, help="a file whose text goes under 'Verdict' in the .md")
    ap.add_argument("--from-json", default=None, help="rewrite the .md (and verdict) of this .json")
    args = ap.parse_args(argv)
    if args.renders < 4 or args.spp < 1:
        raise SystemExit(
            f"ms_splitting: --renders must be >= 4 and --spp >= 1, got {args.renders}, {args.spp}"
        )
    if BASE not in args.methods:
        args.methods.insert(0, BASE)
    out = Path(args.out)
    if args.from_json:
        res = json.loads(Path(args.from_json).read_text())
    else:
        rng = np.random.default_rng(0)
        t0, load0 = time.perf_counter(), os.getloadavg()
        res = {
            "machine": machine_info(),
            "argv": " ".join(sys.argv[1:]),
            "load_start": list(load0),
            "res": list(args.res),
            "spp": args.spp,
            "renders": args.renders,
            "max_depth": args.max_depth,
            "boot": args.boot,
            "scenes": {},
        }
        for s in args.scenes:
            res["scenes"][s] = run_scene(s, args, rng)
        res["load_end"], res["total_s"] = list(os.getloadavg()), time.perf_counter() - t0
    if args.reading:
        res["reading"] = Path(args.reading).read_text().strip()
    write_text_atomic(out / f"{args.name}.json", json.dumps(res, indent=1) + "\n")
    write_text_atomic(out / f"{args.name}.md", write_md(res, args))


if __name__ == "__main__":
    main()
