"""``fogref fit`` with BLAS on one thread (as fogref runs it) or on every core, side by side.
-> reports/benchmarks/fit_blas_threads.{json,md}

The fits run BLAS on one thread (``threadpoolctl``, in ``fit_unreal`` and ``fit_to_targets``) so
that their last digits do not depend on the machine's thread count.  Does one thread cost time?
Each run is a fresh process (``--child``) with an empty fit cache that calls ``fogref fit --model
M`` in-process and times the call (interpreter start and imports left out): ``one`` as shipped,
``every`` with the fits' ``threadpool_limits`` replaced by a no-op (BLAS on every core, OpenBLAS's
default).  The modes alternate; medians over the repeats, the ratio per model is every-core time
over one-thread time (the median of the back-to-back pairs' ratios, with the smallest and
largest pair's).  Whether the two modes' JSON is the same bit for bit is reported too.

    .venv/bin/python benchmarks/fit_blas_threads.py [--repeats 5] [--models ue4 filament bevy godot]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODES = ("one", "every")


def child(mode: str, model: str) -> None:
    """(A fresh process.)  Print ``{"s": seconds, "out": the command's JSON}``."""
    import fogref.mapping.fit as F
    import fogref.mapping.unreal as U
    from fogref.cli import main

    if mode == "every":
        F.threadpool_limits = U.threadpool_limits = lambda **_: contextlib.nullcontext()
    out = io.StringIO()
    t = time.perf_counter()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        rc = main(["fit", "--model", model])
    s = time.perf_counter() - t
    if rc:
        raise SystemExit(f"fogref fit --model {model} failed ({rc})")
    print(json.dumps({"s": s, "out": out.getvalue()}))


def _without_times(doc):
    if isinstance(doc, dict):
        return {k: _without_times(v) for k, v in doc.items() if not k.endswith("seconds")}
    return [_without_times(v) for v in doc] if isinstance(doc, list) else doc


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--models", nargs="+", default=["ue4", "filament", "bevy", "godot"])
    ap.add_argument("--child", nargs=2, metavar=("MODE", "MODEL"), help=argparse.SUPPRESS)
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks"))
    a = ap.parse_args(argv)
    if a.child:
        child(*a.child)
        return 0
    load0 = float(open("/proc/loadavg").read().split()[0])
    res: dict = {"repeats": a.repeats, "cores": len(os.sched_getaffinity(0)), "models": {}}
    for model in a.models:
        runs: dict = {m: [] for m in MODES}
        for r in range(a.repeats):
            for mode in MODES if r % 2 else MODES[::-1]:
                with tempfile.TemporaryDirectory() as cache:
                    p = subprocess.run(
                        [sys.executable, __file__, "--child", mode, model],
                        env={**os.environ, "FOGREF_CACHE": cache},
                        capture_output=True,
                        text=True,
                        check=True,
                    )
                runs[mode].append(json.loads(p.stdout.strip().splitlines()[-1]))
        times = {m: [x["s"] for x in runs[m]] for m in MODES}
        pairs = [e / o for e, o in zip(times["every"], times["one"])]
        same = _without_times(json.loads(runs["one"][0]["out"])) == _without_times(
            json.loads(runs["every"][0]["out"])
        )
        res["models"][model] = {
            "times_s": times,
            "median_s": {m: statistics.median(v) for m, v in times.items()},
            "ratio_every_over_one": statistics.median(pairs),
            "ratio_range": [min(pairs), max(pairs)],
            "same_values": same,
        }
        print(model, {k: round(v, 2) for k, v in res["models"][model]["median_s"].items()}, flush=True)
    res["load_average"] = [load0, float(open("/proc/loadavg").read().split()[0])]
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "fit_blas_threads.json").write_text(json.dumps(res, indent=1) + "\n")
    text = report(res)
    (out / "fit_blas_threads.md").write_text(text)
    print(text)
    return 0


def report(res: dict) -> str:
    lines = [
        "# `fogref fit` with BLAS on one thread or on every core",
        "",
        f"`benchmarks/fit_blas_threads.py` (see its docstring): a fresh process per run, empty fit cache, "
        f"the call timed in-process; {res['repeats']} runs per mode alternating, {res['cores']} cores "
        f"(shared), load average {res['load_average'][0]:.1f} before, {res['load_average'][1]:.1f} after.  "
        "Seconds, medians; ratio: every core over one thread, the median of the back-to-back pairs' "
        "ratios [the smallest and largest pair's].",
        "",
        "| model | one thread [s] | every core [s] | ratio | values bit for bit the same |",
        "|---|---:|---:|---:|---|",
    ]
    for model, d in res["models"].items():
        lo, hi = d["ratio_range"]
        same = "yes" if d["same_values"] else "no"
        lines.append(
            f"| {model} | {d['median_s']['one']:.2f} | {d['median_s']['every']:.2f} "
            f"| {d['ratio_every_over_one']:.2f} [{lo:.2f}, {hi:.2f}] | {same} |"
        )
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    raise SystemExit(main())
