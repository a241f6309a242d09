"""Unreal Engine 5 Local Fog Volume, in front of the Exponential Height Fog.

Reproduces the **linear** HDR fog the height-fog pass blends into scene colour (before
tonemapping) for one Local Fog Volume with no rotation.  Sources, read in the public mirror of
UE 5.8.0 ``unicorn2022/UE5.8.0`` at commit 5d9a05c15b1f8c6d7b3354b360677ce30d688149:

* ``Engine/Shaders/Private/LocalFogVolumes/LocalFogVolumeCommon.ush``:
  ``GetLFVInstanceContribution``, ``LocalFogVolumeEvaluateAnalyticalIntegral`` (its
  "reference path"), ``LocalFogVolumeEvaluateInScattering``;
* ``Engine/Source/Runtime/Renderer/Private/LocalFogVolumeRendering.cpp``:
  ``GetLocalFogVolumeViewSortingData`` (the packing: falloff ``max(HeightFogFalloff, 1) *
  0.01``; extinctions, falloff and emissive as R11G11B10 floats, albedo and phase g as
  UNorm8) and ``r.LocalFogVolume.GlobalStartDistance`` (default 2000 cm);
* ``Engine/Shaders/Private/HeightFogPixelShader.usf``: the volume in front of the height fog,
  ``(LFV.rgb + HeightFog.rgb * LFV.a, LFV.a * HeightFog.a)``;
* ``Engine/Shaders/Common.ush``: ``RayIntersectSphere`` (both -1 when the ray misses).

The volume is the unit sphere of the volume's frame: ``u = (p - Location) / FogUniformScale``
(Unreal cm, z-up), a sphere of radius ``R = FogUniformScale`` cm.  Along the chord of the view
ray inside it (from ``max(GlobalStartDistance, FogStartDistance)`` to the shaded point), in
unit-sphere lengths::

    tau_r = RadialFogExtinction * 3/4 * int (1 - |u|^2) dt
    tau_h = HeightFogExtinction * int exp(-k (u_z - HeightFogOffset)) dt,  k = max(HeightFogFalloff, 1) / 100
    T_u   = 1 - (1 - exp(-tau_r)) (1 - exp(-tau_h))          (the coverages multiply)
    T     = exp(log(T_u) * R / 100) = T_u^(R [m])

so the height term masks the radial one: with ``HeightFogExtinction = 0`` the volume is
invisible (``T_u = 1``), as in the engine.  The light, ``L`` toward the sun::

    inscatter = ((E_sun * HG(-g, dot(d, L)) + SkyLighting) * FogAlbedo + FogEmissive) * (1 - T)

with ``HenyeyGreensteinPhase(-g, cos) = (1 - g^2) / (4 pi (1 + g^2 - 2 g cos)^1.5)`` (forward
scattering peaks looking into the sun).  ``SkyLighting`` is ``SkyLightColor *
SkyLightVolumetricScatteringIntensity * GetSkySHDiffuseSimple(-g d)``: for a uniform sky of
radiance ``L_sky`` (the SH's band 1 vanishes) it is ``L_sky``.  Composited with the height fog
(:class:`~fogref.models.ue4.UE4ExponentialHeightFog`, ``HeightFog``):
``transmittance = T * T_hf`` (grey), ``inscatter = L_lfv + L_hf * T``.

Units: the volume in Unreal's frame (cm, z-up: ``(x, y, z)_Unreal = 100 (x, z, y)_fogref``);
``RadialFogExtinction``, ``HeightFogExtinction`` [1/m]; ``HeightFogFalloff`` the editor's value;
``HeightFogOffset`` in unit-sphere units; colours linear RGB (``DirectionalLightColor`` the
sun's illuminance, scene radiance units x sr).  ``precision="float32"`` rounds the packed
parameters as the CPU packs them (R11G11B10: 6 mantissa bits for the extinctions and the
emissive's R and G, 5 for the falloff and B, truncated; UNorm8: ``floor(255 x) / 255``) and
computes in float32; ``"float64"`` leaves the packing out.  Not modelled: rotation (the volume's
frame is the world's), several volumes, ``r.LocalFogVolume.RenderIntoVolumetricFog``.
Robustness (deviation): a pixel at the camera has no view direction; its chord is empty.

The truth renders the physical volume (:class:`~fogref.media.local_fog_volume.LocalFogVolume`,
the ``heightfog`` parameters ``lfv_*``) exactly, its density added to the height fog's.  Against
it on one scene (``docs/findings.md``, "Unreal's Local Fog Volume against the truth"): with the
height term saturated the transmittance agrees (+0.2 %, the packing); the coverage product with
``HeightFogExtinction = 1`` lets 9.9 % more light through than the summed densities; the
unshadowed light gives +93 % of the truth's single scattering (64 spp, SE 1.2 %) and the missing
multiple scattering (a third of the truth's inscatter) cancels part of it: +27 % in all.

Examples
--------
>>> import numpy as np
>>> lfv = UELocalFogVolume(UELocalFogVolumeParams(FogUniformScale=1000.0, GlobalStartDistance=0.0))
>>> r = lfv.evaluate(np.array([0.0, 0.0, -20.0]), np.array([[0.0, 0.0, 20.0]]), "float64")
>>> bool(0.0 < r.transmittance[0, 0] < 1.0)
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from fogref.errors import ParameterError
from fogref.models._num import dtype_of, grey, split
from fogref.models.base import FogResult, ParamModel, register
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams, direction_to_unreal, world_to_unreal
from fogref.params import number, vector
from fogref.params import rgb as valid_rgb

#: ``r.LocalFogVolume.GlobalStartDistance``'s default [cm] (LocalFogVolumeRendering.cpp).
GLOBAL_START_DISTANCE = 2000.0
#: ``GetLocalFogVolumeViewSortingData``: ``SafeFalloffThreshold`` and ``FalloffScaleUI``.
SAFE_FALLOFF_THRESHOLD, FALLOFF_SCALE_UI = 1.0, 0.01
#: ``LocalFogVolumeEvaluateAnalyticalIntegral``: the floor of ``|RayDirU.z|`` and of ``Factor0``.
SAFE_DIR_THRESHOLD, MIN_FACTOR0 = 0.0001, -80.0
CENTIMETER_TO_METER = 0.01


def pack_float(x: Any, mantissa_bits: int) -> Any:
    """``AsFloat111110`` then ``UnpackR11G11B10F``: ``x >= 0`` rounded to a half float, its
    mantissa truncated to ``mantissa_bits`` (6 for R and G, 5 for B); float32.

    >>> float(pack_float(0.7, 6)), float(pack_float(0.7, 5))
    (0.6953125, 0.6875)
    """
    h = np.asarray(np.float16(np.minimum(np.asarray(x, np.float32), np.float32(65504.0))))
    keep = np.uint16((0x7FFF >> (10 - mantissa_bits)) << (10 - mantissa_bits))
    return (h.view(np.uint16) & keep).view(np.float16).astype(np.float32)


def pack_unorm8(x: Any) -> Any:
    """``AsUNorm8888`` then ``UnpackRGBA8``: ``uint(clamp(255 x, 0, 255)) / 255``; float32.

    >>> round(float(pack_unorm8(0.6)), 6)
    0.6
    """
    return (np.floor(np.clip(np.asarray(x, np.float64) * 255.0, 0.0, 255.0)) / 255.0).astype(np.float32)


@dataclass(frozen=True)
class UELocalFogVolumeParams:
    """One Local Fog Volume (``ALocalFogVolume``'s component), its light and the height fog.

    Location: the centre (X, Y, Z) [cm], Unreal's frame.  FogUniformScale: the radius [cm], > 0.
    RadialFogExtinction, HeightFogExtinction [1/m] >= 0; HeightFogFalloff (editor value, the
    CPU uses ``max(f, 1) / 100`` per unit radius); HeightFogOffset (unit-sphere units).
    FogAlbedo: linear RGB in [0, 1]; FogPhaseG in [0, 1] (the CPU packs it as UNorm8);
    FogEmissive: linear RGB >= 0.  FogStartDistance, GlobalStartDistance [cm] >= 0.
    DirectionalLightDirection: unit vector toward the sun in Unreal's frame, or None (no sun);
    DirectionalLightColor: the sun's illuminance, linear RGB.  SkyLighting: linear RGB (see the
    module doc).  HeightFog: the Exponential Height Fog behind the volume
    (:class:`~fogref.models.ue4.UE4FogParams` or its fields as a dict), or None.

    Examples
    --------
    >>> UELocalFogVolumeParams().FogUniformScale
    100.0
    >>> UELocalFogVolumeParams(FogPhaseG=-0.2)
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: <UELocalFogVolumeParams>: parameter 'FogPhaseG': -0.2 is outside [0, 1]
    """

    Location: tuple = (0.0, 0.0, 0.0)
    FogUniformScale: float = 100.0
    RadialFogExtinction: float = 1.0
    HeightFogExtinction: float = 1.0
    HeightFogFalloff: float = 1000.0
    HeightFogOffset: float = 0.0
    FogAlbedo: tuple = (1.0, 1.0, 1.0)
    FogPhaseG: float = 0.2
    FogEmissive: tuple = (0.0, 0.0, 0.0)
    FogStartDistance: float = 0.0
    GlobalStartDistance: float = GLOBAL_START_DISTANCE
    DirectionalLightDirection: tuple | None = None
    DirectionalLightColor: tuple = (0.0, 0.0, 0.0)
    SkyLighting: tuple = (0.0, 0.0, 0.0)
    HeightFog: Any = None

    def __post_init__(self) -> None:
        src = "<UELocalFogVolumeParams>"
        object.__setattr__(
            self, "Location", tuple(float(x) for x in vector(self.Location, "Location", source=src))
        )
        for name, lo, lo_open, hi, unit in (
            ("FogUniformScale", 0.0, True, math.inf, "cm"),
            ("RadialFogExtinction", 0.0, False, math.inf, "1/m"),
            ("HeightFogExtinction", 0.0, False, math.inf, "1/m"),
            ("HeightFogFalloff", 0.0, False, math.inf, ""),
            ("HeightFogOffset", -math.inf, False, math.inf, ""),
            ("FogPhaseG", 0.0, False, 1.0, ""),
            ("FogStartDistance", 0.0, False, math.inf, "cm"),
            ("GlobalStartDistance", 0.0, False, math.inf, "cm"),
        ):
            x = number(getattr(self, name), name, source=src, lo=lo, hi=hi, lo_open=lo_open, unit=unit)
            object.__setattr__(self, name, x)
        object.__setattr__(
            self, "FogAlbedo", valid_rgb(self.FogAlbedo, "FogAlbedo", source=src, lo=0.0, hi=1.0)
        )
        for name in ("FogEmissive", "DirectionalLightColor", "SkyLighting"):
            object.__setattr__(self, name, valid_rgb(getattr(self, name), name, source=src, lo=0.0))
        if self.DirectionalLightDirection is not None:
            w = np.asarray(vector(self.DirectionalLightDirection, "DirectionalLightDirection", source=src))
            if not np.linalg.norm(w) > 0:
                raise ParameterError(src, "DirectionalLightDirection", "expected a non-zero vector, or None")
            object.__setattr__(
                self, "DirectionalLightDirection", tuple(float(x) for x in w / np.linalg.norm(w))
            )
        if isinstance(self.HeightFog, dict):
            object.__setattr__(self, "HeightFog", UE4FogParams(**self.HeightFog))
        if self.HeightFog is not None and not isinstance(self.HeightFog, UE4FogParams):
            raise ParameterError(
                src, "HeightFog", f"expected UE4FogParams, a dict or None, got {self.HeightFog!r}"
            )

    def with_sun(self, direction_world: Any, illuminance: Any) -> "UELocalFogVolumeParams":
        """Copy with the sun given in **fogref's** frame (y-up, toward the sun) and its illuminance."""
        return replace(
            self,
            DirectionalLightDirection=direction_to_unreal(direction_world),
            DirectionalLightColor=illuminance,
        )


@register("ue5_lfv")
class UELocalFogVolume(ParamModel[UELocalFogVolumeParams]):
    """Unreal Engine 5's Local Fog Volume over its Exponential Height Fog (see module doc)."""

    Params = UELocalFogVolumeParams

    def evaluate(self, camera: Any, world_pos: Any, precision: str = "float32") -> FogResult:
        """Fog of each pixel: camera (3,) and world_pos (..., 3) in fogref metres."""
        dt = dtype_of(precision)
        p = self.params
        cam, wp = split(camera, world_pos)
        with np.errstate(all="ignore"):
            T, L = _volume(p, world_to_unreal(cam), world_to_unreal(wp), dt)
            if p.HeightFog is not None:
                hf = UE4ExponentialHeightFog(p.HeightFog).evaluate(cam, wp, precision)
                L = L + hf.inscatter * T[..., None]
                T = T * hf.transmittance[..., 0]
        return FogResult(inscatter=L.astype(dt), transmittance=grey(T, dt))


def _volume(p: UELocalFogVolumeParams, cam_cm: Any, wp_cm: Any, dt: Any) -> tuple[Any, Any]:
    """``GetLFVInstanceContribution`` for one unrotated volume: ``(T (...), inscatter (..., 3))``."""
    packed = dt is np.float32
    S = dt(p.FogUniformScale)
    falloff = max(p.HeightFogFalloff, SAFE_FALLOFF_THRESHOLD) * FALLOFF_SCALE_UI
    if packed:
        rho_r, rho_h = pack_float(p.RadialFogExtinction, 6), pack_float(p.HeightFogExtinction, 6)
        k = pack_float(np.float32(falloff), 5)
        emissive = np.array([pack_float(e, b) for e, b in zip(p.FogEmissive, (6, 6, 5))], np.float32)
        albedo, g = pack_unorm8(p.FogAlbedo), pack_unorm8(p.FogPhaseG)
    else:
        rho_r, rho_h, k = p.RadialFogExtinction, p.HeightFogExtinction, falloff
        emissive, albedo, g = np.asarray(p.FogEmissive), np.asarray(p.FogAlbedo), p.FogPhaseG
    rho_r, rho_h, k, g = dt(rho_r), dt(rho_h), dt(k), dt(g)
    center = np.asarray(p.Location, dtype=np.float64)
    ray_pos = ((cam_cm - center) / p.FogUniformScale).astype(dt)
    depth_pos = ((wp_cm - center) / p.FogUniformScale).astype(dt)
    view = (wp_cm - cam_cm).astype(dt)
    view_len = np.sqrt(np.sum(view * view, axis=-1))
    d = view / view_len[..., None]  # CamRayWorldDir (unit); RayDirU is the same direction here
    d = np.where(np.isfinite(d), d, dt(0.0))
    # RayIntersectSphere(RayPosU, RayDirU, float4(0, 0, 0, 1)): both -1 when the ray misses
    qb = dt(2.0) * np.sum(d * ray_pos, axis=-1)
    qc = np.sum(ray_pos * ray_pos) - dt(1.0)
    qa = np.sum(d * d, axis=-1)
    disc = qb * qb - dt(4.0) * qa * qc
    root = np.sqrt(np.maximum(disc, dt(0.0)))
    t0 = np.where(disc >= 0, (-qb - root) / (dt(2.0) * qa), dt(-1.0))
    t1 = np.where(disc >= 0, (-qb + root) / (dt(2.0) * qa), dt(-1.0))
    start_u = dt(max(p.GlobalStartDistance, p.FogStartDistance)) * (dt(1.0) / S)
    depth_vec = depth_pos - ray_pos
    depth_u = np.sqrt(np.sum(depth_vec * depth_vec, axis=-1))
    t0 = np.minimum(np.maximum(start_u, t0), depth_u)
    t1 = np.minimum(np.maximum(start_u, t1), depth_u)
    length_u = np.where((t0 > 0) | (t1 > 0), np.maximum(dt(0.0), np.abs(t1 - t0)), dt(0.0))
    length_u = np.where(np.isfinite(length_u) & (qa > 0), length_u, dt(0.0))
    o = ray_pos + d * t0[..., None]
    tau_r = _radial_depth(rho_r, o, d, length_u, dt)
    tau_h = _height_depth(rho_h, k, dt(p.HeightFogOffset), o, d, length_u, dt)
    t_u = dt(1.0) - (dt(1.0) - np.exp(-tau_r)) * (dt(1.0) - np.exp(-tau_h))
    T = np.exp(np.log(t_u) * S * dt(CENTIMETER_TO_METER))  # exp(-OpticalDepth * UniformScale * cm_to_m)
    T = np.where(length_u > 0, T, dt(1.0))
    light = np.zeros(3, dtype=dt)
    in_scatter = np.zeros(d.shape, dtype=dt) + np.asarray(p.SkyLighting, dtype=dt)
    if p.DirectionalLightDirection is not None:
        light = np.asarray(p.DirectionalLightDirection, dtype=dt)
        cos = d[..., 0] * light[0] + d[..., 1] * light[1] + d[..., 2] * light[2]
        G = -g  # HenyeyGreensteinPhase(-FogInstance.PhaseG, dot(RayDirWorld, L))
        phase = (dt(1.0) - G * G) / (
            dt(4.0) * dt(math.pi) * np.power(dt(1.0) + G * G + dt(2.0) * G * cos, dt(1.5))
        )
        in_scatter = np.asarray(p.DirectionalLightColor, dtype=dt) * phase[..., None] + in_scatter
    in_scatter = in_scatter * np.asarray(albedo, dtype=dt) + np.asarray(emissive, dtype=dt)
    return T.astype(dt), (in_scatter * (dt(1.0) - T)[..., None]).astype(dt)


def _radial_depth(rho: Any, o: Any, d: Any, length: Any, dt: Any) -> Any:
    """The radial optical depth in unit lengths: ``rho 3/4 int (1 - |o + t d|^2) dt`` over the chord."""
    b = np.sum(d * o, axis=-1)
    c = np.sum(o * o, axis=-1) - dt(1.0)
    h = b * b - c
    sq = np.sqrt(np.maximum(h, dt(0.0)))
    l0 = np.maximum(-b - sq, dt(0.0))
    l1 = np.minimum(np.maximum(-b + sq, dt(0.0)), length)
    i0 = -(c * l0 + b * l0 * l0 + l0 * l0 * l0 / dt(3.0))
    i1 = -(c * l1 + b * l1 * l1 + l1 * l1 * l1 / dt(3.0))
    tau = np.maximum(dt(0.0), rho * (i1 - i0) * dt(0.75))
    return np.where((h >= 0) & (rho > 0), tau, dt(0.0))


def _height_depth(rho: Any, k: Any, offset: Any, o: Any, d: Any, length: Any, dt: Any) -> Any:
    """The height optical depth in unit lengths, with the shader's safe direction and clamp."""
    if not rho > 0:
        return np.zeros(length.shape, dtype=dt)
    dz = d[..., 2]
    sign = np.where(dz >= 0, dt(1.0), dt(-1.0))
    dz = np.where(np.abs(dz) < dt(SAFE_DIR_THRESHOLD), dt(SAFE_DIR_THRESHOLD) * sign, dz)
    f0 = np.maximum(dt(MIN_FACTOR0), (o[..., 2] - offset) * k)
    f1 = dz * length * k
    return (rho / (k * dz)) * (np.exp(-f0) - np.exp(-(f0 + f1)))
