"""Filament fog: a surface_fog.fs (1.53.4) transcription and the exponential medium (exp, not exp2)."""

import math

import numpy as np
import pytest

from fogref.mapping import PhysicalScene
from fogref.mapping.engines import filament_from_physical, filament_to_medium
from fogref.media import NP
from fogref.models.filament import FilamentFog, FilamentFogParams

f32 = np.float32


def filament_fog_fs(cam, wp, o, scene):
    """surface_fog.fs (Filament 1.53.4, the GLSL in its filament.wasm) + prepareFog, float32, one pixel."""
    y = f32(-o["heightFalloff"]) * (f32(cam[1]) - f32(o["height"]))
    density = (f32(o["density"]), y, f32(o["density"]) * np.exp(y))  # frameUniforms.fogDensity
    view = (np.asarray(wp) - np.asarray(cam)).astype(f32)
    falloff = f32(o["heightFalloff"])
    fi = density[2]  # fogOpticalPathAtOneMeter
    h = falloff * view[1]
    if abs(h) > f32(0.00125):
        with np.errstate(over="ignore"):  # exp overflows far below the camera: inf, as on the GPU
            fi = (density[2] - density[0] * np.exp(density[1] - h)) / h
    d = np.sqrt(np.sum(view * view))
    fogIntegral = fi * max(d - f32(o["distance"]), f32(0))
    fogOpacity = min(f32(1) - np.exp(-fogIntegral), f32(o["maximumOpacity"]))
    fogColor = np.asarray(o["color"], f32) * fogOpacity
    if o["inScatteringSize"] > 0:
        insc = fi * max(d - f32(o["inScatteringStart"]), f32(0))
        inscOpacity = f32(1) - np.exp(-insc)
        sunColor = np.asarray(o["sun"], f32)
        sunAmount = max(f32(np.dot(view, np.asarray(o["l"], f32))) / d, f32(0))
        fogColor = fogColor + sunColor * (np.power(sunAmount, f32(o["inScatteringSize"])) * inscOpacity)
    return np.asarray(scene, f32) * (f32(1) - fogOpacity) + fogColor


def test_float32_matches_fog_fs():
    rng = np.random.default_rng(0)
    l = np.array([0.2, 0.7, -0.3])
    l /= np.linalg.norm(l)
    o = dict(
        density=0.05,
        heightFalloff=0.3,
        height=2.0,
        distance=4.0,
        maximumOpacity=0.9,
        color=(0.5, 0.6, 0.7),
        inScatteringStart=10.0,
        inScatteringSize=8.0,
        l=l,
        sun=(2.0, 1.8, 1.5),
    )
    p = FilamentFogParams(
        density=0.05,
        heightFalloff=0.3,
        height=2.0,
        distance=4.0,
        maximumOpacity=0.9,
        color=(0.5, 0.6, 0.7),
        inScatteringStart=10.0,
        inScatteringSize=8.0,
        lightDirection=tuple(l),
        lightColorIntensity=(1.0, 0.9, 0.75, 2.0),
    )
    cam = np.array([0.0, 3.0, 0.0])
    d = rng.normal(size=(200, 3))
    d[:40, 1] = 0
    d[40:80, 1] *= 1e-3
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    wp = cam + d * 10 ** rng.uniform(-1, 3, (200, 1))
    scene = rng.uniform(0, 1, (200, 3))
    out = FilamentFog(p).evaluate(cam, wp, "float32").composite(scene.astype(f32))
    for i in range(200):
        np.testing.assert_allclose(out[i], filament_fog_fs(cam, wp[i], o, scene[i]), rtol=2e-5, atol=2e-6)


def test_float64_equals_exponential_medium():
    p = FilamentFogParams(density=0.02, heightFalloff=0.15, height=-1.0)
    m = filament_to_medium(p)
    rng = np.random.default_rng(1)
    cam = np.array([0.0, 4.0, 0.0])
    d = rng.normal(size=(300, 3))
    d[:50, 1] = 0
    d[50:100, 1] *= 1e-5
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    L = 10 ** rng.uniform(-2, 3, 300)
    T = FilamentFog(p).evaluate(cam, cam + d * L[:, None], "float64").transmittance[:, 0]
    np.testing.assert_allclose(T, m.transmittance(NP, tuple(cam), tuple(d.T), L)[0], rtol=1e-9, atol=1e-300)
    q = filament_from_physical(PhysicalScene(m)).params
    assert (q.density, q.heightFalloff, q.height) == pytest.approx((0.02, 0.15, -1.0))
    # exp, not exp2: a horizontal ray at the fog height has T = exp(-density L)
    T1 = (
        FilamentFog(FilamentFogParams(density=0.02, heightFalloff=0.15, height=0.0))
        .evaluate(np.zeros(3), np.array([[100.0, 0, 0]]), "float64")
        .transmittance[0, 0]
    )
    assert T1 == pytest.approx(math.exp(-2.0))


def test_extremes_are_finite():
    rng = np.random.default_rng(2)
    fog = FilamentFog(FilamentFogParams(inScatteringSize=4.0, cutOffDistance=1e6))
    for cam_y in (-1e3, 0.0, 50.0, 1e5):
        cam = np.array([0.0, cam_y, 0.0])
        d = rng.normal(size=(100, 3))
        d[:20, 1] = 0
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        wp = np.vstack([cam + d * 10 ** rng.uniform(-4, 7, (100, 1)), cam])
        for prec in ("float32", "float64"):
            r = fog.evaluate(cam, wp, prec)
            assert np.all(np.isfinite(r.transmittance)) and np.all(np.isfinite(r.inscatter))
