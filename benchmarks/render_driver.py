"""The render driver's cost: ``fogref render`` against one ``mi.render`` call of the same image.

For each case (the default scene at a resolution and spp) four ways of making the
same pixel-exact image are timed:

* ``mi.render``   — one ``mi.render(scene, spp=N)`` call on a loaded scene (fogpath's
  ``render``: the driver's passes, ``pixel_exact`` on, no sums of squares), result copied
  to numpy;
* ``render()``    — :func:`fogref.render.render.render` in this process (scene load,
  passes, float64 moments, EXR written, ``png=False``, no resume);
* ``CLI``         — ``fogref render ... --no-png --quiet --no-resume`` in a subprocess
  (Python start-up, imports, variant, scene load, render, EXR);
* ``mi.render script`` — a subprocess that imports fogref, loads the scene and makes the
  one ``mi.render`` call (the CLI's fixed costs without the driver).

Every method is called once per case first (tracing + LLVM compile or a kernel-cache
load: the *first call*), then the cases x methods are timed round-robin ``--repeats``
times (steady time: median and range).  Compile time = first call - median steady.
The order of the methods rotates per repeat (a fresh process's page faults depend on
what ran just before it), and Dr.Jit's memory cache is flushed before each call.  The
target is CLI / mi.render <= 1.1 at equal spp.  How many kernels over all lanes run the
path tracer per ``render_moments`` call is reported too (1: every output evaluated in
one kernel).

    .venv/bin/python benchmarks/render_driver.py [--quick] [--repeats 4]
        [--cases 320x180x64,320x180x256,640x360x64] [--variant cuda_ad_rgb]

Writes reports/benchmarks/render_driver.{json,md}.  No GPU is needed (or used):
``cuda_ad_rgb`` is measured only with ``--variant cuda_ad_rgb`` on a machine that has one.

``--startup [N]`` measures only the CLI's fixed start-up instead (seconds, no full run):
``fogref render`` of a tiny image (16x9, 1 spp; ``--startup-case WxHxSPP``) in N fresh
processes, each phase timed from process launch to exit (the minimum over the N runs, per
phase), and the plain console script's wall time; writes
reports/benchmarks/render_driver_startup.{json,md}.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: the environment's names before this process set any (fogref.set_variant sets DRJIT_LIBLLVM_PATH)
_USER_ENV = frozenset(os.environ)
SCENE = ROOT / "scenes" / "valley.xml"
PY = sys.executable


def path_kernels_per_call(scene_path=SCENE) -> dict:
    """How many kernels over all lanes with the path tracer in them one render_moments makes."""
    import drjit as dr

    from fogref.render.load import load_scene

    scene, _ = load_scene(scene_path, {"res": 16, "resy": 9})
    integ = scene.integrator()
    integ.aovs = True
    integ.render_moments(scene, 0, 0, 4, pixel_exact=True)
    dr.sync_thread()
    dr.kernel_history()
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        s, q = integ.render_moments(scene, 0, 1, 4, pixel_exact=True)
        dr.eval(s, q)
        dr.sync_thread()
        hist = dr.kernel_history()
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    lanes = 16 * 9 * 4
    big = [k for k in hist if k.get("size") == lanes and (k.get("operation_count") or 0) > 1000]
    return {
        "kernels": len(hist),
        "path_tracing_kernels": len(big),
        "ops_per_path_kernel": sorted({int(k.get("operation_count") or 0) for k in big}),
    }


# ------------------------------------------------------------------ methods


def _cli_cmd(w, h, spp, seed, out):
    script = Path(PY).parent / "fogref"  # the installed command; without an install, its module
    return [
        *([str(script)] if script.exists() else [PY, "-m", "fogref.cli"]),
        "render",
        str(SCENE),
        "--set",
        f"res={w}",
        "--set",
        f"resy={h}",
        "--spp",
        str(spp),
        "--seed",
        str(seed),
        "--out",
        str(out),
        "--no-png",
        "--quiet",
        "--no-resume",
    ]


_SCRIPT = """
import sys, time
import numpy as np
import fogref
fogref.set_variant()
import drjit as dr, mitsuba as mi
from fogref.render.load import load_scene
w, h, spp, seed = (int(x) for x in sys.argv[1:5])
scene, _ = load_scene({scene!r}, {{"res": w, "resy": h}})
integ = scene.integrator(); integ.pixel_exact = True; integ.aovs = True
img = np.asarray(mi.render(scene, spp=spp, seed=seed)); dr.sync_thread()
"""


def _run(cmd, env=None):
    t0 = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, cmd))} failed ({r.returncode}):\n{r.stderr[-3000:]}")
    return time.perf_counter() - t0


class Case:
    def __init__(self, w, h, spp, tmp: Path):
        import mitsuba as mi
        from fogref_plugins.passes import max_lanes, pass_sizes

        import fogref.render.render as R
        from fogref.render.load import load_scene

        self.w, self.h, self.spp, self.tmp = w, h, spp, tmp
        self.name = f"{w}x{h} {spp} spp"
        self.scene, _ = load_scene(SCENE, {"res": w, "resy": h})
        integ = self.scene.integrator()
        integ.pixel_exact, integ.aovs = True, True
        self.R = R
        self.script = tmp / "mi_render_script.py"
        self.script.write_text(_SCRIPT.format(scene=str(SCENE)))
        self.passes = pass_sizes(w * h, spp, max_lanes(mi.variant()))

    def mi_render(self, seed):
        import drjit as dr
        import mitsuba as mi
        import numpy as np

        t0 = time.perf_counter()
        img = np.asarray(mi.render(self.scene, spp=self.spp, seed=seed))
        dr.sync_thread()
        assert img.shape[:2] == (self.h, self.w)
        return time.perf_counter() - t0

    def render_fn(self, seed):
        t0 = time.perf_counter()
        self.R.render(
            SCENE,
            self.tmp / "fn.exr",
            spp=self.spp,
            seed=seed,
            overrides={"res": self.w, "resy": self.h},
            progress=False,
            resume=False,
            png=False,
        )
        return time.perf_counter() - t0

    def cli(self, seed):
        return _run(_cli_cmd(self.w, self.h, self.spp, seed, self.tmp / "cli.exr"))

    def mi_script(self, seed):
        return _run([PY, str(self.script), str(self.w), str(self.h), str(self.spp), str(seed)])


METHODS = {"mi.render": "mi_render", "render()": "render_fn", "CLI": "cli", "mi.render script": "mi_script"}


def measure(cases: list, repeats: int, log, after_repeat=None) -> dict:
    """First calls, then ``repeats`` interleaved rounds; ``after_repeat(summary, rounds done)``
    after each round but the last (a run stopped at a time limit keeps its finished rounds)."""
    res = {c.name: {m: {"first_s": None, "steady_s": []} for m in METHODS} for c in cases}
    for c in cases:  # first calls: tracing + compile (or kernel-cache load)
        for m, fn in METHODS.items():
            t = getattr(c, fn)(0)
            res[c.name][m]["first_s"] = t
            log(f"  first call  {c.name:18s} {m:17s} {t:7.2f} s")
    import drjit as dr

    names = list(METHODS)
    for r in range(repeats):  # interleaved: background load falls on every method alike
        for c in cases:
            # the order rotates per repeat: a fresh process started right after another one
            # exited reuses its freed pages, one started after a pause or beside this process's
            # memory faults them in from the VM (up to ~1 s at 640x360 on the measuring machine)
            for m in names[r % len(names) :] + names[: r % len(names)]:
                dr.flush_malloc_cache()  # in-process methods give their memory back first
                t = getattr(c, METHODS[m])(r + 1)
                res[c.name][m]["steady_s"].append(t)
                log(f"  repeat {r + 1}    {c.name:18s} {m:17s} {t:7.2f} s")
        if after_repeat is not None and r + 1 < repeats:
            after_repeat(summarize(res, cases), r + 1)
    return summarize(res, cases)


def summarize(res: dict, cases: list) -> dict:
    """``res`` (first calls and steady times per case and method) with medians, ranges, compile
    times and the ratios to ``mi.render`` added, in place."""
    for c in cases:
        d = res[c.name]
        for m in METHODS:
            s = d[m]["steady_s"]
            d[m]["median_s"] = statistics.median(s)
            d[m]["min_s"], d[m]["max_s"] = min(s), max(s)
            d[m]["compile_s"] = max(d[m]["first_s"] - d[m]["median_s"], 0.0)
        base = d["mi.render"]["median_s"]
        d["ratio"] = {m: d[m]["median_s"] / base for m in METHODS}
        # spread of the ratio: each repeat's own ratio (the methods of one repeat ran back to back)
        d["ratio_per_repeat"] = {
            m: [a / b for a, b in zip(d[m]["steady_s"], d["mi.render"]["steady_s"])] for m in METHODS
        }
        d["passes"] = c.passes
    return res


# ------------------------------------------------------------------ start-up breakdown (--startup)

#: The child of :func:`startup_breakdown`: runs ``fogref.cli.main`` with timers put on
#: fogref's functions as their modules are imported (an import hook; the import order is
#: the CLI's own), so no phase is moved by the measuring.  argv: launch time
#: (``time.perf_counter``, CLOCK_MONOTONIC: the same clock in parent and child), JSON path, CLI args.
_STARTUP_CHILD = r"""
import sys, time
first = time.perf_counter()
import importlib.abc, json
launch, out, argv = float(sys.argv[1]), sys.argv[2], sys.argv[3:]
ev = {"first_line": first - launch}
def clock(key, f, once=True):
    def w(*a, **k):
        t0 = time.perf_counter()
        try:
            return f(*a, **k)
        finally:
            if not (once and key in ev):
                ev[key] = (t0 - launch, time.perf_counter() - launch)
    return w
def first_moments(f):
    def w(*a, **k):
        if "render_moments" in ev:
            return f(*a, **k)
        import drjit as dr
        dr.kernel_history()
        dr.set_flag(dr.JitFlag.KernelHistory, True)
        t0 = time.perf_counter()
        try:
            return f(*a, **k)
        finally:
            dr.sync_thread()  # LLVM kernels run asynchronously: wait here, not in the copy to the host
            t1 = time.perf_counter()
            h = dr.kernel_history()
            dr.set_flag(dr.JitFlag.KernelHistory, False)
            ev["render_moments"] = (t0 - launch, t1 - launch)
            ev["kernels"] = len(h)
            ev["kernel_compile_s"] = sum(k.get("codegen_time", 0) + k.get("backend_time", 0) for k in h) / 1e3
            ev["kernel_run_s"] = sum(k.get("execution_time", 0) for k in h) / 1e3
    return w
def patch(name, m):
    if name == "fogref.render.render":
        m.render, m.write_exr = clock("render", m.render), clock("write_exr", m.write_exr)
    elif name == "fogref.render.variant":
        m.set_variant = clock("set_variant", m.set_variant)
        m.ensure_llvm = clock("ensure_llvm", m.ensure_llvm)
    elif name == "fogref_plugins":
        m.register = clock("register", m.register)
    elif name == "fogref.render.load":
        m.load_scene = clock("load_scene", m.load_scene)
        m.describe_scene = clock("describe_scene", m.describe_scene)
    elif name == "fogref_plugins.fogpath":
        m.FogPathIntegrator.render_moments = first_moments(m.FogPathIntegrator.render_moments)
WATCH = {"fogref.render.render", "fogref.render.variant", "fogref_plugins", "fogref.render.load",
         "fogref_plugins.fogpath", "fogref_plugins.fog_medium", "mitsuba", "drjit", "numpy", "fogref.cli"}
class Hook(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name not in WATCH or name in ev:
            return None
        for finder in sys.meta_path:  # the others (fogref_plugins comes from the editable install's finder)
            spec = None if finder is self else finder.find_spec(name, path, target)
            if spec is not None:
                break
        if spec is None or spec.loader is None or not hasattr(spec.loader, "exec_module"):
            return spec
        run = spec.loader.exec_module
        def exec_module(module):
            t0 = time.perf_counter()
            run(module)
            ev["import " + name] = (t0 - launch, time.perf_counter() - launch)
            patch(name, module)
        spec.loader.exec_module = exec_module
        return spec
sys.meta_path.insert(0, Hook())
from fogref.cli import main
sys.argv = ["fogref", *argv]
rc = main()  # as the console script calls it
ev["main_end"] = time.perf_counter() - launch
with open(out, "w") as f:
    json.dump(ev, f)
sys.exit(rc)
"""


def _startup_phases(ev: dict, exit_at: float) -> dict:
    """Seconds per phase of one instrumented CLI run (events: launch-relative (start, end))."""
    s = lambda k: ev[k][0]  # noqa: E731
    e = lambda k: ev[k][1]  # noqa: E731
    d = lambda k: e(k) - s(k)  # noqa: E731
    imp_dr, imp_mi = d("import drjit"), d("import mitsuba")
    if s("import mitsuba") <= s("import drjit") <= e("import mitsuba"):  # `import mitsuba` imported Dr.Jit
        imp_mi -= imp_dr
    imp_med, imp_fp = d("import fogref_plugins.fog_medium"), d("import fogref_plugins.fogpath")
    rm = d("render_moments")
    ph = {
        "interpreter start (python, site)": ev["first_line"],
        "import fogref.cli, parse arguments": s("render")
        - ev["first_line"]
        - d("import fogref.render.render"),
        "import fogref.render.render (numpy, OpenEXR glue)": d("import fogref.render.render"),
        "render(): checks before set_variant": s("set_variant") - s("render"),
        "set_variant: find LLVM": d("ensure_llvm"),
        "set_variant: import drjit": imp_dr,
        "set_variant: import mitsuba (without drjit)": imp_mi,
        "set_variant: mi.set_variant (and the rest)": d("set_variant")
        - d("ensure_llvm")
        - imp_dr
        - imp_mi
        - d("register"),
        "register: import fog_medium (+fogref.media)": imp_med,
        "register: import fogpath (+dr.syntax)": imp_fp,
        "register: the rest": d("register") - imp_med - imp_fp,
        "load_scene: describe_scene (XML, validation)": d("describe_scene"),
        "load_scene: mi.load_file": d("load_scene") - d("describe_scene"),
        "render(): between load_scene and the first pass": s("render_moments") - e("load_scene"),
        "first pass: tracing (Python)": rm - ev["kernel_compile_s"] - ev["kernel_run_s"],
        "first pass: kernel compile / cache load": ev["kernel_compile_s"],
        "first pass: kernels run": ev["kernel_run_s"],
        "after the pass: sums to host, channels": s("write_exr") - e("render_moments"),
        "write_exr": d("write_exr"),
        "after write_exr, until main returns": ev["main_end"] - e("write_exr"),
        "process exit": exit_at - ev["main_end"],
    }
    ph["= launch to first kernel launch"] = s("render_moments") + rm - ev["kernel_run_s"]
    ph["= launch to exit"] = exit_at
    return ph


def startup_breakdown(repeats: int, log, w: int = 16, h: int = 9, spp: int = 1) -> dict:
    """``fogref render`` of a w x h, spp image in fresh processes: per-phase times (instrumented
    child) and the plain console script's wall time, each the minimum over ``repeats`` runs."""
    runs, plain = [], []
    with tempfile.TemporaryDirectory(prefix="fogref-startup-") as tmp:
        out = Path(tmp) / "x.exr"
        args = [
            "render",
            str(SCENE),
            "--set",
            f"res={w}",
            "--set",
            f"resy={h}",
            "--spp",
            str(spp),
            "--out",
            str(out),
            "--no-png",
            "--quiet",
            "--no-resume",
        ]
        # the child finds LLVM itself, as a user's shell does (this process's set_variant set the variable)
        env = {k: v for k, v in os.environ.items() if k != "DRJIT_LIBLLVM_PATH" or k in _USER_ENV}

        def instrumented(r):
            js = Path(tmp) / f"ev{r}.json"
            t0 = time.perf_counter()
            p = subprocess.run(
                [PY, "-c", _STARTUP_CHILD, repr(t0), str(js), *args],
                capture_output=True,
                text=True,
                env=env,
                cwd=tmp,
            )  # not ROOT: `python -c` puts the folder first on sys.path
            t1 = time.perf_counter()
            if p.returncode != 0:
                raise RuntimeError(f"instrumented fogref render failed:\n{p.stderr[-3000:]}")
            return _startup_phases(json.loads(js.read_text()), t1 - t0)

        # warm the kernel cache and the file cache (the kernel history flag is part of a kernel's key)
        _run([str(Path(PY).parent / "fogref"), *args], env=env)
        instrumented(-1)
        for r in range(repeats):  # interleaved: instrumented, plain, `python -c pass`
            runs.append(instrumented(r))
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            wall = _run([str(Path(PY).parent / "fogref"), *args], env=env)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            # as a user types it: the PNG preview, the float64 sums kept, the progress bar, resume checks
            typed = [a for a in args if a not in ("--no-png", "--quiet", "--no-resume")]
            before_typed = resource.getrusage(resource.RUSAGE_CHILDREN)
            wall_typed = _run([str(Path(PY).parent / "fogref"), *typed], env=env)
            after_typed = resource.getrusage(resource.RUSAGE_CHILDREN)
            plain.append(
                {
                    "fogref render (console script)": wall,
                    "fogref render (console script), CPU user + sys": after.ru_utime
                    - before.ru_utime
                    + after.ru_stime
                    - before.ru_stime,
                    "fogref render as typed (PNG, moments, progress bar)": wall_typed,
                    "fogref render as typed, CPU user + sys": after_typed.ru_utime
                    - before_typed.ru_utime
                    + after_typed.ru_stime
                    - before_typed.ru_stime,
                    "python -c pass": _run([PY, "-c", "pass"], env=env),
                }
            )
            log(
                f"  run {r + 1}: launch to first kernel {runs[-1]['= launch to first kernel launch']:.3f} s, "
                f"to exit {runs[-1]['= launch to exit']:.3f} s; console script "
                f"{plain[-1]['fogref render (console script)']:.3f} s"
            )
    return {
        "case": f"{w}x{h} {spp} spp",
        "repeats": repeats,
        "phases_min_s": {k: min(r[k] for r in runs) for k in runs[0]},
        "phases_median_s": {k: statistics.median(r[k] for r in runs) for k in runs[0]},
        "plain_min_s": {k: min(p[k] for p in plain) for k in plain[0]},
        "plain_median_s": {k: statistics.median(p[k] for p in plain) for k in plain[0]},
        "runs": runs,
        "plain": plain,
    }


def _startup_md(doc: dict) -> str:
    b = doc["startup"]
    L = [
        "# `fogref render` start-up: process launch to the first kernel (CPU, llvm_ad_rgb)",
        "",
        f"Command: `{doc['command']}`.  Machine: {doc['machine']['cpu']}, {doc['machine']['cores']} cores, "
        f"shared with other jobs (load average {doc['load_before']} before, {doc['load_after']} after); "
        f"Mitsuba {doc['machine']['mitsuba']}, Dr.Jit {doc['machine']['drjit']}.",
        "",
        f"`fogref render scenes/valley.xml` at {b['case']} (`--no-png --quiet --no-resume`), kernel cache "
        f"warm, {b['repeats']} fresh processes per method, interleaved.  Phases come from an instrumented "
        "child (timers put on fogref's functions by an import hook, as their modules are imported; the "
        "launch time is the parent's `perf_counter`, the same monotonic clock).  Each phase: the minimum "
        "over the runs (and the median); the totals' minimum is over whole runs, so the phases' minima "
        "need not add up to it.",
        "",
        "| phase | min [s] | median [s] |",
        "|---|---|---|",
    ]
    for k, v in b["phases_min_s"].items():
        bold = "**" if k.startswith("=") else ""
        L.append(f"| {bold}{k}{bold} | {bold}{v:.3f}{bold} | {b['phases_median_s'][k]:.3f} |")
    L += [
        "",
        "Uninstrumented, wall time or the process's CPU time (user + sys: what the machine's load does "
        "not inflate), min [median]:",
        "",
    ]
    for k, v in b["plain_min_s"].items():
        L.append(f"* {k}: {v:.3f} s [{b['plain_median_s'][k]:.3f}]")
    L.append("")
    if doc.get("reading"):
        L += ["## Reading", "", doc["reading"], ""]
    return "\n".join(L)


# ------------------------------------------------------------------ report


def _md(doc: dict) -> str:
    variant = doc.get("variant", "llvm_ad_rgb")
    L = [
        f"# Render driver vs one `mi.render` call ({variant})",
        "",
        f"Command: `{doc['command']}`.  Machine: {doc['machine']['cpu']}, {doc['machine']['cores']} cores, "
        f"shared with other jobs while measured (load average {doc['load_before']} before, "
        f"{doc['load_after']} after); Mitsuba {doc['machine']['mitsuba']}, Dr.Jit {doc['machine']['drjit']}.",
        *(
            [f"**Partial: {doc['repeats_done']} of {doc['repeats']} repeats** (the run stopped after them)."]
            if doc.get("repeats_done", doc["repeats"]) < doc["repeats"]
            else []
        ),
        "",
        "Scene: `scenes/valley.xml` (pixel-exact, all AOVs, max_depth 16).  Methods: `mi.render` = one "
        "call on a loaded scene; `render()` = `fogref.render.render.render` in the same process (scene "
        "load, passes, float64 moments, EXR, no PNG); `CLI` = `fogref render ... --no-png --quiet "
        "--no-resume` in a subprocess; `mi.render script` = a subprocess that imports fogref, loads the "
        "scene and calls `mi.render` once.  First call = tracing + LLVM compile or kernel-cache load; "
        "steady = median of the interleaved repeats [min, max]; compile = first - steady.  Ratios are of "
        "medians; in brackets the range of the per-repeat ratios.",
        "",
        f"fogpath `render_moments`: {doc['kernels']['path_tracing_kernels']} kernel(s) over all lanes "
        f"that contain the path tracer ({doc['kernels']['kernels']} kernels in all) per call.",
        "",
    ]
    for label, runs in doc["runs"].items():
        L += [
            f"## {label}",
            "",
            "| case | passes (spp each) | method | first call [s] | steady [s] median [min, max] | "
            "compile [s] | / mi.render |",
            "|---|---|---|---|---|---|---|",
        ]
        for case, d in runs.items():
            for m in METHODS:
                x = d[m]
                rr = d["ratio_per_repeat"][m]
                L.append(
                    f"| {case} | {len(d['passes'])} ({', '.join(map(str, sorted(set(d['passes']))))}) | {m} "
                    f"| {x['first_s']:.2f} | {x['median_s']:.2f} [{x['min_s']:.2f}, {x['max_s']:.2f}] | "
                    f"{x['compile_s']:.2f} | {d['ratio'][m]:.2f}x [{min(rr):.2f}, {max(rr):.2f}] |"
                )
        L.append("")
        L += [
            "Fair comparison (both fresh processes with the same start-up): `CLI` / `mi.render script`, "
            "ratio of medians [range of the per-repeat ratios]:",
            "",
        ]
        for case, d in runs.items():
            rr = [a / b for a, b in zip(d["CLI"]["steady_s"], d["mi.render script"]["steady_s"])]
            L.append(
                f"* {case}: {d['CLI']['median_s'] / d['mi.render script']['median_s']:.2f}x "
                f"[{min(rr):.2f}, {max(rr):.2f}]"
            )
        L.append("")
    if not variant.startswith("cuda"):
        L += [
            "cuda_ad_rgb: not measured here; run `benchmarks/render_driver.py --variant cuda_ad_rgb` on a "
            "GPU.",
            "",
        ]
    if doc.get("reading"):
        L += ["## Reading", "", doc["reading"], ""]
    return "\n".join(L)


def _load():
    return ", ".join(f"{x:.1f}" for x in os.getloadavg())


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", default="320x180x64,320x180x256,640x360x64", help="WxHxSPP,...")
    ap.add_argument(
        "--repeats", type=int, default=4, help="timed rounds (4: each method once in each position)"
    )
    ap.add_argument("--variant", default=None, help="Mitsuba variant (default llvm_ad_rgb)")
    ap.add_argument("--quick", action="store_true", help="64x36x16 only, 1 repeat (smoke test)")
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks" / "render_driver"))
    ap.add_argument("--reading", default=None, help="a file whose text goes under 'Reading' in the .md")
    ap.add_argument(
        "--startup",
        type=int,
        nargs="?",
        const=7,
        default=None,
        metavar="N",
        help="only the CLI's start-up breakdown (16x9, 1 spp) in N fresh processes (default 7); "
        "writes <out>_startup.{json,md}",
    )
    ap.add_argument("--startup-case", default="16x9x1", metavar="WxHxSPP", help="the image of --startup")
    a = ap.parse_args(argv)
    if a.startup is not None:
        return main_startup(a, argv)
    if a.quick:
        a.cases, a.repeats = "64x36x16", 1
    if a.variant:
        os.environ["FOGREF_VARIANT"] = a.variant
    sys.path.insert(0, str(ROOT))
    import fogref

    variant = fogref.set_variant(a.variant)
    cases = [tuple(int(x) for x in c.split("x")) for c in a.cases.split(",")]
    log = lambda s: print(s, flush=True)  # noqa: E731
    doc = {
        "command": "python benchmarks/render_driver.py "
        + " ".join(argv if argv is not None else sys.argv[1:]),
        "load_before": _load(),
        "cases": a.cases,
        "repeats": a.repeats,
        "variant": variant,
    }
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from _common import machine_info

    doc["machine"] = machine_info()
    doc["kernels"] = path_kernels_per_call()
    log(f"render_moments: {doc['kernels']}")
    from fogref_plugins.passes import MAX_LANES

    doc["max_lanes"] = MAX_LANES
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)

    def write(runs, repeats_done):
        doc["runs"], doc["repeats_done"], doc["load_after"] = {"fogpath": runs}, repeats_done, _load()
        out.with_suffix(".json").write_text(json.dumps(doc, indent=2) + "\n")
        out.with_suffix(".md").write_text(_md(doc))
        log(f"wrote {out.with_suffix('.md')} and .json ({repeats_done} of {a.repeats} repeats)")

    if a.reading:
        doc["reading"] = Path(a.reading).read_text().strip()
    with tempfile.TemporaryDirectory(prefix="fogref-bench-") as tmp:
        cases_ = [Case(w, h, s, Path(tmp)) for w, h, s in cases]
        runs = measure(cases_, a.repeats, log, after_repeat=write)
    write(runs, a.repeats)


def main_startup(a, argv) -> None:
    """``--startup N``: :func:`startup_breakdown`, written to ``<out>_startup.{json,md}``."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from _common import machine_info

    log = lambda s: print(s, flush=True)  # noqa: E731
    doc = {
        "command": "python benchmarks/render_driver.py "
        + " ".join(argv if argv is not None else sys.argv[1:]),
        "load_before": _load(),
        "machine": machine_info(),
    }
    w, h, spp = (int(x) for x in a.startup_case.split("x"))
    doc["startup"] = startup_breakdown(a.startup, log, w, h, spp)
    doc["load_after"] = _load()
    if a.reading:
        doc["reading"] = Path(a.reading).read_text().strip()
    out = Path(a.out + "_startup")
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps(doc, indent=2) + "\n")
    out.with_suffix(".md").write_text(_startup_md(doc))
    for k, v in doc["startup"]["phases_min_s"].items():
        log(f"  {k:55s} {v:7.3f} s")
    log(f"wrote {out.with_suffix('.md')} and .json")


if __name__ == "__main__":
    main()
