"""Unreal 5 Local Fog Volume: LocalFogVolumeCommon.ush transcription, quadrature, composition."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from fogref.errors import ParameterError
from fogref.models import get
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams, world_to_unreal
from fogref.models.ue_local_fog_volume import UELocalFogVolume, UELocalFogVolumeParams

f32 = np.float32


def unpack_11_10(x, mantissa_bits):
    """LocalFogVolumeRendering.cpp AsFloat111110 (half bits, shifted and masked) then
    UnpackR11G11B10F: 5 exponent bits, ``mantissa_bits`` mantissa bits, no sign."""
    half_bits = int(np.array(np.float16(x)).view(np.uint16))
    drop = 10 - mantissa_bits
    e, m = (half_bits >> 10) & 0x1F, (half_bits & 0x3FF) >> drop
    if e == 0:
        return f32(m / 2**mantissa_bits * 2.0**-14)
    return f32((1.0 + m / 2**mantissa_bits) * 2.0 ** (e - 15))


def lfv_shader(u, cam_m, wp_m):
    """Independent float32 transcription of UE 5.8's GetLFVInstanceContribution,
    LocalFogVolumeEvaluateAnalyticalIntegral (reference path) and LocalFogVolumeEvaluateInScattering
    (LocalFogVolumeCommon.ush, unicorn2022/UE5.8.0 5d9a05c), one unrotated volume, one pixel, with the
    packing of GetLocalFogVolumeViewSortingData.  Returns (rgb, transmittance)."""
    S = f32(u["FogUniformScale"])
    radial = unpack_11_10(u["RadialFogExtinction"], 6)
    height = unpack_11_10(u["HeightFogExtinction"], 6)
    falloff = unpack_11_10(f32(max(u["HeightFogFalloff"], 1.0) * 0.01), 5)
    emissive = np.array([unpack_11_10(e, b) for e, b in zip(u["FogEmissive"], (6, 6, 5))], f32)
    albedo = np.array([int(min(max(a * 255.0, 0.0), 255.0)) / 255.0 for a in u["FogAlbedo"]], f32)
    phase_g = f32(int(min(max(u["FogPhaseG"] * 255.0, 0.0), 255.0)) / 255.0)
    offset = f32(u["HeightFogOffset"])
    loc = np.asarray(u["Location"], np.float64)
    cam = world_to_unreal(cam_m)
    wp = world_to_unreal(wp_m)
    depth_pos_u = ((wp - loc) / S).astype(f32)
    ray_pos_u = ((cam - loc) / S).astype(f32)
    ray_dir = (wp - cam).astype(f32)
    ray_dir = ray_dir / np.sqrt(np.sum(ray_dir * ray_dir))  # CamRayWorldDir
    ray_dir_u = ray_dir  # identity rotation: mul(dir, I / S) then normalize
    # RayIntersectSphere (Common.ush)
    qa = np.sum(ray_dir_u * ray_dir_u)
    qb = f32(2) * np.sum(ray_dir_u * ray_pos_u)
    qc = np.sum(ray_pos_u * ray_pos_u) - f32(1)
    disc = qb * qb - f32(4) * qa * qc
    ts = np.array([-1.0, -1.0], f32)
    if disc >= 0:
        ts = ((-qb + np.array([-1, 1], f32) * np.sqrt(disc)) / (f32(2) * qa)).astype(f32)
    start = f32(max(u["GlobalStartDistance"], u["FogStartDistance"]))
    ts = np.maximum(start * (f32(1) / S), ts)
    v = depth_pos_u - ray_pos_u
    ts = np.minimum(ts, np.sqrt(np.sum(v * v)))
    if not np.any(ts > 0):
        return np.zeros(3, f32), f32(1)
    length = max(f32(0), abs(ts[1] - ts[0]))
    if not length > 0:
        return np.zeros(3, f32), f32(1)
    o = ray_pos_u + ray_dir_u * ts[0]
    tau_r = f32(0)
    if radial > 0:
        b = np.sum(ray_dir_u * o)
        c = np.sum(o * o) - f32(1)
        h = b * b - c
        if h >= 0:
            h = np.sqrt(h)
            l0, l1 = max(-b - h, f32(0)), min(max(-b + h, f32(0)), length)
            i0 = -(c * l0 + b * l0 * l0 + l0 * l0 * l0 / f32(3))
            i1 = -(c * l1 + b * l1 * l1 + l1 * l1 * l1 / f32(3))
            tau_r = max(f32(0), radial * (i1 - i0) * f32(0.75))
    tau_h = f32(0)
    if height > 0:
        start_height = o[2] - offset
        dz = ray_dir_u[2]
        safe = dz if abs(dz) >= f32(0.0001) else f32(0.0001) * (f32(1) if dz >= 0 else f32(-1))
        factor0 = max(f32(-80), start_height * falloff)
        factor1 = safe * length * falloff
        tau_h = (height / (falloff * safe)) * (np.exp(-factor0) - np.exp(-(factor0 + factor1)))
    t = f32(1) - (f32(1) - np.exp(-tau_r)) * (f32(1) - np.exp(-tau_h))
    optical_depth = -np.log(t)
    transmittance = np.exp(-optical_depth * S * f32(0.01))
    coverage = f32(1) - transmittance
    insc = np.asarray(u["SkyLighting"], f32).copy()
    if u["DirectionalLightDirection"] is not None:
        G = -phase_g
        cos = f32(np.dot(ray_dir, np.asarray(u["DirectionalLightDirection"], f32)))
        hg = (f32(1) - G * G) / (
            f32(4) * f32(math.pi) * np.power(f32(1) + G * G + f32(2) * G * cos, f32(1.5))
        )
        insc = insc + np.asarray(u["DirectionalLightColor"], f32) * hg
    insc = insc * albedo + emissive
    return insc * coverage, transmittance


U = dict(
    Location=(1500.0, -800.0, 600.0),
    FogUniformScale=2500.0,
    RadialFogExtinction=1.3,
    HeightFogExtinction=2.1,
    HeightFogFalloff=180.0,
    HeightFogOffset=-0.2,
    FogAlbedo=(0.9, 0.8, 0.6),
    FogPhaseG=0.45,
    FogEmissive=(0.02, 0.01, 0.05),
    FogStartDistance=300.0,
    GlobalStartDistance=0.0,
    DirectionalLightDirection=(0.5, 0.3, 0.81),
    DirectionalLightColor=(3.2, 2.9, 2.4),
    SkyLighting=(0.2, 0.3, 0.5),
)


def _pixels(rng, n, cam, centre):
    """Rays from the camera, most toward the volume (centre in fogref metres)."""
    d = centre - cam + rng.normal(size=(n, 3)) * 20.0
    d[: n // 8] = rng.normal(size=(n // 8, 3))  # anywhere, many missing the sphere
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return cam + d * 10 ** rng.uniform(0.5, 3.0, (n, 1))


@pytest.mark.parametrize("cam", [(0.0, 2.0, 0.0), (15.0, 6.0, -8.0)])  # outside, inside the sphere
def test_float32_matches_shader_transcription(cam):
    cam = np.asarray(cam)
    rng = np.random.default_rng(0)
    u = dict(U, DirectionalLightDirection=tuple(np.asarray(U["DirectionalLightDirection"]) / 1.0))
    p = UELocalFogVolumeParams(**u)
    u["DirectionalLightDirection"] = p.DirectionalLightDirection
    centre = np.array([15.0, 6.0, -8.0])  # Location in fogref metres
    wp = _pixels(rng, 200, cam, centre)
    r = UELocalFogVolume(p).evaluate(cam, wp, "float32")
    assert r.transmittance.dtype == np.float32
    fogged = 0
    for i in range(len(wp)):
        rgb, t = lfv_shader(u, cam, wp[i])
        fogged += t < 0.999
        np.testing.assert_allclose(r.transmittance[i], t, rtol=1e-5, atol=2e-6)
        np.testing.assert_allclose(r.inscatter[i], rgb, rtol=1e-5, atol=2e-6)
    assert fogged > 50  # the comparison covers fogged pixels


def _unit_depths(p, cam_m, wp_m):
    """Radial and height optical depths (unit-sphere lengths) by quadrature of the densities
    3/4 rho_r (1 - |u|^2) and rho_h exp(-k (u_z - offset)) along the chord inside the sphere."""
    S = p.FogUniformScale
    o = (world_to_unreal(cam_m) - np.asarray(p.Location)) / S
    e = (world_to_unreal(wp_m) - np.asarray(p.Location)) / S
    d = (e - o) / np.linalg.norm(e - o)
    b, c = d @ o, o @ o - 1.0
    h = b * b - c
    if h < 0:
        return 0.0, 0.0
    start = max(p.GlobalStartDistance, p.FogStartDistance) / S
    t0 = min(max(-b - math.sqrt(h), start), np.linalg.norm(e - o))
    t1 = min(max(-b + math.sqrt(h), start), np.linalg.norm(e - o))
    k = max(p.HeightFogFalloff, 1.0) * 0.01

    def radial(t):
        x = o + t * d
        return 0.75 * p.RadialFogExtinction * (1.0 - x @ x)

    def height(t):
        return p.HeightFogExtinction * math.exp(-k * (o[2] + t * d[2] - p.HeightFogOffset))

    opts = dict(epsabs=0.0, epsrel=1e-12, limit=200)
    return quad(radial, t0, t1, **opts)[0], quad(height, t0, t1, **opts)[0]


def test_float64_matches_quadrature_of_the_densities():
    """The closed-form chord integrals against scipy quad (relative 1e-12), combined as the source
    does: T = (1 - (1 - e^-tau_r)(1 - e^-tau_h))^(radius in m); tolerance 1e-9 relative."""
    p = UELocalFogVolumeParams(**dict(U, GlobalStartDistance=0.0, FogStartDistance=0.0))
    rng = np.random.default_rng(1)
    cam = np.array([0.0, 2.0, 0.0])
    wp = _pixels(rng, 120, cam, np.array([15.0, 6.0, -8.0]))
    r = UELocalFogVolume(p).evaluate(cam, wp, "float64")
    n_fog = 0
    for i in range(len(wp)):
        tr, th = _unit_depths(p, cam, wp[i])
        t_unit = 1.0 - (1.0 - math.exp(-tr)) * (1.0 - math.exp(-th))
        T = t_unit ** (p.FogUniformScale / 100.0)
        n_fog += T < 0.999
        assert r.transmittance[i, 0] == pytest.approx(T, rel=1e-9, abs=1e-15)
    assert n_fog > 50


def test_chord_through_the_centre_and_height_masking():
    """Through the centre the radial depth is rho_r (the 3/4 normalises the chord), so with an
    opaque height term T = exp(-rho_r R); with HeightFogExtinction = 0 the volume vanishes."""
    cam, wp = np.array([-100.0, 0.0, 0.0]), np.array([[100.0, 0.0, 0.0]])
    base = dict(
        FogUniformScale=2000.0, RadialFogExtinction=0.05, GlobalStartDistance=0.0, HeightFogFalloff=1.0
    )
    opaque = UELocalFogVolume(UELocalFogVolumeParams(**base, HeightFogExtinction=1e4))
    T = opaque.evaluate(cam, wp, "float64").transmittance[0, 0]
    assert T == pytest.approx(math.exp(-0.05 * 20.0), rel=1e-9)
    gone = UELocalFogVolume(UELocalFogVolumeParams(**base, HeightFogExtinction=0.0))
    r = gone.evaluate(cam, wp, "float64")
    assert r.transmittance[0, 0] == 1.0 and np.all(r.inscatter == 0.0)


def test_in_front_of_the_height_fog():
    """HeightFogPixelShader.usf: (LFV.rgb + HF.rgb * LFV.a, LFV.a * HF.a)."""
    hf = UE4FogParams(FogDensity=0.05, FogHeightFalloff=0.2)
    p = UELocalFogVolumeParams(**dict(U, GlobalStartDistance=0.0))
    both = UELocalFogVolume(UELocalFogVolumeParams(**dict(U, GlobalStartDistance=0.0, HeightFog=hf)))
    rng = np.random.default_rng(2)
    cam = np.array([0.0, 2.0, 0.0])
    wp = _pixels(rng, 64, cam, np.array([15.0, 6.0, -8.0]))
    lfv = UELocalFogVolume(p).evaluate(cam, wp, "float64")
    h = UE4ExponentialHeightFog(hf).evaluate(cam, wp, "float64")
    r = both.evaluate(cam, wp, "float64")
    np.testing.assert_allclose(r.transmittance, lfv.transmittance * h.transmittance, rtol=1e-12)
    np.testing.assert_allclose(r.inscatter, lfv.inscatter + h.inscatter * lfv.transmittance, rtol=1e-12)


def test_registered_extremes_and_bad_input():
    assert get("ue5_lfv") is UELocalFogVolume
    rng = np.random.default_rng(3)
    for cam in (np.array([15.0, 6.0, -8.0]), np.array([0.0, 1e5, 0.0])):
        wp = np.vstack([cam + rng.normal(size=(100, 3)) * 10 ** rng.uniform(-4, 6, (100, 1)), cam])
        for kw in (dict(U), dict(U, HeightFogOffset=-1e3, HeightFogFalloff=1e6, RadialFogExtinction=1e3)):
            for prec in ("float32", "float64"):
                r = UELocalFogVolume(UELocalFogVolumeParams(**kw)).evaluate(cam, wp, prec)
                assert np.all(np.isfinite(r.transmittance)) and np.all(np.isfinite(r.inscatter))
                assert np.all((r.transmittance >= 0) & (r.transmittance <= 1))
    for kw, name in (
        (dict(FogUniformScale=0.0), "FogUniformScale"),
        (dict(FogPhaseG=1.5), "FogPhaseG"),
        (dict(FogAlbedo=(1.2, 1.0, 1.0)), "FogAlbedo"),
        (dict(DirectionalLightDirection=(0, 0, 0)), "DirectionalLightDirection"),
        (dict(HeightFog=3), "HeightFog"),
    ):
        with pytest.raises(ParameterError, match=name):
            UELocalFogVolumeParams(**kw)
