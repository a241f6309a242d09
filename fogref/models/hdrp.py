"""Unity HDRP height fog (Fog volume override, non-volumetric path).

Reproduces the **linear** HDR fog of HDRP's opaque atmospheric-scattering pass (pre-exposed
colour, before tonemapping).  Source: HDRP ``Fog.cs`` (``UpdateShaderVariablesGlobalCB``),
``VolumeRendering.cs`` (``ScaleHeightFromLayerDepth``, ``ExtinctionFromMeanFreePath``)
and ``Runtime/Lighting/AtmosphericScattering/AtmosphericScattering.hlsl``
(``OpticalDepthHeightFog``, ``EvaluateAtmosphericScattering``: the fallback fog
``GetFogColor * exposure * albedo * (1 - exp(-od))``, read in ``Unity-Technologies/Graphics``
at commit 0119fcbd7e6704145be47f88b843e757cc9a81d7) in the High Definition Render Pipeline
package (``com.unity.render-pipelines.high-definition``); the Fog volume override's
parameter list in Unity's HDRP manual.

Units: HDRP is y-up **metres** (same as fogref), and uses **exp** (not exp2).
CPU set-up: ``extinction = 1 / meanFreePath`` (the "Fog Attenuation Distance" is
the mean free path at the base height), ``layerDepth = max(0.01, maximumHeight -
baseHeight)``, ``H = layerDepth * 0.144765`` (= layerDepth / ln 1000: the density
has fallen to 0.001 at maximumHeight), ``_HeightFogExponents = (1/H, H)``,
``_HeightFogBaseScattering = albedo * extinction``.

Density: ``sigma_t(y) = extinction * exp(-max(y - baseHeight, 0) / H)``:
homogeneous below the base height, exponential above (:class:`fogref.media.HDRPLayer`).
``OpticalDepthHeightFog`` integrates it exactly, except that it clamps
``|cos zenith| >= 0.001`` (horizontal rays above the base saturate at
``1000 H``); float64 mode drops that clamp (exact closed form with ``phi``).

Compositing: ``T = exp(-od)`` (grey), ``inscatter = fogColor * albedo * (1 - T)``
(constant "Color" mode; exposure 1), ``final = scene * T + inscatter``.  A surface's ray is
integrated over its whole distance; a sky pixel's over ``maxFogDistance``
(``Runtime/Lighting/AtmosphericScattering/OpaqueAtmosphericScattering.shader``, commit
1390609ca74ecc860907a6e87759644f944fbada: a pixel at the far plane is put at
``GetCurrentViewPosition() - V * _MaxFogDistance``; sky pixels as in
:func:`~fogref.models._num.sky_pixels`).  (HDRP's ray tracing clamps every ray to
``min(t, _MaxFogDistance)``; that is not the raster pass.)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fogref import params as valid
from fogref.media import NP
from fogref.media.closed_form import phi
from fogref.models._num import dtype_of, grey, sky_pixels, split, view_ray
from fogref.models.base import SKY_DISTANCE, FogResult, ParamModel, register

#: VolumeRendering.cs ScaleHeightFromLayerDepth: 1 / ln(1000).
LAYER_DEPTH_TO_H = 0.144765


@dataclass(frozen=True)
class HDRPFogParams:
    """HDRP Fog override (metres).  meanFreePath = "Fog Attenuation Distance".  Defaults are
    ``Fog.cs``'s (``color = Color.grey``, passed to the shader as it is: linear); fogref models the
    Constant Color mode (HDRP's default mode is Sky Color)."""

    meanFreePath: float = 400.0
    baseHeight: float = 0.0
    maximumHeight: float = 50.0
    albedo: tuple = (1.0, 1.0, 1.0)
    color: tuple = (0.5, 0.5, 0.5)
    maxFogDistance: float = 5000.0

    def __post_init__(self) -> None:
        # Fog.cs: meanFreePath MinFloatParameter(400, 1), maxFogDistance MinFloatParameter(5000, 0),
        # baseHeight/maximumHeight FloatParameter.  The mean free path's editor minimum of 1 m is
        # not enforced: fogref's mapping of a dense medium gives less, and the model is exact there.
        src = "<HDRPFogParams>"
        for name, lo, lo_open in (
            ("meanFreePath", 0.0, True),
            ("maxFogDistance", 0.0, False),
            ("baseHeight", -math.inf, False),
            ("maximumHeight", -math.inf, False),
        ):
            x = valid.number(getattr(self, name), name, source=src, lo=lo, lo_open=lo_open, unit="m")
            object.__setattr__(self, name, x)
        object.__setattr__(self, "albedo", valid.rgb(self.albedo, "albedo", source=src, lo=0.0))
        object.__setattr__(self, "color", valid.rgb(self.color, "color", source=src, lo=0.0))

    def scale_height(self, dt: Any = np.float64) -> float:
        """H [m] as the CPU computes it."""
        depth = max(dt(0.01), dt(self.maximumHeight) - dt(self.baseHeight))
        return dt(depth * dt(LAYER_DEPTH_TO_H))


def optical_depth_height_fog(
    base_extinction: Any,
    base_height: Any,
    exps: Any,
    cos_zenith: Any,
    start_height: Any,
    interval: Any,
    dt: Any,
    exact: bool = False,
) -> Any:
    """AtmosphericScattering.hlsl ``OpticalDepthHeightFog`` (vectorised)."""
    rcpH, H = exps
    Z = cos_zenith
    end_height = start_height + interval * Z
    min_height = np.minimum(start_height, end_height)
    h = np.maximum(min_height - base_height, dt(0.0))
    if exact:
        absZ = np.abs(Z)
        hom = np.where(
            absZ > 0,
            np.clip((base_height - min_height) / np.where(absZ > 0, absZ, dt(1.0)), 0.0, interval),
            np.where(start_height <= base_height, interval, dt(0.0)),
        )
        exp_dist = interval - hom
        mult = np.exp(-h * rcpH) * exp_dist * phi(NP, exp_dist * absZ * rcpH)
        return base_extinction * (hom + mult)
    absZ = np.maximum(np.abs(Z), dt(0.001))
    rcpAbsZ = dt(1.0) / absZ
    hom = np.clip((base_height - min_height) * rcpAbsZ, dt(0.0), interval)
    exp_dist = interval - hom
    mult = np.exp(-h * rcpH) * (dt(1.0) - np.exp(-exp_dist * absZ * rcpH)) * (rcpAbsZ * H)
    return base_extinction * (hom + mult)


@register("hdrp")
class HDRPFog(ParamModel[HDRPFogParams]):
    """HDRP height fog (see module doc)."""

    Params = HDRPFogParams

    def optical_depth(
        self, camera: Any, world_pos: Any, precision: str = "float32", hit: Any = None
    ) -> np.ndarray:
        """Optical depth (dimensionless) of each pixel's ray; ``hit`` (...,) bool, False on the
        pixels that see the sky (integrated over ``maxFogDistance``)."""
        dt = dtype_of(precision)
        q = self.params
        cam, wp = split(camera, world_pos)
        H = q.scale_height(dt)
        ext = dt(1.0) / dt(q.meanFreePath)
        v, dist = view_ray(cam, wp, dt)
        sky = sky_pixels(cam, wp, hit, SKY_DISTANCE)
        with np.errstate(all="ignore"):
            cos_z = np.where(dist > 0, v[..., 1] / np.where(dist > 0, dist, dt(1.0)), dt(0.0))
            interval = np.where(sky, dt(q.maxFogDistance), dist)
            od = optical_depth_height_fog(
                ext,
                dt(q.baseHeight),
                (dt(1.0) / H, H),
                cos_z,
                dt(cam[1]),
                interval,
                dt,
                exact=(dt is np.float64),
            )
        return od.astype(dt, copy=False)

    def evaluate(self, camera: Any, world_pos: Any, precision: str = "float32", hit: Any = None) -> FogResult:
        """Fog of each pixel: camera (3,), world_pos (..., 3) in metres; ``hit`` as in
        :meth:`optical_depth`."""
        dt = dtype_of(precision)
        q = self.params
        T = np.exp(-self.optical_depth(camera, world_pos, precision, hit))
        col = np.asarray(q.color, dtype=dt) * np.asarray(q.albedo, dtype=dt)
        return FogResult(inscatter=col * (dt(1.0) - T)[..., None], transmittance=grey(T, dt))
