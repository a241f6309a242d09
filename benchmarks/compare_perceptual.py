"""`fogref compare` with and without its perceptual metrics (ΔE2000, HDR-FLIP), side by side.
-> reports/benchmarks/compare_perceptual.{json,md}

``fogref compare TRUTH --model ue4 --from-scene --no-figures`` (``full``) against the same with
``--no-perceptual`` (``lean``) on truths of ``scenes/valley.xml`` rendered here (64x36 and 320x180
at 16 spp, 960x540 at 4 spp, seed 0), and at 320x180 the command with its figures too; each run a
fresh process, the two alternating, the Unreal fit read from a fit cache filled before the
rounds (so neither run fits).  In each run the FLIP maps (``fogref.compare.error_maps.flip_map``)
are timed apart.  Identity: every metric, binned value and ``check.json`` row of ``lean`` equal
to ``full``'s (JSON values, paths left out), and ``lean`` without any ΔE2000 or FLIP key.

Then the example sweep (``reports/sweeps/unreal_sun_falloff_g``, 48 configurations) as committed
(``full``) and with ``[outputs] perceptual = false`` (``lean``), ``fogref sweep --quiet`` in a
fresh process from empty truth and fit caches, ``--sweep-rounds`` rounds alternating; identity:
every cell of ``lean``'s table equal to ``full``'s (the rows matched by their parameters; the
configuration ids, timings and paths left out), and no ΔE2000 or FLIP column in it.

    .venv/bin/python benchmarks/compare_perceptual.py [--rounds 3] [--sweep-rounds 2]
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _checkouts import (
    FOGREF_MAIN,
    ROOT,
    alternating,
    checkout_env,
    commit_of,
    example_sweep,
    kept_reading,
    ratio_range,
    timed_command,
    valley_truth,
    write_report,
)

from fogref.study.plot_units import is_perceptual

CASES = ((64, 36, 16, False), (320, 180, 16, False), (320, 180, 16, True), (960, 540, 4, False))
FLIP = "fogref.compare.error_maps:flip_map"  # timed apart in each run


def _compare(truth: Path, out: Path, figures: bool, perceptual: bool) -> dict:
    args = ["compare", truth, "--model", "ue4", "--from-scene", "--out", out]
    args += ([] if figures else ["--no-figures"]) + ([] if perceptual else ["--no-perceptual"])
    return timed_command(ROOT, FLIP, args, codes=(0, 1, 3))  # pass, fail, inconclusive: a verdict


def _same_but_perceptual(full: Path, lean: Path) -> bool:
    """Whether ``lean``'s report is ``full``'s without the perceptual metrics (paths left out)."""
    a, b = (json.loads((f / "metrics.json").read_text()) for f in (full, lean))
    for part, regions in a["metrics"].items():
        for region, s in regions.items():
            if b["metrics"][part][region] != {k: v for k, v in s.items() if not is_perceptual(k)}:
                return False
    for axis, binned in a["binned"].items():
        for part, s in (binned or {}).get("parts", {}).items():
            if b["binned"][axis]["parts"][part] != {k: v for k, v in s.items() if not is_perceptual(k)}:
                return False
    leaks = [k for regions in b["metrics"].values() for s in regions.values() for k in s if is_perceptual(k)]
    checks = [json.loads((f / "check.json").read_text()) for f in (full, lean)]
    return not leaks and checks[0]["rows"] == checks[1]["rows"]


#: Columns of a sweep's table that name the run, its timings or paths, not its results.
SWEEP_RUN_COLUMNS = {"config_id", "scene_path", "render_seconds", "compare_seconds", "worker_pid"}
SWEEP_RUN_COLUMNS |= {"worker_host", "truth_path", "truth_cached", "truth_sha256"}


def _sweep(work: Path, lean: bool) -> dict:
    """The example sweep in ``work`` from empty truth and fit caches, ``lean``: without its
    perceptual metrics; its wall time and the sweep's own 'configurations in' seconds."""
    shutil.rmtree(work, ignore_errors=True)
    sweep = example_sweep(ROOT, work, {"perceptual": "false"} if lean else None)
    env = {**checkout_env(ROOT), "FOGREF_CACHE": str(work / "fits")}
    t0 = time.perf_counter()
    p = subprocess.run(
        [sys.executable, "-c", FOGREF_MAIN, "sweep", str(sweep), "--quiet"],
        env=env,
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise SystemExit(f"fogref sweep failed ({p.returncode}):\n{p.stderr[-3000:]}")
    line = next(x for x in p.stdout.splitlines() if "configurations" in x)
    return {"wall_s": wall, "configs_s": float(line.split(" in ")[1].split(" s")[0])}


def _same_table_but_perceptual(full: Path, lean: Path) -> bool:
    """Whether every cell of ``lean``'s ``results.csv`` equals ``full``'s (rows matched by their
    parameters and model, :data:`SWEEP_RUN_COLUMNS` left out) and ``lean`` has no perceptual column."""

    def rows(folder: Path) -> dict:
        with open(folder / "results.csv", newline="") as f:
            table = list(csv.DictReader(f))
        key = ("sun_elevation", "FogHeightFalloff", "g", "model")
        return {tuple(r[k] for k in key): r for r in table}

    a, b = rows(full), rows(lean)
    if set(a) != set(b):
        return False
    for k, r in b.items():
        if any(is_perceptual(c) for c in r):
            return False
        if any(r[c] != a[k][c] for c in r if c not in SWEEP_RUN_COLUMNS):
            return False
    return True


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--sweep-rounds", type=int, default=2, help="rounds of the example sweep (0: none)")
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks"))
    a = ap.parse_args()
    work = Path(tempfile.mkdtemp(prefix="compare-perceptual-"))
    os.environ["FOGREF_CACHE"] = str(work / "cache")  # the fit, once, for every run (the children inherit it)
    load = [os.getloadavg()[0]]
    cases = []
    for w, h, spp, figures in CASES:
        truth = valley_truth(work, w, h, spp)
        name = f"{w}x{h}, {spp} spp" + (", figures" if figures else ", --no-figures")
        folder = work / name.replace(", ", "_").replace(" ", "")
        _compare(truth, folder / "warm", figures, True)  # the fit, the page cache, Python's bytecode

        def run(mode, _checkout, truth=truth, folder=folder, figures=figures):
            return _compare(truth, folder / mode, figures, mode == "full")

        runs = alternating({"full": ROOT, "lean": ROOT}, a.rounds, run)
        same = _same_but_perceptual(folder / "full", folder / "lean")
        cases.append({"case": name, "runs": runs, "identical": same})
        print(name, {m: [round(r["wall_s"], 2) for r in rs] for m, rs in runs.items()}, flush=True)
    sweep = None
    if a.sweep_rounds:
        where = work / "sweep"
        runs = alternating(
            {"full": ROOT, "lean": ROOT}, a.sweep_rounds, lambda m, _: _sweep(where / m, m == "lean")
        )
        sweep = {"runs": runs, "identical": _same_table_but_perceptual(where / "full", where / "lean")}
        print("sweep", {m: [round(r["wall_s"], 2) for r in rs] for m, rs in runs.items()}, flush=True)
    load.append(os.getloadavg()[0])
    cores = len(os.sched_getaffinity(0))
    result = {"commit": commit_of(ROOT), "cores": cores, "load_average": load, "cases": cases, "sweep": sweep}
    result["reading"] = kept_reading(Path(a.out) / "compare_perceptual.md")  # hand-written, kept
    write_report(Path(a.out), "compare_perceptual", result, report(result))


def report(r: dict) -> str:
    """The Markdown page of a run."""
    rounds = len(r["cases"][0]["runs"]["full"])
    md = [
        "# `fogref compare` with and without its perceptual metrics",
        "",
        "`benchmarks/compare_perceptual.py`: `fogref compare TRUTH --model ue4 --from-scene` (`full`) "
        "against the same with `--no-perceptual` (`lean`: no ΔE2000 or HDR-FLIP), on truths of "
        f"`scenes/valley.xml`, the fit read from a cache filled before; each run a fresh process, {rounds} "
        f"rounds alternating the two; {r['commit']}, {r['cores']} cores, load average (1 min) "
        + " -> ".join(f"{x:.1f}" for x in r["load_average"])
        + ".  Seconds: median over the rounds; ratio `full` / `lean` per round, median [smallest, largest]; "
        "FLIP: the FLIP maps' share of `full` (timed inside the same runs).",
        "",
        "| truth | full [s] | lean [s] | full / lean | FLIP maps in full [s] | lean's values |",
        "|---|---:|---:|---|---:|---|",
    ]
    for c in r["cases"]:
        full, lean = ([v["wall_s"] for v in c["runs"][m]] for m in ("full", "lean"))
        flip = statistics.median(v["part_s"] for v in c["runs"]["full"])
        same = "full's, less ΔE2000 and FLIP" if c["identical"] else "DIFFERENT"
        md.append(
            f"| {c['case']} | {statistics.median(full):.2f} | {statistics.median(lean):.2f} | "
            f"{ratio_range(full, lean)} | {flip:.2f} | {same} |"
        )
    if r.get("sweep"):
        runs = r["sweep"]["runs"]
        md += [
            "",
            f"The example sweep (48 configurations, 64x36, 16 spp, `fogref sweep --quiet` from empty truth "
            f"and fit caches, {len(runs['full'])} rounds alternating), as committed (`full`) and with "
            "`[outputs] perceptual = false` (`lean`):",
            "",
            "| | full [s] | lean [s] | full / lean |",
            "|---|---:|---:|---|",
        ]
        for key, label in (("wall_s", "the command"), ("configs_s", "its 'configurations in'")):
            full, lean = ([v[key] for v in runs[m]] for m in ("full", "lean"))
            md.append(
                f"| {label} | {statistics.median(full):.2f} | {statistics.median(lean):.2f} | "
                f"{ratio_range(full, lean)} |"
            )
        same = "equal" if r["sweep"]["identical"] else "DIFFERENT"
        md += ["", f"Every cell of `lean`'s table but the ΔE2000 and FLIP columns against `full`'s: {same}."]
    md += ["", *r["reading"]] if r.get("reading") else []
    return "\n".join(md) + "\n"


if __name__ == "__main__":
    main()
