"""Babylon.js fog: a float32 transcription of fogFragmentDeclaration.fx, the mapping, extremes.

The real engine is in tests/test_web_babylon.py."""

import math

import numpy as np
import pytest

from fogref.errors import ParameterError
from fogref.mapping import PhysicalScene, from_physical
from fogref.mapping.engines import babylon_to_medium
from fogref.media import NP, Box, ExpLayer, FogMedium
from fogref.models import SKY_DISTANCE, get
from fogref.models.babylon import BabylonFog, BabylonFogParams

f32 = np.float32


def calc_fog_factor(mode, start, end, density, view_pos):
    """fogFragmentDeclaration.fx + fogVertex.fx (vFogDistance = view * worldPos), float32, one pixel."""
    E = f32(2.71828)
    v = np.asarray(view_pos, f32)
    fogDistance = np.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])  # length(vFogDistance)
    fogCoeff = f32(1.0)
    with np.errstate(over="ignore"):  # pow(E, huge) = inf, 1/inf = 0 as on the GPU
        if mode == "LINEAR":
            fogCoeff = (f32(end) - fogDistance) / (f32(end) - f32(start))
        elif mode == "EXP":
            fogCoeff = f32(1.0) / np.power(E, fogDistance * f32(density))
        elif mode == "EXP2":
            fogCoeff = f32(1.0) / np.power(E, fogDistance * fogDistance * f32(density) * f32(density))
    return min(max(fogCoeff, f32(0.0)), f32(1.0))


@pytest.mark.parametrize("mode", ["LINEAR", "EXP", "EXP2"])
def test_float32_matches_fog_fragment(mode):
    rng = np.random.default_rng(1)
    p = BabylonFogParams(fogMode=mode, fogDensity=0.03, fogStart=4.0, fogEnd=90.0, fogColor=(0.3, 0.5, 0.7))
    cam = np.array([1.0, -2.0, 3.0])
    wp = cam + rng.normal(size=(300, 3)) * 10 ** rng.uniform(-2, 2.5, (300, 1))
    scene = rng.uniform(0, 1, (300, 3)).astype(f32)
    out = BabylonFog(p).evaluate(cam, wp, "float32").composite(scene)
    assert out.dtype == np.float32
    for i in range(300):
        fog = calc_fog_factor(mode, 4.0, 90.0, 0.03, wp[i] - cam)
        ref = np.asarray((0.3, 0.5, 0.7), f32) * (f32(1) - fog) + scene[i] * fog  # mix(vFogColor, color, fog)
        np.testing.assert_allclose(out[i], ref, rtol=0, atol=3e-7)


def test_linear_is_clamped_and_reversible():
    fog = BabylonFog(BabylonFogParams(fogMode="LINEAR", fogStart=10.0, fogEnd=20.0))
    T = fog.evaluate(np.zeros(3), [[0.0, 0.0, -5.0], [0.0, 0.0, -15.0], [0.0, 0.0, -30.0]], "float64")
    assert T.transmittance[:, 0].tolist() == [1.0, 0.5, 0.0]
    rev = BabylonFog(BabylonFogParams(fogMode="LINEAR", fogStart=20.0, fogEnd=10.0))  # allowed, reversed
    T = rev.evaluate(np.zeros(3), [[0.0, 0.0, -12.0], [0.0, 0.0, -25.0]], "float64").transmittance[:, 0]
    assert T.tolist() == pytest.approx([0.2, 1.0])  # (end - d)/(end - start), clamped


def test_background_gets_no_fog():
    fog = BabylonFog(BabylonFogParams(fogMode="EXP", fogDensity=1.0))
    r = fog.evaluate(np.zeros(3), np.array([[0.0, 0.6, -0.8]]) * SKY_DISTANCE, "float32")
    assert np.all(r.transmittance == 1.0) and np.all(r.inscatter == 0.0)


def test_exp_mapping_is_exact_for_homogeneous_fog():
    m = FogMedium(sigma_t=0.02, albedo=0.5, layers=(ExpLayer(1.0, 0.0, 0.0),))
    fog = from_physical("babylon", PhysicalScene(m, sky_radiance=(0.2, 0.4, 0.6), camera=(0.0, 0.0, 0.0)))
    assert fog.params.fogColor == pytest.approx((0.1, 0.2, 0.3))
    d = np.array([1.0, 30.0, 200.0])
    wp = np.stack([d * 0.6, d * 0.0, -d * 0.8], -1)
    T = fog.evaluate(np.zeros(3), wp, "float64").transmittance[:, 0]
    ref = m.transmittance(NP, (0.0, 0.0, 0.0), (0.6, 0.0, -0.8), d)
    np.testing.assert_allclose(T, ref[0], rtol=1e-12)
    assert babylon_to_medium(fog.params).sigma_t[0] == pytest.approx(0.02, rel=1e-12)
    with pytest.raises(ParameterError, match="fogMode"):
        babylon_to_medium(BabylonFogParams(fogMode="EXP2"))


def test_mapping_refuses_box_and_colour():
    box = FogMedium(sigma_t=0.01, layers=(ExpLayer(1.0, 0.0, 0.0),), bounds=Box((0, 0, 0), (1, 1, 1)))
    with pytest.raises(ParameterError, match="profile"):
        from_physical("babylon", PhysicalScene(box))
    with pytest.raises(ParameterError, match="sigma_t"):
        from_physical("babylon", PhysicalScene(FogMedium(sigma_t=(0.01, 0.02, 0.03))))


def test_registered_and_bad_input():
    assert get("babylon") is BabylonFog
    for kw, name in (
        ({"fogMode": "exp"}, "fogMode"),
        ({"fogDensity": -1.0}, "fogDensity"),
        ({"fogDensity": math.nan}, "fogDensity"),
        ({"fogStart": 3.0, "fogEnd": 3.0}, "fogEnd"),
        ({"fogColor": (1.0, -0.1, 0.0)}, "fogColor"),
        ({"sky_distance": 0.0}, "sky_distance"),
    ):
        with pytest.raises(ParameterError, match=name):
            BabylonFogParams(**kw)


def test_extremes_are_finite():
    rng = np.random.default_rng(4)
    wp = rng.normal(size=(200, 3)) * 10 ** rng.uniform(-4, 9, (200, 1))
    wp = np.vstack([wp, np.zeros(3)])
    for p in (
        BabylonFogParams(fogMode="EXP2", fogDensity=1e3),
        BabylonFogParams(fogMode="EXP", fogDensity=0.0),
        BabylonFogParams(fogMode="EXP2", fogDensity=0.0),
        BabylonFogParams(fogMode="LINEAR", fogStart=-1e6, fogEnd=1e7),
        BabylonFogParams(fogMode="LINEAR", fogStart=0.0, fogEnd=1e-6),
    ):
        for prec in ("float32", "float64"):
            r = BabylonFog(p).evaluate(np.zeros(3), wp, prec)
            assert np.all(np.isfinite(r.transmittance)) and np.all(np.isfinite(r.inscatter))
            assert np.all((r.transmittance >= 0) & (r.transmittance <= 1)) and np.all(r.inscatter >= 0)
