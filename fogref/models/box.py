"""Box volume fog (a Unity image effect from Jim's GameDev Blog, "体积雾", 2016).

Source: Jim's GameDev Blog, "体积雾" ("Volumetric fog", 2016-04-12), a Unity
image-effect shader; a blog post has no version or commit, and the original page is not in the
searchable index; a page with the same description (``k`` the linear fog density at a point,
the ray ``ez`` and its intersections a and b with the volume) is
http://jiangsulong.com/news/1124Y22E2020.html.
Reproduces the colour the image effect writes: linear in a Linear colour-space project.
Its formula is printed as an image; the text fixes it:
the eye ray e→c (c: the G-buffer point) meets the box at
a (entry) and b (exit); ``t = |ac|`` is the fog in front of c and ``d = |cb|``
the fog behind it; the fog amount is 0 at ``t = 0``, grows *linearly* in t, and
is total when ``d = 0``; ``k`` is the fog density.  We read it as

    fog = saturate(k * t / (t + d))          (mode "ratio", the blog's reading)

(``k = 1``: fully opaque at the far wall).  Because ``t + d`` is the chord of the
ray in the box, this is *not* a medium: the same t gives less fog in a longer
box.  Mode "thickness" is the other common reading, ``fog = saturate(k t)`` with
``k`` [1/m]: linear in the optical depth of the homogeneous box medium
``sigma_t = k``.  Points outside the box: ``c`` is clamped to the chord
(``t = 0`` before a, ``d = 0`` behind b); a ray that misses the box gets no fog.
The ray–box intersection is the slab test (RaySlabIntersection) of the blog post.

Units: Unity, y-up metres (same as fogref).  Compositing:
``final = lerp(scene, _FogColor, fog)``: ``transmittance = 1 - fog`` (grey),
``inscatter = _FogColor * fog``.  Mode "beer" (not in the blog post) replaces the
blend by ``1 - exp(-k t)``: exactly the homogeneous box medium.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from fogref import params as valid
from fogref.errors import ParameterError
from fogref.models._num import dtype_of, grey, saturate, split, view_ray
from fogref.models.base import FogResult, ParamModel, register

BOX_MODES = ("ratio", "thickness", "beer")


@dataclass(frozen=True)
class BoxFogParams:
    """Box fog material: box corners [m], density k, colour, mode (see module doc).

    k is dimensionless in mode "ratio", [1/m] in "thickness" and "beer".
    """

    box_min: tuple = (-50.0, 0.0, -50.0)
    box_max: tuple = (50.0, 20.0, 50.0)
    density: float = 1.0
    fog_color: tuple = (0.7, 0.7, 0.75)
    mode: str = "ratio"

    def __post_init__(self) -> None:
        src = "<BoxFogParams>"
        lo = valid.vector(self.box_min, "box_min", source=src, unit="m")
        hi = valid.vector(self.box_max, "box_max", source=src, unit="m")
        if any(a >= b for a, b in zip(lo, hi)):
            raise ParameterError(src, "box_min", f"need box_min < box_max per axis, got {lo}, {hi}")
        valid.choice(self.mode, "mode", BOX_MODES, src)
        object.__setattr__(self, "density", valid.number(self.density, "density", source=src, lo=0.0))
        object.__setattr__(self, "box_min", lo)
        object.__setattr__(self, "box_max", hi)
        object.__setattr__(self, "fog_color", valid.rgb(self.fog_color, "fog_color", source=src, lo=0.0))


def slab_chord(cam: Any, v: Any, lo: Any, hi: Any, dt: Any) -> Any:
    """Ray ``cam + s v`` (s = 1 at the pixel) against the box: ``(s_near, s_far)``.

    ``s_near`` is clamped to >= 0 (camera inside: the chord starts at the camera).
    A zero direction component is replaced by a tiny one of either sign, so the
    slab test stays NaN-free; no intersection gives ``s_far < s_near``.
    """
    tiny = dt(1e-30)
    s0: Any = None
    s1: Any = None
    for a in range(3):
        va = v[..., a]
        va = np.where(va == 0, tiny, va)
        inv = dt(1.0) / va
        ta = (dt(lo[a]) - dt(cam[a])) * inv
        tb = (dt(hi[a]) - dt(cam[a])) * inv
        near = np.minimum(ta, tb)
        far = np.maximum(ta, tb)
        s0 = near if s0 is None else np.maximum(s0, near)
        s1 = far if s1 is None else np.minimum(s1, far)
    return np.maximum(s0, dt(0.0)), s1


@register("box")
class BoxFog(ParamModel[BoxFogParams]):
    """The blog's box volume fog (see module doc)."""

    Params = BoxFogParams

    def fog_lengths(self, camera: Any, world_pos: Any, precision: str = "float32") -> Any:
        """``(t, d)`` [m]: fog length in front of and behind each pixel along its ray."""
        dt = dtype_of(precision)
        q = self.params
        cam, wp = split(camera, world_pos)
        v, length = view_ray(cam, wp, dt)
        with np.errstate(all="ignore"):
            s0, s1 = slab_chord(cam, v, q.box_min, q.box_max, dt)
            hit = s1 > s0
            c = np.minimum(np.maximum(dt(1.0), s0), s1)
            t = np.where(hit, (c - s0) * length, dt(0.0))
            d = np.where(hit, (s1 - c) * length, dt(0.0))
            t = np.where(np.isfinite(t), t, dt(0.0))
            d = np.where(np.isfinite(d), d, dt(np.finfo(dt).max))
        return t.astype(dt), d.astype(dt)

    def evaluate(self, camera: Any, world_pos: Any, precision: str = "float32") -> FogResult:
        """Fog of each pixel: camera (3,), world_pos (..., 3) in metres."""
        dt = dtype_of(precision)
        q = self.params
        t, d = self.fog_lengths(camera, world_pos, precision)
        k = dt(q.density)
        with np.errstate(all="ignore"):
            if q.mode == "ratio":
                chord = t + d
                fog = saturate(np.where(chord > 0, k * t / np.where(chord > 0, chord, dt(1.0)), dt(0.0)))
            elif q.mode == "thickness":
                fog = saturate(k * t)
            else:
                fog = -np.expm1(-k * t)
        fog = fog.astype(dt)
        color = np.asarray(q.fog_color, dtype=dt)
        return FogResult(inscatter=color * fog[..., None], transmittance=grey(dt(1.0) - fog, dt))
