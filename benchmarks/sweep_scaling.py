"""Wall time of one small sweep on a LocalCluster of one worker vs two workers -> reports/sweeps/scaling.md.

The same 8 configurations (valley, sun elevation x g, 48x27 px, 16 spp, one model) run
from an empty truth cache on each cluster shape; every run includes starting the
cluster, importing Mitsuba in each worker and compiling its kernels.  Dr.Jit's
thread pool is sized so that workers x threads = cores.

    .venv/bin/python benchmarks/sweep_scaling.py [--out reports/sweeps/scaling.md]
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

SWEEP = """
[sweep]
name = "scaling"
scenes = ["{scene}"]
cache = "{cache}"
[render]
spp = 16
overrides = {{ res = 48, resy = 27 }}
[design]
kind = "grid"
[parameters.sun_elevation]
values = [4, 10, 20, 40]
[parameters.g]
values = [0.3, 0.85]
[[models]]
name = "ue4"
[outputs]
plots = false
"""


def run(n_workers: int, threads: int) -> dict:
    from fogref.study.sweep import run_sweep

    with tempfile.TemporaryDirectory(prefix="fogref-scaling-") as tmp:
        p = Path(tmp) / "SWEEP.toml"
        p.write_text(SWEEP.format(scene=(ROOT / "scenes" / "valley.xml").as_posix(),
                                  cache=(Path(tmp) / "cache").as_posix()))
        t0 = time.perf_counter()
        info = run_sweep(p, n_workers=n_workers, drjit_threads=threads, progress=False)
        wall = time.perf_counter() - t0
        import pandas as pd

        df = pd.read_parquet(info["parquet"])
        return {"workers": n_workers, "threads": threads, "wall": wall, "configs": info["configs"],
                "failed": info["failed"], "render_sum": float(df["render_seconds"].sum())}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=str(ROOT / "reports" / "sweeps" / "scaling.md"))
    a = ap.parse_args(argv)
    cores = os.cpu_count() or 1
    shapes = [(1, cores), (2, max(1, cores // 2))]
    results = [run(w, t) for w, t in shapes]
    base = results[0]["wall"]
    lines = ["# Sweep scaling: LocalCluster with one worker vs two", "",
             f"Machine: {platform.processor() or platform.machine()}, {cores} cores (shared with other jobs while "
             "measured); llvm_ad_rgb.  Command: `.venv/bin/python benchmarks/sweep_scaling.py`.", "",
             "Sweep: 8 configurations (valley, sun elevation {4, 10, 20, 40} x g {0.3, 0.85}, 48x27 px, 16 spp, "
             "model ue4), empty truth cache; wall time includes starting the cluster, Mitsuba's import and "
             "kernel compilation in every worker.", "",
             "| workers | Dr.Jit threads each | wall [s] | sum of render times [s] | speed-up vs 1 worker |",
             "|---|---|---|---|---|"]
    for r in results:
        lines.append(f"| {r['workers']} | {r['threads']} | {r['wall']:.1f} | {r['render_sum']:.1f} | "
                     f"{base / r['wall']:.2f}x |")
    lines.append("")
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    from fogref.atomic import write_text_atomic

    write_text_atomic(a.out, "\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
