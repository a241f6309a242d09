"""Unreal Engine Exponential Height Fog (UE 4.22 to 5.8), with UE 5's EndDistance and the
``r.SupportExpFogMatchesVolumetricFog`` mode.

Reproduces the **linear** HDR fog the height-fog pass blends into scene colour (before
tonemapping).  Sources, read in the public mirror of UE 5.8.0 ``unicorn2022/UE5.8.0`` at commit
5d9a05c15b1f8c6d7b3354b360677ce30d688149, ported to y-up:

* ``Engine/Shaders/Private/HeightFogCommon.ush``: ``GetExponentialHeightFog``,
  ``CalculateLineIntegralShared``, and the ``PROJECT_EXPFOG_MATCHES_VFOG`` lines;
* ``Engine/Source/Runtime/Renderer/Private/FogRendering.cpp``: ``InitFogConstants`` (the
  uniforms, and what ``bExpFogMatchesVolumetricFog`` replaces on the CPU);
* ``Engine/Shaders/Private/ParticipatingMediaCommon.ush``: ``HenyeyGreensteinPhase``.

The default mode is the shader without a sky atmosphere (its ``#else`` branch), the same as
UE 4.22 to 4.27 apart from UE 5's EndDistance.  ``SkyAtmosphereAffectsHeightFog`` is the branch
that ``r.SupportSkyAtmosphereAffectsHeightFog`` compiles (its default is 1 in UE 5.8's
``SkyAtmosphereRendering.cpp``, so a default UE 5.8 project renders it)::

    InscatteringColor            = FogInscatteringColor + SkyAtmosphereAmbient
    DirectionalLightInscattering = (DirectionalInscatteringColor * SunLuminance + AtmosphereLightIlluminance)
                                   * pow(saturate(dot(CameraToReceiverNormalized, L)), exponent) / (4 pi)

so the same DirectionalInscatteringColor gives a lobe 4 pi times weaker than UE 4's.  The
physical scene -> Unreal mapping and colour fit live in :mod:`fogref.mapping.unreal` (the
default mode).

Units: Unreal is **z-up, centimetres**; fogref is **y-up, metres**.  Positions are
converted internally by ``(x, y, z)_ue = 100 * (x, z, y)_fogref`` (this swap also
turns fogref's right-handed frame into Unreal's left-handed one; fog depends only
on heights and distances, so nothing else changes).  The editor's FogDensity ``D``
and FogHeightFalloff ``f`` are divided by 1000 on the CPU; the shader uses
**exp2**.  The exact physical medium is therefore (per cm)

    sigma_t(z) = (ln 2)^2 * D/1000 * 2^(-(f/1000) (z - H)),

i.e. per metre ``a = 100 (ln 2)^2 D/1000`` and ``b = 100 ln 2 f/1000`` (one factor
ln 2 turns the exp2 of the line integral into exp, the other comes from
integrating 2^(-x)).  See :func:`fogref.models.ue4.ue4_to_medium` and its inverse
:func:`fogref.mapping.unreal_basis.base_params`.

**Base 2, and the path tracer's 0.5.**  The shader integrates the density in base 2
(``CalculateLineIntegralShared``: ``(1 - exp2(-F)) / F``, Taylor ``ln 2 - ln^2 2 F / 2``) and
attenuates with ``exp2``, so the raster fog's extinction is ``(ln 2)^2 D/1000 = 0.4805 D/1000``
per cm.  Unreal's path tracer (``PathTracing.cpp``, ``MatchHeightFogFactor = .5``, "See
VolumetricFog.usf", whose ``GlobalDensity *= 0.5`` has the same origin) uses ``0.5 D/1000``:
``0.5 / (ln 2)^2 = 1.0407`` times the raster fog's optical depth, about 4 % more
(:mod:`fogref.media.ue_pathtracer`).

Compositing rule (``FogRendering.cpp`` blend ``One, SourceAlpha``):
``final = scene * ExpFogFactor + FogColor``, so ``transmittance = ExpFogFactor``
(grey) and ``inscatter = FogInscatteringColor * (1 - ExpFogFactor) +
DirectionalInscattering``.

**ExpFogMatchesVolumetricFog** (``r.SupportExpFogMatchesVolumetricFog``, UE >= 5.5: the
volumetric fog's g and albedo reach the fog uniforms from 5.5).  The CPU sets the directional
start distance to 0, ``ExponentialFogColor = VolumetricFogEmissive``, ``VolumetricFogAlbedo``
and ``DirectionalInscatteringColor = Black`` ("directional scattering is only impacted by the
atmospheric light"); with ``SkyAtmosphereAffectsHeightFog`` the shader then computes (without
it the black colour leaves no directional light and no sky ambient)::

    InscatteringColor      = VolumetricFogEmissive + SkyAtmosphereAmbient * VolumetricFogAlbedo
    DirectionalInscattering = AtmosphereLightIlluminance
                              * HenyeyGreensteinPhase(g, dot(-CameraToReceiverNormalized, L))
                              * (1 - saturate(exp2(-shared * RayLength))) * VolumetricFogAlbedo

(``L`` toward the sun, ``g = VolumetricFogScatteringDistribution``).  With ``E`` the sun's
illuminance, this is ``albedo p_HG E (1 - T)``: the single scattering of an unattenuated sun
with the true phase function, and ``albedo L_sky (1 - T)`` for a uniform sky.
FogInscatteringColor, DirectionalInscatteringColor, DirectionalInscatteringExponent and
DirectionalInscatteringStartDistance are then unused, as in the engine.

``precision="float32"`` follows the shader line by line in float32 (CPU set-up in
float32 too): observer-height clamp, the ``[-125, 126]`` clamp of the collapsed
exponent, ``max(-127, ...)``, the Taylor branch below ``|Falloff| <= FLT_EPSILON2
= 0.01``, ``saturate``, ``exp2``.  ``precision="float64"`` keeps every engine rule
(clamps, start distance, max opacity, cutoff) but computes in float64 and
replaces the Taylor branch by the exact ``(1 - 2^-F)/F``.  EndDistance (UE 5): where the
receiver's horizontal distance exceeds it, ``CameraToReceiver`` is scaled by ``EndDistance /
sqrt(max(1, |xy|^2))`` before anything else.  Deviation for robustness, as in UE5:
``rsqrt(max(|v|^2, 1e-8))`` so a pixel at the camera gives no NaN.

Example:
    >>> import numpy as np
    >>> from fogref.models import get
    >>> fog = get("ue4")(UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2))
    >>> r = fog.evaluate(np.zeros(3), np.array([[100.0, 0.0, 0.0]]))
    >>> bool(0.0 < r.transmittance[0, 0] < 1.0)
    True
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from fogref.errors import ParameterError
from fogref.media import NP, ExpLayer, FogMedium
from fogref.media.closed_form import phi
from fogref.models._num import LN2, dtype_of, grey, saturate, split
from fogref.models.base import FogResult, ParamModel, register
from fogref.params import number, vector
from fogref.params import rgb as valid_rgb

CM_PER_M = 100.0
#: HeightFogCommon.ush: threshold of the Taylor branch of the line integral.
FLT_EPSILON2 = 0.01
#: FogRendering.cpp: the observer is clamped to FogHeight + this [cm].
MAX_OBSERVER_HEIGHT_DIFFERENCE = 65536.0


def world_to_unreal(p: Any) -> np.ndarray:
    """fogref (..., 3) y-up metres -> Unreal (..., 3) z-up centimetres."""
    p = np.asarray(p, dtype=np.float64)
    return np.stack([p[..., 0], p[..., 2], p[..., 1]], axis=-1) * CM_PER_M


def direction_to_unreal(w: Any) -> tuple:
    """A fogref direction (y-up) -> unit Unreal direction (z-up)."""
    w = np.asarray(w, dtype=np.float64)
    v = np.array([w[0], w[2], w[1]])
    return tuple(float(x) for x in v / np.linalg.norm(v))


def unreal_rotator(forward: Any, up: Any = (0.0, 0.0, 1.0)) -> dict:
    """The FRotator ``{pitch, yaw, roll}`` [deg] whose X axis is ``forward`` and whose Z axis is
    nearest ``up`` (FRotationMatrix), both unit vectors in **Unreal's** frame (z-up).

    Examples
    --------
    >>> r = unreal_rotator((0.0, 0.0, -1.0), (1.0, 0.0, 0.0))
    >>> round(r["pitch"], 6), round(r["yaw"], 6), round(r["roll"], 6)
    (-90.0, 0.0, 0.0)
    """
    fwd, up = np.asarray(forward, dtype=np.float64), np.asarray(up, dtype=np.float64)
    pitch = math.degrees(math.asin(max(-1.0, min(1.0, float(fwd[2])))))
    yaw = math.degrees(math.atan2(fwd[1], fwd[0]))
    cy, sy = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    cp, sp = math.cos(math.radians(pitch)), math.sin(math.radians(pitch))
    y0, z0 = np.array([-sy, cy, 0.0]), np.array([-sp * cy, -sp * sy, cp])  # the axes at roll 0
    roll = math.degrees(math.atan2(float(up @ y0), float(up @ z0)))
    return {"pitch": pitch, "yaw": yaw, "roll": roll}


@dataclass(frozen=True)
class SecondFogData:
    """UExponentialHeightFogComponent::SecondFogData (editor units)."""

    FogDensity: float = 0.0  #: editor density (x 1/1000 per cm)
    FogHeightFalloff: float = 0.2  #: editor falloff (x 1/1000 per cm)
    FogHeightOffset: float = 0.0  #: cm, relative to the component's Z

    def __post_init__(self) -> None:
        src = "<UE4FogParams.SecondFogData>"
        for name, lo in (("FogDensity", 0.0), ("FogHeightFalloff", 0.0), ("FogHeightOffset", -math.inf)):
            unit = "cm" if name == "FogHeightOffset" else ""
            object.__setattr__(self, name, number(getattr(self, name), name, source=src, lo=lo, unit=unit))


@dataclass(frozen=True)
class UE4FogParams:
    """Exponential height fog component, in Unreal's names and units (cm, z-up).

    FogHeight: world Z of the first layer [cm] (component Z, plus its height
    offset where the engine version has one); the second layer sits at
    ``FogHeight + SecondFogData.FogHeightOffset``.
    InscatteringLightDirection: unit vector **toward** the sun in Unreal's frame
    (``-SunLight->GetDirection()``), or None when there is no atmosphere sun
    light (directional inscattering off).  SunLuminance: the sun light colour's
    luminance, which multiplies DirectionalInscatteringColor on the CPU.
    EndDistance (UE5, cm, 0 = off): a receiver farther than this horizontally is moved back
    along its view ray to that horizontal distance.
    FogCutoffDistance (cm, 0 = off): pixels farther than this get no fog.
    DirectionalInscatteringExponent is clamped to [1e-6, 1000] as the engine does.

    SkyAtmosphereAffectsHeightFog: the project setting ``r.SupportSkyAtmosphereAffectsHeightFog``
    (on by default in UE 5.8, off here; see the module doc); only then are
    AtmosphereLightIlluminance (linear RGB, the sun's ``SkyAtmosphereHeightFogContribution *
    AtmosphereLightIlluminanceOnGroundPostTransmittance[0]``, scene radiance units x sr) and
    SkyAtmosphereAmbient (linear RGB, ``SkyAtmosphereAmbientContributionColorScale *
    SkyAtmosphereHeightFogContribution *`` the distant sky light colour) read.
    ExpFogMatchesVolumetricFog: the project setting ``r.SupportExpFogMatchesVolumetricFog``
    (UE >= 5.5; see the module doc); only then are the next three read.
    VolumetricFogScatteringDistribution: the HG g in [-0.99, 0.99] (``SceneCore.cpp``'s clamp).
    VolumetricFogAlbedo, VolumetricFogEmissive: linear RGB (the albedo in [0, 1]).

    Examples
    --------
    >>> UE4FogParams(ExpFogMatchesVolumetricFog=True).VolumetricFogScatteringDistribution
    0.2
    >>> UE4FogParams(AtmosphereLightIlluminance=(1.0, 1.0, 1.0))
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: <UE4FogParams>: parameter 'AtmosphereLightIlluminance': read only with ...
    """

    FogDensity: float = 0.02
    FogHeightFalloff: float = 0.2
    FogHeight: float = 0.0
    SecondFogData: SecondFogData = field(default_factory=SecondFogData)
    FogInscatteringColor: tuple = (0.447, 0.638, 1.0)
    FogMaxOpacity: float = 1.0
    StartDistance: float = 0.0
    FogCutoffDistance: float = 0.0
    EndDistance: float = 0.0
    DirectionalInscatteringExponent: float = 4.0
    DirectionalInscatteringStartDistance: float = 10000.0
    DirectionalInscatteringColor: tuple = (0.25, 0.25, 0.125)
    InscatteringLightDirection: tuple | None = None
    SunLuminance: float = 1.0
    SkyAtmosphereAffectsHeightFog: bool = False
    ExpFogMatchesVolumetricFog: bool = False
    VolumetricFogScatteringDistribution: float = 0.2
    VolumetricFogAlbedo: tuple = (1.0, 1.0, 1.0)
    VolumetricFogEmissive: tuple = (0.0, 0.0, 0.0)
    AtmosphereLightIlluminance: tuple = (0.0, 0.0, 0.0)
    SkyAtmosphereAmbient: tuple = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        _validate(self)

    def with_sun(self, direction_world: Any, luminance: float = 1.0) -> "UE4FogParams":
        """Copy with the sun given in **fogref's** frame (y-up, toward the sun)."""
        return replace(
            self,
            InscatteringLightDirection=direction_to_unreal(direction_world),
            SunLuminance=float(luminance),
        )


#: The ranges fogref accepts, by parameter: ``(lo, hi, unit)``.  Where Unreal has a range it is
#: cited: ``ExponentialHeightFogComponent.h`` gives only editor slider ranges (``UIMin``/``UIMax``:
#: FogDensity [0, 0.05], FogHeightFalloff [0.001, 2], FogMaxOpacity [0, 1], StartDistance
#: [0, 5000], FogCutoffDistance [100000, 20000000], DirectionalInscatteringExponent [2, 64]),
#: which a typed value may leave.  ``FogRendering.cpp`` clamps the exponent to
#: ``[0.000001, 1000]`` on the CPU: a large exponent is a narrow cone the engine clamps (kept,
#: and clamped as the engine does), but one <= 0 is no cone at all (the clamp would turn -5
#: into 1e-6, a uniform glow the user did not ask for) and is refused.  Densities, distances
#: and colours are >= 0 (negative ones have no physical meaning and the shader's exp2 would
#: amplify instead of attenuate); FogMaxOpacity is a fraction in [0, 1] (the shader's
#: ``1 - FogMaxOpacity`` is a minimum transmittance); SunLuminance (the light's luminance,
#: fogref's name) is >= 0; FogHeight is any finite height [cm].
RANGES = {
    "FogDensity": (0.0, math.inf, ""),
    "FogHeightFalloff": (0.0, math.inf, ""),
    "FogHeight": (-math.inf, math.inf, "cm"),
    "FogMaxOpacity": (0.0, 1.0, ""),
    "StartDistance": (0.0, math.inf, "cm"),
    "FogCutoffDistance": (0.0, math.inf, "cm"),
    "EndDistance": (0.0, math.inf, "cm"),
    "DirectionalInscatteringExponent": (0.0, math.inf, ""),
    "DirectionalInscatteringStartDistance": (0.0, math.inf, "cm"),
    "SunLuminance": (0.0, math.inf, ""),
    "VolumetricFogScatteringDistribution": (-0.99, 0.99, ""),
}
#: Parameters whose lower end is open (must be > lo).
OPEN_LOW = ("DirectionalInscatteringExponent",)
#: Colours: each of R, G, B finite and >= 0 (linear, the scene's radiance units).
COLOURS = (
    "FogInscatteringColor",
    "DirectionalInscatteringColor",
    "VolumetricFogEmissive",
    "AtmosphereLightIlluminance",
    "SkyAtmosphereAmbient",
)
#: Read only with SkyAtmosphereAffectsHeightFog (refused when non-zero without it).
SKY_ATMOSPHERE_ONLY = ("AtmosphereLightIlluminance", "SkyAtmosphereAmbient")


def _validate(p: "UE4FogParams") -> None:
    """Check and normalise every field of ``p`` through :mod:`fogref.params` (:data:`RANGES`)."""
    src = "<UE4FogParams>"
    for name, (lo, hi, unit) in RANGES.items():
        x = number(getattr(p, name), name, source=src, lo=lo, hi=hi, unit=unit, lo_open=name in OPEN_LOW)
        object.__setattr__(p, name, x)
    for name in COLOURS:
        object.__setattr__(p, name, valid_rgb(getattr(p, name), name, source=src, lo=0.0))
    object.__setattr__(
        p,
        "VolumetricFogAlbedo",
        valid_rgb(p.VolumetricFogAlbedo, "VolumetricFogAlbedo", source=src, lo=0.0, hi=1.0),
    )
    for name in ("SkyAtmosphereAffectsHeightFog", "ExpFogMatchesVolumetricFog"):
        if not isinstance(getattr(p, name), bool):
            raise ParameterError(src, name, f"expected true or false, got {getattr(p, name)!r}")
    for name in SKY_ATMOSPHERE_ONLY:
        if not p.SkyAtmosphereAffectsHeightFog and any(getattr(p, name)):
            raise ParameterError(src, name, "read only with SkyAtmosphereAffectsHeightFog=True")
    if isinstance(p.SecondFogData, dict):
        try:
            object.__setattr__(p, "SecondFogData", SecondFogData(**p.SecondFogData))
        except TypeError as e:
            raise ParameterError(
                src, "SecondFogData", f"{e} (fields: FogDensity, FogHeightFalloff, FogHeightOffset)"
            ) from None
    if not isinstance(p.SecondFogData, SecondFogData):
        raise ParameterError(
            src, "SecondFogData", f"expected SecondFogData or a dict, got {p.SecondFogData!r}"
        )
    if p.InscatteringLightDirection is not None:
        w = vector(p.InscatteringLightDirection, "InscatteringLightDirection", source=src)
        norm = float(np.linalg.norm(w))
        if not norm > 0:
            raise ParameterError(
                src,
                "InscatteringLightDirection",
                "(0, 0, 0) has no direction: give a non-zero vector toward the sun, or None for no sun",
            )
        object.__setattr__(p, "InscatteringLightDirection", tuple(float(x) for x in np.asarray(w) / norm))


def directional_start_uniform(start_cm: float, light: bool, match: bool, dt: Any = np.float32) -> Any:
    """The w of :func:`fog_constants`'s ``light`` uniform (FogRendering.cpp), in ``dt``:
    DirectionalInscatteringStartDistance ``start_cm`` [cm] clamped at 0; 0 with
    ExpFogMatchesVolumetricFog (``match``); -1 without a light.

    >>> [float(directional_start_uniform(s, *f)) for s, f in ((-5.0, (1, 0)), (5.0, (1, 1)), (5.0, (0, 0)))]
    [0.0, 0.0, -1.0]
    """
    if not light:
        return dt(-1.0)
    return dt(0.0) if match else dt(max(0.0, start_cm))


def fog_constants(p: UE4FogParams, camera_z_cm: float, dt: Any = np.float32) -> dict:
    """The uniforms of FogRendering.cpp for an observer at ``camera_z_cm``.

    Returns ExponentialFogParameters{,2,3}, the colour parameter and the
    directional-inscattering uniforms as dtype ``dt`` scalars (float32 mimics
    the engine's CPU arithmetic).
    """
    f = dt
    dens = [f(p.FogDensity) / f(1000.0), f(p.SecondFogData.FogDensity) / f(1000.0)]
    fall = [f(p.FogHeightFalloff) / f(1000.0), f(p.SecondFogData.FogHeightFalloff) / f(1000.0)]
    height = [f(p.FogHeight), f(p.FogHeight) + f(p.SecondFogData.FogHeightOffset)]
    max_obs = f(np.finfo(np.float32).max)
    for i in range(2):
        if dens[i] > 0:
            max_obs = min(max_obs, f(height[i] + f(MAX_OBSERVER_HEIGHT_DIFFERENCE)))
    obs = min(f(camera_z_cm), max_obs)
    collapsed = []
    for i in range(2):
        power = np.clip(-fall[i] * (obs - height[i]), f(-126.0 + 1.0), f(127.0 - 1.0)).astype(dt)
        collapsed.append(dens[i] * np.power(f(2.0), power))
    match, sky = p.ExpFogMatchesVolumetricFog, p.SkyAtmosphereAffectsHeightFog
    light_w = directional_start_uniform(
        p.DirectionalInscatteringStartDistance, p.InscatteringLightDirection is not None, match, f
    )
    light_dir = p.InscatteringLightDirection or (0.0, 0.0, 0.0)
    color = tuple(f(c) for c in p.FogInscatteringColor)
    dir_color = tuple(f(c) * f(p.SunLuminance) for c in p.DirectionalInscatteringColor)
    if match:  # InitFogConstants: no start distance, the emissive as fog colour, black directional
        color = tuple(f(e) for e in p.VolumetricFogEmissive)
        dir_color = (f(0.0),) * 3
    if sky:  # PROJECT_SUPPORT_SKY_ATMOSPHERE_AFFECTS_HEIGHFOG: the atmosphere's sky and sun added
        ambient = [f(s) for s in p.SkyAtmosphereAmbient]
        if match:
            ambient = [a * f(b) for a, b in zip(ambient, p.VolumetricFogAlbedo)]
        color = tuple(c + a for c, a in zip(color, ambient))
        dir_color = tuple(c + f(e) for c, e in zip(dir_color, p.AtmosphereLightIlluminance))
    return dict(
        P=(f(collapsed[0]), fall[0], max_obs, f(p.StartDistance)),
        P2=(f(collapsed[1]), fall[1], dens[1], height[1]),
        P3=(dens[0], height[0], f(0.0), f(p.FogCutoffDistance)),
        color=color,
        min_opacity=f(1.0) - f(p.FogMaxOpacity),
        light=(f(light_dir[0]), f(light_dir[1]), f(light_dir[2]), light_w),
        dir_color=dir_color,
        dir_exponent=f(np.clip(f(p.DirectionalInscatteringExponent), f(0.000001), f(1000.0))),
        end_distance=f(p.EndDistance),
        match=match,
        sky=sky,
        phase_g=f(p.VolumetricFogScatteringDistribution),
        albedo=tuple(f(a) for a in p.VolumetricFogAlbedo),
    )


def _hg_shader(g: Any, cos_theta: Any, dt: Any) -> Any:
    """``HenyeyGreensteinPhase(G, CosTheta)`` of ``ParticipatingMediaCommon.ush`` in ``dt``
    arithmetic [1/sr]: ``(1 - G^2) / (4 PI pow(1 + G^2 + 2 G CosTheta, 1.5))``, PBRT's sign
    (forward scattering at ``CosTheta = -1``).  The phase function itself is
    :func:`fogref.media.hg_phase` (``cos_theta`` there is ``-CosTheta`` here)."""
    g = dt(g)
    denom = dt(1.0) + g * g + dt(2.0) * g * cos_theta
    return (dt(1.0) - g * g) / (dt(4.0) * dt(math.pi) * np.power(denom, dt(1.5)))


def line_integral_shared(falloff: Any, ray_dir_z: Any, origin_terms: Any, dt: Any, exact: bool) -> Any:
    """CalculateLineIntegralShared (HeightFogCommon.ush): ``origin_terms (1 - 2^-F) / F`` with
    ``F = max(-127, falloff ray_dir_z)`` (falloff [1/cm], ray_dir_z [cm]; any real), in the float
    type ``dt``, ``ln 2 origin_terms`` near ``F = 0``.  ``exact``: no Taylor branch.

    >>> round(float(line_integral_shared(1.0, 0.0, 1.0, np.float64, True)), 12)  # ln 2
    0.69314718056
    """
    F = np.maximum(dt(-127.0), falloff * ray_dir_z)
    if exact:
        return origin_terms * (dt(LN2) * phi(NP, dt(LN2) * F))
    with np.errstate(all="ignore"):
        li = (dt(1.0) - np.exp2(-F)) / F
    ln2 = dt(np.log(dt(2.0)))
    taylor = ln2 - (dt(0.5) * (ln2 * ln2)) * F
    return origin_terms * np.where(np.abs(F) > dt(FLT_EPSILON2), li, taylor)


def shade_geometry(C: dict, cam_z_cm: float, rel_cm: np.ndarray, dt: Any, exact: bool) -> dict:
    """The part of :func:`shade` that the directional light's start distance, exponent and colour
    leave alone, per camera-relative receiver position (Unreal cm): ``n`` (the unit view direction,
    3 arrays), ``length`` and ``ray_length`` (beyond StartDistance) [cm], the line integral
    ``shared`` [1/cm] and the optical depth ``integral`` (of ``2^-integral``)."""
    P, P2, P3 = C["P"], C["P2"], C["P3"]
    rel = np.asarray(rel_cm, dtype=dt)
    obs_z = min(dt(cam_z_cm), P[2])
    end = C["end_distance"]
    if end > 0:  # EndDistance: on the receiver's horizontal distance, before the observer clamp
        xy_sqr = rel[..., 0] * rel[..., 0] + rel[..., 1] * rel[..., 1]
        scale = np.where(xy_sqr > end * end, end / np.sqrt(np.maximum(dt(1.0), xy_sqr)), dt(1.0))
        rel = rel * scale[..., None]
    cx, cy = rel[..., 0], rel[..., 1]
    cz = rel[..., 2] + (dt(cam_z_cm) - obs_z)
    len_sqr = cx * cx + cy * cy + cz * cz
    len_inv = dt(1.0) / np.sqrt(np.maximum(len_sqr, dt(1e-8)))
    length = len_sqr * len_inv
    nx, ny, nz = cx * len_inv, cy * len_inv, cz * len_inv

    ray_length = length
    ray_dir_z = cz
    ro = np.broadcast_to(P[0], length.shape)
    ro2 = np.broadcast_to(P2[0], length.shape)
    exclude = P[3]
    if exclude > 0:
        t = exclude * len_inv
        cam_to_excl_z = t * cz
        excl_z = obs_z + cam_to_excl_z
        ray_length = (dt(1.0) - t) * ray_length
        ray_dir_z = ray_dir_z - cam_to_excl_z
        expo = np.maximum(dt(-127.0), P[1] * (excl_z - P3[1]))
        ro = P3[0] * np.exp2(-expo)
        expo2 = np.maximum(dt(-127.0), P2[1] * (excl_z - P2[3]))
        ro2 = P2[2] * np.exp2(-expo2)
    shared = line_integral_shared(P[1], ray_dir_z, ro, dt, exact)
    if P2[2] > 0:  # second layer only when it exists (exact: a zero-density layer adds 0)
        shared = shared + line_integral_shared(P2[1], ray_dir_z, ro2, dt, exact)
    # Robustness (deviation): the shader's ``shared * length`` is NaN when an
    # overflowed (inf) density meets a zero-length ray; an empty ray has no fog.
    # Identical to the shader wherever the shader is not NaN.
    integral = np.where(ray_length > 0, shared * ray_length, dt(0.0))
    return {
        "n": (nx, ny, nz),
        "length": length,
        "ray_length": ray_length,
        "shared": shared,
        "integral": integral,
    }


def directional_lobe(C: dict, geo: dict, dt: Any) -> Any:
    """The directional inscattering's angular factor of :func:`shade` on :func:`shade_geometry`'s
    ``geo``: ``max(cos, 0)^DirectionalInscatteringExponent`` (HG with the volumetric fog's match)."""
    nx, ny, nz = geo["n"]
    light = C["light"]
    if C["match"]:  # HG of the volumetric fog's g at dot(-CameraToReceiverNormalized, L)
        return _hg_shader(C["phase_g"], -(nx * light[0] + ny * light[1] + nz * light[2]), dt)
    cos = saturate(nx * light[0] + ny * light[1] + nz * light[2])
    lobe = np.power(cos, C["dir_exponent"])
    if C["sky"]:  # the sky-atmosphere branch: ... * UniformPhaseFunction
        lobe = lobe * (dt(1.0) / (dt(4.0) * dt(math.pi)))
    return lobe


def directional_opacity(C: dict, geo: dict, dt: Any) -> Any:
    """``1 - T_dir`` of :func:`shade`: the opacity of the part of each ray beyond
    DirectionalInscatteringStartDistance (``C["light"][3]`` [cm]), on :func:`shade_geometry`'s ``geo``."""
    dir_run = np.maximum(geo["ray_length"] - C["light"][3], dt(0.0))
    dir_integral = np.where(dir_run > 0, geo["shared"] * dir_run, dt(0.0))  # no inf * 0 (see above)
    dir_factor = saturate(np.exp2(-dir_integral))
    return dt(1.0) - dir_factor


def shade(C: dict, cam_z_cm: float, rel_cm: np.ndarray, dt: Any, exact: bool) -> Any:
    """GetExponentialHeightFog on camera-relative receiver positions (Unreal cm).

    Returns ``(FogColor (..., 3), ExpFogFactor (...))``.
    """
    P3 = C["P3"]
    min_opacity = C["min_opacity"]
    geo = shade_geometry(C, cam_z_cm, rel_cm, dt, exact)
    length, integral = geo["length"], geo["integral"]

    color = np.asarray(C["color"], dtype=dt)
    light = C["light"]
    dir_inscatter = None
    if light[3] >= 0:
        lobe = directional_lobe(C, geo, dt)
        dir_inscatter = (lobe * directional_opacity(C, geo, dt))[..., None] * np.asarray(
            C["dir_color"], dtype=dt
        )
        if C["match"]:
            dir_inscatter = dir_inscatter * np.asarray(C["albedo"], dtype=dt)
    factor = np.maximum(saturate(np.exp2(-integral)), min_opacity)
    if P3[3] > 0:
        cut = length > P3[3]
        factor = np.where(cut, dt(1.0), factor)
        if dir_inscatter is not None:
            dir_inscatter = np.where(cut[..., None], dt(0.0), dir_inscatter)
    fog_color = color * (dt(1.0) - factor)[..., None]
    if dir_inscatter is not None:
        fog_color = fog_color + dir_inscatter
    return fog_color.astype(dt, copy=False), factor.astype(dt, copy=False)


@register("ue4")
class UE4ExponentialHeightFog(ParamModel[UE4FogParams]):
    """Unreal's exponential height fog; ``params`` in Unreal units (see module doc)."""

    Params = UE4FogParams

    def evaluate(self, camera: Any, world_pos: Any, precision: str = "float32") -> FogResult:
        """Fog of each pixel: camera (3,) and world_pos (..., 3) in fogref metres."""
        dt, cam_z_cm, rel = self.receivers(camera, world_pos, precision)
        C = fog_constants(self.params, cam_z_cm, dt)
        with np.errstate(all="ignore"):
            fog_color, factor = shade(C, cam_z_cm, rel, dt, exact=(dt is np.float64))
        return FogResult(inscatter=fog_color, transmittance=grey(factor, dt))

    @staticmethod
    def receivers(camera: Any, world_pos: Any, precision: str = "float32") -> tuple:
        """``(dt, camera height [cm], receivers relative to the camera (..., 3) [Unreal cm])``: the
        inputs of :func:`shade` that :meth:`evaluate` makes of a camera (3,) and world positions
        (..., 3) in fogref metres (the height rounded to float32 in float32)."""
        dt = dtype_of(precision)
        cam, wp = split(camera, world_pos)
        cam_z_cm = float(np.float32(cam[1] * CM_PER_M)) if dt is np.float32 else cam[1] * CM_PER_M
        return dt, cam_z_cm, world_to_unreal(wp - cam)


# -- exact physical mapping -----------------------------------------------------
def unreal_to_sigma(density: float, falloff: float) -> tuple[float, float]:
    """Editor (FogDensity, FogHeightFalloff) -> (a [1/m], b [1/m]) of ``a exp(-b (y - h))``."""
    return CM_PER_M * LN2 * LN2 * density / 1000.0, CM_PER_M * LN2 * falloff / 1000.0


def sigma_to_unreal(a: float, b: float) -> tuple[float, float]:
    """Inverse of :func:`unreal_to_sigma`."""
    return a * 1000.0 / (CM_PER_M * LN2 * LN2), b * 1000.0 / (CM_PER_M * LN2)


def ue4_to_medium(params: UE4FogParams, albedo: Any = (1.0, 1.0, 1.0), g: float = 0.0) -> FogMedium:
    """The physical medium with the same extinction as the Unreal fog.

    ``sigma_t(y) = a_i exp(-b_i (y - h_i))`` per metre for each layer i with
    density > 0 (:func:`fogref.models.ue4.unreal_to_sigma`, see :mod:`fogref.models.ue4`).
    Albedo and g are free (Unreal has neither; its FogInscatteringColor stands for
    ``albedo * L_sky``).  The inverse is :func:`~fogref.mapping.unreal_basis.base_params`.

    Examples
    --------
    >>> m = ue4_to_medium(UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2, FogHeight=100.0))
    >>> round(m.sigma_t[0], 8), m.layers[0].height
    (0.00096091, 1.0)
    """
    sfd = params.SecondFogData
    specs = [
        (params.FogDensity, params.FogHeightFalloff, params.FogHeight),
        (sfd.FogDensity, sfd.FogHeightFalloff, params.FogHeight + sfd.FogHeightOffset),
    ]
    specs = [s for s in specs if s[0] > 0]
    if not specs:
        return FogMedium(sigma_t=0.0, albedo=albedo, g=g, layers=(ExpLayer(),), source="<ue4_to_medium>")
    a0, _ = unreal_to_sigma(specs[0][0], specs[0][1])
    layers = []
    for d, f, h in specs:
        a, b = unreal_to_sigma(d, f)
        layers.append(ExpLayer(density=a / a0, falloff=b, height=h / CM_PER_M))
    return FogMedium(sigma_t=a0, albedo=albedo, g=g, layers=tuple(layers), source="<ue4_to_medium>")
