"""The fog Unreal Engine 5's path tracer renders for Exponential Height Fog, as a medium profile.

Unreal's path tracer does not trace the raster Exponential Height Fog; it builds a
small physical medium of its own from the fog component.  This module is that
medium in fogref's units (y-up, metres): the ``heightfog`` profile
``"ue_pathtracer"``, exact closed forms for its optical depth and free flight.
The editor settings -> these values are :mod:`fogref.mapping.unreal_pathtracer`.

Sources
-------
[PT] ``Engine/Source/Runtime/Renderer/Private/PathTracing.cpp`` (UE 5.x),
``CVarPathTracingFogDensityClamp``, ``FPathTracingFogParameters`` and
``PrepareFogParameters``, read in the public mirror ``unicorn2022/UE5.8.0`` (commit
5d9a05c); the pre-5.6 constant in the ``#if ENGINE_MINOR_VERSION >= 6`` switch of
``jambuttenshaw/HVPT`` ``Source/HVPT/Private/Rendering/Helpers.cpp`` (a plug-in's
copy of ``PrepareFogParameters``).
[SC] ``Engine/Source/Runtime/Renderer/Private/SceneCore.cpp``
(``FExponentialHeightFogSceneInfo``'s constructor, ``unicorn2022/UE5.8.0``): the
editor density and falloff / 1000, ``FogData[1].Height = Height +
SecondFogData.FogHeightOffset``, ``VolumetricFogScatteringDistribution`` clamped to
[-0.99, 0.99], ``VolumetricFogAlbedo = FLinearColor(FColor)``,
``VolumetricFogExtinctionScale = max(., 0)``, ``VolumetricFogDistance =
max(VolumetricFogStartDistance + VolumetricFogDistance, 0)``.
[FOG] ``Engine/Shaders/Private/PathTracing/Volume/PathTracingFog.ush``: only its
first lines could be read (the parameter block and the start of ``FogIntersect``,
a capped vertical cylinder from (FogCenter, FogMinZ) to (FogCenter, FogMaxZ) of
radius FogRadius, "adapted from iquilezles.org intersectors"); its density and
transmittance functions were not in the searchable index.
[VOL] ``Engine/Shaders/Private/PathTracing/Volume/PathTracingVolume.ush``: the fog's
transmittance is ``FogGetTransmittance`` (analytic) or a ratio-tracking loop over
``FogGetDensity`` inside ``FogIntersect``'s interval.

Verified in [PT] and [SC] (Unreal units: cm, z-up; ``FogData[i]`` are [SC]'s values,
the editor density and falloff / 1000)::

    FogDensity_i  = 0.5 * FogData[i].Density * VolumetricFogExtinctionScale   (1/cm)
                    ("MatchHeightFogFactor = .5", "See VolumetricFog.usf")
    FogHeight_i   = FogData[i].Height                                         (cm)
    FogFalloff_i  = max(FogData[i].HeightFalloff, 0.001 / 1000)               (1/cm)
    FogAlbedo     = VolumetricFogAlbedo;   FogPhaseG = VolumetricFogScatteringDistribution
    FogCenter     = the view origin's X, Y;   FogRadius = VolumetricFogDistance (cm)
    FogMinZ       = min_i(FogHeight_i - Radius)
    FogMaxZ       = max_i(FogHeight_i + min(Radius, log2(max(FogDensity_i, 1e-6) / 1e-6) / FogFalloff_i))
    FogFalloffClamp = -log2(clamp(r.PathTracing.FogDensityClamp, 1, 256))   (UE >= 5.6)
                    = -log2(8)                                               (before 5.6)

and the console variable ``r.PathTracing.FogDensityClamp`` (default 8): "Limit the
density growth in exponential heightfog ... clamp it to some multiplier of the
overall density".  Two layers (``static_assert(NumFogs == 2)``).  The inscattering
colour, the directional inscattering, start distance, max opacity and cutoff are
not among the parameters.  [PT] notes the camera-centred cylinder "can lead to
'sliding' when the view distance is low".

**Not verified** (the body of [FOG] was not readable), inferred from [PT]:

* the density of layer i is ``FogDensity_i * 2^-max(FogFalloff_i (z - FogHeight_i),
  FogFalloffClamp)``, i.e. base 2 as in the raster fog and ``FogMaxZ`` above
  (``FogMaxZ`` is where ``FogDensity_i 2^(-FogFalloff_i dz)`` falls to 1e-6), and
  the clamp an exponent clamp applied to each layer separately (it is a single
  exponent, ``-log2`` of a multiple): ``rho_i <= DensityClamp * FogDensity_i``;
* the layers add, the medium is grey (``SigmaT = density``, ``SigmaS = albedo *
  density``) with one HG phase of ``FogPhaseG``;
* the cylinder is closed (its caps at FogMinZ, FogMaxZ) and the fog is 0 outside it.

In fogref's units a layer is ``rho(y) = density * min(exp(-b (y - h)), C)``, i.e.
constant ``C * density`` below the clamp height ``y_c = h - ln(C) / b`` and
``C * density * exp(-b (y - y_c))`` above: the piecewise profile of
:class:`fogref.media.HDRPLayer`, whose exact closed forms it uses.  The cylinder
is a :class:`Cylinder` bounds object: its ray interval is a closed-form
quadratic-and-slab intersection, and :class:`~fogref.media.FogMedium` clips every
ray to it before the height profile is integrated.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from fogref.errors import ParameterError
from fogref.media.medium import check_layer_param
from fogref.media.ops import Ops, Real
from fogref.media.profiles import HDRPLayer
from fogref.media.protocol import NonIncreasingLayer, number, register_profile, rgb

__all__ = [
    "DENSITY_CLAMP_DEFAULT",
    "DENSITY_CLAMP_RANGE",
    "DENSITY_EPSILON_PER_CM",
    "RADIUS_RANGE",
    "Cylinder",
    "UEPathTracerLayer",
    "bounds_from_params",
    "ue_fog_y_range",
]

#: ``r.PathTracing.FogDensityClamp``'s default, and the constant before UE 5.6 ([PT]).
DENSITY_CLAMP_DEFAULT = 8.0
#: [PT] clamps the console variable to this range.
DENSITY_CLAMP_RANGE = (1.0, 256.0)
#: The fog cylinder's radius [m] (``VolumetricFogDistance`` / 100): what a scene may hold.
RADIUS_RANGE = (1e-3, 1e7)
#: [PT]'s ``DensityEpsilon`` [1/cm]: the density at which the cylinder's top is put.
DENSITY_EPSILON_PER_CM = 1.0e-6
_CM_PER_M = 100.0


@dataclass(frozen=True)
class UEPathTracerLayer(NonIncreasingLayer):
    """One layer of Unreal's path-traced fog: ``density * min(exp(-falloff (y - height)), clamp)``.

    density: relative scale at ``height`` (multiplies ``sigma_t``), 0 to 1e6.
    falloff: b [1/m], 1e-6 to 1e3 (Unreal floors it at 6.9e-5: never homogeneous);
             Unreal's ``2^(-F z)`` per cm is ``b = 100 ln(2) F``.
    height:  h [m], -1e7 to 1e7: where the relative density is ``density``.
    clamp:   C, 1 to 256 (``r.PathTracing.FogDensityClamp``): the density never
             exceeds ``C * density``; below ``clamp_height`` it is that constant.

    Examples
    --------
    >>> from fogref.media import NP
    >>> L = UEPathTracerLayer(density=1.0, falloff=math.log(2), height=0.0, clamp=8.0)
    >>> round(L.clamp_height, 12), float(L.rho(NP, -10.0)), float(L.rho(NP, 1.0))
    (-3.0, 8.0, 0.5)
    >>> float(L.depth(NP, -13.0, 0.0, 2.0))   # horizontal, below the clamp height
    16.0
    """

    profile = "ue_pathtracer"

    density: float = 1.0
    falloff: float = 0.01
    height: float = 0.0
    clamp: float = DENSITY_CLAMP_DEFAULT

    @classmethod
    def from_params(cls, params: dict, src: str = "<params>") -> tuple:
        """Profile "ue_pathtracer": ``density, falloff, height``, an optional second
        layer ``density2, falloff2, height2`` (``density2 = 0``: none) and ``clamp``
        (1 to 256, default 8), shared by both layers.

        Examples
        --------
        >>> UEPathTracerLayer.from_params({"falloff": 0.02, "clamp": 4})
        (UEPathTracerLayer(density=1.0, falloff=0.02, height=0.0, clamp=4.0),)
        """
        clamp = number(params, "clamp", DENSITY_CLAMP_DEFAULT, src, *DENSITY_CLAMP_RANGE)
        layers = [
            cls(
                number(params, "density", 1.0, src, 0.0, 1e6),
                number(params, "falloff", 0.01, src, 1e-6, 1e3),
                number(params, "height", 0.0, src, -1e7, 1e7),
                clamp,
            )
        ]
        d2 = number(params, "density2", 0.0, src, 0.0, 1e6)
        if d2 > 0:
            layers.append(
                cls(
                    d2,
                    number(params, "falloff2", 0.01, src, 1e-6, 1e3),
                    number(params, "height2", 0.0, src, -1e7, 1e7),
                    clamp,
                )
            )
        return tuple(layers)

    @property
    def clamp_height(self) -> float:
        """``h - ln(C) / b`` [m]: below it the density is the constant ``C * density``
        (``-inf`` for a homogeneous layer; ``h`` itself when ``C = 1``)."""
        if self.falloff <= 0:
            return -math.inf
        return float(self.height) - math.log(float(self.clamp)) / float(self.falloff)

    @property
    def piecewise(self) -> HDRPLayer:
        """The same profile as an :class:`~fogref.media.HDRPLayer` (constant, then exponential)."""
        if self.falloff <= 0:
            return HDRPLayer(float(self.density), 0.0, 0.0)
        return HDRPLayer(float(self.density) * float(self.clamp), self.clamp_height, float(self.falloff))

    @property
    def is_constant(self) -> bool:
        """Never (``falloff > 0``)."""
        return False

    @property
    def reference_height(self) -> float:
        """``height`` [m]: where the relative density is ``density``."""
        return float(self.height)

    def validate(self, src: str, i: int) -> None:
        check_layer_param(src, i, "density", self.density, 0.0, 1e6)
        check_layer_param(src, i, "falloff", self.falloff, 1e-6, 1e3)
        check_layer_param(src, i, "height", self.height, -1e7, 1e7)
        check_layer_param(src, i, "clamp", self.clamp, *DENSITY_CLAMP_RANGE)

    def rho(self, ops: Ops, y: Real) -> Real:
        """Relative density at height y (dimensionless)."""
        return self.piecewise.rho(ops, y)

    def depth(self, ops: Ops, oy: Real, dy: Real, t: Real) -> Real:
        """Shape optical depth [m] over ``[0, t]`` (``t = ops.largest``: infinity), exact."""
        return self.piecewise.depth(ops, oy, dy, t)

    def sample(self, ops: Ops, oy: Real, dy: Real, s: Real) -> Real:
        """Distance [m] where the shape optical depth reaches ``s`` (exact); ops.largest if never."""
        return self.piecewise.sample(ops, oy, dy, s)


@dataclass(frozen=True)
class Cylinder:
    """A closed vertical cylinder [m]: axis through ``(center_x, center_z)``, ``radius``,
    heights ``[y_min, y_max]``; the bounds of Unreal's path-traced fog ([PT]:
    ``FogCenter`` = the camera, ``FogRadius``, ``FogMinZ``, ``FogMaxZ``).

    Same interface as :class:`fogref.media.Box`: ``lo``/``hi`` (bounding box),
    ``validate``, ``inside``, ``clip``.

    Examples
    --------
    >>> from fogref.media import NP
    >>> c = Cylinder(0.0, 0.0, 10.0, -5.0, 5.0)
    >>> t0, t1 = c.clip(NP, (-20.0, 0.0, 0.0), (1.0, 0.0, 0.0))
    >>> float(t0), float(t1)
    (10.0, 30.0)
    >>> t0, t1 = c.clip(NP, (0.0, 0.0, 0.0), (0.0, 1.0, 0.0))   # straight up: the cap
    >>> float(t0), float(t1)
    (0.0, 5.0)
    """

    center_x: float
    center_z: float
    radius: float
    y_min: float
    y_max: float

    @property
    def lo(self) -> tuple:
        return (self.center_x - self.radius, self.y_min, self.center_z - self.radius)

    @property
    def hi(self) -> tuple:
        return (self.center_x + self.radius, self.y_max, self.center_z + self.radius)

    def validate(self, src: str) -> Cylinder:
        """This cylinder with float fields; ParameterError naming the bad field."""
        vals = {}
        for name, lo, hi in (
            ("center_x", -1e7, 1e7),
            ("center_z", -1e7, 1e7),
            ("radius", *RADIUS_RANGE),
            ("y_min", -2e7, 2e7),
            ("y_max", -2e7, 2e7),
        ):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and lo <= v <= hi):
                raise ParameterError(src, f"cylinder.{name}", f"value {v} outside [{lo:g}, {hi:g}]")
            vals[name] = v
        if not vals["y_min"] < vals["y_max"]:
            raise ParameterError(
                src, "cylinder.y_max", f"value {vals['y_max']} must exceed y_min {vals['y_min']}"
            )
        return Cylinder(**vals)

    def inside(self, ops: Ops, p: Any) -> Any:
        """Whether the points ``p`` lie in the closed cylinder."""
        px = p[0] - ops.param(self.center_x, 0)
        pz = p[2] - ops.param(self.center_z, 2)
        r = ops.param(self.radius)
        in_y = (p[1] >= ops.param(self.y_min, 1)) & (p[1] <= ops.param(self.y_max, 1))
        return ((px * px + pz * pz) <= r * r) & in_y

    def clip(self, ops: Ops, o: Any, d: Any) -> Any:
        """Ray interval ``[t0, t1]`` (t0 >= 0) inside the cylinder; ``t1 < t0`` if none.

        The wall: the roots of ``a t^2 + 2 b t + c = 0`` (``a = dx^2 + dz^2``,
        ``b = px dx + pz dz``, ``c = px^2 + pz^2 - r^2``, ``p = o - centre``) in the
        cancellation-free form ``q = -(b + sign(b) sqrt(b^2 - a c))``, roots ``q/a``
        and ``c/q``; a vertical ray (``a = 0``) is inside the wall iff ``c <= 0``.
        The caps: the slab ``y_min <= y <= y_max``.
        """
        L = ops.largest
        px = o[0] - ops.param(self.center_x, 0)
        pz = o[2] - ops.param(self.center_z, 2)
        r = ops.param(self.radius)
        a = d[0] * d[0] + d[2] * d[2]
        b = px * d[0] + pz * d[2]
        c = px * px + pz * pz - r * r
        disc = b * b - a * c
        sq = ops.sqrt(ops.maximum(disc, 0.0))
        q = -(b + ops.where(b >= 0, sq, -sq))
        vertical = a < 1e-30
        r1 = ops.safe_div(q, ops.where(vertical, 1.0, a))
        r2 = ops.safe_div(c, ops.where(q == 0, 1.0, q))
        r2 = ops.where(q == 0, r1, r2)
        w_near = ops.minimum(r1, r2)
        w_far = ops.maximum(r1, r2)
        miss = disc < 0
        w_near = ops.where(vertical, ops.where(c <= 0, -L, L), ops.where(miss, L, w_near))
        w_far = ops.where(vertical, ops.where(c <= 0, L, -L), ops.where(miss, -L, w_far))
        # the caps (slab in y)
        lo, hi = ops.param(self.y_min, 1), ops.param(self.y_max, 1)
        dy = d[1]
        par = ops.abs(dy) < 1e-30
        inv = 1.0 / ops.where(par, 1.0, dy)
        ta = (lo - o[1]) * inv
        tb = (hi - o[1]) * inv
        outside = (o[1] < lo) | (o[1] > hi)
        y_near = ops.where(par, ops.where(outside, L, -L), ops.minimum(ta, tb))
        y_far = ops.where(par, ops.where(outside, -L, L), ops.maximum(ta, tb))
        t0 = ops.maximum(ops.maximum(w_near, y_near), 0.0)
        t1 = ops.minimum(w_far, y_far)
        return t0, t1


def ue_fog_y_range(sigma_t: float, layers: list, radius: float) -> tuple[float, float]:
    """[PT]'s ``FogMinZ``, ``FogMaxZ`` in metres for grey extinction ``sigma_t`` [1/m].

    ``layers``: ``(density, falloff [1/m], height [m])`` of both of Unreal's layers
    (a layer of density 0 still counts, as in [PT]).  In metres [PT]'s rule is
    ``y_max = max_i(h_i + min(R, ln(max(sigma_i, 1e-6) / 1e-6) / b_i))`` with
    ``sigma_i = sigma_t density_i / 100`` per cm, and ``y_min = min_i(h_i) - R``.

    Examples
    --------
    >>> lo, hi = ue_fog_y_range(0.001, [(1.0, 0.1, 0.0)], 60.0)
    >>> lo, round(hi, 6)   # ln(1e-5 / 1e-6) / 0.1 = 23.03 m above the fog height
    (-60.0, 23.025851)
    """
    y_lo, y_hi = math.inf, -math.inf
    for d, b, h in layers:
        sig_cm = sigma_t * d / _CM_PER_M
        top = math.log(max(sig_cm, DENSITY_EPSILON_PER_CM) / DENSITY_EPSILON_PER_CM)
        up = radius if b <= 0 else min(radius, top / b)
        y_lo, y_hi = min(y_lo, h - radius), max(y_hi, h + up)
    return y_lo, y_hi


def bounds_from_params(params: dict, src: str = "<params>") -> Cylinder:
    """The profile's cylinder from ``center`` (point [m], the camera: only x and z are
    used; required), ``radius`` [m] (default 60: VolumetricFogDistance 6000 cm) and
    optional ``y_min``/``y_max`` [m] (default: [PT]'s rule, :func:`ue_fog_y_range`,
    over the layer ``density, falloff, height`` and, when ``height2`` is given, the
    second layer even of density 0).

    Examples
    --------
    >>> bounds_from_params({"center": [1, 2, 3], "radius": 10, "y_min": -1, "y_max": 4})
    Cylinder(center_x=1.0, center_z=3.0, radius=10.0, y_min=-1.0, y_max=4.0)
    >>> bounds_from_params({}, "<doc>")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: <doc>: parameter 'center': profile 'ue_pathtracer' needs the camera position
    """
    if params.get("center") is None:
        raise ParameterError(src, "center", "profile 'ue_pathtracer' needs the camera position")
    c = rgb(params["center"], "center", src, -1e7, 1e7)
    radius = number(params, "radius", 60.0, src, 1e-3, 1e7)
    sig = params.get("sigma_t")
    sigma = max(rgb(sig, "sigma_t", src, 0.0, 1e2)) if sig is not None else 0.01
    specs = [
        (
            number(params, "density", 1.0, src, 0.0, 1e6),
            number(params, "falloff", 0.01, src, 0.0, 1e3),
            number(params, "height", 0.0, src, -1e7, 1e7),
        )
    ]
    if params.get("height2") is not None or number(params, "density2", 0.0, src, 0.0, 1e6) > 0:
        specs.append(
            (
                number(params, "density2", 0.0, src, 0.0, 1e6),
                number(params, "falloff2", 0.01, src, 0.0, 1e3),
                number(params, "height2", 0.0, src, -1e7, 1e7),
            )
        )
    y_lo, y_hi = ue_fog_y_range(sigma, specs, radius)
    y_lo = number(params, "y_min", y_lo, src, -2e7, 2e7)
    y_hi = number(params, "y_max", y_hi, src, -2e7, 2e7)
    return Cylinder(c[0], c[2], radius, y_lo, y_hi).validate(src)


register_profile("ue_pathtracer", UEPathTracerLayer.from_params, parse_bounds=bounds_from_params)
