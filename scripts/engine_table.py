"""Write reports/engines/README.md: the truth against the real three.js, linear and canvas.

Usage: ``.venv/bin/python scripts/engine_table.py [--res 96 --resy 54 --spp 64 --out reports/engines]``

For the default scene (``scenes/valley.xml``) and the open plane (``scenes/open_plane.xml``):
a ground truth (``fogref.cached_truth``, seed 0, pixel-exact), then three.js from
``node_modules`` in headless Chromium renders the truth's view (``fogref.engines``), and
``fogref.compare.check`` compares the engine's linear float render target (final, T,
inscatter; ``composite`` is its fog over the truth's surface) and its 8-bit sRGB canvas with the
truth, as ``fogref compare TRUTH --engine threejs [--engine-output canvas]`` does.  The
engine's images and ``engine.json`` go to ``out/engines/<scene>/`` (git-ignored).  A few minutes
on two cores (the truths are cached after the first run).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: scene name -> (file, fog settings: None = the scene's mapping, else --param values, and why)
SCENES = {
    "valley": (
        "scenes/valley.xml",
        None,
        "mapped from the scene (`--from-scene`: FogExp2, density = σt at the camera)",
    ),
    "open_plane": (
        "scenes/open_plane.xml",
        {"mode": "FogExp2", "density": 0.002 * 0.9704455335485082, "color": [0.18, 0.27, 0.45]},
        "`--param`: the mapping refuses the scene's coloured σt (0.0015, 0.002, 0.0025)/m; FogExp2 with the "
        "green channel's σt at the camera (0.002 exp(-0.01·3)) and colour albedo × sky",
    ),
}
ROWS = {
    "linear": [
        ("T", "surface"),
        ("inscatter", "surface"),
        ("inscatter", "sky"),
        ("composite", "surface"),
        ("composite", "sky"),
        ("final", "surface"),
        ("final", "sky"),
    ],
    "canvas": [("final", "surface"), ("final", "sky")],
}


def _cell(row, sign: str = "") -> str:
    if row.estimate is None:
        return "—"
    return f"{row.estimate:{sign}.3f} [{row.low:{sign}.3f}, {row.high:{sign}.3f}]"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, default=96)
    ap.add_argument("--resy", type=int, default=54)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--out", default="reports/engines")
    ap.add_argument("--work", default="out/engines")
    a = ap.parse_args(argv)
    import fogref
    from fogref.atomic import write_text_atomic
    from fogref.cli.engine import engine_model
    from fogref.compare.check import check
    from fogref.compare.foreign import load_engine_images
    from fogref.engines.render import render_and_write
    from fogref.engines.view import view_from_truth

    command = (
        f".venv/bin/python scripts/engine_table.py --res {a.res} --resy {a.resy} --spp {a.spp} --out {a.out}"
    )
    lines, record = [], {}
    t0 = time.perf_counter()
    for name, (scene, params, how) in SCENES.items():
        truth = fogref.cached_truth(ROOT / scene, res=(a.res, a.resy), spp=a.spp, seed=0)
        view = view_from_truth(truth)
        model = engine_model("threejs", params, truth.params if params is None else None)
        r, paths, rec = render_and_write(
            view, model, Path(a.work) / name, "threejs", truth, [(truth.path, "truth")]
        )
        shape = truth.shape
        results = {
            "linear": check(
                truth,
                load_engine_images(paths["final"], paths["transmittance"], paths["inscatter"], shape=shape),
            ),
            "canvas": check(truth, load_engine_images(paths["canvas"], shape=shape)),
        }
        record[name] = {"engine": rec, "rows": {k: v.to_dict() for k, v in results.items()}}
        lines += [
            f"### `{scene}` ({a.res}×{a.resy} px, {a.spp} spp, seed 0)",
            "",
            f"three.js fog: {how}; settings `{json.dumps(rec['fog_settings'])}`.",
            "",
            *[f"- {s}" for s in rec["summary"]],
            "",
            "| output | part | region | rel. RMSE [99 %] | rel. bias [99 %] |",
            "|---|---|---|---|---|",
        ]
        for out, rows in ROWS.items():
            for part, region in rows:
                res = results[out]
                lines.append(
                    f"| {out} | {part} | {region} | {_cell(res.row(part, region, 'rel_rmse'))} "
                    f"| {_cell(res.row(part, region, 'rel_bias'), '+')} |"
                )
        lines.append("")
        print(f"{name}: done ({time.perf_counter() - t0:.0f} s)", file=sys.stderr)
    first = next(iter(record.values()))["engine"]
    head = [
        "# The truth against the real three.js",
        "",
        f"three.js {first['version']} (npm `three`, `package.json`) in headless {first['browser']} with "
        f"SwiftShader WebGL 2 (`{first['webgl_renderer']}`), driven by selenium (`fogref.engines`). Each row "
        "compares one part of the engine's images with the truth: `linear` is its float32 render target "
        "(final image, and its fog's transmittance `T` and inscatter from passes with black materials; "
        "`composite` puts that fog over the truth's own surface radiance, so only the fog differs), "
        "`canvas` the 8-bit sRGB canvas three.js ships (default output colour space and tone mapping; "
        "its fog is blended in sRGB). Metrics: relative RMSE and relative bias against the truth, with "
        "99 % intervals from the truth's noise (`fogref.compare.check`); `final` also carries the "
        "engine's own surface shading (Lambert under a directional sun and a hemisphere sky, no "
        "shadows), which is not the fog's error. three.js draws its background without fog, so on "
        "`sky` its transmittance is 1 and its inscatter 0.",
        "",
        f"Made by `{command}` in {time.perf_counter() - t0:.0f} s.",
        "",
    ]
    out = Path(a.out)
    write_text_atomic(out / "README.md", "\n".join(head + lines))
    write_text_atomic(out / "engines.json", json.dumps(record, indent=2) + "\n")
    print(f"wrote {out / 'README.md'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
