"""three.js scene fog: ``Fog`` (linear, smoothstep) and ``FogExp2`` (exponential squared).

Follows three.js r187 (npm ``three`` 0.187.0, tag ``r187`` of ``mrdoob/three.js``), held to
the real engine in headless Chromium by ``tests/test_web_threejs.py``.
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

Output (``output``): where the frame goes decides where the fog is blended.  In
``src/renderers/shaders/ShaderLib/meshbasic.glsl.js`` (and every other material) the
``fog_fragment`` chunk comes **after** ``colorspace_fragment``:

* ``"linear"``: a linear render target (``WebGLRenderTarget``, e.g. ``FloatType``): the blend
  above in linear RGB.  ``transmittance = 1 - fogFactor`` (grey), ``inscatter = color *
  fogFactor``; ``final = scene * transmittance + inscatter``.
* ``"canvas"``: the default canvas (``outputColorSpace = SRGBColorSpace``, ``NoToneMapping``):
  the shaded colour is first encoded (``sRGBTransferOETF`` of
  ``colorspace_pars_fragment.glsl.js``: ``1.055 x^0.41666 - 0.055``, ``12.92 x`` up to
  0.0031308) and the fog colour is converted to sRGB on the CPU
  (``WebGLMaterials.refreshFogUniforms``: ``getUnlitUniformColorSpace``, ``LinearToSRGB`` of
  ``src/math/ColorManagement.js``), and the two are mixed in sRGB.  That is not affine in the
  linear scene colour, so :meth:`ThreeJSFog.evaluate` returns a :class:`CanvasBlend`, whose
  :meth:`~CanvasBlend.display` is the canvas value (before its 8-bit rounding) and whose
  ``composite`` is that value decoded to linear; its ``transmittance`` and ``inscatter`` are
  the linear target's (what ``fogref compare`` reads).

Background: ``scene.background`` is the clear colour or a mesh drawn with ``fog: false``
(``src/renderers/webgl/WebGLBackground.js``): pixels at distance >= ``sky_distance`` (fogref
puts the sky at :data:`~fogref.models.base.SKY_DISTANCE`) get no fog.

Physical counterpart: **none exact**.  three.js has no height term, no sun and no
``exp`` (Beer–Lambert) mode: ``FogExp2`` is ``exp(-(density z)^2)`` on the eye depth.
:func:`threejs_sigma` gives the homogeneous medium with the same transmittance at a
reference depth (``FogExp2``: ``sigma = density^2 r``, ``r = 1/density`` by
default, i.e. ``sigma = density``; ``Fog``: ``-ln(1 - f(r))/r`` at ``r = (near + far)/2``).
Robustness (deviations): ``far == near`` is refused (GLSL's smoothstep is undefined there);
on the canvas, a scene colour is clipped to [0, 1] before its encoding (GLSL's ``pow`` of a
negative number is undefined; the 8-bit canvas holds [0, 1]).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fogref import params as P
from fogref.errors import ParameterError
from fogref.media import rgb
from fogref.models._num import dtype_of, glsl_smoothstep, grey, sky_pixels, split, unit_direction
from fogref.models.base import SKY_DISTANCE, FogResult, ParamModel, register

MODES = ("Fog", "FogExp2")
OUTPUTS = ("linear", "canvas")


@dataclass(frozen=True)
class ThreeFogParams:
    """``scene.fog`` (three.js): ``Fog(color, near, far)`` or ``FogExp2(color, density)``.

    mode: "Fog" or "FogExp2".  color: linear RGB.  near, far [m] (Fog, far > near,
    defaults 1 and 1000 as in three.js).  density [1/m] (FogExp2, default 0.00025 as
    in three.js).  camera_forward: fogref-frame unit view direction (the depth axis).
    output: "linear" (a linear render target) or "canvas" (the default sRGB canvas; see the
    module doc).  sky_distance [m]: pixels at least this far show the background (no fog).

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
    output: str = "linear"
    sky_distance: float = SKY_DISTANCE

    def __post_init__(self) -> None:
        src = "<ThreeFogParams>"
        if self.mode not in MODES:
            raise ParameterError(src, "mode", f"expected one of {MODES}, got {self.mode!r}")
        if self.output not in OUTPUTS:
            raise ParameterError(src, "output", f"expected one of {OUTPUTS}, got {self.output!r}")
        if not (math.isfinite(self.sky_distance) and self.sky_distance > 0):
            raise ParameterError(src, "sky_distance", f"value {self.sky_distance} must be finite and > 0")
        for name, lo in (("density", 0.0), ("near", -math.inf), ("far", -math.inf)):
            object.__setattr__(self, name, P.number(getattr(self, name), name, source=src, lo=lo))
        if self.mode == "Fog" and not self.far > self.near:
            raise ParameterError(src, "far", f"must be greater than near ({self.far} <= {self.near})")
        object.__setattr__(self, "color", rgb(self.color, "color", src, lo=0.0))  # linear RGB >= 0
        object.__setattr__(self, "camera_forward", unit_direction(self.camera_forward, "camera_forward", src))


def srgb_transfer_oetf(linear: Any, dt: Any) -> Any:
    """three.js's ``sRGBTransferOETF`` (``colorspace_pars_fragment.glsl.js``) in ``dt``.

    Domain [0, 1] (clipped to it first, as the canvas holds).  ``pow(x, 0.41666) * 1.055 -
    0.055``, ``12.92 x`` for ``x <= 0.0031308``; the exponent is three.js's 0.41666, not 1/2.4.

    >>> round(float(srgb_transfer_oetf(0.5, np.float64)), 6)
    0.735361
    """
    x = np.clip(np.asarray(linear, dtype=dt), dt(0.0), dt(1.0))
    with np.errstate(all="ignore"):
        curve = np.power(x, dt(0.41666)) * dt(1.055) - dt(0.055)
    return np.where(x <= dt(0.0031308), x * dt(12.92), curve).astype(dt)


def srgb_transfer_eotf(encoded: Any, dt: Any) -> Any:
    """three.js's ``sRGBTransferEOTF`` in ``dt``: the decoding of an sRGB value in [0, 1].

    ``pow(x * 0.9478672986 + 0.0521327014, 2.4)``, ``x * 0.0773993808`` for ``x <= 0.04045``.

    >>> round(float(srgb_transfer_eotf(srgb_transfer_oetf(0.5, np.float64), np.float64)), 4)
    0.5
    """
    x = np.clip(np.asarray(encoded, dtype=dt), dt(0.0), dt(1.0))
    curve = np.power(x * dt(0.9478672986) + dt(0.0521327014), dt(2.4))
    return np.where(x <= dt(0.04045), x * dt(0.0773993808), curve).astype(dt)


def linear_to_srgb_cpu(color: tuple) -> tuple:
    """three.js's CPU conversion ``LinearToSRGB`` (``src/math/ColorManagement.js``), float64.

    >>> [round(c, 6) for c in linear_to_srgb_cpu((0.0, 0.002, 0.5))]
    [0.0, 0.02584, 0.735361]
    """
    return tuple(c * 12.92 if c < 0.0031308 else 1.055 * c**0.41666 - 0.055 for c in color)


@dataclass
class CanvasBlend(FogResult):
    """Fog blended on three.js's sRGB canvas, after the colour-space conversion.

    ``transmittance`` and ``inscatter`` are the linear target's (see the module doc).
    ``factor`` (...,): ``fogFactor``; ``fog_srgb`` (3,): the fog colour's uniform on the
    canvas (sRGB), both in the evaluation's dtype.

    Examples
    --------
    >>> fog = ThreeJSFog(ThreeFogParams(mode="FogExp2", density=1.0, color=(1.0, 0.0, 0.0),
    ...                                 output="canvas"))
    >>> r = fog.evaluate([0.0, 0.0, 0.0], [[0.0, 0.0, -1.0]], "float64")
    >>> (r.display(np.array([[0.0, 0.0, 0.0]])) * 255).round(1).tolist()   # 255 (1 - 1/e) red
    [[161.2, 0.0, 0.0]]
    """

    factor: np.ndarray
    fog_srgb: np.ndarray

    def display(self, scene_rgb: Any) -> np.ndarray:
        """The canvas value in [0, 1] (sRGB, before the 8-bit rounding) over a linear ``scene_rgb``:
        ``mix(sRGBTransferOETF(scene), fog_srgb, fogFactor)``."""
        dt = self.factor.dtype.type
        enc = srgb_transfer_oetf(scene_rgb, dt)
        f = self.factor[..., None]
        return np.clip(enc * (dt(1.0) - f) + self.fog_srgb * f, dt(0.0), dt(1.0)).astype(dt)

    def composite(self, scene_rgb: np.ndarray) -> np.ndarray:
        """The canvas over a linear ``scene_rgb``, decoded to linear RGB (``sRGBTransferEOTF``)."""
        return srgb_transfer_eotf(self.display(scene_rgb), self.factor.dtype.type)


@register("threejs")
class ThreeJSFog(ParamModel[ThreeFogParams]):
    """three.js Fog / FogExp2 (see module doc).

    Examples
    --------
    >>> fog = ThreeJSFog(ThreeFogParams(mode="FogExp2", density=0.01))
    >>> r = fog.evaluate([0.0, 0.0, 0.0], [[0.0, 0.0, -100.0]], "float64")
    >>> round(float(r.transmittance[0, 0]), 6)     # exp(-(0.01 * 100)^2)
    0.367879
    >>> float(fog.evaluate([0.0, 0.0, 0.0], [[0.0, 0.0, -1e5]]).transmittance[0, 0])  # background: no fog
    1.0
    """

    Params = ThreeFogParams

    def fog_depth(self, camera: Any, world_pos: Any, dt: Any = np.float64) -> np.ndarray:
        """``vFogDepth`` [m]: the eye depth ``dot(p - camera, camera_forward)`` of each pixel."""
        cam, wp = split(camera, world_pos)
        v = (wp - cam).astype(dt)
        f = np.asarray(self.params.camera_forward, dtype=dt)
        return v[..., 0] * f[0] + v[..., 1] * f[1] + v[..., 2] * f[2]

    def evaluate(self, camera: Any, world_pos: Any, precision: str = "float32", hit: Any = None) -> FogResult:
        """Fog of each pixel: camera (3,), world_pos (..., 3) in metres; ``hit`` (...,) bool,
        False on the pixels that see the background (drawn without fog), else decided by distance
        (:func:`~fogref.models._num.sky_pixels`).

        A :class:`CanvasBlend` for ``output="canvas"``, a :class:`FogResult` otherwise.
        """
        dt = dtype_of(precision)
        p = self.params
        cam, wp = split(camera, world_pos)
        with np.errstate(all="ignore"):
            z = self.fog_depth(cam, wp, dt)
            if p.mode == "FogExp2":
                d = dt(p.density)
                factor = dt(1.0) - np.exp(-d * d * z * z)
            else:
                factor = glsl_smoothstep(p.near, p.far, z, dt)
            factor = np.where(np.isfinite(factor), factor, dt(1.0)).astype(dt)
            factor = np.where(sky_pixels(cam, wp, hit, p.sky_distance), dt(0.0), factor).astype(dt)
        color = np.asarray(p.color, dtype=dt)
        inscatter, transmittance = color * factor[..., None], grey(dt(1.0) - factor, dt)
        if p.output == "linear":
            return FogResult(inscatter=inscatter, transmittance=transmittance)
        fog_srgb = np.asarray(linear_to_srgb_cpu(p.color), dtype=dt)
        return CanvasBlend(inscatter, transmittance, factor=factor, fog_srgb=fog_srgb)
