"""Wall time of the example sweep on a LocalCluster of one worker vs two -> reports/sweeps/scaling.md.

The sweep of ``reports/sweeps/unreal_sun_falloff_g`` (valley, sun elevation x
FogHeightFalloff x g, 48 configurations, 64x36 px, 16 spp, model ue4) runs from an
empty truth cache on each cluster shape; every run includes starting the cluster,
importing Mitsuba in each worker and (``cold``) compiling fogpath's kernels into an
empty Dr.Jit disk cache (``HOME`` points to a fresh folder for the workers) or
(``warm``) loading them from the disk cache a cold run filled.  Dr.Jit's thread pool
is sized so that workers x threads = cores.  Shapes are alternated.

    .venv/bin/python benchmarks/sweep_scaling.py [--repeats 2]
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path

from _checkouts import ROOT, example_sweep


def run(n_workers: int, threads: int, home: str) -> dict:
    """One sweep run from an empty truth cache, the workers' HOME (Dr.Jit disk cache) at ``home``."""
    from fogref.study.sweep import run_sweep

    with tempfile.TemporaryDirectory(prefix="fogref-scaling-") as tmp:
        p = example_sweep(ROOT, Path(tmp), {"plots": "false"})
        old_home = os.environ.get("HOME")
        os.environ["HOME"] = home  # the LocalCluster's worker processes inherit it
        try:
            t0 = time.perf_counter()
            info = run_sweep(p, n_workers=n_workers, drjit_threads=threads, progress=False)
            wall = time.perf_counter() - t0
        finally:
            if old_home is not None:
                os.environ["HOME"] = old_home
        import pandas as pd

        df = pd.read_parquet(info["parquet"])
        return {
            "workers": n_workers,
            "threads": threads,
            "wall": wall,
            "configs": info["configs"],
            "failed": info["failed"],
            "render_sum": float(df["render_seconds"].sum()),
        }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=str(ROOT / "reports" / "sweeps" / "scaling.md"))
    ap.add_argument("--repeats", type=int, default=1, help="timed runs of each cluster shape (default 1)")
    a = ap.parse_args(argv)
    cores = os.cpu_count() or 1
    shapes = [(1, cores), (2, max(1, cores // 2))]
    results = {(s, kind): [] for s in shapes for kind in ("cold", "warm")}
    for _ in range(a.repeats):
        for s in shapes:
            with tempfile.TemporaryDirectory(prefix="fogref-home-") as home:
                results[(s, "cold")].append(run(*s, home=home))  # empty Dr.Jit disk cache: compiles
                results[(s, "warm")].append(run(*s, home=home))  # the kernels the cold run left on disk
    lines = [
        "# Sweep scaling: LocalCluster with one worker vs two",
        "",
        f"Machine: {platform.processor() or platform.machine()}, {cores} cores; llvm_ad_rgb.  Command: "
        f"`.venv/bin/python benchmarks/sweep_scaling.py --repeats {a.repeats}`.",
        "",
        "Sweep: the example `reports/sweeps/unreal_sun_falloff_g/SWEEP.toml` (48 configurations: valley, "
        "sun elevation x FogHeightFalloff x g, 64x36 px, 16 spp, model ue4, no plots), empty truth cache "
        "every run.  Wall time includes starting the cluster and importing Mitsuba in every worker.  "
        "`cold`: the workers' Dr.Jit disk cache is empty, so each worker compiles fogpath's kernels once "
        "(scene values are opaque to them, so once is enough: `kernel_reuse.md`); `warm`: a second run on "
        f"the disk cache the cold run filled.  Shapes alternated, {a.repeats} time(s) each; best wall time "
        "shown.",
        "",
        "| workers | Dr.Jit threads each | Dr.Jit disk cache | wall [s] (best) | wall [s] (all runs) "
        "| sum of render times [s] | speed-up vs 1 worker |",
        "|---|---|---|---|---|---|---|",
    ]
    for kind in ("cold", "warm"):
        base = min(r["wall"] for r in results[(shapes[0], kind)])
        for s in shapes:
            best = min(results[(s, kind)], key=lambda r: r["wall"])
            walls = ", ".join(f"{r['wall']:.1f}" for r in results[(s, kind)])
            lines.append(
                f"| {s[0]} | {s[1]} | {kind} | {best['wall']:.1f} | {walls} | {best['render_sum']:.1f} | "
                f"{base / best['wall']:.2f}x |"
            )
    lines.append("")
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    from fogref.atomic import write_text_atomic

    write_text_atomic(a.out, "\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
