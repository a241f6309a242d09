"""``fogref study TRUTH --ue-pathtracer``: what a UE user sees, split into raster EHF vs UE's
path-traced fog and UE's path-traced fog vs the exact fog, each with its noise
(:func:`split_study`), written as a section of the study's ``budget.md``, as
``ue_pathtracer_split.json`` and into ``summary.json``.  The renders and statistics are
:func:`fogref.study.ue_pathtracer.render_split` and :func:`~fogref.study.ue_pathtracer.split_stats`.
"""

from __future__ import annotations

from pathlib import Path

from fogref.mapping.unreal_pathtracer import (
    UEPathTracerSettings,
)
from fogref.models.ue4 import UE4FogParams
from fogref.study.ue_pathtracer import render_split

__all__ = ["SECTION_BEGIN", "SECTION_END", "SPLIT_ROWS", "split_section", "split_study"]

SECTION_BEGIN = "<!-- fogref: ue_pathtracer split -->"
SECTION_END = "<!-- /fogref: ue_pathtracer split -->"
#: The three differences of the split, in the report's order, with what each one is.
SPLIT_ROWS = (
    ("raster_vs_pt", "raster EHF - UE path-traced fog", "what the raster fog's approximations cost"),
    ("pt_vs_exact", "UE path-traced fog - exact fog", "what the path tracer's clamp and cylinder cost"),
    ("raster_vs_exact", "raster EHF - exact fog", "the sum of both (telescoping)"),
)


def split_section(split: dict, ue: UE4FogParams, pt: UEPathTracerSettings, spp: int) -> str:
    """The Markdown section of :func:`split_study` (between :data:`SECTION_BEGIN` and :data:`SECTION_END`).

    Examples
    --------
    >>> import numpy as np
    >>> from fogref.study.ue_pathtracer import split_stats
    >>> s = {k: split_stats(np.full((1, 1, 3), 0.1), np.full((1, 1, 3), 1e-4)) for k, _, _ in SPLIT_ROWS}
    >>> print(split_section(s, UE4FogParams(), UEPathTracerSettings(), 4).splitlines()[7])
    | raster EHF - UE path-traced fog | 0.1 | 0.01 | 0.0995 | no | what the raster fog's approximations cost |
    """
    lines = [
        SECTION_BEGIN,
        "## What a UE user sees: raster EHF, UE's path-traced fog, the exact fog",
        "",
        f"Final radiance (RGB), fogpath at {spp} spp; noise: the renders' per-pixel standard errors "
        "(fogref.study.ue_pathtracer_split.split_study).",
        "",
        "| difference | RMSE | noise floor | RMSE without noise | within 2x noise | what it is |",
        "|---|---|---|---|---|---|",
    ]
    for key, name, what in SPLIT_ROWS:
        st = split[key]
        below = "yes" if st.below_noise else "no"
        lines.append(
            f"| {name} | {st.rmse:.3g} | {st.noise_floor:.3g} | {st.debiased:.3g} | {below} | {what} |"
        )
    lines += [
        "",
        f"Path tracer: density clamp {pt.density_clamp:g} (r.PathTracing.FogDensityClamp), cylinder radius "
        f"{pt.radius_cm:g} cm (VolumetricFogDistance), extinction scale {pt.VolumetricFogExtinctionScale:g}, "
        f"albedo {', '.join(f'{a:.3g}' for a in pt.VolumetricFogAlbedo)}, g {pt.g:g}; raster FogDensity "
        f"{ue.FogDensity:.4g}, FogHeightFalloff {ue.FogHeightFalloff:.4g}.",
        SECTION_END,
    ]
    return "\n".join(lines) + "\n"


def _put_section(path: Path, section: str) -> None:
    from fogref.atomic import write_text_atomic

    text = path.read_text(encoding="utf-8") if path.exists() else ""
    if SECTION_BEGIN in text and SECTION_END in text:
        head, rest = text.split(SECTION_BEGIN, 1)
        text = head + section.rstrip("\n") + rest.split(SECTION_END, 1)[1]
    else:
        text = text + ("\n" if text and not text.endswith("\n\n") else "") + section
    write_text_atomic(path, text)


def split_study(
    exr: str | Path,
    out_dir: str | Path = "out/unreal_study",
    renders_dir: str | Path | None = None,
    pt: UEPathTracerSettings | None = None,
    ue: UE4FogParams | None = None,
    spp: int | None = None,
    seed: int | None = None,
    scene: str | Path | None = None,
) -> dict:
    """What a UE user sees for the truth ``exr``, split into raster EHF vs UE's path-traced fog and
    UE's path-traced fog vs the exact fog, each with its noise (:func:`render_split`), written
    into the study's report folder ``out_dir``.

    ``ue``: the raster EHF settings (default: the study's Unreal fog of the truth's physical fog,
    :func:`fogref.mapping.unreal.ue4_from_physical`: exact density, falloff and height, fitted
    colours); ``pt``: the path tracer's settings (default: UEPathTracerSettings with the truth's
    albedo and g as VolumetricFogAlbedo and VolumetricFogScatteringDistribution, the engine's
    defaults otherwise).  The scene is the truth's (checked against its recorded hash), with its
    overrides; ``spp`` and ``seed`` default to the truth's.  Renders go to ``renders_dir``
    (default ``out_dir/ue_pathtracer``).

    Writes ``ue_pathtracer_split.json``, a section of ``budget.md`` (:func:`split_section`,
    replaced when run again) and, when the study's ``summary.json`` exists, its key
    ``"ue_pathtracer_split"``.  Returns the JSON's dict.
    """
    import json

    from fogref.atomic import write_text_atomic
    from fogref.gbuffer import load_truth
    from fogref.mapping import PhysicalScene
    from fogref.mapping.unreal import ue4_from_physical
    from fogref.study.unreal import _overrides, scene_of_truth

    truth = load_truth(exr)
    pf = PhysicalScene.from_params(truth.params)
    if ue is None:
        ue = ue4_from_physical(pf).params
    if pt is None:
        pt = UEPathTracerSettings(
            VolumetricFogAlbedo=tuple(float(a) for a in pf.albedo),
            VolumetricFogScatteringDistribution=float(pf.medium.g),
        )
    spp = int(truth.spp if spp is None else spp)
    seed = int(truth.attrs.get("fogref.seed", 0) if seed is None else seed)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rdir = Path(renders_dir) if renders_dir is not None else out / "ue_pathtracer"
    path = scene_of_truth(truth, None if scene is None else str(scene))
    split = render_split(path, ue, pt, rdir, spp=spp, seed=seed, overrides=_overrides(truth))
    doc = {
        "truth": str(exr),
        "scene": str(path),
        "spp": spp,
        "seed": seed,
        "pathtracer": {
            "density_clamp": pt.density_clamp,
            "radius_cm": pt.radius_cm,
            "extinction_scale": pt.VolumetricFogExtinctionScale,
            "albedo": list(pt.VolumetricFogAlbedo),
            "g": pt.g,
        },
        "raster": {"FogDensity": ue.FogDensity, "FogHeightFalloff": ue.FogHeightFalloff},
        **{
            key: {
                "rmse": split[key].rmse,
                "noise_floor": split[key].noise_floor,
                "debiased": split[key].debiased,
                "below_noise": bool(split[key].below_noise),
            }
            for key, _, _ in SPLIT_ROWS
        },
        "notes": split["notes"],
    }
    write_text_atomic(out / "ue_pathtracer_split.json", json.dumps(doc, indent=2) + "\n")
    _put_section(out / "budget.md", split_section(split, ue, pt, spp))
    summary = out / "summary.json"
    if summary.exists():
        d = json.loads(summary.read_text(encoding="utf-8"))
        d["ue_pathtracer_split"] = doc
        write_text_atomic(summary, json.dumps(d, indent=2) + "\n")
    return doc


# -- the sweep ---------------------------------------------------------------------
