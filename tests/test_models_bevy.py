"""Bevy DistanceFog: fog.wgsl + apply_fog transcription, the mapping, extremes."""

import math

import numpy as np
import pytest

from fogref.errors import ParameterError
from fogref.mapping import PhysicalScene, from_physical, lobe_fit
from fogref.mapping.engines import bevy_sigma, bevy_to_medium
from fogref.media import NP, ExpLayer, FogMedium
from fogref.models import get
from fogref.models.bevy import BevyDistanceFog, BevyFogParams

f32 = np.float32


def bevy_fog(o, cam, wp, frag):
    """bevyengine/bevy crates/bevy_pbr/src/render/pbr_functions.wgsl apply_fog + fog.wgsl, f32, one pixel."""
    view_to_world = (np.asarray(wp) - np.asarray(cam)).astype(f32)
    distance = np.sqrt(np.sum(view_to_world * view_to_world))
    scattering = np.zeros(3, f32)
    dlc = np.asarray(o["directional_light_color"], f32)
    if dlc[3] > 0:
        n = view_to_world / distance
        l = np.asarray(o["direction_to_light"], f32)
        scattering = scattering + np.power(
            max(f32(n[0] * l[0] + n[1] * l[1] + n[2] * l[2]), f32(0.0)), f32(o["exponent"])
        ) * np.asarray(o["light_color"], f32)
    base = np.asarray(o["color"], f32)
    fog_color = base.copy()
    if dlc[3] > 0:  # scattering_adjusted_fog_color
        fog_color[:3] = base[:3] + scattering * dlc[:3] * dlc[3]
    frag = np.asarray(frag, f32)
    mode = o["mode"]
    if mode == "Atmospheric":
        extinction_factor = f32(1.0) - f32(1.0) / np.exp(distance * np.asarray(o["be"], f32))
        inscattering_factor = f32(1.0) - f32(1.0) / np.exp(distance * np.asarray(o["bi"], f32))
        return (
            frag * (f32(1.0) - extinction_factor * fog_color[3])
            + fog_color[:3] * inscattering_factor * fog_color[3]
        )
    be_x = f32(o["be"][0])
    if mode == "Linear":
        start, end = f32(o["be"][0]), f32(o["be"][1])
        fog_color[3] *= f32(1.0) - min(max((end - distance) / (end - start), f32(0.0)), f32(1.0))
    elif mode == "Exponential":
        fog_color[3] *= f32(1.0) - f32(1.0) / np.exp(distance * be_x)
    else:
        distance_times_density = distance * be_x
        fog_color[3] *= f32(1.0) - f32(1.0) / np.exp(distance_times_density * distance_times_density)
    return frag + (fog_color[:3] - frag) * fog_color[3]  # mix(input, fog, a)


@pytest.mark.parametrize("mode", ["Linear", "Exponential", "ExponentialSquared", "Atmospheric"])
def test_float32_matches_fog_wgsl(mode):
    rng = np.random.default_rng(1)
    l = np.array([0.3, 0.6, -0.5])
    l /= np.linalg.norm(l)
    p = BevyFogParams(
        falloff=mode,
        start=4.0,
        end=250.0,
        density=0.011,
        extinction=(0.01, 0.02, 0.04),
        inscattering=(0.005, 0.01, 0.02),
        color=(0.3, 0.4, 0.5, 0.9),
        directional_light_color=(1.0, 0.9, 0.7, 0.5),
        directional_light_exponent=12.0,
        light_direction=tuple(l),
        light_color=(2.0, 1.9, 1.7),
    )
    be = {
        "Linear": (4.0, 250.0, 0.0),
        "Exponential": (0.011, 0, 0),
        "ExponentialSquared": (0.011, 0, 0),
        "Atmospheric": (0.01, 0.02, 0.04),
    }[mode]
    o = dict(
        mode=mode,
        be=be,
        bi=(0.005, 0.01, 0.02),
        color=(0.3, 0.4, 0.5, 0.9),
        directional_light_color=(1.0, 0.9, 0.7, 0.5),
        exponent=12.0,
        direction_to_light=l,
        light_color=(2.0, 1.9, 1.7),
    )
    cam = np.array([0.0, 5.0, 0.0])
    wp = cam + rng.normal(size=(300, 3)) * 10 ** rng.uniform(-1, 3, (300, 1))
    scene = rng.uniform(0, 2, (300, 3))
    out = BevyDistanceFog(p).evaluate(cam, wp, "float32").composite(scene.astype(f32))
    assert out.dtype == np.float32
    for i in range(300):
        with np.errstate(over="ignore"):  # exp overflows to inf, 1/inf = 0, as on a GPU
            ref = bevy_fog(o, cam, wp[i], scene[i])
        np.testing.assert_allclose(out[i], ref, rtol=3e-6, atol=3e-6)


def test_exponential_and_atmospheric_are_homogeneous_media():
    rng = np.random.default_rng(2)
    cam = np.array([0.0, 1.0, 0.0])
    d = rng.normal(size=(200, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    L = 10 ** rng.uniform(-3, 3.5, 200)
    o, dd = tuple(np.full(200, c) for c in cam), tuple(d.T)
    for p in (
        BevyFogParams(falloff="Exponential", density=0.013),
        BevyFogParams(falloff="Atmospheric", extinction=(0.01, 0.02, 0.03), inscattering=(0.01, 0.02, 0.03)),
    ):
        m = bevy_to_medium(p)
        T = BevyDistanceFog(p).evaluate(cam, cam + d * L[:, None], "float64").transmittance
        np.testing.assert_allclose(T, np.stack(m.transmittance(NP, o, dd, L), -1), rtol=1e-12, atol=1e-300)
    assert bevy_sigma(BevyFogParams(falloff="ExponentialSquared", density=0.05)) == pytest.approx((0.05,) * 3)


def test_mapping_exact_for_coloured_homogeneous_fog_and_lobe():
    sun = np.array([0.3, 0.5, 0.8])
    sun /= np.linalg.norm(sun)
    med = FogMedium(sigma_t=(0.002, 0.003, 0.005), albedo=0.8, g=0.6, layers=(ExpLayer(1.0, 0.0, 0.0),))
    ps = PhysicalScene(
        med,
        sun_direction=tuple(sun),
        sun_irradiance=(3.0, 2.8, 2.5),
        sky_radiance=(0.2, 0.3, 0.5),
        camera=(0.0, 2.0, 0.0),
    )
    fog = from_physical("bevy", ps)
    q = fog.params
    assert q.falloff == "Atmospheric" and q.extinction == pytest.approx((0.002, 0.003, 0.005))
    assert q.inscattering == q.extinction and q.color == pytest.approx((0.16, 0.24, 0.4, 1.0))
    lobe = lobe_fit(0.6, isotropic=False)
    assert q.directional_light_exponent == pytest.approx(lobe["exponent"])
    assert q.light_color == pytest.approx((3.0, 2.8, 2.5))
    rng = np.random.default_rng(3)
    cam = np.array([0.0, 2.0, 0.0])
    d = rng.normal(size=(200, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    L = np.concatenate([10 ** rng.uniform(-2, 4, 199), [1e5]])  # a mesh 100 km away
    T = fog.evaluate(cam, cam + d * L[:, None], "float64", hit=np.ones(200, bool)).transmittance
    ref = np.stack(med.transmittance(NP, tuple(np.full(200, c) for c in cam), tuple(d.T), L), -1)
    np.testing.assert_allclose(T, ref, rtol=1e-12, atol=1e-300)
    # no sun: no lobe
    assert from_physical("bevy", PhysicalScene(med)).params.directional_light_color[3] == 0.0


def test_mapping_height_profile_uses_camera_density():
    med = FogMedium(sigma_t=0.01, layers=(ExpLayer(1.0, 0.1, 0.0),))
    fog = from_physical("bevy", PhysicalScene(med, camera=(0.0, 10.0, 0.0)))
    assert fog.params.extinction[0] == pytest.approx(0.01 * math.exp(-1.0))


def test_registered_and_bad_input():
    assert get("bevy") is BevyDistanceFog
    with pytest.raises(ParameterError, match="end"):
        BevyFogParams(falloff="Linear", start=5.0, end=5.0)
    with pytest.raises(ParameterError, match="color"):
        BevyFogParams(color=(1.0, 1.0, 1.0, 2.0))


def test_extremes_are_finite():
    rng = np.random.default_rng(5)
    wp = rng.normal(size=(200, 3)) * 10 ** rng.uniform(-4, 9, (200, 1))
    wp = np.vstack([wp, np.zeros(3)])
    lobe = dict(directional_light_color=(1, 1, 1, 1), directional_light_exponent=1e3)
    for p in (
        BevyFogParams(falloff="Exponential", density=1e3, **lobe),
        BevyFogParams(falloff="ExponentialSquared", density=1e2, **lobe),
        BevyFogParams(falloff="Atmospheric", extinction=1e3, inscattering=1e-9, **lobe),
        BevyFogParams(falloff="Linear", start=-1e6, end=1e7, **lobe),
        BevyFogParams(
            falloff="Linear",
            start=0.0,
            end=1e-6,
            directional_light_color=(1, 1, 1, 1),
            directional_light_exponent=0.0,
        ),
    ):
        for prec in ("float32", "float64"):
            r = BevyDistanceFog(p).evaluate(np.zeros(3), wp, prec)
            assert np.all(np.isfinite(r.transmittance)) and np.all(np.isfinite(r.inscatter))
            assert np.all((r.transmittance >= 0) & (r.transmittance <= 1)) and np.all(r.inscatter >= 0)


@pytest.mark.parametrize("mode", ["Linear", "Exponential", "ExponentialSquared", "Atmospheric"])
def test_skybox_is_not_fogged(mode):
    """bevy_core_pipeline skybox.wgsl returns the cube map's sample: no fog on the background,
    whether the truth's hit mask says so or (without it) the point lies at SKY_DISTANCE."""
    from fogref.models import SKY_DISTANCE

    p = BevyFogParams(
        falloff=mode,
        density=0.01,
        extinction=(0.01, 0.02, 0.03),
        inscattering=(0.01, 0.02, 0.03),
        directional_light_color=(1.0, 0.9, 0.8, 1.0),
        light_direction=(1.0, 0.0, 4.0),
    )
    d = np.array([[1.0, 0.0, 4.0], [0.0, 1.0, 0.0]]) / np.array([[math.sqrt(17.0)], [1.0]])
    cam = np.array([0.0, 2.0, 0.0])
    wp = cam + d * SKY_DISTANCE
    for kw in ({"hit": np.array([False, False])}, {}):
        for prec in ("float32", "float64"):
            r = BevyDistanceFog(p).evaluate(cam, wp, prec, **kw)
            assert np.all(r.transmittance == 1.0) and np.all(r.inscatter == 0.0)
    # the same points as meshes are fogged (saturated at 100 km)
    r = BevyDistanceFog(p).evaluate(cam, wp, "float64", hit=np.array([True, True]))
    assert np.all(r.transmittance < 1e-6) and np.all(r.inscatter > 0.1)
