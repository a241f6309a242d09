"""Unreal exponential height fog: shader transcription, physics, robustness."""

import math

import numpy as np
import pytest

from fogref.mapping import PhysicalScene
from fogref.mapping.unreal import base_params
from fogref.media import NP
from fogref.models import get
from fogref.models.ue4 import SecondFogData, UE4ExponentialHeightFog, UE4FogParams, ue4_to_medium

f32 = np.float32


def unreal_shader_fog(
    cam_m,
    wp_m,
    D,
    f,
    H,
    D2,
    f2,
    H2,
    color,
    max_opacity,
    start,
    cutoff,
    light=None,
    dir_color=(0, 0, 0),
    dir_exp=4.0,
    dir_start=0.0,
    vfog=None,
    skyatm=None,
):
    """Independent float32 transcription of UE 4.22's ``GetExponentialHeightFog``
    (``Engine/Shaders/Private/HeightFogCommon.ush``, ported y-up) with the uniforms
    that ``InitFogConstants`` (``Engine/Source/Runtime/Renderer/Private/FogRendering.cpp``)
    sets, in centimetres.  One pixel.  UE 5.8 (unicorn2022/UE5.8.0 5d9a05c): ``vfog`` (dict: g,
    albedo, emissive) the PROJECT_EXPFOG_MATCHES_VFOG lines and InitFogConstants'
    bExpFogMatchesVolumetricFog; ``skyatm`` (dict: ambient, illuminance) the
    PROJECT_SUPPORT_SKY_ATMOSPHERE_AFFECTS_HEIGHFOG branch."""
    fog_dir_color = np.asarray(dir_color, f32)
    if vfog is not None:  # InitFogConstants with bExpFogMatchesVolumetricFog
        dir_start = 0.0
        albedo = np.asarray(vfog["albedo"], f32)
        color = np.asarray(vfog["emissive"], f32)
        fog_dir_color = np.zeros(3, f32)  # FLinearColor::Black
    if skyatm is not None:  # ComputeInscatteringColor: Inscattering += SkyAmbient (* albedo)
        sky_ambient = np.asarray(skyatm["ambient"], f32)
        if vfog is not None:
            sky_ambient = sky_ambient * albedo
        color = np.asarray(color, f32) + sky_ambient
        fog_dir_color = fog_dir_color + np.asarray(skyatm["illuminance"], f32)
    cam = (np.asarray(cam_m, np.float64) * 100).astype(f32)
    rel = ((np.asarray(wp_m, np.float64) - np.asarray(cam_m, np.float64)) * 100).astype(f32)
    d0, fa0 = f32(D) / f32(1000), f32(f) / f32(1000)
    d1, fa1 = f32(D2) / f32(1000), f32(f2) / f32(1000)
    H, H2 = f32(H), f32(H2)
    max_obs = min(H + f32(65536) if d0 > 0 else f32(3e38), H2 + f32(65536) if d1 > 0 else f32(3e38))
    # ExponentialFogParameters(.x .y .z .w), 2, 3 as FogRendering.cpp fills them
    P = (d0 * f32(2) ** (-fa0 * (cam[1] - H)), fa0, max_obs, f32(start))
    P2 = (d1 * f32(2) ** (-fa1 * (cam[1] - H2)), fa1, d1, H2)
    P3 = (d0, H, f32(0), f32(cutoff))
    MinFogOpacity = f32(1) - f32(max_opacity)

    def CalculateLineIntegralShared(FogHeightFalloff, RayDirectionY, RayOriginTerms):
        Falloff = max(f32(-127.0), FogHeightFalloff * RayDirectionY)
        if abs(Falloff) > f32(0.01):
            return RayOriginTerms * ((f32(1) - np.exp2(-Falloff)) / Falloff)
        ln2 = f32(math.log(2.0))
        return RayOriginTerms * (ln2 - (f32(0.5) * ln2 * ln2) * Falloff)

    observer_y = min(cam[1], P[2])
    c2r = rel.copy()
    c2r[1] += cam[1] - observer_y
    lsq = f32(c2r[0] * c2r[0] + c2r[1] * c2r[1] + c2r[2] * c2r[2])
    linv = f32(1) / np.sqrt(lsq)
    length = lsq * linv
    normd = c2r * linv
    ro, ro2 = P[0], P2[0]
    ray_len, ray_dy = length, c2r[1]
    if P[3] > 0:
        t = P[3] * linv
        cdy = t * c2r[1]
        ey = observer_y + cdy
        ray_len = (f32(1) - t) * length
        ray_dy = c2r[1] - cdy
        ro = P3[0] * np.exp2(-max(f32(-127), P[1] * (ey - P3[1])))
        ro2 = P2[2] * np.exp2(-max(f32(-127), P2[1] * (ey - P2[3])))
    shared = CalculateLineIntegralShared(P[1], ray_dy, ro) + CalculateLineIntegralShared(P2[1], ray_dy, ro2)
    integral = shared * ray_len
    dir_insc = np.zeros(3, f32)
    if light is not None and vfog is not None:
        G = f32(vfog["g"])
        cos_theta = f32(np.dot(-normd, np.asarray(light, f32)))  # dot(-CameraToReceiverNormalized, L)
        phase = (f32(1) - G * G) / (
            f32(4) * f32(math.pi) * np.power(f32(1) + G * G + f32(2) * G * cos_theta, f32(1.5))
        )
        lobe = fog_dir_color * phase
    elif light is not None:
        lobe = fog_dir_color * np.power(
            np.clip(f32(np.dot(normd, np.asarray(light, f32))), 0, 1), f32(dir_exp)
        )
        if skyatm is not None:
            lobe = lobe * (f32(1) / (f32(4) * f32(math.pi)))  # UniformPhaseFunction
    if light is not None:
        dint = shared * max(ray_len - f32(dir_start), f32(0))
        dff = np.clip(np.exp2(-dint), 0, 1)
        dir_insc = lobe * (f32(1) - dff)
        if vfog is not None:
            dir_insc = dir_insc * albedo
    factor = max(np.clip(np.exp2(-integral), 0, 1), MinFogOpacity)
    if P3[3] > 0 and length > P3[3]:
        factor = f32(1)
        dir_insc = np.zeros(3, f32)
    return np.asarray(color, f32) * (f32(1) - factor) + dir_insc, factor


def _rays(rng, n, cam):
    d = rng.normal(size=(n, 3))
    d[: n // 4, 1] = 0.0  # horizontal rays
    d[n // 4 : n // 2, 1] = rng.uniform(-1e-4, 1e-4, n // 4)  # Taylor branch
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return cam + d * 10 ** rng.uniform(-1, 4, (n, 1))


def ue4_params_of(kw: dict, **extra) -> UE4FogParams:
    """The ``UE4FogParams`` of a transcription's inputs ``kw`` (heights in cm), plus ``extra`` fields."""
    return UE4FogParams(
        FogDensity=kw["D"],
        FogHeightFalloff=kw["f"],
        FogHeight=kw["H"],
        SecondFogData=SecondFogData(kw["D2"], kw["f2"], kw["H2"] - kw["H"]),
        FogInscatteringColor=kw["color"],
        FogMaxOpacity=kw["max_opacity"],
        StartDistance=kw["start"],
        FogCutoffDistance=kw["cutoff"],
        DirectionalInscatteringExponent=kw["dir_exp"],
        DirectionalInscatteringStartDistance=kw["dir_start"],
        DirectionalInscatteringColor=kw["dir_color"],
        **extra,
    )


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_float32_matches_shader_transcription(seed):
    rng = np.random.default_rng(seed)
    # sun given in the y-up port's frame; the model takes Unreal's z-up frame
    sun_y_up = np.array([0.4, 0.6, -0.2])
    sun_y_up /= np.linalg.norm(sun_y_up)
    kw = dict(
        D=rng.uniform(0.005, 0.2),
        f=rng.uniform(0.0, 1.0),
        H=rng.uniform(-500, 500),
        D2=rng.uniform(0, 0.1),
        f2=rng.uniform(0, 2.0),
        H2=rng.uniform(-2000, 2000),
        color=(0.4, 0.5, 0.9),
        max_opacity=rng.uniform(0.5, 1.0),
        start=[0.0, 0.0, 3000.0][seed],
        cutoff=[0.0, 200000.0, 0.0][seed],
        light=sun_y_up,
        dir_color=(1.0, 0.8, 0.5),
        dir_exp=rng.uniform(1, 16),
        dir_start=[0.0, 5000.0, 100.0][seed],
    )
    params = ue4_params_of(kw).with_sun(sun_y_up)
    cam = np.array([3.0, rng.uniform(-2, 20), -7.0])
    wp = _rays(rng, 64, cam)
    res = UE4ExponentialHeightFog(params).evaluate(cam, wp, "float32")
    assert res.transmittance.dtype == np.float32
    for i in range(len(wp)):
        col, fac = unreal_shader_fog(cam, wp[i], **kw)
        np.testing.assert_allclose(res.transmittance[i], fac, rtol=2e-5, atol=1e-6)
        np.testing.assert_allclose(res.inscatter[i], col, rtol=2e-5, atol=1e-6)


def _exact_T(params, cam, wp):
    m = ue4_to_medium(params)
    d = wp - cam
    L = np.linalg.norm(d, axis=-1)
    d = d / L[:, None]
    return m.transmittance(NP, tuple(cam), tuple(d.T), L)[0]


def test_float64_equals_physical_medium():
    rng = np.random.default_rng(5)
    params = UE4FogParams(
        FogDensity=0.05,
        FogHeightFalloff=0.3,
        FogHeight=150.0,
        SecondFogData=SecondFogData(0.02, 0.05, 3000.0),
    )
    cam = np.array([0.0, 12.0, 0.0])
    wp = _rays(rng, 400, cam)
    T64 = UE4ExponentialHeightFog(params).evaluate(cam, wp, "float64").transmittance[:, 0]
    T_exact = _exact_T(params, cam, wp)
    np.testing.assert_allclose(T64, T_exact, rtol=1e-10, atol=1e-13)
    T32 = UE4ExponentialHeightFog(params).evaluate(cam, wp, "float32").transmittance[:, 0]
    np.testing.assert_allclose(T32, T_exact, rtol=2e-3, atol=2e-5)


def test_sigma_formula_and_roundtrip():
    p = UE4FogParams(
        FogDensity=0.04,
        FogHeightFalloff=0.25,
        FogHeight=-120.0,
        SecondFogData=SecondFogData(0.01, 0.5, 700.0),
    )
    m = ue4_to_medium(p)
    a = 100 * math.log(2) ** 2 * 0.04 / 1000
    b = 100 * math.log(2) * 0.25 / 1000
    assert m.sigma_t[0] == pytest.approx(a, rel=1e-14)
    assert m.layers[0].falloff == pytest.approx(b, rel=1e-14)
    assert m.layers[0].height == pytest.approx(-1.2)
    # density at a point (per metre) equals (ln2)^2 D/1000 2^(-f/1000 (z - H)) per cm, x 100
    y = 3.0
    z_cm = 300.0
    per_cm = math.log(2) ** 2 * 0.04 / 1000 * 2 ** (-0.25 / 1000 * (z_cm + 120.0)) + math.log(
        2
    ) ** 2 * 0.01 / 1000 * 2 ** (-0.5 / 1000 * (z_cm - 580.0))
    assert m.sigma_t[0] * m.density(NP, (0.0, np.array(y), 0.0)) == pytest.approx(100 * per_cm, rel=1e-12)
    q = base_params(PhysicalScene(m))
    for k in ("FogDensity", "FogHeightFalloff", "FogHeight"):
        assert getattr(q, k) == pytest.approx(getattr(p, k), rel=1e-12, abs=1e-9)
    assert q.SecondFogData.FogDensity == pytest.approx(0.01, rel=1e-12)
    assert q.SecondFogData.FogHeightOffset == pytest.approx(700.0, rel=1e-12)


def test_start_distance_is_exact_fog_from_the_exclusion_point():
    p = UE4FogParams(FogDensity=0.05, FogHeightFalloff=0.2, StartDistance=2000.0)
    cam = np.array([0.0, 5.0, 0.0])
    rng = np.random.default_rng(3)
    wp = _rays(rng, 100, cam)
    wp = wp[np.linalg.norm(wp - cam, axis=1) > 25.0]
    T = UE4ExponentialHeightFog(p).evaluate(cam, wp, "float64").transmittance[:, 0]
    d = (wp - cam) / np.linalg.norm(wp - cam, axis=1, keepdims=True)
    o = cam + 20.0 * d
    L = np.linalg.norm(wp - o, axis=1)
    T_exact = ue4_to_medium(p).transmittance(NP, tuple(o.T), tuple(d.T), L)[0]
    np.testing.assert_allclose(T, T_exact, rtol=1e-10)


def test_engine_rules():
    cam = np.zeros(3)
    wp = np.array([[1000.0, 0.0, 0.0], [200.0, 0.0, 0.0]])
    fog = UE4ExponentialHeightFog(UE4FogParams(FogDensity=1.0, FogMaxOpacity=0.7, FogCutoffDistance=50000.0))
    r = fog.evaluate(cam, wp, "float64")
    assert r.transmittance[0, 0] == 1.0 and np.all(r.inscatter[0] == 0)  # beyond the cutoff
    assert r.transmittance[1, 0] == pytest.approx(0.3)  # max opacity
    p = UE4FogParams(DirectionalInscatteringExponent=1e9)
    assert UE4ExponentialHeightFog(p).evaluate(cam, wp).transmittance.shape == (2, 3)


def test_observer_height_clamp_and_extremes_are_finite():
    fog = UE4ExponentialHeightFog(UE4FogParams(FogDensity=0.05, FogHeightFalloff=0.2).with_sun((0, 1, 0)))
    rng = np.random.default_rng(9)
    for cam_y in (-1e5, -10.0, 0.0, 3.0, 655.0, 700.0, 1e6):
        cam = np.array([0.0, cam_y, 0.0])
        d = rng.normal(size=(200, 3))
        d[:50, 1] = 0
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        wp = cam + d * 10 ** rng.uniform(-4, 7, (200, 1))
        wp = np.vstack([wp, cam])  # a pixel at the camera
        for prec in ("float32", "float64"):
            r = fog.evaluate(cam, wp, prec)
            assert np.all(np.isfinite(r.transmittance)) and np.all(np.isfinite(r.inscatter))
            assert np.all((r.transmittance >= 0) & (r.transmittance <= 1))


def test_registry_and_end_distance():
    assert get("ue4") is UE4ExponentialHeightFog
    cam = np.zeros(3)
    wp = np.array([[0.0, 0.0, 500.0], [0.0, 0.0, 5000.0]])
    p = UE4FogParams(FogDensity=0.1, FogHeightFalloff=0.0, EndDistance=100000.0)
    T = UE4ExponentialHeightFog(p).evaluate(cam, wp, "float64").transmittance[:, 0]
    assert T[0] < 1 and T[1] == pytest.approx(T[0] ** 2, rel=1e-9)  # fog stops at 1 km


VFOG = dict(g=0.6, albedo=(0.9, 0.8, 0.7), emissive=(0.01, 0.02, 0.03))
SKYATM = dict(ambient=(0.2, 0.3, 0.5), illuminance=(3.2, 2.9, 2.4))


@pytest.mark.parametrize("match,sky", [(True, True), (True, False), (False, True)])
def test_ue5_project_settings_match_shader_transcription(match, sky):
    """r.SupportExpFogMatchesVolumetricFog and r.SupportSkyAtmosphereAffectsHeightFog (each
    combination but the default, which test_float32_matches_shader_transcription covers)."""
    rng = np.random.default_rng(10 + 2 * match + sky)
    sun = np.array([0.4, 0.2, -0.6])
    sun /= np.linalg.norm(sun)
    kw = dict(
        D=rng.uniform(0.005, 0.2),
        f=rng.uniform(0.0, 1.0),
        H=rng.uniform(-500, 500),
        D2=rng.uniform(0, 0.1),
        f2=rng.uniform(0, 2.0),
        H2=rng.uniform(-2000, 2000),
        color=(0.4, 0.5, 0.9),
        max_opacity=rng.uniform(0.5, 1.0),
        start=3000.0 * sky,
        cutoff=200000.0 * match,
        light=sun,
        dir_color=(1.0, 0.8, 0.5),
        dir_exp=8.0,
        dir_start=5000.0,
    )
    params = ue4_params_of(
        kw,
        ExpFogMatchesVolumetricFog=match,
        SkyAtmosphereAffectsHeightFog=sky,
        VolumetricFogScatteringDistribution=VFOG["g"],
        VolumetricFogAlbedo=VFOG["albedo"],
        VolumetricFogEmissive=VFOG["emissive"],
        SkyAtmosphereAmbient=SKYATM["ambient"] if sky else (0.0, 0.0, 0.0),
        AtmosphereLightIlluminance=SKYATM["illuminance"] if sky else (0.0, 0.0, 0.0),
    ).with_sun(sun)
    cam = np.array([3.0, rng.uniform(-2, 20), -7.0])
    wp = _rays(rng, 64, cam)
    wp[:8] = cam + sun * 10 ** rng.uniform(1, 4, (8, 1))  # into the forward peak
    res = UE4ExponentialHeightFog(params).evaluate(cam, wp, "float32")
    for i in range(len(wp)):
        col, fac = unreal_shader_fog(
            cam, wp[i], **kw, vfog=VFOG if match else None, skyatm=SKYATM if sky else None
        )
        np.testing.assert_allclose(res.transmittance[i], fac, rtol=2e-5, atol=1e-6)
        np.testing.assert_allclose(res.inscatter[i], col, rtol=2e-5, atol=1e-6)
    if match:  # the cosine lobe and its colour are unused in this mode, as in the engine
        off = UE4ExponentialHeightFog(replace_fields(params, DirectionalInscatteringColor=(9.0, 9.0, 9.0)))
        np.testing.assert_array_equal(off.evaluate(cam, wp, "float32").inscatter, res.inscatter)
    if match and not sky:  # the CPU's black directional colour: only the emissive is left
        np.testing.assert_allclose(res.inscatter, np.asarray(VFOG["emissive"], f32) * (1 - res.transmittance))


def replace_fields(params, **kw):
    import dataclasses

    return dataclasses.replace(params, **kw)


def test_exp_fog_matches_volumetric_fog_is_unattenuated_single_scattering():
    """float64, one layer: inscatter = albedo (E p_HG(d . w) + L_sky) (1 - T), T the exact medium's
    (the closed form of an unattenuated sun and a uniform sky), p_HG from fogref.media."""
    from fogref.media import hg_phase

    sun = np.array([0.3, 0.25, 0.9])
    sun /= np.linalg.norm(sun)
    params = UE4FogParams(
        FogDensity=0.05,
        FogHeightFalloff=0.3,
        FogHeight=50.0,
        ExpFogMatchesVolumetricFog=True,
        SkyAtmosphereAffectsHeightFog=True,
        VolumetricFogScatteringDistribution=-0.4,
        VolumetricFogAlbedo=(0.9, 0.8, 0.7),
        SkyAtmosphereAmbient=(0.2, 0.3, 0.5),
        AtmosphereLightIlluminance=(3.2, 2.9, 2.4),
    ).with_sun(sun)
    rng = np.random.default_rng(4)
    cam = np.array([0.0, 3.0, 0.0])
    wp = _rays(rng, 200, cam)
    r = UE4ExponentialHeightFog(params).evaluate(cam, wp, "float64")
    T = _exact_T(params, cam, wp)[:, None]
    np.testing.assert_allclose(r.transmittance, np.repeat(T, 3, axis=1), rtol=1e-9, atol=1e-15)
    d = (wp - cam) / np.linalg.norm(wp - cam, axis=1, keepdims=True)
    p = hg_phase(NP, d @ sun, -0.4)[:, None]
    expected = np.array([0.9, 0.8, 0.7]) * (np.array([3.2, 2.9, 2.4]) * p + [0.2, 0.3, 0.5]) * (1 - T)
    np.testing.assert_allclose(r.inscatter, expected, rtol=1e-9, atol=1e-15)


def test_exp_fog_matches_volumetric_fog_bad_input():
    from fogref.errors import ParameterError

    for kw, name in (
        (
            dict(ExpFogMatchesVolumetricFog=True, VolumetricFogScatteringDistribution=0.995),
            "VolumetricFogScatteringDistribution",
        ),
        (dict(ExpFogMatchesVolumetricFog=True, VolumetricFogAlbedo=(1.2, 1.0, 1.0)), "VolumetricFogAlbedo"),
        (dict(ExpFogMatchesVolumetricFog="yes"), "ExpFogMatchesVolumetricFog"),
        (dict(SkyAtmosphereAffectsHeightFog=1), "SkyAtmosphereAffectsHeightFog"),
        (dict(ExpFogMatchesVolumetricFog=True, SkyAtmosphereAmbient=(0.1, 0.1, 0.1)), "SkyAtmosphereAmbient"),
    ):
        with pytest.raises(ParameterError, match=name):
            UE4FogParams(**kw)


def test_end_distance_applies_to_the_horizontal_distance():
    """HeightFogCommon.ush (UE 5.8): CameraToReceiver *= End / sqrt(max(1, |xy|^2)) where |xy| > End;
    homogeneous fog: T = exp(-sigma * the scaled length), sigma = 100 (ln 2)^2 D / 1000 per metre."""
    sigma = 100 * math.log(2) ** 2 * 0.1 / 1000
    p = UE4FogParams(FogDensity=0.1, FogHeightFalloff=0.0, EndDistance=100000.0)  # 1 km
    cam = np.zeros(3)
    wp = np.array([[500.0, 2000.0, 0.0], [3000.0, 4000.0, 0.0]])  # |xy| (Unreal) = 500 m, 3000 m
    T = UE4ExponentialHeightFog(p).evaluate(cam, wp, "float64").transmittance[:, 0]
    lengths = [math.hypot(500.0, 2000.0), math.hypot(3000.0, 4000.0) / 3.0]  # the 2nd scaled to |xy| = 1 km
    assert T == pytest.approx([math.exp(-sigma * x) for x in lengths], rel=1e-9)
