"""``fogref study``: the Unreal study on one ground-truth EXR, end to end.

1. The truth is read by :func:`fogref.gbuffer.load_truth` (the one reader); the
   physical fog, sun, sky and camera come from its ``fogref.params``.
2. Unreal's parameters: density/falloff/height by the exact mapping
   (:func:`fogref.mapping.unreal_basis.base_params`); FogInscatteringColor,
   DirectionalInscatteringColor, the exponent and the directional start distance
   fitted to the closed-form single scattering (:mod:`fogref.study.fit`); the
   other engine settings (StartDistance, FogMaxOpacity, FogCutoffDistance) at
   the editor defaults unless given.
3. ``fogref.compare`` writes its report to ``<out>/compare``.
4. The error budget (:mod:`fogref.study.budget`) needs three extra renders of
   the truth's scene *as the truth recorded it*: the header's ``fogref.scene``
   (path), ``fogref.scene_sha256`` (its bytes) and ``fogref.overrides``, the same
   sample count and pixel filter.  A scene file whose content changed since is
   refused (:func:`scene_of_truth`).  The renders: the scene without its sun (seed
   s), and scene and sun-less scene again with seed s + 1 (for the Monte Carlo
   noise); cached under ``renders_dir`` on the scene's content.
5. ``<out>/README.md`` summarises the headline numbers (:mod:`fogref.study.unreal_report`);
   its text is generated from the data (scene, overrides, spp, seed).
"""

from __future__ import annotations

import json
import time
from functools import partial
from pathlib import Path

import numpy as np

from fogref.atomic import write_text_atomic as write_text
from fogref.compare import compare
from fogref.compare.workers import check_processes, run_jobs, start_workers
from fogref.errors import FogrefError
from fogref.gbuffer import Truth, load_truth
from fogref.mapping import PhysicalScene, fit_unreal
from fogref.mapping.build import build_model
from fogref.render.cache import render_cached
from fogref.scene.defaults import overrides_used_by
from fogref.scene.edit import sunless_scene
from fogref.scene.inputs import file_sha256
from fogref.shipped_scenes import SCENES_DIR, scene_label
from fogref.study import budget as B
from fogref.study.unreal_report import readme

#: What-if variants of the engine settings (Unreal units, cm).
WHAT_IF = {
    "Unreal default DirectionalInscatteringStartDistance (100 m)": {
        "DirectionalInscatteringStartDistance": 10000.0
    },
    "StartDistance 20 m": {"StartDistance": 2000.0},
    "FogMaxOpacity 0.9": {"FogMaxOpacity": 0.9},
    "FogCutoffDistance 2 km": {"FogCutoffDistance": 200000.0},
}


def scene_of_truth(truth: Truth, scene: str | None = None) -> Path:
    """The scene file the truth was rendered from, checked against its recorded hash.

    Candidates: ``scene`` (``--scene``) if given, else the header's ``fogref.scene``
    as written, then relative to the EXR's folder and its parent.  Raises
    FogrefError when none exists, when the header lacks ``fogref.scene_sha256``,
    or when the file's SHA-256 differs from the recorded one (naming the file and
    both hashes): the budget must re-render the scene as the truth recorded it.
    """
    exr = Path(truth.path)
    recorded = truth.attrs.get("fogref.scene")
    recorded = None if recorded is None else str(recorded)
    sha = truth.attrs.get("fogref.scene_sha256")
    if not sha:
        raise FogrefError(
            f"{exr}: header attribute 'fogref.scene_sha256' is missing, so the scene it was "
            "rendered from cannot be checked; render the truth again with this fogref"
        )
    sha = str(sha)
    cands = [Path(scene)] if scene else []
    if recorded and not scene:
        cands += [Path(recorded), exr.parent / recorded, exr.parent.parent / recorded]
    found = [c for c in cands if c.is_file()]
    if not found:
        raise FogrefError(f"{exr}: cannot find the scene it was rendered from ({recorded!r}); pass --scene")
    for c in found:
        if file_sha256(c) == sha:
            return c
    c = found[0]
    raise FogrefError(
        f"{exr}: the scene file {c} has changed since this truth was rendered (its SHA-256 is now "
        f"{file_sha256(c)}, the truth recorded {sha}). The study re-renders budget steps from the scene "
        "as the truth recorded it: restore that version (or pass it with --scene), or render the truth again."
    )


def _render_cached(
    scene: Path, out: Path, spp: int, seed: int, overrides: dict, log, pixel_filter: str = "centre"
) -> Truth:
    """A truth of ``scene`` from fogref's render cache (:mod:`fogref.render.cache`) in ``out``'s folder."""

    t = time.perf_counter()
    truth, cached = render_cached(
        scene, spp, seed, overrides, cache_dir=out.parent, pixel_filter=pixel_filter
    )
    log(f"  {'cached' if cached else 'rendered'} {truth.path} ({time.perf_counter() - t:.1f} s)")
    return truth


def open_plane_check(scene: Path, rdir: Path, log, spp: int = 64, res=(160, 90)) -> dict:
    """The 'shadows' step on a scene without occluders: it must be pure Monte Carlo noise.

    Renders the scene (seeds 0 and 1) and its sun-less copy at low resolution;
    compares ``single - single_sky - closed-form sun`` with the noise expected of
    ``single - single_sky`` (from the two seeds, and from the stderr channels)."""
    ov = {"res": res[0], "resy": res[1]}
    nosun = sunless_scene(scene, rdir)
    a = _render_cached(scene, rdir / f"{scene.stem}_s0.exr", spp, 0, ov, log)
    b = _render_cached(scene, rdir / f"{scene.stem}_s1.exr", spp, 1, ov, log)
    ov_nosun = overrides_used_by(nosun, ov)
    sa = _render_cached(nosun, rdir / f"{scene.stem}_nosun_s0.exr", spp, 0, ov_nosun, log)
    sb = _render_cached(nosun, rdir / f"{scene.stem}_nosun_s1.exr", spp, 1, ov_nosun, log)
    pf = PhysicalScene.from_params(a.params)
    sun = B.closed_forms(a, pf)["sun_att"]
    sh = a.single - sa.single - sun
    sh_b = b.single - sb.single - sun
    return {
        "scene": scene_label(scene),
        "spp": spp,
        "resolution": list(res),
        "shadows_rmse": float(np.sqrt(np.mean(sh**2))),
        "shadows_mean": float(sh.mean()),
        "noise_rmse": float(np.sqrt(np.mean((sh - sh_b) ** 2)) / np.sqrt(2.0)),
        "noise_floor_stderr": float(np.sqrt(np.mean(a.stderr["single"] ** 2 + sa.stderr["single"] ** 2))),
        "single_rms": float(np.sqrt(np.mean(a.single**2))),
    }


def truth_overrides(truth: Truth) -> dict:
    """The truth's ``--set`` overrides (header ``fogref.overrides``); FogrefError if not an object."""
    ov = truth.attrs.get("fogref.overrides") or {}
    if not isinstance(ov, dict):
        raise FogrefError(f"{truth.path}: header attribute 'fogref.overrides' is not a JSON object: {ov!r}")
    return {str(k): v for k, v in ov.items()}


def run_study(
    exr,
    out_dir="out/unreal_study",
    renders_dir="out/study",
    scene: str | None = None,
    compare_report: bool = True,
    settings: dict | None = None,
    log=print,
    open_plane: str | Path | None = SCENES_DIR / "open_plane.xml",
    processes: int | None = 1,
) -> dict:
    """Run the whole study; returns the summary dict (also written as ``summary.json``).

    ``processes``: worker processes that draw the comparison's figures, as
    :func:`fogref.compare.compare` takes it (None: one per core; ``fogref study``'s default); they
    start here and import matplotlib while the fits run.

    FogrefError (before any work) for a truth that :func:`fogref.gbuffer.load_truth`
    refuses or whose scene changed since it was rendered (:func:`scene_of_truth`), or for a
    ``processes`` that is not None or an integer >= 1.
    """

    t0 = time.perf_counter()
    check_processes(processes)
    exr = Path(exr)
    truth = load_truth(exr)
    params = truth.params
    if not params.get("medium"):
        raise FogrefError(f"{exr}: header 'fogref.params' with the medium is missing")
    pf = PhysicalScene.from_params(params)
    spp = truth.spp
    if spp < 1:
        raise FogrefError(f"{exr}: header attribute 'fogref.spp' is missing or < 1")
    seed = int(truth.attrs.get("fogref.seed", 0))
    overrides = truth_overrides(truth)
    pixel_filter = str(truth.attrs.get("fogref.pixel_filter") or "centre")
    scene_path = scene_of_truth(truth, scene)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    provenance = {
        "truth": str(exr),
        "scene": str(scene_path),
        "scene_sha256": str(truth.attrs["fogref.scene_sha256"]),
        "overrides": overrides,
        "spp": spp,
        "seed": seed,
        "pixel_filter": pixel_filter,
    }

    # -- 1. fits ------------------------------------------------------------
    if compare_report:
        start_workers(processes)  # they import matplotlib while the fits run
    log("fitting Unreal's colours, exponent and start distance ...")
    fit = fit_unreal(pf)  # the one fit (as --from-scene and the sweeps; cached, so the model below reuses it)
    lobe = fit_unreal(pf, sun_attenuation=False, fit_start=False)
    model = build_model("ue4", settings, params)
    model_params = model.params
    fit_doc = fit.to_dict()
    fit_doc["unreal_editor"].update(
        {
            k: v
            for k, v in {
                "Start Distance": model_params.StartDistance,
                "Fog Max Opacity": model_params.FogMaxOpacity,
                "Fog Cutoff Distance": model_params.FogCutoffDistance,
            }.items()
        }
    )
    write_text(
        out / "fit.json",
        json.dumps({"scene": params.get("scene"), "fit": fit_doc, "lobe_only_fit": lobe.to_dict()}, indent=2)
        + "\n",
    )

    # -- 2. comparison --------------------------------------------------------
    cmp_summary = None
    if compare_report:
        log("comparing (fogref.compare) ...")
        rep = compare(truth, model, out / "compare", precision="float32", processes=processes)
        m = rep["metrics"]
        cmp_summary = {part: m[part]["all"] for part in ("final", "inscatter", "transmittance")}

    # -- 3. renders for the budget -------------------------------------------
    log("rendering the budget's extra images ...")
    rdir = Path(renders_dir)
    nosun = sunless_scene(scene_path, rdir)
    ov_nosun = overrides_used_by(nosun, overrides)
    sa = _render_cached(nosun, rdir / f"{exr.stem}_nosun_s{seed}.exr", spp, seed, ov_nosun, log, pixel_filter)
    tb = _render_cached(
        scene_path, rdir / f"{exr.stem}_s{seed + 1}.exr", spp, seed + 1, overrides, log, pixel_filter
    )
    sb = _render_cached(
        nosun, rdir / f"{exr.stem}_nosun_s{seed + 1}.exr", spp, seed + 1, ov_nosun, log, pixel_filter
    )

    # -- 4. budget -------------------------------------------------------------
    log("computing the error budget ...")
    for other in (tb, sa, sb):
        if other.shape != truth.shape:
            raise FogrefError(
                f"{other.path}: resolution {other.shape[::-1]} differs from {exr} {truth.shape[::-1]}"
            )
    S_a = B.chain(truth, sa.single, pf, lobe.params, model_params)
    S_b = B.chain(tb, sb.single, pf, lobe.params, model_params)
    valid = truth.surface_valid & tb.surface_valid
    noise = B.chain_noise(truth, sa.stderr["single"], lobe.params, model_params)
    res = B.attribute(S_a, truth.hit, valid, noise)
    B.add_noise(res, S_a, S_b, truth.hit, valid)
    log("computing the Shapley budget (all coalitions of the effects) ...")
    engine = B.unreal_engine(lobe.params, model_params)
    parts_a = B.shapley_parts(truth, sa.single, pf, engine)
    parts_b = B.shapley_parts(tb, sb.single, pf, engine)
    with_phase = B.phase_effect(pf)  # droplet fogs: their phase vs HG(g)
    for key, effects in (
        ("shapley", B.EFFECTS + with_phase),
        ("shapley_colours_in_lobe", B.EFFECTS_COLOURS_IN_LOBE + with_phase),
    ):
        res[key] = B.add_shapley_seed_noise(
            B.shapley_budget(parts_a, valid, effects), B.shapley_budget(parts_b, valid, effects, resamples=0)
        )
    del parts_a, parts_b
    res["what_if"] = B.what_if(truth, model_params, WHAT_IF)
    res["footprint"] = B.footprint_check(truth, pf, S_a)
    if open_plane:
        op = Path(open_plane)
        if op.is_file():
            log("closed-form check on the open plane ...")
            res["open_plane_check"] = open_plane_check(op, rdir, log)
    res["inputs"] = {
        **provenance,
        "sky_only": str(sa.path),
        "truth_other_seed": str(tb.path),
        "sky_only_other_seed": str(sb.path),
        "resolution": list(truth.shape[::-1]),
        "unreal_params": fit_doc["unreal"]
        | {
            "StartDistance_cm": model_params.StartDistance,
            "FogMaxOpacity": model_params.FogMaxOpacity,
            "FogCutoffDistance_cm": model_params.FogCutoffDistance,
        },
        "lobe_fit_params": lobe.to_dict()["unreal"],
    }
    res["method"] = B.__doc__
    write_text(out / "budget.json", json.dumps(res, indent=2) + "\n")
    write_text(
        out / "budget.md",
        B.markdown(res, title=f"Error budget of Unreal's exponential height fog on `{scene_path.stem}`"),
    )
    run_jobs([partial(B.plot, res, out / "budget.png")], processes)  # matplotlib stays in the workers

    summary = {
        "exr": str(exr),
        "scene": str(scene_path),
        "provenance": provenance,
        "fit": fit_doc,
        "lobe_fit": lobe.to_dict(),
        "compare": cmp_summary,
        "budget_total": res["total"],
        "largest_term": max(res["steps"], key=lambda s: s["share"]),
        "largest_shapley_term": max(res["shapley"]["effects"], key=lambda s: s["share"]),
        "seconds": time.perf_counter() - t0,
    }
    write_text(out / "summary.json", json.dumps(summary, indent=2) + "\n")
    write_text(out / "README.md", readme(summary, res))
    log(f"study written to {out} ({summary['seconds']:.1f} s)")
    return summary
