"""`fogref engine render` before and after, for each web engine, side by side.
-> reports/benchmarks/engine_speed.{json,md}

``fogref engine render TRUTH --engine E --from-scene --out DIR`` on a truth of ``scenes/valley.xml``
(320x180, 16 spp, seed 0, rendered here) for each engine (three.js, Babylon.js, PlayCanvas,
Filament), each run a fresh process (Chromium started, the page loaded, the view drawn, the images
written), the base checkout and this one alternating, ``--rounds`` rounds.  In each run the page's
part (``fogref.engines.render.render_engine``: Chromium's start, the page's load and draw) is timed
apart.  Identity: each engine's images (``final.exr``, ``T.exr``, ``inscatter.exr``, ``surface.exr``:
every channel's pixels; ``canvas.png``) and ``engine.json`` (less its ``seconds``) the same in both
checkouts.  Both checkouts use this checkout's ``node_modules``.

    .venv/bin/python benchmarks/engine_speed.py --base /tmp/base [--rounds 3]
"""

from __future__ import annotations

import json
import os
import statistics
import tempfile
from pathlib import Path

import numpy as np
from _checkouts import (
    ROOT,
    before_after,
    before_after_arguments,
    identity_lines,
    kept_reading,
    ratio_range,
    timed_command,
    valley_truth,
    write_report,
)
from PIL import Image

from fogref.engines import ENGINES
from fogref.exrio import read_exr

PART = "fogref.engines.render:render_engine"  # Chromium's start, the page's load and its draw
IMAGES = ("final.exr", "T.exr", "inscatter.exr", "surface.exr", "canvas.png")


def _decoded(path: Path) -> dict:
    """An image's pixels, channel name -> array (a PNG: one array)."""
    return {"": np.asarray(Image.open(path))} if path.suffix == ".png" else read_exr(path)[0]


def _same_outputs(a: Path, b: Path) -> bool:
    """Do two ``fogref engine render`` folders hold the same pixels and the same record (its
    ``seconds`` left out)?"""

    def same_pixels(x: dict, y: dict) -> bool:
        return sorted(x) == sorted(y) and all(np.array_equal(x[k], y[k]) for k in x)

    def record(folder: Path) -> dict:
        return {k: v for k, v in json.loads((folder / "engine.json").read_text()).items() if k != "seconds"}

    return all(same_pixels(_decoded(a / n), _decoded(b / n)) for n in IMAGES) and record(a) == record(b)


def main() -> None:
    args = before_after_arguments(__doc__)
    work = Path(tempfile.mkdtemp(prefix="fogref-engine-speed-"))
    truth = valley_truth(work, 320, 180, 16)
    os.environ["FOGREF_NODE_MODULES"] = str(ROOT / "node_modules")  # the same engines for both
    engines = sorted(ENGINES)
    folder = {}

    def run(name: str, checkout: Path) -> dict:
        row = {}
        for engine in engines:
            out = work / name / engine
            folder[name, engine] = out
            cmd = ["engine", "render", truth, "--engine", engine, "--from-scene", "--out", out]
            row[engine] = timed_command(checkout, PART, cmd)
        return row

    def identical() -> dict:
        return {f"`{e}`": _same_outputs(folder["before", e], folder["after", e]) for e in engines}

    result = before_after(Path(args.base), args.rounds, run, identical)
    result["truth"] = {"scene": "scenes/valley.xml", "resolution": [320, 180], "spp": 16, "seed": 0}
    runs, described = result["runs"], __doc__.split("\n\n")[1]
    md = [
        "# `fogref engine render`, each web engine, before and after",
        "",
        f"`benchmarks/engine_speed.py`: {described}",
        "",
        f"Base: {result['base']}; after: {result['after']}.  {result['cores']} cores, load average "
        f"(1 min) {result['load_average'][0]:.1f} before and {result['load_average'][1]:.1f} after; "
        f"{args.rounds} rounds.  Seconds are wall time (medians of the rounds); the ratio is each "
        "round's before / after, median [smallest, largest].",
        "",
        "| engine | command before [s] | command after [s] | before / after | page before [s] | "
        "page after [s] | before / after |",
        "|---|---:|---:|---|---:|---:|---|",
    ]
    for e in engines:
        cells = []
        for key in ("wall_s", "part_s"):
            before, after = ([r[e][key] for r in runs[m]] for m in ("before", "after"))
            cells += [f"{statistics.median(before):.2f}", f"{statistics.median(after):.2f}"]
            cells.append(ratio_range(before, after))
        md.append(f"| {e} | " + " | ".join(cells) + " |")
    how = " (every channel's pixels, the canvas, engine.json less its time)"
    md += identity_lines(result["identical"], how)
    md += kept_reading(Path(args.out) / "engine_speed.md") or []
    write_report(Path(args.out), "engine_speed", result, "\n".join(md) + "\n")


if __name__ == "__main__":
    main()
