"""Write reports/engines/README.md: the truth against every real engine, linear and canvas.

Usage: ``.venv/bin/python scripts/engine_table.py [--res 96 --resy 54 --spp 64 --out reports/engines]``

For the default scene (``scenes/valley.xml``) and the open plane (``scenes/open_plane.xml``):
a ground truth (``fogref.cached_truth``, seed 0, pixel-exact), then each engine of
``fogref.engines.ENGINES`` (three.js, Babylon.js, PlayCanvas, Filament from ``node_modules``, in headless
Chromium) renders the truth's view with its fog mapped from the scene (``fogref.cli.engine.
engine_model``, as ``--from-scene``), and ``fogref.compare.check`` compares the engine's linear
float render target (final, T, inscatter; ``composite`` is its fog over the truth's surface) and
its 8-bit canvas with the truth, as ``fogref compare TRUTH --engine NAME --from-scene
[--engine-output canvas]`` does.  The engine's images and ``engine.json`` go to
``out/engines/<engine>/<scene>/`` (git-ignored).  A few minutes on two cores (the truths are
cached after the first run).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: scene name -> (file, the medium's sigma_t to map instead of the scene's (None: its own), why)
SCENES = {
    "valley": ("scenes/valley.xml", None, "mapped from the scene (`--from-scene`)"),
    "open_plane": (
        "scenes/open_plane.xml",
        0.002,
        "mapped from the scene with its green channel's σt, 0.002/m (the mappings refuse the scene's "
        "coloured σt (0.0015, 0.002, 0.0025)/m; `--param` gives the same settings)",
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
    from fogref.engines import ENGINES
    from fogref.engines.render import render_and_write
    from fogref.engines.view import view_from_truth

    command = (
        f".venv/bin/python scripts/engine_table.py --res {a.res} --resy {a.resy} --spp {a.spp} --out {a.out}"
    )
    lines, record = [], {}
    t0 = time.perf_counter()
    for engine in ENGINES:
        for name, (scene, sigma_t, how) in SCENES.items():
            truth = fogref.cached_truth(ROOT / scene, res=(a.res, a.resy), spp=a.spp, seed=0)
            view = view_from_truth(truth)
            params = json.loads(json.dumps(truth.params))
            if sigma_t is not None:
                params["medium"]["sigma_t"] = sigma_t
            model, sources = engine_model(engine, None, params, view)
            r, paths, rec = render_and_write(
                view,
                model,
                Path(a.work) / engine / name,
                engine,
                truth,
                [(truth.path, "truth")],
                sources=sources,
            )
            shape = truth.shape
            finals = [paths["final"], paths["transmittance"], paths["inscatter"]]
            results = {
                "linear": check(truth, load_engine_images(*finals, shape=shape)),
                "canvas": check(truth, load_engine_images(paths["canvas"], shape=shape)),
            }
            record.setdefault(engine, {})[name] = {
                "engine": rec,
                "rows": {k: v.to_dict() for k, v in results.items()},
            }
            lines += [
                f"### {engine} {r.version}: `{scene}` ({a.res}×{a.resy} px, {a.spp} spp, seed 0)",
                "",
                f"`fogref compare TRUTH --engine {engine} --from-scene`; fog {how}; settings "
                f"`{json.dumps(rec['fog_settings'])}`; canvas: {rec['canvas_colour_space']}, tone "
                f"mapping {rec['canvas_tone_mapping']}.",
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
            print(f"{engine} {name}: done ({time.perf_counter() - t0:.0f} s)", file=sys.stderr)
    versions = ", ".join(f"{e} {v['valley']['engine']['version']}" for e, v in record.items())
    first = next(iter(record.values()))["valley"]["engine"]
    head = [
        "# The truth against the real engines",
        "",
        f"{versions} (npm, `package.json`) in headless {first['browser']} with SwiftShader WebGL 2 "
        f"(`{first['webgl_renderer']}`), driven by selenium (`fogref.engines`). Each row compares one "
        "part of an engine's images with the truth: `linear` is its float32 render target (final "
        "image, and its fog's transmittance `T` and inscatter from passes with black materials; "
        "`composite` puts that fog over the truth's own surface radiance, so only the fog differs), "
        "`canvas` the 8-bit canvas the engine ships with its defaults (three.js: sRGB output, its fog"
        " blended in sRGB; Babylon.js: the linear values unconverted; PlayCanvas: a 2.2 power; "
        "Filament: its default colour grading, ACES-legacy tone mapping and sRGB output, with FXAA "
        "and dithering off), read as sRGB. Metrics: relative RMSE and relative bias against the "
        "truth, with 99 % intervals from the truth's noise (`fogref.compare.check`); `final` also "
        "carries the engine's own surface shading (Lambert under a directional sun and a sky light: "
        "three.js's and Babylon's hemisphere lights are the truth's sky, PlayCanvas's uniform ambient"
        " light is it only on horizontal ground; Filament (WebAssembly, whose npm build ships no "
        "material compiler): unlit glTF triangles whose vertex colours are fogref's Lambert shading "
        "of each vertex, interpolated; no shadows), which is not the fog's error. The engines draw "
        "their background without fog, so on `sky` their transmittance is 1 and their inscatter 0.",
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
