"""Blender Cycles as a measured peer: equal-error time of fogref (fogpath) vs Cycles.

    FOGREF_BPY_PYTHON=/path/to/bpy-venv/bin/python \
    .venv/bin/python benchmarks/cycles_peer.py [--quick]   # ~9 min (--quick ~1.5 min), 2 cores

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
* one-time costs: Mitsuba's scene load and first call, here and in a fresh ``$HOME`` (no
  kernel cache: LLVM compiles); Cycles' ``import bpy``, scene build, first render (device +
  sync + BVH + volume set-up), a render without persistent data (sync + BVH every call);
* variance per sample, time per sample (relative least squares of steady time over spp);
* the bias of both: image mean of all runs minus the reference's, SE from the runs' spread;
* the equal-error time ratio Cycles / fogref (> 1: fogref faster), interpolated log-log on
  fogref's ladder at each Cycles ladder RMSE, and asymptotically from (time per sample x
  variance per sample); noise by a jackknife over the repeats.

Writes ``reports/benchmarks/cycles.{md,json}`` (``cycles_quick.*`` with ``--quick``).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
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
)
SCENES = {"open": dict(BASE), "box": dict(BASE, boxes=[((4, 6, 4), 0, (5, 6, 25))])}
NO_BPY = (
    "cycles_peer: bpy is not installed; install it (pip install 'fogref[cycles]', Python 3.11) in a venv "
    "and pass --bpy-python PATH or set FOGREF_BPY_PYTHON."
)


def find_bpy_python(arg: str | None) -> str:
    """The first interpreter among --bpy-python, $FOGREF_BPY_PYTHON, this one that imports bpy."""
    for py in (arg, os.environ.get("FOGREF_BPY_PYTHON"), sys.executable):
        try:
            if py and subprocess.run([py, "-c", "import bpy"], capture_output=True).returncode == 0:
                return py
        except OSError:
            pass
    raise SystemExit(NO_BPY)


class Cycles:
    """One Blender process holding one scene; ``render`` returns (rgb float64 image, wall s)."""

    def __init__(self, py, spec, res, max_depth, threads):
        self.dir = tempfile.mkdtemp(prefix="cycles_peer_")
        self.exr = os.path.join(self.dir, "out.exr")
        self.p = subprocess.Popen(
            [py, str(WORKER)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
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
        shutil.rmtree(self.dir, ignore_errors=True)


def mitsuba_scene(mi, S, spec, res, max_depth, fogpath=()):
    """fogpath + heightfog (bounded), the same camera / lights / shapes (y up); ``fogpath``:
    ``KEY=VALUE`` strings, the integrator's parameters besides its defaults."""
    T = mi.ScalarTransform4f()
    integ = {"type": "fogpath", "max_depth": max_depth, **dict(kv.split("=", 1) for kv in fogpath)}
    if S.KNOBS & integ.keys():  # a setting only the benchmarks' fogpath_knobs reads
        import _fogpath_knobs  # noqa: F401  (registers fogpath_knobs)

        integ["type"] = "fogpath_knobs"
    d = {
        "type": "scene",
        "integrator": integ,
        "sensor": {
            "type": "perspective",
            "fov": spec["fov"],
            "fov_axis": "x",
            "near_clip": 1e-4,
            "far_clip": 1e7,
            "to_world": T.look_at(origin=spec["origin"], target=spec["target"], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": res[0], "height": res[1], "rfilter": {"type": "box"}},
            "sampler": {"type": "independent"},
            "medium": mi.load_dict(S.heightfog_dict(mi, spec), parallel=False),
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
    return mi.load_dict(d, optimize=False, parallel=False)


def rmse(img, ref, var_ref):
    return math.sqrt(max(float(((img - ref) ** 2).mean() - var_ref.mean()), 1e-30))


def ladder_stats(np, runs, ref, var_ref):
    """runs: {spp: [(img, wall)]} -> per spp RMSE (rms over repeats), median time,
    variance per sample (spp x per-pixel variance across repeats)."""
    rows = []
    for spp, rs in sorted(runs.items()):
        imgs = np.stack([im for im, _ in rs])
        e = [rmse(im, ref, var_ref) for im, _ in rs]
        rows.append(
            {
                "spp": spp,
                "repeats": len(rs),
                "rmse": math.sqrt(sum(x * x for x in e) / len(e)),
                "rmse_each": e,
                "time_s": float(np.median([t for _, t in rs])),
                "time_each": [t for _, t in rs],
                "var_per_sample": float(spp * imgs.var(0, ddof=1).mean()) if len(rs) > 1 else None,
            }
        )
    return rows


def per_sample(np, rows):
    """(per-call seconds, seconds per sample) from a least-squares line through the
    median times; variance per sample averaged over the ladder."""
    x = np.array([r["spp"] for r in rows], float)
    y = np.array([r["time_s"] for r in rows], float)
    c, a = np.polyfit(x, y, 1, w=1 / y)  # relative residuals: the small spp count too
    v = [r["var_per_sample"] for r in rows if r["var_per_sample"] is not None]
    return float(a), float(c), float(np.mean(v))


def mean_bias(np, runs, ref_mean, ref_mean_se):
    """Image mean of all runs minus the reference's, SE from the spread of the runs'
    means (a run of n spp has variance sigma^2 / n) and the reference's own SE."""
    n = np.array([s for s, rs in runs.items() for _ in rs], float)
    m = np.array([float(im.mean()) for _, rs in runs.items() for im, _ in rs])
    N = n.sum()
    M = float((n * m).sum() / N)
    s2 = float((n * (m - M) ** 2).sum() / (len(m) - 1))
    se = math.sqrt(s2 / N + ref_mean_se**2)
    return {
        "mean": M,
        "bias": M - ref_mean,
        "se": se,
        "rel_bias": (M - ref_mean) / ref_mean,
        "z": (M - ref_mean) / se,
    }


def equal_error(tva, rows_cy, rows_fr):
    """Cycles time / fogref time at each Cycles ladder RMSE (fogref's time interpolated
    log-log on its ladder)."""
    f_pts = [(r["time_s"], r["rmse"]) for r in rows_fr]
    out = []
    for r in rows_cy:
        t, e = r["time_s"], r["rmse"]
        tf, how = tva.fogpath_time_at(e, f_pts)
        out.append({"spp": r["spp"], "rmse": e, "cycles_s": t, "fogref_s": tf, "ratio": t / tf, "how": how})
    return out


def headline(np, tva, runs_fr, runs_cy, ref, var_ref):
    """Ladder statistics of both renderers and the two equal-error ratios."""
    out: dict = {}
    rows_fr, rows_cy = (ladder_stats(np, r, ref, var_ref) for r in (runs_fr, runs_cy))
    for key, rows in (("fogref", rows_fr), ("cycles", rows_cy)):
        a, c, v = per_sample(np, rows)
        out[key] = {"ladder": rows, "per_call_s": a, "time_per_sample_s": c, "var_per_sample": v}
    ee = equal_error(tva, rows_cy, rows_fr)
    inter = [r["ratio"] for r in ee if r["how"] == "interpolated"]
    out["points"] = ee
    out["at_lowest_rmse"] = inter[-1] if inter else None  # the top of Cycles' ladder
    cy, fr = out["cycles"], out["fogref"]
    out["asymptotic"] = (cy["time_per_sample_s"] * cy["var_per_sample"]) / (
        fr["time_per_sample_s"] * fr["var_per_sample"]
    )
    return out


def run_scene(name, args, py, env):
    mi, np, S, tva = env["mi"], env["np"], env["S"], env["tva"]
    from _common import kernel_profile, timed_render, warm_ladder

    spec = SCENES[name]
    res, D = (64, 36), args.max_depth
    out: dict = {"spec": spec, "res": list(res), "max_depth": D}
    t0 = time.perf_counter()
    scene = mitsuba_scene(mi, S, spec, res, D, args.fogpath)
    fr = {"scene_load_s": time.perf_counter() - t0}
    k = kernel_profile(scene, args.ladder_fr[0], 777)
    fr.update(first_call_s=k["wall_s"], first_call_llvm_backend_s=k["backend_s"])
    fr.update(first_call_codegen_s=k["codegen_s"])
    home = tempfile.mkdtemp(prefix="cycles_peer_home_")  # no ~/.drjit kernel cache: LLVM compiles
    cmd = [sys.executable, __file__, "--cold-child", name, "--max-depth", str(D)]
    cmd += [f"--fogpath={kv}" for kv in args.fogpath]
    p = subprocess.run(cmd, env={**os.environ, "HOME": home}, capture_output=True, text=True)
    shutil.rmtree(home, ignore_errors=True)
    k = json.loads([x for x in p.stdout.splitlines() if x.startswith("@@MI ")][-1][5:])
    fr.update(
        cold_first_call_s=k["wall_s"], cold_llvm_backend_s=k["backend_s"], cold_codegen_s=k["codegen_s"]
    )
    warm_ladder([scene], args.ladder_fr, 778)  # compiled and recorded outside the timed ladder
    cy = Cycles(py, spec, res, D, args.threads)
    c0 = args.ladder_cy[0]
    cyi = {"import_bpy_s": cy.info["import_s"], "scene_build_s": cy.info["build_s"]}
    cyi["first_render_s"] = cy.render(c0, 777)[1]
    cyi["steady_same_spp_s"] = cy.render(c0, 778)[1]
    cyi["render_without_persistent_data_s"] = cy.render(c0, 779, persistent=False)[1]
    cy.render(c0, 780)  # persistent data again (this call re-syncs)
    homog = dict(spec, fog=dict(spec["fog"], layers=[(1.0, 0.0, 0.0)]))
    cyh = Cycles(py, homog, res, D, args.threads)
    cyi["first_render_homogeneous_fog_s"] = cyh.render(c0, 777)[1]
    cyh.close()
    out["blender"] = cy.info["versions"]["blender"]
    # reference: fogpath in 8 chunks
    ref, var_ref, t_ref, ref_spp = tva.render_reference(scene, args.ref_spp)
    ref_mean = float(ref.mean())
    ref_se = math.sqrt(float(var_ref.sum())) / var_ref.size
    out["reference"] = {"spp": ref_spp, "time_s": t_ref, "mean": ref_mean, "mean_se": ref_se}
    print(f"[{name}] reference {ref_spp} spp in {t_ref:.1f} s, mean {ref_mean:.5f}", flush=True)
    runs_fr: dict = {s: [] for s in args.ladder_fr}
    runs_cy: dict = {s: [] for s in args.ladder_cy}
    for rep in range(args.repeats):  # round-robin: load from other work falls on both alike
        for i, spp in enumerate(sorted(set(args.ladder_fr) | set(args.ladder_cy))):
            seed = 1000 * rep + i
            if spp in runs_fr:
                runs_fr[spp].append(timed_render(scene, spp, seed))
            if spp in runs_cy:
                runs_cy[spp].append(cy.render(spp, seed))
        print(f"[{name}] repeat {rep + 1}/{args.repeats} done", flush=True)
    bias_runs = {s: list(v) for s, v in runs_cy.items()}
    for j in range(args.bias_runs):
        bias_runs.setdefault(args.bias_spp, []).append(cy.render(args.bias_spp, 50_000 + j))
    cy.close()
    h = headline(np, tva, runs_fr, runs_cy, ref, var_ref)
    for key in ("fogref", "cycles"):
        out[key] = h[key]
    # noise of the two ratios: jackknife over the repeats (each leaves one repeat of both out)
    R = args.repeats
    jk = [
        headline(
            np,
            tva,
            *({s: v[:r] + v[r + 1 :] for s, v in x.items()} for x in (runs_fr, runs_cy)),
            ref,
            var_ref,
        )
        for r in range(R)
    ]
    for k in ("at_lowest_rmse", "asymptotic"):
        th = np.array([j[k] for j in jk], float)
        out[k] = {
            "ratio": h[k],
            "jackknife_se": float(math.sqrt((R - 1) / R * ((th - th.mean()) ** 2).sum())),
        }
    out["equal_error_points"] = h["points"]
    out["fogref"]["one_time"], out["cycles"]["one_time"] = fr, cyi
    out["fogref"]["bias"] = mean_bias(np, runs_fr, ref_mean, ref_se)
    out["cycles"]["bias"] = mean_bias(np, bias_runs, ref_mean, ref_se)
    rng = np.random.default_rng(5)
    for key, runs in (("fogref", runs_fr), ("cycles", bias_runs)):
        pool, var_pool, N = tva.pooled([(im, s) for s, rs in runs.items() for im, _ in rs])
        b = tva.bias_stats(pool, var_pool, ref, var_ref, rng)
        out[key]["pixel_bias"] = {
            "N": N,
            **{k: b[k] for k in ("bias_rms", "bias_rms_ci95", "chi2_per_pixel")},
        }
        if key == "cycles":  # alignment: row / column profiles of the pooled Cycles image vs the reference
            out["alignment"] = {
                "row_means_ref": ref.mean((1, 2)).tolist(),
                "row_means_cycles": pool.mean((1, 2)).tolist(),
                "max_rel_row_diff": float(np.abs(pool.mean((1, 2)) / ref.mean((1, 2)) - 1).max()),
                "max_rel_col_diff": float(np.abs(pool.mean((0, 2)) / ref.mean((0, 2)) - 1).max()),
            }
    print(
        f"[{name}] equal-error ratio (Cycles/fogref): {out['at_lowest_rmse']}, "
        f"asymptotic {out['asymptotic']}; Cycles bias {out['cycles']['bias']['rel_bias']:+.2e} "
        f"(z {out['cycles']['bias']['z']:+.1f})",
        flush=True,
    )
    return out


def _f(x, n=3):
    return "-" if x is None else f"{x:.{n}g}"


def write_report(res, path_md):
    from _cycles_worker import OTHER_SETTINGS, fair_settings

    m, a = res["machine"], res["args"]
    L = [
        "# Blender Cycles as a measured peer",
        "",
        f"Written by `benchmarks/cycles_peer.py{' --quick' if a['quick'] else ''}` ({res['date']}, "
        f"{res['wall_min']:.1f} min). An optional benchmark, not a test.",
        "",
        f"Machine: {m['cpu']}, {m['cores']} cores (shared), {a['threads']} threads in both. "
        f"Mitsuba {m['mitsuba']}, Dr.Jit {m['drjit']}, `{m['variant']}`; Blender {res['blender']} "
        f"(`bpy` from PyPI, Python {res['bpy_python_version']}). Load average (1 min) "
        + (
            " -> ".join(f"{x:.1f}" for x in res["load_avg_1min"]) + " (start, after each scene)."
            if "load_avg_1min" in res
            else "not recorded."
        ),
        "",
        "Scenes: 64x36, exponential height fog sigma_t = 0.03 exp(-0.06 y) /m, albedo 0.9, HG g 0.5, in "
        "the box [-60, 60] x [-1, 40] x [-60, 60] m; delta sun E = (2, 1.9, 1.7) W/m^2; constant sky "
        "(0.2, 0.3, 0.5); diffuse ground 300 x 300 m; `box` adds one 8 x 12 x 8 m block. "
        f"fogref: `fogpath` + bounded `heightfog`, max_depth {a['max_depth']}"
        + "".join(f", `{kv}`" for kv in a.get("fogpath", []))
        + "; Cycles: the same scene "
        f"in z-up (x, y, z) -> (x, -z, y), {a['max_depth'] - 2} bounces of every kind.",
        "",
        "Equal-error ratio = Cycles steady time / fogref steady time at the same RMSE against a fogref "
        "reference (> 1: fogref faster). *Interpolated*: at each Cycles ladder point, fogref's time "
        "interpolated log-log on its ladder; in the summary, at the lowest RMSE (the top of Cycles' "
        "ladder). *Asymptotic*: (time per "
        "sample x variance per sample) of Cycles over fogref's, the ratio when per-call costs vanish "
        "and both are unbiased. +- : jackknife standard error over the repeats. Bias: image mean "
        "minus the reference's, relative, with z = bias / standard error.",
        "",
        "| scene | ratio at the lowest RMSE | ratio, asymptotic | Cycles bias (rel, z) "
        "| fogref bias (rel, z) | Cycles row / col profile vs ref (max rel diff) |",
        "|---|---|---|---|---|---|",
    ]
    for name, r in res["scenes"].items():
        mi_, as_ = r["at_lowest_rmse"], r["asymptotic"]
        cb, fb, al = r["cycles"]["bias"], r["fogref"]["bias"], r["alignment"]
        L.append(
            f"| {name} | {_f(mi_['ratio'])} +- {_f(mi_['jackknife_se'], 2)} "
            f"| {_f(as_['ratio'])} +- {_f(as_['jackknife_se'], 2)} | {cb['rel_bias']:+.2e} ({cb['z']:+.1f}) "
            f"| {fb['rel_bias']:+.2e} ({fb['z']:+.1f}) "
            f"| {al['max_rel_row_diff']:.3f} / {al['max_rel_col_diff']:.3f} |"
        )
    for name, r in res["scenes"].items():
        fr, cy = r["fogref"], r["cycles"]
        o1, o2 = fr["one_time"], cy["one_time"]
        L += [
            "",
            f"## {name}",
            "",
            f"Reference: fogref {r['reference']['spp']} spp ({r['reference']['time_s']:.1f} s), image mean "
            f"{r['reference']['mean']:.5f} +- {r['reference']['mean_se']:.1e}.",
            "",
            "One-time costs (s): fogref scene load (`mi.load_dict`) "
            f"{o1['scene_load_s']:.3f}, first call {o1['first_call_s']:.2f} (of which LLVM back end "
            f"{o1['first_call_llvm_backend_s']:.2f}, codegen {o1['first_call_codegen_s']:.2f}; a "
            f"kernel-cache hit has ~0 back end); in a fresh `$HOME` (no kernel cache) "
            f"{o1['cold_first_call_s']:.2f} (LLVM back end {o1['cold_llvm_backend_s']:.2f}, codegen "
            f"{o1['cold_codegen_s']:.2f}). Cycles `import bpy` {o2['import_bpy_s']:.2f}, scene build "
            f"(bpy data) "
            f"{o2['scene_build_s']:.3f}, first render {o2['first_render_s']:.2f} vs steady "
            f"{o2['steady_same_spp_s']:.3f} at the same spp (difference: device + sync + BVH + volume "
            f"set-up), a render without persistent data {o2['render_without_persistent_data_s']:.2f} "
            f"(sync + BVH every call); the same first render with the fog made homogeneous (falloff 0) "
            f"{o2['first_render_homogeneous_fog_s']:.3f}: the rest is the set-up of the procedural "
            "(heterogeneous) volume for null scattering.",
            "",
            "| | per-call s | time per sample s | variance per sample | bias rms per pixel (95%) "
            "| chi2/pixel |",
            "|---|---|---|---|---|---|",
        ]
        for key, d in (("fogref", fr), ("Cycles", cy)):
            pb = d["pixel_bias"]
            L.append(
                f"| {key} | {_f(d['per_call_s'])} | {_f(d['time_per_sample_s'])} | {_f(d['var_per_sample'])} "
                f"| {_f(pb['bias_rms'])} ({_f(pb['bias_rms_ci95'][0])}..{_f(pb['bias_rms_ci95'][1])}) "
                f"| {_f(pb['chi2_per_pixel'])} |"
            )
        L += [
            "",
            "| spp | fogref RMSE | fogref s | Cycles RMSE | Cycles s | equal-error ratio | how |",
            "|---|---|---|---|---|---|---|",
        ]
        by_f = {x["spp"]: x for x in fr["ladder"]}
        by_c = {x["spp"]: x for x in cy["ladder"]}
        by_e = {x["spp"]: x for x in r["equal_error_points"]}
        for spp in sorted(set(by_f) | set(by_c)):
            f_, c_, e_ = by_f.get(spp), by_c.get(spp), by_e.get(spp)
            L.append(
                f"| {spp} | {_f(f_ and f_['rmse'])} | {_f(f_ and f_['time_s'])} | {_f(c_ and c_['rmse'])} "
                f"| {_f(c_ and c_['time_s'])} | {_f(e_ and e_['ratio'])} | {e_['how'] if e_ else ''} |"
            )
    L += ["", "## Cycles settings", "", "`scene.cycles.<name>` (Blender Python API), as set:", ""]
    L += [f"- `{k} = {v!r}`" for k, v in fair_settings(a["max_depth"]).items()]
    L += [*OTHER_SETTINGS, ""]
    Path(path_md).write_text("\n".join(L))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="small ladders, 1024-spp reference (~1.5 min)")
    ap.add_argument("--bpy-python", help="a Python that imports bpy (default: $FOGREF_BPY_PYTHON, this one)")
    ap.add_argument("--scenes", default="open,box")
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default=str(HERE.parent / "reports" / "benchmarks"))
    ap.add_argument(
        "--fogpath",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a fogpath parameter besides its defaults (e.g. sky_at_media=mis); repeatable",
    )
    ap.add_argument("--cold-child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.cold_child:  # a fresh process in a fresh $HOME: fogref's first call with LLVM compiling
        import _scenes as S
        from _common import kernel_profile, mi

        sc = mitsuba_scene(mi, S, SCENES[args.cold_child], (64, 36), args.max_depth, args.fogpath)
        print("@@MI " + json.dumps(kernel_profile(sc, 1, 777)))
        return
    py = find_bpy_python(args.bpy_python)
    q = args.quick
    args.ladder_fr = (1, 4, 16, 64) if q else (1, 4, 16, 64, 256, 1024)
    args.ladder_cy = (4, 16, 64) if q else (4, 16, 64, 256, 1024)
    args.repeats = 3 if q else 6
    args.ref_spp = 1024 if q else 16384
    args.bias_spp, args.bias_runs = (256, 2) if q else (1024, 12)
    import _scenes as S
    import time_vs_error as tva
    from _common import dr, machine_info, mi, np

    env = {"mi": mi, "np": np, "S": S, "tva": tva, "dr": dr}
    t0 = time.time()
    vers = subprocess.run(
        [py, "-c", "import platform; print(platform.python_version())"], capture_output=True, text=True
    )
    res: dict = {
        "machine": {**machine_info(), "drjit_threads": dr.thread_count()},
        "bpy_python_version": vers.stdout.strip(),
        "scenes": {},
    }
    res["args"] = {k: v for k, v in vars(args).items() if k != "out"}
    res["load_avg_1min"] = [os.getloadavg()[0]]
    for name in args.scenes.split(","):
        res["scenes"][name] = run_scene(name, args, py, env)
        res["load_avg_1min"].append(os.getloadavg()[0])
    res["blender"] = next(iter(res["scenes"].values()))["blender"]
    res["date"] = time.strftime("%Y-%m-%d")
    res["wall_min"] = (time.time() - t0) / 60
    out = Path(args.out)
    suffix = "_quick" if q else ""
    out.mkdir(parents=True, exist_ok=True)
    (out / f"cycles{suffix}.json").write_text(json.dumps(res, indent=1))
    write_report(res, out / f"cycles{suffix}.md")
    print(f"wrote {out / f'cycles{suffix}.md'}")


if __name__ == "__main__":
    main()
