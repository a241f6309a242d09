"""A physical Local Fog Volume: a sphere of fog with a parabolic radial profile and an
exponential height term, in closed form (numpy and Dr.Jit).

Relative density (dimensionless; like a :class:`~fogref.media.medium.FogMedium` layer, it
multiplies the fog's ``sigma_t`` [1/m], and it adds to the height fog's relative density)::

    rho_lfv(p) = density * max(1 - |p - centre|^2 / radius^2, 0) * exp(-falloff * (p_y - height))

World space is fogref's (y-up, metres).  This is the physical counterpart of Unreal 5's Local
Fog Volume (:mod:`fogref.models.ue_local_fog_volume`), whose radial and height terms are
separate media combined by multiplying their coverages.  An unrotated Unreal volume at
``Location`` [cm, z-up], ``FogUniformScale`` ``S`` [cm] and ``HeightFogFalloff`` ``f``,
``HeightFogOffset`` ``h_u`` has the same shapes here with ``centre = (X, Z, Y) / 100``,
``radius = S / 100`` m, ``falloff = max(f, 1) / 100 / radius`` [1/m] and
``height = centre_y + h_u * radius`` [m].

Along a ray ``p(t) = o + t d`` (``|d| = 1``) the radial factor is a quadratic in ``t`` that
vanishes at both ends of the chord through the sphere and the height factor is ``exp(a - m t)``
with ``m = falloff * d_y``; the optical depth over a piece of the chord of length ``L`` is
``L (p0 E0(x) + p1 L E1(x) + p2 L^2 E2(x))`` times the density at the piece's start, with
``x = m L`` and ``E_n(x) = int_0^1 u^n exp(-x u) du`` (a series for ``|x| < 2``, the closed
forms beyond).  A piece on which the density grows (``m < 0``) is integrated from its far end,
so that ``x >= 0`` always and no exponential overflows.  Free flight inverts that closed form
with safeguarded Newton steps (bisection when a step leaves the bracket), which is exact to the
arithmetic's precision; combined with the height fog, the nearer of the two collisions is the
exact free flight through the sum (their transmittances multiply).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from fogref.errors import ParameterError
from fogref.media import closed_form as cf
from fogref.media.ops import DrJitOps, Ops, Real
from fogref.params import number, vector

#: ``E_n`` uses its Taylor series below this ``x`` (30 terms: truncation < 1e-22 there).
SERIES_LIMIT = 2.0
SERIES_TERMS = 30
#: Safeguarded Newton steps of :meth:`LocalFogVolume.sample` (each halves the bracket at least).
SAMPLE_ITERATIONS = 64
#: The scalar fields' ranges: (name, lo, lo open, hi, unit); ``centre``'s coordinates lie in
#: [-1e7, 1e7] m.  In scene parameters each name takes the prefix ``lfv_``.
RANGES = (
    ("radius", 0.0, True, 1e6, "m"),
    ("density", 0.0, False, 1e6, ""),
    ("falloff", 0.0, False, 1e3, "1/m"),
    ("height", -1e7, False, 1e7, "m"),
)
#: The ``heightfog`` parameters of a volume (:meth:`LocalFogVolume.from_params`).
PARAMS = ("lfv_centre",) + tuple("lfv_" + r[0] for r in RANGES)


def exp_moments(ops: Ops, x: Real) -> tuple:
    """``(E0, E1, E2)(x)``, ``E_n(x) = int_0^1 u^n exp(-x u) du``, for ``x >= 0``.

    Each lies in ``(0, 1 / (n + 1)]``.  Relative error a few ulp times ``exp(x)`` for
    ``x < 2`` (an alternating series), a few ulp beyond.

    >>> from fogref.media import NP
    >>> [round(float(e), 12) for e in exp_moments(NP, 0.0)]
    [1.0, 0.5, 0.333333333333]
    >>> [round(float(e), 12) for e in exp_moments(NP, 3.0)]
    [0.316737643877, 0.08898352517, 0.042726660657]
    """
    x = ops.maximum(x, 0.0)
    xs = ops.minimum(x, SERIES_LIMIT)
    series = [0.0, 0.0, 0.0]
    term = 1.0 + 0.0 * xs  # (-x)^j / j!
    for j in range(SERIES_TERMS):
        for n in range(3):
            series[n] = series[n] + term / (n + j + 1)
        term = term * (-xs) / (j + 1)
    xb = ops.maximum(x, SERIES_LIMIT)
    e = ops.exp(-ops.minimum(xb, ops.exp_limit))
    big = (
        (1.0 - e) / xb,
        (1.0 - e * (1.0 + xb)) / (xb * xb),
        (2.0 - e * (2.0 + xb * (2.0 + xb))) / (xb * xb * xb),
    )
    return tuple(ops.where(x < SERIES_LIMIT, s, b) for s, b in zip(series, big))


@dataclass(frozen=True)
class LocalFogVolume:
    """A sphere of fog (see the module doc).

    centre: (x, y, z) [m], each in [-1e7, 1e7].  radius: [m], in (0, 1e6].  density: the relative
    density at the centre when ``centre_y == height``, in [0, 1e6].  falloff: [1/m], in
    [0, 1e3] (0: no height term).  height: [m], in [-1e7, 1e7].

    Methods take the array back end ``ops``, positions and directions as 3-sequences of
    arrays ``(x, y, z)`` (directions unit vectors) and return relative densities or shape
    optical depths [m] (multiply by ``sigma_t``), as :class:`~fogref.media.medium.FogMedium`.

    Examples
    --------
    >>> from fogref.media import NP
    >>> v = LocalFogVolume(centre=(0.0, 0.0, 0.0), radius=2.0, density=3.0)
    >>> float(v.optical_depth(NP, (-5.0, 0.0, 0.0), (1.0, 0.0, 0.0), NP.largest))  # 3 * 4/3 * 2
    8.0
    >>> float(v.sample(NP, (-5.0, 0.0, 0.0), (1.0, 0.0, 0.0), 4.0))  # half way: the centre
    5.0
    >>> LocalFogVolume(radius=-1.0)
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: <LocalFogVolume>: parameter 'radius': -1 is outside (0, 1000000] m
    """

    centre: tuple = (0.0, 0.0, 0.0)
    radius: float = 1.0
    density: float = 1.0
    falloff: float = 0.0
    height: float = 0.0
    source: str = field(default="<LocalFogVolume>", compare=False, repr=False)

    def __post_init__(self) -> None:
        for name, value in self._checked(vars(self), "", self.source).items():
            object.__setattr__(self, name, value)

    @staticmethod
    def _checked(values: dict, prefix: str, src: str) -> dict:
        """The fields in ``values`` (keys ``prefix + name``), validated against :data:`RANGES`."""
        out: dict[str, Any] = {}
        if prefix + "centre" in values:
            out["centre"] = vector(
                values[prefix + "centre"], prefix + "centre", source=src, lo=-1e7, hi=1e7, unit="m"
            )
        for name, lo, lo_open, hi, unit in RANGES:
            if prefix + name in values:
                v = values[prefix + name]
                out[name] = number(v, prefix + name, source=src, lo=lo, hi=hi, lo_open=lo_open, unit=unit)
        return out

    @classmethod
    def from_params(cls, params: dict, src: str = "<params>") -> LocalFogVolume | None:
        """The volume of a ``heightfog``'s parameters :data:`PARAMS` (``lfv_centre`` a point or
        ``"x, y, z"``), None when there are none.  ``lfv_radius`` is required; the others default
        to the fields' defaults.

        >>> LocalFogVolume.from_params({"lfv_radius": "5", "lfv_centre": "0, 2, 0"})
        LocalFogVolume(centre=(0.0, 2.0, 0.0), radius=5.0, density=1.0, falloff=0.0, height=0.0)
        >>> LocalFogVolume.from_params({"lfv_density": 2.0}, "<doc>")
        Traceback (most recent call last):
        ...
        fogref.errors.ParameterError: <doc>: parameter 'lfv_radius': required for a volume, in (0, 1e6] m
        >>> LocalFogVolume.from_params({"lfv_radius": 0.0}, "<doc>")
        Traceback (most recent call last):
        ...
        fogref.errors.ParameterError: <doc>: parameter 'lfv_radius': 0 is outside (0, 1000000] m
        """
        given = {k: v for k, v in params.items() if k.startswith("lfv_") and v is not None}
        if not given:
            return None
        for k in given:
            if k not in PARAMS:
                raise ParameterError(src, k, f"unknown; a Local Fog Volume takes {', '.join(PARAMS)}")
        if "lfv_radius" not in given:
            raise ParameterError(src, "lfv_radius", "required for a volume, in (0, 1e6] m")
        return cls(**cls._checked(given, "lfv_", src), source=src)

    def max_density(self, ops: Ops, y_lo: Real, y_hi: Real) -> Real:
        """An upper bound of the relative density on heights ``[y_lo, y_hi]``: the height
        term at the lowest height the sphere and the range share (the radial factor <= 1), 0
        where they share none.

        >>> from fogref.media import NP
        >>> v = LocalFogVolume(centre=(0.0, 0.0, 0.0), radius=2.0, density=3.0, falloff=0.5)
        >>> [round(float(v.max_density(NP, y, 5.0)), 6) for y in (-5.0, 1.0, 3.0)]
        [8.154845, 1.819592, 0.0]
        """
        c_y, R = ops.param(self.centre[1]), ops.param(self.radius)
        y = ops.maximum(y_lo, c_y - R)
        la = ops.param(self._log_density()) - ops.param(self.falloff) * (y - ops.param(self.height))
        if not self.density > 0:
            return 0.0 * y
        return ops.where(y <= ops.minimum(y_hi, c_y + R), ops.exp(ops.minimum(la, ops.exp_limit)), 0.0)

    def _log_density(self) -> float:
        return math.log(self.density) if self.density > 0 else -1.0e4

    def rho(self, ops: Ops, p: Any) -> Real:
        """Relative density at the points ``p`` (dimensionless, >= 0)."""
        r2 = 0.0
        for a in range(3):
            q = p[a] - ops.param(self.centre[a], a)
            r2 = r2 + q * q
        inv_r2 = ops.param(1.0 / (self.radius * self.radius))
        radial = ops.maximum(1.0 - r2 * inv_r2, 0.0)
        la = ops.param(self._log_density()) - ops.param(self.falloff) * (p[1] - ops.param(self.height))
        return radial * ops.exp(ops.minimum(la, ops.exp_limit))

    def chord(self, ops: Ops, o: Any, d: Any) -> tuple:
        """``(t0, t1, b, h)``: the ray's chord ``[t0, t1]`` through the sphere (``t1 <= t0``
        when it misses or is tangent), ``-b`` the closest approach to the centre and ``h``
        the half chord [m]."""
        q = [o[a] - ops.param(self.centre[a], a) for a in range(3)]
        b = q[0] * d[0] + q[1] * d[1] + q[2] * d[2]
        perp2 = 0.0
        for a in range(3):
            w = q[a] - b * d[a]
            perp2 = perp2 + w * w
        R = ops.param(self.radius)
        dp = ops.sqrt(perp2)
        h = ops.sqrt(ops.maximum((R - dp) * (R + dp), 0.0))
        return -b - h, -b + h, b, h

    def optical_depth(self, ops: Ops, o: Any, d: Any, t: Real) -> Real:
        """Shape optical depth [m] over ``[0, t]`` (``t = ops.largest``: to infinity)."""
        with ops.errstate():
            return self._depth(ops, o, d, t, self.chord(ops, o, d))

    def _depth(self, ops: Ops, o: Any, d: Any, t: Real, chord: tuple) -> Real:
        c0, c1, b, h = chord
        ta = ops.maximum(c0, 0.0)
        tb = ops.minimum(c1, t)
        L = ops.maximum(tb - ta, 0.0)
        inv_r2 = ops.param(1.0 / (self.radius * self.radius))
        k = ops.param(self.falloff)
        m = k * d[1]
        s0 = ta + b  # both ends measured from the closest approach
        s1 = s0 + L
        back = m < 0.0  # density grows along the piece: integrate from its far end
        s_start = ops.where(back, s1, s0)
        p0 = ops.maximum((h - s_start) * (h + s_start), 0.0) * inv_r2
        p1 = ops.where(back, 2.0 * s1, -2.0 * s0) * inv_r2
        p2 = -inv_r2
        e0, e1, e2 = exp_moments(ops, ops.abs(m) * L)
        poly = ops.maximum(p0 * e0 + L * (p1 * e1 + L * (p2 * e2)), 0.0)
        t_start = ops.where(back, tb, ta)
        la = ops.param(self._log_density()) - k * (o[1] + t_start * d[1] - ops.param(self.height))
        tau = cf.exp_times(ops, la, ops.minimum(L * poly, ops.largest))
        return ops.where(L > 0.0, ops.minimum(tau, cf.TAU_MAX), 0.0)

    def sample(self, ops: Ops, o: Any, d: Any, s: Real, iterations: int = SAMPLE_ITERATIONS) -> Real:
        """Distance [m] where the shape optical depth from ``o`` reaches ``s >= 0``;
        ``ops.largest`` when the ray leaves the sphere first.

        Newton steps on :meth:`optical_depth` inside a bracket that starts as the chord, a
        bisection whenever a step would leave it.  Where ``s`` is tiny and the density is 0 at
        the chord's start (a ray from outside), each step near the root halves the error until
        the quadratic convergence sets in: ``iterations = 64`` leave a round trip
        ``|depth(sample(s)) - s|`` below 1e-14 of the ray's total depth for ``s`` down to 1e-30
        of it (float64).  The steps run in :func:`iterate`: in Dr.Jit a lane stops at a fixed
        point, with the result of all ``iterations``."""
        with ops.errstate():
            chord = self.chord(ops, o, d)
            total = self._depth(ops, o, d, ops.largest, chord)
            start = ops.maximum(chord[0], 0.0)

            def step(lo: Real, hi: Real, t: Real) -> tuple:
                f = self._depth(ops, o, d, t, chord) - s
                lo = ops.where(f < 0.0, t, lo)
                hi = ops.where(f < 0.0, hi, t)
                p = [o[a] + t * d[a] for a in range(3)]
                rho = self.rho(ops, p)
                step = t - f / ops.where(rho > 0.0, rho, 1.0)
                newton_ok = (rho > 0.0) & (step >= lo) & (step <= hi)
                return lo, hi, ops.where(newton_ok, step, 0.5 * (lo + hi))

            lo, hi = start, ops.maximum(chord[1], start)
            _, _, t = iterate(ops, step, (lo, hi, 0.5 * (lo + hi)), iterations)
            t = ops.where(s > 0.0, t, start)
            return ops.where(s < total, t, ops.largest)


def iterate(ops: Ops, step: Any, state: tuple, iterations: int) -> tuple:
    """``state`` (a tuple of arrays) after ``iterations`` applications of ``state = step(*state)``.

    ``step`` maps the state's arrays (floating point) to new ones, the same function of their
    bits wherever it runs.  numpy: a Python loop.  Dr.Jit: one symbolic loop
    (``dr.while_loop``), so that the kernel holds one copy of ``step``, not ``iterations``
    (traced unrolled, its compile time grows with ``iterations``); a lane leaves the loop once
    ``step`` returns its state bit for bit unchanged, a fixed point of ``step``, so that the
    result is bit for bit that of ``iterations`` steps, in fewer of them.

    >>> from fogref.media import NP
    >>> iterate(NP, lambda x: (0.5 * (x + 2.0 / x),), (1.0,), 6)  # Newton for sqrt(2)
    (1.414213562373095,)
    """
    if not isinstance(ops, DrJitOps):
        for _ in range(iterations):
            state = step(*state)
        return state
    dr = ops.dr
    UInt = dr.uint32_array_t(ops.Float)

    def bits(x: Any) -> Any:
        return dr.reinterpret_array(dr.uint_array_t(type(x)), x)

    def body(i: Any, moving: Any, *old: Any) -> tuple:
        new = step(*old)
        moving = dr.zeros(dr.mask_t(ops.Float))
        for x, y in zip(new, old):
            moving = moving | (bits(x) != bits(y))
        return (i + 1, moving, *new)

    out = dr.while_loop(
        (UInt(0), dr.mask_t(ops.Float)(True), *state),
        lambda i, moving, *_: moving & (i < iterations),
        body,
        label="iterate",
    )
    return tuple(out[2:])
