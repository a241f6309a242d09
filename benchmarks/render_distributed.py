"""Distributed render scaling: one truth's passes on 1, 2 and N single-thread Dask workers.

The default scene (``scenes/valley.xml``) at ``--res`` (160x90) and ``--spp`` (64), in the
passes of the real split (:func:`fogref_plugins.passes.pass_sizes` under ``MAX_LANES``: 4 passes
of 16 spp at the defaults), or in ``--passes`` equal passes (``MAX_LANES`` set to pixels x spp
/ passes in this driver), rendered by :func:`fogref.render.render.render`:

* ``one process``: in this process, Dr.Jit on one thread;
* ``N workers``: on a LocalCluster of N worker processes (``processes=True``, one Dask thread,
  Dr.Jit on one thread each), N in ``--workers`` (1,2,4), started fresh for each N.

Each way renders once first (``first``: on fresh workers it includes tracing and compiling the
kernels, or loading them from Dr.Jit's disk cache), then ``--repeats`` (3) times (``steady``:
median and range).  Compile time = first - median steady.  Every render's pixels are compared
bitwise with the one-process render.  Efficiency of N workers = T(1 worker) / (N T(N workers)),
steady medians; the load average (1 min) before and after each way is in the report.

The model for N machines uses the measured per-pass time on a worker ``t_p`` (the median of the
workers' own pass times, steady), the bytes of float64 moments a pass sends back ``b``
(:func:`fogref.render.distributed.transfer_bytes`: 576 B per pixel), the driver's measured
merge rate (adding one pass's moments on the device) and an assumed network rate (10 GbE).
The driver receives and merges the passes one after another, so with P passes on N workers

    T(N) = t_fixed + max(ceil(P / N) t_p, P t_d),   t_d = b / network + b / merge rate,

and the efficiency is T(1) / (N T(N)).

    .venv/bin/python benchmarks/render_distributed.py [--res 160x90] [--spp 64] [--passes P]
        [--workers 1,2,4]

Each way starts in a fresh ``$HOME`` (no Dr.Jit kernel cache): ``first`` includes the whole
compile; ``--warm`` keeps the user's ``$HOME`` (kernels loaded from the disk cache).

Writes reports/benchmarks/render_distributed.{json,md}.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "valley.xml"
NETWORK = 1.25e9  # bytes/s: 10 GbE


def _one_thread():
    import drjit as dr

    from fogref.render.variant import set_variant

    set_variant(None)
    dr.set_thread_count(1)
    return os.getpid()


def _pixels(path):
    from fogref.exrio import read_exr

    return read_exr(path)


def _render(out, args, **kw) -> tuple[float, list, list]:
    """(wall seconds, each pass's wall seconds, each pass's CPU seconds) of one render.  The CPU
    seconds are the workers' own (their process time) on a cluster, this process's here."""
    from unittest import mock

    import fogref.render.distributed as D
    from fogref.render.render import render

    cpu, real = [], D.passes_in_order

    def spy(*a, **k):
        for r in real(*a, **k):
            cpu.append(r["cpu_seconds"])
            yield r

    t0, c0 = time.perf_counter(), time.process_time()
    with mock.patch.object(D, "passes_in_order", spy):
        render(SCENE, out, spp=args.spp, seed=0, overrides=args.overrides, progress=False, png=False,
               resume=False, **kw)  # fmt: skip
    wall = time.perf_counter() - t0
    passes = _pixels(out)[1]["fogref.render_seconds"]["passes"]
    if not cpu:  # in this process: its CPU time, shared out over the passes by their wall time
        c = time.process_time() - c0
        cpu = [c * p / sum(passes) for p in passes]
    return wall, passes, cpu


def _series(args, tmp: Path, name: str, reference, **kw) -> tuple[dict, dict]:
    """First render and ``repeats`` steady renders, pixels checked against ``reference`` (None: the
    first render's); returns the timings and the reference."""
    import numpy as np

    runs, pass_times, pass_cpu = [], [], []
    load = os.getloadavg()[0]
    for i in range(1 + args.repeats):
        out = tmp / f"{name}-{i}.exr"
        wall, passes, cpu = _render(out, args, **kw)
        ch = _pixels(out)[0]
        if reference is None:  # the first one-process render is the reference
            reference = ch
        else:
            bad = [c for c in ch if not np.array_equal(ch[c], reference[c])]
            assert not bad, f"{name}: pixels differ from the one-process render in {bad[:5]}"
        runs.append(wall)
        if i:
            pass_times += passes
            pass_cpu += cpu
        else:
            first_passes = passes
        print(f"  {name} run {i}: {wall:.2f} s", file=sys.stderr)
    steady = runs[1:]
    return {
        "first_s": runs[0],
        "steady_median_s": statistics.median(steady),
        "steady_min_s": min(steady),
        "steady_max_s": max(steady),
        "compile_s": runs[0] - statistics.median(steady),
        "first_passes_s": first_passes,
        "pass_median_s": statistics.median(pass_times),
        "pass_cpu_median_s": statistics.median(pass_cpu),
        "load_average": [load, os.getloadavg()[0]],
        "bitwise_equal": True,
    }, reference


def _merge_rate(w: int, h: int, repeats: int = 20) -> float:
    """Bytes per second at which the driver adds one pass's float64 moments (host -> device, add)."""
    import drjit as dr
    import numpy as np

    from fogref.render.render import device_f64

    rng = np.random.default_rng(0)
    s, q = rng.random((h, w, 30)), rng.random((h, w, 42))
    acc = (device_f64(s), device_f64(q))
    t0 = time.perf_counter()
    for _ in range(repeats):
        a, b = acc[0] + device_f64(s), acc[1] + device_f64(q)
        dr.eval(a, b)
        dr.sync_thread()
        acc = (a, b)
    return repeats * (s.nbytes + q.nbytes) / (time.perf_counter() - t0)


def _model(t_fixed: float, t_p: float, t_d: float, passes: int, ns=(1, 2, 4, 8, 16, 32, 64)) -> list:
    def t(n):
        return t_fixed + max(math.ceil(passes / n) * t_p, passes * t_d)

    return [{"n": n, "T_s": t(n), "efficiency": t(1) / (n * t(n))} for n in ns]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--res", default="160x90")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--passes", type=int, default=None, help="default: the real split")
    ap.add_argument("--workers", default="1,2,4", help="worker counts, comma-separated; 1 first")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--report-only", action="store_true", help="rewrite the .md from the .json")
    ap.add_argument("--warm", action="store_true", help="keep $HOME (Dr.Jit's kernel cache) as it is")
    args = ap.parse_args()
    out = ROOT / "reports" / "benchmarks"
    if args.report_only:
        (out / "render_distributed.md").write_text(
            _report(json.loads((out / "render_distributed.json").read_text()))
        )
        return
    w, h = (int(x) for x in args.res.split("x"))
    args.overrides = {"res": w, "resy": h}

    import fogref_plugins.passes as P
    from dask.distributed import Client, LocalCluster

    from fogref.render.distributed import transfer_bytes

    ns = [int(n) for n in args.workers.split(",")]
    assert ns[0] == 1, "--workers: the first count must be 1 (the efficiency's reference)"
    if args.passes:
        lanes = w * h * (args.spp // args.passes)
        P.MAX_LANES = {"llvm": lanes, "cuda": lanes}
    sizes = P.pass_sizes(w * h, args.spp, P.max_lanes("llvm_ad_rgb"))
    assert not args.passes or len(sizes) == args.passes, sizes
    lanes = w * h * sizes[0]
    homes = tempfile.TemporaryDirectory()
    if not args.warm:  # a fresh $HOME for this process: no Dr.Jit kernel cache, no fogref syntax cache
        os.environ["HOME"] = tempfile.mkdtemp(dir=homes.name)
    _one_thread()
    result = {
        "cold": not args.warm,
        "scene": "scenes/valley.xml",
        "res": [w, h],
        "spp": args.spp,
        "passes": sizes,
        "max_lanes": P.max_lanes("llvm_ad_rgb"),
        "split": "--passes" if args.passes else "real",
        "workers": ns,
        "repeats": args.repeats,
        "machine": {
            "cpus": os.cpu_count(),
            "platform": platform.platform(),
            "python": platform.python_version(),
        },
    }
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        print("one process", file=sys.stderr)
        result["one_process"], reference = _series(args, tmp, "one", None)
        for n in ns:
            print(f"{n} worker(s)", file=sys.stderr)
            if not args.warm:  # the workers inherit a fresh $HOME: they compile their kernels
                os.environ["HOME"] = tempfile.mkdtemp(dir=homes.name)
            t0 = time.perf_counter()
            with (
                LocalCluster(
                    n_workers=n,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=None,
                    silence_logs=logging.CRITICAL,
                ) as cluster,
                Client(cluster) as client,
            ):
                start = time.perf_counter() - t0
                client.run(_one_thread)
                r, _ = _series(args, tmp, f"w{n}", reference, scheduler=cluster.scheduler_address)
                r["cluster_start_s"] = start
            result[f"workers_{n}"] = r
        result["merge_bytes_per_s"] = _merge_rate(w, h)
    t1 = result["workers_1"]["steady_median_s"]
    result["efficiency"] = {str(n): t1 / (n * result[f"workers_{n}"]["steady_median_s"]) for n in ns}
    b = transfer_bytes(w, h)
    t_p = result["workers_1"]["pass_cpu_median_s"]  # on a dedicated core: its CPU time
    t_d = b / NETWORK + b / result["merge_bytes_per_s"]
    t_fixed = max(0.0, t1 - len(sizes) * t_p)  # the driver's own work: scene load, EXR, scheduling
    result["model"] = {
        "bytes_per_pass": b,
        "t_pass_s": t_p,
        "t_driver_per_pass_s": t_d,
        "t_fixed_s": t_fixed,
        "network_bytes_per_s": NETWORK,
        "this_case": _model(t_fixed, t_p, t_d, len(sizes)),
        # the same per-lane cost at a studio's size: 3840x2160, 1024 spp in passes of 1 spp (CPU MAX_LANES)
        "uhd_1024spp": _model(
            t_fixed, t_p * (3840 * 2160) / lanes, transfer_bytes(3840, 2160) * t_d / b, 1024
        ),
    }
    previous = out / "render_distributed.json"
    result["history"] = _history(result, json.loads(previous.read_text()) if previous.exists() else None)
    (out / "render_distributed.json").write_text(json.dumps(result, indent=1) + "\n")
    (out / "render_distributed.md").write_text(_report(result))
    print(out / "render_distributed.md")


def _summary(r: dict) -> dict:
    """One run's efficiency per worker count and the load average (1 min) over its runs."""
    ns = r.get("workers", [1, 2])
    t1 = r["workers_1"]["steady_median_s"]
    loads = [x for k in ["one_process"] + [f"workers_{n}" for n in ns] for x in r[k]["load_average"]]
    return {
        "efficiency": {str(n): t1 / (n * r[f"workers_{n}"]["steady_median_s"]) for n in ns},
        "load_average": [min(loads), max(loads)],
        "passes": len(r["passes"]),
    }


def _history(r: dict, previous: dict | None) -> list:
    """The summaries of the earlier runs of the same case (resolution, spp, passes, workers), then
    this run's: the spread between runs is the load's, on a shared machine."""
    same = ("res", "spp", "passes", "workers")
    old = []
    if previous is not None and all(previous.get(k) == r.get(k) for k in same):
        old = previous.get("history") or [_summary(previous)]
    return old + [_summary(r)]


def _efficiency_row(r: dict, n: int) -> str:
    """A row of the efficiency table: the median's, and the range from the steady extremes."""
    one, x = r["workers_1"], r[f"workers_{n}"]
    e = one["steady_median_s"] / (n * x["steady_median_s"])
    lo, hi = one["steady_min_s"] / (n * x["steady_max_s"]), one["steady_max_s"] / (n * x["steady_min_s"])
    return f"| {n} | {e:.2f} | {lo:.2f}-{hi:.2f} |"


def _report(r: dict) -> str:
    w, h = r["res"]
    m = r["model"]
    rows = []
    ns = r.get("workers", [1, 2])
    ways = [("one process", "one_process")]
    ways += [(f"{n} worker{'s' if n > 1 else ''}", f"workers_{n}") for n in ns]
    for name, key in ways:
        x = r[key]
        rows.append(
            f"| {name} | {x['first_s']:.2f} | {x['steady_median_s']:.2f} "
            f"({x['steady_min_s']:.2f}-{x['steady_max_s']:.2f}) | {x['compile_s']:.2f} | "
            f"{x['pass_median_s'] * 1e3:.0f} | {x['pass_cpu_median_s'] * 1e3:.0f} | "
            f"{x['load_average'][0]:.1f}-{x['load_average'][1]:.1f} | "
            f"{'yes' if x['bitwise_equal'] else '-'} |"
        )

    def table(model):
        return "\n".join(
            ["| machines N | T(N) [s] | efficiency |", "|---:|---:|---:|"]
            + [f"| {x['n']} | {x['T_s']:.2f} | {x['efficiency']:.2f} |" for x in model]
        )

    return f"""# Distributed render: one truth's passes on Dask workers

`benchmarks/render_distributed.py`: `scenes/valley.xml` at {w}x{h}, {r["spp"]} spp in {len(r["passes"])}
passes of {r["passes"][0]} spp ({
        f"the real split, at most {r['max_lanes']} lanes per pass"
        if r.get("split") == "real"
        else "`MAX_LANES` set for `--passes`"
    }), seed 0, on a {r["machine"]["cpus"]}-core machine shared with other work
({r["machine"]["platform"]}, Python {r["machine"]["python"]}).  Workers: LocalCluster processes, one
Dask thread and one Dr.Jit thread each; the one-process render also on one Dr.Jit thread.  Times
are whole `fogref.render.render.render` calls (scene load in the driver, passes, merge, EXR
write), median of {r["repeats"]} after a first render; compile = first - median: tracing and
compiling the kernels, {
        "each way in a fresh `$HOME` (no Dr.Jit kernel cache, no fogref syntax cache)"
        if r["cold"]
        else "or loading them from Dr.Jit's disk cache (`--warm`)"
    }.

| way | first [s] | steady median (range) [s] | compile [s] | pass wall [ms] | pass CPU [ms] | load avg |\
 bitwise = one process |
|---|---:|---:|---:|---:|---:|---:|---|
{chr(10).join(rows)}

Cluster start: {", ".join(f"{r[f'workers_{n}']['cluster_start_s']:.1f} s ({n})" for n in ns)} (workers),
not in the times above.

**Efficiency of N single-thread workers against 1** (T1 / (N TN), steady medians; the range of
each from the steady minima and maxima):

| workers N | efficiency | range |
|---:|---:|---:|
{chr(10).join(_efficiency_row(r, n) for n in ns)}

Every run of this case on this machine (the table above is the last; the spread is the other
users' load as much as fogref's):

| run | load average (1 min) | {" | ".join(f"efficiency N = {n}" for n in ns)} |
|---:|---:|{"---:|" * len(ns)}
{
        chr(10).join(
            f"| {i + 1} | {h['load_average'][0]:.1f}-{h['load_average'][1]:.1f} | "
            + " | ".join(f"{h['efficiency'][str(n)]:.2f}" for n in ns)
            + " |"
            for i, h in enumerate(r.get("history", [_summary(r)]))
        )
    }

{r["machine"]["cpus"]} cores shared with the driver and with other users: more than
{r["machine"]["cpus"]} single-thread workers share cores, and with the load average above the cores
no way of rendering gets its cores, the 1-worker reference included, so the efficiencies measure
the load as much as fogref (neither a lower nor an upper bound of what N machines give).  The
load-free measure is the CPU time: the work per pass does not grow with the workers: a pass's
CPU time on 1 worker / on each of N
workers = {
        ", ".join(
            f"{r['workers_1']['pass_cpu_median_s'] / r[f'workers_{n}']['pass_cpu_median_s']:.2f} (N = {n})"
            for n in ns[1:]
        )
    }; the wall time per pass grows with the contention for the cores.

## Model for N machines

Each pass sends back its float64 moments: {m["bytes_per_pass"] / 1e6:.1f} MB at {w}x{h}
(576 bytes per pixel: 30 sums and 42 squares).  The driver receives and merges them one after
another (in pass order, which makes the pixels independent of N): per pass
t_d = b / network + b / merge rate = {m["t_driver_per_pass_s"] * 1e3:.1f} ms (network
{m["network_bytes_per_s"] / 1e9:.2f} GB/s assumed, 10 GbE; merge rate measured here
{r["merge_bytes_per_s"] / 1e9:.2f} GB/s).  A pass on one single-thread worker takes
(its CPU time, what it takes on a dedicated core)
t_p = {m["t_pass_s"] * 1e3:.0f} ms; the driver's fixed work t_fixed = {m["t_fixed_s"]:.2f} s.
T(N) = t_fixed + max(ceil(P / N) t_p, P t_d), efficiency = T(1) / (N T(N)):

This case ({len(r["passes"])} passes):

{table(m["this_case"])}

A studio frame, 3840x2160 at 1024 spp (1024 passes of 1 spp under the CPU's `MAX_LANES`; t_p and
t_d scaled by the pixels: {m["t_pass_s"] * 3840 * 2160 / (w * h * r["passes"][0]):.1f} s and
{m["t_driver_per_pass_s"] * 3840 * 2160 / (w * h):.2f} s per pass):

{table(m["uhd_1024spp"])}

The driver receives and merges the passes one at a time, so the speed-up is bounded by
t_p / t_d, whatever N: {m["t_pass_s"] / m["t_driver_per_pass_s"]:.1f} in this case, and
{
        m["t_pass_s"]
        * 3840
        * 2160
        / (w * h * r["passes"][0])
        / (m["t_driver_per_pass_s"] * 3840 * 2160 / (w * h)):.1f}
for the studio frame on single-thread workers (less on many-core workers, whose t_p is shorter).
At 1 spp per pass a pass's 576 bytes per pixel cost about as much to send as to render.  The
bytes per pass do not grow with the samples, so more samples per pass (a larger `MAX_LANES`
on machines with the memory) raise the bound in proportion; so would workers that add a
fixed block of consecutive passes before sending them (the one-process driver adding the same
blocks in the same order, to keep the pixels independent of N).
"""


if __name__ == "__main__":
    main()
