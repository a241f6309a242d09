"""The example sweep before and after, side by side: wall time, phases, identical results
-> reports/benchmarks/sweep_speed.{md,json}.

Checkouts, each with its own ``.venv`` (``scripts/setup.sh``): one or more ``--base`` (e.g. a clone
of main: ``git clone -q /work/main /tmp/base && bash /tmp/base/scripts/setup.sh``; the first is
``base``, the next ``base2``, ...) and this one (``after``).

* **Command**: ``fogref sweep`` on a copy of ``reports/sweeps/unreal_sun_falloff_g/SWEEP.toml``
  (48 configurations, valley, 64x36 px, 16 spp, model ue4 with its Unreal fit), each run from an
  empty truth cache and an empty fit cache (``$FOGREF_CACHE``), the Dr.Jit kernel cache warm
  (every checkout compiles the same kernels), or empty with ``--empty-kernel-cache`` (``HOME`` a
  fresh folder per run: a user's first sweep on a machine); runs alternate base, [base2, ...,]
  after, base ...; the wall time of the whole process, the sweep's own "configurations in X s",
  the CPU time of the process and its workers (user + sys, what the machine's load does not
  inflate) and the load average before and after each run.
* **Phases**: one process per checkout runs one configuration to warm up (its imports and kernels
  are a fixed cost, timed apart), then ``--phase-configs`` configurations (spread over the
  grid) one after the other, with no cluster, timers put on the functions of each phase
  (the render's parse, load, passes and EXR write; the truth's reads; the model's build, that is
  the Unreal fit; the comparison's parts) and the table and plots at the end; fixed costs
  (imports, reading the sweep) apart from per-configuration costs.  With ``--dask-malloc``, this
  checkout's phases once more with ``MALLOC_TRIM_THRESHOLD_=65536``, the variable Dask's nanny
  sets in its workers and fogref's LocalCluster leaves out (a column of its own).
* **Identity**: the two command runs' ``results.csv`` must agree in every cell but the timings and
  the run's own paths (``scene_path``, ``render_seconds``, ``compare_seconds``, ``worker_pid``,
  ``worker_host``, ``truth_path``, ``truth_cached``, ``truth_sha256``: the truth EXR's header holds
  its render time, so the file's hash differs between any two runs), every truth's pixels must be
  equal bit for bit and every plot's pixels (decoded: the PNGs' zlib level is not part of what
  is compared); plots drawn otherwise (a new style) are counted apart from the numbers.

    .venv/bin/python benchmarks/sweep_speed.py --base /tmp/base [--base /tmp/base2] [--repeats 1]
        [--phase-configs 12] [--dask-malloc]
"""

from __future__ import annotations

import argparse
import csv
import functools
import importlib
import json
import os
import platform
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

import numpy as np
from _checkouts import commit_of, example_sweep, kept_reading
from PIL import Image

ROOT = Path(__file__).resolve().parents[1]
#: Columns of results.csv that hold timings or the run's own paths (module doc).
RUN_COLUMNS = (
    "scene_path",
    "render_seconds",
    "compare_seconds",
    "worker_pid",
    "worker_host",
    "truth_path",
    "truth_cached",
    "truth_sha256",
)
#: What Dask's nanny sets in its workers by default (``distributed.nanny.pre-spawn-environ``) and
#: fogref's LocalCluster leaves out (:data:`fogref.cluster.WORKER_UNSET_ENV`): ``--dask-malloc``
#: runs this checkout's phases with it too, under this name.
DASK_MALLOC_ENV = {"MALLOC_TRIM_THRESHOLD_": "65536"}
DASK_MALLOC = "after, MALLOC_TRIM_THRESHOLD_=65536"
#: (module, function, phase) timed in the phase child; indented phases are parts of the one above; a
#: phase may name two functions (a checkout has one of them).
PHASES = (
    ("fogref.study.sweep.task", "render_cached", "render (fogref.render.cache.render_cached)"),
    ("fogref.render.cache", "read_scene", "  parse the scene XML (read_scene; also for the key)"),
    ("fogref.render.load", "load_scene", "  load_scene (describe, mi.load_file)"),
    ("fogref_plugins.fogpath", "render_moments", "  passes: tracing, kernels (render_moments)"),
    ("fogref.render.render", "write_exr", "  write the truth EXR"),
    ("fogref.study.sweep.task", "read_exr", "read the truth's header (read_exr)"),
    ("fogref.study.sweep.task", "load_truth", "read the truth (load_truth)"),
    ("fogref.study.sweep.task", "file_sha256", "hash the truth file"),
    ("fogref.study.sweep.task", "build_model", "build the model (ue4: the Unreal fit)"),
    ("fogref.study.sweep.task", "compare", "compare (metrics of every part)"),
    ("fogref.study.sweep.task", "compare_metrics", "compare (metrics of every part)"),
    ("fogref.compare.report", "load_truth", "  compare: read the truth"),
    ("fogref.compare.report", "evaluate_parts", "  compare: evaluate the model"),
    ("fogref.compare.report", "error_maps", "  compare: error maps (incl. dE2000, FLIP)"),
    ("fogref.compare.error_maps", "flip_map", "  compare: FLIP maps (model and noise floor)"),
    ("fogref.compare.error_maps", "delta_e2000_map", "  compare: dE2000 maps (model and noise floor)"),
    ("fogref.compare.error_maps", "delta_e2000_maps", "  compare: dE2000 maps (model and noise floor)"),
    ("fogref.compare.report", "binned_errors", "  compare: binned errors"),
    ("fogref.compare.report", "write_exr", "  compare: write errors.exr"),
    ("fogref.compare.report", "write_text_atomic", "  compare: write metrics.json, index.md"),
)


def _env(work: Path, empty_kernel_cache: bool = False) -> dict:
    env = dict(os.environ, FOGREF_CACHE=str(work / "fits-cache"))
    env.pop("PYTHONPATH", None)
    if empty_kernel_cache:  # Dr.Jit's disk cache is ~/.drjit
        (work / "home").mkdir(parents=True, exist_ok=True)
        env["HOME"] = str(work / "home")
    return env


# ------------------------------------------------------------------ the command, end to end
def run_command(tree: Path, work: Path, empty_kernel_cache: bool = False) -> dict:
    """``fogref sweep`` of ``tree`` on a fresh copy of the example in ``work``."""
    shutil.rmtree(work, ignore_errors=True)
    sweep = example_sweep(tree, work)
    load0 = os.getloadavg()
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run(
        [str(tree / ".venv" / "bin" / "fogref"), "sweep", str(sweep), "--quiet"],
        cwd=work,
        env=_env(work, empty_kernel_cache),
        capture_output=True,
        text=True,
    )
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        raise SystemExit(f"{tree}: fogref sweep failed ({p.returncode}):\n{p.stderr[-3000:]}")
    line = next(x for x in p.stdout.splitlines() if "configurations" in x)
    return {
        "tree": str(tree),
        "wall_s": wall,
        "sweep_line": line,
        "configs_s": float(line.split(" in ")[1].split(" s")[0]),
        "cpu_s": (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime),
        "load_before": load0,
        "load_after": os.getloadavg(),
    }


def _truth_pixels(folder: Path, rows: dict) -> dict:
    """The truth EXR of every row under ``folder``, found by its file name (the render cache's key,
    which hashes the renderer's sources, so it differs between checkouts): row key -> {channel: bytes}."""
    from fogref.exrio import read_exr

    files = {f.name: f for f in folder.rglob("*.exr")}
    out = {}
    for k, r in rows.items():
        f = files.get(Path(r["truth_path"]).name)
        out[k] = None if f is None else {c: a.tobytes() for c, a in read_exr(f)[0].items()}
    return out


def _numbers(cell: str):
    """The numbers of a ``results.csv`` cell, in order (a number, or JSON holding numbers), with
    its text less those numbers; None for text with no number in it.

    >>> _numbers('{"a": [1.5, 2], "b": "x"}')
    ([1.5, 2.0], '{"a": [#, #], "b": "x"}')
    >>> _numbers("0.25"), _numbers("ue4")
    (([0.25], '#'), None)
    """
    try:
        value = json.loads(cell)
    except ValueError:
        return None
    found: list[float] = []

    def walk(v):
        if isinstance(v, bool) or v is None or isinstance(v, str):
            return v
        if isinstance(v, (int, float)):
            found.append(float(v))
            return "#"
        if isinstance(v, list):
            return [walk(x) for x in v]
        return {k: walk(x) for k, x in v.items()}

    shape = json.dumps(walk(value)).replace('"#"', "#")
    return (found, shape) if found else None


def _relative_difference(a: str, b: str) -> float | None:
    """The largest ``|x - y| / max(|x|, |y|)`` over the numbers of two cells of the same shape
    (:func:`_numbers`; 0 where both are 0); None when they are not both numbers of one shape.

    >>> _relative_difference("[1.0, 2.0]", "[1.0, 2.5]")
    0.2
    >>> _relative_difference("1.0", "x") is None
    True
    """
    na, nb = _numbers(a), _numbers(b)
    if na is None or nb is None or na[1] != nb[1]:
        return None
    x, y = np.array(na[0]), np.array(nb[0])
    if not (np.isfinite(x).all() and np.isfinite(y).all()):
        return None if not np.array_equal(x, y, equal_nan=True) else 0.0
    scale = np.maximum(np.abs(x), np.abs(y))
    return float(np.max(np.where(scale > 0, np.abs(x - y) / np.where(scale > 0, scale, 1.0), 0.0)))


def identical(base: Path, after: Path) -> dict:
    """Cell by cell (but :data:`RUN_COLUMNS`), pixel by pixel and byte by byte.

    ``{"ok": every cell, pixel and plot equal, "close": the cells that differ, per column, with
    their largest relative difference (numbers of one shape), "differ": what differs otherwise
    (text, pixels, plots, columns), ...}``."""
    rows = [list(csv.DictReader((d / "results.csv").open())) for d in (base, after)]
    key = [{r["config_id"] + "/" + r["model"]: r for r in rs} for rs in rows]
    differ, close, n_close = [], {}, 0
    if set(key[0]) != set(key[1]):
        differ.append("the rows' (config_id, model) differ")
    for k in sorted(set(key[0]) & set(key[1])):
        a, b = key[0][k], key[1][k]
        if set(a) != set(b):
            differ.append(f"{k}: columns differ")
        for c in a:
            if c in RUN_COLUMNS or a[c] == b.get(c):
                continue
            rel = _relative_difference(a[c], b.get(c, ""))
            if rel is None:
                differ.append(f"{k}: {c}: {a[c][:80]!r} != {str(b.get(c))[:80]!r}")
            else:
                close[c], n_close = max(close.get(c, 0.0), rel), n_close + 1
    px = [_truth_pixels(d / "cache", rows) for d, rows in zip((base, after), key)]
    if px[0] != px[1]:
        differ.append("truth pixels differ: " + ", ".join(n for n in px[0] if px[0].get(n) != px[1].get(n)))
    pngs = sorted(p.name for p in (base / "plots").glob("*.png"))
    plots_differ = [
        n
        for n in pngs
        if not (after / "plots" / n).is_file()
        or not np.array_equal(
            np.asarray(Image.open(base / "plots" / n)), np.asarray(Image.open(after / "plots" / n))
        )
    ]
    if pngs != sorted(p.name for p in (after / "plots").glob("*.png")):
        differ.append("the plots' names differ")
    cells = sum(len(r) - len(RUN_COLUMNS) for r in rows[0])
    return {
        "ok": not differ and not close and not plots_differ,
        "plots_differ": plots_differ,
        "rows": len(rows[0]),
        "cells_compared": cells,
        "cells_close": n_close,
        "close": dict(sorted(close.items(), key=lambda kv: -kv[1])),
        "truths": len(px[0]),
        "plots": len(pngs),
        "differ": differ[:20],
    }


# ------------------------------------------------------------------ phases, one process, no cluster
def phase_child(tree: Path, work: Path, n_configs: int) -> None:
    """(Runs in the checkout's own interpreter.)  Print the phases' JSON on the last line of stdout."""
    t_start = time.perf_counter()
    shutil.rmtree(work, ignore_errors=True)
    sweep = example_sweep(tree, work)
    os.environ["FOGREF_CACHE"] = str(work / "fits-cache")
    acc: dict = defaultdict(float)
    cpu: dict = defaultdict(float)
    cnt: dict = defaultdict(int)

    def wrap(owner, name: str, label: str) -> None:
        f = getattr(owner, name, None)
        if f is None:
            return

        @functools.wraps(f)
        def timed(*a, **k):
            t, c = time.perf_counter(), time.process_time()
            try:
                return f(*a, **k)
            finally:
                acc[label] += time.perf_counter() - t
                cpu[label] += time.process_time() - c
                cnt[label] += 1

        setattr(owner, name, timed)

    import fogref.study.sweep as S
    from fogref.render.variant import set_variant

    t_import = time.perf_counter()
    set_variant(None)
    for mod, name, label in PHASES:
        m = importlib.import_module(mod)
        if name == "render_moments":  # a method of the integrator class
            for c in vars(m).values():
                if isinstance(c, type) and "render_moments" in vars(c):
                    wrap(c, name, label)
        else:
            wrap(m, name, label)
    t_setup = time.perf_counter()
    spec = S.load_sweep(sweep)
    configs = S.build_configs(spec)
    step = max(1, len(configs) // n_configs)
    chosen = configs[::step][:n_configs]
    t_spec = time.perf_counter()
    (work / "configs").mkdir(exist_ok=True)
    # the first configuration imports what a comparison needs (colour-science, flip_evaluator) and
    # loads the kernels: a fixed cost, timed apart; its phases are not averaged in
    rest = [c for c in configs if c not in chosen]
    warm_up = rest[0] if rest else chosen.pop(0)  # --phase-configs as large as the sweep: one fewer timed
    S.run_config(warm_up, os.cpu_count())
    t_warm = time.perf_counter()
    for d in (acc, cpu, cnt):
        d.clear()
    per, per_cpu = [], []
    for cfg in chosen:
        t, c = time.perf_counter(), time.process_time()
        r = S.run_config(cfg, os.cpu_count())
        body = json.dumps({**r, "status": "ok", "config": cfg}, indent=1, default=str) + "\n"
        (work / "configs" / f"{cfg['id']}.json").write_text(body)
        per.append(time.perf_counter() - t)
        per_cpu.append(time.process_time() - c)
    t_cfg = time.perf_counter()
    S.write_table(spec, chosen)
    t_table = time.perf_counter()
    import drjit
    import mitsuba
    import numpy

    print(
        json.dumps(
            {
                "configs": len(per),
                "fixed": {
                    "import fogref.study.sweep": t_import - t_start,
                    "Mitsuba variant, timers": t_setup - t_import,
                    "read the sweep, build the configurations": t_spec - t_setup,
                    "a first configuration (imports, kernels; not in the table above)": t_warm - t_spec,
                    "table and plots (of these configurations)": t_table - t_cfg,
                },
                "per_config_s": per,
                "per_config_cpu_s": per_cpu,
                "phases": {
                    k: {"s": acc[k], "cpu_s": cpu[k], "calls": cnt[k]} for _, _, k in PHASES if cnt[k]
                },
                "versions": {
                    "mitsuba": mitsuba.__version__,
                    "drjit": drjit.__version__,
                    "numpy": numpy.__version__,
                },
            }
        )
    )


def run_phases(tree: Path, work: Path, n_configs: int, env: dict | None = None) -> dict:
    """The phase child of ``tree`` (``env``: variables to add to its environment)."""
    load0 = os.getloadavg()
    p = subprocess.run(
        [str(tree / ".venv" / "bin" / "python"), __file__, "--child", str(tree), str(work), str(n_configs)],
        cwd=tree,
        env={**_env(work), **(env or {})},
        capture_output=True,
        text=True,
    )
    if p.returncode != 0:
        raise SystemExit(f"{tree}: phase run failed:\n{p.stderr[-3000:]}")
    return {
        **json.loads(p.stdout.strip().splitlines()[-1]),
        "load_before": load0,
        "load_after": os.getloadavg(),
    }


# ------------------------------------------------------------------ report
def _median(xs):
    xs = sorted(xs)
    n = len(xs)
    return (xs[n // 2] + xs[(n - 1) // 2]) / 2 if n else float("nan")


def report(res: dict) -> str:
    runs = res["command"]
    names = [n for n in res["trees"] if n != "after"]
    after = [r for r in runs if r["which"] == "after"]
    commits = "; ".join(f"{n}: `{res['trees'][n]}` at {res['commits'][n]}" for n in names)
    L = [
        "# The example sweep before and after (`fogref sweep`, 48 configurations)",
        "",
        f"Command: `{res['command_line']}`.  Machine: {res['machine']}; {res['versions']}.  "
        f"{commits}; after: this checkout at {res['commits']['after']}.",
        "",
        "Sweep: `reports/sweeps/unreal_sun_falloff_g/SWEEP.toml` (valley, sun elevation x "
        "FogHeightFalloff x g, "
        "64x36 px, 16 spp, model ue4 fitted to each truth), a LocalCluster of one single-threaded worker per "
        "core, every run from an empty truth cache and an empty fit cache, the Dr.Jit kernel cache "
        f"{res.get('kernel_cache', 'warm')}.  "
        f"Runs alternate {', '.join(names)}, after, ...  CPU = user + sys of the command and its workers.",
        "",
        "| run | checkout | wall [s] | sweep's 'configurations in' [s] | CPU [s] | "
        "load average before -> after (1 min) |",
        "|---|---|---|---|---|---|",
    ]
    for i, r in enumerate(runs):
        L.append(
            f"| {i + 1} | {r['which']} | {r['wall_s']:.1f} | {r['configs_s']:.1f} | {r['cpu_s']:.1f} | "
            f"{r['load_before'][0]:.1f} -> {r['load_after'][0]:.1f} |"
        )
    for n in names:
        base = [r for r in runs if r["which"] == n]
        if base and after:
            rw = [b["wall_s"] / a["wall_s"] for b, a in zip(base, after)]
            rc = [b["cpu_s"] / a["cpu_s"] for b, a in zip(base, after)]
            L += [
                "",
                f"**Speed-up ({n} / after, runs of one round): wall {', '.join(f'{x:.2f}x' for x in rw)}; "
                f"CPU {', '.join(f'{x:.2f}x' for x in rc)}.**",
            ]
    for n in names:
        ident = res.get("identical", {}).get(n)
        if ident:
            close = ident.get("close", {})
            drawn = ident.get("plots_differ", [])
            verdict = (
                "**identical**"
                if ident["ok"]
                else "**DIFFERENT**"
                if ident["differ"]
                else f"**equal to {max(close.values()):.1e} relative**"
                if close
                else f"**cells and truths identical; {len(drawn)} of {ident['plots']} plots drawn otherwise**"
            )
            L += [
                "",
                f"Identity ({n} / after): {verdict}: "
                f"{ident['rows']} rows, {ident['cells_compared']} cells compared (all but "
                f"{', '.join(RUN_COLUMNS)}), the pixels of {ident['truths']} truths, "
                f"and of {ident['plots']} plots.",
            ]
            if close:
                L += [
                    "",
                    f"{ident['cells_close']} cells hold other numbers (the rest of every cell, every "
                    "truth's pixels and every plot are the same); the largest relative difference "
                    "per column:",
                    "",
                    "| column | cells' largest relative difference |",
                    "|---|---:|",
                    *(f"| `{c}` | {r:.1e} |" for c, r in list(close.items())[:12]),
                ]
                if len(close) > 12:
                    L.append(f"| ({len(close) - 12} more columns) | <= {list(close.values())[12]:.1e} |")
            L += [f"* {d}" for d in ident["differ"]]
            if drawn and close:
                L += ["", f"{len(drawn)} of {ident['plots']} plots are drawn otherwise."]
    ph = res.get("phases")
    if ph:
        others = [c for c in ph if c != "after"]  # the bases and, with --dask-malloc, after with it
        cols = [*others, "after"]
        n = ph["after"]["configs"]
        loads = ", ".join(f"{c} {ph[c]['load_before'][0]:.1f} -> {ph[c]['load_after'][0]:.1f}" for c in cols)
        L += [
            "",
            f"## Phases (one process, no cluster, {n} of the 48 configurations spread over the grid, "
            "one after the other, after one more that imports and loads what they share; timers on "
            "the phases' functions)",
            "",
            f"Load average (1 min) before -> after: {loads}.  "
            "Rows marked (part) are parts of the row above; 'per configuration': the phase's total over the "
            "configurations divided by their number; CPU: the process's (all its threads).",
            "",
            "| phase | "
            + " | ".join(f"{c}: wall, CPU per configuration [s]" for c in cols)
            + " | "
            + " | ".join(f"{c} / after (CPU)" for c in others)
            + " |",
            "|---|" + "---|" * (len(cols) + len(others)),
        ]
        for k in dict.fromkeys(label for _, _, label in PHASES):
            xs = [ph[c]["phases"].get(k) for c in cols]
            cells = [f"{x['s'] / n:.3f}, {x['cpu_s'] / n:.3f}" if x else "not called" for x in xs]
            y = xs[-1]
            ratios = [
                f"{x['cpu_s'] / y['cpu_s']:.2f}x" if x and y and y["cpu_s"] > 0 else "" for x in xs[:-1]
            ]
            part = " (part)" if k.startswith("  ") else ""
            L.append(f"| {k.strip()}{part} | " + " | ".join(cells + ratios) + " |")
        tot = {c: sum(ph[c]["per_config_cpu_s"]) for c in cols}
        cells = [f"{_median(ph[c]['per_config_s']):.3f}, {tot[c] / n:.3f}" for c in cols]
        ratios = [f"{tot[c] / tot['after']:.2f}x" for c in others]
        L.append(
            "| **a configuration, all of it** (wall median, CPU mean) | " + " | ".join(cells + ratios) + " |"
        )
        L += [
            "",
            "| fixed cost | " + " | ".join(f"{c} [s]" for c in cols) + " |",
            "|---" * (len(cols) + 1) + "|",
        ]
        for k in ph["after"]["fixed"]:
            L.append(
                f"| {k} | " + " | ".join(f"{ph[c]['fixed'].get(k, float('nan')):.2f}" for c in cols) + " |"
            )
    L += ["", *res.get("reading", [])]
    return "\n".join(L) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--base", action="append", help="a checkout to compare with (with its own .venv); repeatable"
    )
    ap.add_argument("--repeats", type=int, default=1, help="command runs of each checkout (default 1)")
    ap.add_argument(
        "--phase-configs", type=int, default=12, help="configurations of the phase runs (0: none)"
    )
    ap.add_argument(
        "--empty-kernel-cache",
        action="store_true",
        help="each command run with an empty Dr.Jit kernel cache (HOME a fresh folder)",
    )
    ap.add_argument(
        "--dask-malloc",
        action="store_true",
        help="also a phase run of this checkout with the MALLOC_TRIM_THRESHOLD_ Dask's nanny sets",
    )
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks" / "sweep_speed"))
    ap.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.child:
        phase_child(Path(a.child[0]), Path(a.child[1]), int(a.child[2]))
        return 0
    if not a.base:
        ap.error("--base is required")
    bases = [Path(b).resolve() for b in a.base]
    trees = {("base" if i == 0 else f"base{i + 1}"): b for i, b in enumerate(bases)}
    trees["after"] = ROOT
    for t in trees.values():
        if not (t / ".venv" / "bin" / "fogref").is_file():
            raise SystemExit(f"{t}: no .venv/bin/fogref (run scripts/setup.sh there)")
    res: dict = {
        "command_line": "python benchmarks/sweep_speed.py "
        + " ".join(argv if argv is not None else sys.argv[1:]),
        "machine": f"{platform.machine()}, {os.cpu_count()} cores",
        "trees": {w: str(t) for w, t in trees.items()},
        "commits": {w: commit_of(t) for w, t in trees.items()},
        "kernel_cache": "empty (HOME a fresh folder per run)" if a.empty_kernel_cache else "warm",
        "command": [],
    }
    with tempfile.TemporaryDirectory(prefix="fogref-sweep-speed-") as tmp:
        last = {}
        for i in range(a.repeats):
            for which, tree in trees.items():
                r = run_command(tree, Path(tmp) / f"{which}-{i}", a.empty_kernel_cache)
                res["command"].append({"which": which, **r})
                last[which] = Path(tmp) / f"{which}-{i}"
                print(
                    f"{which}: {r['wall_s']:.1f} s wall, {r['cpu_s']:.1f} s CPU, "
                    f"load {r['load_before'][0]:.1f}",
                    flush=True,
                )
        res["identical"] = {w: identical(last[w], last["after"]) for w in trees if w != "after"}
        for w, ident in res["identical"].items():
            close = list(ident["close"].items())[:3]
            print(f"identical ({w}):", ident["ok"], ident["differ"][:3], close, flush=True)
        if a.phase_configs:
            res["phases"] = {
                w: run_phases(t, Path(tmp) / f"phases-{w}", a.phase_configs) for w, t in trees.items()
            }
            if a.dask_malloc:  # after's phases as in a Dask nanny's worker (a column before after's)
                dask = run_phases(ROOT, Path(tmp) / "phases-dask", a.phase_configs, DASK_MALLOC_ENV)
                after = res["phases"].pop("after")
                res["phases"].update({DASK_MALLOC: dask, "after": after})
    v = (res.get("phases") or {}).get("after", {}).get("versions", {})
    res["versions"] = ", ".join(f"{k} {x}" for k, x in v.items()) or "versions not recorded"
    out = Path(a.out)
    reading = kept_reading(out.with_suffix(".md"))  # the hand-written reading is kept across reruns
    if reading:
        res["reading"] = reading
    out.with_suffix(".json").write_text(json.dumps(res, indent=1, default=str) + "\n")
    out.with_suffix(".md").write_text(report(res))
    print(out.with_suffix(".md").read_text())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
