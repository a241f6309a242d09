"""HDRP height fog: OpticalDepthHeightFog transcription, mpmath quadrature, medium."""

import math

import mpmath
import numpy as np
import pytest

from fogref.mapping import PhysicalScene
from fogref.mapping.engines import hdrp_from_physical, hdrp_to_medium
from fogref.media import NP, HDRPLayer
from fogref.models.hdrp import HDRPFog, HDRPFogParams

f32 = np.float32


def hdrp_optical_depth(baseExtinction, baseHeight, heightExponents, cosZenith, startHeight, intervalLength):
    """AtmosphericScattering.hlsl OpticalDepthHeightFog, transcribed in float32."""
    H = heightExponents[1]
    rcpH = heightExponents[0]
    Z = cosZenith
    absZ = max(abs(cosZenith), f32(0.001))
    rcpAbsZ = f32(1) / absZ
    endHeight = startHeight + intervalLength * Z
    minHeight = min(startHeight, endHeight)
    h = max(minHeight - baseHeight, f32(0))
    homFogDist = np.clip((baseHeight - minHeight) * rcpAbsZ, f32(0), intervalLength)
    expFogDist = intervalLength - homFogDist
    expFogMult = np.exp(-h * rcpH) * (f32(1) - np.exp(-expFogDist * absZ * rcpH)) * (rcpAbsZ * H)
    return baseExtinction * (homFogDist + expFogMult)


def test_float32_matches_transcription():
    rng = np.random.default_rng(0)
    p = HDRPFogParams(meanFreePath=150.0, baseHeight=5.0, maximumHeight=80.0, maxFogDistance=400.0)
    H = f32(max(f32(0.01), f32(80.0) - f32(5.0)) * f32(0.144765))
    for cam in (np.array([0.0, 1.0, 0.0]), np.array([0.0, 50.0, 0.0])):
        d = rng.normal(size=(200, 3))
        d[:40, 1] = 0.0
        d[40:60, 1] *= 1e-4
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        wp = cam + d * 10 ** rng.uniform(-1, 3.5, (200, 1))
        od = HDRPFog(p).optical_depth(cam, wp, "float32")
        for i in range(200):
            v = (wp[i] - cam).astype(f32)
            dist = np.sqrt(np.sum(v * v))
            ref = hdrp_optical_depth(
                f32(1) / f32(150.0),
                f32(5.0),
                (f32(1) / H, H),
                v[1] / dist,
                f32(cam[1]),
                dist,  # a surface: its whole distance (maxFogDistance is the sky's)
            )
            assert od[i] == pytest.approx(ref, rel=2e-5, abs=1e-7)


def _quad(cam, wp, ext, base, H):
    mpmath.mp.dps = 30
    c = [mpmath.mpf(float(x)) for x in cam]
    w = [mpmath.mpf(float(x)) for x in wp]
    L = mpmath.sqrt(sum((a - b) ** 2 for a, b in zip(w, c)))
    dy = (w[1] - c[1]) / L
    f = lambda s: ext * mpmath.exp(-max(c[1] + s * dy - base, 0) / H)
    pts = [0, L]
    if dy != 0 and 0 < (base - c[1]) / dy < L:
        pts.insert(1, (base - c[1]) / dy)
    return float(mpmath.quad(f, pts))


def test_float64_against_mpmath_and_medium():
    rng = np.random.default_rng(1)
    p = HDRPFogParams(meanFreePath=90.0, baseHeight=-3.0, maximumHeight=40.0, maxFogDistance=1000.0)
    H = float(p.scale_height())
    assert H == pytest.approx(43.0 / math.log(1000.0), rel=1e-5)
    m = hdrp_to_medium(p)
    fog = HDRPFog(p)
    for cam in (np.array([0.0, -10.0, 0.0]), np.array([0.0, 5.0, 0.0]), np.array([0.0, 100.0, 0.0])):
        d = rng.normal(size=(8, 3))
        d[0, 1] = 0.0
        d[1, 1] = 1e-6
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        L = rng.uniform(1, 1500, 8)
        wp = cam + d * L[:, None]
        od = fog.optical_depth(cam, wp, "float64")
        tau = m.optical_depth(NP, tuple(cam), tuple(d.T), L) * m.sigma_t[0]
        for i in range(8):
            q = _quad(cam, wp[i], 1 / 90.0, -3.0, H)
            assert od[i] == pytest.approx(q, rel=1e-9)
            assert tau[i] == pytest.approx(q, rel=1e-9)


def test_profile_sampling_inverts_depth_and_roundtrip():
    L = HDRPLayer(density=1.0, base_height=2.0, falloff=0.1)
    oy = np.array([0.0, 0.0, 10.0, 10.0, 10.0, 1.0])
    dy = np.array([0.5, -0.5, -0.5, 0.5, 0.0, 0.0])
    s = np.array([5.0, 5.0, 20.0, 1.0, 2.0, 3.0])
    t = L.sample(NP, oy, dy, s)
    np.testing.assert_allclose(L.depth(NP, oy, dy, t), s, rtol=1e-9)
    p = HDRPFogParams(meanFreePath=70.0, baseHeight=1.0, maximumHeight=31.0)
    q = hdrp_from_physical(PhysicalScene(hdrp_to_medium(p))).params
    assert q.meanFreePath == pytest.approx(70.0) and q.maximumHeight == pytest.approx(31.0, rel=1e-5)


def test_extremes_are_finite():
    rng = np.random.default_rng(3)
    fog = HDRPFog()
    for cam_y in (-1e5, 0.0, 30.0, 1e6):
        cam = np.array([0.0, cam_y, 0.0])
        d = rng.normal(size=(100, 3))
        d[:20, 1] = 0
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        wp = np.vstack([cam + d * 10 ** rng.uniform(-4, 7, (100, 1)), cam])
        for prec in ("float32", "float64"):
            r = fog.evaluate(cam, wp, prec)
            assert np.all(np.isfinite(r.transmittance)) and np.all(np.isfinite(r.inscatter))


def test_sky_pixels_are_fogged_over_max_fog_distance_surfaces_over_their_distance():
    """OpaqueAtmosphericScattering.shader: a far-plane pixel sits at camera - V * _MaxFogDistance;
    a surface farther than maxFogDistance is fogged over its whole distance (homogeneous fog)."""
    p = HDRPFogParams(meanFreePath=500.0, baseHeight=1e4, maximumHeight=1e4 + 10.0, maxFogDistance=300.0)
    cam = np.zeros(3)
    wp = np.array([[1000.0, 0.0, 0.0], [1000.0, 0.0, 0.0]])
    for prec in ("float32", "float64"):
        T = HDRPFog(p).evaluate(cam, wp, prec, hit=np.array([True, False])).transmittance[:, 0]
        assert T == pytest.approx([math.exp(-1000.0 / 500.0), math.exp(-300.0 / 500.0)], rel=2e-6)
    # without the truth's mask, a point at SKY_DISTANCE is sky
    from fogref.models import SKY_DISTANCE

    T = HDRPFog(p).evaluate(cam, np.array([[SKY_DISTANCE, 0.0, 0.0]]), "float64").transmittance[0, 0]
    assert T == pytest.approx(math.exp(-300.0 / 500.0), rel=1e-12)
