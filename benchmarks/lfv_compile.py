"""A Local Fog Volume scene's first render (compile) and steady render time: free flight's Newton
steps traced unrolled against one symbolic loop, side by side.

The scene is the one of ``docs/findings.md`` (the volume alone over the ground, sun and sky) at
32x18: ``fogref scene --sigma-t 0.02 --density 0 --lfv-centre 0,11,40 --lfv-radius 10
--lfv-density 5 --albedo 0.9 --g 0.2 --sun-elevation 30 --sun-azimuth 20 --camera-origin 0,5,0
--camera-target 0,9,40 --fov 60 --res 32 --resy 18``.  Three versions of
:meth:`fogref.media.local_fog_volume.LocalFogVolume.sample`, each run in a fresh process whose
``$HOME`` is a new empty folder (no Dr.Jit kernel cache ``~/.drjit``, no fogref ``dr.syntax``
cache), round-robin over the repeats so that background load falls on all alike:

* ``before``: the code at ``--before-rev`` (a temporary git worktree on ``PYTHONPATH``; the
  plugins are this checkout's, which the change leaves alone), whose 64 Newton steps are traced
  one after another into the kernel;
* ``loop64``: this checkout with :func:`~fogref.media.local_fog_volume.iterate`'s fixed-point
  exit taken out (a symbolic loop of exactly 64 steps): what the loop alone changes;
* ``after``: this checkout (the symbolic loop; a lane leaves at a fixed point).

In each process: ``first``, the wall time of the first ``mi.render`` (4 spp, seed 0; tracing,
code generation, LLVM compilation, execution), with Dr.Jit's kernel history split into code
generation and LLVM compilation (``backend``) of the kernels compiled; ``steady``, the median
wall time of ``--steady`` renders at 64 spp (seeds 1, 2, ...), ``dr.sync_thread()`` inside the
clock; the SHA-256 of the first 64-spp image's float32 bits, which must be the same in all
versions (the loop is bit for bit the unrolled steps).

    .venv/bin/python benchmarks/lfv_compile.py [--repeats 3] [--steady 5] [--before-rev REV]

Writes reports/benchmarks/lfv_compile.{json,md}.
"""

from __future__ import annotations

import argparse
import hashlib
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
OUT = ROOT / "reports" / "benchmarks"
SCENE_ARGS = "--sigma-t 0.02 --density 0 --lfv-centre 0,11,40 --lfv-radius 10 --lfv-density 5 --albedo 0.9"
SCENE_ARGS += " --g 0.2 --sun-elevation 30 --sun-azimuth 20 --camera-origin 0,5,0 --camera-target 0,9,40"
SCENE_ARGS += " --fov 60 --res 32 --resy 18"
FIRST_SPP, STEADY_SPP = 4, 64
VERSIONS = ("before", "loop64", "after")
#: The commit before free flight's steps became a symbolic loop.
BEFORE_REV = "28ab169"


def loop64(ops, step, state, iterations):
    """:func:`fogref.media.local_fog_volume.iterate`'s Dr.Jit loop without its fixed-point exit."""
    dr = ops.dr
    UInt = dr.uint32_array_t(ops.Float)
    out = dr.while_loop(
        (UInt(0), *state), lambda i, *_: i < iterations, lambda i, *x: (i + 1, *step(*x)), label="iterate"
    )
    return tuple(out[1:])


def child(version: str, scene_path: str, steady_n: int) -> None:
    """One fresh process: first render, then steady renders; prints JSON."""
    import drjit as dr
    import numpy as np

    import fogref
    from fogref.media import local_fog_volume
    from fogref.render.load import load_scene

    if version == "loop64":
        local_fog_volume.iterate = loop64
    import mitsuba as mi

    scene, _ = load_scene(Path(scene_path))
    load = os.getloadavg()[0]
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    dr.kernel_history()
    t0 = time.perf_counter()
    img = mi.render(scene, spp=FIRST_SPP, seed=0)
    dr.eval(img)
    dr.sync_thread()
    first = time.perf_counter() - t0
    hist = dr.kernel_history()
    dr.set_flag(dr.JitFlag.KernelHistory, False)
    jit = [k for k in hist if str(k.get("type", "")).endswith("JIT")]
    compiled = [k for k in jit if not k.get("cache_hit", False)]
    largest = max(jit, key=lambda k: k.get("operation_count") or 0)
    steady, digest = [], ""
    for seed in range(1, steady_n + 1):
        t0 = time.perf_counter()
        img = mi.render(scene, spp=STEADY_SPP, seed=seed)
        dr.eval(img)
        dr.sync_thread()
        steady.append(time.perf_counter() - t0)
        if seed == 1:
            digest = hashlib.sha256(
                np.ascontiguousarray(np.array(img, dtype=np.float32)).tobytes()
            ).hexdigest()
    print(
        json.dumps(
            {
                "first_s": first,
                "codegen_s": sum(k.get("codegen_time", 0.0) for k in compiled) / 1e3,
                "backend_s": sum(k.get("backend_time", 0.0) for k in compiled) / 1e3,
                "kernels_compiled": len(compiled),
                "largest_kernel_ops": largest.get("operation_count"),
                "steady_s": steady,
                "steady_median_s": statistics.median(steady),
                "image_sha256": digest,
                "load_average": [load, os.getloadavg()[0]],
                "fogref": str(Path(fogref.__file__).parents[1]),
                "has_iterate": hasattr(local_fog_volume, "iterate"),
                "mitsuba": mi.__version__,
                "drjit": dr.__version__,
                "variant": mi.variant(),
            }
        )
    )


def run_child(version: str, root: Path, scene: Path, home: Path, steady_n: int) -> dict:
    env = {**os.environ, "HOME": str(home), "PYTHONPATH": str(root)}
    env.pop("FOGREF_SYNTAX_CACHE", None)
    cmd = [sys.executable, __file__, "--child", version, str(scene), "--steady", str(steady_n)]
    r = subprocess.run(cmd, cwd=root, env=env, capture_output=True, text=True)
    if r.returncode:
        raise SystemExit(f"{version}: child failed ({r.returncode}):\n{r.stderr[-3000:]}")
    return json.loads(r.stdout.strip().splitlines()[-1])


def cpu_name() -> str:
    for line in Path("/proc/cpuinfo").read_text().splitlines():
        if line.startswith("model name"):
            return line.split(":", 1)[1].strip()
    return platform.processor()


def spread(xs: list[float]) -> dict:
    return {"median": statistics.median(xs), "min": min(xs), "max": max(xs), "n": len(xs)}


def report(d: dict) -> str:
    s = d["summary"]
    rows = []
    for v in VERSIONS:
        x = s[v]

        def cell(k, x=x, p=2):
            return f"{x[k]['median']:.{p}f} ({x[k]['min']:.{p}f}–{x[k]['max']:.{p}f})"

        rows.append(
            f"| `{v}` | {cell('first_s')} | {cell('codegen_s', p=3)} | {cell('backend_s')} | "
            f"{x['largest_kernel_ops']} | {cell('steady_median_s', p=3)} |"
        )
    r, pr = d["ratios"], d["paired_ratios"]

    def rng(k):
        return f"{pr[k]['median']:.2f} ({pr[k]['min']:.2f}–{pr[k]['max']:.2f})"

    m = d["machine"]
    load = d["load_average"]
    return f"""# Local Fog Volume: first render (compile) and steady time, Newton steps unrolled vs a loop

`benchmarks/lfv_compile.py` (`{d["command"]}`): the volume scene of `docs/findings.md` at
32x18 (`fogref scene {SCENE_ARGS}`), `llvm_ad_rgb`; each version {d["repeats"]} fresh processes,
each in a new empty `$HOME` (no Dr.Jit kernel cache, no `dr.syntax` cache), round-robin.
**first**: wall seconds of the first `mi.render` ({FIRST_SPP} spp: tracing, code generation,
LLVM compilation, execution); **codegen**, **backend**: Dr.Jit's kernel history over the kernels
compiled in it; **steady**: per process the median wall seconds of {d["steady"]} renders at
{STEADY_SPP} spp, `dr.sync_thread()` inside the clock.  Median (min–max) over the processes.

* `before`: `{d["before_rev"]}` (a git worktree), free flight's 64 Newton steps traced unrolled;
* `loop64`: this checkout with `iterate`'s fixed-point exit taken out (a symbolic loop of 64 steps);
* `after`: `{d["after_rev"]}`, the symbolic loop, a lane leaving at a bitwise fixed point.

| version | first [s] | codegen [s] | backend [s] | ops of the largest kernel | steady, 64 spp [s] |
|---|---:|---:|---:|---:|---:|
{chr(10).join(rows)}

Ratios of medians, before / after: first render {r["first"]:.1f}x, LLVM compilation
{r["backend"]:.1f}x, steady {r["steady"]:.2f}x (before / loop64: first {r["first_loop64"]:.1f}x,
steady {r["steady_loop64"]:.2f}x).  The same ratios per repeat (the versions' processes one after
another, so that they share the load), median (min–max): before / after first {rng("first")},
steady {rng("steady")}; before / loop64 first {rng("first_loop64")}, steady {rng("steady_loop64")}.
The 64-spp images are bit for bit equal in all {d["processes"]} processes: {d["images_equal"]}.

Machine: {m["cpu"]}, {m["cores"]} cores shared with other work; load average (1 min) from
{load["min"]:.1f} to {load["max"]:.1f} over the run; Python {m["python"]}, Mitsuba {m["mitsuba"]},
Dr.Jit {m["drjit"]}.  Compare the versions within this run, not across runs.
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--steady", type=int, default=5, help="steady renders per process")
    ap.add_argument("--before-rev", default=BEFORE_REV)
    ap.add_argument("--child", nargs=2, metavar=("VERSION", "SCENE"))
    ap.add_argument("--report-only", action="store_true", help="rewrite the .md from the .json")
    a = ap.parse_args()
    if a.child:
        child(a.child[0], a.child[1], a.steady)
        return
    from fogref.atomic import write_text_atomic

    if a.report_only:
        write_text_atomic(OUT / "lfv_compile.md", report(json.loads((OUT / "lfv_compile.json").read_text())))
        return
    tmp = Path(tempfile.mkdtemp(prefix="fogref-lfv-bench-"))
    before = tmp / "before"
    subprocess.run(
        ["git", "-C", str(ROOT), "worktree", "add", "-q", "--detach", str(before), a.before_rev], check=True
    )
    roots = {"before": before, "loop64": ROOT, "after": ROOT}
    runs: dict = {v: [] for v in VERSIONS}
    try:
        scene = tmp / "lfv.xml"
        subprocess.run(
            [sys.executable, "-m", "fogref.cli", "scene", "--out", str(scene), *SCENE_ARGS.split()],
            check=True,
        )
        for i in range(a.repeats):
            for v in VERSIONS:
                home = tmp / f"home-{v}-{i}"
                home.mkdir()
                runs[v].append(run_child(v, roots[v], scene, home, a.steady))
                x = runs[v][-1]
                print(
                    f"repeat {i} {v}: first {x['first_s']:.2f} s (backend {x['backend_s']:.2f} s), "
                    f"steady {x['steady_median_s']:.3f} s, load {x['load_average'][0]:.1f}",
                    file=sys.stderr,
                )
    finally:
        subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(before)], check=False)
    for v in VERSIONS:  # each version ran the code it names
        want = str(before) if v == "before" else str(ROOT)
        assert all(x["fogref"] == want and x["has_iterate"] == (v != "before") for x in runs[v]), v
    keys = ("first_s", "codegen_s", "backend_s", "steady_median_s")
    summary = {v: {k: spread([x[k] for x in runs[v]]) for k in keys} for v in VERSIONS}
    for v in VERSIONS:
        summary[v]["largest_kernel_ops"] = runs[v][0]["largest_kernel_ops"]

    def ratio(k, num="before", den="after"):
        return summary[num][k]["median"] / summary[den][k]["median"]

    def paired(k, num="before", den="after"):  # per repeat: the processes ran one after another
        return spread([x[k] / y[k] for x, y in zip(runs[num], runs[den])])

    loads = [y for v in VERSIONS for x in runs[v] for y in x["load_average"]]
    digests = {x["image_sha256"] for v in VERSIONS for x in runs[v]}
    head = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
    )
    first = runs["after"][0]
    d = {
        "command": " ".join(["benchmarks/lfv_compile.py", *sys.argv[1:]]),
        "scene": f"fogref scene {SCENE_ARGS}",
        "first_spp": FIRST_SPP,
        "steady_spp": STEADY_SPP,
        "steady": a.steady,
        "repeats": a.repeats,
        "processes": a.repeats * len(VERSIONS),
        "before_rev": a.before_rev,
        "after_rev": head.stdout.strip(),
        "machine": {
            "cpu": cpu_name(),
            "cores": os.cpu_count(),
            "python": platform.python_version(),
            "mitsuba": first["mitsuba"],
            "drjit": first["drjit"],
            "variant": first["variant"],
        },
        "load_average": spread(loads),
        "images_equal": len(digests) == 1,
        "ratios": {
            "first": ratio("first_s"),
            "backend": ratio("backend_s"),
            "steady": ratio("steady_median_s"),
            "first_loop64": ratio("first_s", "before", "loop64"),
            "steady_loop64": ratio("steady_median_s", "before", "loop64"),
        },
        "paired_ratios": {
            "first": paired("first_s"),
            "steady": paired("steady_median_s"),
            "first_loop64": paired("first_s", "before", "loop64"),
            "steady_loop64": paired("steady_median_s", "before", "loop64"),
        },
        "summary": summary,
        "runs": runs,
    }
    write_text_atomic(OUT / "lfv_compile.json", json.dumps(d, indent=1) + "\n")
    write_text_atomic(OUT / "lfv_compile.md", report(d))
    print(OUT / "lfv_compile.md")
    if len(digests) != 1:
        raise SystemExit(f"the versions' images differ: {sorted(digests)}")


if __name__ == "__main__":
    main()
