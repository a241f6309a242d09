"""Unity built-in render pipeline fog: Linear, Exp and Exp2 (forward fog).

Follows Unity 2019.4's built-in shaders and reproduces the colour the forward shader writes in
a project with the **Linear** colour space (a Gamma-space project blends in sRGB; not modelled).
Source: ``CGIncludes/UnityCG.cginc`` (``UNITY_CALC_FOG_FACTOR_RAW``,
``UNITY_Z_0_FAR_FROM_CLIPSPACE``, ``UNITY_FOG_LERP_COLOR``), read in the unofficial mirror of
Unity's built-in shaders ``TwoTailsGames/Unity-Built-in-Shaders`` (README: 2019.4.1) at commit
09db4ee6ce064d3de5364341de62fc7165bb7e75, and ``UnityShaderVariables.cginc``
(``unity_FogParams``); J. Flick, Catlike Coding, "Rendering 14: Fog"
(https://catlikecoding.com/unity/tutorials/rendering/part-14/).

Units: Unity is y-up, **metres** (left-handed; irrelevant to fog), the same
lengths as fogref, so no conversion.  ``unity_FogParams`` (CPU, float32):
``x = density / sqrt(ln 2)`` (Exp2), ``y = density / ln 2`` (Exp),
``z = -1 / (end - start)``, ``w = end / (end - start)`` (Linear).  The factor is
evaluated with **exp2**: ``Exp``: ``exp2(-y c) = exp(-density c)``; ``Exp2``:
``exp2(-(x c)^2) = exp(-(density c)^2)``; ``Linear``: ``c z + w``.

Fog coordinate ``c``: ``"depth"`` (Unity's default: the clip-space depth fed
through ``UNITY_Z_0_FAR_FROM_CLIPSPACE``, which on D3D-style APIs equals
``far (z_eye - near) / (far - near)``; with ``clip_near = None`` the plain eye
depth ``z_eye = dot(p - camera, camera_forward)``) or ``"distance"``
(``length(p - camera)``, catlikecoding's FOG_DISTANCE).

Compositing: ``color.rgb = lerp(unity_FogColor.rgb, color.rgb, saturate(f))``,
i.e. ``transmittance = saturate(f)`` (grey), ``inscatter = fogColor (1 - T)``, in the material
shaders only: the skybox (``DefaultResourcesExtra/Skybox-Procedural.shader`` at the same
commit) applies no fog, so sky pixels (the truth's ``hit`` mask is False, or without it a float64
distance of at least :data:`~fogref.models.base.SKY_DISTANCE`, see
:func:`~fogref.models._num.sky_pixels`) get ``transmittance = 1``, ``inscatter = 0``.

Physical counterpart: Exp fog on *distance* is exactly a homogeneous medium with
``sigma_t = density`` [1/m].  Exp2 and Linear have none; :func:`fogref.mapping.engines.unity_to_medium`
gives the homogeneous medium that matches the transmittance at a reference
distance (default: Linear at ``(start + end) / 2``, Exp2 at ``1 / density``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fogref import params as valid
from fogref.errors import ParameterError
from fogref.models._num import LN2, dtype_of, grey, saturate, sky_pixels, split
from fogref.models.base import SKY_DISTANCE, FogResult, ParamModel, register

MODES = ("linear", "exp", "exp2")


#: Unity's default fog colour, (0.5, 0.5, 0.5) in the Lighting window (sRGB, as every Unity ``Color``),
#: as linear RGB (``Color.linear``, the IEC 61966-2-1 curve).
DEFAULT_FOG_COLOR = (0.21404114, 0.21404114, 0.21404114)


@dataclass(frozen=True)
class UnityFogParams:
    """RenderSettings fog (Lighting window), Unity units (metres).

    fogMode: "linear", "exp" or "exp2".  fogDensity [1/m] (Exp, Exp2).
    fogStartDistance, fogEndDistance [m] (Linear).  fogColor: linear RGB (the Lighting window's
    sRGB colour linearised, as a Linear-colour-space project does).  Defaults are Unity's.
    fog_coordinate: "depth" or "distance".  camera_forward: fogref-frame unit
    view direction (for "depth").  clip_near, clip_far [m]: if given, the depth
    is remapped as UNITY_Z_0_FAR_FROM_CLIPSPACE does on D3D/Metal/Vulkan.
    """

    fogMode: str = "exp2"
    fogDensity: float = 0.01
    fogStartDistance: float = 0.0
    fogEndDistance: float = 300.0
    fogColor: tuple = DEFAULT_FOG_COLOR
    fog_coordinate: str = "depth"
    camera_forward: tuple = (0.0, 0.0, -1.0)
    clip_near: float | None = None
    clip_far: float | None = None

    def __post_init__(self) -> None:
        src = "<UnityFogParams>"
        valid.choice(self.fogMode, "fogMode", MODES, src)
        valid.choice(self.fog_coordinate, "fog_coordinate", ("depth", "distance"), src)
        density = valid.number(self.fogDensity, "fogDensity", source=src, lo=0.0)
        object.__setattr__(self, "fogDensity", density)
        for name in ("fogStartDistance", "fogEndDistance"):
            object.__setattr__(self, name, valid.number(getattr(self, name), name, source=src, unit="m"))
        if self.fogMode == "linear" and not self.fogEndDistance > self.fogStartDistance:
            raise ParameterError(src, "fogEndDistance", "must be greater than fogStartDistance")
        object.__setattr__(self, "fogColor", valid.rgb(self.fogColor, "fogColor", source=src, lo=0.0))
        f = np.asarray(valid.vector(self.camera_forward, "camera_forward", source=src), dtype=np.float64)
        if not np.linalg.norm(f) > 0:
            raise ParameterError(src, "camera_forward", "(0, 0, 0) has no direction")
        object.__setattr__(self, "camera_forward", tuple(float(x) for x in f / np.linalg.norm(f)))

    def fog_params(self, dt: Any = np.float32) -> tuple:
        """unity_FogParams (x, y, z, w) as the CPU computes them (in ``dt``)."""
        d = dt(self.fogDensity)
        rng = dt(self.fogEndDistance) - dt(self.fogStartDistance)
        rng = rng if rng != 0 else dt(1e-30)
        return (d / dt(math.sqrt(LN2)), d / dt(LN2), dt(-1.0) / rng, dt(self.fogEndDistance) / rng)


def unity_fog_factor(mode: str, fog_params: Any, coord: Any, dt: Any) -> Any:
    """UNITY_CALC_FOG_FACTOR_RAW: the un-saturated fog factor for coordinate ``coord``."""
    x, y, z, w = fog_params
    if mode == "linear":
        return coord * z + w
    if mode == "exp":
        f = y * coord
        return np.exp2(-f)
    f = x * coord
    return np.exp2(-f * f)


@register("unity")
class UnityBuiltinFog(ParamModel[UnityFogParams]):
    """Unity built-in Linear/Exp/Exp2 fog (see module doc)."""

    Params = UnityFogParams

    def fog_coordinate(self, camera: Any, world_pos: Any, dt: Any = np.float64) -> np.ndarray:
        """The fog coordinate c [m] of each pixel (eye depth or distance)."""
        p = self.params
        cam, wp = split(camera, world_pos)
        v = (wp - cam).astype(dt)
        if p.fog_coordinate == "distance":
            return np.sqrt(np.sum(v * v, axis=-1))
        fwd = np.asarray(p.camera_forward, dtype=dt)
        z = v[..., 0] * fwd[0] + v[..., 1] * fwd[1] + v[..., 2] * fwd[2]
        if p.clip_near is None:
            return z
        n, f = dt(p.clip_near), dt(p.clip_far)
        zc = n * (f - z) / (f - n)  # reversed-Z clip-space z
        return np.maximum((dt(1.0) - zc / n) * f, dt(0.0))

    def evaluate(self, camera: Any, world_pos: Any, precision: str = "float32", hit: Any = None) -> FogResult:
        """Fog of each pixel: camera (3,), world_pos (..., 3) in metres; ``hit`` (...,) bool,
        False on the pixels that see the sky (the skybox: no fog)."""
        dt = dtype_of(precision)
        p = self.params
        cam, wp = split(camera, world_pos)
        sky = sky_pixels(cam, wp, hit, SKY_DISTANCE)
        with np.errstate(all="ignore"):
            c = self.fog_coordinate(camera, world_pos, dt)
            factor = saturate(unity_fog_factor(p.fogMode, p.fog_params(dt), c, dt)).astype(dt)
            factor = np.where(sky, dt(1.0), factor).astype(dt)
        color = np.asarray(p.fogColor, dtype=dt)
        return FogResult(inscatter=color * (dt(1.0) - factor)[..., None], transmittance=grey(factor, dt))
