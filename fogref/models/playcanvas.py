"""PlayCanvas scene fog: ``FOG_LINEAR``, ``FOG_EXP`` and ``FOG_EXP2`` (``StandardMaterial``).

Follows the PlayCanvas Engine 2.23.3 (npm ``playcanvas`` 2.23.3, tag ``v2.23.3`` of
``playcanvas/engine``, revision b7655d8), held to the real engine in headless Chromium by
``tests/test_web_playcanvas.py``.  ``src/scene/shader-lib/glsl/chunks/common/frag/fog.js``
(the fog chunk, formerly ``fogPS``), fragment path::

    float depth = gl_FragCoord.z / gl_FragCoord.w;
    #if (FOG == LINEAR)  fogFactor = (fog_end - depth) / (fog_end - fog_start);
    #elif (FOG == EXP)   fogFactor = exp(-depth * fog_density);
    #elif (FOG == EXP2)  fogFactor = exp(-depth * depth * fog_density * fog_density);
    return clamp(fogFactor, 0.0, 1.0);
    ...
    vec3 addFog(vec3 color) { return mix(fog_color * dBlendModeFogFactor, color, getFogFactor()); }

The fog coordinate is **not** the eye depth: on WebGL (clip z in [-1, 1], depth range [0, 1])
``gl_FragCoord.z / gl_FragCoord.w = (z_clip + w_clip) / 2 = far (z - near) / (far - near)``
for the eye depth ``z`` and the camera's clip planes ``nearClip``, ``farClip`` (about
``z - near`` when ``far >> near``).  ``dBlendModeFogFactor`` is 1 for opaque materials.

Colours: ``ForwardRenderer.setFogConstants`` sets ``fog_color`` to ``Color.linear`` of
``scene.fog.color``, i.e. ``color^2.2`` on the CPU (``src/core/math/color.js``); material
colours are converted the same way.  ``color`` here is the engine's (gamma-encoded)
``scene.fog.color``; the linear fog colour is ``color^2.2``.

Output: ``lit/frag/end.js`` blends the fog in linear, then ``toneMap`` (the camera's default
``TONEMAP_LINEAR``: times the exposure, 1) and ``gammaCorrectOutput`` (the camera's default
``GAMMA_SRGB``: ``pow(c + 0.0000001, 1/2.2)``, a 2.2 power, not the sRGB curve;
``common/frag/gamma.js``).  :meth:`PlayCanvasFog.evaluate` is the linear blend (a float target
with ``GAMMA_NONE``; ``transmittance = fogFactor`` (grey), ``inscatter = color^2.2 (1 -
fogFactor)``); :func:`gamma_correct_output` gives the default canvas from it.

Background: the camera's clear colour is not fogged (and written unconverted): pixels at
distance >= ``sky_distance`` (fogref puts the sky at
:data:`~fogref.models.base.SKY_DISTANCE`) get no fog.

Units: PlayCanvas has no unit; fogref reads it as metres (y-up, camera looking down -z: the
default ``camera_forward``).  ``density`` [1/m], ``start``, ``end``, ``nearClip``, ``farClip`` [m].
Physical counterpart: none exact (``EXP`` is Beer–Lambert on the remapped depth, exact only as
``nearClip/farClip -> 0`` on the camera axis).  Robustness (deviation): ``end == start`` is
refused (the shader divides by zero).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from fogref import params as valid
from fogref.errors import ParameterError
from fogref.models._num import dtype_of, grey, sky_pixels, split, unit_direction
from fogref.models.base import SKY_DISTANCE, FogResult, ParamModel, register

TYPES = ("linear", "exp", "exp2")


@dataclass(frozen=True)
class PlayCanvasFogParams:
    """``scene.fog`` (``FogParams``) and the camera's clip planes (defaults are PlayCanvas's).

    type: "linear", "exp" or "exp2" (``FOG_*``).  color: ``scene.fog.color`` (gamma-encoded,
    >= 0; the shader gets ``color^2.2``).  density [1/m] (exp, exp2).  start, end [m] (linear,
    end != start).  nearClip, farClip [m]: the camera's (0 < nearClip < farClip).
    camera_forward: fogref-frame unit view direction.  sky_distance [m]: pixels at least this
    far show the clear colour (no fog).

    Examples
    --------
    >>> PlayCanvasFogParams(type="exp", density=0.05).density
    0.05
    >>> PlayCanvasFogParams(nearClip=10.0, farClip=1.0)
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: <PlayCanvasFogParams>: parameter 'farClip': must exceed nearClip (1.0 m)
    """

    type: str = "linear"
    color: tuple = (0.0, 0.0, 0.0)
    density: float = 0.0
    start: float = 1.0
    end: float = 1000.0
    nearClip: float = 0.1
    farClip: float = 1000.0
    camera_forward: tuple = (0.0, 0.0, -1.0)
    sky_distance: float = SKY_DISTANCE

    def __post_init__(self) -> None:
        src = "<PlayCanvasFogParams>"
        valid.choice(self.type, "type", TYPES, src)
        object.__setattr__(self, "color", valid.rgb(self.color, "color", source=src, lo=0.0))
        object.__setattr__(self, "density", valid.number(self.density, "density", source=src, lo=0.0))
        for name in ("start", "end"):
            object.__setattr__(self, name, valid.number(getattr(self, name), name, source=src, unit="m"))
        if self.end == self.start:
            raise ParameterError(src, "end", f"must differ from start ({self.start})")
        for name in ("nearClip", "farClip", "sky_distance"):
            v = valid.number(getattr(self, name), name, source=src, lo=0.0, lo_open=True, unit="m")
            object.__setattr__(self, name, v)
        if not self.farClip > self.nearClip:
            raise ParameterError(src, "farClip", f"must exceed nearClip ({self.farClip} m)")
        object.__setattr__(self, "camera_forward", unit_direction(self.camera_forward, "camera_forward", src))


def gamma_correct_output(linear: Any, dt: Any = np.float32) -> Any:
    """The default canvas in [0, 1] from the linear colour: ``pow(c + 0.0000001, 1/2.2)`` in ``dt``.

    ``gammaCorrectOutput`` of ``common/frag/gamma.js`` (``GAMMA_SRGB``) after ``TONEMAP_LINEAR``
    at exposure 1; clipped to [0, 1] (what the 8-bit canvas holds; negative input reads 0).

    >>> round(float(gamma_correct_output(0.5, np.float64)), 6)
    0.729740
    """
    x = np.maximum(np.asarray(linear, dtype=dt), dt(0.0))
    return np.clip(np.power(x + dt(1e-7), dt(1.0 / 2.2)), dt(0.0), dt(1.0)).astype(dt)


@register("playcanvas")
class PlayCanvasFog(ParamModel[PlayCanvasFogParams]):
    """PlayCanvas scene fog (see module doc).

    Examples
    --------
    >>> fog = PlayCanvasFog(PlayCanvasFogParams(type="exp", density=0.1, nearClip=0.1, farClip=1000.0))
    >>> r = fog.evaluate([0.0, 0.0, 0.0], [[0.0, 0.0, -10.1]], "float64")
    >>> round(float(r.transmittance[0, 0]), 4)     # exp(-0.1 * 1000 (10.1 - 0.1) / 999.9)
    0.3679
    """

    Params = PlayCanvasFogParams

    def fog_depth(self, camera: Any, world_pos: Any, dt: Any = np.float64) -> np.ndarray:
        """``gl_FragCoord.z / gl_FragCoord.w`` [m]: ``far (z - near) / (far - near)`` of the eye depth z."""
        cam, wp = split(camera, world_pos)
        v = (wp - cam).astype(dt)
        f = np.asarray(self.params.camera_forward, dtype=dt)
        z = v[..., 0] * f[0] + v[..., 1] * f[1] + v[..., 2] * f[2]
        n, fa = dt(self.params.nearClip), dt(self.params.farClip)
        return fa * (z - n) / (fa - n)

    def evaluate(self, camera: Any, world_pos: Any, precision: str = "float32", hit: Any = None) -> FogResult:
        """Fog of each pixel (linear): camera (3,), world_pos (..., 3) in metres; ``hit`` (...,) bool,
        False on the pixels that see the background (drawn without fog), else decided by distance
        (:func:`~fogref.models._num.sky_pixels`)."""
        dt = dtype_of(precision)
        p = self.params
        cam, wp = split(camera, world_pos)
        with np.errstate(all="ignore"):
            d = self.fog_depth(cam, wp, dt)
            if p.type == "linear":
                f = (dt(p.end) - d) / (dt(p.end) - dt(p.start))
            elif p.type == "exp":
                f = np.exp(-d * dt(p.density))
            else:
                f = np.exp(-d * d * dt(p.density) * dt(p.density))
            f = np.clip(np.where(np.isnan(f), dt(1.0), f), dt(0.0), dt(1.0))  # NaN: 0 * inf, no fog
        f = np.where(sky_pixels(cam, wp, hit, p.sky_distance), dt(1.0), f).astype(dt)
        color = np.asarray([c**2.2 for c in p.color], dtype=dt)  # Color.linear on the CPU (float64)
        return FogResult(inscatter=color * (dt(1.0) - f)[..., None], transmittance=grey(f, dt))
