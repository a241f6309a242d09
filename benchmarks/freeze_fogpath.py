"""Can ``dr.freeze`` replay fogpath's render without tracing Python?  -> reports/benchmarks/freeze_fogpath.md

``scenes/valley.xml`` at 32x18, 4 spp, pixel-exact, ``llvm_ad_rgb``.  Each case runs in its own
process (a crash is recorded, not fatal to the others) and compares, call by call, the traced
``render_moments`` pass body with the same body under ``dr.freeze``: wall time (the call, then
``dr.eval`` and ``dr.sync_thread``), bitwise equality of the per-pixel sums, and how many times
Dr.Jit recorded the function.

* ``as_is``: ``FogPathIntegrator.render_moments`` frozen as it is;
* ``reads_out``: the values fogpath reads from the scene while tracing (the sensor's kind, the
  constant sky, the sun's direction and irradiance, the emitters' selection pdfs) read before the
  frozen call, its per-call opaque parameter cache emptied;
* ``same_scene``: as ``reads_out``, and every one-value scene parameter (``mi.traverse``) passed
  as an explicit input; one loaded scene, new seeds;
* ``new_scenes``: the same, with the scene loaded again for each configuration (what a sweep
  does): sun elevations 20, 20, 40, 60 degrees, three seeds each.

    .venv/bin/python benchmarks/freeze_fogpath.py

Writes reports/benchmarks/freeze_fogpath.{json,md}.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "valley.xml"
RES, SPP = (32, 18), 4
CASES = {
    "as_is": [(20, (1, 2))],
    "reads_out": [(20, (1, 2))],
    "same_scene": [(20, (1, 2, 3, 4, 5))],
    "new_scenes": [(20, (1, 2, 3)), (20, (1, 2, 3)), (40, (1, 2, 3)), (60, (1, 2, 3))],
}


def child(case: str) -> None:
    """Run one case in this process; one JSON line per call on stdout."""
    from fogref.render.variant import set_variant

    set_variant("llvm_ad_rgb")
    import drjit as dr
    import fogref_plugins.fogpath as common
    import mitsuba as mi
    import numpy as np

    from fogref.media import drjit_ops
    from fogref.media.ops import DrJitOps
    from fogref.render.load import load_scene

    base = common.FogPathIntegrator
    reads = {"sun": base._read_scene_sun, "sky": base._read_constant_sky, "sel": base._read_sky_selection}
    facts: dict = {}
    if case != "as_is":  # the trace-time reads answered from values read before the call
        base._scene_sun = staticmethod(lambda scene: facts["sun"])
        base._constant_sky = staticmethod(lambda scene: facts["sky"])
        base._sky_selection = lambda self, scene: facts["sel"]

    def body(scene, seed, spp, values=None):
        """render_moments' pass: camera rays, fogpath's ``sample``, per-pixel sums."""
        fp, sensor = scene.integrator(), scene.sensors()[0]
        size = sensor.film().crop_size()
        n_pix = int(dr.prod(size))
        sampler = sensor.sampler().clone()
        sampler.set_sample_count(spp)
        sampler.set_samples_per_wavefront(spp)
        sampler.seed(seed, n_pix * spp)
        idx = dr.arange(mi.UInt32, n_pix * spp) // dr.opaque(mi.UInt32, spp)
        pos = mi.Vector2u(0)
        pos.y = idx // size[0]
        pos.x = idx - pos.y * size[0]
        uv = (mi.Vector2f(pos) + mi.Vector2f(0.5)) / mi.ScalarVector2f(size)
        ray, weight = sensor.sample_ray(sensor.shutter_open(), 0.5, uv, mi.Point2f(0.5))
        ray = mi.Ray3f(sensor.world_transform().translation(), ray.d, ray.time, ray.wavelengths)
        L, _, aovs = fp.sample(scene, sampler, ray, None, True)
        L = L * weight
        values_out = [L[0], L[1], L[2]] + list(aovs)
        dr.eval(values_out)
        return fp._per_pixel_sums(values_out, [(j, j) for j in range(3)], n_pix, spp)

    def as_is(scene, seed, spp, values=None):
        return scene.integrator().render_moments(scene, 0, seed, spp, pixel_exact=True)

    frozen = dr.freeze(as_is if case == "as_is" else body, warn_after=1000)

    def timed(f, *args):
        t0 = time.perf_counter()
        r = f(*args)
        dr.eval(r)
        dr.sync_thread()
        return r, time.perf_counter() - t0

    def host(r):
        return np.concatenate([np.asarray(x, dtype=np.float64).ravel() for part in r for x in part])

    def rgb(r):
        return np.concatenate([np.asarray(x, dtype=np.float64).ravel() for x in r[0][:3]])

    for sun, seeds in CASES[case]:
        scene, _ = load_scene(SCENE, {"res": RES[0], "resy": RES[1], "sun_elevation": sun})
        scene.integrator().aovs = True
        common.make_scene_values_opaque(scene)
        facts.update(sun=reads["sun"](scene), sky=reads["sky"](scene))
        facts["sel"] = reads["sel"](scene.integrator(), scene)
        for sd in seeds:
            seed_t = sd if case == "as_is" else dr.opaque(mi.UInt32, sd)  # render_moments takes an int
            sites: set = set()
            param = DrJitOps._param

            def counted(self, x, caller, slot, _param=param):  # the call sites of Python values
                sites.add((caller.f_code.co_filename, caller.f_lineno))
                return _param(self, x, caller, slot)

            DrJitOps._param = counted
            traced, t_traced = timed(body if case != "as_is" else as_is, scene, seed_t, SPP)
            DrJitOps._param = param
            drjit_ops()._params.clear()  # opaque values made by the traced call are not inputs
            values = None
            if case in ("same_scene", "new_scenes"):
                values = {k: v for k, v in mi.traverse(scene).items() if dr.is_jit_v(v) and dr.width(v) == 1}
            row = {"sun_elevation": sun, "seed": sd, "traced_s": t_traced, "param_sites": len(sites)}
            try:
                replay, t_frozen = timed(frozen, scene, seed_t, SPP, values)
            except RuntimeError as e:
                cause = e.__cause__ if e.__cause__ is not None else e
                row["error"] = str(cause).strip().splitlines()[0]
                print(json.dumps(row), flush=True)
                return
            row.update(
                frozen_s=t_frozen,
                bitwise_equal=bool(np.array_equal(host(traced), host(replay))),
                max_rel_diff=float(np.max(np.abs(rgb(traced) - rgb(replay))) / np.max(rgb(traced))),
                recordings=int(frozen.n_recordings),
            )
            print(json.dumps(row), flush=True)
        del scene


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--child", choices=tuple(CASES), help=argparse.SUPPRESS)
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks"))
    a = ap.parse_args()
    if a.child:
        child(a.child)
        return
    import drjit as dr
    import mitsuba as mi

    result: dict = {
        "machine": f"{platform.machine()}, {os.cpu_count()} cores (shared)",
        "load_average_before": os.getloadavg()[0],
        "mitsuba": mi.__version__,
        "drjit": dr.__version__,
        "res": list(RES),
        "spp": SPP,
        "cases": {},
    }
    for case in CASES:
        r = subprocess.run(
            [sys.executable, __file__, "--child", case], capture_output=True, text=True, cwd=ROOT
        )
        rows = [json.loads(line) for line in r.stdout.splitlines() if line.startswith("{")]
        result["cases"][case] = {"returncode": r.returncode, "calls": rows}
        if r.returncode != 0:
            result["cases"][case]["stderr_tail"] = r.stderr.strip().splitlines()[-3:]
    result["load_average_after"] = os.getloadavg()[0]
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "freeze_fogpath.json").write_text(json.dumps(result, indent=1) + "\n")
    (out / "freeze_fogpath.md").write_text(report(result))


def report(r: dict) -> str:
    """The Markdown page of a run: one table per case, every call."""
    md = [
        "# Freezing fogpath's render with `dr.freeze`",
        "",
        f"`benchmarks/freeze_fogpath.py`: `scenes/valley.xml` at {r['res'][0]}x{r['res'][1]}, "
        f"{r['spp']} spp, pixel-exact, `llvm_ad_rgb`; Mitsuba {r['mitsuba']}, Dr.Jit {r['drjit']}; "
        f"{r['machine']}, load average {r['load_average_before']:.1f} before and "
        f"{r['load_average_after']:.1f} after.  Wall times in seconds of one call each (the "
        "call, `dr.eval`, `dr.sync_thread`): `traced` the pass body as fogref runs it, `frozen` "
        "the same body under `dr.freeze` (the first call of a recording records, later ones "
        "replay); `bitwise` compares their per-pixel float64 sums.",
    ]
    for case, res in r["cases"].items():
        md += ["", f"## `{case}` (exit status {res['returncode']})", ""]
        md += ["| sun [deg] | seed | traced [s] | frozen [s] | bitwise | RGB: max diff / max | recordings |"]
        md += ["|---:|---:|---:|---:|---|---:|---:|"]
        for c in res["calls"]:
            if "error" in c:
                md.append(f"| {c['sun_elevation']} | {c['seed']} | {c['traced_s']:.3f} | refused | | | |")
                md += ["", f"Dr.Jit: `{c['error']}`"]
                continue
            md.append(
                f"| {c['sun_elevation']} | {c['seed']} | {c['traced_s']:.3f} | {c['frozen_s']:.3f} "
                f"| {'yes' if c['bitwise_equal'] else 'NO'} | {c['max_rel_diff']:.2g} | {c['recordings']} |"
            )
        if res.get("stderr_tail"):
            md += ["", "The process ended with:", "", "```", *res["stderr_tail"], "```"]
    calls = r["cases"]["new_scenes"]["calls"]
    wrong = [c for c in calls if "error" not in c and not c["bitwise_equal"]]
    replays = [c for c in calls if "error" not in c and c["bitwise_equal"] and c["seed"] != 1]
    md += [
        "",
        "## What this shows",
        "",
        "* Recording refuses fogpath as it is: it reads evaluated scene values while tracing "
        "(the sensor's and the sky's kind through `str()`, the sun through `float()`, the "
        "emitters' pdfs), and its opaque parameters outlive a call (`DrJitOps`' cache) without "
        "being inputs.  The sensor's `heightfog` medium is a Python plugin: Dr.Jit's traversal "
        "of the scene does not reach its phase function, whose `g` must be passed by hand.",
        "* With those reads done before the call and the scene's values passed as inputs, a "
        "replay of one loaded scene with a new seed is bitwise equal to the traced pass and "
        "skips the tracing (the `same_scene` table).",
        f"* A scene loaded again: `dr.freeze` tells Python objects among its inputs apart by "
        f"`hash()` or `id()` (its documentation), and fogpath's integrator and medium are Python "
        f"objects whose values (the fog's parameters, the sun fogpath reads) are Python numbers, "
        f"not traversed.  When the new scene's objects get new ids Dr.Jit records again (no "
        f"gain); when they reuse ids a recording saw (Python reuses a freed object's id) it "
        f"replays that recording, whose fog "
        f"and sun values are constants of that recording.  In this run "
        f"{len(wrong)} of {len(calls)} new-scene calls replayed with pixels that differ from "
        f"the traced render ({len(replays)} replays were correct).  Freezing a sweep's "
        f"configurations needs every value the trace reads (the fog's parameters and what is "
        f"derived from them in Python, the sun, the sky, the pdfs) to be a Dr.Jit input of the "
        f"frozen function, not a Python number: on this scene the traced pass takes Python "
        f"values at {calls[0].get('param_sites', '?')} `ops.param` call sites (fogpath, the media's "
        f"closed forms, the sun's single-scattering sampler), each computed there from the fog "
        f"object's fields.",
    ]
    return "\n".join(md) + "\n"


if __name__ == "__main__":
    main()
