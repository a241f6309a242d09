"""Where a cold CI render's seconds go: a 32x18, 64-spp truth of the default scene, phase by phase.

A CI job that keeps nothing between runs starts in a fresh home: no Dr.Jit kernel cache
(``~/.drjit``), no fogref syntax cache (``~/.cache/fogref/drjit-syntax``).  Each run here is a
fresh process (``--child``) with ``$HOME`` set to a new empty folder (``cold``) or to the folder
of a previous run (``warm``: the caches that run left), timing the phases of
:func:`fogref.render.render.render` as it runs them:

* ``python``: interpreter start-up to the first line of the script;
* ``import``: ``import fogref.render.render`` (numpy, fogref's modules);
* ``variant``: :func:`fogref.render.variant.set_variant` (LLVM discovery, Mitsuba and Dr.Jit
  import, the plugins' registration and their ``dr.syntax`` rewriting);
* ``inputs``: listing and hashing the scene's inputs (the checkpoint key);
* ``load``: :func:`fogref.render.load.load_scene`;
* ``pass``: the one ``render_moments`` call, split with Dr.Jit's kernel history into Python
  tracing (the rest), code generation, LLVM compilation (``backend``; nothing on a kernel-cache
  hit) and execution;
* ``channels``: means and errors on the device and the one host copy;
* ``exr``: writing the EXR.

The command-line total (``fogref render ... --quiet --no-png``, cold and warm) is timed too, and
what its start-up imports cost (``python -X importtime``, cumulative per package).

    .venv/bin/python benchmarks/cold_start.py [--repeats 2]

Writes reports/benchmarks/cold_start.{json,md}.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "valley.xml"
OVERRIDES = {"res": 32, "resy": 18}
SPP = 64
PHASES = ("python", "import", "variant", "inputs", "load", "tracing", "codegen", "backend", "execution")
PHASES += ("channels", "exr")


def child(t_launch: float, out: str) -> None:
    """One cold or warm render in this fresh process, printing its phases as JSON."""
    t = {"python": time.time() - t_launch}
    t0 = time.perf_counter()

    def lap(name):
        nonlocal t0
        now = time.perf_counter()
        t[name] = now - t0
        t0 = now

    import fogref.render.render as R

    lap("import")
    from fogref.render.variant import set_variant

    variant = set_variant(None)
    import drjit as dr

    lap("variant")
    from fogref.scene.inputs import inputs_digest, scene_inputs

    inputs_digest(SCENE, OVERRIDES, scene_inputs(SCENE, OVERRIDES))
    lap("inputs")
    from fogref.render.load import load_scene

    scene, desc = load_scene(SCENE, OVERRIDES)
    integrator = scene.integrator()
    integrator.aovs = True
    lap("load")
    from fogref_plugins.passes import max_lanes, pass_seed, pass_sizes

    passes = pass_sizes(32 * 18, SPP, max_lanes(variant))
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    dr.kernel_history()
    state = None
    for k, n in enumerate(passes):
        s, q = integrator.render_moments(scene, 0, pass_seed(0, k), n, pixel_exact=True)
        if state is not None:
            s, q = state[0] + s, state[1] + q
        dr.eval(s, q)
        dr.sync_thread()
        state = (s, q)
    hist = dr.kernel_history()
    dr.set_flag(dr.JitFlag.KernelHistory, False)
    whole = time.perf_counter() - t0
    jit = [k for k in hist if str(k.get("type", "")).endswith("JIT")]
    t["codegen"] = sum(k.get("codegen_time", 0.0) for k in jit) / 1e3
    t["backend"] = sum(k.get("backend_time", 0.0) for k in jit) / 1e3
    t["execution"] = sum(k.get("execution_time", 0.0) for k in hist) / 1e3
    t["tracing"] = max(0.0, whole - t["codegen"] - t["backend"] - t["execution"])
    t["kernels"] = len(jit)
    t["kernels_compiled"] = sum(1 for k in jit if k.get("backend_time", 0.0) > 0.05)
    t0 = time.perf_counter()
    import numpy as np

    sums, squares = np.asarray(state[0]), np.asarray(state[1])
    channels = R._float32_planes(R._channels(sums, squares, SPP))[0]  # 32x18: the driver's host path
    lap("channels")
    from fogref.exrio import write_exr

    write_exr(Path(out), channels, {"fogref.spp": str(SPP)})
    lap("exr")
    t["total"] = time.time() - t_launch
    print(json.dumps(t))


def _run_child(home: Path, out: Path) -> dict:
    env = {**os.environ, "HOME": str(home)}
    r = subprocess.run(
        [sys.executable, __file__, "--child", repr(time.time()), str(out)],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(r.stdout.strip().splitlines()[-1])


def _run_cli(home: Path, out: Path) -> float:
    env = {**os.environ, "HOME": str(home)}
    cmd = [sys.executable, "-m", "fogref.cli", "render", str(SCENE), "--out", str(out), "--spp", str(SPP)]
    cmd += ["--set", "res=32", "--set", "resy=18", "--quiet", "--no-png", "--no-resume"]
    t0 = time.perf_counter()
    subprocess.run(cmd, env=env, capture_output=True, check=True)
    return time.perf_counter() - t0


#: Imports whose cumulative time ``python -X importtime`` reports (a module counts where it is
#: first imported: ``fogref.models`` inside ``fogref.mapping``, for instance).
IMPORTS = ("fogref.render.render", "numpy", "fogref.mapping", "fogref.models", "fogref.gbuffer")
IMPORTS += ("drjit", "mitsuba", "mitsuba.llvm_ad_rgb", "fogref_plugins.fogpath")


def _import_times(home: Path) -> dict:
    """Cumulative import time [s] of :data:`IMPORTS` in a fresh process that imports the render
    driver and sets the variant (Mitsuba, Dr.Jit, the plugins), as ``fogref render --quiet``
    does, from ``python -X importtime``; ``all`` is the sum of the top-level imports."""
    code = "import fogref.render.render; from fogref.render.variant import set_variant; set_variant(None)"
    env = {**os.environ, "HOME": str(home)}
    r = subprocess.run(
        [sys.executable, "-X", "importtime", "-c", code], env=env, capture_output=True, text=True, check=True
    )
    out: dict = {"all": 0.0}
    for line in r.stderr.splitlines():
        if not line.startswith("import time:") or "cumulative" in line:
            continue
        _, cumulative, name = line.split("|")
        seconds = int(cumulative) / 1e6
        if not name.startswith("  "):  # top level: counted once
            out["all"] += seconds
        out.setdefault(name.strip(), seconds)
    return {k: out.get(k, 0.0) for k in ("all", *IMPORTS)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--child", nargs=2, metavar=("T_LAUNCH", "OUT"))
    args = ap.parse_args()
    if args.child:
        child(float(args.child[0]), args.child[1])
        return
    runs: dict = {"cold": [], "warm": [], "cli_cold": [], "cli_warm": [], "imports": []}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.repeats):
            home = Path(tmp) / f"home{i}"
            home.mkdir()
            runs["cold"].append(_run_child(home, Path(tmp) / f"c{i}.exr"))
            runs["warm"].append(_run_child(home, Path(tmp) / f"w{i}.exr"))
            cli_home = Path(tmp) / f"cli{i}"
            cli_home.mkdir()
            runs["cli_cold"].append(_run_cli(cli_home, Path(tmp) / f"cc{i}.exr"))
            runs["cli_warm"].append(_run_cli(cli_home, Path(tmp) / f"cw{i}.exr"))
            runs["imports"].append(_import_times(cli_home))
            cold, warm = runs["cold"][-1]["total"], runs["warm"][-1]["total"]
            cli = f"CLI {runs['cli_cold'][-1]:.2f} / {runs['cli_warm'][-1]:.2f} s"
            print(f"repeat {i}: cold {cold:.2f} s, warm {warm:.2f} s, {cli}", file=sys.stderr)
    med = {
        w: {
            p: statistics.median(r[p] for r in runs[w])
            for p in (*PHASES, "total", "kernels", "kernels_compiled")
        }
        for w in ("cold", "warm")
    }
    result = {
        "scene": "scenes/valley.xml",
        "res": [32, 18],
        "spp": SPP,
        "repeats": args.repeats,
        "load_average": os.getloadavg()[0],
        "runs": runs,
        "median": med,
    }
    out = ROOT / "reports" / "benchmarks"
    (out / "cold_start.json").write_text(json.dumps(result, indent=1) + "\n")
    rows = [
        f"| {p} | {med['cold'][p]:.2f} | {med['warm'][p]:.2f} | {med['cold'][p] - med['warm'][p]:+.2f} |"
        for p in (*PHASES, "total")
    ]
    cli = {w: statistics.median(runs[f"cli_{w}"]) for w in ("cold", "warm")}
    imports = {k: statistics.median(r[k] for r in runs["imports"]) for k in runs["imports"][0]}
    result["imports"] = imports
    (out / "cold_start.json").write_text(json.dumps(result, indent=1) + "\n")
    import_rows = "\n".join(f"| `{k}` | {v:.3f} |" for k, v in imports.items() if k != "all")
    md = f"""# Cold start of a CI render: where the seconds go

`benchmarks/cold_start.py`: `scenes/valley.xml` at 32x18, {SPP} spp, seed 0, each run a fresh
process; **cold**: `$HOME` a new empty folder (no Dr.Jit kernel cache `~/.drjit`, no fogref syntax
cache `~/.cache/fogref/drjit-syntax`), **warm**: the same process again in the `$HOME` the cold run
left.  Medians of {args.repeats} (2-core machine shared with other work, load average
{result["load_average"]:.1f}).

| phase | cold [s] | warm [s] | cold - warm [s] |
|---|---:|---:|---:|
{chr(10).join(rows)}

Kernels launched by the pass: {med["cold"]["kernels"]:.0f}; compiled by LLVM (backend > 50 ms):
{med["cold"]["kernels_compiled"]:.0f} cold, {med["warm"]["kernels_compiled"]:.0f} warm.  `tracing` is the
pass's wall time less code generation, compilation and execution (Python running fogpath's
`@dr.syntax` loop to record the kernel).

`fogref render` on the command line, same image, `--quiet --no-png --no-resume`: {cli["cold"]:.2f} s
cold, {cli["warm"]:.2f} s warm (median wall time of the whole process).

Where a warm command line's start-up goes: `python -X importtime` of what `fogref render`
imports with `--quiet` (the render driver, `set_variant`) in a fresh, warm process, cumulative seconds,
median of {args.repeats}; {imports["all"]:.2f} s in all (a module counts where it is first
imported):

| import | cumulative [s] |
|---|---:|
{import_rows}

What a CI keeps between runs decides most of the difference: `~/.drjit` (Dr.Jit's kernel
cache) removes the `backend` (LLVM compilation) row, and `~/.cache/fogref` the `dr.syntax`
rewriting inside `variant`.
"""
    (out / "cold_start.md").write_text(md)
    print(out / "cold_start.md")


if __name__ == "__main__":
    main()
