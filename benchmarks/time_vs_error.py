"""Time vs error: fogpath against stock Mitsuba on bounded height-fog scenes.

    .venv/bin/python benchmarks/time_vs_error.py            # full (~10-15 min, 2 cores)
    .venv/bin/python benchmarks/time_vs_error.py --quick    # tiny images, spp <= 64

For every scene in ``benchmarks/_scenes.py`` and every method that applies, render
a ladder of sample counts (1, 4, 16, 64, 256, 1024) and record

* the RMSE against a converged ``fogpath`` reference (``--ref-spp``, rendered in 8
  independent chunks so that its own per-pixel variance is known and subtracted:
  ``MSE = mean((img - ref)^2) - mean(Var[ref])``);
* the wall time: the first call (tracing + compilation, or the kernel-cache load)
  apart from the steady time (median of repeated calls, ``dr.sync_thread()`` before
  the clock stops).  Methods are interleaved round-robin so that load from other
  processes on the machine falls on all of them alike.

All the ladder renders of a method (independent seeds) are pooled into one
"converged" image of N = sum(spp) samples whose per-pixel variance is estimated
from the spread of the ladder images (``s^2 = sum n_i (X_i - X)^2 / (k - 1)``).  Its
**bias** against the reference is ``b^2 = mean((X - ref)^2 - s^2/N - Var[ref])``,
with a bootstrap (over pixels) 95% interval; the **noise** at each spp is the rest,
``sqrt(MSE - b^2)``.

The **equal-error time ratio** of a method at one of its ladder points is its steady
time divided by the time fogpath needs for the same RMSE (linear interpolation of
log time against log RMSE on fogpath's ladder; beyond fogpath's ladder, t ~ RMSE^-2
toward low error and fogpath's 1-spp time toward high error).  > 1 means fogpath
is faster.

Writes ``reports/benchmarks/time_vs_error.{json,csv,png}`` and ``summary.md``.

``--reference-from PREVIOUS.json`` re-times a ladder without recomputing its errors: every
render is seeded, so with unchanged code a ladder image, and the reference, are bitwise
those of the previous run.  The reference render and the variance shares are skipped and the
errors (MSE, RMSE, noise, bias) are read from the previous run's JSON (same image size,
ladder, repeats, reference spp, max_depth and methods, or a one-line error); the ladder,
first calls and kernel profiles are rendered and timed afresh, methods interleaved as
without it.  The scenes named by ``--verify`` (default: the first) still render their
reference and compute every error afresh, and the JSON and summary give the largest
relative difference between fresh and stored ``mse_raw`` (0 when the code is unchanged).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import _scenes as S
from _common import (  # noqa: F401
    ROOT,
    dr,
    kernel_profile,
    machine_info,
    median,
    mi,
    np,
    part_variances,
    timed_render,
    warm_ladder,
)

LADDER = (1, 4, 16, 64, 256, 1024)
REPEATS = {1: 5, 4: 5, 16: 5, 64: 3, 256: 2, 1024: 1}
LABEL = {
    "fogpath": "fogpath (analytic)",
    "fogpath_before": "fogpath, earlier sampling (1 sun sample, no split)",
    "fogpath_split": "fogpath, forced splitting on",
    "fogpath_nosplit": "fogpath, forced splitting off",
    "fogpath_prev": "fogpath, MIS sky at surfaces, 1 sun segment",
    "volpath_hf": "volpath + heightfog (delta tracking)",
    "grid64": "volpath + heterogeneous 1x64x1",
    "grid256": "volpath + heterogeneous 1x256x1",
    "homogeneous": "volpath + homogeneous (null cube)",
}


#: R,G,B then inscatter.R,G,B in a fogpath render (mi.render: R,G,B + AOVs)
def _insc_channels():
    from fogref import gbuffer

    names = gbuffer.sample_channel_names()
    return [0, 1, 2] + [3 + names.index(f"inscatter.{c}") for c in "RGB"]


def variance_shares(scene, spp=64, seeds=(31, 32)):
    """Per-pixel variance of one sample of each part, summed over pixels and RGB, as a
    share of the final image's (the parts are correlated: shares need not add to 1)."""
    acc = part_variances(scene, spp, seeds)
    tot = float(np.mean(acc["final"]))
    out = {
        g: float(np.mean(v)) / tot
        for g, v in acc.items()
        if g in ("attenuated_surface", "inscatter", "single", "multiple")
    }
    out["final_variance_per_sample"] = tot
    return out


def rel(x, ref_mean):
    return x / ref_mean if ref_mean > 0 else float("nan")


def render_reference(scene, spp, chunks=8, seed0=900_000, channels=slice(0, 3)):
    """Mean and per-pixel variance of the mean from ``chunks`` independent renders."""
    per = max(spp // chunks, 1)
    imgs, ts = [], []
    for k in range(chunks):
        img, t = timed_render(scene, per, seed0 + k, channels)
        imgs.append(img)
        ts.append(t)
    a = np.stack(imgs)
    return a.mean(0), a.var(0, ddof=1) / chunks, sum(ts), per * chunks


def pooled(imgs_spp):
    """Sample-weighted mean of independent estimates, its per-pixel variance, N."""
    n = np.array([s for _, s in imgs_spp], dtype=np.float64)
    X = np.stack([im for im, _ in imgs_spp])
    N = n.sum()
    mean = np.tensordot(n, X, axes=1) / N
    s2 = np.tensordot(n, (X - mean) ** 2, axes=1) / (len(n) - 1)
    return mean, s2 / N, int(N)


def bias_stats(img, var_img, ref, var_ref, rng, n_boot=1000):
    d = img - ref
    v = var_img + var_ref
    e = (d * d - v).ravel()
    b2 = float(e.mean())
    idx = rng.integers(0, e.size, size=(n_boot, e.size))
    boot = e[idx].mean(1)
    lo, hi = np.percentile(boot, [2.5, 97.5])
    ref_mean = float(ref.mean())
    mean_d = float(d.mean())
    se_mean = float(math.sqrt(v.sum()) / v.size)
    return {
        "bias_rms": math.sqrt(max(b2, 0.0)),
        "bias2": b2,
        "bias2_ci95": [float(lo), float(hi)],
        "bias_rms_ci95": [math.sqrt(max(lo, 0.0)), math.sqrt(max(hi, 0.0))],
        "rel_bias_rms": rel(math.sqrt(max(b2, 0.0)), ref_mean),
        "rel_bias_rms_ci95": [rel(math.sqrt(max(lo, 0.0)), ref_mean), rel(math.sqrt(max(hi, 0.0)), ref_mean)],
        "mean_diff": mean_d,
        "mean_diff_se": se_mean,
        "rel_mean_diff": rel(mean_d, ref_mean),
        "rel_mean_diff_ci95": [
            rel(mean_d - 1.96 * se_mean, ref_mean),
            rel(mean_d + 1.96 * se_mean, ref_mean),
        ],
        "mean_diff_z": mean_d / se_mean if se_mean > 0 else float("nan"),
        "chi2_per_pixel": float((d * d).mean() / v.mean()),  # ~1 if unbiased
    }


def fogpath_time_at(err, f_pts):
    """Steady time fogpath needs for RMSE ``err`` (f_pts: [(time, rmse)] by spp)."""
    pts = sorted((e, t) for t, e in f_pts if e > 0)  # increasing error
    le = [math.log(e) for e, _ in pts]
    lt = [math.log(t) for _, t in pts]
    x = math.log(err)
    if x <= le[0]:  # more accurate than fogpath's best point: t ~ e^-2
        return math.exp(lt[0] - 2.0 * (x - le[0])), "extrapolated (t ~ e^-2)"
    if x >= le[-1]:  # noisier than fogpath at 1 spp: fixed per-call cost
        return math.exp(lt[-1]), "clamped (fogpath 1 spp)"
    for i in range(len(le) - 1):
        if le[i] <= x <= le[i + 1]:
            w = (x - le[i]) / (le[i + 1] - le[i]) if le[i + 1] > le[i] else 0.0
            return math.exp(lt[i] + w * (lt[i + 1] - lt[i])), "interpolated"
    return float("nan"), "none"


#: what ``--reference-from`` reads from the previous run, per ladder point
ERROR_KEYS = ("mse_raw", "mse", "rmse", "rel_rmse", "noise_rmse", "rel_noise_rmse", "rmse_inscatter")


def load_previous(path: str, args) -> dict:
    """The previous run's JSON, checked against this run's settings (one-line errors)."""
    try:
        prev = json.loads(Path(path).read_text())
        cfg = prev["config"]
    except (OSError, ValueError, KeyError) as e:
        raise SystemExit(f"--reference-from {path}: not a time_vs_error.json ({e})") from None
    want = {
        "res": list(args.res),
        "ladder": list(args.ladder),
        "ref_spp": args.ref_spp,
        "max_depth": args.max_depth,
        "repeats": {str(s): REPEATS[s] for s in args.ladder},
    }
    got = {k: cfg.get(k) for k in want}
    got["repeats"] = {str(k): v for k, v in (got["repeats"] or {}).items()}
    for k, v in want.items():
        if got[k] != v:
            raise SystemExit(
                f"--reference-from {path}: its {k} is {got[k]}, this run's is {v} (must be equal)"
            )
    for name in args.scenes:
        if name not in prev.get("scenes", {}):
            raise SystemExit(
                f"--reference-from {path}: has no scene {name!r} (it has {list(prev['scenes'])})"
            )
        had = list(prev["scenes"][name]["methods"])
        if had != S.methods_for(name):
            raise SystemExit(
                f"--reference-from {path}: scene {name!r} had methods {had}, now {S.methods_for(name)} "
                "(the seeds would differ)"
            )
    return prev


def run_scene(name, args, rng, prev=None):
    """One scene's ladder; ``prev``: that scene in a previous run's JSON (errors reused)."""
    methods = S.methods_for(name)
    fresh = prev is None or name in args.verify  # render the reference, compute the errors
    scenes = {m: S.build(mi, name, m, res=args.res, max_depth=args.max_depth) for m in methods}
    out = {"methods": {}}
    print(f"[{name}] methods: {methods}", flush=True)

    # first call: tracing + compilation (or kernel-cache load), per method
    first = {}
    for m in methods:
        _, t = timed_render(scenes[m], 1, 12345)
        first[m] = t
    # every ladder size compiled (or loaded) and fogpath's passes recorded outside the timings, or a
    # repeat that compiles or records counts in the median (2 repeats at the top: half of it)
    warm_ladder([scenes[m] for m in methods], args.ladder, 54321)
    if fresh:  # reference
        refx, var_refx, t_ref, ref_spp = render_reference(
            scenes["fogpath"], args.ref_spp, channels=_insc_channels()
        )
        ref, var_ref, ref_i, var_ref_i = refx[..., :3], var_refx[..., :3], refx[..., 3:], var_refx[..., 3:]
        ref_mean = float(ref.mean())
        out["reference"] = {
            "method": "fogpath",
            "spp": ref_spp,
            "chunks": 8,
            "time_s": t_ref,
            "mean": ref_mean,
            "rms_sd_of_mean": float(math.sqrt(var_ref.mean())),
            "rel_rms_sd_of_mean": rel(math.sqrt(var_ref.mean()), ref_mean),
        }
        print(
            f"[{name}] reference {ref_spp} spp: {t_ref:.1f} s, mean {ref_mean:.4f}, "
            f"rel sd {out['reference']['rel_rms_sd_of_mean']:.2e}",
            flush=True,
        )
        vref = float(var_ref.mean())
    else:  # the previous run's reference (its statistics; the ladder's errors below)
        out["reference"] = dict(prev["reference"], reused_from=args.reference_from)
        ref_mean = out["reference"]["mean"]

    # ladder, round-robin over methods (rotated each repeat)
    rec = {m: {} for m in methods}
    pool = {m: [] for m in methods}
    seed = 0
    for spp in args.ladder:
        reps = REPEATS.get(spp, 1)
        for r in range(reps):
            order = methods[r % len(methods) :] + methods[: r % len(methods)]
            for m in order:
                seed += 1
                img, t = timed_render(
                    scenes[m], spp, seed, _insc_channels() if m.startswith("fogpath") else slice(0, 3)
                )
                d = rec[m].setdefault(spp, {"times": [], "mse_raw": [], "mse_insc_raw": []})
                d["times"].append(t)
                if not fresh:
                    continue
                d["mse_raw"].append(float(((img[..., :3] - ref) ** 2).mean()))
                if m.startswith("fogpath"):
                    d["mse_insc_raw"].append(float(((img[..., 3:] - ref_i) ** 2).mean()))
                pool[m].append((img[..., :3], spp))
        print(
            f"[{name}] spp {spp}: " + ", ".join(f"{m} {median(rec[m][spp]['times']):.3f}s" for m in methods),
            flush=True,
        )

    for m in methods:
        if fresh:
            P, var_P, N = pooled(pool[m])
            b = bias_stats(P, var_P, ref, var_ref, rng)
            b["pooled_spp"] = N
        else:
            b = prev["methods"][m]["bias"]
        ladder = []
        for i, spp in enumerate(args.ladder):
            d = rec[m][spp]
            if fresh:
                mse = float(np.mean(d["mse_raw"])) - vref
                rmse = math.sqrt(max(mse, 1e-30))
                noise = math.sqrt(max(mse - max(b["bias2"], 0.0), 1e-30))
                if d["mse_insc_raw"]:
                    ladder_insc = math.sqrt(
                        max(float(np.mean(d["mse_insc_raw"])) - float(var_ref_i.mean()), 1e-30)
                    )
                else:
                    ladder_insc = None
                err = {
                    "mse_raw": float(np.mean(d["mse_raw"])),
                    "mse": mse,
                    "rmse": rmse,
                    "rel_rmse": rel(rmse, ref_mean),
                    "noise_rmse": noise,
                    "rel_noise_rmse": rel(noise, ref_mean),
                    "rmse_inscatter": ladder_insc,
                }
            else:
                err = {k: prev["methods"][m]["ladder"][i][k] for k in ERROR_KEYS}
            ladder.append(
                {
                    "spp": spp,
                    "repeats": len(d["times"]),
                    "time_median_s": median(d["times"]),
                    "time_min_s": float(min(d["times"])),
                    "times_s": d["times"],
                    **err,
                }
            )
        steady1 = ladder[0]["time_median_s"]
        out["methods"][m] = {
            "label": LABEL[m],
            "first_call_s": first[m],
            "steady_1spp_s": steady1,
            "compile_s": first[m] - steady1,
            "ladder": ladder,
            "bias": b,
        }
        fp = scenes[m].integrator()
        if hasattr(fp, "freeze_refused"):  # fogpath: were its ladder passes replayed recordings?
            out["methods"][m]["frozen_passes"] = {
                "recordings": fp.n_recordings,
                "refused": fp.freeze_refused,
            }
    # equal-error ratios against fogpath
    f_pts = [(p["time_median_s"], p["rmse"]) for p in out["methods"]["fogpath"]["ladder"]]
    f_pts_noise = [(p["time_median_s"], p["noise_rmse"]) for p in out["methods"]["fogpath"]["ladder"]]
    for m in methods:
        for p in out["methods"][m]["ladder"]:
            tf, how = fogpath_time_at(p["rmse"], f_pts)
            p["fogpath_time_at_equal_error_s"] = tf
            p["equal_error_ratio"] = p["time_median_s"] / tf
            p["equal_error_how"] = how
            tfn, hown = fogpath_time_at(p["noise_rmse"], f_pts_noise)
            p["equal_noise_ratio"] = p["time_median_s"] / tfn
            p["equal_noise_how"] = hown
        if "fogpath_before" in out["methods"]:  # the same ratio against fogpath as it was
            b_pts = [(p["time_median_s"], p["rmse"]) for p in out["methods"]["fogpath_before"]["ladder"]]
            for p in out["methods"][m]["ladder"]:
                tb, _ = fogpath_time_at(p["rmse"], b_pts)
                p["equal_error_ratio_vs_before"] = p["time_median_s"] / tb
        top = out["methods"][m]["ladder"][-1]
        out["methods"][m]["equal_error_ratio_top"] = top["equal_error_ratio"]
        out["methods"][m]["equal_noise_ratio_top"] = top["equal_noise_ratio"]
        # time per sample per pixel at the top spp (steady)
        if m.startswith("fogpath_"):  # inscatter.* alone: only fogpath writes it
            f_pts_i = [(p["time_median_s"], p["rmse_inscatter"]) for p in out["methods"]["fogpath"]["ladder"]]
            for p in out["methods"][m]["ladder"]:
                tfi, _ = fogpath_time_at(p["rmse_inscatter"], f_pts_i)
                p["equal_error_ratio_inscatter"] = p["time_median_s"] / tfi
            out["methods"][m]["equal_error_ratio_inscatter_top"] = out["methods"][m]["ladder"][-1][
                "equal_error_ratio_inscatter"
            ]
        out["methods"][m]["ns_per_sample_top"] = (
            top["time_median_s"] / (top["spp"] * args.res[0] * args.res[1]) * 1e9
        )
    if prev is not None and fresh:  # the fresh errors against the stored ones
        pairs = [
            (p["mse_raw"], q["mse_raw"])
            for m in methods
            for p, q in zip(out["methods"][m]["ladder"], prev["methods"][m]["ladder"], strict=True)
        ]
        out["error_check"] = {
            "against": args.reference_from,
            "points": len(pairs),
            "bitwise_equal": sum(a == b for a, b in pairs),
            "max_rel_diff_mse_raw": max(abs(a / b - 1.0) for a, b in pairs),
        }
        print(f"[{name}] fresh errors vs {args.reference_from}: {out['error_check']}", flush=True)
    # where the variance lives, fogpath_before against fogpath (one sample, per part)
    if prev is None:
        out["variance_shares"] = {m: variance_shares(scenes[m]) for m in methods if m.startswith("fogpath")}
    else:
        out["variance_shares"] = prev["variance_shares"]
    # where the time goes (kernel history), fogpath and the slowest stock method
    prof_spp = args.ladder[-2] if len(args.ladder) > 1 else args.ladder[-1]
    out["profile"] = {}
    for m in methods:
        out["profile"][m] = kernel_profile(scenes[m], prof_spp, 777_777)
    return out


def write_reports(res, args, outdir: Path):
    outdir.mkdir(parents=True, exist_ok=True)
    (outdir / "time_vs_error.json").write_text(json.dumps(res, indent=1))
    with open(outdir / "time_vs_error.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(
            [
                "scene",
                "method",
                "spp",
                "repeats",
                "time_median_s",
                "time_min_s",
                "rmse",
                "rel_rmse",
                "noise_rmse",
                "equal_error_ratio",
                "equal_error_how",
                "equal_noise_ratio",
                "first_call_s",
                "compile_s",
                "bias_rms",
                "rel_bias_rms",
            ]
        )
        for sname, sc in res["scenes"].items():
            for m, d in sc["methods"].items():
                for p in d["ladder"]:
                    w.writerow(
                        [
                            sname,
                            m,
                            p["spp"],
                            p["repeats"],
                            f"{p['time_median_s']:.5f}",
                            f"{p['time_min_s']:.5f}",
                            f"{p['rmse']:.6g}",
                            f"{p['rel_rmse']:.6g}",
                            f"{p['noise_rmse']:.6g}",
                            f"{p['equal_error_ratio']:.4g}",
                            p["equal_error_how"],
                            f"{p['equal_noise_ratio']:.4g}",
                            f"{d['first_call_s']:.4f}",
                            f"{d['compile_s']:.4f}",
                            f"{d['bias']['bias_rms']:.6g}",
                            f"{d['bias']['rel_bias_rms']:.6g}",
                        ]
                    )
    # plots
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(res["scenes"])
    fig, axes = plt.subplots(1, len(names), figsize=(5.2 * len(names), 4.4), squeeze=False)
    colors = {
        "fogpath": "C3",
        "fogpath_before": "C5",
        "fogpath_split": "C6",
        "fogpath_nosplit": "C6",
        "fogpath_prev": "C8",
        "volpath_hf": "C0",
        "grid64": "C2",
        "grid256": "C1",
        "homogeneous": "C4",
    }
    for ax, sname in zip(axes[0], names):
        sc = res["scenes"][sname]
        for m, d in sc["methods"].items():
            t = [p["time_median_s"] for p in d["ladder"]]
            e = [p["rel_rmse"] for p in d["ladder"]]
            ax.loglog(t, e, "o-", color=colors[m], label=d["label"], lw=2 if m == "fogpath" else 1.2, ms=4)
            for p in d["ladder"]:
                if p["spp"] in (1, args.ladder[-1]):
                    ax.annotate(
                        f"{p['spp']}",
                        (p["time_median_s"], p["rel_rmse"]),
                        fontsize=7,
                        xytext=(3, 3),
                        textcoords="offset points",
                        color=colors[m],
                    )
            if m.startswith("grid") and d["bias"]["rel_bias_rms"] > 0:
                ax.axhline(d["bias"]["rel_bias_rms"], color=colors[m], ls=":", lw=1)
        ax.set_title(f"{sname} ({args.res[0]}x{args.res[1]}, max_depth {args.max_depth})")
        ax.set_xlabel("steady wall time per render [s]")
        ax.set_ylabel("relative RMSE vs reference")
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].legend(fontsize=7)
    fig.suptitle("time vs error (dotted: grid discretisation bias)", fontsize=10)
    fig.tight_layout()
    fig.savefig(outdir / "time_vs_error.png", dpi=110)
    plt.close(fig)
    (outdir / "summary.md").write_text(summary_md(res, args))


def _reuse_lines(res) -> list[str]:
    """The summary's note on errors reused from a previous run (``--reference-from``)."""
    src = res["config"].get("reference_from")
    if not src:
        return []
    checks = {n: sc["error_check"] for n, sc in res["scenes"].items() if "error_check" in sc}
    told = "; ".join(
        f"{n}: {c['bitwise_equal']} of {c['points']} (method, spp) MSEs bitwise equal to the stored ones, "
        f"largest relative difference {c['max_rel_diff_mse_raw']:.1e}"
        for n, c in checks.items()
    )
    return [
        f"Errors reused: the times are fresh; the reference, RMSEs, noise, bias and variance shares are "
        f"those of `{src}` (same seeds, image size, ladder and reference), except in the scenes "
        f"rendered afresh to check them ({told or 'none'}).\n"
    ]


def _frozen_line(res) -> str:
    """Whether fogpath's passes in the ladder were replayed ``dr.freeze`` recordings or traced."""
    rows = [
        (f"{s}/{m}", d["frozen_passes"])
        for s, sc in res["scenes"].items()
        for m, d in sc["methods"].items()
        if "frozen_passes" in d
    ]
    if not rows:
        return "fogpath's passes: not recorded by this run.\n"
    refused = [f"{k} ({f['refused']})" for k, f in rows if f["refused"]]
    if refused:
        return "fogpath's passes: **traced, dr.freeze refused** in " + "; ".join(refused) + ".\n"
    n = sum(f["recordings"] for _, f in rows)
    return (
        f"fogpath's passes: recorded with `dr.freeze` on their second call and replayed after, in every "
        f"fogpath method of every scene ({n} recordings in all, none refused).\n"
    )


def ratio_spread(m_ladder: list, f_ladder: list) -> dict:
    """The top rung's equal-error ratio of a method against fogpath with its spread from the
    repeats' times: ``low`` = the method's fastest repeat over fogpath's slowest (fogpath's
    ladder built from each rung's slowest repeat), ``high`` the reverse; ``per_sample`` =
    (time x MSE) of the method over fogpath's at the top rung, each time less that method's
    1-spp time (the ratio once per-call costs are removed)."""
    top, ftop = m_ladder[-1], f_ladder[-1]
    slow = [(max(q["times_s"]), q["rmse"]) for q in f_ladder]
    fast = [(min(q["times_s"]), q["rmse"]) for q in f_ladder]
    work = (top["time_median_s"] - m_ladder[0]["time_median_s"]) * top["mse"]
    fwork = (ftop["time_median_s"] - f_ladder[0]["time_median_s"]) * ftop["mse"]
    return {
        "ratio": top["equal_error_ratio"],
        "low": min(top["times_s"]) / fogpath_time_at(top["rmse"], slow)[0],
        "high": max(top["times_s"]) / fogpath_time_at(top["rmse"], fast)[0],
        "per_sample": work / fwork if fwork > 0 else float("nan"),
    }


def _spread_lines(res) -> list:
    """The top rung's ratio of every stock method with its spread (:func:`ratio_spread`)."""
    L = [
        "### At the top of the ladder, with the spread of the repeats\n",
        "| scene | method | equal-error ratio [fastest/slowest, slowest/fastest] | per sample, 1-spp time "
        "subtracted |",
        "|---|---|---|---|",
    ]
    for sname, sc in res["scenes"].items():
        f = sc["methods"]["fogpath"]["ladder"]
        for m, d in sc["methods"].items():
            if m.startswith("fogpath"):
                continue
            r = ratio_spread(d["ladder"], f)
            spread = f"{r['ratio']:.2f} [{r['low']:.1f}, {r['high']:.1f}]"
            L.append(f"| {sname} | {m} | {spread} | {r['per_sample']:.1f} |")
    return L + [""]


def summary_md(res, args) -> str:
    cfg = res["config"]
    L = [
        "# Time vs error: fogpath vs stock Mitsuba\n",
        f"Command: `{cfg['command']}`  ",
        f"Machine: {cfg['machine']['cpu']}, {cfg['machine']['cores']} cores (shared), mitsuba "
        f"{cfg['machine']['mitsuba']}, drjit {cfg['machine']['drjit']}, `{cfg['machine']['variant']}`  ",
        f"Images {cfg['res'][0]}x{cfg['res'][1]}, max_depth {cfg['max_depth']} for every method, rr_depth 5; "
        f"ladder {cfg['ladder']} spp (repeats {cfg['repeats']}); reference fogpath {cfg['ref_spp']} spp "
        f"in 8 chunks. Total run {cfg['total_s']:.0f} s.  ",
        f"Load average (1 min) {cfg['load_avg_1min']['start']:.1f} at the start, "
        f"{cfg['load_avg_1min']['end']:.1f} at the end, {cfg['load_avg_1min']['min']:.1f}-"
        f"{cfg['load_avg_1min']['max']:.1f} at the scene boundaries; "
        f"fogref commit `{cfg.get('commit', '?')}`.\n",
        "Times are steady wall times (median of repeats, methods interleaved); the first call "
        "(tracing + LLVM compilation or kernel-cache load) is reported apart. Grids: density sampled at "
        "cell **centres** of a 1xNx1 `gridvolume` over the fog box, trilinear, `has_spectral_extinction` "
        "false.\n",
        *_reuse_lines(res),
        _frozen_line(res),
        "![time vs error](time_vs_error.png)\n",
        "## Equal-error time ratio (method time / fogpath time at the same RMSE; > 1: fogpath faster)\n",
        "| scene | method | " + " | ".join(f"{s} spp" for s in cfg["ladder"]) + " | noise-only @top |",
        "|---|---|" + "---|" * len(cfg["ladder"]) + "---|",
    ]
    for sname, sc in res["scenes"].items():
        for m, d in sc["methods"].items():
            if m == "fogpath":
                continue
            cells = []
            for p in d["ladder"]:
                mark = "" if p["equal_error_how"] == "interpolated" else "*"
                cells.append(f"{p['equal_error_ratio']:.2f}{mark}")
            L.append(f"| {sname} | {m} | " + " | ".join(cells) + f" | {d['equal_noise_ratio_top']:.2f} |")
    L.append(
        "\n`*`: outside fogpath's measured range (extrapolated with t ~ RMSE^-2, or clamped at fogpath's "
        "1-spp time).  Noise-only: the same ratio with the method's bias removed from its error.\n"
    )
    L += _spread_lines(res)
    L += [
        "## fogpath without and with its variance reduction, side by side in this run\n",
        "`fogpath_before` = fogpath with one sun sample, sun sampling only in unbounded one-layer fog, no "
        "forced splitting, MIS for the sky at surfaces and one sun-sampled segment "
        "(`benchmarks/_scenes.py: FOGPATH_BEFORE`); `fogpath` = today's defaults; "
        "`fogpath_split` / `fogpath_nosplit` = today's defaults with forced splitting on the camera ray "
        "switched to the other setting (`forced_split`). "
        "Ratios at the top of the ladder (equal-error time ratio; > 1: the second is faster).\n",
        "| scene | method | ratio vs fogpath (after) | ratio vs fogpath_before | inscatter.* only: method "
        "vs fogpath |",
        "|---|---|---|---|---|",
    ]
    for sname, sc in res["scenes"].items():
        for m, d in sc["methods"].items():
            if m == "fogpath":
                continue
            top = d["ladder"][-1]
            ins = (
                f"{d['equal_error_ratio_inscatter_top']:.2f}"
                if "equal_error_ratio_inscatter_top" in d
                else "n/a (no split)"
            )
            L.append(
                f"| {sname} | {m} | {top['equal_error_ratio']:.2f} | "
                f"{top.get('equal_error_ratio_vs_before', float('nan')):.2f} | {ins} |"
            )
    L += [
        "\nStock volpath has no `inscatter.*` output (it does not split the fog's light from the "
        "surface's), so the inscatter-only ratio is fogpath against its other variants.\n",
        "### Where the variance lives (per-sample variance of each part / that of the final image, 64 spp, "
        "2 seeds)\n",
        "| scene | method | final var/sample | attenuated surface | single | multiple | inscatter |",
        "|---|---|---|---|---|---|---|",
    ]
    for sname, sc in res["scenes"].items():
        for m, v in sc.get("variance_shares", {}).items():
            L.append(
                f"| {sname} | {m} | {v['final_variance_per_sample']:.4g} | {v['attenuated_surface']:.2f} | "
                f"{v['single']:.2f} | {v['multiple']:.2f} | {v['inscatter']:.2f} |"
            )
    L.append(
        "\nThe parts are correlated (a camera ray either scatters or reaches the surface), so the shares "
        "need not add to 1.\n"
    )
    L += [
        "## Bias against the fogpath reference (pooled ladder images vs reference)\n",
        "| scene | method | pooled spp | rel. RMS bias [95% CI] | rel. mean diff [95% CI] | chi2/pixel |",
        "|---|---|---|---|---|---|",
    ]
    for sname, sc in res["scenes"].items():
        for m, d in sc["methods"].items():
            b = d["bias"]
            L.append(
                f"| {sname} | {m} | {b['pooled_spp']} | {b['rel_bias_rms']:.2e} "
                f"[{b['rel_bias_rms_ci95'][0]:.1e}, {b['rel_bias_rms_ci95'][1]:.1e}] | "
                f"{b['rel_mean_diff']:+.2e} [{b['rel_mean_diff_ci95'][0]:+.1e}, "
                f"{b['rel_mean_diff_ci95'][1]:+.1e}] | {b['chi2_per_pixel']:.3f} |"
            )
    L.append(
        "\nRMS bias = sqrt(mean((X - ref)^2 - Var X - Var ref)) over pixels and RGB; chi2/pixel = "
        "mean((X-ref)^2) / mean(Var X + Var ref), ~1 when the two agree within noise.\n"
    )
    L += [
        "## Time (seconds)\n",
        "| scene | method | first call | compile (first - steady 1 spp) | steady "
        f"{cfg['ladder'][-1]} spp | ns / sample / pixel | rel. RMSE @ {cfg['ladder'][-1]} spp |",
        "|---|---|---|---|---|---|---|",
    ]
    for sname, sc in res["scenes"].items():
        for m, d in sc["methods"].items():
            top = d["ladder"][-1]
            L.append(
                f"| {sname} | {m} | {d['first_call_s']:.2f} | {d['compile_s']:.2f} | "
                f"{top['time_median_s']:.3f} | {d['ns_per_sample_top']:.0f} | {top['rel_rmse']:.2e} |"
            )
    L += [
        "\n## Where the time goes (Dr.Jit kernel history, one render each)\n",
        "| scene | method | spp | wall | main kernel exec | other kernels | host (trace, launch) | main "
        "kernel ops |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for sname, sc in res["scenes"].items():
        for m, p in sc["profile"].items():
            L.append(
                f"| {sname} | {m} | {p['spp']} | {p['wall_s']:.3f} | {p['exec_s_main_kernel']:.3f} | "
                f"{p['exec_s_other_jit'] + p['exec_s_non_jit']:.3f} | {p['host_overhead_s']:.3f} | "
                f"{p['main_kernel_ops']} |"
            )
    return "\n".join(L) + "\n"


def _commit() -> str:
    """The repository's commit (``git describe --always --dirty``), or '?' outside git."""
    try:
        return subprocess.run(
            ["git", "describe", "--always", "--dirty"], cwd=ROOT, capture_output=True, text=True, check=True
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "?"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="32x18 images, spp <= 64, 512-spp reference")
    ap.add_argument("--scenes", nargs="*", default=list(S.SCENES))
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--ref-spp", type=int, default=None)
    ap.add_argument("--max-spp", type=int, default=1024, help="top of the spp ladder")
    ap.add_argument("--res", type=int, nargs=2, default=None, metavar=("W", "H"), help="default 96 54")
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks"))
    ap.add_argument(
        "--reference-from",
        default=None,
        metavar="JSON",
        help="a previous run's time_vs_error.json: re-time the ladder, reuse its reference and errors",
    )
    ap.add_argument(
        "--verify",
        nargs="*",
        default=None,
        metavar="SCENE",
        help="with --reference-from: scenes whose reference and errors are recomputed and compared "
        "(default: the first scene)",
    )
    args = ap.parse_args(argv)
    res_given = args.res
    for name in args.scenes:
        if name not in S.SCENES:
            raise SystemExit(f"--scenes: unknown scene {name!r} (allowed: {', '.join(S.SCENES)})")
    if args.verify is None:
        args.verify = args.scenes[:1]
    elif not set(args.verify) <= set(args.scenes):
        raise SystemExit(f"--verify: {args.verify} must be among --scenes {args.scenes}")
    if args.quick:
        args.res, args.ladder = (32, 18), [s for s in LADDER if s <= 64]
        args.ref_spp = args.ref_spp or 512
    else:
        args.res, args.ladder = tuple(res_given or (96, 54)), [s for s in LADDER if s <= args.max_spp]
        args.ref_spp = args.ref_spp or 4096
    prev = load_previous(args.reference_from, args) if args.reference_from else None
    rng = np.random.default_rng(0)
    t0 = time.perf_counter()
    loads = [os.getloadavg()[0]]
    res = {
        "config": {
            "command": "python " + " ".join(["benchmarks/time_vs_error.py", *sys.argv[1:]])
            if argv is None
            else "main(" + repr(argv) + ")",
            "res": list(args.res),
            "ladder": args.ladder,
            "repeats": {s: REPEATS[s] for s in args.ladder},
            "ref_spp": args.ref_spp,
            "max_depth": args.max_depth,
            "machine": machine_info(),
            "commit": _commit(),
            "reference_from": args.reference_from,
        },
        "scenes": {},
    }
    for name in args.scenes:
        res["scenes"][name] = run_scene(name, args, rng, prev["scenes"][name] if prev else None)
        res["config"]["total_s"] = time.perf_counter() - t0
        loads.append(os.getloadavg()[0])
        res["config"]["load_avg_1min"] = {
            "start": loads[0],
            "end": loads[-1],
            "min": min(loads),
            "max": max(loads),
        }
        write_reports(res, args, Path(args.out))  # partial results survive an interruption
    print(f"done in {time.perf_counter() - t0:.0f} s -> {args.out}", flush=True)


if __name__ == "__main__":
    main()
