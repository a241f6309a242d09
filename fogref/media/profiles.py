"""More height profiles with exact closed-form optical depth and free flight.

Each profile follows :class:`fogref.media.protocol.HeightProfile` (like
:class:`fogref.media.ExpLayer`), can be put in ``FogMedium(layers=...)`` and
registers its XML ``profile`` name here:

* ``validate(src, i)`` raises :class:`fogref.errors.ParameterError`;
* ``rho(ops, y)``: relative density at height ``y`` (dimensionless);
* ``depth(ops, oy, dy, t)``: shape optical depth [m] of ``[0, t]`` along a ray
  leaving height ``oy`` with direction y-component ``dy`` (``t = ops.largest``:
  to infinity), saturating at :data:`~fogref.media.closed_form.TAU_MAX`;
* ``sample(ops, oy, dy, s)``: the exact inverse of ``depth`` in ``t``; returns
  ``ops.largest`` when the ray leaves the fog before reaching ``s`` (escape);
* ``max_density(ops, y_lo, y_hi)``, ``is_constant``, ``is_empty``,
  ``reference_height``, ``from_params(params, src)``.

Everything is written once against the array back end ``ops`` (numpy float64 or
Dr.Jit float32) and is branch-free on array values: every piece of the ray is
computed and the right one selected with ``ops.where``.  y-up, metres.

Profiles
--------
:class:`HDRPLayer` (Unity HDRP's volumetric fog height profile)::

    rho(y) = density                                  y <= base_height
    rho(y) = density * exp(-falloff (y - base_height))  y >  base_height

:class:`PowerLawLayer` (Unity "altitude fog", the power-law height fade of
:mod:`fogref.models.altitude`, made physical)::

    rho(y) = density                                   y <= start
    rho(y) = density * ((end - y) / (end - start))**power   start < y < end
    rho(y) = 0                                         y >= end

Along a ray a piece of the power law from height ``y_lo`` (its lower end) over a
length ``L`` integrates to ``L u^p g(delta, q)`` with ``u = (end - y_lo)/H``,
``H = end - start``, ``q = p + 1``, ``delta = |dy| L / (end - y_lo)`` and
``g(delta, q) = -expm1(q log1p(-delta)) / (q delta)`` (``g(0) = 1``): no
cancellation for near-horizontal rays, horizontal rays are ``delta = 0``.  Its
inverse is ``L = sigma h(w, q)``, ``sigma = s / (density u_a^p)``,
``w = q dy sigma / (H u_a)``, ``h(w, q) = -q expm1(log1p(-w)/q) / w`` (``h(0) =
1``), with a log form for ``w < -1`` (descending from near the top).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from fogref.errors import ParameterError
from fogref.media import closed_form as cf
from fogref.media.medium import check_layer_param, quiet_numpy
from fogref.media.ops import Ops, Real
from fogref.media.protocol import NonIncreasingLayer, number, register_profile

__all__ = ["HDRPLayer", "PowerLawLayer"]


def _crossing(ops: Ops, oy: Real, dy: Real, y: Real) -> Real:
    """Ray parameter where height ``y`` is crossed, clamped to [-largest, largest]."""
    L = ops.largest
    diff = y - oy
    r = ops.safe_div(diff, dy)
    r = ops.where(ops.isfinite(r), r, ops.where((diff > 0) == (dy > 0), L, -L))
    r = ops.where(dy == 0, ops.where(diff > 0, L, -L), r)
    return ops.minimum(ops.maximum(r, -L), L)


def _pow(ops: Ops, u: Real, p: Real) -> Real:
    """u**p for u >= 0, p >= 0 (0**0 = 1); ``p`` a Python number (``p == 0`` is a branch)."""
    if p == 0:
        return ops.where(u >= 0, 1.0, 1.0) if not isinstance(u, float) else 1.0
    return ops.where(u > 0, ops.exp(ops.param(p) * ops.log(ops.maximum(u, ops.tiny))), 0.0)


@dataclass(frozen=True)
class HDRPLayer(NonIncreasingLayer):
    """Unity HDRP height profile: ``density`` below ``base_height``, then exponential.

    density:     relative scale (multiplies ``sigma_t``), 0 to 1e6.
    base_height: [m], -1e7 to 1e7.
    falloff:     b [1/m] above the base, 0 (homogeneous) to 1e3.

    Examples
    --------
    >>> from fogref.media import NP
    >>> L = HDRPLayer(density=1.0, base_height=10.0, falloff=0.1)
    >>> float(L.rho(NP, 0.0)), float(L.depth(NP, 0.0, 0.0, 5.0))
    (1.0, 5.0)
    """

    profile = "hdrp"

    density: float = 1.0
    base_height: float = 0.0
    falloff: float = 0.0

    @classmethod
    def from_params(cls, params: dict, src: str = "<params>") -> tuple:
        """Profile "hdrp": ``density``, ``base_height`` [m], ``falloff`` [1/m].

        Examples
        --------
        >>> HDRPLayer.from_params({"base_height": 5.0})
        (HDRPLayer(density=1.0, base_height=5.0, falloff=0.01),)
        """
        return (
            cls(
                number(params, "density", 1.0, src, 0.0, 1e6),
                number(params, "base_height", 0.0, src, -1e7, 1e7),
                number(params, "falloff", 0.01, src, 0.0, 1e3),
            ),
        )

    @property
    def is_constant(self) -> bool:
        """Constant everywhere when ``falloff == 0``."""
        return self.falloff == 0

    @property
    def reference_height(self) -> float:
        """``base_height`` [m]: the top of the constant part."""
        return float(self.base_height)

    def validate(self, src: str, i: int) -> None:
        check_layer_param(src, i, "density", self.density, 0.0, 1e6)
        check_layer_param(src, i, "base_height", self.base_height, -1e7, 1e7)
        check_layer_param(src, i, "falloff", self.falloff, 0.0, 1e3)

    @property
    def _log_density(self) -> Real:
        return math.log(self.density) if self.density > 0 else -1.0e4

    def _log_c(self, ops: Ops, y: Real) -> Real:
        """log of the exponential piece's density at ``y`` (valid for y >= base)."""
        return ops.param(self._log_density) - ops.param(self.falloff) * (y - ops.param(self.base_height))

    @quiet_numpy
    def rho(self, ops: Ops, y: Real) -> Real:
        """Relative density at height y."""
        h = ops.maximum(y - ops.param(self.base_height), 0.0)
        return cf.exp_times(ops, ops.param(self._log_density) - ops.param(self.falloff) * h, 1.0)

    def _pieces(self, ops: Ops, oy: Real, dy: Real) -> Real:
        """(t_b, below0, up, down): base crossing and the ray's configuration."""
        hb = ops.param(self.base_height)
        t_b = _crossing(ops, oy, dy, hb)
        below0 = oy <= hb
        return t_b, below0, dy > 0, dy < 0

    @quiet_numpy
    def depth(self, ops: Ops, oy: Real, dy: Real, t: Real) -> Real:
        """Shape optical depth [m] over ``[0, t]`` (``t = ops.largest``: infinity)."""
        L = ops.largest
        hb, density = ops.param(self.base_height), ops.param(self.density)
        k = ops.param(self.falloff) * dy
        t = ops.maximum(t, 0.0)
        t_b, below0, up, down = self._pieces(ops, oy, dy)
        t_bp = ops.maximum(t_b, 0.0)
        # constant piece length
        len_c = ops.where(
            up,
            ops.where(below0, ops.minimum(t, t_bp), 0.0),
            ops.where(down, ops.where(below0, t, ops.maximum(t - t_bp, 0.0)), ops.where(below0, t, 0.0)),
        )
        # exponential piece: start height and length
        y0 = ops.where(up & below0, hb, oy)
        rest = ops.where(t >= L, L, ops.maximum(t - t_bp, 0.0))
        len_e = ops.where(
            up,
            ops.where(below0, rest, t),
            ops.where(down, ops.where(below0, 0.0, ops.minimum(t, t_bp)), ops.where(below0, 0.0, t)),
        )
        tau_c = ops.minimum(density * ops.minimum(len_c, ops.largest), ops.largest)
        tau_c = ops.where((len_c >= L) & (self.density > 0), cf.TAU_MAX, tau_c)
        tau_e = cf.exp_layer_optical_depth(ops, self._log_c(ops, y0), k, len_e)
        tau_e = ops.where(len_e > 0, tau_e, 0.0)
        return ops.minimum(tau_c + tau_e, cf.TAU_MAX)

    @quiet_numpy
    def sample(self, ops: Ops, oy: Real, dy: Real, s: Real) -> Real:
        """Distance [m] where the shape optical depth reaches ``s``; ops.largest if never."""
        L = ops.largest
        hb, density = ops.param(self.base_height), ops.param(self.density)
        k = ops.param(self.falloff) * dy
        t_b, below0, up, down = self._pieces(ops, oy, dy)
        t_bp = ops.maximum(t_b, 0.0)
        inv_d = ops.param(1.0 / self.density if self.density > 0 else L)
        # constant: s / density
        t_const = ops.minimum(s * inv_d, L)
        # going up from below: constant up to the base, then exponential from hb
        tau_c1 = ops.minimum(density * t_bp, L)
        s_rem_up = ops.maximum(s - tau_c1, 0.0)
        t_up_exp = cf.exp_layer_sample(ops, self._log_c(ops, hb + 0.0 * oy), k, s_rem_up)
        t_up_below = ops.where(
            s <= tau_c1, t_const, ops.where(t_up_exp >= L, L, ops.minimum(t_bp + t_up_exp, L))
        )
        # exponential from oy (above base: up, horizontal, or down until the base)
        t_exp = cf.exp_layer_sample(ops, self._log_c(ops, oy), k, s)
        # going down from above: exponential to the base, then constant
        tau_e1 = cf.exp_layer_optical_depth(ops, self._log_c(ops, oy), k, t_bp)
        t_down_above = ops.where(
            s <= tau_e1, t_exp, ops.minimum(t_bp + ops.maximum(s - tau_e1, 0.0) * inv_d, L)
        )
        t = ops.where(
            up,
            ops.where(below0, t_up_below, t_exp),
            ops.where(down, ops.where(below0, t_const, t_down_above), ops.where(below0, t_const, t_exp)),
        )
        t = ops.where(t >= L, L, t)
        return ops.where(s > 0, t, 0.0)


@dataclass(frozen=True)
class PowerLawLayer(NonIncreasingLayer):
    """Power-law altitude profile (Unity altitude fog, :mod:`fogref.models.altitude`), physical.

    density: relative scale (multiplies ``sigma_t``), 0 to 1e6.
    start:   S [m], full density at and below; -1e7 to 1e7.
    end:     E [m] > start, zero density at and above; -1e7 to 1e7.
    power:   p >= 0 (0: a slab of constant density up to ``end``), at most 100.

    Examples
    --------
    >>> from fogref.media import NP
    >>> L = PowerLawLayer(density=1.0, start=0.0, end=100.0, power=1.0)
    >>> float(L.rho(NP, 50.0)), float(L.depth(NP, 0.0, 1.0, NP.largest))
    (0.5, 50.0)
    """

    profile = "powerlaw"

    density: float = 1.0
    start: float = 0.0
    end: float = 100.0
    power: float = 1.0

    @classmethod
    def from_params(cls, params: dict, src: str = "<params>") -> tuple:
        """Profile "powerlaw": ``density``, ``start``, ``end`` [m] and ``power``.

        Examples
        --------
        >>> PowerLawLayer.from_params({"end": 50.0, "power": 2.0})
        (PowerLawLayer(density=1.0, start=0.0, end=50.0, power=2.0),)
        """
        return (
            cls(
                number(params, "density", 1.0, src, 0.0, 1e6),
                number(params, "start", 0.0, src, -1e7, 1e7),
                number(params, "end", 100.0, src, -1e7, 1e7),
                number(params, "power", 1.0, src, 0.0, 1e3),
            ),
        )

    @property
    def is_constant(self) -> bool:
        """Never: the density is 0 at and above ``end``."""
        return False

    @property
    def reference_height(self) -> float:
        """``start`` [m]: full density at and below it."""
        return float(self.start)

    def validate(self, src: str, i: int) -> None:
        check_layer_param(src, i, "density", self.density, 0.0, 1e6)
        check_layer_param(src, i, "start", self.start, -1e7, 1e7)
        check_layer_param(src, i, "end", self.end, -1e7, 1e7)
        check_layer_param(src, i, "power", self.power, 0.0, 100.0)
        if not self.end > self.start:
            raise ParameterError(
                src,
                f"layer{i}.end",
                f"value {float(self.end)} outside [start={float(self.start)}, 1e7]"
                " (end must be greater than start)",
            )

    @property
    def _H(self) -> Real:
        return float(self.end) - float(self.start)

    def _u(self, ops: Ops, y: Real) -> Real:
        return ops.minimum(ops.maximum((ops.param(self.end) - y) / ops.param(self._H), 0.0), 1.0)

    @quiet_numpy
    def rho(self, ops: Ops, y: Real) -> Real:
        """Relative density at height y."""
        u = self._u(ops, y)
        return ops.where(y >= ops.param(self.end), 0.0, ops.param(self.density) * _pow(ops, u, self.power))

    def _geometry(self, ops: Ops, oy: Real, dy: Real) -> Real:
        s_S = _crossing(ops, oy, dy, ops.param(self.start))
        s_E = _crossing(ops, oy, dy, ops.param(self.end))
        return s_S, s_E, dy > 0, dy < 0

    def _power_piece(self, ops: Ops, gap: Real, abs_dy: Real, length: Real, reaches_end: Real) -> Real:
        """int of u^p over a piece of length ``length`` whose lower end lies ``gap`` below E."""
        L = ops.largest
        p, q = float(self.power), float(self.power) + 1.0
        H, qp = ops.param(self._H), ops.param(q)
        gap = ops.minimum(ops.maximum(gap, 0.0), H)  # = H u_hi
        u_hi = ops.minimum(gap / H, 1.0)
        dl = ops.minimum(abs_dy * length, L)
        delta = ops.minimum(ops.safe_div(dl, gap), 1.0)
        delta = ops.where(reaches_end, 1.0, delta)
        dmid = ops.minimum(delta, 0.5)
        g_small = ops.safe_div(-ops.expm1(qp * ops.log1p(-dmid)), qp * dmid)
        g_small = ops.where(dmid == 0, 1.0, g_small)
        dbig = ops.maximum(delta, 0.5)
        # 1 - (1-d)^q with 1 - d exact for d >= 0.5
        one_m = ops.maximum(1.0 - dbig, 0.0)
        g_big = (1.0 - _pow(ops, one_m, q)) / (qp * dbig)
        g = ops.where(delta > 0.5, g_big, g_small)
        val = ops.minimum(length, L) * _pow(ops, u_hi, p) * g
        return ops.where((length > 0) & (gap > 0), ops.minimum(val, L), 0.0)

    @quiet_numpy
    def depth(self, ops: Ops, oy: Real, dy: Real, t: Real) -> Real:
        """Shape optical depth [m] over ``[0, t]`` (``t = ops.largest``: infinity)."""
        L = ops.largest
        S, E, density = ops.param(self.start), ops.param(self.end), ops.param(self.density)
        t = ops.maximum(t, 0.0)
        s_S, s_E, up, down = self._geometry(ops, oy, dy)
        abs_dy = ops.abs(dy)
        # constant piece (y <= S)
        len_c = ops.where(
            up,
            ops.where(oy < S, ops.minimum(t, s_S), 0.0),
            ops.where(
                down,
                ops.where(t >= L, L, t - ops.minimum(ops.maximum(s_S, 0.0), t)),
                ops.where(oy <= S, t, 0.0),
            ),
        )
        # power piece: parameter interval [a, b] and lower end height
        a = ops.where(up, ops.maximum(s_S, 0.0), ops.where(down, ops.maximum(s_E, 0.0), 0.0))
        b = ops.where(up, ops.minimum(t, s_E), ops.where(down, ops.minimum(t, s_S), t))
        inside_h = (oy > S) & (oy < E)
        length = ops.where(up | down, ops.maximum(b - a, 0.0), ops.where(inside_h, t, 0.0))
        # gap = E - (lower end of the piece), formed without cancellation
        gap_dn = (E - oy) + ops.minimum(ops.where(t >= L, 0.0, t) * abs_dy, ops.largest)
        gap = ops.where(
            up,
            E - ops.maximum(oy, S),
            ops.where(down, ops.where((t >= L) | (t >= s_S), E - S, gap_dn), E - oy),
        )
        reaches_end = (up & (t >= s_E)) | (down & (oy >= E))
        tau_p = self._power_piece(ops, gap, abs_dy, length, reaches_end)
        tau = density * ops.minimum(len_c, L) + density * tau_p
        tau = ops.where(((len_c >= L) | (length >= L)) & (self.density > 0), cf.TAU_MAX, tau)
        return ops.minimum(tau, cf.TAU_MAX)

    def _invert_power(self, ops: Ops, y_a: Real, dy: Real, sig: Real) -> Real:
        """Length along the ray, from height y_a in [S, E], where int u^p = sig."""
        L = ops.largest
        p, q = float(self.power), float(self.power) + 1.0
        pp, qp, H, log_H = ops.param(p), ops.param(q), ops.param(self._H), ops.param(math.log(self._H))
        u_a = ops.minimum(ops.maximum((ops.param(self.end) - y_a) / H, 0.0), 1.0)
        log_u = ops.log(ops.maximum(u_a, ops.tiny))
        log_sig = ops.log(ops.maximum(sig, ops.tiny))
        abs_dy = ops.abs(dy)
        # log|w| = log(q |dy| sig) - log H - q log u_a
        lw = ops.log(ops.maximum(qp * abs_dy, ops.tiny)) + log_sig - log_H - qp * log_u
        lw = ops.where(u_a > 0, lw, ops.largest)
        small = (dy == 0) | (lw <= 0.0)
        # |w| <= 1: L = sigma h(w, q), sigma = sig / u_a^p
        sigma = cf.exp_times(ops, -pp * log_u, sig)
        w = ops.where(dy > 0, 1.0, -1.0) * ops.exp(ops.minimum(lw, 0.0))
        w = ops.where(dy == 0, 0.0, w)
        wm = ops.minimum(w, 0.5)
        h_small = ops.safe_div(-qp * ops.expm1(ops.log1p(-wm) / qp), wm)
        h_small = ops.where(wm == 0, 1.0, h_small)
        wb = ops.minimum(ops.maximum(w, 0.5), 1.0)
        h_big = qp * (1.0 - ops.exp(ops.log(ops.maximum(1.0 - wb, ops.tiny)) / qp)) / wb
        h = ops.where(w > 0.5, h_big, h_small)
        t_small = ops.minimum(sigma * h, L)
        # w < -1 (descending, from near the top): u_b = (u_a^q + A)^(1/q),
        # A = q |dy| sig / H; length = H (u_b - u_a) / |dy|
        lw_p = ops.minimum(ops.maximum(lw, 0.0), ops.largest)
        log_A = ops.log(ops.maximum(qp * abs_dy, ops.tiny)) + log_sig - log_H
        X = (lw_p + ops.log1p(ops.exp(-lw_p))) / qp  # log((1+|w|)^(1/q))
        u_b = ops.exp(ops.minimum((log_A + ops.log1p(ops.exp(-lw_p))) / qp, ops.log_largest))
        diff = ops.where(X < 1.0, u_a * ops.expm1(ops.minimum(X, 1.0)), u_b - u_a)
        inv_dy = 1.0 / ops.where(abs_dy > 0, abs_dy, 1.0)
        t_big = ops.minimum(H * ops.minimum(diff, ops.param(L / self._H)) * inv_dy, L)
        t = ops.where(small, t_small, t_big)
        # going up with w >= 1: leaves the top first
        t = ops.where((dy > 0) & (lw >= 0.0), L, t)
        return ops.where(sig > 0, t, 0.0)

    @quiet_numpy
    def sample(self, ops: Ops, oy: Real, dy: Real, s: Real) -> Real:
        """Distance [m] where the shape optical depth reaches ``s``; ops.largest if never."""
        L = ops.largest
        S, E = ops.param(self.start), ops.param(self.end)
        s_S, s_E, up, down = self._geometry(ops, oy, dy)
        inv_d = ops.param(1.0 / self.density if self.density > 0 else L)
        sig = ops.minimum(s * inv_d, L)  # shape depth in units of density
        s_Sp = ops.maximum(s_S, 0.0)
        s_Ep = ops.maximum(s_E, 0.0)
        # --- going up: constant [0, s_S+] then power from max(oy, S), then escape
        c1 = ops.where(oy < S, s_Sp, 0.0)  # constant length before the power piece
        t_up_p = self._invert_power(ops, ops.maximum(oy, S), dy, ops.maximum(sig - c1, 0.0))
        t_up = ops.where(sig <= c1, sig, ops.where(t_up_p >= L, L, ops.minimum(c1 + t_up_p, L)))
        # --- going down: nothing to s_E+, power from min(oy, E) down to S, then constant
        y_a = ops.minimum(oy, E)
        len_p = ops.maximum(s_Sp - s_Ep, 0.0)
        len_p = ops.where(oy <= S, 0.0, len_p)
        tot_p = self._power_piece(ops, E - S + 0.0 * oy, ops.abs(dy), len_p, oy >= E)
        tot_p = ops.where(oy <= S, 0.0, tot_p)
        t_dn_p = self._invert_power(ops, y_a, dy, sig)
        t_dn = ops.where(
            sig < tot_p,
            ops.minimum(s_Ep + t_dn_p, L),
            ops.minimum(ops.maximum(s_Sp, 0.0) + ops.maximum(sig - tot_p, 0.0), L),
        )
        t_dn = ops.where(oy <= S, sig, t_dn)
        # --- horizontal
        u0 = self._u(ops, oy)
        t_h = ops.where(
            oy <= S,
            sig,
            ops.where(
                oy >= E,
                L,
                cf.exp_times(ops, -ops.param(self.power) * ops.log(ops.maximum(u0, ops.tiny)), sig),
            ),
        )
        t = ops.where(up, t_up, ops.where(down, t_dn, t_h))
        t = ops.where(t >= L, L, t)
        return ops.where(s > 0, t, 0.0)


register_profile("hdrp", HDRPLayer.from_params)
register_profile("powerlaw", PowerLawLayer.from_params)
