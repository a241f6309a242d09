"""Unreal's path-traced fog (profile ``ue_pathtracer``): closed forms against quadrature.

The fog is ``sum_i sigma d_i min(exp(-b_i (y - h_i)), C)`` inside a vertical cylinder
centred on the camera (:mod:`fogref.media.ue_pathtracer`).  The reference here is
independent of the closed forms: the density written as that ``min`` (not as the
piecewise profile), the inside test written on the point, the ray split where it
crosses the clamp heights, the cylinder's wall (roots found by mpmath's bisection,
not by the quadratic formula) and its caps, and each piece integrated by mpmath's
Gauss-Legendre quadrature at 30 digits.  Tolerance 1e-5 relative on the optical depth
and on T (the brief's); float64 closed forms agree to ~1e-12, so any wrong piece (a
clamp height off by one metre, a wall root swapped) fails by orders of magnitude.
"""

from __future__ import annotations

import math

import mpmath as mp
import numpy as np
import pytest

from fogref.errors import ParameterError
from fogref.mapping.unreal_pathtracer import (
    DROPPED,
    UEPathTracerSettings,
    exact_medium,
    pathtracer_fog_params,
    pathtracer_layers,
    pathtracer_medium,
)
from fogref.media import NP, Cylinder, FogMedium, UEPathTracerLayer, medium_from_params
from fogref.models.ue4 import SecondFogData, UE4FogParams

mp.mp.dps = 30

CAM = (3.0, 2.0, -4.0)
# two layers, strong falloffs so both clamp heights lie inside the cylinder
LAYERS = (UEPathTracerLayer(1.0, 0.08, 5.0, 8.0), UEPathTracerLayer(0.4, 0.2, 12.0, 8.0))
CYL = Cylinder(CAM[0], CAM[2], 60.0, -55.0, 40.0)
SIGMA = 0.02


def _medium(layers=LAYERS, cyl=CYL, sigma=SIGMA):
    return FogMedium(sigma_t=sigma, albedo=0.8, g=0.3, layers=layers, bounds=cyl)


def _rho_ref(layers, cyl, p):
    x, y, z = p
    if (x - cyl.center_x) ** 2 + (z - cyl.center_z) ** 2 > mp.mpf(cyl.radius) ** 2:
        return mp.mpf(0)
    if not (cyl.y_min <= y <= cyl.y_max):
        return mp.mpf(0)
    return sum(
        mp.mpf(L.density) * min(mp.exp(-mp.mpf(L.falloff) * (y - L.height)), mp.mpf(L.clamp)) for L in layers
    )


def _wall_roots(cyl, o, d, t_end):
    """Parameters where the ray crosses the cylinder's wall, by bisection on a fine grid."""

    def f(t):
        dx, dz = o[0] + t * d[0] - cyl.center_x, o[2] + t * d[2] - cyl.center_z
        return dx**2 + dz**2 - mp.mpf(cyl.radius) ** 2

    grid = np.linspace(0.0, t_end, 4001)
    vals = [f(mp.mpf(t)) for t in grid]
    roots = []
    for a, b, fa, fb in zip(grid[:-1], grid[1:], vals[:-1], vals[1:]):
        if fa == 0:
            roots.append(mp.mpf(a))
        elif fa * fb < 0:
            roots.append(mp.findroot(f, (mp.mpf(a), mp.mpf(b)), solver="bisect"))
    return roots


def _tau_ref(layers, cyl, sigma, o, d, t_end):
    o = [mp.mpf(x) for x in o]
    d = [mp.mpf(x) for x in d]
    t_end = mp.mpf(t_end)
    cuts = {mp.mpf(0), t_end}
    cuts.update(r for r in _wall_roots(cyl, o, d, float(t_end)) if 0 < r < t_end)
    if d[1] != 0:
        heights = [cyl.y_min, cyl.y_max] + [L.clamp_height for L in layers]
        for h in heights:
            t = (mp.mpf(h) - o[1]) / d[1]
            if 0 < t < t_end:
                cuts.add(t)
    cuts = sorted(cuts)
    tau = mp.mpf(0)
    for a, b in zip(cuts[:-1], cuts[1:]):
        tau += mp.quad(
            lambda t: _rho_ref(layers, cyl, [o[i] + t * d[i] for i in range(3)]),
            [a, b],
            method="gauss-legendre",
        )
    return sigma * tau


def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


# rays: (origin, direction, end distance); every one crosses a clamp height or the wall
RAYS = [
    (CAM, _unit([1.0, -0.08, 0.3]), 200.0),  # down through both clamp heights, out of the wall
    (CAM, _unit([-0.3, -0.02, 1.0]), 80.0),  # nearly level, below both clamp heights, out of the wall
    (CAM, _unit([0.2, 0.5, -1.0]), 150.0),  # up through the clamp heights (one above CAM), the wall
    (CAM, _unit([0.0, 1.0, 0.0]), 100.0),  # straight up: the top cap
    (CAM, _unit([0.0, -1.0, 0.0]), 57.0),  # straight down, ends above the bottom cap
    (CAM, _unit([1.0, 0.0, 0.0]), 30.0),  # horizontal, ends inside
    ((-90.0, 10.0, -4.0), _unit([1.0, -0.05, 0.02]), 200.0),  # from outside: enters and leaves the wall
    ((40.0, -20.0, 30.0), _unit([-0.6, 0.3, -0.5]), 120.0),  # inside, below the clamp heights, rising out
]


@pytest.mark.parametrize("o,d,t_end", RAYS)
def test_optical_depth_and_T_match_quadrature(o, d, t_end):
    m = _medium()
    tau_ref = _tau_ref(LAYERS, CYL, SIGMA, o, d, t_end)
    tau = SIGMA * float(
        m.optical_depth(
            NP, tuple(np.array([x]) for x in o), tuple(np.array([x]) for x in d), np.array([t_end])
        )[0]
    )
    assert float(tau_ref) > 0.05, "the ray must see some fog for the check to mean something"
    assert tau == pytest.approx(float(tau_ref), rel=1e-5)
    T = float(m.transmittance(NP, o, d, t_end)[0])
    assert T == pytest.approx(float(mp.exp(-tau_ref)), rel=1e-5)


def test_ray_to_infinity_is_the_ray_to_the_cylinder_exit():
    m = _medium()
    o, d = CAM, _unit([1.0, -0.08, 0.3])
    t0, t1 = CYL.clip(NP, o, d)
    assert float(m.optical_depth(NP, o, d, NP.largest)) == pytest.approx(
        float(m.optical_depth(NP, o, d, float(t1))), rel=1e-12
    )
    assert float(t0) == 0.0


def test_clip_misses_and_vertical_rays():
    c = Cylinder(0.0, 0.0, 10.0, -5.0, 5.0)
    t0, t1 = c.clip(NP, (20.0, 0.0, 0.0), (0.0, 0.0, 1.0))  # parallel to the wall, outside
    assert float(t1) < float(t0)
    t0, t1 = c.clip(NP, (20.0, 0.0, 0.0), (0.0, 1.0, 0.0))  # vertical, outside the wall
    assert float(t1) < float(t0)
    t0, t1 = c.clip(NP, (0.0, 10.0, 0.0), (1.0, 0.0, 0.0))  # level, above the top cap
    assert float(t1) < float(t0)
    t0, t1 = c.clip(NP, (-20.0, 0.0, 0.0), (-1.0, 0.0, 0.0))  # pointing away
    assert float(t1) < float(t0)


def test_free_flight_inverts_the_optical_depth_per_layer():
    rng = np.random.default_rng(5)
    for L in LAYERS:
        m = _medium(layers=(L,))
        for o, d, _ in RAYS:
            for e in rng.exponential(size=5):
                t = float(m.sample_distance(NP, o, d, [np.float64(e)], SIGMA))
                total = SIGMA * float(m.optical_depth(NP, o, d, NP.largest))
                if e >= total:
                    assert t == NP.largest  # escapes through the cylinder
                else:
                    tau = SIGMA * float(m.optical_depth(NP, o, d, t))
                    assert tau == pytest.approx(e, rel=1e-9, abs=1e-12)


def test_density_is_clamped_and_zero_outside():
    m = _medium()
    L0, L1 = LAYERS
    y_low = min(L0.clamp_height, L1.clamp_height) - 5.0
    rho = float(m.density(NP, (CAM[0], y_low, CAM[2])))
    assert rho == pytest.approx(8.0 * (L0.density + L1.density), rel=1e-12)
    assert float(m.density(NP, (CAM[0] + 61.0, y_low, CAM[2]))) == 0.0
    assert float(m.density(NP, (CAM[0], 41.0, CAM[2]))) == 0.0


def test_params_parse_and_errors():
    p = {
        "profile": "ue_pathtracer",
        "sigma_t": 0.01,
        "falloff": 0.05,
        "center": [1, 2, 3],
        "radius": 30,
        "clamp": 16,
    }
    m = medium_from_params(p, "<t>")
    assert isinstance(m.bounds, Cylinder) and m.bounds.center_z == 3.0 and m.layers[0].clamp == 16.0
    with pytest.raises(ParameterError, match="'center'"):
        medium_from_params({k: v for k, v in p.items() if k != "center"}, "<t>")
    with pytest.raises(ParameterError, match="'clamp'"):
        medium_from_params({**p, "clamp": 300}, "<t>")
    with pytest.raises(ParameterError, match="'bounds_min'"):
        medium_from_params({**p, "bounds_min": [0, 0, 0], "bounds_max": [1, 1, 1]}, "<t>")
    with pytest.raises(ParameterError, match="'radius'"):
        medium_from_params({**p, "radius": -1}, "<t>")


def test_mapping_follows_prepare_fog_parameters():
    ue = UE4FogParams(
        FogDensity=0.05,
        FogHeightFalloff=0.0,
        FogHeight=250.0,
        SecondFogData=SecondFogData(FogDensity=0.02, FogHeightFalloff=0.5, FogHeightOffset=-300.0),
    )
    pt = UEPathTracerSettings(
        VolumetricFogExtinctionScale=2.0,
        VolumetricFogDistance=5000.0,
        VolumetricFogStartDistance=1000.0,
        VolumetricFogScatteringDistribution=1.5,
        FogDensityClamp=4.0,
    )
    (s0, b0, h0), (s1, b1, h1) = pathtracer_layers(ue, pt)
    assert s0 == pytest.approx(100 * 0.5 * 0.05 / 1000 * 2.0)  # per cm -> per m
    assert b0 == pytest.approx(100 * math.log(2) * 0.001 / 1000)  # falloff floor 0.001
    assert (h0, h1) == (2.5, -0.5)
    m = pathtracer_medium(ue, pt, (0.0, 1.0, 0.0))
    assert m.g == 0.99 and m.layers[0].clamp == 4.0 and m.bounds.radius == 60.0  # start + distance
    # [PT]: FogMinZ = min_i(H_i) - R, FogMaxZ = max_i(H_i + min(R, log2(D_i / 1e-6) / F_i)), in cm
    R = 6000.0
    D = [0.5 * 0.05 / 1000 * 2.0, 0.5 * 0.02 / 1000 * 2.0]
    F = [0.001 / 1000, 0.5 / 1000]
    H = [250.0, -50.0]
    zmax = max(h + min(R, math.log2(max(d, 1e-6) / 1e-6) / f) for d, f, h in zip(D, F, H))
    assert m.bounds.y_min == pytest.approx((min(H) - R) / 100.0, rel=1e-12)
    assert m.bounds.y_max == pytest.approx(zmax / 100.0, rel=1e-12)
    assert UEPathTracerSettings(FogDensityClamp=3.0, version=(5, 4)).density_clamp == 8.0
    assert {
        "FogInscatteringColor",
        "DirectionalInscatteringExponent",
        "StartDistance",
        "FogMaxOpacity",
        "FogCutoffDistance",
    } <= set(DROPPED)


def test_exact_medium_equals_pathtracer_fog_where_neither_clamp_nor_cylinder_acts():
    ue, pt = UE4FogParams(FogHeight=-10000.0), UEPathTracerSettings(VolumetricFogDistance=1e6)
    cam = (0.0, 2.0, 0.0)
    pt_m, ex = pathtracer_medium(ue, pt, cam), exact_medium(ue, pt)
    o, d = cam, _unit([1.0, 0.05, 0.0])  # rising, far above the clamp height, short of the wall
    a = float(pt_m.optical_depth(NP, o, d, 500.0))
    assert a == pytest.approx(float(ex.optical_depth(NP, o, d, 500.0)), rel=1e-9)


def test_heightfog_params_round_trip():
    p = pathtracer_fog_params(UE4FogParams(), UEPathTracerSettings(), (0.0, 2.0, 0.0))
    text = {k: (", ".join(str(x) for x in v) if isinstance(v, list) else v) for k, v in p.items()}
    m = medium_from_params(text, "<xml>")
    assert m.layers == medium_from_params(p, "<dict>").layers


@pytest.mark.render
def test_render_T_matches_closed_form(mitsuba, tmp_path):
    """``fogref render``'s path: the valley rewritten with UE's path-traced fog, rendered by
    fogpath on a tiny image; its T channel (closed form per sample, every sample through
    the pixel centre) against the float64 closed form on the rays it reports (view,
    distance).  The fog is set so that the camera (2 m) sits below the clamp height
    (5 m) and rays beyond 60 m leave through the wall.  Tolerance: float32 (Dr.Jit) vs
    float64, 1e-5 relative (measured: 3e-7)."""
    from fogref.mapping.unreal_pathtracer import rewrite_scene
    from fogref.render.load import load_scene

    mi = mitsuba
    ue = UE4FogParams(FogDensity=0.05, FogHeightFalloff=2.0, FogHeight=2000.0)
    pt = UEPathTracerSettings()
    dst = tmp_path / "ue_pt.xml"
    params = rewrite_scene("scenes/valley.xml", dst, ue, pt)
    scene, desc = load_scene(dst, {"res": 16, "resy": 9, "max_depth": 2})
    scene.integrator().pixel_exact = True  # every sample through the pixel centre
    assert desc["medium"]["profile"] == "ue_pathtracer"
    names = ["R", "G", "B"] + list(scene.integrator().aov_names())
    img = np.array(mi.render(scene, spp=2, seed=0))
    T = img[..., names.index("T.R")].ravel()
    view = np.stack([img[..., names.index(f"view.{c}")].ravel() for c in "XYZ"])
    hit = img[..., names.index("hit")].ravel() > 0.5
    D = np.where(hit, img[..., names.index("distance")].ravel().astype(float), NP.largest)
    cam = [float(x) for x in desc["camera"]["origin"]]
    m = pathtracer_medium(ue, pt, cam)
    assert m.layers[0].clamp_height == pytest.approx(20.0 - math.log(8.0) / m.layers[0].falloff)
    assert 2.0 < m.layers[0].clamp_height < 10.0 and params["radius"] == 60.0
    view = view / np.linalg.norm(view, axis=0)
    o = tuple(np.full(T.shape, c) for c in cam)
    T_ref = m.transmittance(NP, o, tuple(view), D)[0]
    assert T_ref.min() < 0.9 and (~hit).any(), "the image must see thick fog and the wall"
    T_exact = exact_medium(ue, pt).transmittance(NP, o, tuple(view), D)[0]
    assert np.abs(T_exact - T_ref).max() > 1e-2, "the clamp and the wall must show in this image"
    np.testing.assert_allclose(T, T_ref, rtol=1e-5, atol=1e-7)


@pytest.mark.render
def test_fogpath_matches_stock_volpath(mitsuba):
    """The whole medium, not only T: fogpath (closed-form free flight and shadow rays through the
    cylinder) against stock volpath's delta tracking on the plugin's majorant, same scene
    (tests/render_scenes.py), Welch's t-test per 4x4 block, family-wise alpha 1e-3.  The camera
    (4 m) sits below the clamp height (5 m), the wall is 40 m away.  Power, measured: the test
    tells a radius of 25 m from 40 m, not a clamp of 2 from 1.2 (1.5 % of the mean); the T
    channel (:func:`test_render_T_matches_closed_form`) checks the clamp and the wall exactly."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from render_scenes import STOCK_SEED0, base_scene, render_runs
    from stats import assert_agree

    mi = mitsuba
    fog = {
        "type": "heightfog",
        "profile": "ue_pathtracer",
        "sigma_t": 0.03,
        "albedo": 0.9,
        "g": 0.5,
        "falloff": 0.06,
        "height": 8.0,
        "clamp": 1.2,
        "radius": 40.0,
        "center": mi.ScalarPoint3f(0, 4, -20),
    }
    m = medium_from_params(
        {k: v for k, v in fog.items() if k not in ("type", "center")} | {"center": [0, 4, -20]}
    )
    assert 4.0 < m.layers[0].clamp_height < 6.0
    runs = []
    for integ in ("fogpath", "volpath"):
        d = base_scene(mi, {"type": integ, "max_depth": 8, "rr_depth": 100}, dict(fog))
        seed0 = 1000 if integ == "fogpath" else STOCK_SEED0  # the stock method's own seeds
        runs.append(render_runs(mi, mi.load_dict(d, parallel=False), 8, 32, seed0=seed0))
    assert np.isfinite(np.stack(runs[0])).all() and np.isfinite(np.stack(runs[1])).all()
    assert_agree(runs[0], runs[1], block=4, alpha=1e-3, what="fogpath vs volpath (ue_pathtracer)")
