"""fogref's web-engine ports against the real engines in headless Chromium: the worst differences.

Runs the probes of ``tests/web_probe.py`` (the same ones ``tests/test_web_*.py`` assert on):
for each engine, 16 fog set-ups x 1024 probe pixels, read back from a float32 render target
(linear) and from the default canvas (8 bits, the engine's own output encoding; Filament: its
default colour grading, FXAA and dithering off), against the fogref port.  Writes
``reports/engines/conformance.md`` and ``conformance.json``.

    .venv/bin/python benchmarks/web_conformance.py [--out DIR]

Needs Debian's chromium and chromium-driver and ``npm ci`` (``scripts/setup.sh``); about 45 s.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import browser_util  # noqa: E402
import web_probe as wp  # noqa: E402

from fogref.atomic import write_text_atomic  # noqa: E402

ENGINES = (
    (wp.THREEJS, "three.js", "threejs", "r187", "eye depth"),
    (wp.BABYLON, "Babylon.js", "babylon", "9.35.0", "distance"),
    (wp.PLAYCANVAS, "PlayCanvas", "playcanvas", "v2.23.3", "far (z - near)/(far - near)"),
    (wp.FILAMENT, "Filament", "filament", "v1.53.4", "distance; height fog, sun term"),
)
CANVAS = {
    "threejs": "sRGB (outputColorSpace), NoToneMapping; fog blended after the encoding",
    "babylon": "unconverted (StandardMaterial, default image processing)",
    "playcanvas": "GAMMA_SRGB: pow(c + 1e-7, 1/2.2), TONEMAP_LINEAR",
    "filament": "default ColorGrading: ACES-legacy tone mapping, sRGB output (32^3 LUT); FXAA, dithering off",
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "reports" / "engines")
    out = ap.parse_args().out
    chromium = subprocess.run(["chromium", "--version"], capture_output=True, text=True).stdout.strip()
    drv = browser_util.start(200, 200, webgl=True)
    drv.set_script_timeout(wp.HANG_S)
    results = {}
    try:
        for engine, *_ in ENGINES:
            print(f"probing {engine.name} ...", flush=True)
            results[engine.name] = wp.measure(drv, engine)
    finally:
        drv.quit()
    lines = [
        "# The web engines' fog against fogref's ports",
        "",
        "Made by `.venv/bin/python benchmarks/web_conformance.py` on the CPU: "
        f"{chromium}, WebGL 2 on SwiftShader, headless, through selenium and chromium-driver.",
        "Per engine, 16 fog set-ups x 1024 probe pixels (60 unlit quads at depths 0.3..60 m with",
        "random colours, and 4 background tiles), 64x64 pixels, vertical field of view 60 deg, clip",
        "planes 0.1 and 500 m (`tests/web_probe.py`).  *linear*: the largest |engine - port| over",
        "pixels and channels of a float32 render target, in the material colour's units; *canvas*:",
        "the largest |engine - round(255 port)| on the default canvas, in 8-bit steps.",
        "",
        "| engine | npm version | source tag | fog coordinate | pixels | linear | canvas | canvas output |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for engine, label, model, tag, coord in ENGINES:
        r = results[engine.name]
        npm = wp.npm_version(engine.package)
        linear = f"{r['linear']:.2g}" if r["linear"] >= 0 else "n/a"
        lines.append(
            f"| {label} (`{model}`) | {engine.package} {npm} | {tag} | {coord} | {r['pixels']} "
            f"| {linear} | {r['canvas']:.0f}/255 | {CANVAS[model]} |"
        )
    lines += [
        "",
        "The tests that hold these bounds: `tests/test_web_threejs.py`, `tests/test_web_babylon.py`,",
        "`tests/test_web_playcanvas.py`, `tests/test_web_filament.py` (linear <= 1e-6, canvas <= 1/255).",
        "Filament: its JS API has no float read-back (*linear* n/a); the quads are unlit glTF",
        "(gltfio's ubershaders), exposure 1 and an indirect light of intensity 1 (the shader scales",
        "the fog colour by `iblLuminance`); the 4 background tiles are left out (Filament clears",
        "without fog; the port, like Filament's skybox, fogs a sky pixel): 960 pixels a set-up.",
        "",
    ]
    write_text_atomic(out / "conformance.md", "\n".join(lines))
    write_text_atomic(out / "conformance.json", json.dumps({"chromium": chromium, **results}, indent=1))
    print(f"wrote {out / 'conformance.md'}")


if __name__ == "__main__":
    main()
