"""A truth's EXR written and read with OpenEXR's thread pool empty (its default) or one thread
per core (``fogref.exrio.use_every_core``), side by side.  -> reports/benchmarks/exr_threads.{json,md}

The channels are those of a real truth (``scenes/valley.xml``, 320x180, 4 spp, rendered once),
cropped or tiled to each size: all 72 of them, float32, ZIP (the default compression).  One
process; per size the two pool sizes alternate, the pool set with
``OpenEXR.set_global_thread_count`` before each call; ``write_exr`` then ``read_exr``, each timed
alone.  Medians over the repeats; the ratio is the median of the back-to-back pairs' ratios.
The files written with and without threads are compared byte for byte.

    .venv/bin/python benchmarks/exr_threads.py [--repeats 7] [--quick]
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SIZES = [(32, 18), (64, 36), (96, 54), (160, 90), (320, 180), (960, 540)]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--quick", action="store_true", help="two small sizes, 2 repeats (a smoke run)")
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks"))
    a = ap.parse_args(argv)
    import numpy as np
    import OpenEXR

    import fogref.exrio as X
    from fogref.render.render import render

    sizes, repeats = (SIZES[:2], 2) if a.quick else (SIZES, a.repeats)
    load0 = float(open("/proc/loadavg").read().split()[0])
    work = Path(tempfile.mkdtemp(prefix="exr_threads."))
    render(
        ROOT / "scenes" / "valley.xml",
        work / "truth.exr",
        spp=4,
        overrides={"res": 320, "resy": 180},
        progress=False,
    )
    source, _ = X.read_exr(work / "truth.exr")
    cores = X.use_every_core()
    X.use_every_core = OpenEXR.global_thread_count  # the pool stays as each call below sets it
    res = {"cores": cores, "channels": len(source), "repeats": repeats, "sizes": []}
    for w, h in sizes:
        tiles = (-(-h // 180), -(-w // 320))
        chans = {k: np.ascontiguousarray(np.tile(v, tiles)[:h, :w]) for k, v in source.items()}
        times: dict = {n: {"write": [], "read": []} for n in (0, cores)}
        files = {}
        for r in range(repeats):
            for n in (0, cores) if r % 2 else (cores, 0):
                OpenEXR.set_global_thread_count(n)
                path = work / f"{w}x{h}_{n}.exr"
                t = time.perf_counter()
                X.write_exr(path, chans)
                times[n]["write"].append(time.perf_counter() - t)
                t = time.perf_counter()
                X.read_exr(path)
                times[n]["read"].append(time.perf_counter() - t)
                files[n] = path.read_bytes()
        med = {str(n): {k: statistics.median(v) * 1e3 for k, v in d.items()} for n, d in times.items()}
        pairs = {k: [x / y for x, y in zip(times[0][k], times[cores][k])] for k in ("write", "read")}
        ratio = {k: statistics.median(v) for k, v in pairs.items()}
        spread = {k: [min(v), max(v)] for k, v in pairs.items()}
        same = files[0] == files[cores]
        res["sizes"].append(
            {
                "size": [w, h],
                "ms": med,
                "ratio": ratio,
                "ratio_range": spread,
                "times_s": {str(n): d for n, d in times.items()},
                "bytes": len(files[0]),
                "identical": same,
            }
        )
        print(
            w, h, {k: round(v, 2) for k, v in ratio.items()}, "identical" if same else "DIFFERENT", flush=True
        )
    OpenEXR.set_global_thread_count(cores)
    res["load_average"] = [load0, float(open("/proc/loadavg").read().split()[0])]
    text = report(res)
    if not a.quick:
        out = Path(a.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "exr_threads.json").write_text(json.dumps(res, indent=1) + "\n")
        (out / "exr_threads.md").write_text(text)
    print(text)
    return 0


def report(res: dict) -> str:
    n = str(res["cores"])
    lines = [
        "# A truth's EXR with OpenEXR's thread pool empty or one thread per core",
        "",
        f"`benchmarks/exr_threads.py` (see its docstring): {res['channels']} channels of a real truth, "
        f"ZIP, {res['repeats']} repeats of each pool size alternating, {n} cores (shared), load average "
        f"{res['load_average'][0]:.1f} before, {res['load_average'][1]:.1f} after.  Milliseconds, medians; "
        "ratio: no thread over one per core, the median of the back-to-back pairs' ratios [the smallest "
        "and largest pair's].",
        "",
        f"| size | file [MB] | write, no thread | write, {n} threads | write ratio | read, no thread "
        f"| read, {n} threads | read ratio | bytes identical |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for s in res["sizes"]:
        m0, m1 = s["ms"]["0"], s["ms"][n]
        r = {
            k: f"{s['ratio'][k]:.2f} [{s['ratio_range'][k][0]:.2f}, {s['ratio_range'][k][1]:.2f}]"
            for k in s["ratio"]
        }
        lines.append(
            f"| {s['size'][0]}x{s['size'][1]} | {s['bytes'] / 1e6:.2f} | {m0['write']:.1f} "
            f"| {m1['write']:.1f} | {r['write']} | {m0['read']:.1f} | {m1['read']:.1f} | {r['read']} "
            f"| {'yes' if s['identical'] else 'NO'} |"
        )
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    raise SystemExit(main())
