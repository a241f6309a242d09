"""Babylon.js scene fog: ``FOGMODE_LINEAR``, ``FOGMODE_EXP`` and ``FOGMODE_EXP2``.

Follows Babylon.js 9.35.0 (npm ``@babylonjs/core`` 9.35.0, tag ``9.35.0`` of
``BabylonJS/Babylon.js``), held to the real engine in headless Chromium by
``tests/test_web_babylon.py``.
``packages/dev/core/src/Shaders/ShadersInclude/fogFragmentDeclaration.fx``::

    #define E 2.71828
    float CalcFogFactor() {
        float fogCoeff = 1.0;
        float fogStart = vFogInfos.y; float fogEnd = vFogInfos.z; float fogDensity = vFogInfos.w;
        float fogDistance = length(vFogDistance);
        if (FOGMODE_LINEAR == vFogInfos.x) fogCoeff = (fogEnd - fogDistance) / (fogEnd - fogStart);
        else if (FOGMODE_EXP == vFogInfos.x) fogCoeff = 1.0 / pow(E, fogDistance * fogDensity);
        else if (FOGMODE_EXP2 == vFogInfos.x)
            fogCoeff = 1.0 / pow(E, fogDistance * fogDistance * fogDensity * fogDensity);
        return clamp(fogCoeff, 0.0, 1.0);
    }

``fogFragment.fx``: ``color.rgb = mix(vFogColor, color.rgb, fog)`` (``fog = CalcFogFactor()``;
``PBRMaterial`` first raises it to 2.2 with ``toLinearSpace``, not modelled here), and
``fogVertex.fx``: ``vFogDistance = (view * worldPos).xyz``: the fog coordinate is the
**distance** from the camera (``length`` of the view-space position), not the depth.

Notes: ``E`` is 2.71828, not e, so ``1/pow(E, x) = exp(-0.99999933 x)`` (6.7e-7 less
optical depth); ``EXP2`` squares the optical depth (``exp(-(density d)^2)``); the factor is
clamped to [0, 1], so ``LINEAR`` is flat before ``fogStart`` and after ``fogEnd``.

Units: Babylon has no unit; fogref reads it as metres (Babylon is y-up; the fog depends on
the distance only, so handedness does not matter).  ``fogDensity`` [1/m], ``fogStart``,
``fogEnd`` [m].  ``fogColor``: ``scene.fogColor``, in the colour space the material works in.

Output: ``StandardMaterial`` blends in the values it is given and, with the default image
processing (exposure 1, contrast 1, no tone mapping: no ``IMAGEPROCESSING`` define), writes
the result unchanged: a float render target holds it and the default canvas holds it rounded
to 8 bits (Babylon does no colour management there: whatever the colours are, the canvas
shows them as sRGB values).  This port reproduces both (``transmittance = fogCoeff`` (grey),
``inscatter = fogColor (1 - fogCoeff)``).

Background: ``scene.clearColor`` is not fogged: pixels at distance >= ``sky_distance``
(fogref puts the sky at :data:`~fogref.models.base.SKY_DISTANCE`) get no fog.

Physical counterpart: ``EXP`` is a homogeneous medium with ``sigma_t = fogDensity`` [1/m]
(to the 6.7e-7 of ``E``); ``EXP2`` and ``LINEAR`` have none.  Robustness (deviation):
``fogEnd == fogStart`` is refused (the shader divides by zero).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from fogref import params as valid
from fogref.errors import ParameterError
from fogref.models._num import dtype_of, grey, sky_pixels, split, view_ray
from fogref.models.base import SKY_DISTANCE, FogResult, ParamModel, register

MODES = ("LINEAR", "EXP", "EXP2")
#: ``fogFragmentDeclaration.fx``'s ``#define E 2.71828``.
E = 2.71828


@dataclass(frozen=True)
class BabylonFogParams:
    """``scene.fogMode`` and its settings (defaults are Babylon's: density 0.1, start 0, end 1000).

    fogMode: "LINEAR", "EXP" or "EXP2" (``Scene.FOGMODE_*``).  fogDensity [1/m] (EXP, EXP2).
    fogStart, fogEnd [m] (LINEAR; fogEnd != fogStart).  fogColor: RGB >= 0.
    sky_distance [m]: pixels at least this far show the clear colour (no fog).

    Examples
    --------
    >>> BabylonFogParams(fogMode="EXP", fogDensity=0.02).fogDensity
    0.02
    >>> BabylonFogParams(fogMode="LINEAR", fogStart=5.0, fogEnd=5.0)
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: <BabylonFogParams>: parameter 'fogEnd': must differ from fogStart (5.0)
    """

    fogMode: str = "EXP"
    fogDensity: float = 0.1
    fogStart: float = 0.0
    fogEnd: float = 1000.0
    fogColor: tuple = (0.2, 0.2, 0.3)
    sky_distance: float = SKY_DISTANCE

    def __post_init__(self) -> None:
        src = "<BabylonFogParams>"
        valid.choice(self.fogMode, "fogMode", MODES, src)
        density = valid.number(self.fogDensity, "fogDensity", source=src, lo=0.0, unit="1/m")
        object.__setattr__(self, "fogDensity", density)
        for name in ("fogStart", "fogEnd"):
            object.__setattr__(self, name, valid.number(getattr(self, name), name, source=src, unit="m"))
        if self.fogEnd == self.fogStart:
            raise ParameterError(src, "fogEnd", f"must differ from fogStart ({self.fogStart})")
        sky = valid.number(self.sky_distance, "sky_distance", source=src, lo=0.0, lo_open=True, unit="m")
        object.__setattr__(self, "sky_distance", sky)
        object.__setattr__(self, "fogColor", valid.rgb(self.fogColor, "fogColor", source=src, lo=0.0))


def calc_fog_factor(p: BabylonFogParams, distance: Any, dt: Any) -> Any:
    """``CalcFogFactor()`` in ``dt``: the clamped ``fogCoeff`` (the transmittance) at ``distance`` [m].

    >>> round(float(calc_fog_factor(BabylonFogParams(fogMode="EXP", fogDensity=0.1), 10.0, np.float64)), 7)
    0.3678797
    """
    d = np.asarray(distance, dtype=dt)
    with np.errstate(all="ignore"):
        if p.fogMode == "LINEAR":
            coeff = (dt(p.fogEnd) - d) / (dt(p.fogEnd) - dt(p.fogStart))
        else:
            x = d * dt(p.fogDensity) if p.fogMode == "EXP" else d * d * dt(p.fogDensity) * dt(p.fogDensity)
            coeff = dt(1.0) / np.power(dt(E), np.where(np.isnan(x), dt(0.0), x))  # 0 * inf: no fog
    return np.clip(coeff, dt(0.0), dt(1.0)).astype(dt)


@register("babylon")
class BabylonFog(ParamModel[BabylonFogParams]):
    """Babylon.js scene fog (see module doc).

    Examples
    --------
    >>> fog = BabylonFog(BabylonFogParams(fogMode="EXP2", fogDensity=0.01))
    >>> r = fog.evaluate([0.0, 0.0, 0.0], [[60.0, 0.0, -80.0]], "float64")
    >>> round(float(r.transmittance[0, 0]), 6)     # 1/E^((0.01 * 100)^2), on the distance
    0.367880
    """

    Params = BabylonFogParams

    def evaluate(self, camera: Any, world_pos: Any, precision: str = "float32", hit: Any = None) -> FogResult:
        """Fog of each pixel: camera (3,), world_pos (..., 3) in metres; ``hit`` (...,) bool,
        False on the pixels that see the background (drawn without fog), else decided by distance
        (:func:`~fogref.models._num.sky_pixels`)."""
        dt = dtype_of(precision)
        p = self.params
        cam, wp = split(camera, world_pos)
        coeff = calc_fog_factor(p, view_ray(cam, wp, dt)[1], dt)
        coeff = np.where(sky_pixels(cam, wp, hit, p.sky_distance), dt(1.0), coeff).astype(dt)
        color = np.asarray(p.fogColor, dtype=dt)
        return FogResult(inscatter=color * (dt(1.0) - coeff)[..., None], transmittance=grey(coeff, dt))
