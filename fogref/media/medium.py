"""Physical fog media: exponential height layers, optionally clipped to a box, plus an
optional Local Fog Volume.

A :class:`FogMedium` has extinction ``sigma_t(p) = sigma_t_rgb * rho(p)`` [1/m] with
relative density ``rho(p) = sum_l density_l * exp(-falloff_l * (p_y - height_l))``
inside ``bounds`` (everywhere when ``bounds`` is None) and 0 outside, plus the relative
density of ``volume`` (a :class:`~fogref.media.local_fog_volume.LocalFogVolume`, not clipped
by ``bounds``) where there is one: optical depths add, and the free flight through the sum is
the nearer of the two parts' exact collisions.  World space is y-up, metres.  Special cases,
all exact:

* one or two exponential layers (Unreal's fog is two);
* ``falloff = 0``: a homogeneous medium;
* homogeneous + ``bounds``: a box of constant fog (Unity-style fog volumes).

Every layer follows :class:`fogref.media.protocol.HeightProfile`; the medium only
asks the protocol (density, depth, inversion, is-constant, is-empty).

The methods take an array back end ``ops`` (``fogref.media.NP`` for numpy float64,
``fogref.media.drjit_ops()`` inside Mitsuba), positions and directions as
3-sequences of arrays ``(x, y, z)``, and return shape optical depths (metres;
multiply by ``sigma_t`` per channel) or distances.  Directions are unit vectors.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Any

from fogref.errors import ParameterError
from fogref.media import closed_form as cf
from fogref.media.local_fog_volume import LocalFogVolume
from fogref.media.protocol import NonIncreasingLayer, number, register_profile, rgb
from fogref.params import number as valid_number


def quiet_numpy(fn: Any) -> Any:
    """Method decorator: silence numpy's overflow warnings (the closed forms
    saturate on purpose).  Shared by every height profile."""

    @functools.wraps(fn)
    def wrapper(self: Any, ops: Any, *args: Any, **kw: Any) -> Any:
        with ops.errstate():
            return fn(self, ops, *args, **kw)

    return wrapper


def check_layer_param(src: str, i: int, name: str, v: Any, lo: float, hi: float) -> None:
    """Raise ParameterError naming ``layer{i}.{name}`` unless ``lo <= v <= hi`` (finite;
    :func:`fogref.params.number`).

    Examples
    --------
    >>> check_layer_param("<doc>", 0, "density", 2.0, 0.0, 1e6)
    >>> check_layer_param("<doc>", 1, "falloff", -1.0, 0.0, 1e3)
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: <doc>: parameter 'layer1.falloff': -1 is outside [0, 1000]
    """
    valid_number(v, f"layer{i}.{name}", source=src, lo=lo, hi=hi)


@dataclass(frozen=True)
class ExpLayer(NonIncreasingLayer):
    """One exponential layer: ``density * exp(-falloff * (y - height))``.

    density: relative scale, dimensionless, >= 0 (multiplies ``sigma_t``).
    falloff: b [1/m], 0 (homogeneous) to 1e3.
    height:  h [m], the height where the layer's relative density is ``density``.

    A :class:`~fogref.media.protocol.HeightProfile`: ``ops`` is the array back
    end, ``oy`` the ray origin's height [m] and ``dy`` the ray direction's y
    component.  ``falloff = 0`` is a homogeneous layer.

    Examples
    --------
    >>> from fogref.media import NP
    >>> L = ExpLayer(density=2.0, falloff=0.1, height=10.0)
    >>> float(L.rho(NP, 10.0))
    2.0
    >>> float(L.depth(NP, 10.0, 1.0, NP.largest))   # density / falloff, straight up
    20.0
    >>> float(L.max_density(NP, 0.0, 10.0)) == float(L.rho(NP, 0.0))
    True
    """

    profile = "exponential"

    density: float = 1.0
    falloff: float = 0.0
    height: float = 0.0

    @classmethod
    def from_params(cls, params: dict, src: str = "<params>") -> tuple:
        """Profile "exponential": ``density, falloff, height`` and an optional second
        layer ``density2, falloff2, height2`` (``density2 = 0``: none).

        Examples
        --------
        >>> ExpLayer.from_params({"falloff": 0.02, "height": 5.0})
        (ExpLayer(density=1.0, falloff=0.02, height=5.0),)
        """
        layers = [
            cls(
                number(params, "density", 1.0, src, 0.0, 1e6),
                number(params, "falloff", 0.01, src, 0.0, 1e3),
                number(params, "height", 0.0, src, -1e7, 1e7),
            )
        ]
        d2 = number(params, "density2", 0.0, src, 0.0, 1e6)
        if d2 > 0:
            layers.append(
                cls(
                    d2,
                    number(params, "falloff2", 0.01, src, 0.0, 1e3),
                    number(params, "height2", 0.0, src, -1e7, 1e7),
                )
            )
        return tuple(layers)

    @classmethod
    def homogeneous_from_params(cls, params: dict, src: str = "<params>") -> tuple:
        """Profiles "homogeneous" and "box": one constant layer of ``density``.

        Examples
        --------
        >>> ExpLayer.homogeneous_from_params({"density": 0.5})
        (ExpLayer(density=0.5, falloff=0.0, height=0.0),)
        """
        return (cls(number(params, "density", 1.0, src, 0.0, 1e6), 0.0, 0.0),)

    @property
    def is_constant(self) -> bool:
        """The density does not depend on height (``falloff == 0``)."""
        return self.falloff == 0

    @property
    def reference_height(self) -> float:
        """``height`` [m]: where the relative density equals ``density``."""
        return float(self.height)

    def validate(self, src: str, i: int) -> None:
        check_layer_param(src, i, "density", self.density, 0.0, 1e6)
        check_layer_param(src, i, "falloff", self.falloff, 0.0, 1e3)
        check_layer_param(src, i, "height", self.height, -1e7, 1e7)

    def log_c(self, ops: Any, oy: Any) -> Any:
        """log of the density at height ``oy``; the parameters enter as ``ops.param``
        (opaque in Dr.Jit kernels: a new value needs no new kernel)."""
        log_density = math.log(self.density) if self.density > 0 else -1.0e4
        return ops.param(log_density) - ops.param(self.falloff) * (oy - ops.param(self.height))

    @quiet_numpy
    def rho(self, ops: Any, y: Any) -> Any:
        """Relative density at height y (dimensionless)."""
        return ops.exp(ops.minimum(self.log_c(ops, y), ops.exp_limit))

    @quiet_numpy
    def depth(self, ops: Any, oy: Any, dy: Any, t: Any) -> Any:
        """Shape optical depth [m] over ``[0, t]`` along a ray (t = ops.largest: infinity)."""
        return cf.exp_layer_optical_depth(ops, self.log_c(ops, oy), ops.param(self.falloff) * dy, t)

    @quiet_numpy
    def sample(self, ops: Any, oy: Any, dy: Any, s: Any) -> Any:
        """Distance [m] where the shape optical depth reaches ``s``; ops.largest if never."""
        return cf.exp_layer_sample(ops, self.log_c(ops, oy), ops.param(self.falloff) * dy, s)


register_profile("exponential", ExpLayer.from_params)
register_profile("homogeneous", ExpLayer.homogeneous_from_params)
register_profile("box", ExpLayer.homogeneous_from_params, needs_bounds=True)


@dataclass(frozen=True)
class Box:
    """Axis-aligned box [m]: ``lo`` and ``hi`` corners, each (x, y, z).

    A bounds object of :class:`FogMedium` (like :class:`fogref.media.ue_pathtracer.Cylinder`):
    ``lo``/``hi`` (its bounding box), ``validate(src)``, ``inside(ops, p)`` and
    ``clip(ops, o, d)``, the ray interval inside it in closed form.

    Examples
    --------
    >>> from fogref.media import NP
    >>> t0, t1 = Box((0, 0, 0), (10, 10, 10)).clip(NP, (-5.0, 5.0, 5.0), (1.0, 0.0, 0.0))
    >>> float(t0), float(t1)
    (5.0, 15.0)
    """

    lo: tuple
    hi: tuple

    def validate(self, src: str) -> Box:
        """This box with float corners; ParameterError naming 'bounds' unless lo < hi per axis."""
        lo, hi = tuple(map(float, self.lo)), tuple(map(float, self.hi))
        if len(lo) != 3 or len(hi) != 3 or any(a >= b for a, b in zip(lo, hi)):
            raise ParameterError(src, "bounds", f"need lo < hi per axis, got {lo}, {hi}")
        return Box(lo, hi)

    def inside(self, ops: Any, p: Any) -> Any:
        """Whether the points ``p`` (3-sequence of arrays) lie in the closed box."""
        m = True
        for a in range(3):
            m = m & (p[a] >= ops.param(self.lo[a], a)) & (p[a] <= ops.param(self.hi[a], a))
        return m

    def clip(self, ops: Any, o: Any, d: Any) -> Any:
        """Ray interval ``[t0, t1]`` (t0 >= 0) inside the box (slabs); ``t1 < t0`` if none."""
        t0, t1 = 0.0, ops.largest
        for a in range(3):
            lo, hi = ops.param(self.lo[a], a), ops.param(self.hi[a], a)
            da = d[a]
            par = ops.abs(da) < 1e-30
            inv = 1.0 / ops.where(par, 1.0, da)
            ta = (lo - o[a]) * inv
            tb = (hi - o[a]) * inv
            near = ops.minimum(ta, tb)
            far = ops.maximum(ta, tb)
            outside = (o[a] < lo) | (o[a] > hi)
            near = ops.where(par, ops.where(outside, ops.largest, -ops.largest), near)
            far = ops.where(par, ops.where(outside, -ops.largest, ops.largest), far)
            t0 = ops.maximum(t0, near)
            t1 = ops.minimum(t1, far)
        return t0, t1


@dataclass(frozen=True)
class FogMedium:
    """Exponential height fog with RGB extinction and albedo and a phase function.

    sigma_t: RGB extinction at each layer's reference height [1/m], 0 to 1e2.
    albedo:  RGB single-scattering albedo, 0 to 1.
    g:       Henyey–Greenstein asymmetry, -0.999 to 0.999; with ``phase``, replaced by
             its mean cosine (the HG that engines' lobes are fitted to).
    phase:   None (Henyey–Greenstein with ``g``) or a
             :class:`~fogref.media.phase.TabulatedPhase` (droplets' Mie phase, approximate
             Mie): :meth:`phase_value` evaluates either.
    layers:  1 to 4 :class:`~fogref.media.protocol.HeightProfile` layers; empty
             layers are dropped (one is kept if all are empty).
    bounds:  optional :class:`Box` (or another convex bounds object with the same
             methods, e.g. :class:`fogref.media.ue_pathtracer.Cylinder`); the layers'
             fog is 0 outside it.
    volume:  None or a :class:`~fogref.media.local_fog_volume.LocalFogVolume` whose relative
             density adds to the layers' (see module).

    Examples
    --------
    >>> from fogref.media import NP
    >>> fog = FogMedium(sigma_t=0.01, layers=(ExpLayer(1.0, 0.0, 0.0),))
    >>> T = fog.transmittance(NP, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), 100.0)
    >>> [round(float(x), 6) for x in T]
    [0.367879, 0.367879, 0.367879]
    >>> ball = LocalFogVolume(centre=(50.0, 0.0, 0.0), radius=10.0, density=3.0)
    >>> lfv = FogMedium(sigma_t=0.01, layers=(ExpLayer(1.0, 0.0, 0.0),), volume=ball)
    >>> round(float(lfv.optical_depth(NP, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), 100.0)), 9)  # 100 + 3 * 40/3
    140.0
    """

    sigma_t: Any = (0.01, 0.01, 0.01)  # one number or three; stored as a 3-tuple
    albedo: Any = (0.9, 0.9, 0.9)  # likewise
    g: float = 0.0
    layers: tuple = (ExpLayer(),)
    bounds: Any = None
    source: str = field(default="<FogMedium>", compare=False, repr=False)
    phase: Any = None
    volume: LocalFogVolume | None = None

    def __post_init__(self) -> None:
        src = self.source
        if self.phase is not None:
            object.__setattr__(self, "g", max(-0.999, min(0.999, self.phase.mean_cosine)))
        object.__setattr__(self, "sigma_t", rgb(self.sigma_t, "sigma_t", src, 0.0, 1e2))
        object.__setattr__(self, "albedo", rgb(self.albedo, "albedo", src, 0.0, 1.0))
        if not (-0.999 <= float(self.g) <= 0.999):
            raise ParameterError(src, "g", f"value {self.g} outside [-0.999, 0.999]")
        object.__setattr__(self, "g", float(self.g))
        layers = tuple(self.layers)
        if not 1 <= len(layers) <= 4:
            raise ParameterError(src, "layers", f"expected 1 to 4 layers, got {len(layers)}")
        for i, L in enumerate(layers):
            L.validate(src, i)
        kept = tuple(L for L in layers if not L.is_empty)
        object.__setattr__(self, "layers", kept or layers[:1])
        if self.bounds is not None:
            object.__setattr__(self, "bounds", self.bounds.validate(src))
        if self.volume is not None and not isinstance(self.volume, LocalFogVolume):
            raise ParameterError(
                src, "volume", f"expected a LocalFogVolume, got {type(self.volume).__name__}"
            )

    # -- the phase function ----------------------------------------------------
    def phase_value(self, ops: Any, cos_theta: Any) -> Any:
        """The phase function [1/sr] at ``cos_theta = dot(d, w)`` (``d`` along the ray, ``w``
        toward the light; see :func:`~fogref.media.closed_form.hg_phase`)."""
        if self.phase is None:
            return cf.hg_phase(ops, cos_theta, self.g)
        return self.phase.eval(ops, cos_theta)

    def require_hg(self, who: str) -> None:
        """ParameterError naming 'phase' unless the phase is Henyey–Greenstein (``who``: the
        closed form or estimator that assumes it)."""
        if self.phase is not None:
            raise ParameterError(
                self.source,
                "phase",
                f"{who} assumes a Henyey-Greenstein phase; the fog's is '{self.phase.label}'",
            )

    def require_height_only(self, who: str) -> None:
        """ParameterError naming 'lfv_radius' when the fog has a Local Fog Volume (``who``: the
        closed form, sampler or mapping that knows height layers only).

        >>> FogMedium(volume=LocalFogVolume(), source="<d>").require_height_only("f")
        Traceback (most recent call last):
        ...
        fogref.errors.ParameterError: <d>: parameter 'lfv_radius': f: height layers only, no Local Fog Volume
        """
        if self.volume is not None:
            raise ParameterError(self.source, "lfv_radius", f"{who}: height layers only, no Local Fog Volume")

    # -- what the scene needs (trace-time specialisation) ---------------------
    @property
    def is_vacuum(self) -> bool:
        empty = all(L.is_empty for L in self.layers) and (self.volume is None or self.volume.density == 0)
        return max(self.sigma_t) == 0 or empty

    @property
    def free_flight_variates(self) -> int:
        """How many Exp(1) variates :meth:`sample_distance` takes: one per layer, one for the volume."""
        return len(self.layers) + (self.volume is not None)

    @property
    def scatters(self) -> bool:
        return not self.is_vacuum and max(self.albedo) > 0

    @property
    def is_homogeneous(self) -> bool:
        return self.volume is None and all(L.is_constant for L in self.layers)

    def grey_sigma_t(self, who: str = "this model") -> float:
        """The extinction scale [1/m] when it is grey (equal RGB channels).

        Raises ParameterError naming 'sigma_t' (``who``'s fog is grey) otherwise.

        Examples
        --------
        >>> FogMedium(sigma_t=0.02).grey_sigma_t()
        0.02
        """
        s = self.sigma_t
        if max(s) - min(s) > 1e-12 * max(max(s), 1e-300):
            raise ParameterError(self.source, "sigma_t", f"{who}'s fog is grey; got {tuple(s)}")
        return float(s[0])

    def max_density(self, ops: Any, y_lo: Any, y_hi: Any) -> Any:
        """Largest relative density on heights ``[y_lo, y_hi]`` (sum over the layers and the
        volume's bound; the bounds' heights are the caller's to apply, and the volume is not
        clipped by them)."""
        rho = 0.0
        for L in self.layers:
            rho = rho + L.max_density(ops, y_lo, y_hi)
        if self.volume is not None:
            rho = rho + self.volume.max_density(ops, y_lo, y_hi)
        return rho

    # -- relative density ----------------------------------------------------
    @quiet_numpy
    def density(self, ops: Any, p: Any) -> Any:
        """Relative density rho(p) (dimensionless); ``sigma_t * rho`` is 1/m."""
        y = p[1]
        rho = 0.0
        for L in self.layers:
            rho = rho + L.rho(ops, y)
        if self.bounds is not None:
            rho = ops.where(self._inside(ops, p), rho, 0.0)
        if self.volume is not None:
            rho = rho + self.volume.rho(ops, p)
        return rho

    def _inside(self, ops: Any, p: Any) -> Any:
        assert self.bounds is not None  # only called on bounded fog
        return self.bounds.inside(ops, p)

    # -- clipping to the bounds ----------------------------------------------
    @quiet_numpy
    def clip(self, ops: Any, o: Any, d: Any) -> Any:
        """Ray interval ``[t0, t1]`` (t0 >= 0) inside the bounds; ``t1 < t0`` if none."""
        if self.bounds is None:
            return 0.0, ops.largest
        return self.bounds.clip(ops, o, d)

    # -- optical depth -------------------------------------------------------
    def _layers_depth(self, ops: Any, oy: Any, dy: Any, t: Any) -> Any:
        tau = 0.0
        for L in self.layers:
            tau = tau + L.depth(ops, oy, dy, t)
        return ops.minimum(tau, cf.TAU_MAX)

    @quiet_numpy
    def optical_depth(self, ops: Any, o: Any, d: Any, t: Any) -> Any:
        """Shape optical depth [m] over ``[0, t]`` (``t = ops.largest``: to infinity)."""
        if self.volume is not None:
            tau = self._height_depth(ops, o, d, t) + self.volume.optical_depth(ops, o, d, t)
            return ops.minimum(tau, cf.TAU_MAX)
        return self._height_depth(ops, o, d, t)

    def _height_depth(self, ops: Any, o: Any, d: Any, t: Any) -> Any:
        if self.bounds is None:
            return self._layers_depth(ops, o[1], d[1], t)
        t0, t1 = self.clip(ops, o, d)
        t_end = ops.minimum(t, t1)
        length = ops.maximum(t_end - t0, 0.0)
        oy = o[1] + ops.where(length > 0, t0, 0.0) * d[1]
        tau = self._layers_depth(ops, oy, d[1], length)
        return ops.where(length > 0, tau, 0.0)

    @quiet_numpy
    def transmittance(self, ops: Any, o: Any, d: Any, t: Any) -> Any:
        """RGB transmittance over ``[0, t]`` as a 3-tuple of arrays."""
        tau = self.optical_depth(ops, o, d, t)
        return tuple(ops.exp(-s * tau) for s in ops.params(self.sigma_t))

    def sun_optical_depth(self, ops: Any, p: Any, w: Any) -> Any:
        """Shape optical depth from ``p`` to infinity toward ``w`` (unit, to the sun)."""
        return self.optical_depth(ops, p, w, ops.largest)

    # -- free-flight sampling ------------------------------------------------
    @quiet_numpy
    def sample_distance(self, ops: Any, o: Any, d: Any, exp_variates: Any, sigma: Any) -> Any:
        """Exact free-flight distance for extinction ``sigma * rho`` [1/m].

        ``exp_variates``: one Exp(1) variate (``-log1p(-u)``) per layer, then one for the
        volume (:attr:`free_flight_variates`).  Each part is inverted in closed form and the
        nearest collision wins (exact: the parts' transmittances multiply).  Returns
        ``ops.largest`` when the ray leaves the fog without a collision.
        """
        t0, t1 = (0.0, ops.largest) if self.bounds is None else self.clip(ops, o, d)
        if self.bounds is not None:
            # A ray that misses the box must never collide: decide that from the
            # clipped interval itself, before t0 is reset for the inversion below.
            meets_box = t1 >= t0
            t0 = ops.where(meets_box, t0, 0.0)
        oy = o[1] + t0 * d[1] if self.bounds is not None else o[1]
        inv_sigma = 1.0 / ops.maximum(sigma, 1e-30)
        t = ops.largest
        for L, e in zip(self.layers, exp_variates):
            tl = L.sample(ops, oy, d[1], e * inv_sigma)
            t = ops.minimum(t, tl)
        if self.bounds is not None:
            hit = (t < ops.largest) & (t0 + t <= t1) & meets_box
            t = ops.where(hit, t0 + t, ops.largest)
        if self.volume is not None:
            t = ops.minimum(t, self.volume.sample(ops, o, d, exp_variates[len(self.layers)] * inv_sigma))
        return t

    @quiet_numpy
    def invert_optical_depth(self, ops: Any, o: Any, d: Any, s: Any, t_max: Any, iterations: int = 16) -> Any:
        """Distance ``t`` in ``[0, t_max]`` where the shape optical depth reaches ``s``.

        Unbounded height layers only (a volume: ParameterError).  One layer: the exact closed
        form.  Several layers: Newton on ``tau(t) - s`` (``tau' = rho > 0``) started where it converges
        monotonically: at 0 for rays that rise or stay level (``tau`` concave or
        linear), at the upper bound ``min_l t_l`` for descending rays (``tau``
        convex), ``t_l`` being where layer ``l`` alone reaches ``s``.  ``s`` must
        lie in ``[0, tau(t_max)]``.
        """
        self.require_height_only("invert_optical_depth")
        oy, dy = o[1], d[1]
        hi = ops.minimum(t_max, ops.largest)
        for L in self.layers:
            hi = ops.minimum(hi, L.sample(ops, oy, dy, s))
        if len(self.layers) == 1:
            return hi
        t = ops.where(dy < 0, hi, 0.0 * hi)
        for _ in range(iterations):
            f = self._layers_depth(ops, oy, dy, t) - s
            rho = 0.0
            for L in self.layers:
                rho = rho + L.rho(ops, oy + t * dy)
            t = ops.minimum(ops.maximum(t - f / ops.maximum(rho, 1e-30), 0.0), hi)
        return t
