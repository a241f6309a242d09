"""``from_physical`` of the non-Unreal models: Unity, altitude, box, HDRP, Filament.

Each function maps a :class:`~fogref.mapping.physical.PhysicalScene` to the
model that best represents it, exactly where the model can (its extinction
mapping, ``medium_to_*`` in the model's module) and by a documented choice where
it cannot.  Colours follow the convention of :mod:`fogref.mapping.physical`
(``albedo * L_sky``).  A scene without a counterpart raises
:class:`~fogref.errors.ParameterError` naming 'profile', 'density2' or 'sigma_t'.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from fogref.errors import ParameterError
from fogref.mapping.lobe import lobe_fit
from fogref.mapping.physical import PhysicalScene
from fogref.mapping.registry import register_mapping
from fogref.media import NP, ExpLayer, FogMedium, HDRPLayer
from fogref.models.altitude import AltitudeFog, AltitudeFogParams
from fogref.models.box import BoxFog, BoxFogParams
from fogref.models.filament import FilamentFog, medium_to_filament
from fogref.models.hdrp import (
    FROM_PHYSICAL_MAX_FOG_DISTANCE,
    HOMOGENEOUS_BASE_HEIGHT,
    HDRPFog,
    medium_to_hdrp,
)
from fogref.models.unity_builtin import UnityBuiltinFog, medium_to_unity

if TYPE_CHECKING:
    from fogref.models.babylon import BabylonFog
    from fogref.models.bevy import BevyDistanceFog
    from fogref.models.godot import GodotFog
    from fogref.models.playcanvas import PlayCanvasFog
    from fogref.models.threejs import ThreeJSFog

__all__ = [
    "altitude_from_physical",
    "babylon_from_physical",
    "bevy_from_physical",
    "box_from_physical",
    "filament_from_physical",
    "fixed_lobe_amplitude",
    "godot_from_physical",
    "hdrp_from_physical",
    "playcanvas_from_physical",
    "threejs_from_physical",
    "unity_from_physical",
]


@register_mapping("unity")
def unity_from_physical(ps: PhysicalScene) -> UnityBuiltinFog:
    """The Unity built-in fog that best represents a physical scene.

    Always Exp fog on distance (``camera_forward``, for a ``--param fog_coordinate=depth``, is the
    scene's view direction where it names one).  Profile "homogeneous": exact
    (:func:`~fogref.models.unity_builtin.medium_to_unity`, ``fogDensity =
    sigma_t`` [1/m]).  Height profiles ("exponential", "hdrp", "powerlaw") have no
    exact counterpart (Unity's fog does not depend on height); the nearest choice
    is the extinction at the camera, ``fogDensity = sigma_t * rho(camera)``, exact
    for horizontal rays (rays climbing out of the fog get too much of it,
    descending ones too little).  ``fogColor = albedo * sky radiance`` (the sun is
    not represented).  Raises ParameterError naming 'profile' for "box" or any
    bounded fog, 'sigma_t' for a coloured extinction.

    Examples
    --------
    >>> from fogref.media import ExpLayer, FogMedium
    >>> ps = PhysicalScene(FogMedium(sigma_t=0.01, layers=(ExpLayer(1.0, 0.1, 0.0),)), camera=(0.0, 0.0, 0.0))
    >>> unity_from_physical(ps).params.fogDensity
    0.01
    """
    _require_space_filling(ps, "Unity", "Unity's built-in fog fills all space (no bounds)")
    sigma = ps.grey_sigma_t("Unity")
    m = ps.medium
    if not m.is_homogeneous:
        rho = float(np.asarray(m.density(NP, tuple(np.asarray([c]) for c in ps.camera))).reshape(-1)[0])
        m = FogMedium(
            sigma_t=sigma * rho, albedo=m.albedo, g=m.g, layers=(ExpLayer(1.0, 0.0, 0.0),), source=ps.source
        )
    return UnityBuiltinFog(replace(medium_to_unity(m, fogColor=ps.sky_colour()), **_view_axis(ps)))


@register_mapping("altitude")
def altitude_from_physical(ps: PhysicalScene) -> AltitudeFog:
    """The altitude fog of a physical scene (inverse of :func:`~fogref.models.altitude.altitude_to_medium`).

    Needs the "powerlaw" profile (unbounded, grey ``sigma_t``):
    ``_FogStart/_FogEnd/_FogPower = start/end/power`` and ``_FogColor.a =
    sigma_t * density`` [1/m], so the optical depth ``a * I`` is exact; only the
    blend differs (``1 - saturate(tau)`` instead of ``exp(-tau)``).
    ``_FogColor.rgb = albedo * sky radiance`` (the sun is not represented).

    Examples
    --------
    >>> from fogref.media import FogMedium, PowerLawLayer
    >>> ps = PhysicalScene(FogMedium(sigma_t=0.01, layers=(PowerLawLayer(2.0, 0.0, 50.0, 1.0),)))
    >>> altitude_from_physical(ps).params._FogColor[3]
    0.02
    """
    ps.require_profile(
        "altitude fog",
        ("powerlaw",),
        "the altitude fog's density is the power law ((end - y)/(end - start))^power",
    )
    ps.require_unbounded("altitude fog")
    sigma = ps.grey_sigma_t("altitude fog")
    L = ps.medium.layers[0]
    return AltitudeFog(
        AltitudeFogParams(
            _FogStart=L.start,
            _FogEnd=L.end,
            _FogPower=L.power,
            _FogColor=(*ps.sky_colour(), sigma * L.density),
        )
    )


@register_mapping("box")
def box_from_physical(ps: PhysicalScene) -> BoxFog:
    """The box fog of a physical scene (inverse of :func:`~fogref.models.box.box_to_medium`).

    Needs a homogeneous fog inside bounds (profile "box", or "homogeneous" /
    falloff-0 "exponential" with ``bounds_min``/``bounds_max``) and a grey
    ``sigma_t``: mode "beer" with ``density = sigma_t * density`` [1/m] and the
    same box, exactly the physical transmittance.  ``fog_color = albedo * sky
    radiance`` (the sun is not represented).  Raises ParameterError naming
    'profile' otherwise.

    Examples
    --------
    >>> from fogref.media import Box, ExpLayer, FogMedium
    >>> m = FogMedium(sigma_t=0.05, layers=(ExpLayer(1.0, 0.0, 0.0),), bounds=Box((0, 0, 0), (10, 10, 10)))
    >>> box_from_physical(PhysicalScene(m)).params.density
    0.05
    """
    m = ps.medium
    if m.bounds is None:
        raise ParameterError(
            ps.source,
            "profile",
            f"'{ps.profile}' fog is unbounded; box fog needs a box (profile 'box', "
            f"bounds_min and bounds_max)",
        )
    if not m.is_homogeneous:
        raise ParameterError(
            ps.source, "profile", f"'{ps.profile}' varies with height; box fog is homogeneous inside its box"
        )
    sigma = ps.grey_sigma_t("box fog")
    k = sigma * sum(L.density for L in m.layers)
    return BoxFog(
        BoxFogParams(
            box_min=m.bounds.lo, box_max=m.bounds.hi, density=k, fog_color=ps.sky_colour(), mode="beer"
        )
    )


@register_mapping("hdrp")
def hdrp_from_physical(ps: PhysicalScene) -> HDRPFog:
    """The HDRP fog that best represents a physical scene.

    Extinction (grey ``sigma_t`` required):

    * "hdrp": exact (:func:`~fogref.models.hdrp.medium_to_hdrp`).
    * "homogeneous" (or falloff 0): exact, ``baseHeight = 1e7`` m
      (:data:`~fogref.models.hdrp.HOMOGENEOUS_BASE_HEIGHT`: constant density below it).
    * "exponential", one layer ``sigma_t exp(-b (y - h))``: the same exponential
      above ``baseHeight = min(h, camera height)``, held constant below it
      (HDRP's profile); exact for every ray that stays at or above that height.
    * two exponential layers: ParameterError naming 'density2'; "powerlaw",
      "box" or any bounded fog: ParameterError naming 'profile'.

    Colour: ``albedo`` = the medium's albedo and ``color`` = sky radiance, so the
    inscatter is ``albedo * L_sky * (1 - T)`` (the sun is not represented).
    ``maxFogDistance`` = :data:`~fogref.models.hdrp.FROM_PHYSICAL_MAX_FOG_DISTANCE`
    (no truncation of the physical ray).

    Examples
    --------
    >>> from fogref.media import FogMedium, HDRPLayer
    >>> ps = PhysicalScene(FogMedium(sigma_t=0.01, layers=(HDRPLayer(1.0, 5.0, 0.02),)))
    >>> hdrp_from_physical(ps).params.baseHeight
    5.0
    """
    ps.require_profile(
        "HDRP",
        ("hdrp", "homogeneous", "exponential"),
        "HDRP's fog is constant below a base height and exponential above",
    )
    ps.require_unbounded("HDRP")
    sigma = ps.grey_sigma_t("HDRP")
    m = ps.medium
    if len(m.layers) != 1:
        raise ParameterError(ps.source, "density2", "HDRP fog has a single height layer")
    L = m.layers[0]
    if m.is_homogeneous:
        layer = HDRPLayer(density=L.density, base_height=HOMOGENEOUS_BASE_HEIGHT, falloff=0.0)
    elif isinstance(L, HDRPLayer):
        layer = L
    else:  # ExpLayer with falloff > 0
        base = min(L.height, float(ps.camera[1]))
        layer = HDRPLayer(
            density=L.density * math.exp(-L.falloff * (base - L.height)), base_height=base, falloff=L.falloff
        )
    m = FogMedium(sigma_t=sigma, albedo=m.albedo, g=m.g, layers=(layer,), source=ps.source)
    return HDRPFog(
        medium_to_hdrp(
            m, color=tuple(float(x) for x in ps.sky_radiance), maxFogDistance=FROM_PHYSICAL_MAX_FOG_DISTANCE
        )
    )


@register_mapping("filament")
def filament_from_physical(ps: PhysicalScene) -> FilamentFog:
    """The Filament fog that best represents a physical scene.

    Extinction: exact (:func:`~fogref.models.filament.medium_to_filament`) for one
    unbounded grey exponential layer (profiles "exponential" and "homogeneous");
    ``distance`` 0, no cutoff, ``maximumOpacity`` 1.  ``color = albedo * sky
    radiance``.

    Sun (the inscattering lobe), a simple documented choice: the sun's single
    scattering without its attenuation along the view ray,
    ``albedo E p_HG(cos) (1 - T)``, with the Henyey–Greenstein phase replaced by
    its best pure cosine lobe ``c max(cos, 0)^n`` over the sphere
    (:func:`~fogref.mapping.lobe.lobe_fit` with ``isotropic=False``), and the sun
    irradiance dimmed by the fog between the camera and the sun,
    ``T_sun(camera)``.  So ``inScatteringSize = n``, ``lightDirection`` = the
    sun, ``lightColorIntensity = (albedo E T_sun(camera) c, 1)``,
    ``inScatteringStart = 0``.  Without a sun, with the sun at or below the
    horizon, or when the best lobe is 0 (g <= 0): no lobe
    (``inScatteringSize = -1``).  Raises ParameterError naming 'profile' for
    "hdrp", "powerlaw", "box" or any bounded fog, 'density2' for two layers,
    'sigma_t' for a coloured extinction.

    Examples
    --------
    >>> from fogref.media import ExpLayer, FogMedium
    >>> ps = PhysicalScene(FogMedium(sigma_t=0.01, g=-0.2, layers=(ExpLayer(1.0, 0.02, 0.0),)))
    >>> filament_from_physical(ps).params.inScatteringSize
    -1.0
    """
    ps.require_profile(
        "Filament", ("exponential", "homogeneous"), "Filament's fog is one exponential height layer"
    )
    ps.require_unbounded("Filament")
    ps.grey_sigma_t("Filament")
    if len(ps.medium.layers) != 1:
        raise ParameterError(ps.source, "density2", "Filament fog has a single exponential layer")
    kw = {
        "distance": 0.0,
        "cutOffDistance": math.inf,
        "maximumOpacity": 1.0,
        "color": ps.sky_colour(),
        "inScatteringStart": 0.0,
        "inScatteringSize": -1.0,
    }
    w = ps.sun_direction
    if ps.has_sun and w[1] > 0:
        lobe = lobe_fit(ps.medium.g, isotropic=False)
        if lobe["exponent"] is not None:
            c = lobe["lobe"] / (4.0 * math.pi)
            sun = ps.albedo * np.asarray(ps.sun_irradiance) * ps.sun_transmittance_at_camera() * c
            kw.update(
                inScatteringSize=float(lobe["exponent"]),
                lightDirection=tuple(float(x) for x in w),
                lightColorIntensity=(*(float(x) for x in sun), 1.0),
            )
    return FilamentFog(medium_to_filament(ps.medium, **kw))


# -- Godot, Bevy, three.js -----------------------------------------------------------


def _view_axis(ps: PhysicalScene) -> dict:
    """``{"camera_forward": ...}``: the scene's view direction for the models that fog the eye
    depth along it, or ``{}`` (their default, -z) where the scene names none."""
    return {} if ps.camera_forward is None else {"camera_forward": tuple(ps.camera_forward)}


def _density_at_camera(ps: PhysicalScene) -> float:
    """``rho(camera)``: the medium's relative density at the camera (1 for a homogeneous fog)."""
    m = ps.medium
    if m.is_homogeneous:
        return float(sum(L.density for L in m.layers))
    return float(np.asarray(m.density(NP, tuple(np.asarray([c]) for c in ps.camera))).reshape(-1)[0])


#: The profiles an engine fog that fills all space can stand for (no box, no bounds).
SPACE_FILLING_PROFILES = ("homogeneous", "exponential", "hdrp", "powerlaw")


def _require_space_filling(ps: PhysicalScene, model: str, why: str) -> None:
    """ParameterError naming 'profile' unless ``ps`` is an unbounded fog of one of
    :data:`SPACE_FILLING_PROFILES` (``why``: what ``model``'s fog is, for the message)."""
    ps.require_profile(model, SPACE_FILLING_PROFILES, why)
    ps.require_unbounded(model)


def _grey_extinction_at_camera(ps: PhysicalScene, model: str) -> float:
    """``sigma_t rho(camera)`` [1/m]: the grey extinction at the camera (ParameterError naming
    'sigma_t' for a coloured one, see :meth:`PhysicalScene.grey_sigma_t`)."""
    return ps.grey_sigma_t(model) * _density_at_camera(ps)


def fixed_lobe_amplitude(g: float, exponent: float, n_quad: int = 256) -> float:
    """Least-squares ``c`` [1/sr] of ``c max(mu, 0)^n`` against the HG phase ``p_g(mu)`` over the sphere.

    For engines whose lobe exponent is fixed (Godot: ``n = 8``): ``c = int_0^1 p mu^n dmu /
    int_0^1 mu^(2n) dmu = (2n + 1) int_0^1 p_g(mu) mu^n dmu`` (Gauss–Legendre on [0, 1]).

    Examples
    --------
    >>> round(fixed_lobe_amplitude(0.0, 8.0) * 4 * math.pi, 6)    # isotropic: (2n + 1)/(n + 1)
    1.888889
    """
    x, w = np.polynomial.legendre.leggauss(n_quad)
    mu, w = 0.5 * (x + 1.0), 0.5 * w
    p = (1.0 - g * g) / (4.0 * math.pi * (1.0 + g * g - 2.0 * g * mu) ** 1.5)
    return float((2.0 * exponent + 1.0) * np.sum(w * p * mu**exponent))


@register_mapping("godot")
def godot_from_physical(ps: PhysicalScene) -> GodotFog:
    """The Godot 4 environment fog that best represents a physical scene.

    Exponential mode (``fog_density`` [1/m] on distance), no height fog.  Profile
    "homogeneous": exact, ``fog_density = sigma_t`` and ``fog_sky_affect = 1 -
    exp(-sigma_t SKY_DISTANCE)`` (the sky pixels' transmittance).  Height profiles
    ("exponential", "hdrp", "powerlaw") have **no exact counterpart**: Godot's height fog
    (``1 - exp((y - fog_height) fog_height_density)`` of the end point, combined with ``max``)
    is not an optical depth; the nearest choice is the extinction at the camera (exact for
    horizontal rays), as for Unity, with the height fog off.  ``fog_light_color = albedo *
    sky radiance`` (energy 1), no aerial perspective.

    Sun: Godot's lobe has the fixed exponent 8; its best amplitude against the HG phase is
    :func:`fixed_lobe_amplitude`, and ``sun_color = albedo E T_sun(camera) c`` with
    ``fog_sun_scatter = 1`` (no sun, or the sun at or below the horizon: no lobe).
    Raises ParameterError naming 'profile' for "box" or bounded fog, 'sigma_t' for a
    coloured extinction.

    Examples
    --------
    >>> from fogref.media import ExpLayer, FogMedium
    >>> ps = PhysicalScene(FogMedium(sigma_t=0.01, layers=(ExpLayer(1.0, 0.0, 0.0),)))
    >>> godot_from_physical(ps).params.fog_density
    0.01
    """
    from fogref.models.base import SKY_DISTANCE
    from fogref.models.godot import SUN_SCATTER_EXPONENT, GodotFog, GodotFogParams

    _require_space_filling(ps, "Godot", "Godot's environment fog fills all space (no bounds)")
    sigma = _grey_extinction_at_camera(ps, "Godot")
    kw: dict[str, Any] = {
        "fog_mode": "exponential",
        "fog_density": sigma,
        "fog_height_density": 0.0,
        "fog_light_color": ps.sky_colour(),
        "fog_light_energy": 1.0,
        "fog_aerial_perspective": 0.0,
        "fog_sky_affect": float(-math.expm1(-sigma * SKY_DISTANCE)),
        "sky_distance": SKY_DISTANCE,
        "sky_color": tuple(float(x) for x in np.asarray(ps.sky_radiance)),
        "fog_sun_scatter": 0.0,
    }
    w = ps.sun_direction
    if ps.has_sun and w[1] > 0:
        c = fixed_lobe_amplitude(ps.medium.g, SUN_SCATTER_EXPONENT)
        sun = ps.albedo * np.asarray(ps.sun_irradiance) * ps.sun_transmittance_at_camera() * c
        kw.update(
            fog_sun_scatter=1.0,
            sun_direction=tuple(float(x) for x in w),
            sun_color=tuple(float(x) for x in sun),
        )
    return GodotFog(GodotFogParams(**kw))


@register_mapping("bevy")
def bevy_from_physical(ps: PhysicalScene) -> BevyDistanceFog:
    """The Bevy ``DistanceFog`` that best represents a physical scene.

    ``FogFalloff::Atmospheric`` with ``extinction = inscattering = sigma_t`` [1/m] (RGB: a
    coloured extinction is represented exactly).  Profile "homogeneous": exact
    (:func:`~fogref.models.bevy.medium_to_bevy`).  Height profiles ("exponential", "hdrp",
    "powerlaw") have **no exact counterpart** (Bevy's fog has no height term): the
    extinction at the camera, exact for horizontal rays.  ``color = (albedo * sky radiance,
    1)``.

    Sun (the directional lobe), as for Filament: the best pure cosine lobe ``c max(cos,
    0)^n`` for the HG phase (:func:`~fogref.mapping.lobe.lobe_fit`, ``isotropic=False``):
    ``directional_light_exponent = n``, ``light_color = E`` (the sun irradiance),
    ``directional_light_color = (albedo T_sun(camera) c, 1)``.  No sun, the sun at or
    below the horizon, or no lobe (g <= 0): alpha 0 (no lobe).  Raises ParameterError
    naming 'profile' for "box" or bounded fog.

    Examples
    --------
    >>> from fogref.media import ExpLayer, FogMedium
    >>> ps = PhysicalScene(FogMedium(sigma_t=(0.01, 0.02, 0.03), layers=(ExpLayer(1.0, 0.0, 0.0),)))
    >>> bevy_from_physical(ps).params.extinction
    (0.01, 0.02, 0.03)
    """
    from fogref.models.bevy import BevyDistanceFog, medium_to_bevy

    _require_space_filling(ps, "Bevy", "Bevy's DistanceFog fills all space (no bounds)")
    m = ps.medium
    rho = _density_at_camera(ps)
    m = FogMedium(
        sigma_t=tuple(float(x) * rho for x in np.asarray(m.sigma_t, dtype=np.float64)),
        albedo=m.albedo,
        g=m.g,
        layers=(ExpLayer(1.0, 0.0, 0.0),),
        source=ps.source,
    )
    kw: dict[str, Any] = {"color": (*ps.sky_colour(), 1.0), "directional_light_color": (0.0, 0.0, 0.0, 0.0)}
    w = ps.sun_direction
    if ps.has_sun and w[1] > 0:
        lobe = lobe_fit(ps.medium.g, isotropic=False)
        if lobe["exponent"] is not None:
            c = lobe["lobe"] / (4.0 * math.pi)
            dl = ps.albedo * ps.sun_transmittance_at_camera() * c
            kw.update(
                directional_light_exponent=float(lobe["exponent"]),
                light_direction=tuple(float(x) for x in w),
                light_color=tuple(float(x) for x in ps.sun_irradiance),
                directional_light_color=(*(float(x) for x in dl), 1.0),
            )
    return BevyDistanceFog(medium_to_bevy(m, **kw))


@register_mapping("threejs")
def threejs_from_physical(ps: PhysicalScene) -> ThreeJSFog:
    """The three.js fog nearest to a physical scene: ``FogExp2``, **never exact**.

    three.js has no Beer–Lambert mode, no height term and no sun.  ``FogExp2`` with
    ``density = sigma_t rho(camera)`` [1/m] has the physical transmittance ``exp(-1)`` at the
    depth ``1/density`` on the camera axis (:func:`~fogref.models.threejs.threejs_sigma`),
    too little fog nearer and too much farther (exp² against exp), and it fogs the eye
    depth, not the distance: ``camera_forward`` is the scene's view direction
    (:attr:`~fogref.mapping.physical.PhysicalScene.camera_forward`; -z where it names none).
    ``color = albedo * sky radiance``.  Raises
    ParameterError naming 'profile' for "box" or bounded fog, 'sigma_t' for a coloured
    extinction.

    Examples
    --------
    >>> from fogref.media import ExpLayer, FogMedium
    >>> ps = PhysicalScene(FogMedium(sigma_t=0.01, layers=(ExpLayer(1.0, 0.0, 0.0),)))
    >>> threejs_from_physical(ps).params.density
    0.01
    """
    from fogref.models.threejs import ThreeFogParams, ThreeJSFog

    _require_space_filling(ps, "three.js", "three.js fog fills all space (no bounds)")
    sigma = _grey_extinction_at_camera(ps, "three.js")
    return ThreeJSFog(ThreeFogParams(mode="FogExp2", density=sigma, color=ps.sky_colour(), **_view_axis(ps)))


@register_mapping("babylon")
def babylon_from_physical(ps: PhysicalScene) -> BabylonFog:
    """The Babylon.js fog that best represents a physical scene: ``FOGMODE_EXP`` on the distance.

    Profile "homogeneous": exact (``fogDensity = sigma_t / ln(2.71828)`` [1/m], inverting the
    shader's ``E``; :func:`~fogref.models.babylon.babylon_to_medium`).  Height profiles have no
    counterpart (no height term); the nearest choice is the extinction at the camera, exact for
    horizontal rays.  ``fogColor = albedo * sky radiance`` (linear; Babylon's
    ``StandardMaterial`` writes it to the canvas unconverted).  Raises ParameterError naming
    'profile' for "box" or bounded fog, 'sigma_t' for a coloured extinction.

    Examples
    --------
    >>> from fogref.media import ExpLayer, FogMedium
    >>> ps = PhysicalScene(FogMedium(sigma_t=0.01, layers=(ExpLayer(1.0, 0.0, 0.0),)))
    >>> round(babylon_from_physical(ps).params.fogDensity, 9)
    0.010000007
    """
    from fogref.models.babylon import BabylonFog, BabylonFogParams, E

    _require_space_filling(ps, "Babylon.js", "Babylon.js fog fills all space (no bounds)")
    sigma = _grey_extinction_at_camera(ps, "Babylon.js")
    density = sigma / math.log(E)
    return BabylonFog(BabylonFogParams(fogMode="EXP", fogDensity=density, fogColor=ps.sky_colour()))


@register_mapping("playcanvas")
def playcanvas_from_physical(ps: PhysicalScene) -> PlayCanvasFog:
    """The PlayCanvas fog nearest to a physical scene: ``FOG_EXP``, **never exact**.

    ``density = sigma_t rho(camera)`` [1/m]; PlayCanvas fogs ``far (z - near)/(far - near)`` of
    the eye depth z (camera clip planes at PlayCanvas's defaults, 0.1 and 1000 m; the depth axis
    ``camera_forward`` is the scene's view direction, -z where it names none), not the
    distance, and has no height term.  ``color = (albedo * sky radiance)^(1/2.2)``: the engine's
    gamma-encoded ``scene.fog.color``, which it raises to 2.2.  Raises ParameterError naming
    'profile' for "box" or bounded fog, 'sigma_t' for a coloured extinction.

    Examples
    --------
    >>> from fogref.media import ExpLayer, FogMedium
    >>> ps = PhysicalScene(FogMedium(sigma_t=0.01, layers=(ExpLayer(1.0, 0.0, 0.0),)))
    >>> playcanvas_from_physical(ps).params.density
    0.01
    """
    from fogref.models.playcanvas import PlayCanvasFog, PlayCanvasFogParams

    _require_space_filling(ps, "PlayCanvas", "PlayCanvas fog fills all space (no bounds)")
    sigma = _grey_extinction_at_camera(ps, "PlayCanvas")
    color = tuple(float(c) ** (1 / 2.2) for c in ps.sky_colour())
    return PlayCanvasFog(PlayCanvasFogParams(type="exp", density=sigma, color=color, **_view_axis(ps)))
