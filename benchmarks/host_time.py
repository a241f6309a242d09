"""Host time of a small truth's pass in a warm process, before and after fogpath's host-side cuts.
-> reports/benchmarks/host_time.{json,md}

One process renders ``scenes/valley.xml`` at 32x18 with ``render_moments`` (pixel-exact), each
render a new sun elevation and a new seed (as a sweep does; the scene is loaded outside the timed
region), at 1 and 64 spp.  Each configuration is rendered in three modes, side by side, in
rotating order:

* ``before``: fogpath reading the sensor's sky, the sun and the emitters' selection pdfs at every
  call site while tracing (``FogPathIntegrator._read_once`` patched to read every time), and Dr.Jit's
  ``OptimizeLoops`` on (each symbolic loop body traced twice);
* ``read_once``: each of those values read once per render, ``OptimizeLoops`` on;
* ``after``: fogref as it is (read once, ``OptimizeLoops`` off: loop bodies traced once).

Per render: the wall time (the call, ``dr.eval``, ``dr.sync_thread``) and, from Dr.Jit's kernel
history, code generation, LLVM compilation (``backend``: 0 on a kernel-cache hit) and execution;
``host`` is the wall time less execution (tracing, code generation, reads, launches).  The first
configurations compile (reported apart); the medians are over the steady ones.  The modes'
per-pixel sums are compared bitwise.  Last, ``before`` and ``after`` at 128x72 and 64 spp,
where execution dominates: does tracing the loops once slow the kernels?

    .venv/bin/python benchmarks/host_time.py [--configs 12]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "valley.xml"
RES = (32, 18)
LARGE = (128, 72)
WARMUP = 2
MODES = ("before", "read_once", "after")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--configs", type=int, default=12)
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks"))
    a = ap.parse_args()

    from fogref.render.variant import set_variant

    set_variant("llvm_ad_rgb")
    import drjit as dr
    import fogref_plugins.fogpath as common
    import mitsuba as mi
    import numpy as np

    from fogref.render.load import load_scene

    read_once, optimize_loops = common.FogPathIntegrator._read_once, common.OPTIMIZE_LOOPS

    def every_time(self, scene, name, read):
        return read()

    def render(mode: str, sun: float, seed: int, spp: int, res: tuple = RES):
        common.FogPathIntegrator._read_once = every_time if mode == "before" else read_once
        common.OPTIMIZE_LOOPS = True if mode != "after" else optimize_loops
        scene, _ = load_scene(SCENE, {"res": res[0], "resy": res[1], "sun_elevation": sun})
        integrator = scene.integrator()
        integrator.aovs = True
        dr.kernel_history()
        dr.set_flag(dr.JitFlag.KernelHistory, True)
        t0 = time.perf_counter()
        sums, squares = integrator.render_moments(scene, 0, seed, spp, pixel_exact=True)
        dr.eval(sums, squares)
        dr.sync_thread()
        wall = time.perf_counter() - t0
        hist = [k for k in dr.kernel_history() if str(k.get("type")).endswith("JIT")]
        dr.set_flag(dr.JitFlag.KernelHistory, False)
        ms = lambda key: sum(k.get(key, 0.0) for k in hist) / 1e3  # noqa: E731
        row = {
            "mode": mode,
            "spp": spp,
            "sun_elevation": sun,
            "seed": seed,
            "wall_s": wall,
            "codegen_s": ms("codegen_time"),
            "backend_s": ms("backend_time"),
            "execution_s": ms("execution_time"),
            "kernels": len(hist),
        }
        row["host_s"] = wall - row["execution_s"]
        return row, np.concatenate([np.asarray(sums).ravel(), np.asarray(squares).ravel()])

    rows, equal = [], True
    load_before = os.getloadavg()
    for spp in (1, 64):
        for i in range(a.configs):
            sun, seed = 5.0 + 50.0 * i / a.configs, 1000 + i
            order = MODES[i % 3 :] + MODES[: i % 3]
            images = {}
            for mode in order:
                row, images[mode] = render(mode, sun, seed, spp)
                row["steady"] = i >= WARMUP
                rows.append(row)
            equal &= all(np.array_equal(images["before"], images[m]) for m in MODES)
    large = []  # execution time where it dominates: does tracing loops once slow the kernel?
    for i in range(6):
        for mode in ("before", "after") if i % 2 == 0 else ("after", "before"):
            row, _ = render(mode, 20.0 + 5.0 * (i // 2), 2000 + i, 64, LARGE)
            row["steady"] = i >= WARMUP
            large.append(row)
    common.FogPathIntegrator._read_once, common.OPTIMIZE_LOOPS = read_once, optimize_loops
    result = {
        "res": list(RES),
        "configs": a.configs,
        "warmup": WARMUP,
        "load_average_before": load_before,
        "load_average_after": os.getloadavg(),
        "cores": os.cpu_count(),
        "mitsuba": mi.__version__,
        "drjit": dr.__version__,
        "bitwise_equal": equal,
        "rows": rows,
        "large_res": list(LARGE),
        "large_rows": large,
    }
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "host_time.json").write_text(json.dumps(result, indent=1) + "\n")
    (out / "host_time.md").write_text(report(result))
    print(report(result))


def _median(rows: list, mode: str, spp: int, key: str) -> float:
    return statistics.median(r[key] for r in rows if r["mode"] == mode and r["spp"] == spp and r["steady"])


def _spread(rows: list, mode: str, spp: int, key: str) -> str:
    v = sorted(r[key] for r in rows if r["mode"] == mode and r["spp"] == spp and r["steady"])
    q = statistics.quantiles(v, n=4) if len(v) >= 4 else [v[0], v[-1]]
    return f"{1e3 * q[0]:.0f}–{1e3 * q[-1]:.0f}"


def _paired(rows: list, spp: int, a: str, b: str) -> str:
    """Median [interquartile range] in ms of host(a) - host(b) over the steady configurations."""
    by = {(r["mode"], r["sun_elevation"]): r["host_s"] for r in rows if r["spp"] == spp and r["steady"]}
    d = sorted(1e3 * (by[(a, sun)] - by[(b, sun)]) for m, sun in by if m == a)
    q = statistics.quantiles(d, n=4)
    return f"{statistics.median(d):+.0f} [{q[0]:+.0f}, {q[-1]:+.0f}]"


def report(r: dict) -> str:
    """The Markdown page of a run."""
    rows = r["rows"]
    n = r["configs"] - r["warmup"]
    md = [
        "# Host time of a small truth's pass: scene values read once, loops traced once",
        "",
        f"`benchmarks/host_time.py`: `scenes/valley.xml` at {r['res'][0]}x{r['res'][1]}, pixel-exact, "
        f"`render_moments` in one warm process (Mitsuba {r['mitsuba']}, Dr.Jit {r['drjit']}, "
        f"`llvm_ad_rgb`), each render a new sun elevation and seed; `before` (fogpath reads the sky, "
        f"the sun and the emitters' pdfs at every call site while tracing; Dr.Jit's `OptimizeLoops` "
        f"on, each loop body traced twice), `read_once` (each value read once per render) and "
        f"`after` (also `OptimizeLoops` off) side by side, in rotating order.  Medians over {n} "
        f"steady configurations per row "
        f"(interquartile range in brackets, ms) after {r['warmup']} that compile; "
        f"{r['cores']} cores shared with other engineers, load average "
        f"{r['load_average_before'][0]:.1f} before and {r['load_average_after'][0]:.1f} after the "
        f"run.  `host` = wall - execution (tracing, reads, code generation, launches).  Pixels of "
        f"the three modes bitwise equal: {'yes' if r['bitwise_equal'] else 'NO'}.",
        "",
        "| spp | mode | wall [ms] | host [ms] | codegen [ms] | execution [ms] | host / wall |",
        "|---:|---|---:|---:|---:|---:|---:|",
    ]
    for spp in (1, 64):
        for mode in MODES:
            w, h = _median(rows, mode, spp, "wall_s"), _median(rows, mode, spp, "host_s")
            md.append(
                f"| {spp} | {mode} | {1e3 * w:.0f} [{_spread(rows, mode, spp, 'wall_s')}] "
                f"| {1e3 * h:.0f} [{_spread(rows, mode, spp, 'host_s')}] "
                f"| {1e3 * _median(rows, mode, spp, 'codegen_s'):.0f} "
                f"| {1e3 * _median(rows, mode, spp, 'execution_s'):.0f} | {h / w:.0%} |"
            )
    md += [
        "",
        "Paired differences (the same configuration in two modes; median over the steady "
        "configurations, interquartile range in brackets), host time [ms]:",
        "",
        "| spp | before - read_once | read_once - after | before - after |",
        "|---:|---:|---:|---:|",
    ]
    for spp in (1, 64):
        cells = [_paired(rows, spp, a, b) for a, b in (MODES[:2], MODES[1:], MODES[::2])]
        md.append(f"| {spp} | " + " | ".join(cells) + " |")
    ex = {
        m: [1e3 * x["execution_s"] for x in r["large_rows"] if x["mode"] == m and x["steady"]]
        for m in ("before", "after")
    }
    md += [
        "",
        f"Execution where it dominates: {r['large_res'][0]}x{r['large_res'][1]}, 64 spp, "
        f"{len(ex['after'])} steady renders per mode, execution time [ms]: before "
        f"{', '.join(f'{v:.0f}' for v in ex['before'])}; after {', '.join(f'{v:.0f}' for v in ex['after'])}.",
    ]
    first = [x for x in rows if not x["steady"]]
    md += [
        "",
        "Compilation, apart: the first configurations' LLVM time (`backend`) per render: "
        + ", ".join(f"{x['mode']} {x['spp']} spp {x['backend_s']:.2f} s" for x in first)
        + " (0 when Dr.Jit's disk cache already holds the kernels).",
    ]
    return "\n".join(md) + "\n"


if __name__ == "__main__":
    main()
