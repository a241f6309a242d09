"""Sun-guided phase sampling at medium vertices against fogpath's defaults: bias and
equal-time error on the ladder's scenes.

    .venv/bin/python benchmarks/sun_guiding.py --renders 32    # 96x54, 16 spp x 32 renders each, share 0.25
    .venv/bin/python benchmarks/sun_guiding.py --res 48 27     # under heavy load

``fogpath_guided`` is ``fogpath_knobs`` (``benchmarks/_fogpath_knobs.py``) with
``sun_guiding = --share``: the phase sample at every medium vertex is drawn from a mixture of
the fog's phase function and a Henyey-Greenstein lobe around the direction toward the sun,
weighted by ``f / p_mix`` (its pdf, ``p_mix``, also in the MIS weights).  For each scene the two
methods render ``--renders`` images of ``--spp`` samples each with their own seeds,
interleaved (the order alternates every render), and from the spread of those images:

* **bias**: the image means (over pixels and RGB) of the two methods, their difference and its
  z-score with the standard error from the spread of the renders' means; and the chi^2 per
  pixel of the two pooled images (~1 when they agree within noise);
* **variance per sample** of the final image and of its ``multiple`` part, summed over pixels
  and RGB;
* **equal-time efficiency ratio** ``(var x time)_fogpath / (var x time)_guided`` (> 1: the
  guided sampler reaches the same RMSE in less time), time the median wall time of a render,
  with a 95 % bootstrap interval over the renders.

Writes ``reports/benchmarks/sun_guiding.{json,md}``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import _scenes as S
from _common import (
    ROOT,
    chi2_per_pixel,
    final_and_multiple_channels,
    machine_info,
    median,
    mi,
    np,
    timed_render,
)

#: The method compared with fogpath's defaults: its label in the tables and JSON, a title, a
#: description for the report, and its ``fogpath_knobs`` parameters from the arguments (and
#: optionally ``baseline``: fogpath's parameters in the column ``fogpath``, default none, and
#: ``note``: a remark on each scene from its loaded baseline scene, shown beside its name).
#: ``benchmarks/sky_residual.py`` passes its own.
SUN_GUIDING = {
    "label": "fogpath_guided",
    "short": "guided",
    "title": "Sun-guided phase sampling at medium vertices (benchmark only)",
    "describe": lambda args: (
        f"lobe share {args.share}, lobe g = the fog's g (at least 0.5).",
        "`fogpath_guided`: the phase sample at every medium vertex drawn from `(1 - s) p_HG + s p_lobe`, "
        "`p_lobe` a Henyey-Greenstein lobe around the direction toward the sun, weight `f / p_mix`, "
        "`p_mix` also in the MIS weights against the sky (`benchmarks/_fogpath_knobs.py`, "
        "`SunGuidedPhase`).",
    ),
    "knobs": lambda args: {"sun_guiding": args.share},
}


def _stats(imgs, times, spp):
    """(variance per sample of final and multiple, summed over pixels and RGB; median time)."""
    a = np.stack(imgs)
    v = a.var(axis=0, ddof=1) * spp
    return float(v[..., :3].sum()), float(v[..., 3:].sum()), median(times)


def run_scene(name, args, rng, method=SUN_GUIDING):
    """fogpath against ``method`` (:data:`SUN_GUIDING`'s form) on the scene ``name``."""
    label = method["label"]
    methods = {"fogpath": method.get("baseline", {}), label: method["knobs"](args)}
    scenes = {
        m: S.build(mi, name, "fogpath", res=args.res, max_depth=args.max_depth, integrator_over=o)
        for m, o in methods.items()
    }
    ch = final_and_multiple_channels()
    for m in methods:  # tracing and compilation outside the timings
        timed_render(scenes[m], args.spp, 7, ch)
    imgs = {m: [] for m in methods}
    times = {m: [] for m in methods}
    seed = {"fogpath": 1000, label: 500_000}
    for r in range(args.renders):
        for m in list(methods)[:: 1 if r % 2 == 0 else -1]:
            img, t = timed_render(scenes[m], args.spp, seed[m] + r, ch)
            imgs[m].append(img)
            times[m].append(t)
    out = {}
    if "note" in method:  # a remark on the scene, from its baseline scene
        out["note"] = method["note"](scenes["fogpath"])
    for m in methods:
        a = np.stack(imgs[m])
        means = a[..., :3].mean(axis=(1, 2, 3))
        vf, vm, t = _stats(imgs[m], times[m], args.spp)
        out[m] = {
            "image_mean": float(means.mean()),
            "image_mean_se": float(means.std(ddof=1) / np.sqrt(len(means))),
            "var_final": vf,
            "var_multiple": vm,
            "time_s": t,
            "time_iqr_s": [float(np.percentile(times[m], 25)), float(np.percentile(times[m], 75))],
        }
    d, g = out["fogpath"], out[label]
    diff = g["image_mean"] - d["image_mean"]
    se = float(np.hypot(g["image_mean_se"], d["image_mean_se"]))
    pa, pb = np.stack(imgs["fogpath"])[..., :3], np.stack(imgs[label])[..., :3]
    n = args.renders
    chi2 = chi2_per_pixel(pa, pb)
    h = n // 2  # the same statistic between the two halves of one method's renders: its value without bias
    chi2_null = [chi2_per_pixel(x[:h], x[h : 2 * h]) for x in (pa, pb)]
    boot = []
    for _ in range(args.boot):
        ia, ib = rng.integers(0, n, n), rng.integers(0, n, n)
        a, b = "fogpath", label
        sa = _stats([imgs[a][i] for i in ia], [times[a][i] for i in ia], args.spp)
        sb = _stats([imgs[b][i] for i in ib], [times[b][i] for i in ib], args.spp)
        boot.append((sa[0] * sa[2] / (sb[0] * sb[2]), sa[1] / sb[1], sa[0] / sb[0]))
    boot = np.array(boot)
    ci = lambda k: [float(np.percentile(boot[:, k], 2.5)), float(np.percentile(boot[:, k], 97.5))]  # noqa: E731
    out["comparison"] = {
        "mean_diff_rel": diff / d["image_mean"],
        "z": diff / se if se > 0 else 0.0,
        "chi2_per_pixel": chi2,
        "chi2_per_pixel_null": chi2_null,
        "efficiency_ratio": d["var_final"] * d["time_s"] / (g["var_final"] * g["time_s"]),
        "efficiency_ratio_ci95": ci(0),
        "multiple_var_ratio": d["var_multiple"] / g["var_multiple"],
        "multiple_var_ratio_ci95": ci(1),
        "final_var_ratio": d["var_final"] / g["var_final"],
        "final_var_ratio_ci95": ci(2),
        "time_ratio": g["time_s"] / d["time_s"],
    }
    c = out["comparison"]
    print(
        f"[{name}] z {c['z']:+.2f}, chi2/px {chi2:.3f}, var final x{c['final_var_ratio']:.3f} "
        f"multiple x{c['multiple_var_ratio']:.3f}, time x{c['time_ratio']:.3f}, "
        f"efficiency {c['efficiency_ratio']:.3f} {c['efficiency_ratio_ci95']}",
        flush=True,
    )
    return out


def write_md(res, args, method=SUN_GUIDING, script="sun_guiding.py") -> str:
    m = res["machine"]
    label, short = method["label"], method["short"]
    settings, description = method["describe"](args)
    null = all("chi2_per_pixel_null" in r["comparison"] for r in res["scenes"].values())
    lines = [
        f"# {method['title']}",
        "",
        f"Command: `python benchmarks/{script} {res['argv']}`  ",
        f"Machine: {m['cpu']}, {m['cores']} cores (shared), mitsuba {m['mitsuba']}, drjit {m['drjit']}, "
        f"`{m['variant']}`; load average (1 min) {res['load_start'][0]:.1f} at the start, "
        f"{res['load_end'][0]:.1f} at the end "
        f"(5 min: {res['load_start'][1]:.1f}, {res['load_end'][1]:.1f}).  ",
        f"Images {args.res[0]}x{args.res[1]}, max_depth {args.max_depth}; per scene and method "
        f"{args.renders} renders of {args.spp} spp with their own seeds, the two methods interleaved; "
        f"{settings} Total run {res['total_s']:.0f} s.",
        "",
        description,
        "",
        f"## Bias: {short} against fogpath",
        "",
        f"| scene | image mean fogpath | image mean {short} | rel. diff | z | smallest detectable rel. diff "
        "| chi2 / pixel |" + (f" the same, halves of fogpath / of {short} |" if null else ""),
        "|---|---|---|---|---|---|---|" + ("---|" if null else ""),
    ]
    for s, r in res["scenes"].items():
        d, g, c = r["fogpath"], r[label], r["comparison"]
        lines.append(
            f"| {s} | {d['image_mean']:.5f} ± {d['image_mean_se']:.5f} | {g['image_mean']:.5f} ± "
            f"{g['image_mean_se']:.5f} | {c['mean_diff_rel']:+.2e} | {c['z']:+.2f} | "
            f"{2.8 * np.hypot(d['image_mean_se'], g['image_mean_se']) / d['image_mean']:.1e} | "
            f"{c['chi2_per_pixel']:.3f} |"
            + (" " + " / ".join(f"{x:.3f}" for x in c["chi2_per_pixel_null"]) + " |" if null else "")
        )
    lines += [
        "",
        "± is the standard error of the mean from the spread of the renders' means; |z| < 1.96 at 95 % "
        "confidence; the smallest detectable relative difference is 2.8 standard errors (95 % confidence, "
        "80 % power). chi2 / pixel = mean over pixels and RGB of (difference of the pooled means)^2 / "
        "(its variance from the spread), ~1 when the two agree (above 1 also from heavy-tailed samples)"
        + (
            "; the last column is the same statistic between the two halves of one method's renders "
            "(no bias by construction)."
            if null
            else "."
        ),
        "",
        "## Variance and equal-time efficiency",
        "",
        f"| scene | var/sample fogpath | var/sample {short} | final var ratio [95% CI] | multiple var ratio "
        f"[95% CI] | time fogpath [s] (IQR) | time {short} [s] (IQR) | efficiency ratio [95% CI] |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for s, r in res["scenes"].items():
        d, g, c = r["fogpath"], r[label], r["comparison"]
        f = lambda k: f"{c[k]:.3f} [{c[k + '_ci95'][0]:.3f}, {c[k + '_ci95'][1]:.3f}]"  # noqa: E731
        t = lambda r: f"{r['time_s']:.3f} ({r['time_iqr_s'][0]:.3f}-{r['time_iqr_s'][1]:.3f})"  # noqa: E731
        lines.append(
            f"| {s}{' (' + r['note'] + ')' if r.get('note') else ''} | {d['var_final']:.4g} | "
            f"{g['var_final']:.4g} | {f('final_var_ratio')} | "
            f"{f('multiple_var_ratio')} | {t(d)} | {t(g)} | {f('efficiency_ratio')} |"
        )
    lines += [
        "",
        f"Ratios are fogpath / {short}: > 1 means {short} has less variance (or, for the "
        "efficiency ratio, reaches the same RMSE in less time: `(var x median time)` of fogpath over that "
        f"of {short}). Variance per sample summed over pixels and RGB; 95 % intervals from "
        f"{args.boot} bootstrap resamples of the renders (the time's noise included).",
        "",
    ]
    if res.get("reading"):
        lines += ["## Verdict", "", res["reading"], ""]
    return "\n".join(lines)


def main(
    argv=None, method=SUN_GUIDING, script="sun_guiding.py", name="sun_guiding", doc=None, scenes=S.SCENES
):
    """The command line of this benchmark, or (``method``, ``script``, ``name``, ``doc``, the
    default ``scenes``) of another method's (``benchmarks/sky_residual.py``)."""
    ap = argparse.ArgumentParser(description=(doc or __doc__).split("\n\n")[0])
    ap.add_argument("--scenes", nargs="*", default=list(scenes))
    ap.add_argument("--res", type=int, nargs=2, default=(96, 54), metavar=("W", "H"))
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--renders", type=int, default=32)
    ap.add_argument("--share", type=float, default=0.25)
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--boot", type=int, default=1000)
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks"))
    ap.add_argument("--name", default=name)
    ap.add_argument("--reading", default=None, help="a file whose text goes under 'Verdict' in the .md")
    ap.add_argument("--from-json", default=None, help="rewrite the .md of this run's .json (same arguments)")
    args = ap.parse_args(argv)
    args.res = tuple(args.res)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.from_json:
        res = json.loads(Path(args.from_json).read_text())
        if args.reading:
            res["reading"] = Path(args.reading).read_text().strip()
        (out / f"{args.name}.json").write_text(json.dumps(res, indent=1))
        (out / f"{args.name}.md").write_text(write_md(res, args, method, script))
        return
    rng = np.random.default_rng(0)
    t0, load0 = time.perf_counter(), os.getloadavg()
    res = {"machine": machine_info(), "argv": " ".join(sys.argv[1:]), "load_start": list(load0), "scenes": {}}
    for s in args.scenes:
        res["scenes"][s] = run_scene(s, args, rng, method)
    res["load_end"], res["total_s"] = list(os.getloadavg()), time.perf_counter() - t0
    if args.reading:
        res["reading"] = Path(args.reading).read_text().strip()
    (out / f"{args.name}.json").write_text(json.dumps(res, indent=1))
    (out / f"{args.name}.md").write_text(write_md(res, args, method, script))


if __name__ == "__main__":
    main()
