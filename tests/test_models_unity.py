"""Unity built-in fog: UnityCG.cginc transcription and the homogeneous medium."""

import math

import numpy as np
import pytest

from fogref.mapping import PhysicalScene
from fogref.mapping.engines import unity_from_physical, unity_to_medium
from fogref.media import NP
from fogref.models.unity_builtin import UnityBuiltinFog, UnityFogParams

f32 = np.float32


def unitycg_fog(mode, density, start, end, color, coord, scene):
    """Transcription of Unity's built-in fog (float32): unity_FogParams + UNITY_CALC_FOG_FACTOR_RAW +
    lerp(unity_FogColor, color, saturate(unityFogFactor))."""
    x = f32(density) / f32(math.sqrt(math.log(2)))
    y = f32(density) / f32(math.log(2))
    z = f32(-1) / (f32(end) - f32(start))
    w = f32(end) / (f32(end) - f32(start))
    c = f32(coord)
    if mode == "linear":
        unityFogFactor = c * z + w
    elif mode == "exp":
        unityFogFactor = np.exp2(-(y * c))
    else:
        unityFogFactor = x * c
        unityFogFactor = np.exp2(-unityFogFactor * unityFogFactor)
    t = np.clip(unityFogFactor, 0, 1)
    fog = np.asarray(color, f32)
    return fog + (np.asarray(scene, f32) - fog) * t


@pytest.mark.parametrize("mode", ["linear", "exp", "exp2"])
@pytest.mark.parametrize("coordinate", ["distance", "depth"])
def test_float32_matches_unitycg(mode, coordinate):
    rng = np.random.default_rng(1)
    fwd = np.array([0.3, -0.1, -1.0])
    fwd /= np.linalg.norm(fwd)
    p = UnityFogParams(
        fogMode=mode,
        fogDensity=0.02,
        fogStartDistance=5.0,
        fogEndDistance=120.0,
        fogColor=(0.3, 0.4, 0.5),
        fog_coordinate=coordinate,
        camera_forward=tuple(fwd),
    )
    cam = np.array([1.0, 2.0, 3.0])
    wp = cam + rng.normal(size=(200, 3)) * 10 ** rng.uniform(-2, 3, (200, 1))
    scene = rng.uniform(0, 2, size=(200, 3))
    out = UnityBuiltinFog(p).evaluate(cam, wp, "float32").composite(scene.astype(f32))
    for i in range(200):
        v = (wp[i] - cam).astype(f32)
        coord = np.sqrt(np.sum(v * v)) if coordinate == "distance" else f32(np.dot(v, fwd.astype(f32)))
        ref = unitycg_fog(mode, 0.02, 5.0, 120.0, (0.3, 0.4, 0.5), coord, scene[i])
        np.testing.assert_allclose(out[i], ref, rtol=1e-5, atol=2e-6)


def test_exp_on_distance_is_the_homogeneous_medium():
    p = UnityFogParams(fogMode="exp", fogDensity=0.013, fog_coordinate="distance")
    m = unity_to_medium(p)
    assert m.sigma_t[0] == pytest.approx(0.013)
    rng = np.random.default_rng(2)
    cam = np.array([0.0, 1.0, 0.0])
    d = rng.normal(size=(100, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    L = 10 ** rng.uniform(-3, 3, 100)
    T = UnityBuiltinFog(p).evaluate(cam, cam + d * L[:, None], "float64").transmittance[:, 0]
    np.testing.assert_allclose(T, m.transmittance(NP, tuple(cam), tuple(d.T), L)[0], rtol=1e-12)
    assert unity_from_physical(PhysicalScene(m)).params.fogDensity == pytest.approx(0.013)


def test_nearest_fits_match_at_the_reference_distance():
    for p, r in (
        (
            UnityFogParams(
                fogMode="linear", fogStartDistance=10, fogEndDistance=90, fog_coordinate="distance"
            ),
            50.0,
        ),
        (UnityFogParams(fogMode="exp2", fogDensity=0.03, fog_coordinate="distance"), 1 / 0.03),
    ):
        sigma = unity_to_medium(p).sigma_t[0]
        T = UnityBuiltinFog(p).evaluate(np.zeros(3), np.array([[r, 0, 0]]), "float64").transmittance[0, 0]
        assert math.exp(-sigma * r) == pytest.approx(T, rel=1e-9)


def test_depth_differs_from_distance_and_clip_remap():
    fwd = (0.0, 0.0, -1.0)
    wp = np.array([[30.0, 0.0, -40.0]])
    c_depth = UnityBuiltinFog(UnityFogParams(camera_forward=fwd)).fog_coordinate(np.zeros(3), wp)
    assert c_depth[0] == pytest.approx(40.0)
    p = UnityFogParams(camera_forward=fwd, clip_near=0.3, clip_far=1000.0)
    c = UnityBuiltinFog(p).fog_coordinate(np.zeros(3), wp)
    assert c[0] == pytest.approx(1000.0 * (40.0 - 0.3) / (1000.0 - 0.3))


def test_extremes_are_finite():
    rng = np.random.default_rng(4)
    wp = rng.normal(size=(100, 3)) * 10 ** rng.uniform(-4, 7, (100, 1))
    wp = np.vstack([wp, np.zeros(3)])
    for mode in ("linear", "exp", "exp2"):
        for prec in ("float32", "float64"):
            r = UnityBuiltinFog(UnityFogParams(fogMode=mode, fogDensity=1.0)).evaluate(np.zeros(3), wp, prec)
            assert np.all(np.isfinite(r.transmittance)) and np.all(np.isfinite(r.inscatter))
