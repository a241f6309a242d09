"""`fogref compare` before and after: the whole command, and the costs it no longer pays.
-> reports/benchmarks/compare_speed.{json,md}

The Quick start's comparison, ``fogref compare TRUTH --model ue4 --from-scene``, on truths of
``scenes/valley.xml`` rendered here at 320x180 and 64x36 (16 spp) and 960x540 (4 spp, half the
rounds), seed 0.  Each run is a fresh
process, one machine; rounds alternate the modes:

* ``before``: the checkout ``--base`` (a git worktree), run with this ``.venv`` and its own
  ``fogref`` package first on ``PYTHONPATH`` (the dependencies are the same);
* ``after``: this checkout as the command runs it (the figures drawn on worker processes, one
  per core);
* ``after, 1 process``: this checkout with ``--processes 1`` (the figures in the command's
  process, as before).

Per size: each mode's median wall time, and the per-round ratios ``before / mode`` as their median
with the smallest and largest in brackets.  Then, apart, the three changes' own costs, each
measured side by side in this process: the zlib level of the HTML viewer's arrays (1 against 9) on
the 320x180 truth's images, the PNG level of the figures (3 against Pillow's default 6) on the
report's own figures re-encoded, and importing ``scipy.stats`` against ``scipy.special`` (fresh
processes, after ``colour`` as in the command).  Identity: ``metrics.json`` of every mode equal
but for paths, every figure's pixels equal (decoded), and the viewer's arrays equal (decoded).

    .venv/bin/python benchmarks/compare_speed.py --base /tmp/compare-base [--rounds 3]

(``git worktree add /tmp/compare-base <commit>`` makes the base.)
"""

from __future__ import annotations

import io
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
import zlib
from pathlib import Path

import numpy as np
from _checkouts import (
    FOGREF_MAIN,
    ROOT,
    alternating,
    before_after_arguments,
    checkout_env,
    commit_of,
    metrics_without_paths,
    ratio_range,
    valley_truth,
    write_report,
)
from PIL import Image

PY = sys.executable
SIZES = ((320, 180, 16), (64, 36, 16), (960, 540, 4))  # width, height, spp
MODES = ("before", "after", "after, 1 process")


def _compare(checkout: Path, truth: Path, out: Path, extra: list[str]) -> float:
    cmd = [PY, "-c", FOGREF_MAIN, "compare", str(truth), "--model", "ue4", "--from-scene"]
    cmd += ["--out", str(out), *extra]
    t0 = time.perf_counter()
    p = subprocess.run(cmd, env=checkout_env(checkout), capture_output=True, text=True, cwd=checkout)
    wall = time.perf_counter() - t0
    if p.returncode not in (0, 1, 3):  # pass, fail, inconclusive: a verdict was reached
        raise SystemExit(f"{' '.join(cmd)} exited {p.returncode}:\n{p.stderr[-3000:]}")
    return wall


def _pixels_equal(a: Path, b: Path) -> tuple[int, int]:
    """(figures whose decoded pixels are equal, figures) of the PNGs under ``a`` and ``b``."""
    pngs = sorted(p.relative_to(a) for p in a.rglob("*.png"))
    same = sum(np.array_equal(np.asarray(Image.open(a / p)), np.asarray(Image.open(b / p))) for p in pngs)
    return same, len(pngs)


def _viewer_arrays(folder: Path) -> list:
    """The decoded arrays of a report page's viewer (what its JavaScript inflates)."""
    sys.path.insert(0, str(ROOT))
    from fogref.html.inline import decode_half

    text = (folder / "report.html").read_text()
    pattern = r'\{"shape":\[[^\]]*\],"encoding":"f16-shuffle-deflate","data":"[^"]*"(?:,"scale":[^}]*)?\}'
    return [decode_half(json.loads(m.group(0))) for m in re.finditer(pattern, text)]


def _zlib_levels(truth: Path) -> dict:
    sys.path.insert(0, str(ROOT))
    from fogref.exrio import read_exr

    ch, _ = read_exr(truth)
    raws = []
    for name in sorted(k[:-1] for k in ch if k.endswith("R")):
        h = np.clip(np.stack([ch[name + c] for c in "RGB"], -1), -65504, 65504).astype("<f2")
        raws.append(np.ascontiguousarray(h).reshape(-1).view(np.uint8).reshape(-1, 2).T.tobytes())
    rows = {}
    for level in (1, 9, 1, 9, 1, 9):
        t0 = time.perf_counter()
        size = sum(len(zlib.compress(r, level)) for r in raws)
        rows.setdefault(level, {"s": [], "bytes": size})["s"].append(time.perf_counter() - t0)
    return {"images": len(raws), "raw_bytes": sum(map(len, raws)), "levels": rows}


def _png_levels(folder: Path) -> dict:
    images = [Image.open(p) for p in sorted(folder.rglob("*.png"))]
    for im in images:
        im.load()
    rows = {}
    for level in (3, 6, 3, 6, 3, 6):
        t0, size = time.perf_counter(), 0
        for im in images:
            buf = io.BytesIO()
            im.save(buf, format="png", compress_level=level)
            size += buf.tell()
        rows.setdefault(level, {"s": [], "bytes": size})["s"].append(time.perf_counter() - t0)
    return {"figures": len(images), "levels": rows}


def _import_seconds(module: str) -> float:
    code = (
        "import time, matplotlib, colour; t = time.perf_counter(); "
        f"import {module}; print(time.perf_counter() - t)"
    )
    return float(subprocess.run([PY, "-c", code], capture_output=True, text=True, check=True).stdout)


def main() -> None:
    a = before_after_arguments(__doc__)
    base = Path(a.base).resolve()
    checkouts = {"before": base, "after": ROOT, "after, 1 process": ROOT}
    extra = {"before": [], "after": [], "after, 1 process": ["--processes", "1"]}
    work = Path(tempfile.mkdtemp(prefix="compare-speed-"))
    load = [os.getloadavg()[0]]
    result: dict = {
        "base": commit_of(base),
        "after": commit_of(ROOT),
        "cores": len(os.sched_getaffinity(0)),
        "rounds": a.rounds,
        "sizes": {},
    }
    for w, h, spp in SIZES:
        rounds = a.rounds if w * h <= 320 * 180 else max(2, a.rounds // 2)
        truth = valley_truth(work, w, h, spp)
        _compare(ROOT, truth, work / "warm", [])  # the page cache and Python's bytecode, once
        times = alternating(
            {m: checkouts[m] for m in MODES},
            rounds,
            lambda mode, checkout: _compare(checkout, truth, work / f"{w}x{h}" / mode, extra[mode]),
        )
        load.append(os.getloadavg()[0])
        folders = {m: work / f"{w}x{h}" / m for m in MODES}
        same_metrics = all(
            metrics_without_paths(folders[m]) == metrics_without_paths(folders["before"]) for m in MODES
        )
        figures = {m: _pixels_equal(folders["before"], folders[m]) for m in MODES[1:]}
        arrays = {m: _viewer_arrays(folders[m]) for m in MODES}
        viewer = {
            m: len(arrays[m]) == len(arrays["before"]) > 0
            and all(np.array_equal(x, y) for x, y in zip(arrays["before"], arrays[m]))
            for m in MODES[1:]
        }
        sizes = {m: sum(p.stat().st_size for p in folders[m].rglob("*") if p.is_file()) for m in MODES}
        result["sizes"][f"{w}x{h}"] = {
            "times_s": times,
            "metrics_equal": same_metrics,
            "figures_pixels_equal": figures,
            "viewer_arrays_equal": viewer,
            "report_bytes": sizes,
            "page_bytes": {m: (folders[m] / "report.html").stat().st_size for m in MODES},
        }
    big = work / "320x180"
    result["zlib"] = _zlib_levels(work / "valley_320x180.exr")
    result["png"] = _png_levels(big / "before")
    result["imports_s"] = {
        m: [_import_seconds(m) for _ in range(3)] for m in ("scipy.stats", "scipy.special")
    }
    load.append(os.getloadavg()[0])
    result["load_average"] = load
    write_report(Path(a.out), "compare_speed", result, report(result))


def report(r: dict) -> str:
    """The Markdown page of a run."""
    md = [
        "# `fogref compare` before and after",
        "",
        f"`benchmarks/compare_speed.py`: `fogref compare TRUTH --model ue4 --from-scene` on truths of "
        f"`scenes/valley.xml` (16 spp; 4 spp at 960x540), each run a fresh process, {r['rounds']} rounds "
        f"alternating the modes (half as many at 960x540); {r['cores']} cores, load average (1 min) "
        + ", ".join(f"{x:.1f}" for x in r["load_average"])
        + f" (start, after each size, end).  `before`: {r['base']}; `after`: {r['after']}, the "
        "figures drawn on worker processes, one per core (the command's default); `after, 1 "
        "process`: the same with `--processes 1`.  Ratio: `before` / the mode's time, per round; "
        "median [smallest, largest].",
        "",
        "| size | mode | wall [s], median | each round [s] | before / mode | report folder [MB] |",
        "|---|---|---:|---|---|---:|",
    ]
    for size, s in r["sizes"].items():
        t = s["times_s"]
        for m in MODES:
            ratio = "" if m == "before" else ratio_range(t["before"], t[m])
            each = ", ".join(f"{x:.2f}" for x in t[m])
            md.append(
                f"| {size} | {m} | {statistics.median(t[m]):.2f} | {each} | {ratio} | "
                f"{s['report_bytes'][m] / 1e6:.2f} |"
            )
    md += ["", "Identity against `before`:", ""]
    for size, s in r["sizes"].items():
        figs = ", ".join(f"{m}: {a} of {b}" for m, (a, b) in s["figures_pixels_equal"].items())
        viewer = ", ".join(f"{m}: {'yes' if v else 'NO'}" for m, v in s["viewer_arrays_equal"].items())
        md.append(
            f"- {size}: `metrics.json` equal but for paths: {'yes' if s['metrics_equal'] else 'NO'}; "
            f"figures with equal pixels: {figs}; the viewer's arrays equal: {viewer}; report page "
            + ", ".join(f"{m} {b / 1e6:.2f} MB" for m, b in s["page_bytes"].items())
            + "."
        )
    z, p = r["zlib"], r["png"]
    zl = {int(k): v for k, v in z["levels"].items()}
    pl = {int(k): v for k, v in p["levels"].items()}
    ms = lambda row: 1e3 * statistics.median(row["s"])  # noqa: E731
    imp = {k: statistics.median(v) for k, v in r["imports_s"].items()}
    md += [
        "",
        "The changes' own costs (side by side, 3 of each alternating, medians):",
        "",
        f"- **The viewer's arrays** ({z['images']} RGB images of the 320x180 truth, "
        f"{z['raw_bytes'] / 1e6:.1f} MB of half floats): zlib level 9 {ms(zl[9]):.0f} ms, "
        f"{zl[9]['bytes'] / 1e6:.2f} MB; level 1 {ms(zl[1]):.0f} ms, {zl[1]['bytes'] / 1e6:.2f} MB "
        f"({ms(zl[9]) / ms(zl[1]):.1f}x faster, {zl[1]['bytes'] / zl[9]['bytes'] - 1:+.1%} bytes).",
        f"- **The figures** (the 320x180 report's {p['figures']} PNGs re-encoded): Pillow's level 6 "
        f"{ms(pl[6]):.0f} ms, {pl[6]['bytes'] / 1e6:.2f} MB; level 3 {ms(pl[3]):.0f} ms, "
        f"{pl[3]['bytes'] / 1e6:.2f} MB ({ms(pl[6]) / ms(pl[3]):.1f}x faster, "
        f"{pl[3]['bytes'] / pl[6]['bytes'] - 1:+.1%} bytes).",
        f"- **The intervals' quantiles**: importing `scipy.stats` after `colour` {imp['scipy.stats']:.2f} s, "
        f"`scipy.special` {imp['scipy.special']:.2f} s (fresh processes, medians of 3); `norm.ppf` and "
        "`t.ppf` are `scipy.special`'s `ndtri` and `stdtrit`, so every interval is the same.",
        "",
    ]
    return "\n".join(md)


if __name__ == "__main__":
    main()
