"""What a UE user sees, split: raster EHF vs UE's path-traced fog vs the exact fog.

A UE user who compares the raster Exponential Height Fog with Unreal's path tracer
sees three things mixed: the raster approximations, the path tracer's own fog (its
density clamp and camera-centred cylinder, :mod:`fogref.media.ue_pathtracer`) and
the path tracer's noise.  This module separates them with fogref:

* :func:`render_split`: one scene rendered twice through fogref's render cache (UE's path-traced
  fog, and the exact fog with the same physical inputs but no clamp and no cylinder:
  :func:`fogref.mapping.unreal_pathtracer.exact_medium`) plus Unreal's raster fog
  (:mod:`fogref.models.ue4`, float64) composited over the first render's surface.
  Two signed differences telescope, ``raster - exact = (raster - PT) + (PT - exact)``;
  each gets its RMSE and its Monte Carlo noise (:func:`split_stats`: the truths' covariances
  through :func:`fogref.compare.metrics.mse_noise`).
* :func:`closed_form_split`: the same split on the transmittance (exact per ray in
  all three fogs: no noise) and on the sun's single scattering (Gauss-Legendre
  quadrature along each ray of closed-form transmittances: :func:`sun_single_scatter`),
  over a set of views; one configuration of a closed-form sweep (:func:`closed_form_row`,
  ``fogref sweep reports/sweeps/ue_pathtracer/SWEEP.toml``).
* :func:`split_study`: :func:`render_split` for a truth (``fogref study TRUTH --ue-pathtracer``):
  the raster EHF is the study's Unreal fog of the truth's physical fog
  (:func:`fogref.mapping.unreal.ue4_from_physical`), the path-traced fog is what UE's path tracer
  renders for the same settings; the split, each part with its noise, goes into the study's
  report (a section of ``budget.md``, ``summary.json``'s ``"ue_pathtracer_split"`` and
  ``ue_pathtracer_split.json``).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from fogref.atomic import write_text_atomic
from fogref.compare.metrics import mse_noise
from fogref.gbuffer import load_truth
from fogref.mapping import PhysicalScene
from fogref.mapping.unreal import Views, sample_views, ue4_from_physical
from fogref.mapping.unreal_pathtracer import (
    UEPathTracerSettings,
    exact_fog_params,
    exact_medium,
    pathtracer_medium,
    rewrite_scene,
    settings_from,
)
from fogref.media import NP, single_scatter_sun
from fogref.models.base import SKY_DISTANCE
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams
from fogref.render.cache import render_cached
from fogref.study.budget.engines import unreal_fog
from fogref.study.unreal import scene_of_truth, truth_overrides

__all__ = [
    "SECTION_BEGIN",
    "SECTION_END",
    "SPLIT_ROWS",
    "closed_form_row",
    "closed_form_split",
    "departure_row",
    "render_split",
    "split_section",
    "split_stats",
    "split_study",
    "sun_single_scatter",
]

#: Gauss-Legendre nodes per panel and panels per ray of :func:`sun_single_scatter`.
GL_NODES = 16
GL_PANELS = 48


def sun_single_scatter(medium, views: Views, w, E: float = 1.0, t_cap: float = 2.0e5) -> np.ndarray:
    """Grey sun single scattering ``int sigma rho alpha p E T(0,t) T_sun(t) dt`` per view, by
    quadrature of closed-form transmittances (any medium, bounded or not; channel 0).

    The ray ``[0, min(D, t_cap, bounds exit)]`` is cut into :data:`GL_PANELS` panels,
    geometric from 1 cm (the integrand falls off with distance) and at every layer's
    clamp height (a kink), each integrated with :data:`GL_NODES`-point Gauss-Legendre.
    Checked against the closed form :func:`fogref.media.single_scatter_sun` in the tests.
    """
    medium.require_height_only("the study's sun quadrature")
    o, d, D = views.rays()
    n = len(D)
    t0, t1 = medium.clip(NP, o, d)
    t0 = np.broadcast_to(np.asarray(t0, dtype=float), (n,))
    t_end = np.minimum(np.minimum(np.broadcast_to(np.asarray(t1, dtype=float), (n,)), D), t_cap)
    ok = t_end > t0
    a, b = np.where(ok, t0, 0.0), np.where(ok, t_end, 1.0)
    # panel edges: geometric in (t - a) from 1e-5 of the length, plus the clamp-height crossings
    frac = np.concatenate([[0.0], np.geomspace(1e-5, 1.0, GL_PANELS)])
    edges = a[:, None] + (b - a)[:, None] * frac[None, :]
    edges[:, -1] = b
    cuts = [edges]
    for layer in medium.layers:
        yc = getattr(layer, "clamp_height", None)
        if yc is not None and math.isfinite(yc):
            with np.errstate(divide="ignore", invalid="ignore"):
                tc = (yc - o[1]) / d[1]
            tc = np.where(np.isfinite(tc) & (tc > a) & (tc < b), tc, a)
            cuts.append(tc[:, None])
    edges = np.sort(np.concatenate(cuts, axis=1), axis=1)
    x, wts = np.polynomial.legendre.leggauss(GL_NODES)
    lo, hi = edges[:, :-1], edges[:, 1:]
    half = 0.5 * (hi - lo)
    t = (0.5 * (hi + lo))[..., None] + half[..., None] * x  # (n, panels, nodes)
    wt = half[..., None] * wts
    tf = t.reshape(n, -1)
    P = tuple(o[i][:, None] + tf * d[i][:, None] for i in range(3))
    flat = tuple(p.ravel() for p in P)
    rep = lambda v: np.repeat(v, tf.shape[1])  # noqa: E731
    sig = medium.sigma_t[0]
    rho = medium.density(NP, flat)
    tau = medium.optical_depth(NP, tuple(rep(x_) for x_ in o), tuple(rep(x_) for x_ in d), tf.ravel())
    wv = tuple(np.full(flat[0].shape, c) for c in w)
    tau_sun = medium.optical_depth(NP, flat, wv, NP.largest)
    cos = d[0] * w[0] + d[1] * w[1] + d[2] * w[2]
    p = medium.phase_value(NP, cos)
    f = sig * rho * np.exp(-sig * (tau + tau_sun))
    out = (f.reshape(wt.shape) * wt).sum(axis=(1, 2)) * medium.albedo[0] * p * E
    return np.where(ok & (w[1] > 0), out, 0.0)


def closed_form_split(
    ue: UE4FogParams,
    pt: UEPathTracerSettings,
    camera,
    views: Views | None = None,
    sun=None,
    ss_views: Views | None = None,
) -> dict:
    """Per-view transmittance of the raster fog, UE's path-traced fog and the exact fog,
    and (with ``sun``, a unit direction toward the sun) the sun's single scattering of
    the last two on ``ss_views`` (default: ``views``).

    Returns a dict of arrays ``T_raster, T_pt, T_exact`` (and ``ss_pt, ss_exact``) and
    ``views``.  The raster fog's T is Unreal's own (its density ``(ln 2)^2 FogDensity``
    per :mod:`fogref.models.ue4`, start distance and cutoff as given in ``ue``).
    """
    views = views or sample_views(camera)
    m_pt, m_ex = pathtracer_medium(ue, pt, camera), exact_medium(ue, pt)
    o, d, D = views.rays()
    raster = (views.camera, views.world_positions(SKY_DISTANCE))
    out: dict[str, Any] = {
        "views": views,
        "radius_m": m_pt.bounds.radius,
        "T_raster": np.asarray(UE4ExponentialHeightFog(ue).evaluate(*raster, "float64").transmittance)[:, 0],
        "T_pt": m_pt.transmittance(NP, o, d, D)[0],
        "T_exact": m_ex.transmittance(NP, o, d, D)[0],
    }
    if sun is not None:
        sv = ss_views or views
        so, sd, sD = sv.rays()
        out["ss_pt"] = sun_single_scatter(m_pt, sv, sun)
        out["ss_exact"] = single_scatter_sun(NP, m_ex, so, sd, sD, tuple(sun), (1.0, 1.0, 1.0))[0]
        out["ss_views"] = sv
    return out


def _rel(a: np.ndarray, b: np.ndarray, floor: float) -> np.ndarray:
    return np.abs(a - b) / np.maximum(np.abs(b), max(floor, 1e-12))


def departure_row(split: dict, threshold: float = 0.01) -> dict:
    """Summary of :func:`closed_form_split`: how far UE's path-traced fog departs from the exact
    fog (and the raster fog from the path-traced one), in the fog's opacity ``1 - T`` (what the
    sky's single scattering ``alpha L_sky (1 - T)`` is proportional to) and in the sun's single
    scattering; relative to the exact value (floor: 1e-3 of the largest, and 1e-12)."""
    op_pt, op_ex, op_r = 1 - split["T_pt"], 1 - split["T_exact"], 1 - split["T_raster"]
    rel = _rel(op_pt, op_ex, 1e-3 * max(op_ex.max(), 1e-300))
    rel_r = _rel(op_r, op_pt, 1e-3 * max(op_pt.max(), 1e-300))
    v = split["views"]
    inside = np.isfinite(v.D) & (v.D <= split.get("radius_m", np.inf))
    row = {
        "opacity_rel_max": float(rel.max()),
        "opacity_frac_over": float((rel > threshold).mean()),
        "opacity_rel_max_inside": float(rel[inside].max()) if inside.any() else None,
        "opacity_nearest_departure_m": _nearest(v, rel > threshold),
        "raster_vs_pt_opacity_rel_median": float(np.median(rel_r)),
    }
    if "ss_pt" in split:
        rs = _rel(split["ss_pt"], split["ss_exact"], 1e-3 * max(split["ss_exact"].max(), 1e-300))
        row.update(
            sun_ss_rel_max=float(rs.max()),
            sun_ss_frac_over=float((rs > threshold).mean()),
            sun_ss_nearest_departure_m=_nearest(split["ss_views"], rs > threshold),
        )
    return row


def _nearest(views: Views, over: np.ndarray) -> float | None:
    """The shortest view distance [m] at which some view departs (``inf``: only the sky; None: none)."""
    if not over.any():
        return None
    return float(np.min(views.D[over]))


# -- renders -----------------------------------------------------------------------
def split_stats(diff: np.ndarray, cov: np.ndarray, mask: np.ndarray | None = None, spp: int = 0) -> dict:
    """One signed difference image's size and its Monte Carlo noise, on the image's scale: the
    square roots of :func:`fogref.compare.metrics.mse_noise`'s MSEs for ``diff`` (H, W, 3) whose noise
    has the per-pixel covariance ``cov`` (H, W, 3, 3) [image units²] from ``spp`` samples per pixel
    (0: exact), over the pixels of ``mask`` (H, W) (default all; none: all 0, below the noise).

    ``rmse``; ``noise_floor``: the RMSE noise alone gives (root of the mean variance); ``debiased``:
    ``sqrt(max(rmse² - noise_floor², 0))``; ``below_noise``: the MSE is within
    :data:`fogref.compare.metrics.NOISE_Z` standard errors of the floor (the channels' full covariance).

    Examples
    --------
    >>> s = split_stats(np.full((2, 2, 3), 0.1), np.broadcast_to(np.eye(3) * 1e-4, (2, 2, 3, 3)))
    >>> round(s["rmse"], 6), round(s["noise_floor"], 6), s["below_noise"], round(s["debiased"], 4)
    (0.1, 0.01, False, 0.0995)
    """
    m = mse_noise(diff, np.sqrt(np.diagonal(cov, axis1=-2, axis2=-1)), mask, cov=cov, spp=spp)
    if m is None:
        return {"rmse": 0.0, "noise_floor": 0.0, "debiased": 0.0, "below_noise": True}
    roots = {"rmse": "mse", "noise_floor": "noise_floor", "debiased": "debiased"}
    return {k: math.sqrt(m[v]) for k, v in roots.items()} | {"below_noise": m["below_noise"]}


def render_split(
    scene_xml: str | Path,
    ue: UE4FogParams,
    pt: UEPathTracerSettings,
    out_dir: str | Path,
    spp: int = 16,
    seed: int = 0,
    overrides: dict | None = None,
) -> dict:
    """Render ``scene_xml`` with UE's path-traced fog and with the exact fog, and split
    ``raster - exact`` into ``raster - PT`` and ``PT - exact`` (final radiance, RGB).

    Both renders are pixel-exact truths of :func:`fogref.render.cache.render_cached` in ``out_dir``
    (a second call renders nothing).  The raster image is Unreal's fog (float64, ``ue``'s colours) over the PT
    truth's ``surface`` (:func:`fogref.study.budget.engines.unreal_fog`):
    ``surface T_raster + inscatter_raster``.  Noise: the PT truth's covariance of R,G,B
    (raster - PT; the raster part's own noise, through ``surface``, is neglected: stated in
    ``notes``), the exact truth's (raster - exact) and their sum (PT - exact).  Pixels where the
    PT truth's ``surface`` is undefined (no sample reached it) are left out of all three.  The
    camera is the scene's ``$camera_origin``.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    p_pt, p_ex = out_dir / "ue_pathtracer.xml", out_dir / "exact.xml"
    rewrite_scene(scene_xml, p_pt, ue, pt)
    rewrite_scene(scene_xml, p_ex, ue, pt, params=exact_fog_params(ue, pt))
    t_pt, t_ex = (render_cached(p, spp, seed, overrides, cache_dir=out_dir)[0] for p in (p_pt, p_ex))
    T_r, L_r = unreal_fog(ue, t_pt, "float64", SKY_DISTANCE)
    S_raster = t_pt.surface * T_r + L_r
    C_pt, C_ex = t_pt.noise_cov("final"), t_ex.noise_cov("final")
    valid = t_pt.surface_valid
    excluded = int((~valid).sum())
    return {
        "raster_vs_pt": split_stats(S_raster - t_pt.final, C_pt, valid, spp),
        "pt_vs_exact": split_stats(t_pt.final - t_ex.final, C_pt + C_ex, valid, spp),
        "raster_vs_exact": split_stats(S_raster - t_ex.final, C_ex, valid, spp),
        "images": {"raster": S_raster, "pt": t_pt.final, "exact": t_ex.final},
        "notes": [
            "the raster image's noise through the rendered surface is neglected",
            "colours of the raster fog are ue's (FogInscatteringColor, DirectionalInscatteringColor)",
        ]
        + ([f"{excluded} pixel(s) left out: the PT render's surface is undefined there"] if excluded else []),
    }


# -- the study's section --------------------------------------------------------------
#: The markers of :func:`split_study`'s section in ``budget.md`` (replaced when run again).
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
    >>> C = np.eye(3)[None, None] * 1e-4
    >>> s = {k: split_stats(np.full((1, 1, 3), 0.1), C) for k, _, _ in SPLIT_ROWS}
    >>> print(split_section(s, UE4FogParams(), UEPathTracerSettings(), 4).splitlines()[7])
    | raster EHF - UE path-traced fog | 0.1 | 0.01 | 0.0995 | no | what the raster fog's approximations cost |
    """
    lines = [
        SECTION_BEGIN,
        "## What a UE user sees: raster EHF, UE's path-traced fog, the exact fog",
        "",
        f"Final radiance (RGB), fogpath at {spp} spp; noise: the renders' per-pixel covariances; below the "
        "noise: within 3 standard errors of the noise floor (fogref.study.ue_pathtracer.split_study).",
        "",
        "| difference | RMSE | noise floor | RMSE without noise | below the noise | what it is |",
        "|---|---|---|---|---|---|",
    ]
    for key, name, what in SPLIT_ROWS:
        st = split[key]
        sizes = " | ".join(f"{st[k]:.3g}" for k in ("rmse", "noise_floor", "debiased"))
        lines.append(f"| {name} | {sizes} | {'yes' if st['below_noise'] else 'no'} | {what} |")
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
    split = render_split(path, ue, pt, rdir, spp=spp, seed=seed, overrides=truth_overrides(truth))
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
        **{key: split[key] for key, _, _ in SPLIT_ROWS},
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


# -- the closed-form sweep ----------------------------------------------------------------
def closed_form_row(values: dict, spec: dict) -> dict:
    """One configuration of a closed-form sweep (``[sweep] kind = "ue_pathtracer"``; ``spec``: its
    tables, :func:`fogref.study.sweep.sections.read_closed_form`): :func:`departure_row` of
    :func:`closed_form_split` for the editor values ``values`` over ``spec["fixed"]``, on
    ``n_dirs`` Fibonacci directions x ``geomspace(*distances)`` [m] (the sun's single scattering:
    ``ss_n_dirs`` x ``ss_distances``), plus ``departs``: either departure over ``spec["threshold"]``.

    Examples
    --------
    A 30 m cylinder in thin fog at the ground: the opacity departs first just past its wall.

    >>> v = {"n_dirs": 16, "distances": [10.0, 1000.0, 3], "ss_n_dirs": 8, "ss_distances": [30.0, 300.0, 2]}
    >>> fixed = {"FogDensity": 0.02, "FogHeightFalloff": 0.02}
    >>> spec = {"fixed": fixed, "views": {**v, "ground": 0.0}, "sun": [0.0, 1.0, 1.0], "threshold": 0.01}
    >>> row = closed_form_row({"VolumetricFogDistance": 3000.0}, spec)
    >>> row["departs"], 30.0 < row["opacity_nearest_departure_m"] < 35.0
    (True, True)
    """
    kw = {**spec["fixed"], **values}
    camera = tuple(kw.pop("camera", (0.0, 2.0, 0.0)))
    v, thr, sun = spec["views"], float(spec["threshold"]), spec.get("sun")
    sun = None if sun is None else tuple(np.asarray(sun, float) / np.linalg.norm(sun))
    views, ss = (
        sample_views(camera, int(v[k + "n_dirs"]), np.geomspace(*v[k + "distances"]), ground=v.get("ground"))
        for k in ("", "ss_")
    )
    row = departure_row(closed_form_split(*settings_from(**kw), camera, views, sun, ss), thr)
    row["departs"] = bool(row["opacity_rel_max"] > thr or (row.get("sun_ss_rel_max") or 0.0) > thr)
    return row
