"""Godot 4 environment fog: fog_process / sky.glsl transcription, the mapping, extremes."""

import math

import numpy as np
import pytest

from fogref.errors import ParameterError
from fogref.mapping import PhysicalScene, from_physical
from fogref.mapping.engines import fixed_lobe_amplitude, godot_to_medium
from fogref.media import NP, ExpLayer, FogMedium
from fogref.models import SKY_DISTANCE, get
from fogref.models.godot import GodotFog, GodotFogParams

f32 = np.float32


def fog_process(u, cam, wp, frag, sky=False):
    """godotengine/godot scene_forward_clustered.glsl (000ae031) fog_process, packHalf2x16 of
    fog.rg and fog.ba, then mix(frag, fog.rgb, fog.a); sky.glsl (0095d7d0) for sky pixels; the CPU
    side of render_scene_data_rd.cpp; float32, one pixel."""
    vertex = (np.asarray(wp) - np.asarray(cam)).astype(f32)  # view space: same length, same dots
    length = np.sqrt(np.sum(vertex * vertex))
    fog_light_color = np.asarray(u["fog_light_color"], f32) * f32(u["fog_light_energy"])
    frag = np.asarray(frag, f32)
    sun = np.asarray(u["sun_direction"], f32)

    def sun_scatter(fog_color, scale=1.0):
        if u["fog_sun_scatter"] > 0.001:
            view = vertex / length
            cos = f32(view[0] * sun[0] + view[1] * sun[1] + view[2] * sun[2])
            light_amount = np.power(max(cos, f32(0.0)), f32(8.0)) * f32(scale)
            fog_color = fog_color + np.asarray(u["sun_color"], f32) * light_amount * f32(u["fog_sun_scatter"])
        return fog_color

    if sky:  # sky.glsl: M_PI = 3.14159265359 on the sun scatter
        fog_color = fog_light_color + (frag - fog_light_color) * f32(u["fog_aerial_perspective"])
        fog_color = sun_scatter(fog_color, f32(3.14159265359))
        a = f32(1.0) * f32(u["fog_sky_affect"])
        return frag + (fog_color - frag) * a
    fog_color = fog_light_color
    if u["fog_aerial_perspective"] > 0:
        sky_fog_color = np.asarray(u["sky_color"], f32)
        fog_color = fog_color + (sky_fog_color - fog_color) * f32(u["fog_aerial_perspective"])
    fog_color = sun_scatter(fog_color)
    if u["mode"] == "depth":
        end = f32(u["fog_depth_end"]) if u["fog_depth_end"] > 0 else f32(u["z_far"])
        begin = min(f32(u["fog_depth_begin"]), f32(end - f32(0.001)))
        t = min(max((length - begin) / (end - begin), f32(0.0)), f32(1.0))
        fog_z = t * t * (f32(3.0) - f32(2.0) * t)
        fog_amount = np.power(fog_z, f32(u["fog_depth_curve"])) * f32(u["fog_density"])
    else:
        fog_amount = f32(1.0) - np.exp(min(f32(0.0), -length * f32(u["fog_density"])))
    if abs(f32(u["fog_height_density"])) >= f32(0.0001):
        y = f32(cam[1]) + vertex[1]  # (inv_view_matrix * vertex).y
        y_dist = y - f32(u["fog_height"])
        vfog_amount = f32(1.0) - np.exp(min(f32(0.0), y_dist * f32(u["fog_height_density"])))
        fog_amount = max(vfog_amount, fog_amount)
    fog_color = np.float16(fog_color).astype(f32)  # packHalf2x16 / unpackHalf2x16
    fog_amount = f32(np.float16(fog_amount))
    return frag + (fog_color - frag) * fog_amount


U = dict(
    fog_light_color=(0.3, 0.35, 0.45),
    fog_light_energy=1.3,
    fog_sun_scatter=0.4,
    fog_density=0.004,
    fog_aerial_perspective=0.25,
    fog_sky_affect=0.7,
    fog_height=12.0,
    fog_height_density=0.05,
    fog_depth_curve=1.7,
    fog_depth_begin=8.0,
    fog_depth_end=0.0,
    z_far=900.0,
    sky_color=(0.2, 0.3, 0.6),
    sun_color=(3.0, 2.7, 2.2),
    sky_distance=SKY_DISTANCE,
)


@pytest.mark.parametrize("mode", ["exponential", "depth"])
@pytest.mark.parametrize("height_density", [0.0, 0.05, -0.02])
def test_float32_matches_fog_process(mode, height_density):
    rng = np.random.default_rng(0)
    sun = np.array([0.4, 0.5, -0.7])
    sun /= np.linalg.norm(sun)
    u = dict(
        U,
        mode=mode,
        fog_height_density=height_density,
        sun_direction=sun,
        fog_density=0.4 if mode == "depth" else 0.004,
    )
    p = GodotFogParams(
        fog_mode=mode,
        **{k: v for k, v in u.items() if k not in ("mode", "sun_direction")},
        sun_direction=tuple(sun),
    )
    cam = np.array([0.0, 20.0, 0.0])
    d = rng.normal(size=(300, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    d[:20] = sun + rng.normal(size=(20, 3)) * 0.05  # near the sun: the lobe
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    L = 10 ** rng.uniform(-1, 3.5, (300, 1))
    L[-30:] = SKY_DISTANCE  # sky pixels
    wp = cam + d * L
    hit = np.arange(300) < 270
    scene = rng.uniform(0, 2, (300, 3))
    out = GodotFog(p).evaluate(cam, wp, "float32", hit=hit).composite(scene.astype(f32))
    assert out.dtype == np.float32
    for i in range(300):
        ref = fog_process(u, cam, wp[i], scene[i], sky=not hit[i])
        np.testing.assert_allclose(out[i], ref, rtol=3e-6, atol=3e-6)


def test_exponential_is_homogeneous_medium_and_height_fog_is_not():
    p = GodotFogParams(fog_density=0.012, fog_sky_affect=1.0)
    m = godot_to_medium(p)
    rng = np.random.default_rng(1)
    cam = np.array([0.0, 3.0, 0.0])
    d = rng.normal(size=(200, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    L = 10 ** rng.uniform(-3, 3.5, 200)
    T = GodotFog(p).evaluate(cam, cam + d * L[:, None], "float64").transmittance[:, 0]
    np.testing.assert_allclose(
        T, m.transmittance(NP, tuple(np.full(200, c) for c in cam), tuple(d.T), L)[0], rtol=1e-9, atol=1e-14
    )
    with pytest.raises(ParameterError, match="fog_height_density"):
        godot_to_medium(GodotFogParams(fog_height_density=0.1))
    with pytest.raises(ParameterError, match="fog_mode"):
        godot_to_medium(GodotFogParams(fog_mode="depth"))
    # height fog: a function of the end point only, max-combined (not an optical depth)
    h = GodotFog(GodotFogParams(fog_density=0.0, fog_height=10.0, fog_height_density=0.1))
    pts = np.array([[1.0, 0.0, 0.0], [1000.0, 0.0, 0.0]])
    T2 = h.evaluate(np.zeros(3), pts, "float64").transmittance[:, 0]
    assert T2 == pytest.approx([math.exp(-1.0), math.exp(-1.0)])


def test_depth_mode_end_defaults_to_z_far():
    p = GodotFogParams(
        fog_mode="depth", fog_density=1.0, fog_depth_begin=10.0, fog_depth_end=0.0, z_far=110.0
    )
    T = (
        GodotFog(p)
        .evaluate(np.zeros(3), np.array([[5.0, 0, 0], [60.0, 0, 0], [200.0, 0, 0]]), "float64")
        .transmittance[:, 0]
    )
    assert T == pytest.approx([1.0, 0.5, 0.0], abs=1e-4)


def test_mapping_homogeneous_exact_including_sky_and_sun_lobe():
    sun = np.array([0.4, 0.139, 0.906])
    sun /= np.linalg.norm(sun)
    med = FogMedium(sigma_t=0.002, albedo=0.8, g=0.3, layers=(ExpLayer(1.0, 0.0, 0.0),))
    ps = PhysicalScene(
        med,
        sun_direction=tuple(sun),
        sun_irradiance=(3.2, 2.9, 2.4),
        sky_radiance=(0.2, 0.3, 0.5),
        camera=(0.0, 2.0, 0.0),
    )
    fog = from_physical("godot", ps)
    q = fog.params
    assert q.fog_density == pytest.approx(0.002) and q.fog_height_density == 0.0
    assert q.fog_light_color == pytest.approx((0.16, 0.24, 0.4))
    c = fixed_lobe_amplitude(0.3, 8.0)
    assert q.fog_sun_scatter == 1.0
    # an unbounded homogeneous fog extinguishes the sun: T_sun(camera) = 0
    expected = 0.8 * np.array([3.2, 2.9, 2.4]) * ps.sun_transmittance_at_camera() * c
    assert q.sun_color == pytest.approx(tuple(expected))
    valley_fog = FogMedium(sigma_t=0.001, albedo=0.9, g=0.6, layers=(ExpLayer(1.0, 0.0138629, 0.0),))
    valley = PhysicalScene(
        valley_fog, sun_direction=tuple(sun), sun_irradiance=(3.2, 2.9, 2.4), camera=(0.0, 2.0, 0.0)
    )
    qv = from_physical("godot", valley).params
    t_sun = valley.sun_transmittance_at_camera()
    assert 0 < t_sun[0] < 1
    expected = 0.9 * np.array([3.2, 2.9, 2.4]) * t_sun * fixed_lobe_amplitude(0.6, 8.0)
    assert qv.sun_color == pytest.approx(tuple(expected))
    assert qv.fog_density == pytest.approx(0.001 * math.exp(-0.0138629 * 2.0))  # density at the camera
    rng = np.random.default_rng(2)
    cam = np.array([0.0, 2.0, 0.0])
    d = rng.normal(size=(300, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    L = np.concatenate([10 ** rng.uniform(-2, 4, 250), np.full(50, SKY_DISTANCE)])
    T = fog.evaluate(cam, cam + d * L[:, None], "float64").transmittance
    ref = np.stack(med.transmittance(NP, tuple(np.full(300, x) for x in cam), tuple(d.T), L), -1)
    np.testing.assert_allclose(T, ref, rtol=1e-9, atol=1e-14)


def test_fixed_lobe_amplitude_is_least_squares():
    g, n = 0.6, 8.0
    mu = np.linspace(-1, 1, 200001)
    p = (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * mu) ** 1.5)
    lobe = np.maximum(mu, 0) ** n
    c = np.sum(p * lobe) / np.sum(lobe * lobe)
    assert fixed_lobe_amplitude(g, n) == pytest.approx(c, rel=1e-4)


def test_mapping_refuses_box_and_colour():
    from fogref.media import Box

    box = FogMedium(sigma_t=0.01, layers=(ExpLayer(1.0, 0.0, 0.0),), bounds=Box((0, 0, 0), (1, 1, 1)))
    with pytest.raises(ParameterError, match="profile"):
        from_physical("godot", PhysicalScene(box))
    with pytest.raises(ParameterError, match="sigma_t"):
        from_physical("godot", PhysicalScene(FogMedium(sigma_t=(0.01, 0.02, 0.03))))


def test_registered_and_bad_input():
    assert get("godot") is GodotFog
    for kw, name in (
        (dict(fog_sky_affect=1.5), "fog_sky_affect"),
        (dict(fog_density=-1.0), "fog_density"),
        (dict(fog_mode="linear"), "fog_mode"),
        (dict(sun_direction=(0, 0, 0)), "sun_direction"),
    ):
        with pytest.raises(ParameterError, match=name):
            GodotFogParams(**kw)


def test_extremes_are_finite():
    rng = np.random.default_rng(5)
    for cam_y in (-1e4, 0.0, 1e6):
        cam = np.array([0.0, cam_y, 0.0])
        wp = cam + rng.normal(size=(200, 3)) * 10 ** rng.uniform(-4, 9, (200, 1))
        wp = np.vstack([wp, cam])
        for p in (
            GodotFogParams(fog_density=1e3, fog_height_density=1e3, fog_sun_scatter=1e3, sun_color=1e3),
            GodotFogParams(fog_density=0.0, fog_height=-1e6, fog_height_density=-10.0),
            GodotFogParams(
                fog_mode="depth",
                fog_density=1.0,
                fog_depth_begin=0.0,
                fog_depth_end=1e-6,
                fog_depth_curve=0.0,
            ),
            GodotFogParams(
                fog_mode="depth",
                fog_density=1.0,
                fog_depth_begin=1e9,
                fog_depth_end=1.0,
                fog_depth_curve=50.0,
            ),
        ):
            for prec in ("float32", "float64"):
                r = GodotFog(p).evaluate(cam, wp, prec)
                assert np.all(np.isfinite(r.transmittance)) and np.all(np.isfinite(r.inscatter))
                assert np.all((r.transmittance >= 0) & (r.transmittance <= 1)) and np.all(r.inscatter >= 0)


def test_height_fog_needs_height_density_of_at_least_1e_4():
    """Godot skips height fog where |fog_height_density| < 0.0001 (fogref used to apply it)."""
    pt = np.array([[0.0, -100.0, 0.0]])
    for prec in ("float32", "float64"):
        weak = GodotFogParams(fog_density=0.0, fog_height=0.0, fog_height_density=5e-5)
        assert GodotFog(weak).evaluate(np.zeros(3), pt, prec).transmittance[0, 0] == 1.0
        strong = GodotFogParams(fog_density=0.0, fog_height=0.0, fog_height_density=-1e-4)  # fog above
        T = GodotFog(strong).evaluate(np.zeros(3), -pt, prec).transmittance[0, 0]
        assert T == pytest.approx(math.exp(-0.01), abs=3e-4)  # 3e-4: the half float of fog.a


def test_sky_is_decided_by_the_hit_mask_not_a_float32_distance():
    """normalize(1, 0, 4) * 1e5 has a float32 length just under 1e5: still sky (T = 0 in depth
    mode with sky affect 1), with the truth's hit mask and without it."""
    d = np.array([1.0, 0.0, 4.0]) / math.sqrt(17.0)
    wp = (d * SKY_DISTANCE)[None]
    v = wp.astype(f32)
    assert np.sqrt(np.sum(v * v)) < f32(SKY_DISTANCE)  # the rounding that misled the old rule
    fog = GodotFog(GodotFogParams(fog_mode="depth", fog_density=0.5))
    for kw in ({"hit": np.array([False])}, {}):
        for prec in ("float32", "float64"):
            assert fog.evaluate(np.zeros(3), wp, prec, **kw).transmittance[0, 0] == 0.0
    # the same point is geometry when the truth says the pixel hit a surface
    T = fog.evaluate(np.zeros(3), wp, "float64", hit=np.array([True])).transmittance[0, 0]
    assert T == pytest.approx(0.5)
    with pytest.raises(ParameterError, match="hit"):
        fog.evaluate(np.zeros(3), wp, "float64", hit=np.array([1.0]))


def test_sky_sun_glow_is_pi_times_the_scene_glow():
    sun = (0.0, 0.6, 0.8)
    p = GodotFogParams(
        fog_density=0.01,
        fog_sun_scatter=0.5,
        sun_color=(2.0, 1.0, 0.5),
        sun_direction=sun,
        fog_light_color=(0.0, 0.0, 0.0),
    )
    wp = np.array([sun]) * SKY_DISTANCE
    r = GodotFog(p).evaluate(np.zeros(3), wp, "float64", hit=np.array([False]))
    np.testing.assert_allclose(r.inscatter[0], math.pi * 0.5 * np.array([2.0, 1.0, 0.5]), rtol=1e-12)


def test_half_float_storage_moves_transmittance_by_at_most_2p4e_4():
    rng = np.random.default_rng(7)
    d = rng.normal(size=(4000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    wp = d * 10 ** rng.uniform(-1, 3.5, (4000, 1))
    fog = GodotFog(GodotFogParams(fog_density=0.004, fog_height=5.0, fog_height_density=0.03))
    t32 = fog.evaluate(np.zeros(3), wp, "float32").transmittance[:, 0].astype(float)
    t64 = fog.evaluate(np.zeros(3), wp, "float64").transmittance[:, 0]
    err = np.abs(t32 - t64)
    assert err.max() <= 2.45e-4  # half of a half-float ulp at [0.5, 1): 2^-12
    assert err.max() > 1e-4  # the rounding is there (float32 alone stays below 1e-6)


def test_compare_passes_the_truths_hit_mask():
    """evaluate_model gives the model the truth's hit mask: sky pixels are the sky shader's even
    when fogged at a short sky distance (50 m) where no distance rule would call them sky."""
    from fogref.compare.candidate import evaluate_model
    from fogref.compare.synthetic import synthetic_truth

    fog = GodotFog(
        GodotFogParams(fog_mode="depth", fog_density=0.5, fog_depth_begin=10.0, fog_depth_end=20.0)
    )
    truth = synthetic_truth(fog, shape=(9, 16))
    parts = evaluate_model(truth, fog, "float64", sky_distance=50.0)
    sky, hit = ~truth.hit, truth.hit
    assert sky.any() and hit.any()
    assert np.all(parts["T"][sky] == 0.0)  # sky.glsl: 1 - fog_sky_affect
    geometry = fog.evaluate(truth.camera, truth.world_positions(50.0), "float64").transmittance
    assert np.all(geometry[sky] == 0.5)  # the same points as geometry: depth fog at 50 m
