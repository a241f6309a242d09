"""Unreal's Exponential Height Fog settings -> the fog Unreal's path tracer renders.

Unreal's path tracer (UE 5.x) renders its own physical fog built from the fog
component (sources and what was verified: :mod:`fogref.media.ue_pathtracer`):
two exponential layers of density ``0.5 * FogDensity/1000 * VolumetricFogExtinctionScale``
per cm, clamped below the fog height to ``r.PathTracing.FogDensityClamp`` times that
density, inside a vertical cylinder centred on the camera of radius
``VolumetricFogStartDistance + VolumetricFogDistance``, with ``VolumetricFogAlbedo``
and an HG phase of ``VolumetricFogScatteringDistribution``.  This module maps the
editor settings onto the ``heightfog`` profile ``"ue_pathtracer"`` (y-up, metres),
so ``fogref render`` renders "what UE's path tracer renders" (:func:`rewrite_scene`;
``fogref scene --ue-pathtracer`` writes such a scene), and onto the same fog without the
clamp and the cylinder (:func:`exact_medium`: the physics the path tracer approximates;
``fogref scene --ue-pathtracer --ue-exact``).

Units: Unreal is z-up, cm, ``2^(-F z)`` per cm with ``F = FogHeightFalloff/1000``;
fogref is y-up, metres, ``exp(-b y)``: ``sigma = 100 * 0.5 * ES * FogDensity/1000``
[1/m] at the fog height, ``b = 100 ln(2) max(FogHeightFalloff, 0.001)/1000`` [1/m].
Compare the raster fog (:func:`fogref.models.ue4.unreal_to_sigma`):
``100 (ln 2)^2 FogDensity/1000``; the path tracer's extinction is
``0.5 / (ln 2)^2 = 1.0407`` times the raster fog's at ``VolumetricFogExtinctionScale = 1``.

The editor values the path tracer does not use are :data:`DROPPED`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from fogref import params as P
from fogref.errors import ParameterError
from fogref.media import ExpLayer, FogMedium, medium_from_params, rgb
from fogref.media.ue_pathtracer import DENSITY_CLAMP_DEFAULT, DENSITY_CLAMP_RANGE, RADIUS_RANGE
from fogref.models.ue4 import CM_PER_M, UE4FogParams
from fogref.scene.defaults import declared
from fogref.scene.edit import replace_fog

__all__ = [
    "CM_PER_M",
    "DROPPED",
    "PT_DENSITY_FACTOR",
    "UEPathTracerSettings",
    "density_clamp",
    "exact_fog_params",
    "exact_medium",
    "pathtracer_fog_params",
    "pathtracer_layers",
    "pathtracer_medium",
    "rewrite_scene",
    "settings_from",
    "SETTING_RANGES",
    "validated_settings",
]

#: [PT] ``MatchHeightFogFactor``: the path tracer's density is half the scene-info density.
PT_DENSITY_FACTOR = 0.5
#: [PT]: ``FogFalloff = max(FogData.HeightFalloff, 0.001 / 1000)``: the editor falloff's floor.
MIN_EDITOR_FALLOFF = 0.001
#: [SC]: the phase g is clamped to this range.
G_RANGE = (-0.99, 0.99)

#: Editor values of the fog component the path tracer does not use ([PT]'s
#: ``FPathTracingFogParameters`` has no field for them): name -> what it does in raster.
DROPPED = {
    "FogInscatteringColor": "raster inscattering colour (the path tracer lights the fog with the scene's "
    "lights)",
    "InscatteringColorCubemap": "raster inscattering cubemap",
    "DirectionalInscatteringColor": "raster sun lobe colour (the path tracer uses the HG phase)",
    "DirectionalInscatteringExponent": "raster sun lobe exponent",
    "DirectionalInscatteringStartDistance": "raster sun lobe start distance",
    "StartDistance": "raster fog start distance (the path-traced fog starts at the camera)",
    "EndDistance": "raster fog end distance",
    "FogMaxOpacity": "raster opacity cap",
    "FogCutoffDistance": "raster cutoff distance",
    "VolumetricFogEmissive": "volumetric fog emission (not in FPathTracingFogParameters)",
}


@dataclass(frozen=True)
class UEPathTracerSettings:
    """The fog component's volumetric values and the path tracer's console variable.

    VolumetricFogExtinctionScale: >= 0 (default 1).
    VolumetricFogAlbedo:          linear RGB in [0, 1] (default white; the editor's
                                  FColor becomes ``FLinearColor(FColor)``, [SC]).
    VolumetricFogScatteringDistribution: HG g, clamped to [-0.99, 0.99] as [SC] does
                                  (default 0.2).
    VolumetricFogDistance:        cm (default 6000); VolumetricFogStartDistance (cm,
                                  default 0) adds to the cylinder's radius ([SC]).
    FogDensityClamp:              ``r.PathTracing.FogDensityClamp``, clamped to [1, 256]
                                  (default 8); ignored before UE 5.6 (``version < (5, 6)``:
                                  the constant 8).

    Defaults: ``UExponentialHeightFogComponent``'s constructor
    (``Engine/Source/Runtime/Engine/Private/Components/ExponentialHeightFogComponent.cpp``:
    ``VolumetricFogScatteringDistribution = .2f``, ``VolumetricFogAlbedo = FColor::White``,
    ``VolumetricFogExtinctionScale = 1.0f``, ``VolumetricFogDistance = 6000.0f``).

    Examples
    --------
    >>> UEPathTracerSettings(FogDensityClamp=1000).density_clamp
    256.0
    >>> UEPathTracerSettings(FogDensityClamp=2, version=(5, 5)).density_clamp
    8.0
    """

    VolumetricFogExtinctionScale: float = 1.0
    VolumetricFogAlbedo: Any = (1.0, 1.0, 1.0)
    VolumetricFogScatteringDistribution: float = 0.2
    VolumetricFogDistance: float = 6000.0
    VolumetricFogStartDistance: float = 0.0
    FogDensityClamp: float = DENSITY_CLAMP_DEFAULT
    version: tuple = (5, 6)

    def __post_init__(self) -> None:
        src = "<UEPathTracerSettings>"
        for name in (
            "VolumetricFogExtinctionScale",
            "VolumetricFogScatteringDistribution",
            "VolumetricFogDistance",
            "VolumetricFogStartDistance",
            "FogDensityClamp",
        ):
            v = float(getattr(self, name))
            if not math.isfinite(v):
                raise ParameterError(src, name, f"value {v} must be finite")
            object.__setattr__(self, name, v)
        albedo = rgb(self.VolumetricFogAlbedo, "VolumetricFogAlbedo", src, 0.0, 1.0)
        object.__setattr__(self, "VolumetricFogAlbedo", albedo)
        if self.radius_cm <= 0:
            raise ParameterError(
                src,
                "VolumetricFogDistance",
                f"VolumetricFogStartDistance + VolumetricFogDistance = {self.radius_cm} cm: "
                "the path-traced fog would be empty (need > 0)",
            )

    @property
    def density_clamp(self) -> float:
        """The density clamp [PT] uses: the console variable in [1, 256] (UE >= 5.6), else 8."""
        return density_clamp(self.FogDensityClamp, self.version)

    @property
    def radius_cm(self) -> float:
        """[SC]'s ``VolumetricFogDistance``: ``max(start + distance, 0)`` [cm]."""
        return max(self.VolumetricFogStartDistance + self.VolumetricFogDistance, 0.0)

    @property
    def g(self) -> float:
        """The HG g [SC] passes on: clamped to [-0.99, 0.99]."""
        return min(max(self.VolumetricFogScatteringDistribution, G_RANGE[0]), G_RANGE[1])


def density_clamp(cvar: float = DENSITY_CLAMP_DEFAULT, version: tuple = (5, 6)) -> float:
    """[PT]'s density clamp: ``clamp(r.PathTracing.FogDensityClamp, 1, 256)`` from UE 5.6, 8 before.

    Examples
    --------
    >>> density_clamp(0.5), density_clamp(16.0), density_clamp(16.0, (5, 5))
    (1.0, 16.0, 8.0)
    """
    if tuple(version) < (5, 6):
        return DENSITY_CLAMP_DEFAULT
    return min(max(float(cvar), DENSITY_CLAMP_RANGE[0]), DENSITY_CLAMP_RANGE[1])


def pathtracer_layers(ue: UE4FogParams, pt: UEPathTracerSettings) -> list[tuple[float, float, float]]:
    """[PT]'s two layers in fogref units: ``(sigma [1/m] at the height, b [1/m], height [m])``.

    Examples
    --------
    >>> [tuple(round(x, 9) for x in L) for L in pathtracer_layers(UE4FogParams(), UEPathTracerSettings())]
    [(0.001, 0.013862944, 0.0), (0.0, 0.013862944, 0.0)]
    """
    sfd = ue.SecondFogData
    specs = [
        (ue.FogDensity, ue.FogHeightFalloff, ue.FogHeight),
        (sfd.FogDensity, sfd.FogHeightFalloff, ue.FogHeight + sfd.FogHeightOffset),
    ]
    es = max(pt.VolumetricFogExtinctionScale, 0.0)
    out = []
    for d, f, h in specs:
        sigma = CM_PER_M * PT_DENSITY_FACTOR * (d / 1000.0) * es
        b = CM_PER_M * math.log(2.0) * max(f, MIN_EDITOR_FALLOFF) / 1000.0
        out.append((sigma, b, h / CM_PER_M))
    return out


def _camera(camera: Any) -> tuple[float, float, float]:
    c = tuple(float(x) for x in camera)
    if len(c) != 3 or not all(math.isfinite(x) for x in c):
        raise ParameterError("<unreal_pathtracer>", "camera", f"expected 3 finite numbers [m], got {camera}")
    return c


def pathtracer_fog_params(ue: UE4FogParams, pt: UEPathTracerSettings, camera: Any) -> dict:
    """The ``heightfog`` parameters (profile ``"ue_pathtracer"``) of UE's path-traced fog.

    ``camera``: the camera position in fogref's frame (m, y-up); the cylinder is
    centred on it ([PT]).  Both layers are written (the second one's height counts
    in the cylinder's z range even at density 0, as in [PT]); the cylinder's y range
    is left to the profile (the same rule as [PT]).

    Examples
    --------
    >>> p = pathtracer_fog_params(UE4FogParams(), UEPathTracerSettings(), (0, 2, 0))
    >>> p["profile"], round(p["sigma_t"][0], 9), p["clamp"], p["radius"], p["center"]
    ('ue_pathtracer', 0.001, 8.0, 60.0, [0.0, 2.0, 0.0])
    """
    (s0, b0, h0), (s1, b1, h1) = pathtracer_layers(ue, pt)
    ref = max(s0, s1)
    d0, d1 = (s0 / ref, s1 / ref) if ref > 0 else (1.0, 0.0)
    return {
        "profile": "ue_pathtracer",
        "sigma_t": [ref] * 3,
        "albedo": list(pt.VolumetricFogAlbedo),
        "g": pt.g,
        "density": d0,
        "falloff": b0,
        "height": h0,
        "density2": d1,
        "falloff2": b1,
        "height2": h1,
        "clamp": pt.density_clamp,
        "radius": pt.radius_cm / CM_PER_M,
        "center": list(_camera(camera)),
    }


def pathtracer_medium(ue: UE4FogParams, pt: UEPathTracerSettings, camera: Any) -> FogMedium:
    """The :class:`~fogref.media.FogMedium` UE's path tracer renders for these settings.

    Examples
    --------
    >>> m = pathtracer_medium(UE4FogParams(), UEPathTracerSettings(), (0, 2, 0))
    >>> type(m.bounds).__name__, m.bounds.radius, m.layers[0].clamp
    ('Cylinder', 60.0, 8.0)
    """
    return medium_from_params(pathtracer_fog_params(ue, pt, camera), "<unreal_pathtracer>")


def exact_medium(ue: UE4FogParams, pt: UEPathTracerSettings) -> FogMedium:
    """The same physical fog without the clamp and the cylinder: unbounded exponential
    layers with [PT]'s density, falloff, height, albedo and g.

    Examples
    --------
    >>> m = exact_medium(UE4FogParams(), UEPathTracerSettings())
    >>> m.bounds, len(m.layers), round(m.layers[0].falloff, 9)
    (None, 1, 0.013862944)
    """
    specs = pathtracer_layers(ue, pt)
    ref = max(s for s, _, _ in specs)
    layers = tuple(ExpLayer(s / ref, b, h) for s, b, h in specs if s > 0) if ref > 0 else (ExpLayer(),)
    src = "<unreal_pathtracer exact>"
    return FogMedium(sigma_t=max(ref, 0.0), albedo=pt.VolumetricFogAlbedo, g=pt.g, layers=layers, source=src)


def exact_fog_params(ue: UE4FogParams, pt: UEPathTracerSettings) -> dict:
    """The ``heightfog`` parameters (profile ``"exponential"``) of :func:`exact_medium`.

    Examples
    --------
    >>> p = exact_fog_params(UE4FogParams(), UEPathTracerSettings())
    >>> p["profile"], p["density2"], "center" in p
    ('exponential', 0.0, False)
    """
    m = exact_medium(ue, pt)
    out = {"profile": "exponential", "sigma_t": list(m.sigma_t), "albedo": list(m.albedo), "g": m.g}
    L0 = m.layers[0]
    out.update(density=L0.density, falloff=L0.falloff, height=L0.height, density2=0.0)
    if len(m.layers) > 1:
        L1 = m.layers[1]
        out.update(density2=L1.density, falloff2=L1.falloff, height2=L1.height)
    return out


#: The ``<default>`` of each fog parameter in a scene :func:`rewrite_scene` writes (the others keep
#: their own name): the scene vocabulary's (:mod:`fogref.scene.defaults`) and two of its own.
DEFAULT_NAMES = {
    "height": "fog_height",
    "center": "camera_origin",
    "clamp": "fog_clamp",
    "radius": "fog_radius",
}


def rewrite_scene(
    src: str | Path,
    dst: str | Path,
    ue: UE4FogParams,
    pt: UEPathTracerSettings,
    camera: Any = None,
    params: dict | None = None,
) -> dict:
    """Copy the fogref scene ``src`` to ``dst`` with its ``heightfog`` replaced by UE's
    path-traced fog of ``ue`` and ``pt`` (or by ``params``, e.g. :func:`exact_fog_params`);
    returns the new fog parameters.

    ``camera`` [m, y-up]: the cylinder's centre; default the scene's ``$camera_origin``
    ``<default>`` (the ``center`` is then written as ``$camera_origin``, so
    ``fogref render --set camera_origin=...`` moves the cylinder with the camera,
    as Unreal does).  The medium's ``phase`` child, if any, is kept.  With that default, every
    other value of the fog becomes a ``<default>`` too (:data:`DEFAULT_NAMES`: the scene
    vocabulary's names, and ``fog_clamp``, ``fog_radius``), so ``--set g=0.9`` changes it; the
    scene's comments are kept (:func:`fogref.scene.edit.replace_fog`).
    """
    follow = camera is None and params is None
    if follow:
        origin = declared(src).get("camera_origin")
        if origin is None:
            raise ParameterError(
                str(src), "camera_origin", "no $camera_origin default: give the camera position"
            )
        camera = [float(x) for x in origin.replace(",", " ").split()]
    if params is None:
        params = pathtracer_fog_params(ue, pt, camera)
    replace_fog(src, dst, params, DEFAULT_NAMES if follow else None)
    return params


#: The settings a user gives (``fogref scene --ue-*``): name -> (lo, hi, lo_open, unit) as the engine
#: takes them: the cylinder's radius ``VolumetricFogDistance`` > 0 cm ([SC]; with the default
#: ``VolumetricFogStartDistance`` 0 the fog would otherwise be empty), ``VolumetricFogExtinctionScale``
#: >= 0 ([SC] multiplies the density by it), g in :data:`G_RANGE` ([SC] clamps to it),
#: ``r.PathTracing.FogDensityClamp`` in ``DENSITY_CLAMP_RANGE`` ([PT] clamps to it), albedo a
#: linear RGB in [0, 1] (from the editor's FColor, [SC]).
SETTING_RANGES: dict[str, tuple[float, float, bool, str]] = {
    # the medium's cylinder radius range, in cm: a scene written is a scene fogref render takes
    "VolumetricFogDistance": (RADIUS_RANGE[0] * CM_PER_M, RADIUS_RANGE[1] * CM_PER_M, False, "cm"),
    "VolumetricFogExtinctionScale": (0.0, math.inf, False, ""),
    "VolumetricFogScatteringDistribution": (G_RANGE[0], G_RANGE[1], False, ""),
    "FogDensityClamp": (DENSITY_CLAMP_RANGE[0], DENSITY_CLAMP_RANGE[1], False, ""),
    "VolumetricFogAlbedo": (0.0, 1.0, False, ""),
}


def validated_settings(source: str, names: dict | None = None, **values: Any) -> UEPathTracerSettings:
    """:class:`UEPathTracerSettings` from user values (numbers or text), each checked through
    :mod:`fogref.params` against :data:`SETTING_RANGES` (one-line ParameterError naming
    ``source`` and the value, shown as ``names[name]`` if given, e.g. a command-line option);
    values not given keep the engine's defaults.

    Examples
    --------
    >>> validated_settings("doc", VolumetricFogDistance="3000", FogDensityClamp=4).radius_cm
    3000.0
    >>> validated_settings("doc", {"FogDensityClamp": "--ue-fog-density-clamp"}, FogDensityClamp=512)
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: doc: parameter '--ue-fog-density-clamp': 512 is outside [1, 256]
    """
    names = names or {}
    out: dict[str, Any] = {}
    for name, value in values.items():
        if value is None:
            continue
        if name not in SETTING_RANGES:
            raise ParameterError(source, name, f"not a path-traced fog setting ({', '.join(SETTING_RANGES)})")
        lo, hi, lo_open, unit = SETTING_RANGES[name]
        shown = names.get(name, name)
        if name == "VolumetricFogAlbedo":
            out[name] = P.rgb(value, shown, source=source, lo=lo, hi=hi, unit=unit)
        else:
            out[name] = P.number(value, shown, source=source, lo=lo, hi=hi, lo_open=lo_open, unit=unit)
    return UEPathTracerSettings(**out)


def settings_from(ue: UE4FogParams | None = None, **pt: Any) -> tuple[UE4FogParams, UEPathTracerSettings]:
    """``(UE4FogParams, UEPathTracerSettings)`` from keyword values of either (a sweep's row)."""
    ue = ue or UE4FogParams()
    ue_fields = {k: v for k, v in pt.items() if hasattr(ue, k)}
    rest = {k: v for k, v in pt.items() if k not in ue_fields}
    return replace(ue, **ue_fields), UEPathTracerSettings(**rest)
