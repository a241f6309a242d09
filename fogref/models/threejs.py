"""three.js scene fog: ``Fog`` (linear, smoothstep) and ``FogExp2`` (exponential squared).

Source (verified against the repository ``mrdoob/three.js``):
``src/renderers/shaders/ShaderChunk/fog_fragment.glsl.js``::

    #ifdef FOG_EXP2
        float fogFactor = 1.0 - exp( - fogDensity * fogDensity * vFogDepth * vFogDepth );
    #else
        float fogFactor = smoothstep( fogNear, fogFar, vFogDepth );
    #endif
    gl_FragColor.rgb = mix( gl_FragColor.rgb, fogColor, fogFactor );

and ``src/renderers/shaders/ShaderChunk/fog_vertex.glsl.js`` (``vFogDepth = - mvPosition.z``):
the fog coordinate is the **eye depth** along the camera's forward axis, not the
distance (older releases called it ``fogDepth`` and used ``exp2(... * LOG2)``, the
same value).  GLSL ``smoothstep(e0, e1, x)``: ``t = clamp((x - e0)/(e1 - e0), 0, 1)``,
``t * t * (3 - 2 t)``.

Units: three.js has no unit; fogref reads it as metres, y-up (three.js is y-up,
right-handed, camera looking down -z: the default ``camera_forward``).
``fogDensity`` [1/m], ``near``/``far`` [m].  ``color`` linear RGB (three.js converts
the sRGB ``Color`` to the working colour space on the CPU).

Compositing: ``transmittance = 1 - fogFactor`` (grey), ``inscatter = color * fogFactor``.

Physical counterpart: **none exact**.  three.js has no height term, no sun and no
``exp`` (Beer–Lambert) mode: ``FogExp2`` is ``exp(-(density z)^2)`` on the eye depth.
:func:`threejs_sigma` gives the homogeneous medium with the same transmittance at a
reference depth (``FogExp2``: ``sigma = density^2 r``, ``r = 1/density`` by
default, i.e. ``sigma = density``; ``Fog``: ``-ln(1 - f(r))/r`` at ``r = (near + far)/2``).
Robustness (deviation): ``far == near`` is refused (GLSL's smoothstep is undefined there).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fogref import params as P
from fogref.errors import ParameterError
from fogref.media import ExpLayer, FogMedium, rgb
from fogref.models._num import dtype_of, grey, split
from fogref.models.base import FogResult, register

MODES = ("Fog", "FogExp2")


@dataclass(frozen=True)
class ThreeFogParams:
    """``scene.fog`` (three.js): ``Fog(color, near, far)`` or ``FogExp2(color, density)``.

    mode: "Fog" or "FogExp2".  color: linear RGB.  near, far [m] (Fog, far > near,
    defaults 1 and 1000 as in three.js).  density [1/m] (FogExp2, default 0.00025 as
    in three.js).  camera_forward: fogref-frame unit view direction (the depth axis).

    Examples
    --------
    >>> ThreeFogParams(mode="FogExp2", density=0.01).density
    0.01
    >>> ThreeFogParams(mode="Fog", near=5.0, far=5.0)
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: <ThreeFogParams>: parameter 'far': must be greater than near (5.0 <= 5.0)
    """

    mode: str = "FogExp2"
    color: tuple = (1.0, 1.0, 1.0)
    near: float = 1.0
    far: float = 1000.0
    density: float = 0.00025
    camera_forward: tuple = (0.0, 0.0, -1.0)

    def __post_init__(self) -> None:
        src = "<ThreeFogParams>"
        if self.mode not in MODES:
            raise ParameterError(src, "mode", f"expected one of {MODES}, got {self.mode!r}")
        for name, lo in (("density", 0.0), ("near", -math.inf), ("far", -math.inf)):
            object.__setattr__(self, name, P.number(getattr(self, name), name, source=src, lo=lo))
        if self.mode == "Fog" and not self.far > self.near:
            raise ParameterError(src, "far", f"must be greater than near ({self.far} <= {self.near})")
        object.__setattr__(self, "color", rgb(self.color, "color", src, lo=0.0))  # linear RGB >= 0
        f = np.asarray(self.camera_forward, dtype=np.float64)
        n = float(np.linalg.norm(f))
        if f.shape != (3,) or not (math.isfinite(n) and n > 0):
            raise ParameterError(src, "camera_forward", "expected a non-zero finite 3-vector")
        object.__setattr__(self, "camera_forward", tuple(float(x) for x in f / n))


def glsl_smoothstep(e0: Any, e1: Any, x: Any, dt: Any) -> Any:
    """GLSL ``smoothstep(e0, e1, x)`` in ``dt`` (e1 > e0)."""
    t = np.minimum(np.maximum((x - dt(e0)) / (dt(e1) - dt(e0)), dt(0.0)), dt(1.0))
    return t * t * (dt(3.0) - dt(2.0) * t)


@register("threejs")
class ThreeJSFog:
    """three.js Fog / FogExp2 (see module doc).

    Examples
    --------
    >>> fog = ThreeJSFog(ThreeFogParams(mode="FogExp2", density=0.01))
    >>> r = fog.evaluate([0.0, 0.0, 0.0], [[0.0, 0.0, -100.0]], "float64")
    >>> round(float(r.transmittance[0, 0]), 6)     # exp(-(0.01 * 100)^2)
    0.367879
    """

    Params = ThreeFogParams

    def __init__(self, params: ThreeFogParams | None = None):
        self.params = params or ThreeFogParams()

    def fog_depth(self, camera: Any, world_pos: Any, dt: Any = np.float64) -> np.ndarray:
        """``vFogDepth`` [m]: the eye depth ``dot(p - camera, camera_forward)`` of each pixel."""
        cam, wp = split(camera, world_pos)
        v = (wp - cam).astype(dt)
        f = np.asarray(self.params.camera_forward, dtype=dt)
        return v[..., 0] * f[0] + v[..., 1] * f[1] + v[..., 2] * f[2]

    def evaluate(self, camera: Any, world_pos: Any, precision: str = "float32") -> FogResult:
        """Fog of each pixel: camera (3,), world_pos (..., 3) in metres."""
        dt = dtype_of(precision)
        p = self.params
        with np.errstate(all="ignore"):
            z = self.fog_depth(camera, world_pos, dt)
            if p.mode == "FogExp2":
                d = dt(p.density)
                factor = dt(1.0) - np.exp(-d * d * z * z)
            else:
                factor = glsl_smoothstep(p.near, p.far, z, dt)
            factor = np.where(np.isfinite(factor), factor, dt(1.0)).astype(dt)
        color = np.asarray(p.color, dtype=dt)
        return FogResult(inscatter=color * factor[..., None], transmittance=grey(dt(1.0) - factor, dt))

    def to_medium(self, **kw: Any) -> FogMedium:
        return threejs_to_medium(self.params, **kw)


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


def threejs_to_medium(
    params: ThreeFogParams,
    reference_depth: float | None = None,
    albedo: Any = (1.0, 1.0, 1.0),
    g: float = 0.0,
) -> FogMedium:
    """Homogeneous :class:`~fogref.media.FogMedium` nearest to ``params`` (see :func:`threejs_sigma`)."""
    return FogMedium(
        sigma_t=threejs_sigma(params, reference_depth),
        albedo=albedo,
        g=g,
        layers=(ExpLayer(1.0, 0.0, 0.0),),
        source="<threejs_to_medium>",
    )
