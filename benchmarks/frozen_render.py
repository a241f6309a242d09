"""A truth rendered again in a warm process: loaded scenes kept and fogpath's passes frozen.
-> reports/benchmarks/frozen_render.{json,md}

One process calls the render driver (:func:`fogref.render.render.render`, as ``fogref render``
does, EXR and moments written) on ``scenes/valley.xml`` again and again, each call a new seed,
in two modes, side by side in rotating order, the same seed in both:

* ``before``: as fogref was: the scene loaded for every render
  (:func:`fogref.render.load.load_scene`) and fogpath's ``freeze`` off (every pass traced);
* ``after``: fogref as it is: the loaded scene kept (:func:`fogref.render.load.loaded_scene`) and
  passes frozen (traced the first time a pass of that kind is seen, recorded the second time,
  replayed from then on: :data:`fogref_plugins.fogpath.RECORD_FROM_CALL`);
* ``after, none``: the same with ``exr_compression="none"`` (the EXR's values the same, the file
  larger);
* with ``--baseline TREE``: ``TREE``, another checkout's ``fogref`` package (e.g. a
  ``git worktree`` of an earlier commit, its ``fogref_plugins`` this checkout's) as ``after``, in a
  child process that renders when asked, alternating with the others (``baseline`` below).

Cases: 32x18 at 64 spp and at 1 spp (one pass each), 320x180 at 64 spp (several passes).  Each
render's wall time is split into phases by timing the driver's calls: ``parse`` (reading the
scene and hashing its inputs), ``load`` (Mitsuba's load, or the kept scene), ``passes`` (fogpath's
``render_moments``: tracing, recording or replaying, and the kernels' execution, which Dr.Jit's
kernel history gives apart), ``channels`` (the means and standard errors from the sums, copied to
the host), ``exr`` (the EXR and the moments file written, atomically) and ``rest`` (the
output checks, the merge of the passes' sums, the non-finite check).  ``host`` = wall - execution.
The first render of each mode compiles (or loads Dr.Jit's disk cache) and is reported apart.
The EXRs of all modes are compared bitwise.  Then what recording costs, which sets
:data:`~fogref_plugins.fogpath.RECORD_FROM_CALL`: a freshly loaded scene's first pass traced
(``freeze`` off) against recorded (``RECORD_FROM_CALL`` 1), alternating, paired differences.
Last, a Dask worker's per-pass check of the inputs (:func:`fogref.render.distributed.render_pass`,
in this process): reading the scene and digesting its inputs on every pass (as it was) against
once per render and a memoised hash per input after each pass.

    .venv/bin/python benchmarks/frozen_render.py [--rounds 12] [--baseline /tmp/main-tree]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "valley.xml"
CASES = [((32, 18), 64), ((32, 18), 1), ((320, 180), 64)]
MODES = ("before", "baseline", "after", "after, none")
PHASES = ("parse", "load", "trace", "execution", "channels", "exr", "rest")


def quartiles(xs: list) -> list:
    """[median, first quartile, third quartile] of ``xs``."""
    if len(xs) < 2:
        return [xs[0]] * 3 if xs else [float("nan")] * 3
    q = statistics.quantiles(xs, n=4, method="inclusive")
    return [statistics.median(xs), q[0], q[2]]


def instrumented(tmp: Path):
    """The render driver with its phases timed: ``(render, clock)``, ``render(mode, res, spp, seed)
    -> (row, exr)`` for the modes rendered in this process (``before``, ``after``, ``after, none``),
    ``clock`` the phases' seconds of the last call (fogpath's passes timed on any call)."""
    from fogref.render.variant import set_variant

    set_variant("llvm_ad_rgb")
    import drjit as dr
    import fogref_plugins.fogpath as fpm

    import fogref.render.render as R
    from fogref.render import load

    traced_scene = tmp / "valley_traced.xml"  # the same scene, freeze off (before)
    traced_scene.write_text(
        SCENE.read_text().replace(
            '<integrator type="fogpath">',
            '<integrator type="fogpath">\n        <boolean name="freeze" value="false"/>',
        )
    )
    clock: dict = {}

    def timed(name, fn):
        def wrapper(*args, **kw):
            t0 = time.perf_counter()
            try:
                return fn(*args, **kw)
            finally:
                clock[name] = clock.get(name, 0.0) + time.perf_counter() - t0

        return wrapper

    R.read_scene = timed("parse", R.read_scene)
    kept = load.loaded_scene
    loading = {"each time": False}

    def load_or_keep(parsed, threads=None):  # before: Mitsuba loads the scene for every render
        if loading["each time"]:
            return load.load_scene(parsed)
        return kept(parsed, threads)

    load.loaded_scene = timed("load", load_or_keep)
    R.write_exr = timed("exr", R.write_exr)
    R.checkpoint.write_checkpoint = timed("exr", R.checkpoint.write_checkpoint)
    # the channels: Dr.Jit arithmetic and one copy (an earlier driver), or numpy on the host copy
    for name in ("_channels", "_host_float32", "_float32_planes", "_device_float32"):
        if hasattr(R, name):
            setattr(R, name, timed("channels", getattr(R, name)))
    moments, body = fpm.FogPathIntegrator.render_moments, fpm.FogPathIntegrator._pass
    kinds: dict = {}

    def pass_timed(self, scene, *args, **kw):
        before_rec = self.n_recordings
        ran = clock.get("_body", 0)
        dr.kernel_history()
        dr.set_flag(dr.JitFlag.KernelHistory, True)
        t0 = time.perf_counter()
        out = moments(self, scene, *args, **kw)
        dr.sync_thread()
        wall = time.perf_counter() - t0
        hist = dr.kernel_history()
        dr.set_flag(dr.JitFlag.KernelHistory, False)
        execution = sum(k.get("execution_time", 0.0) for k in hist) / 1e3
        kind = (
            "recorded"
            if self.n_recordings > before_rec
            else ("traced" if clock.get("_body", 0) > ran else "replayed")
        )
        kinds[kind] = kinds.get(kind, 0) + 1
        clock["execution"] = clock.get("execution", 0.0) + execution
        clock["trace"] = clock.get("trace", 0.0) + wall - execution
        clock["backend"] = clock.get("backend", 0.0) + sum(k.get("backend_time", 0.0) for k in hist) / 1e3
        return out

    def body_counted(self, *args):
        clock["_body"] = clock.get("_body", 0) + 1
        return body(self, *args)

    fpm.FogPathIntegrator.render_moments = pass_timed
    fpm.FogPathIntegrator._pass = body_counted

    def render(mode: str, res: tuple, spp: int, seed: int) -> tuple[dict, Path]:
        loading["each time"] = mode == "before"
        clock.clear()
        kinds.clear()
        out = tmp / f"{mode.replace(', ', '_')}.exr"
        kw = {"exr_compression": "none"} if mode == "after, none" else {}
        t0 = time.perf_counter()
        R.render(
            traced_scene if mode == "before" else SCENE,
            out,
            spp=spp,
            seed=seed,
            overrides={"res": res[0], "resy": res[1]},
            progress=False,
            png=False,
            resume=False,
            **kw,
        )
        wall = time.perf_counter() - t0
        row = {"wall": wall, **{p: clock.get(p, 0.0) for p in PHASES if p != "rest"}}
        row["rest"] = wall - sum(row[p] for p in PHASES if p != "rest")
        row["host"] = wall - row["execution"]
        row["backend"] = clock.get("backend", 0.0)
        row["passes"] = dict(kinds)
        return row, out

    return render, clock


def serve() -> None:
    """The ``baseline`` child: render ``after`` for each JSON request line on stdin, answer one
    JSON line (the row and the EXR's path) on stdout."""
    tmp = Path(tempfile.mkdtemp(prefix="frozen_render_baseline_"))
    render, _ = instrumented(tmp)
    import fogref

    print(json.dumps({"fogref": fogref.__file__}), flush=True)
    for line in sys.stdin:
        q = json.loads(line)
        row, out = render("after", tuple(q["res"]), q["spp"], q["seed"])
        print(json.dumps({"row": row, "exr": str(out)}), flush=True)


def worker_check(rounds: int = 200) -> dict:
    """A Dask worker's per-pass input check on valley at 32x18, in this process: ``every pass`` (the
    scene read, its inputs digested and the kept scene looked up on each pass, as it was) against
    ``once per render`` (:func:`fogref.render.distributed.render_pass`'s check), alternating, seconds."""
    import fogref.render.distributed as D

    res = {"res": 32, "resy": 18}
    j = D.job(SCENE, res, D.read_scene(SCENE, res).digest, "llvm_ad_rgb", 0, "centre", None)

    def every_pass():
        D.set_variant(j["variant"])
        parsed = D.read_scene(Path(j["scene"]), j["overrides"])
        assert parsed.digest == j["digest"]
        D.loaded_scene(parsed, j["threads"])

    def once_per_render():
        _, _, hashes = D._worker_scene(j)
        D._check_unchanged(j, hashes)

    times: dict = {"every pass": [], "once per render": []}
    for f in (every_pass, once_per_render):
        f()
    for _ in range(rounds):
        for name, f in (("every pass", every_pass), ("once per render", once_per_render)):
            t0 = time.perf_counter()
            f()
            times[name].append(time.perf_counter() - t0)
    return {k: quartiles(v) for k, v in times.items()} | {"n": rounds}


def channel_paths(rounds: int = 7) -> dict:
    """The driver's two ways from a render's float64 sums to the EXR's float32 planes, on the same
    sums (valley, 16 spp): ``host`` (numpy on the host copy, ``_float32_planes``, the copy included)
    and ``device`` (one Dr.Jit kernel, ``_device_float32``), alternating, seconds per resolution."""
    import drjit as dr
    import numpy as np

    import fogref.render.render as R
    from fogref.render import load

    out = {}
    for w, h in ((32, 18), (64, 36), (128, 72), (320, 180)):
        scene, _ = load.load_scene(SCENE, {"res": w, "resy": h})
        integrator = scene.integrator()
        integrator.aovs = True
        s, q = integrator.render_moments(scene, 0, 0, 16, pixel_exact=True)
        dr.eval(s, q)
        ways = {
            "host": lambda: R._float32_planes(R._channels(np.asarray(s), np.asarray(q), 16)),
            "device": lambda: R._device_float32(R._channels(s, q, 16)),
        }
        times: dict = {k: [] for k in ways}
        for f in ways.values():  # the first compiles the device's kernel
            f()
        for _ in range(rounds):
            for k, f in ways.items():
                t0 = time.perf_counter()
                f()
                times[k].append(time.perf_counter() - t0)
        out[f"{w}x{h}"] = {k: quartiles(v) for k, v in times.items()}
    return out | {"n": rounds, "limit": R.HOST_CHANNELS_MAX_PIXELS, "load_average": os.getloadavg()[0]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=12, help="renders per mode and case (small cases)")
    ap.add_argument("--big-rounds", type=int, default=3, help="renders per mode of the multi-pass case")
    ap.add_argument("--first", type=int, default=6, help="fresh scenes per first-pass policy")
    ap.add_argument("--baseline", help="another checkout's root: its fogref package as the mode 'baseline'")
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks"))
    ap.add_argument("--report-only", action="store_true", help="rewrite the Markdown from the JSON")
    ap.add_argument("--serve", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--channels-only", action="store_true", help="rerun only the channels' two paths")
    a = ap.parse_args()
    if a.serve:
        return serve()
    if a.channels_only:
        from fogref.render.variant import set_variant

        set_variant("llvm_ad_rgb")
        r = json.loads((Path(a.out) / "frozen_render.json").read_text())
        r["channel_paths"] = channel_paths()
        (Path(a.out) / "frozen_render.json").write_text(json.dumps(r, indent=1) + "\n")
        (Path(a.out) / "frozen_render.md").write_text(report(r))
        return
    if a.report_only:
        r = json.loads((Path(a.out) / "frozen_render.json").read_text())
        (Path(a.out) / "frozen_render.md").write_text(report(r))
        return

    load0 = os.getloadavg()
    tmp = Path(tempfile.mkdtemp(prefix="frozen_render_"))
    render, clock = instrumented(tmp)
    import drjit as dr
    import fogref_plugins.fogpath as fpm
    import mitsuba as mi
    import numpy as np

    from fogref.exrio import read_exr
    from fogref.render import load

    modes = [m for m in MODES if m != "baseline" or a.baseline]
    child, baseline = None, None
    if a.baseline:
        env = {**os.environ, "PYTHONPATH": str(Path(a.baseline).resolve())}
        child = subprocess.Popen(
            [sys.executable, __file__, "--serve"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            env=env,
        )
        baseline = {
            "tree": str(Path(a.baseline).resolve()),
            "commit": subprocess.run(
                ["git", "-C", a.baseline, "rev-parse", "--short", "HEAD"], capture_output=True, text=True
            ).stdout.strip(),
            "fogref": json.loads(child.stdout.readline())["fogref"],
        }

    def run(mode, res, spp, seed):
        if mode != "baseline":
            return render(mode, res, spp, seed)
        child.stdin.write(json.dumps({"res": res, "spp": spp, "seed": seed}) + "\n")
        child.stdin.flush()
        answer = json.loads(child.stdout.readline())
        return answer["row"], Path(answer["exr"])

    result: dict = {
        "machine": f"{platform.machine()}, {os.cpu_count()} cores (shared)",
        "mitsuba": mi.__version__,
        "drjit": dr.__version__,
        "variant": "llvm_ad_rgb",
        "record_from_call": fpm.RECORD_FROM_CALL,
        "load_average_before": load0[0],
        "modes": modes,
        "baseline": baseline,
        "cases": [],
    }
    for res, spp in CASES:
        rounds = a.big_rounds if res[0] * res[1] * spp > 1 << 20 else a.rounds
        case: dict = {
            "res": list(res),
            "spp": spp,
            "first": {},
            "rows": {m: [] for m in modes},
            "bitwise": True,
        }
        for mode in modes:  # the first render of each mode: compilation (or the disk cache), apart
            case["first"][mode] = run(mode, res, spp, 1000)[0]
        for r in range(rounds):
            order = modes[r % len(modes) :] + modes[: r % len(modes)]  # each mode first in turn
            pixels = {}
            for mode in order:
                row, exr = run(mode, res, spp, r)
                case["rows"][mode].append(row)
                channels, _ = read_exr(exr)
                pixels[mode] = np.stack([channels[k] for k in sorted(channels)])
            case["bitwise"] &= all(np.array_equal(pixels[m], pixels["after"]) for m in modes)
        case["summary"] = {
            m: {k: quartiles([row[k] for row in case["rows"][m]]) for k in ("wall", "host", *PHASES)}
            for m in modes
        }
        result["cases"].append(case)
        print(json.dumps({"res": res, "spp": spp, "summary": case["summary"]}), flush=True)
    if child is not None:
        child.stdin.close()
        child.wait()

    # what recording costs: a freshly loaded scene's first pass traced (freeze off) or recorded
    first: dict = {"traced": [], "recorded": []}
    policy = fpm.RECORD_FROM_CALL
    for i in range(2 * a.first + 2):
        kind = ("traced", "recorded")[i % 2]
        fpm.RECORD_FROM_CALL = 1
        scene, _ = load.load_scene(SCENE, {"res": 32, "resy": 18})
        fp = scene.integrator()
        fp.aovs, fp.freeze = True, kind == "recorded"
        clock.clear()
        fp.render_moments(scene, 0, i, 64, pixel_exact=True)
        if i >= 2:  # the first of each compiles
            first[kind].append(clock["trace"])
        del scene, fp
    fpm.RECORD_FROM_CALL = policy
    diff = [r - t for t, r in zip(first["traced"], first["recorded"])]
    result["first_pass"] = {
        "traced": quartiles(first["traced"]),
        "recorded": quartiles(first["recorded"]),
        "recorded_minus_traced": quartiles(diff),
        "n": len(diff),
    }
    result["worker_check"] = worker_check()
    result["channel_paths"] = channel_paths()
    result["load_average_after"] = os.getloadavg()[0]
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "frozen_render.json").write_text(json.dumps(result, indent=1) + "\n")
    (out / "frozen_render.md").write_text(report(result))
    print((out / "frozen_render.md").read_text())


def report(r: dict) -> str:
    """The Markdown page of a run."""
    ms = lambda q: f"{q[0] * 1e3:.0f} [{q[1] * 1e3:.0f}–{q[2] * 1e3:.0f}]"  # noqa: E731
    modes = r.get("modes", ["before", "after"])
    base = r.get("baseline")
    md = [
        "# A truth rendered again in a warm process: loaded scenes kept, fogpath's passes frozen",
        "",
        f"`benchmarks/frozen_render.py`: the render driver (`fogref.render.render.render`, EXR and "
        f"moments written) on `scenes/valley.xml`, one warm process, each render a new seed; "
        f"Mitsuba {r['mitsuba']}, Dr.Jit {r['drjit']}, `{r['variant']}`; {r['machine']}, load "
        f"average {r['load_average_before']:.1f} before and {r['load_average_after']:.1f} after.  "
        "`before`: the scene loaded for every render, fogpath's `freeze` off (as fogref was); "
        "`after`: the loaded scene kept and the passes frozen (a pass of a kind traced the first "
        f"time, recorded on call {r['record_from_call']}, replayed after)"
        + (
            f"; `baseline`: `after` with the `fogref` package of commit {base['commit']} (a child "
            "process, the same plugins), the driver before the changes since that commit"
            if base
            else ""
        )
        + '; `after, none`: `after` with `exr_compression="none"` (ZIP is the default).  Modes '
        "alternate; medians over the renders after each mode's first, interquartile range in "
        "brackets, milliseconds.  `host` = wall - kernel execution; `trace` = fogpath's passes "
        "less execution (tracing, recording or replaying, launches).",
    ]
    for c in r["cases"]:
        (w, h), spp = c["res"], c["spp"]
        n = len(c["rows"]["after"])
        md += [
            "",
            f"## {w}x{h}, {spp} spp ({n} renders per mode; EXRs of all modes bitwise equal: "
            f"{'yes' if c['bitwise'] else 'NO'})",
            "",
        ]
        head = "| mode | wall | host | host/wall | parse | load | trace | execution | channels | exr | rest |"
        md += [head + " passes (last render) |"]
        md += ["|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
        for m in modes:
            s = c["summary"][m]
            kinds = ", ".join(f"{v} {k}" for k, v in sorted(c["rows"][m][-1]["passes"].items()))
            share = statistics.median(row["host"] / row["wall"] for row in c["rows"][m])
            md.append(
                f"| {m} | {ms(s['wall'])} | {ms(s['host'])} | {share:.0%} | "
                + " | ".join(ms(s[p]) for p in PHASES)
                + f" | {kinds} |"
            )
        f = c["first"]
        md += [
            "",
            "First render of each mode (compilation, or Dr.Jit's disk cache, included): "
            + ", ".join(
                f"{m} {f[m]['wall'] * 1e3:.0f} ms (LLVM {f[m]['backend'] * 1e3:.0f} ms)" for m in modes
            )
            + ".",
        ]
    small = r["cases"][0]["summary"]
    share = {
        m: statistics.median(row["host"] / row["wall"] for row in r["cases"][0]["rows"][m]) for m in modes
    }
    met = lambda m: "met" if share[m] < 1 / 8 else "not met"  # noqa: E731
    rows = r["cases"][0]["rows"]
    paired = {  # after's host time over another mode's, render by render (the same round and seed)
        m: quartiles([a["host"] / b["host"] for a, b in zip(rows["after"], rows[m])])
        for m in modes
        if m != "after"
    }
    ratio = lambda m: f"{paired[m][0]:.2f} [{paired[m][1]:.2f}–{paired[m][2]:.2f}]"  # noqa: E731
    after = small["after"]
    md += [
        "",
        "## Fixed cost",
        "",
        f"At 32x18 and 64 spp the host time (everything but kernel execution) is {share['after']:.0%} "
        f"of the render's wall time after (goal: under 1/8 = 12.5%, {met('after')}), "
        f"{share['after, none']:.0%} with an uncompressed EXR ({met('after, none')})"
        + (f", {share['baseline']:.0%} with the driver of {base['commit']}" if base else "")
        + f", {share['before']:.0%} before (medians of the per-render ratios).  Of the "
        f"{after['host'][0] * 1e3:.0f} ms after, fogpath's replayed pass takes {after['trace'][0] * 1e3:.0f} "
        f"ms and loading {after['load'][0] * 1e3:.1f} ms (a kept scene); the rest is the driver's: "
        f"the channels {after['channels'][0] * 1e3:.1f} ms"
        + (f" ({small['baseline']['channels'][0] * 1e3:.1f} ms in {base['commit']})" if base else "")
        + f", the EXR (72 channels, ZIP) and moments files {after['exr'][0] * 1e3:.0f} ms "
        f"({small['after, none']['exr'][0] * 1e3:.0f} ms with an uncompressed EXR), reading the scene "
        f"{after['parse'][0] * 1e3:.1f} ms, checks, the inputs' listing and digest and the merge "
        f"{after['rest'][0] * 1e3:.0f} ms (medians of each phase; they do not add up to the median "
        "of the sum).  After's host time over each other mode's, render by render (same round and "
        "seed): " + ", ".join(f"{m} {ratio(m)}" for m in paired) + ".",
    ]
    fp = r["first_pass"]
    md += [
        "",
        "## Recording against tracing: a freshly loaded scene's first pass",
        "",
        f"32x18, 64 spp, host time of `render_moments` (wall - execution) of a freshly loaded "
        f"scene's first pass, `freeze` off (traced) and on (recorded), alternating, {fp['n']} pairs "
        f"after one of each that compiles: traced {ms(fp['traced'])} ms, recorded "
        f"{ms(fp['recorded'])} ms; recorded - traced, paired: {ms(fp['recorded_minus_traced'])} ms.",
    ]
    cp = r.get("channel_paths")
    if cp:
        sizes = [k for k in cp if "x" in k]
        md += [
            "",
            "## The channels: numpy on the host or one Dr.Jit kernel",
            "",
            f"The same float64 sums (valley, 16 spp) to the EXR's float32 planes, {cp['n']} of each "
            f"way alternating after one that compiles, load average {cp['load_average']:.1f}, ms: "
            + "; ".join(f"{k} host {ms(cp[k]['host'])}, device {ms(cp[k]['device'])}" for k in sizes)
            + f".  The driver takes the host's way up to {cp['limit']} pixels "
            "(`HOST_CHANNELS_MAX_PIXELS`), the device's above.",
        ]
    wc = r.get("worker_check")
    if wc:
        us = lambda q: f"{q[0] * 1e3:.2f} [{q[1] * 1e3:.2f}–{q[2] * 1e3:.2f}]"  # noqa: E731
        md += [
            "",
            "## A Dask worker's check of the inputs, per pass",
            "",
            f"valley at 32x18 (its one input file, the XML), in this process, alternating, {wc['n']} "
            f"of each: the scene read, its inputs listed and digested and the kept scene looked up on "
            f"every pass (as it was) {us(wc['every pass'])} ms; once per render, then each input's "
            f"memoised SHA-256 (a `stat`) after each pass {us(wc['once per render'])} ms.  The bytes "
            "of a large input were already read once per process (the hash is memoised on the file's "
            "size, times and inode) unless the file was modified in the 2 s before a pass; what every "
            "pass repeated was reading and walking the XML.",
        ]
    return "\n".join(md) + "\n"


if __name__ == "__main__":
    main()
