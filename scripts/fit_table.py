"""Write reports/fit/engines.md and engines.json: every engine's best fit to the physical fog, and
each engine's paste-ready settings of that fit (``fogref export``) under ``snippets/``.

Usage: ``.venv/bin/python scripts/fit_table.py [--scene scenes/valley.xml] [--out reports/fit]``;
``--from-json`` rewrites engines.md and the snippets from the committed ``engines.json`` without
fitting again.

For each built-in model, :func:`fogref.fit_model` on the scene's fog with the sun at the scene's
own elevation and at 30 and 60 degrees (the scene's azimuth), each elevation fitted on its own;
directions doubled from 128 to at most 512.  Then :func:`fogref.translate` of the scene's Unreal
settings (its physical mapping) to every engine, at the scene's sun, on 256 directions.  Closed
forms only (no rendering).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

MODELS = ("ue4", "unity", "hdrp", "filament", "altitude", "box", "godot", "bevy", "threejs")
EXTRA_ELEVATIONS = (30.0, 60.0)
MAX_DIRS = 512
TRANSLATE_DIRS = 256


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="scenes/valley.xml")
    ap.add_argument("--out", default="out/fit")
    ap.add_argument(
        "--from-json", action="store_true", help="rewrite engines.md and the snippets from OUT/engines.json"
    )
    a = ap.parse_args(argv)
    if a.from_json:
        from fogref.atomic import write_text_atomic

        table = Path(a.out) / "engines.json"
        write_text_atomic(Path(a.out) / "engines.md", markdown(json.loads(table.read_text())))
        write_snippets(table, Path(a.out) / "snippets")
        return 0
    from fogref.atomic import write_text_atomic as write_text
    from fogref.mapping.fit import sun_elevation
    from fogref.study.fit import fit_model, reference_scene, translate

    pf = reference_scene(a.scene)
    elevations = [round(sun_elevation(pf), 2), *EXTRA_ELEVATIONS]
    command = f"python scripts/fit_table.py --scene {a.scene} --out {a.out}"
    rows = []
    t0 = time.perf_counter()
    for name in MODELS:
        for e in elevations:
            r = fit_model(name, pf, sun_elevations=[e], max_dirs=MAX_DIRS)
            rows.append(r.to_dict())
            print(
                f"{name:9s} {e:5.1f} deg  rel RMSE {r.rel_rmse:.3f}  T RMSE {r.rmse_T:.3f}  "
                f"({r.history['fit_seconds']:.1f} s)",
                file=sys.stderr,
            )
    translations = []
    for name in MODELS:
        t = translate("ue4", name, None, pf, views=TRANSLATE_DIRS)
        translations.append(t.to_dict())
        print(
            f"ue4 -> {name:9s} vs truth {t.residual_vs_truth:.3f}  vs source {t.residual_vs_source:.3f}",
            file=sys.stderr,
        )
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    doc = {
        "command": command,
        "scene": a.scene,
        "sun_elevations_deg": elevations,
        "max_directions": MAX_DIRS,
        "fits": rows,
        "translations": translations,
        "translate_directions": TRANSLATE_DIRS,
        "seconds": time.perf_counter() - t0,
    }
    write_text(out / "engines.json", json.dumps(doc, indent=2) + "\n")
    write_text(out / "engines.md", markdown(doc))
    write_snippets(out / "engines.json", out / "snippets")
    return 0


#: engine -> file names of its snippets under OUT/snippets/, by the suffix export gives.
SNIPPET_FILES = {
    "unreal": {".py": "unreal.py"},
    "godot": {".tres": "fogref_environment.tres", ".tscn": "fogref.tscn"},
    "bevy": {".rs": "bevy.rs"},
    "threejs": {".mjs": "threejs.mjs"},
    "unity": {".cs": "FogrefFog.cs"},
    "hdrp": {".cs": "FogrefHdrpFog.cs"},
    "filament": {".mjs": "filament.mjs"},
}


def write_snippets(table: Path, folder: Path) -> None:
    """Each engine's ``fogref export`` of its fit at the table's first sun elevation (the scene's own),
    with the table's scene's camera and sun."""
    from fogref.atomic import write_text_atomic as write_text
    from fogref.study.export import export_engine

    doc = json.loads(table.read_text())
    folder.mkdir(parents=True, exist_ok=True)
    for engine, names in SNIPPET_FILES.items():
        files = export_engine(engine, json_path=table, scene=doc["scene"])
        for suffix, text in files.items():
            write_text(folder / names[suffix], text)
        print(f"{engine}: {', '.join(names.values())}", file=sys.stderr)


def markdown(doc: dict) -> str:
    from fogref.models.terms import with_unit

    el = doc["sun_elevations_deg"]
    by = {}
    for r in doc["fits"]:
        by.setdefault(r["model"], []).append(r)
    lines = [
        "# Every engine's fog fitted to the physical fog",
        "",
        f"Made by `{doc['command']}` (closed forms, no rendering; {doc['seconds']:.0f} s).",
        "",
        f"Scene `{doc['scene']}`; the sun at {', '.join(f'{e:g}°' for e in el)} above the horizon "
        f"(the first is the scene's own; same azimuth), each elevation fitted on its own.  Target: the "
        "closed-form single scattering (sun + sky) and transmittance of the physical fog over "
        "views from the camera (Fibonacci directions with d_y ≥ −0.5 at 12 distances from 10 m to "
        "20 km, plus the sky), directions doubled from 128 until converged (at most "
        f"{doc['max_directions']}).  Loss: "
        "squared inscatter error + squared transmittance error times the RMS inscatter "
        "(`fogref.mapping.fit`).  Free parameters and bounds: `fogref.mapping.free`; the other "
        "settings come from the model's physical mapping (or its defaults where the scene has "
        "none).",
        "",
        "*Residual*: relative RMSE of the inscatter (RMSE / RMS of the physical inscatter) and RMSE of "
        "the transmittance at the best fit: the error no setting of that engine can remove.  "
        "*±*: 1σ from the Jacobian at the optimum, cov = s²(JᵀJ)⁺, s² = SSE/(m − p) (the misfit "
        "treated as noise: how sharply the views pin the parameter).",
        "",
        "## Residual error",
        "",
        "| model | "
        + " | ".join(f"{e:g}°: inscatter rel. RMSE / T RMSE" for e in el)
        + " | cannot represent |",
        "|---|" + "---|" * len(el) + "---|",
    ]
    for m, rs in by.items():
        cells = [f"{r['error']['rel_rmse']:.3f} / {r['error']['rmse_transmittance']:.3f}" for r in rs]
        lines.append(f"| {m} | " + " | ".join(cells) + f" | {rs[0]['fit']['cannot_represent']} |")
    if doc.get("translations"):
        lines += [
            "",
            "## Unreal's settings translated to every engine",
            "",
            f"`fogref.translate('ue4', NAME)`: the scene's Unreal settings (its physical mapping) -> "
            "their physical fog (Unreal's exact extinction; g, sun and sky fitted to Unreal's "
            "inscatter) "
            f"-> NAME fitted to it; the scene's sun, {doc['translate_directions']} directions.  "
            "Residual: relative RMSE of the inscatter of NAME's best settings against the physical fog "
            "and against Unreal itself.  ue4 -> ue4 is not the identity with a sun: the physical "
            "fog reproduces Unreal's cosine lobe only to the 'physical vs Unreal' error, and Unreal's "
            "best fit to that fog differs from the settings it came from by that much.",
            "",
            "| target | vs physical fog | vs Unreal | physical fog vs Unreal |",
            "|---|---|---|---|",
        ]
        for t in doc["translations"]:
            r = t["residual"]
            lines.append(
                f"| {t['target']['model']} | {r['target_vs_truth_rel_rmse']:.3f} | "
                f"{r['target_vs_source_rel_rmse']:.3f} | {r['physical_vs_source_rel_rmse']:.3f} |"
            )
    lines += [
        "",
        "## Best-fit parameters",
        "",
        "In brackets, each parameter's unit in the engine; a colour is linear (fogref's value, the "
        "shader's) and the bracket says what the engine's UI shows (sRGB for Godot's and Unity's "
        "colour pickers; `fogref.models.terms`).  Paste-ready settings of the first column's fits, "
        "with the scene's camera and sun, in each engine's units and axes (`fogref export`): "
        + ", ".join(f"[{n}](snippets/{n})" for names in SNIPPET_FILES.values() for n in names.values())
        + ".",
        "",
    ]
    for m, rs in by.items():
        lines += [
            f"### {m}",
            "",
            "| parameter | " + " | ".join(f"{e:g}°" for e in el) + " |",
            "|---|" + "---|" * len(el),
        ]
        for k in rs[0]["parameters"]:
            cells = []
            for r in rs:
                p = r["parameters"][k]
                cells.append(
                    f"{p['value']:.4g} ± {p['uncertainty']:.2g}" + (" (bound)" if p.get("at_bound") else "")
                )
            name, _, unit = with_unit(m, k).partition(" ")
            lines.append(f"| `{name}` {unit} | " + " | ".join(cells) + " |")
        conv = ", ".join("yes" if r["fit"].get("directions_converged") else "no" for r in rs)
        lines += [
            "",
            f"Directions: {', '.join(str(r['fit']['n_dirs']) for r in rs)} (converged: {conv}); "
            f"start: {rs[0]['fit']['start']}.",
            "",
        ]
    return "\n".join(lines)


if __name__ == "__main__":
    raise SystemExit(main())
