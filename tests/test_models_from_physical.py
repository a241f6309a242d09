"""``fogref.mapping.from_physical``: every game fog model built from a ground truth's ``fogref.params``.

Exact mappings give the physical float64 transmittance; colours follow the light
(albedo * sky radiance; Unreal's from the fit of fogref.mapping.unreal); a profile
without a counterpart raises ParameterError naming 'profile'.
"""

import copy
import inspect
import math

import numpy as np
import pytest

from fogref.errors import FogrefError, ParameterError
from fogref.mapping import (
    PhysicalScene,
    fit_unreal,
    from_physical,
    lobe_fit,
)
from fogref.mapping.build import build_model
from fogref.media import NP, medium_from_params
from fogref.models import get
from fogref.models.ue4 import direction_to_unreal

SUN = np.array([0.4, 0.139, 0.906]) / np.linalg.norm([0.4, 0.139, 0.906])
VALLEY = {
    "scene": "valley.xml",
    "medium": {
        "profile": "exponential",
        "sigma_t": 0.000960906,
        "albedo": 0.9,
        "g": 0.6,
        "falloff": 0.0138629,
        "height": 0.0,
    },
    "sun": {"direction": SUN.tolist(), "irradiance": [3.2, 2.9, 2.4]},
    "sky": {"type": "constant", "radiance": [0.2, 0.3, 0.5]},
    "camera": {"origin": [0.0, 2.0, 0.0]},
}
CAMERA = np.array([0.0, 2.0, 0.0])
ALBEDO_SKY = np.array([0.18, 0.27, 0.45])


def scene(**medium):
    """VALLEY with its medium dict replaced by ``medium``."""
    p = copy.deepcopy(VALLEY)
    p["medium"] = medium
    return p


def views(camera=CAMERA, min_y=0.0):
    """World points (N, 3) seen from ``camera``: 200 directions x 8 distances (10 m to
    100 km, the compare's sky distance), kept at or above ``min_y``."""
    i = np.arange(200) + 0.5
    y = 1.0 - 2.0 * i / 200
    r = np.sqrt(1.0 - y * y)
    a = i * math.pi * (3.0 - math.sqrt(5.0))
    d = np.stack([r * np.cos(a), y, r * np.sin(a)], -1)
    D = np.geomspace(10.0, 1.0e5, 8)
    pts = (camera + d[:, None, :] * D[None, :, None]).reshape(-1, 3)
    return pts[pts[:, 1] >= min_y]


def at_points(model, camera, pts, precision="float64"):
    """``model.evaluate`` on ``pts`` as surfaces: the truth's hit mask (all True) for a model
    that takes one, so a point at the sky distance (100 km) is a surface there too."""
    kw = {"hit": np.ones(len(pts), bool)} if "hit" in inspect.signature(model.evaluate).parameters else {}
    return model.evaluate(camera, pts, precision=precision, **kw)


def physical_transmittance(params, camera, pts):
    """Exact RGB transmittance (N, 3) of the scene's medium from camera to each point."""
    m = medium_from_params(params["medium"])
    v = pts - camera
    D = np.linalg.norm(v, axis=-1)
    d = v / D[:, None]
    o = tuple(np.full(len(D), c) for c in camera)
    return np.stack(m.transmittance(NP, o, tuple(d.T), D), -1)


def check_finite(model, camera, pts):
    for precision in ("float32", "float64"):
        r = model.evaluate(camera, pts, precision=precision)
        assert np.all(np.isfinite(r.inscatter)) and np.all(np.isfinite(r.transmittance)), precision
        assert np.all(r.inscatter >= 0)


# -- exact transmittance -------------------------------------------------------------


@pytest.mark.parametrize("name", ["ue4", "hdrp", "filament"])
def test_valley_transmittance_is_exact(name):
    pts = views()
    model = from_physical(name, VALLEY)
    got = at_points(model, CAMERA, pts).transmittance
    np.testing.assert_allclose(got, physical_transmittance(VALLEY, CAMERA, pts), rtol=1e-9, atol=1e-14)
    check_finite(model, CAMERA, pts)


@pytest.mark.parametrize("name", ["ue4", "unity", "hdrp", "filament"])
def test_homogeneous_transmittance_is_exact(name):
    p = scene(profile="homogeneous", sigma_t=0.002, albedo=0.8, g=0.3)
    pts = views(min_y=-1e9)[:800]
    model = from_physical(name, p)
    got = at_points(model, CAMERA, pts).transmittance
    np.testing.assert_allclose(got, physical_transmittance(p, CAMERA, pts), rtol=1e-9, atol=1e-14)
    check_finite(model, CAMERA, pts)


def test_ue4_two_layers_exact():
    p = scene(
        profile="exponential",
        sigma_t=0.001,
        albedo=0.9,
        g=0.6,
        falloff=0.01,
        height=0.0,
        density2=0.5,
        falloff2=0.05,
        height2=20.0,
    )
    pts = views()
    model = from_physical("ue4", p)
    got = model.evaluate(CAMERA, pts, precision="float64").transmittance
    np.testing.assert_allclose(got, physical_transmittance(p, CAMERA, pts), rtol=1e-9, atol=1e-14)


def test_hdrp_profile_exact_and_camera_below_fog_height():
    p = scene(profile="hdrp", sigma_t=0.003, albedo=0.7, g=0.2, base_height=10.0, falloff=0.02)
    pts = views(min_y=-1e9)
    model = from_physical("hdrp", p)
    np.testing.assert_allclose(
        at_points(model, CAMERA, pts).transmittance,
        physical_transmittance(p, CAMERA, pts),
        rtol=1e-9,
        atol=1e-14,
    )
    # exponential layer referenced above the camera: HDRP's base goes down to the camera
    q = scene(profile="exponential", sigma_t=0.001, falloff=0.01, height=50.0)
    model = from_physical("hdrp", q)
    assert model.params.baseHeight == pytest.approx(2.0)
    pts = views()
    pts = pts[pts[:, 1] >= 2.0]
    np.testing.assert_allclose(
        at_points(model, CAMERA, pts).transmittance,
        physical_transmittance(q, CAMERA, pts),
        rtol=1e-9,
        atol=1e-14,
    )


def test_box_exact():
    p = scene(
        profile="box", sigma_t=0.05, albedo=0.9, g=0.0, bounds_min=[-30, 0, 20], bounds_max=[30, 15, 80]
    )
    pts = views(min_y=-1e9)
    model = from_physical("box", p)
    assert model.params.mode == "beer"
    np.testing.assert_allclose(
        at_points(model, CAMERA, pts).transmittance,
        physical_transmittance(p, CAMERA, pts),
        rtol=1e-9,
        atol=1e-14,
    )
    np.testing.assert_allclose(model.params.fog_color, ALBEDO_SKY)
    check_finite(model, CAMERA, pts)


def test_altitude_optical_depth_exact():
    p = scene(profile="powerlaw", sigma_t=0.004, albedo=0.9, g=0.0, start=0.0, end=60.0, power=2.0)
    pts = views()
    model = from_physical("altitude", p)
    tau = -np.log(physical_transmittance(p, CAMERA, pts))[:, 0]
    got = model.path_integral(CAMERA, pts, precision="float64") * model.params._FogColor[3]
    np.testing.assert_allclose(got, tau, rtol=1e-9, atol=1e-14)
    # the blend is linear in optical depth (only that differs from Beer-Lambert)
    T = model.evaluate(CAMERA, pts, precision="float64").transmittance[:, 0]
    np.testing.assert_allclose(T, 1.0 - np.minimum(tau, 1.0), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(model.params._FogColor[:3], ALBEDO_SKY)
    check_finite(model, CAMERA, pts)


def test_unity_valley_uses_density_at_camera():
    pts = views()
    model = from_physical("unity", VALLEY)
    q = model.params
    assert (q.fogMode, q.fog_coordinate) == ("exp", "distance")
    assert q.fogDensity == pytest.approx(0.000960906 * math.exp(-0.0138629 * 2.0), rel=1e-12)
    # exact for horizontal rays
    flat = CAMERA + np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]) * np.array([[50.0], [5000.0]])
    np.testing.assert_allclose(
        model.evaluate(CAMERA, flat, precision="float64").transmittance,
        physical_transmittance(VALLEY, CAMERA, flat),
        rtol=1e-9,
    )
    np.testing.assert_allclose(q.fogColor, ALBEDO_SKY)
    check_finite(model, CAMERA, pts)


# -- colours -------------------------------------------------------------------------


def test_ue4_colours_from_fit():
    q = from_physical("ue4", VALLEY).params
    assert q.InscatteringLightDirection == pytest.approx(direction_to_unreal(SUN))
    assert q.SunLuminance == 1.0 and q.StartDistance == 0.0 and q.FogMaxOpacity == 1.0
    pf = PhysicalScene.from_params(VALLEY)
    fit = fit_unreal(pf).params
    for k in (
        "FogInscatteringColor",
        "DirectionalInscatteringColor",
        "DirectionalInscatteringExponent",
        "DirectionalInscatteringStartDistance",
    ):
        assert getattr(q, k) == pytest.approx(getattr(fit, k), rel=1e-9, abs=1e-12), k
    # a low forward-scattering sun: a strong lobe, a sky-dominated isotropic colour
    assert max(q.DirectionalInscatteringColor) > 0.1 and q.DirectionalInscatteringExponent > 1
    np.testing.assert_allclose(q.FogInscatteringColor, ALBEDO_SKY, rtol=0.5)


def test_filament_colours_and_lobe():
    q = from_physical("filament", VALLEY).params
    np.testing.assert_allclose(q.color, ALBEDO_SKY)
    lobe = lobe_fit(0.6, isotropic=False)
    assert q.inScatteringSize == pytest.approx(lobe["exponent"])
    np.testing.assert_allclose(q.lightDirection, SUN)
    # light colour = albedo * E * T_sun(camera) * c, with T_sun in (0, 1) for this low sun
    c = lobe["lobe"] / (4 * math.pi)
    t_sun = np.asarray(q.lightColorIntensity[:3]) / (0.9 * np.array([3.2, 2.9, 2.4]) * c)
    assert np.allclose(t_sun, t_sun[0]) and 0.3 < t_sun[0] < 1.0
    assert q.lightColorIntensity[3] == 1.0


def test_hdrp_colour():
    q = from_physical("hdrp", VALLEY).params
    np.testing.assert_allclose(np.asarray(q.color) * np.asarray(q.albedo), ALBEDO_SKY)
    assert q.maxFogDistance >= 1e5


@pytest.mark.parametrize("name", ["ue4", "unity", "hdrp", "filament"])
def test_no_sun_no_sky(name):
    p = copy.deepcopy(VALLEY)
    p["sun"] = None
    p["sky"] = None
    model = from_physical(name, p)
    r = model.evaluate(CAMERA, views(), precision="float64")
    assert np.all(r.inscatter == 0) and np.all(np.isfinite(r.transmittance))


def test_ue4_no_sun_colour_is_albedo_sky():
    p = copy.deepcopy(VALLEY)
    p["sun"] = None
    q = from_physical("ue4", p).params
    assert q.InscatteringLightDirection is None
    np.testing.assert_allclose(q.FogInscatteringColor, ALBEDO_SKY)


def test_filament_sun_below_horizon_has_no_lobe():
    p = copy.deepcopy(VALLEY)
    p["sun"]["direction"] = [0.3, -0.2, 0.9]
    assert from_physical("filament", p).params.inScatteringSize < 0


# -- through the compare factory -----------------------------------------------------


def test_build_model_from_scene_with_override():
    model = build_model(get("ue4"), {"FogMaxOpacity": 0.9}, VALLEY)
    assert model.params.FogMaxOpacity == 0.9
    assert model.params.FogDensity == pytest.approx(from_physical("ue4", VALLEY).params.FogDensity)
    model = build_model(get("filament"), {"distance": 5.0}, VALLEY)
    assert model.params.distance == 5.0 and model.params.inScatteringSize > 0


# -- no counterpart ------------------------------------------------------------------

BOX = {"profile": "box", "sigma_t": 0.01, "bounds_min": [-10, 0, -10], "bounds_max": [10, 10, 10]}
HDRP = {"profile": "hdrp", "sigma_t": 0.01, "base_height": 0.0, "falloff": 0.02}
POWER = {"profile": "powerlaw", "sigma_t": 0.01, "start": 0.0, "end": 50.0, "power": 2.0}
EXP = {"profile": "exponential", "sigma_t": 0.01, "falloff": 0.01}
BOUNDED_EXP = {**EXP, "bounds_min": [-10, 0, -10], "bounds_max": [10, 10, 10]}


@pytest.mark.parametrize(
    "name, medium",
    [
        ("ue4", HDRP),
        ("ue4", POWER),
        ("ue4", BOX),
        ("ue4", BOUNDED_EXP),
        ("unity", BOX),
        ("unity", BOUNDED_EXP),
        ("hdrp", POWER),
        ("hdrp", BOX),
        ("filament", HDRP),
        ("filament", POWER),
        ("filament", BOX),
        ("altitude", EXP),
        ("altitude", HDRP),
        ("altitude", BOX),
        ("box", EXP),
        ("box", POWER),
        ("box", BOUNDED_EXP),
    ],
)
def test_no_counterpart_raises_profile(name, medium):
    with pytest.raises(ParameterError) as e:
        from_physical(name, scene(**medium))
    assert e.value.name == "profile"
    assert "valley.xml: medium" in str(e.value) and "'profile'" in str(e.value)


@pytest.mark.parametrize("name", ["hdrp", "filament"])
def test_two_layers_raise(name):
    p = scene(**EXP, density2=0.5, falloff2=0.05, height2=20.0)
    with pytest.raises(ParameterError) as e:
        from_physical(name, p)
    assert e.value.name == "density2"


@pytest.mark.parametrize("name", ["ue4", "unity", "hdrp", "filament"])
def test_coloured_extinction_raises(name):
    with pytest.raises(ParameterError) as e:
        from_physical(name, scene(**{**EXP, "sigma_t": [0.01, 0.02, 0.03]}))
    assert e.value.name == "sigma_t"


# -- the protocols and the registry's fallback ---------------------------------------


@pytest.mark.parametrize("name", ["ue4", "unity", "altitude", "box", "hdrp", "filament"])
def test_builtin_models_follow_the_protocol_and_have_a_mapping(name):
    from fogref.mapping import MAPPINGS, has_mapping
    from fogref.models import FogModel

    model = get(name)()
    assert isinstance(model, FogModel) and model.name == name
    assert name in MAPPINGS and has_mapping(name) and not hasattr(get(name), "from_physical")


def test_unregistered_class_falls_back_to_its_own_from_physical():
    class Custom:
        name = "custom_test"

        def __init__(self, sigma):
            self.sigma = sigma

        @classmethod
        def from_physical(cls, physical):
            return cls(physical.medium.sigma_t)

    ps = PhysicalScene.from_params(VALLEY)
    assert from_physical(Custom, ps).sigma == ps.medium.sigma_t
    assert from_physical(Custom, VALLEY).sigma == ps.medium.sigma_t  # a fogref.params dict is parsed
    with pytest.raises(FogrefError, match="from_physical"):
        from_physical(object, ps)
    with pytest.raises(FogrefError, match="unknown fog model"):
        from_physical("no_such_model", ps)


def test_physical_scene_parser():
    ps = PhysicalScene.from_params(VALLEY)
    np.testing.assert_allclose(ps.sun_direction, SUN, rtol=1e-15)
    assert ps.has_sun and ps.profile == "exponential" and ps.source == "valley.xml: medium"
    assert ps.camera == (0.0, 2.0, 0.0) and ps.sky_radiance == (0.2, 0.3, 0.5)
    p = copy.deepcopy(VALLEY)
    p["sun"], p["sky"], p["camera"] = None, None, None
    ps = PhysicalScene.from_params(p, camera=(1.0, 5.0, 0.0))
    assert not ps.has_sun and ps.sky_radiance == (0.0, 0.0, 0.0) and ps.camera == (1.0, 5.0, 0.0)
    p = copy.deepcopy(VALLEY)
    p["sun"]["direction"] = [0.0, 0.0, 0.0]
    with pytest.raises(ParameterError, match="direction"):
        PhysicalScene.from_params(p)


# -- the scene's view direction ------------------------------------------------------

#: the valley's camera (its sensor's lookat, normalised): forward, and an orthonormal up, right
FORWARD = np.array([0.1401808, 0.3270885, 0.9345386]) / np.linalg.norm([0.1401808, 0.3270885, 0.9345386])
RIGHT = np.cross(FORWARD, [0.0, 1.0, 0.0]) / np.linalg.norm(np.cross(FORWARD, [0.0, 1.0, 0.0]))
UP = np.cross(RIGHT, FORWARD)


@pytest.mark.parametrize(
    "name, param",
    [("threejs", {}), ("playcanvas", {}), ("unity", {"fog_coordinate": "depth"})],
)
def test_eye_depth_is_along_the_scenes_camera(name, param):
    """The models that fog the eye depth take their depth axis from the scene's camera: points
    ``camera + z forward + a right + b up`` have eye depth ``z`` (float64 rounding, 1e-9 m
    tolerance); with the default -z axis the valley's eye depths would be negative."""
    params = copy.deepcopy(VALLEY)
    params["camera"]["forward"] = (3.0 * FORWARD).tolist()  # not normalised: the parser does it
    model = build_model(name, param, params)
    rng = np.random.default_rng(1)
    z = np.geomspace(1.0, 2.0e4, 64)
    a, b = (rng.uniform(-0.5, 0.5, 64) * z for _ in range(2))
    pts = CAMERA + z[:, None] * FORWARD + a[:, None] * RIGHT + b[:, None] * UP
    if name == "threejs":
        depth = model.fog_depth(CAMERA, pts)
    elif name == "playcanvas":
        n, f = model.params.nearClip, model.params.farClip
        depth = model.fog_depth(CAMERA, pts) * (f - n) / f + n  # undo far (z - near) / (far - near)
    else:
        depth = model.fog_coordinate(CAMERA, pts)
    np.testing.assert_allclose(depth, z, rtol=0, atol=1e-9 * z.max())
    assert PhysicalScene.from_params(VALLEY).camera_forward is None  # no view direction: the default
    assert build_model(name, param, VALLEY).params.camera_forward == (0.0, 0.0, -1.0)


def test_scene_file_gives_its_view_direction():
    """``physical_from_scene`` (no Mitsuba) reads the sensor's lookat: forward = target - origin."""
    from fogref.scene.describe import lookat_camera
    from fogref.shipped_scenes import scene_path
    from fogref.study.fit import physical_from_scene

    c = lookat_camera(scene_path("valley"))
    want = np.subtract(c["target"], c["origin"])
    np.testing.assert_allclose(
        physical_from_scene(scene_path("valley")).camera_forward, want / np.linalg.norm(want)
    )
    np.testing.assert_allclose(want / np.linalg.norm(want), FORWARD, atol=1e-7)
