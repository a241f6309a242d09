"""What a UE user sees, split: raster EHF vs UE's path-traced fog vs the exact fog.

A UE user who compares the raster Exponential Height Fog with Unreal's path tracer
sees three things mixed: the raster approximations, the path tracer's own fog (its
density clamp and camera-centred cylinder, :mod:`fogref.media.ue_pathtracer`) and
the path tracer's noise.  This module separates them with fogref:

* :func:`render_split`: one scene rendered twice by fogpath (UE's path-traced fog,
  and the exact fog with the same physical inputs but no clamp and no cylinder:
  :func:`fogref.mapping.unreal_pathtracer.exact_medium`) plus Unreal's raster fog
  (:mod:`fogref.models.ue4`, float64) composited over the first render's surface.
  Two signed differences telescope, ``raster - exact = (raster - PT) + (PT - exact)``;
  each gets its RMSE and its Monte Carlo noise (per-pixel standard errors from the
  renders' second moments: :func:`split_stats`).
* :func:`closed_form_split`: the same split on the transmittance (exact per ray in
  all three fogs: no noise) and on the sun's single scattering (Gauss-Legendre
  quadrature along each ray of closed-form transmittances: :func:`sun_single_scatter`),
  over a set of views; what the committed sweep ``reports/sweeps/ue_pathtracer`` uses
  (:func:`run_sweep`, ``python -m fogref.study.ue_pathtracer SWEEP.toml``).
* :func:`split_study`: :func:`render_split` for a truth (``fogref study TRUTH --ue-pathtracer``):
  the raster EHF is the study's Unreal fog of the truth's physical fog
  (:func:`fogref.mapping.unreal.ue4_from_physical`), the path-traced fog is what UE's path tracer
  renders for the same settings; the split, each part with its noise, goes into the study's
  report (a section of ``budget.md``, ``summary.json``'s ``"ue_pathtracer_split"`` and
  ``ue_pathtracer_split.json``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fogref.compare import noise
from fogref.mapping.unreal import Views, sample_views
from fogref.mapping.unreal_pathtracer import (
    UEPathTracerSettings,
    exact_medium,
    pathtracer_medium,
    settings_from,
)
from fogref.media import NP, single_scatter_sun
from fogref.models.base import SKY_DISTANCE
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams

__all__ = [
    "SplitStats",
    "closed_form_split",
    "departure_row",
    "render_split",
    "run_sweep",
    "split_stats",
    "sun_single_scatter",
]

#: Gauss-Legendre nodes per panel and panels per ray of :func:`sun_single_scatter`.
GL_NODES = 16
GL_PANELS = 48


def _rays(views: Views):
    o = tuple(np.full(len(views.D), c) for c in views.camera)
    d = tuple(views.d[:, i] for i in range(3))
    D = np.where(views.sky, NP.largest, views.D)
    return o, d, D


def sun_single_scatter(medium, views: Views, w, E: float = 1.0, t_cap: float = 2.0e5) -> np.ndarray:
    """Grey sun single scattering ``int sigma rho alpha p E T(0,t) T_sun(t) dt`` per view, by
    quadrature of closed-form transmittances (any medium, bounded or not; channel 0).

    The ray ``[0, min(D, t_cap, bounds exit)]`` is cut into :data:`GL_PANELS` panels,
    geometric from 1 cm (the integrand falls off with distance) and at every layer's
    clamp height (a kink), each integrated with :data:`GL_NODES`-point Gauss-Legendre.
    Checked against the closed form :func:`fogref.media.single_scatter_sun` in the tests.
    """
    medium.require_height_only("the study's sun quadrature")
    o, d, D = _rays(views)
    n = len(D)
    t0, t1 = medium.clip(NP, o, d)
    t0 = np.broadcast_to(np.asarray(t0, dtype=float), (n,))
    t_end = np.minimum(np.minimum(np.broadcast_to(np.asarray(t1, dtype=float), (n,)), D), t_cap)
    ok = t_end > t0
    a = np.where(ok, t0, 0.0)
    b = np.where(ok, t_end, 1.0)
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


def _raster_T(ue: UE4FogParams, views: Views) -> np.ndarray:
    fog = UE4ExponentialHeightFog(ue)
    r = fog.evaluate(views.camera, views.world_positions(SKY_DISTANCE), "float64")
    return np.asarray(r.transmittance, dtype=float)[:, 0]


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
    o, d, D = _rays(views)
    out: dict[str, Any] = {
        "views": views,
        "radius_m": m_pt.bounds.radius,
        "T_raster": _raster_T(ue, views),
        "T_pt": m_pt.transmittance(NP, o, d, D)[0],
        "T_exact": m_ex.transmittance(NP, o, d, D)[0],
    }
    if sun is not None:
        sv = ss_views or views
        so, sd, sD = _rays(sv)
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
@dataclass
class SplitStats:
    """One signed difference image's size and its Monte Carlo noise (over the valid pixels).

    rmse: RMSE of the difference; noise_floor: the RMSE that noise alone gives (root of the
    mean of the per-pixel variances); debiased: ``sqrt(max(rmse^2 - noise_floor^2, 0))``,
    the difference's size without the noise; below_noise: ``rmse <= 2 noise_floor``.
    """

    rmse: float
    noise_floor: float
    below_noise: bool
    debiased: float = 0.0


def split_stats(diff: np.ndarray, var: np.ndarray, mask: np.ndarray | None = None) -> SplitStats:
    """:class:`SplitStats` of a difference image ``diff`` (H, W, C) with per-pixel variance ``var``.

    Examples
    --------
    >>> s = split_stats(np.full((2, 2, 3), 0.1), np.full((2, 2, 3), 1e-4))
    >>> round(s.rmse, 6), round(s.noise_floor, 6), s.below_noise, round(s.debiased, 4)
    (0.1, 0.01, False, 0.0995)
    """
    m = np.ones(diff.shape[:2], bool) if mask is None else mask
    d, v = diff[m], var[m]
    if not d.size:
        return SplitStats(0.0, 0.0, True, 0.0)
    # the renders give each channel's variance only; Q (the debiased square) reads only C's diagonal
    q, _ = noise.squared_stat(d, noise.add_diagonal(np.zeros((*v.shape, 3)), v), spp=0)
    rmse = float(np.sqrt(np.mean(d * d)))
    floor = float(np.sqrt(np.mean(v)))
    return SplitStats(rmse, floor, rmse <= 2.0 * floor, math.sqrt(max(q / d.size, 0.0)))


def _moments(mi, scene, spp: int, seed: int):
    integ = scene.integrator()
    names = ["R", "G", "B"] + list(integ.aov_names())
    sums, squares = integ.render_moments(scene, seed=seed, spp=spp)
    mean = np.array(sums) / spp
    sq = np.array(squares) / spp
    return names, mean, sq


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

    The raster image is Unreal's fog (float64, ``ue``'s colours) over the PT render's
    unattenuated ``surface``: ``surface T_raster + inscatter_raster``.  Noise: the PT
    render's variance of R,G,B (raster - PT; the raster part's own noise, through
    ``surface``, is neglected: stated in ``notes``) and the sum of both renders' variances
    (PT - exact).  The camera is the scene's ``$camera_origin``.
    """
    from fogref.mapping.unreal_pathtracer import exact_fog_params, rewrite_scene
    from fogref.render.load import load_scene
    from fogref.render.variant import set_variant

    set_variant()
    import mitsuba as mi

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    p_pt, p_ex = out_dir / "ue_pathtracer.xml", out_dir / "exact.xml"
    # every sample through the pixel centre: the truths' convention
    rewrite_scene(scene_xml, p_pt, ue, pt, pixel_exact=True)
    rewrite_scene(scene_xml, p_ex, ue, pt, params=exact_fog_params(ue, pt), pixel_exact=True)
    res: dict[str, Any] = {}
    for key, p in (("pt", p_pt), ("exact", p_ex)):
        scene, desc = load_scene(p, overrides)
        names, mean, sq = _moments(mi, scene, spp, seed)
        res[key] = (names, mean, sq, desc)
    names, m_pt, sq_pt, desc = res["pt"]
    _, m_ex, sq_ex, _ = res["exact"]
    ix = {n: i for i, n in enumerate(names)}
    rgb = [ix["R"], ix["G"], ix["B"]]
    n_sq = len(rgb)
    var_pt = np.maximum(sq_pt[..., :n_sq] - m_pt[..., rgb] ** 2, 0.0) / spp
    var_ex = np.maximum(sq_ex[..., :n_sq] - m_ex[..., rgb] ** 2, 0.0) / spp
    hit = m_pt[..., ix["hit"]] > 0.5
    cam = np.asarray(desc["camera"]["origin"], dtype=float)
    view = np.stack([m_pt[..., ix[f"view.{c}"]] for c in "XYZ"], axis=-1)
    view /= np.linalg.norm(view, axis=-1, keepdims=True)
    dist = np.where(hit, m_pt[..., ix["distance"]], SKY_DISTANCE)
    wp = cam + view * dist[..., None]
    r = UE4ExponentialHeightFog(ue).evaluate(cam, wp.reshape(-1, 3), "float64")
    T_r = np.asarray(r.transmittance, float).reshape(*hit.shape, 3)
    L_r = np.asarray(r.inscatter, float).reshape(*hit.shape, 3)
    surface = m_pt[..., [ix["surface.R"], ix["surface.G"], ix["surface.B"]]]
    S_raster = surface * T_r + L_r
    S_pt, S_ex = m_pt[..., rgb], m_ex[..., rgb]
    return {
        "raster_vs_pt": split_stats(S_raster - S_pt, var_pt),
        "pt_vs_exact": split_stats(S_pt - S_ex, var_pt + var_ex),
        "raster_vs_exact": split_stats(S_raster - S_ex, var_ex),
        "images": {"raster": S_raster, "pt": S_pt, "exact": S_ex},
        "notes": [
            "the raster image's noise through the rendered surface is neglected",
            "colours of the raster fog are ue's (FogInscatteringColor, DirectionalInscatteringColor)",
        ],
    }


# -- the study's section --------------------------------------------------------------
#: The markers of :func:`split_study`'s section in ``budget.md`` (replaced when run again).
def _grounded(views: Views, ground: float | None) -> Views:
    """``views`` with every downward ray stopped at the plane ``y = ground`` [m] (None: no ground)."""
    if ground is None:
        return views
    dy = views.d[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        t_g = np.where(dy < 0, (float(ground) - views.camera[1]) / dy, np.inf)
    return Views(views.camera, views.d, np.minimum(views.D, np.where(t_g > 0, t_g, np.inf)))


def run_sweep(toml_path: str | Path, out: str | Path | None = None) -> list[dict]:
    """Run the closed-form sweep of ``toml_path`` (``reports/sweeps/ue_pathtracer/SWEEP.toml``)
    and write its table (``results.csv`` and ``results.md`` beside it, or in ``out``)."""
    import csv
    import itertools

    import tomllib

    toml_path = Path(toml_path)
    spec = tomllib.loads(toml_path.read_text())
    fixed = dict(spec.get("fixed", {}))
    thr = float(spec.get("sweep", {}).get("threshold", 0.01))
    camera = tuple(fixed.pop("camera", (0.0, 2.0, 0.0)))
    sun = spec.get("sun", {}).get("direction")
    sun = None if sun is None else tuple(np.asarray(sun, float) / np.linalg.norm(sun))
    v = spec.get("views", {})
    names = list(spec["parameters"])
    grids = [spec["parameters"][n]["values"] for n in names]
    dist = np.geomspace(*v.get("distances", [10, 2e4, 12]))
    views = _grounded(sample_views(camera, n_dirs=int(v.get("n_dirs", 400)), distances=dist), v.get("ground"))
    sv = _grounded(
        sample_views(
            camera,
            n_dirs=int(v.get("ss_n_dirs", 64)),
            distances=np.geomspace(*v.get("ss_distances", [30, 1e4, 6])),
        ),
        v.get("ground"),
    )
    rows = []
    for combo in itertools.product(*grids):
        kw = {**fixed, **dict(zip(names, combo))}
        ue, pt = settings_from(**kw)
        row = dict(zip(names, combo))
        row.update(departure_row(closed_form_split(ue, pt, camera, views, sun, sv), thr))
        row["departs"] = bool(row["opacity_rel_max"] > thr or row.get("sun_ss_rel_max", 0.0) > thr)
        rows.append(row)
    out = Path(out) if out else toml_path.parent
    out.mkdir(parents=True, exist_ok=True)
    keys = list(rows[0])
    with open(out / "results.csv", "w", newline="") as f:
        wr = csv.DictWriter(f, keys)
        wr.writeheader()
        wr.writerows(rows)
    fmt = lambda x: "" if x is None else f"{x:.3g}" if isinstance(x, float) else str(x)  # noqa: E731
    lines = ["| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    lines += ["| " + " | ".join(fmt(r[k]) for k in keys) + " |" for r in rows]
    (out / "results.md").write_text("\n".join(lines) + "\n")
    return rows


if __name__ == "__main__":
    import sys

    run_sweep(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else None)
