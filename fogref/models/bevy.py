"""Bevy ``DistanceFog``: ``FogFalloff::{Linear, Exponential, ExponentialSquared, Atmospheric}``.

Follows Bevy's ``DistanceFog`` (the name since Bevy 0.15; ``bevyengine/bevy``) and reproduces
the **linear** HDR colour the PBR fragment shader writes before tonemapping:

* ``crates/bevy_pbr/src/render/fog.wgsl`` (commit c75754ebce7bfd43c6bbd62f0000483c0141d740;
  ``scattering_adjusted_fog_color``, ``linear_fog``, ``exponential_fog``,
  ``exponential_squared_fog``, ``atmospheric_fog``);
* ``crates/bevy_pbr/src/render/pbr_functions.wgsl`` (commit
  5b608baeafd4b2204ade9fe53ec0c5db8c189dac; ``apply_fog``: ``distance = length(world -
  camera)``; the directional lobe ``scattering += pow(max(dot(v, l), 0),
  directional_light_exponent) * light.color.rgb * view.exposure`` over the directional
  lights, ``v`` the unit view vector, ``l`` = ``direction_to_light``, only when
  ``directional_light_color.a > 0``), called by the mesh fragment shaders only (``if
  (fog.mode != FOG_MODE_OFF && (material.flags & STANDARD_MATERIAL_FLAGS_FOG_ENABLED_BIT) !=
  0u)`` in ``pbr.wgsl``);
* ``crates/bevy_pbr/src/render/fog.rs`` (``prepare_fog``: ``be = (start, end, 0)`` for
  Linear, ``(density, 0, 0)`` for Exponential and ExponentialSquared, ``be = extinction``
  and ``bi = inscattering`` for Atmospheric; colours as ``LinearRgba``);
* ``crates/bevy_core_pipeline/src/skybox/skybox.wgsl`` (commit
  002c68066a98faf210ce337539a6c107bf9cad0f): ``skybox_fragment`` returns the cube map's
  sample and nothing else: **the skybox (and the clear colour) is not fogged**.

The fog colour (``scattering_adjusted_fog_color``): ``c = base_color.rgb + scattering *
directional_light_color.rgb * directional_light_color.a`` (alpha ``a = base_color.a``).
Then, with ``d`` the distance [m]:

* Linear: ``f = a (1 - clamp((end - d)/(end - start), 0, 1))``, ``mix(input, c, f)``;
* Exponential: ``f = a (1 - 1/exp(d density))``;
* ExponentialSquared: ``f = a (1 - 1/exp((d density)^2))``;
* Atmospheric (per RGB channel): ``E = 1 - 1/exp(d extinction)``, ``I = 1 - 1/exp(d
  inscattering)``, ``out = input (1 - E a) + c I a``.

So ``transmittance = 1 - f`` (grey) or ``1 - E a`` (RGB), ``inscatter = c f`` or ``c I a``
on meshes; on the background (sky pixels: the truth's ``hit`` mask is False, or without it a
float64 distance of at least :data:`~fogref.models.base.SKY_DISTANCE`, see
:func:`~fogref.models._num.sky_pixels`) ``transmittance = 1`` and ``inscatter = 0``.

Units: Bevy is y-up, right-handed, **metres** by convention, the same frame as fogref.
``density``, ``extinction``, ``inscattering`` [1/m]; ``start``/``end`` [m].  The light's
``color * exposure`` is one parameter here, ``light_color`` (linear RGB), and
``light_direction`` points **toward** the sun (Bevy's ``direction_to_light``).

Physical counterpart: Exponential (and Atmospheric with ``extinction = inscattering``)
is exactly a homogeneous medium, ``sigma_t = density`` [1/m]; Atmospheric with an RGB
``extinction`` is exactly a homogeneous medium with coloured extinction.  Bevy's fog
has no height term: an exponential height profile has no exact counterpart.  Linear
and ExponentialSquared have none either (:func:`bevy_sigma` gives the nearest medium).
float64 forms the transmittance as ``(1 - a) + a exp(-x)`` (the same value without the
cancellation of ``1 - (1 - 1/exp(x))``).  Robustness (deviations): ``d`` is floored at 1e-30
where the shader divides by it (the
pixel at the camera); ``end == start`` is refused for Linear (the shader divides by 0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fogref import params as P
from fogref.errors import ParameterError
from fogref.media import rgb
from fogref.models._num import dtype_of, grey, sky_pixels, split, unit_direction, view_ray
from fogref.models.base import SKY_DISTANCE, FogResult, ParamModel, register

FALLOFFS = ("Linear", "Exponential", "ExponentialSquared", "Atmospheric")


@dataclass(frozen=True)
class BevyFogParams:
    """``DistanceFog`` (Bevy), plus the one directional light it scatters.

    falloff: "Linear", "Exponential", "ExponentialSquared" or "Atmospheric".
    start, end [m] (Linear); density [1/m] (Exponential, ExponentialSquared);
    extinction, inscattering: RGB [1/m] (Atmospheric).  color: linear RGBA (the alpha
    scales the whole fog).  directional_light_color: linear RGBA (alpha 0: no lobe),
    directional_light_exponent: the lobe's power.  light_direction: unit vector toward
    the sun (fogref frame); light_color: the light's linear RGB colour times the view's
    exposure.  Defaults are Bevy's ``DistanceFog::default()`` (Linear 0..100 m, white,
    no lobe; exponent 8).

    Examples
    --------
    >>> BevyFogParams(falloff="Exponential", density=0.02).density
    0.02
    >>> BevyFogParams(falloff="Fog")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: <BevyFogParams>: parameter 'falloff': expected one of ('Linear', \
'Exponential', 'ExponentialSquared', 'Atmospheric'), got 'Fog'
    """

    falloff: str = "Linear"
    start: float = 0.0
    end: float = 100.0
    density: float = 0.0
    extinction: tuple = (0.0, 0.0, 0.0)
    inscattering: tuple = (0.0, 0.0, 0.0)
    color: tuple = (1.0, 1.0, 1.0, 1.0)
    directional_light_color: tuple = (0.0, 0.0, 0.0, 0.0)
    directional_light_exponent: float = 8.0
    light_direction: tuple = (0.0, 1.0, 0.0)
    light_color: tuple = (1.0, 1.0, 1.0)

    def __post_init__(self) -> None:
        src = "<BevyFogParams>"
        if self.falloff not in FALLOFFS:
            raise ParameterError(src, "falloff", f"expected one of {FALLOFFS}, got {self.falloff!r}")
        for name, lo in (("density", 0.0), ("start", -math.inf), ("end", -math.inf)):
            object.__setattr__(self, name, P.number(getattr(self, name), name, source=src, lo=lo))
        e = P.number(self.directional_light_exponent, "directional_light_exponent", source=src, lo=0.0)
        object.__setattr__(self, "directional_light_exponent", e)
        if self.falloff == "Linear" and not self.end > self.start:
            raise ParameterError(src, "end", f"must be greater than start ({self.end} <= {self.start})")
        for name in ("extinction", "inscattering"):
            object.__setattr__(self, name, rgb(getattr(self, name), name, src, lo=0.0))
        object.__setattr__(self, "light_color", rgb(self.light_color, "light_color", src, lo=0.0))
        for name in ("color", "directional_light_color"):  # linear RGBA: RGB >= 0, alpha in [0, 1]
            v = getattr(self, name)
            if isinstance(v, (str, bytes)) or not hasattr(v, "__len__") or len(v) not in (3, 4):
                raise ParameterError(src, name, f"expected (r, g, b) or (r, g, b, a), got {v!r}")
            c = rgb(tuple(v[:3]), name, src, lo=0.0)
            a = P.number(v[3], f"{name} alpha", source=src, lo=0.0, hi=1.0) if len(v) == 4 else 1.0
            object.__setattr__(self, name, (*c, a))
        object.__setattr__(
            self, "light_direction", unit_direction(self.light_direction, "light_direction", src)
        )


def _one_minus_inv_exp(x: Any, dt: Any) -> Any:
    """``1 - 1/exp(x)`` as the WGSL writes it (exp overflows to inf: 1 - 0 = 1)."""
    return dt(1.0) - dt(1.0) / np.exp(x)


@register("bevy")
class BevyDistanceFog(ParamModel[BevyFogParams]):
    """Bevy DistanceFog (see module doc).

    Examples
    --------
    >>> fog = BevyDistanceFog(BevyFogParams(falloff="Exponential", density=0.01))
    >>> r = fog.evaluate([0.0, 0.0, 0.0], [[100.0, 0.0, 0.0]], "float64")
    >>> round(float(r.transmittance[0, 0]), 6)     # exp(-0.01 * 100)
    0.367879
    """

    Params = BevyFogParams

    def evaluate(self, camera: Any, world_pos: Any, precision: str = "float32", hit: Any = None) -> FogResult:
        """Fog of each pixel: camera (3,), world_pos (..., 3) in metres; ``hit`` (...,) bool,
        False on the pixels that see the sky (the skybox: no fog)."""
        dt = dtype_of(precision)
        p = self.params
        cam, wp = split(camera, world_pos)
        v, d = view_ray(cam, wp, dt)
        sky = sky_pixels(cam, wp, hit, SKY_DISTANCE)
        with np.errstate(all="ignore"):
            base = np.asarray(p.color[:3], dtype=dt)
            a = dt(p.color[3])
            color = np.broadcast_to(base, d.shape + (3,)).astype(dt)
            if p.directional_light_color[3] > 0:
                l = np.asarray(p.light_direction, dtype=dt)
                vn = v / np.maximum(d, dt(1e-30))[..., None]
                cos = vn[..., 0] * l[0] + vn[..., 1] * l[1] + vn[..., 2] * l[2]
                lobe = np.power(np.maximum(cos, dt(0.0)), dt(p.directional_light_exponent))
                scattering = lobe[..., None] * np.asarray(p.light_color, dtype=dt)
                dl = p.directional_light_color
                color = color + scattering * np.asarray(dl[:3], dtype=dt) * dt(dl[3])
            exact = dt is np.float64  # same values, without the cancellation of 1 - (1 - 1/exp(x))
            if p.falloff == "Atmospheric":
                xe = d[..., None] * np.asarray(p.extinction, dtype=dt)
                I = _one_minus_inv_exp(d[..., None] * np.asarray(p.inscattering, dtype=dt), dt)
                trans = (dt(1.0) - a) + a * np.exp(-xe) if exact else dt(1.0) - _one_minus_inv_exp(xe, dt) * a
                insc = color * I * a
            else:
                if p.falloff == "Linear":
                    s, e = dt(p.start), dt(p.end)
                    f = dt(1.0) - np.minimum(np.maximum((e - d) / (e - s), dt(0.0)), dt(1.0))
                    t = dt(1.0) - a * f
                else:
                    x = d * dt(p.density)
                    if p.falloff == "ExponentialSquared":
                        x = x * x
                    f = _one_minus_inv_exp(x, dt)
                    t = (dt(1.0) - a) + a * np.exp(-x) if exact else dt(1.0) - a * f
                f = a * f
                trans = grey(t, dt)
                insc = color * f[..., None]
            trans = np.where(sky[..., None], dt(1.0), trans)
            insc = np.where(sky[..., None], dt(0.0), insc)
        return FogResult(inscatter=insc.astype(dt), transmittance=trans.astype(dt))
