"""Each non-Unreal model and the physical fog, both ways: ``X_from_physical`` and ``X_to_medium``.

``X_from_physical`` maps a :class:`~fogref.mapping.physical.PhysicalScene` to the model that
best represents it, exactly where the model can and by a documented choice where it cannot.
Colours follow the convention of :mod:`fogref.mapping.physical` (``albedo * L_sky``).  A scene
without a counterpart raises :class:`~fogref.errors.ParameterError` naming 'profile',
'density2' or 'sigma_t'.

``X_to_medium`` is the inverse for the extinction: the :class:`~fogref.media.FogMedium`
whose transmittance the engine's settings give (exact where the engine's fog is
Beer-Lambert; a documented nearest medium where it is not).  The fit's exact extinction
(:attr:`fogref.mapping.free.FitSpec.exact_medium`, used by :mod:`fogref.mapping.translate`)
calls these.  Unreal's pair is :func:`fogref.mapping.unreal.ue4_from_physical` and
:func:`fogref.models.ue4.ue4_to_medium`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from fogref.errors import ParameterError
from fogref.mapping.lobe import lobe_fit
from fogref.mapping.physical import PhysicalScene
from fogref.mapping.registry import register_mapping
from fogref.media import NP, Box, ExpLayer, FogMedium, HDRPLayer, PowerLawLayer
from fogref.models.altitude import AltitudeFog, AltitudeFogParams
from fogref.models.babylon import BabylonFog, BabylonFogParams, E
from fogref.models.base import SKY_DISTANCE
from fogref.models.bevy import BevyDistanceFog, BevyFogParams
from fogref.models.box import BoxFog, BoxFogParams
from fogref.models.filament import FilamentFog, FilamentFogParams
from fogref.models.godot import SUN_SCATTER_EXPONENT, GodotFog, GodotFogParams
from fogref.models.hdrp import LAYER_DEPTH_TO_H, HDRPFog, HDRPFogParams
from fogref.models.playcanvas import PlayCanvasFog, PlayCanvasFogParams
from fogref.models.threejs import ThreeFogParams, ThreeJSFog
from fogref.models.unity_builtin import UnityBuiltinFog, UnityFogParams

__all__ = [
    "FROM_PHYSICAL_MAX_FOG_DISTANCE",
    "HOMOGENEOUS_BASE_HEIGHT",
    "altitude_from_physical",
    "altitude_to_medium",
    "babylon_from_physical",
    "babylon_to_medium",
    "bevy_from_physical",
    "bevy_sigma",
    "bevy_to_medium",
    "box_from_physical",
    "box_to_medium",
    "filament_from_physical",
    "filament_to_medium",
    "fixed_lobe_amplitude",
    "godot_from_physical",
    "godot_to_medium",
    "hdrp_from_physical",
    "hdrp_to_medium",
    "playcanvas_from_physical",
    "threejs_from_physical",
    "threejs_sigma",
    "unity_from_physical",
    "unity_sigma",
    "unity_to_medium",
]

#: :func:`hdrp_from_physical`: base height [m] that makes HDRP's fog homogeneous everywhere below it.
HOMOGENEOUS_BASE_HEIGHT = 1.0e7
#: :func:`hdrp_from_physical`: maxFogDistance [m], the distance over which sky pixels are
#: fogged: far enough to stand for the physical sky ray's infinite one.
FROM_PHYSICAL_MAX_FOG_DISTANCE = 1.0e7


def _homogeneous(sigma_t: Any, albedo: Any, g: float, source: str, bounds: Box | None = None) -> FogMedium:
    """The homogeneous medium of extinction ``sigma_t`` [1/m] (one number or RGB), inside ``bounds``."""
    return FogMedium(
        sigma_t=sigma_t, albedo=albedo, g=g, layers=(ExpLayer(1.0, 0.0, 0.0),), bounds=bounds, source=source
    )


def _medium_at_camera(ps: PhysicalScene) -> FogMedium:
    """The homogeneous medium of ``ps``'s extinction at the camera, ``sigma_t rho(camera)`` [1/m]
    (RGB): the nearest to ``ps`` for a fog without a height term, exact for horizontal rays."""
    rho = _density_at_camera(ps)
    m = ps.medium
    sigma = tuple(float(x) * rho for x in np.asarray(m.sigma_t, dtype=np.float64))
    return _homogeneous(sigma, m.albedo, m.g, ps.source)


@register_mapping("unity")
def unity_from_physical(ps: PhysicalScene) -> UnityBuiltinFog:
    """The Unity built-in fog that best represents a physical scene.

    Always Exp fog on distance (``camera_forward``, for a ``--param fog_coordinate=depth``, is the
    scene's view direction where it names one).  Profile "homogeneous": exact (``fogDensity =
    sigma_t`` [1/m], the inverse of :func:`unity_to_medium`).  Height profiles ("exponential",
    "hdrp", "powerlaw") have no exact counterpart (Unity's fog does not depend on height); the
    nearest choice is the extinction at the camera, ``fogDensity = sigma_t * rho(camera)``, exact
    for horizontal rays (rays climbing out of the fog get too much of it, descending ones too
    little).  ``fogColor = albedo * sky radiance`` (the sun is
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
    ps.grey_sigma_t("Unity")
    density = _medium_at_camera(ps).grey_sigma_t("Unity")
    kw = {"fogColor": ps.sky_colour(), "fog_coordinate": "distance", **_view_axis(ps)}
    return UnityBuiltinFog(UnityFogParams(fogMode="exp", fogDensity=density, **kw))


def unity_sigma(params: UnityFogParams, reference_distance: float | None = None) -> float:
    """Extinction [1/m] of the homogeneous medium nearest to ``params``.

    Exp: ``density`` (exact on distance).  Exp2: ``density^2 r`` (equal
    transmittance ``exp(-(density r)^2)`` at ``r``, default ``1/density``).
    Linear: ``-ln(T(r)) / r`` with ``T(r) = (end - r)/(end - start)`` at ``r``
    (default ``(start + end)/2``).

    Examples
    --------
    >>> unity_sigma(UnityFogParams(fogMode="exp2", fogDensity=0.03), reference_distance=10.0)
    0.009
    """
    if params.fogMode == "exp":
        return params.fogDensity
    if params.fogMode == "exp2":
        r = reference_distance or (1.0 / params.fogDensity if params.fogDensity > 0 else 1.0)
        return params.fogDensity**2 * r
    s, e = params.fogStartDistance, params.fogEndDistance
    r = reference_distance if reference_distance is not None else 0.5 * (s + e)
    T = min(max((e - r) / (e - s), 1e-12), 1.0)
    return -math.log(T) / r if r > 0 else 0.0


def unity_to_medium(
    params: UnityFogParams,
    reference_distance: float | None = None,
    albedo: Any = (1.0, 1.0, 1.0),
    g: float = 0.0,
) -> FogMedium:
    """Homogeneous :class:`~fogref.media.FogMedium` for ``params`` (see :func:`unity_sigma`).

    Examples
    --------
    >>> unity_to_medium(UnityFogParams(fogMode="exp", fogDensity=0.02)).sigma_t
    (0.02, 0.02, 0.02)
    """
    return _homogeneous(unity_sigma(params, reference_distance), albedo, g, "<unity_to_medium>")


@register_mapping("altitude")
def altitude_from_physical(ps: PhysicalScene) -> AltitudeFog:
    """The altitude fog of a physical scene (inverse of :func:`altitude_to_medium`).

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


def altitude_to_medium(params: AltitudeFogParams, albedo: Any = (1.0, 1.0, 1.0), g: float = 0.0) -> FogMedium:
    """The medium ``sigma_t = _FogColor.a * T(y)`` [1/m]: its optical depth is ``a * I``.

    Examples
    --------
    >>> altitude_to_medium(AltitudeFogParams(_FogColor=(1.0, 1.0, 1.0, 0.02))).sigma_t
    (0.02, 0.02, 0.02)
    """
    return FogMedium(
        sigma_t=params._FogColor[3],
        albedo=albedo,
        g=g,
        layers=(
            PowerLawLayer(density=1.0, start=params._FogStart, end=params._FogEnd, power=params._FogPower),
        ),
        source="<altitude_to_medium>",
    )


@register_mapping("box")
def box_from_physical(ps: PhysicalScene) -> BoxFog:
    """The box fog of a physical scene (inverse of :func:`box_to_medium`).

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


def box_to_medium(
    params: BoxFogParams, reference_chord: float | None = None, albedo: Any = (1.0, 1.0, 1.0), g: float = 0.0
) -> FogMedium:
    """The homogeneous medium ``sigma_t`` [1/m] inside :class:`~fogref.media.Box`.

    "thickness"/"beer": ``sigma_t = k`` (optical depth ``k t`` exactly; "beer" is
    then exact).  "ratio": nearest fit, equal opacity at the far wall of a chord
    of length ``reference_chord`` (default: the box's smallest side):
    ``1 - exp(-sigma L) = min(k, 1 - 1e-6)``.

    Examples
    --------
    >>> box_to_medium(BoxFogParams(density=0.05, mode="beer")).sigma_t
    (0.05, 0.05, 0.05)
    """
    if params.mode == "ratio":
        L = reference_chord or min(h - l for l, h in zip(params.box_min, params.box_max))
        sigma = -math.log1p(-min(params.density, 1.0 - 1e-6)) / L
    else:
        sigma = params.density
    return _homogeneous(sigma, albedo, g, "<box_to_medium>", Box(params.box_min, params.box_max))


@register_mapping("hdrp")
def hdrp_from_physical(ps: PhysicalScene) -> HDRPFog:
    """The HDRP fog that best represents a physical scene.

    Extinction (grey ``sigma_t`` required):

    * "hdrp": exact (the inverse of :func:`hdrp_to_medium`; ``maximumHeight = baseHeight +
      H ln(1000)`` for the layer's scale height ``H``).
    * "homogeneous" (or falloff 0): exact, ``baseHeight = 1e7`` m
      (:data:`HOMOGENEOUS_BASE_HEIGHT`: constant density below it).
    * "exponential", one layer ``sigma_t exp(-b (y - h))``: the same exponential
      above ``baseHeight = min(h, camera height)``, held constant below it
      (HDRP's profile); exact for every ray that stays at or above that height.
    * two exponential layers: ParameterError naming 'density2'; "powerlaw",
      "box" or any bounded fog: ParameterError naming 'profile'.

    Colour: ``albedo`` = the medium's albedo and ``color`` = sky radiance, so the
    inscatter is ``albedo * L_sky * (1 - T)`` (the sun is not represented).
    ``maxFogDistance`` = :data:`FROM_PHYSICAL_MAX_FOG_DISTANCE`
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
    depth = (1.0 / layer.falloff) / LAYER_DEPTH_TO_H if layer.falloff > 0 else 1e9
    return HDRPFog(
        HDRPFogParams(
            meanFreePath=1.0 / (sigma * layer.density),
            baseHeight=layer.base_height,
            maximumHeight=layer.base_height + depth,
            albedo=m.albedo,
            color=tuple(float(x) for x in ps.sky_radiance),
            maxFogDistance=FROM_PHYSICAL_MAX_FOG_DISTANCE,
        )
    )


def hdrp_to_medium(params: HDRPFogParams, g: float = 0.0) -> FogMedium:
    """Exact medium: ``sigma_t = 1/meanFreePath`` [1/m] with a :class:`~fogref.media.HDRPLayer`.

    Examples
    --------
    >>> hdrp_to_medium(HDRPFogParams(meanFreePath=50.0)).sigma_t
    (0.02, 0.02, 0.02)
    """
    H = float(params.scale_height(np.float64))
    return FogMedium(
        sigma_t=1.0 / params.meanFreePath,
        albedo=params.albedo,
        g=g,
        layers=(HDRPLayer(density=1.0, base_height=params.baseHeight, falloff=1.0 / H),),
        source="<hdrp_to_medium>",
    )


@register_mapping("filament")
def filament_from_physical(ps: PhysicalScene) -> FilamentFog:
    """The Filament fog that best represents a physical scene.

    Extinction: exact (the inverse of :func:`filament_to_medium`) for one
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
    sigma = ps.grey_sigma_t("Filament")
    if len(ps.medium.layers) != 1:
        raise ParameterError(ps.source, "density2", "Filament fog has a single exponential layer")
    kw: dict[str, Any] = {
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
    L = ps.medium.layers[0]
    p = FilamentFogParams(density=sigma * L.density, heightFalloff=L.falloff, height=L.height, **kw)
    return FilamentFog(p)


def filament_to_medium(params: FilamentFogParams, albedo: Any = (1.0, 1.0, 1.0), g: float = 0.0) -> FogMedium:
    """Exact medium ``sigma_t = density`` [1/m], ``ExpLayer(1, heightFalloff, height)``.

    Examples
    --------
    >>> filament_to_medium(FilamentFogParams(density=0.02, heightFalloff=0.1)).layers[0].falloff
    0.1
    """
    return FogMedium(
        sigma_t=params.density,
        albedo=albedo,
        g=g,
        layers=(ExpLayer(1.0, params.heightFalloff, params.height),),
        source="<filament_to_medium>",
    )


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


def godot_to_medium(params: GodotFogParams, albedo: Any = (1.0, 1.0, 1.0), g: float = 0.0) -> FogMedium:
    """The homogeneous medium ``sigma_t = fog_density`` [1/m] (exact for the exponential
    mode without height fog; ParameterError naming 'fog_mode' or 'fog_height_density' otherwise).

    Examples
    --------
    >>> float(godot_to_medium(GodotFogParams(fog_density=0.02)).sigma_t[0])
    0.02
    """
    src = "<godot_to_medium>"
    if params.fog_mode != "exponential":
        raise ParameterError(src, "fog_mode", "only the exponential mode has a physical counterpart")
    if params.fog_height_density != 0.0:
        raise ParameterError(src, "fog_height_density", "Godot's height fog is not an optical depth")
    return _homogeneous(params.fog_density, albedo, g, src)


@register_mapping("bevy")
def bevy_from_physical(ps: PhysicalScene) -> BevyDistanceFog:
    """The Bevy ``DistanceFog`` that best represents a physical scene.

    ``FogFalloff::Atmospheric`` with ``extinction = inscattering = sigma_t`` [1/m] (RGB: a
    coloured extinction is represented exactly).  Profile "homogeneous": exact (the inverse
    of :func:`bevy_to_medium`).  Height profiles ("exponential", "hdrp",
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
    _require_space_filling(ps, "Bevy", "Bevy's DistanceFog fills all space (no bounds)")
    s = tuple(float(x) for x in _medium_at_camera(ps).sigma_t)
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
    return BevyDistanceFog(BevyFogParams(falloff="Atmospheric", extinction=s, inscattering=s, **kw))


def bevy_sigma(params: BevyFogParams, reference_distance: float | None = None) -> tuple:
    """RGB extinction [1/m] of the homogeneous medium nearest to ``params``.

    Exponential: ``density`` (exact); Atmospheric: ``extinction`` (exact for the
    transmittance); ExponentialSquared: ``density^2 r`` (equal transmittance at ``r``,
    default ``1/density``); Linear: ``-ln(T(r))/r`` at ``r`` (default ``(start + end)/2``).
    All for a fog alpha of 1.

    Examples
    --------
    >>> bevy_sigma(BevyFogParams(falloff="Atmospheric", extinction=(0.1, 0.2, 0.3)))
    (0.1, 0.2, 0.3)
    """
    if params.falloff == "Atmospheric":
        return tuple(params.extinction)
    if params.falloff == "Exponential":
        return (params.density,) * 3
    if params.falloff == "ExponentialSquared":
        if params.density <= 0:
            return (0.0,) * 3
        r = reference_distance or 1.0 / params.density
        return (params.density**2 * r,) * 3
    s, e = params.start, params.end
    r = reference_distance if reference_distance is not None else 0.5 * (s + e)
    T = min(max((e - r) / (e - s), 1e-300), 1.0)
    return (-math.log(T) / r if r > 0 else 0.0,) * 3


def bevy_to_medium(
    params: BevyFogParams,
    reference_distance: float | None = None,
    albedo: Any = (1.0, 1.0, 1.0),
    g: float = 0.0,
) -> FogMedium:
    """Homogeneous :class:`~fogref.media.FogMedium` for ``params`` (see :func:`bevy_sigma`).

    Examples
    --------
    >>> bevy_to_medium(BevyFogParams(falloff="Exponential", density=0.01)).sigma_t
    (0.01, 0.01, 0.01)
    """
    return _homogeneous(bevy_sigma(params, reference_distance), albedo, g, "<bevy_to_medium>")


@register_mapping("threejs")
def threejs_from_physical(ps: PhysicalScene) -> ThreeJSFog:
    """The three.js fog nearest to a physical scene: ``FogExp2``, **never exact**.

    three.js has no Beer–Lambert mode, no height term and no sun.  ``FogExp2`` with
    ``density = sigma_t rho(camera)`` [1/m] has the physical transmittance ``exp(-1)`` at the
    depth ``1/density`` on the camera axis (:func:`threejs_sigma`),
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
    _require_space_filling(ps, "three.js", "three.js fog fills all space (no bounds)")
    sigma = _grey_extinction_at_camera(ps, "three.js")
    return ThreeJSFog(ThreeFogParams(mode="FogExp2", density=sigma, color=ps.sky_colour(), **_view_axis(ps)))


def threejs_sigma(params: ThreeFogParams, reference_depth: float | None = None) -> float:
    """Extinction [1/m] of the homogeneous medium with the same transmittance at ``reference_depth``.

    FogExp2: ``density^2 r`` (default ``r = 1/density``: ``sigma = density``).  Fog:
    ``-ln(1 - smoothstep(near, far, r))/r`` (default ``r = (near + far)/2``).  Exact only at
    ``r`` on the camera axis (three.js fogs the eye depth, and exp2 is not Beer–Lambert).

    Examples
    --------
    >>> threejs_sigma(ThreeFogParams(mode="FogExp2", density=0.02))
    0.02
    """
    if params.mode == "FogExp2":
        if params.density <= 0:
            return 0.0
        r = reference_depth or 1.0 / params.density
        return params.density**2 * r
    r = reference_depth if reference_depth is not None else 0.5 * (params.near + params.far)
    t = min(max((r - params.near) / (params.far - params.near), 0.0), 1.0)
    f = t * t * (3 - 2 * t)
    T = min(max(1.0 - f, 1e-300), 1.0)
    return -math.log(T) / r if r > 0 else 0.0


@register_mapping("babylon")
def babylon_from_physical(ps: PhysicalScene) -> BabylonFog:
    """The Babylon.js fog that best represents a physical scene: ``FOGMODE_EXP`` on the distance.

    Profile "homogeneous": exact (``fogDensity = sigma_t / ln(2.71828)`` [1/m], inverting the
    shader's ``E``; the inverse of :func:`babylon_to_medium`).  Height profiles have no
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
    _require_space_filling(ps, "Babylon.js", "Babylon.js fog fills all space (no bounds)")
    sigma = _grey_extinction_at_camera(ps, "Babylon.js")
    density = sigma / math.log(E)
    return BabylonFog(BabylonFogParams(fogMode="EXP", fogDensity=density, fogColor=ps.sky_colour()))


def babylon_to_medium(params: BabylonFogParams, albedo: Any = (1.0, 1.0, 1.0), g: float = 0.0) -> FogMedium:
    """The homogeneous medium of ``EXP`` fog: ``sigma_t = fogDensity ln(E)`` [1/m] (exact).

    ``EXP2`` and ``LINEAR`` have no physical counterpart: ParameterError naming 'fogMode'.

    >>> round(babylon_to_medium(BabylonFogParams(fogMode="EXP", fogDensity=0.5)).sigma_t[0], 8)
    0.49999966
    """
    if params.fogMode != "EXP":
        raise ParameterError(
            "<babylon_to_medium>", "fogMode", f"only EXP is Beer-Lambert, got {params.fogMode}"
        )
    return _homogeneous(params.fogDensity * math.log(E), albedo, g, "<babylon_to_medium>")


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
    _require_space_filling(ps, "PlayCanvas", "PlayCanvas fog fills all space (no bounds)")
    sigma = _grey_extinction_at_camera(ps, "PlayCanvas")
    color = tuple(float(c) ** (1 / 2.2) for c in ps.sky_colour())
    return PlayCanvasFog(PlayCanvasFogParams(type="exp", density=sigma, color=color, **_view_axis(ps)))
