"""Godot 4 environment fog (``Environment.fog_*``, the non-volumetric "fixed" fog).

Follows Godot 4 as read in ``godotengine/godot`` at the commits below (the repository's
``version.py`` in the same index, commit 001aa128, reads 4.6.2) and reproduces the **linear**
HDR colour the scene shader writes before tonemapping:

* ``servers/rendering/renderer_rd/shaders/forward_clustered/scene_forward_clustered.glsl``
  (commit 000ae031b1c3ab6437707522aa9e1070ee129cec; ``forward_mobile/scene_forward_mobile.glsl``
  at dbd17baab5bd2fc371cefaaf255a27941d756eab has the same ``fog_process``):
  ``fog = fog_process(vertex)`` (``vertex``: the view-space position), packed with
  ``packHalf2x16(fog.rg)``, ``packHalf2x16(fog.ba)`` and unpacked before
  ``frag_color.rgb = mix(frag_color.rgb, fog.rgb, fog.a)``::

      fog_color = fog_light_color;
      if (aerial perspective) fog_color = mix(fog_color, sky_fog_color, fog_aerial_perspective);
      if (sun scatter) for each directional light:
          fog_color += light.color * light.energy
                       * pow(max(dot(normalize(vertex), light.direction), 0.0), 8.0) * fog_sun_scatter;
      if (depth fog) fog_amount = pow(smoothstep(fog_depth_begin, fog_depth_end, length(vertex)),
                                      fog_depth_curve) * fog_density;
      else           fog_amount = 1 - exp(min(0.0, -length(vertex) * fog_density));
      if (abs(fog_height_density) >= 0.0001)
          fog_amount = max(1.0 - exp(min(0.0, (y - fog_height) * fog_height_density)), fog_amount);

  (``y``: the world height of the shaded point);
* ``servers/rendering/renderer_rd/storage_rd/render_scene_data_rd.cpp`` (CPU):
  ``fog_light_color = srgb_to_linear(color) * fog_light_energy``; ``fog_depth_end = end > 0 ?
  end : z_far``; ``fog_depth_begin = min(begin, fog_depth_end - 0.001)``;
* ``servers/rendering/renderer_rd/shaders/environment/sky.glsl`` (commit
  0095d7d0c0c910f6d5800215e720bc54bb74f002): sky pixels are fogged by the sky shader instead,
  in float32 without half packing: ``fog_process(view, sky_color)`` returns
  ``(mix(fog_light_color, sky_color, fog_aerial_perspective) + sun scatter, 1.0)``, its sun
  scatter ``pow(max(dot(view, l), 0.0), 8.0) * M_PI`` (pi times the scene shader's), and
  ``frag_color.rgb = mix(frag_color.rgb, fog.rgb, fog.a * fog_sky_affect)``.

Units: Godot is y-up, **metres**, the same frame as fogref.  ``fog_density`` [1/m]
(exponential mode; in depth mode it is the maximum opacity, in [0, 1]),
``fog_height`` [m], ``fog_height_density`` [1/m] (> 0: fog below ``fog_height``; < 0:
above).  Colours: ``fog_light_color`` is *linear* RGB here (Godot converts the
editor's sRGB colour on the CPU: pass ``srgb_to_linear(c)``; the default is Godot's
default colour converted); ``sun_color`` = the light's linear colour times its energy as the
shader gets it (``light_energy * pi`` without physical light units, ``light_storage.cpp``);
``sun_direction`` points **toward** the sun; ``sky_color`` is the sky radiance the
aerial perspective samples (fogref's skies are constant, so the blurred radiance map is
that constant).

Result: scene pixels ``transmittance = 1 - fog_amount`` (grey), ``inscatter = fog_color *
fog_amount``; at ``precision="float32"`` both ``fog_color`` and ``fog_amount`` pass through
half floats first (:func:`half_round`: up to 2.4e-4 on the transmittance, 2^-11 relative on
the inscatter); ``"float64"`` leaves that rounding out.  Sky pixels (the truth's ``hit`` mask
is False, or without it a float64 distance of at least ``sky_distance``, see
:func:`~fogref.models._num.sky_pixels`): ``s = fog_sky_affect``, ``transmittance = 1 - s (1 -
fog_aerial_perspective)`` and ``inscatter = s ((1 - fog_aerial_perspective) fog_light_color +
pi * sun scatter)``: the sky's own colour stands in for ``sky_color``.

Physical counterpart: the exponential mode without height fog is exactly a homogeneous
medium, ``sigma_t = fog_density`` [1/m].  Godot's height fog is **not** an optical
depth: it depends only on the end point's height and is combined with ``max``, so an
exponential height profile has no exact counterpart (see
:func:`fogref.mapping.engines.godot_from_physical`).  The depth mode has none either.
Robustness (deviations): the lobe normalises ``vertex`` with ``length`` floored at 1e-30
(the shader's ``normalize(0)`` is NaN at the camera); a fog colour beyond the largest half
float (65504) is clamped to it (``packHalf2x16`` of it is implementation-defined).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fogref import params as P
from fogref.errors import ParameterError
from fogref.media import rgb
from fogref.models._num import dtype_of, glsl_smoothstep, grey, sky_pixels, split, unit_direction, view_ray
from fogref.models.base import SKY_DISTANCE, FogResult, ParamModel, register

MODES = ("exponential", "depth")
#: Godot's default ``fog_light_color`` Color(0.518, 0.553, 0.608) (sRGB) as linear RGB.
DEFAULT_FOG_LIGHT_COLOR = (0.231082, 0.266417, 0.327964)
#: The lobe exponent Godot hard-codes in ``fog_process`` (``pow(..., 8.0)``).
SUN_SCATTER_EXPONENT = 8.0
#: ``fog_sun_scatter`` at or below this adds nothing (Godot's test ``fog_sun_scatter > 0.001``).
SUN_SCATTER_MIN = 0.001
#: ``|fog_height_density|`` below this adds no height fog (Godot's test ``abs(...) >= 0.0001``).
HEIGHT_DENSITY_MIN = 0.0001
#: The largest finite half float: ``packHalf2x16`` of a larger fog colour is clamped here.
HALF_MAX = 65504.0


def half_round(x: Any) -> Any:
    """``unpackHalf2x16(packHalf2x16(x))`` in float32: round to the nearest half float
    (IEEE binary16, round to nearest even), magnitudes clamped to :data:`HALF_MAX`.

    Examples
    --------
    >>> float(half_round(np.float32(0.1)))
    0.0999755859375
    >>> float(half_round(np.float32(1e6)))
    65504.0
    """
    x = np.clip(np.asarray(x, dtype=np.float32), -HALF_MAX, HALF_MAX)
    return x.astype(np.float16).astype(np.float32)


def srgb_to_linear(c: Any) -> tuple:
    """Godot's ``Color.srgb_to_linear`` of an RGB triple (each component in [0, 1]).

    Examples
    --------
    >>> [round(x, 6) for x in srgb_to_linear((0.518, 0.553, 0.608))]
    [0.231082, 0.266417, 0.327964]
    """
    return tuple(float(x / 12.92 if x < 0.04045 else ((x + 0.055) / 1.055) ** 2.4) for x in c)


@dataclass(frozen=True)
class GodotFogParams:
    """``Environment`` fog properties (Godot 4), the sun, the sky colour and the far plane.

    Defaults are Godot's (``fog_mode`` exponential, density 0.01, sky affect 1, depth curve 1,
    begin 10 m, end 100 m; ``z_far`` = Camera3D's default 4000 m).

    Examples
    --------
    >>> GodotFogParams().fog_density
    0.01
    >>> GodotFogParams(fog_mode="depth", fog_density=2.0)
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: <GodotFogParams>: parameter 'fog_density': depth mode: 2.0 outside [0, 1]
    """

    fog_mode: str = "exponential"
    fog_light_color: tuple = DEFAULT_FOG_LIGHT_COLOR
    fog_light_energy: float = 1.0
    fog_sun_scatter: float = 0.0
    fog_density: float = 0.01
    fog_aerial_perspective: float = 0.0
    fog_sky_affect: float = 1.0
    fog_height: float = 0.0
    fog_height_density: float = 0.0
    fog_depth_curve: float = 1.0
    fog_depth_begin: float = 10.0
    fog_depth_end: float = 100.0
    z_far: float = 4000.0
    sun_direction: tuple = (0.0, 1.0, 0.0)
    sun_color: tuple = (0.0, 0.0, 0.0)
    sky_color: tuple = (0.0, 0.0, 0.0)
    sky_distance: float = SKY_DISTANCE

    def __post_init__(self) -> None:
        src = "<GodotFogParams>"
        if self.fog_mode not in MODES:
            raise ParameterError(src, "fog_mode", f"expected one of {MODES}, got {self.fog_mode!r}")
        ranges = {  # (lo, hi, lo open): every number finite (fogref.params.number)
            "fog_light_energy": (0.0, math.inf, False),
            "fog_sun_scatter": (0.0, math.inf, False),
            "fog_density": (0.0, math.inf, False),
            "fog_depth_curve": (0.0, math.inf, False),
            "z_far": (0.0, math.inf, True),  # the far plane divides the depth: > 0
            "sky_distance": (0.0, math.inf, False),
            "fog_aerial_perspective": (0.0, 1.0, False),
            "fog_sky_affect": (0.0, 1.0, False),
            "fog_height": (-math.inf, math.inf, False),
            "fog_height_density": (-math.inf, math.inf, False),
            "fog_depth_begin": (-math.inf, math.inf, False),
            "fog_depth_end": (-math.inf, math.inf, False),
        }
        for name, (lo, hi, lo_open) in ranges.items():
            v = P.number(getattr(self, name), name, source=src, lo=lo, hi=hi, lo_open=lo_open)
            object.__setattr__(self, name, v)
        if self.fog_mode == "depth" and self.fog_density > 1.0:
            raise ParameterError(src, "fog_density", f"depth mode: {self.fog_density} outside [0, 1]")
        for name in ("fog_light_color", "sun_color", "sky_color"):
            object.__setattr__(self, name, rgb(getattr(self, name), name, src, lo=0.0))
        object.__setattr__(self, "sun_direction", unit_direction(self.sun_direction, "sun_direction", src))

    def depth_range(self, dt: Any = np.float32) -> tuple:
        """(begin, end) [m] as the CPU passes them (end <= 0 means z_far; begin < end)."""
        end = dt(self.fog_depth_end) if self.fog_depth_end > 0 else dt(self.z_far)
        begin = min(dt(self.fog_depth_begin), dt(end - dt(0.001)))
        return dt(begin), dt(end)


@register("godot")
class GodotFog(ParamModel[GodotFogParams]):
    """Godot 4 environment fog (see module doc).

    Examples
    --------
    >>> fog = GodotFog(GodotFogParams(fog_density=0.01))
    >>> r = fog.evaluate([0.0, 0.0, 0.0], [[100.0, 0.0, 0.0]], "float64")
    >>> round(float(r.transmittance[0, 0]), 6)     # exp(-0.01 * 100)
    0.367879
    """

    Params = GodotFogParams

    def evaluate(self, camera: Any, world_pos: Any, precision: str = "float32", hit: Any = None) -> FogResult:
        """Fog of each pixel: camera (3,), world_pos (..., 3) in metres; ``hit`` (..., ) bool,
        False on the pixels that see the sky (see :func:`~fogref.models._num.sky_pixels`)."""
        dt = dtype_of(precision)
        p = self.params
        cam, wp = split(camera, world_pos)
        v, d = view_ray(cam, wp, dt)
        sky = sky_pixels(cam, wp, hit, p.sky_distance)
        with np.errstate(all="ignore"):
            light = np.asarray(p.fog_light_color, dtype=dt) * dt(p.fog_light_energy)
            ap = dt(p.fog_aerial_perspective)
            fog_color = np.broadcast_to(
                light + (np.asarray(p.sky_color, dtype=dt) - light) * ap, d.shape + (3,)
            ).astype(dt)
            scatter = np.zeros(d.shape + (3,), dtype=dt)
            if p.fog_sun_scatter > SUN_SCATTER_MIN:
                l = np.asarray(p.sun_direction, dtype=dt)
                vn = v / np.maximum(d, dt(1e-30))[..., None]
                cos = vn[..., 0] * l[0] + vn[..., 1] * l[1] + vn[..., 2] * l[2]
                amount = np.power(np.maximum(cos, dt(0.0)), dt(SUN_SCATTER_EXPONENT))
                scatter = np.asarray(p.sun_color, dtype=dt) * amount[..., None] * dt(p.fog_sun_scatter)
            fog_color = fog_color + scatter
            if p.fog_mode == "depth":
                begin, end = p.depth_range(dt)
                fog_z = glsl_smoothstep(begin, end, d, dt)
                amount = np.power(fog_z, dt(p.fog_depth_curve)) * dt(p.fog_density)
            else:
                amount = dt(1.0) - np.exp(np.minimum(dt(0.0), -d * dt(p.fog_density)))
            if abs(np.float32(p.fog_height_density)) >= np.float32(HEIGHT_DENSITY_MIN):
                y = dt(cam[1]) + v[..., 1]
                y_dist = y - dt(p.fog_height)
                vfog = dt(1.0) - np.exp(np.minimum(dt(0.0), y_dist * dt(p.fog_height_density)))
                amount = np.maximum(vfog, amount)
            amount = np.where(np.isfinite(amount), amount, dt(1.0)).astype(dt)
            if dt is np.float32:  # packHalf2x16 / unpackHalf2x16 between fog_process and the blend
                fog_color, amount = half_round(fog_color), half_round(amount)
            trans = dt(1.0) - amount
            insc = fog_color * amount[..., None]
            if np.any(sky):
                s = dt(p.fog_sky_affect)
                t_sky = dt(1.0) - s * (dt(1.0) - ap)
                i_sky = s * (light * (dt(1.0) - ap) + scatter * dt(math.pi))
                trans = np.where(sky, t_sky, trans)
                insc = np.where(sky[..., None], i_sky, insc)
        return FogResult(inscatter=insc.astype(dt), transmittance=grey(trans, dt))
