"""Closed-form single scattering along an unoccluded camera ray.

This is exactly the term that Unreal's cosine-lobe directional inscattering
approximates: sunlight scattered once toward the camera, attenuated on the way in
and on the way out, with the true phase function.

For exponential layers sharing one albedo, along ``p(t) = o + t d`` and toward the
sun ``w`` (unit, ``w_y > 0``)::

    tau_sun(p(t)) = tau_sun(o) - (d_y / w_y) tau(t)          (every layer)
    L_ss = alpha p(d.w) E T_sun(o) int_0^D sigma e^{-m tau} dt,   m = 1 - d_y / w_y
         = alpha p(d.w) E T_sun(o) tau(D) phi(m tau(D))

which is stable everywhere through ``phi`` (:func:`fogref.media.closed_form.phi`).
The first identity holds for any height profile; the sun's optical depth is
infinite (no sun light) when a layer is constant in height.

Beside the delta sun and the uniform sky: :func:`sky_phase_projection` projects any sky
(e.g. Mitsuba's ``sunsky``) onto the Henyey–Greenstein phase function per view direction, so
the sky's single scattering along an unoccluded ray is ``albedo S(v) (1 - T)``
(:func:`single_scatter_sky_projected`; for a uniform sky :func:`single_scatter_sky`), and
:func:`single_scatter_sun_disk` integrates the sun's disk where :func:`single_scatter_sun`
takes a delta.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numpy.polynomial import legendre

from fogref.errors import ParameterError
from fogref.media import closed_form as cf
from fogref.media.closed_form import phi, psi
from fogref.media.medium import ExpLayer
from fogref.media.ops import NP, Ops, Real


def single_scatter_sun(
    ops: Ops, medium: Real, o: Real, d: Real, D: Real, w: Real, E: Real, tau: Real = None
) -> Real:
    """Single-scattered sun radiance along ``[0, D]`` of ``o + t d`` (RGB tuple).

    medium: :class:`~fogref.media.FogMedium` without bounds.
    o, d:   camera position [m] and unit view direction (away from the camera).
    D:      distance to the first surface [m] (``ops.largest`` for the sky).
    w:      unit direction toward the sun (a 3-tuple of floats; or of arrays, one direction
            per sample, all above the horizon: the caller checks, e.g. a point of a sun disk).
    E:      RGB sun irradiance on a plane facing the sun [W/m^2 or any unit].
    tau:    optional shape optical depth over ``[0, D]`` when the caller has it
            (saves recomputing it; default: computed here).

    Returns radiance in E's unit per steradian, no occlusion, no sky.  Zero when
    the sun is at or below the horizon (``w_y <= 0``) or a layer is homogeneous
    and unbounded (the sun is then fully extinguished).

    The sun is a delta along ``w``.  For a sun disk (fogpath's ``sun_angular_diameter``) use
    :func:`~fogref.media.single_scatter.single_scatter_sun_disk`; the delta's relative
    error at 0.53 deg is 1.2e-4 at
    ``g = 0.6`` and 14 % at ``g = 0.99`` looking into the sun, below 1e-4 30 deg away from it.

    Examples
    --------
    >>> from fogref.media import NP, ExpLayer, FogMedium
    >>> fog = FogMedium(sigma_t=0.01, albedo=1.0, layers=(ExpLayer(1.0, 0.05, 0.0),))
    >>> o, d, w, E = (0.0, 1.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (1.0, 1.0, 1.0)
    >>> L = single_scatter_sun(NP, fog, o, d, 100.0, w, E)
    >>> round(float(L[0]), 4)   # (1 - T) p T_sun = 0.61 * 1/(4 pi) * 0.83
    0.0404
    """
    if medium.bounds is not None:
        raise ParameterError(
            medium.source, "bounds", "closed-form single scattering needs an unbounded medium"
        )
    medium.require_height_only("closed-form single scattering")
    try:
        wy, per_sample = float(w[1]), False
    except (TypeError, RuntimeError):  # one direction per sample: the caller keeps them up
        wy, per_sample = 1.0, True
    if wy <= 0 or any(L.is_constant for L in medium.layers):
        zero = 0.0 * d[0]
        return (zero, zero, zero)
    w_ = tuple(w) if per_sample else ops.params(w)
    cos_theta = d[0] * w_[0] + d[1] * w_[1] + d[2] * w_[2]
    phase = medium.phase_value(ops, cos_theta)
    if tau is None:
        tau = medium.optical_depth(ops, o, d, D)
    tau_sun_o = medium.sun_optical_depth(ops, o, w_)
    m = 1.0 - d[1] / w_[1]
    tau_sun_end = medium.sun_optical_depth(ops, tuple(o[i] + D * d[i] for i in range(3)), w_)
    sigs, alb_es = ops.params(medium.sigma_t), ops.params([alb * e for alb, e in zip(medium.albedo, E)])
    integrals: list = []
    out: list = []
    for c, (sig, alb_e, first) in enumerate(zip(sigs, alb_es, first_equal(medium.sigma_t))):
        if first < c:  # a channel with an earlier one's extinction (grey fog): its integral
            integrals.append(integrals[first])
        else:
            tc = sig * tau
            # m >= 0: T_sun(o) * tc * phi(m tc), all factors bounded.
            t_sun_o = ops.exp(-sig * tau_sun_o)
            pos = t_sun_o * ops.minimum(tc * cf.phi(ops, ops.maximum(m, 0.0) * tc), ops.largest)
            # m < 0 (looking up more steeply than the sun): fold both exponentials,
            # exp(-sig (tau_sun(D) + tau)) (1 - exp(m tc)) / (-m), whose exponent is <= 0.
            neg_m = ops.where(m < 0, -m, 1.0)
            neg = ops.exp(-sig * (tau_sun_end + tau)) * (-ops.expm1(-neg_m * tc)) / neg_m
            integrals.append(ops.where(m < 0, neg, pos))
        out.append(alb_e * phase * integrals[c])
    return tuple(out)


def single_scatter_sky(
    ops: Ops, medium: Real, o: Real, d: Real, D: Real, L_sky: Real, tau: Real = None
) -> Real:
    """Single-scattered uniform sky, unoccluded and unattenuated: alpha L (1 - T(D)).
    A non-uniform sky (``sunsky``):
    :func:`~fogref.media.single_scatter.single_scatter_sky_projected`.  ``tau``: the shape
    optical depth over ``[0, D]`` when the caller has it (as :func:`single_scatter_sun` takes it)."""
    if tau is None:
        tau = medium.optical_depth(ops, o, d, D)
    alb_L = ops.params([alb * L for alb, L in zip(medium.albedo, L_sky)])
    opacity = _opacities(ops, ops.params(medium.sigma_t), first_equal(medium.sigma_t), tau)
    return tuple(aL * op for aL, op in zip(alb_L, opacity))


def _opacities(ops: Ops, sigs: Real, first: list[int], tau: Real) -> list:
    """``1 - exp(-sigma_c tau)`` per channel of ``sigs``, a channel whose extinction equals an
    earlier one's (``first``, :func:`first_equal`) that one's."""
    out: list = []
    for c, (sig, j) in enumerate(zip(sigs, first)):
        out.append(out[j] if j < c else -ops.expm1(-sig * tau))
    return out


def first_equal(values: Real) -> list[int]:
    """Per value, the index of the first value equal to it: a channel's results are an earlier
    channel's when their parameters are equal.  numpy computes a grey fog's three channels three
    times unless told; Dr.Jit merges identical arithmetic itself (:meth:`fogref.media.ops.DrJitOps.params`
    gives equal values one array, by the same rule).

    >>> first_equal((0.5, 0.5, 0.25))
    [0, 0, 2]
    """
    values = list(values)
    return [values.index(v) for v in values]


def _log_x_phi(ops: Ops, X: Real, mX: Real) -> Real:
    """log(X * phi(m X)) for X > 0, stable for any sign and size of m X."""
    big_neg = mX < -20.0
    z = ops.where(big_neg, -1.0, mX)
    direct = ops.log(ops.maximum(X, 1e-37)) + ops.log(phi(ops, z))
    zneg = ops.minimum(mX, -20.0)
    via = ops.log(ops.maximum(X, 1e-37)) - zneg - ops.log(-zneg)
    return ops.where(big_neg, via, direct)


def sample_sun_single_scatter(
    ops: Ops, medium: Real, o: Real, d: Real, D: Real, w: Real, E: Real, u: Real, channel: Real
) -> Real:
    """Sample a point on ``[0, D]`` in proportion to the sun's single-scattering
    integrand and return ``(t, weights)`` with ``weights[c] = f_c(t) / pdf(t)``.

    Multiply the weights by the sun's geometric visibility at ``o + t d`` and the
    estimate of each channel is unbiased for :func:`single_scatter_sun`; without
    occluders it is exact (zero variance).  Valid for exponential layers with
    ``falloff > 0`` (one layer: closed-form inversion; several: Newton, see
    :meth:`FogMedium.invert_optical_depth`), no bounds and the sun above the
    horizon (``w_y > 0``); the caller checks (see :func:`sun_sampling_applies`).

    Per channel, with ``x = sigma_c tau(t)``, ``X = sigma_c tau(D)`` and
    ``m = 1 - d_y / w_y``, the integrand is proportional to ``exp(-m x) dx``: its
    CDF ``x phi(m x) / (X phi(m X))`` inverts to ``x = Y psi(m Y)`` with
    ``Y = u X phi(m X)``, and ``t`` follows from the layer's exact inversion.
    The channel used for sampling (``channel`` in {0,1,2}, uniform) is combined
    by one-sample MIS: ``weights_c = CF_c pdf_c(t) / mean_k pdf_k(t)``.
    """
    m = 1.0 - d[1] / ops.param(w[1])
    tau_D = medium.optical_depth(ops, o, d, D)
    sig = ops.params(medium.sigma_t)
    s_ch = ops.where(channel == 1, sig[1], ops.where(channel == 2, sig[2], sig[0]))
    X = s_ch * tau_D
    x = _invert_exp_integrand(ops, X, m, u)
    t = medium.invert_optical_depth(ops, o, d, x / ops.maximum(s_ch, 1e-30), D)
    t = ops.minimum(t, D)
    tau_t = medium.optical_depth(ops, o, d, t)
    # log pdf_c(t) / rho(t) for each channel
    logs = []
    for s in sig:
        Xc = s * tau_D
        logs.append(ops.log(ops.maximum(s, 1e-37)) - m * s * tau_t - _log_x_phi(ops, Xc, m * Xc))
    lmax = ops.maximum(ops.maximum(logs[0], logs[1]), logs[2])
    r = [ops.exp(lc - lmax) for lc in logs]
    mean_r = (r[0] + r[1] + r[2]) / 3.0
    closed = single_scatter_sun(ops, medium, o, d, D, w, E, tau=tau_D)
    weights = tuple(
        ops.where((mean_r > 0) & (tau_D > 0), cf_c * rc / mean_r, 0.0) for cf_c, rc in zip(closed, r)
    )
    return t, weights


def _invert_exp_integrand(ops: Ops, X: Real, m: Real, u: Real) -> Real:
    """``x`` in ``[0, X]`` with ``int_0^x e^{-m y} dy = u int_0^X e^{-m y} dy`` (any sign of m).

    ``m X >= -20``: ``Y psi(m Y)`` with ``Y = u X phi(m X)``; strongly rising rays
    (``m X < -20``): the log form, which cannot overflow.
    """
    mX = m * X
    Y = u * X * phi(ops, ops.maximum(mX, -20.0))
    x_pos = Y * psi(ops, ops.minimum(m * Y, 0.999999))
    abs_m = ops.where(m < 0, -m, 1.0)
    x_neg = X + ops.log(ops.maximum(u + (1.0 - u) * ops.exp(-abs_m * X), 1e-37)) / abs_m
    x = ops.where(mX < -20.0, x_neg, x_pos)
    return ops.minimum(ops.maximum(x, 0.0), X)


def _pick(ops: Ops, index: Real, values: Real) -> Real:
    out = values[0]
    for i, v in enumerate(values[1:], start=1):
        out = ops.where(index == i, v, out)
    return out


def sample_sun_single_scatter_mixture(
    ops: Ops, medium: Real, o: Real, d: Real, D: Real, w: Real, E: Real, u: Real, u_layer: Real, channel: Real
) -> Real:
    """Sample a point on the fogged part of ``[0, D]`` for the sun's single scattering
    in *any* layered medium (bounded by a box or not, several layers, constant
    layers) and return ``(t, weights)``, ``weights[c] = f_c(t) / pdf(t)``.

    ``f_c(t) = alpha_c p(d.w) E_c sigma_c rho(t) exp(-sigma_c (tau(t) + tau_sun(t)))``
    is the exact integrand: camera optical depth and the sun's optical depth to the
    box's exit (or to infinity), both closed form.  Multiply the weights by the
    sun's geometric visibility at ``o + t d`` and each channel is unbiased.

    The proposal is a one-sample mixture over the layers and the three channels
    (balance heuristic): layer ``l`` alone, as if unbounded, has the integrand
    ``sigma rho_l exp(-m_l sigma tau_l)`` with ``m_l = 1 - d_y / w_y`` (exponential
    layers, sun above the horizon: the exact sampler of
    :func:`sample_sun_single_scatter`) or ``m_l = 1`` (constant layers: truncated
    free flight), sampled in closed form on the ray's segment inside the box.
    Layer ``l`` is picked with probability proportional to its grey mass
    ``X_l phi(m_l X_l)``.  One unbounded exponential layer needs no mixture: use
    :func:`sample_sun_single_scatter` (zero variance without shadows).
    ``u``, ``u_layer``: uniform variates; ``channel`` in {0, 1, 2}, uniform.
    """
    medium.require_height_only("the sun's mixture sampler")
    wy, w_ = float(w[1]), ops.params(w)
    sig, layers = medium.sigma_t, medium.layers
    sig_p, log_sig = ops.params(sig), ops.params([math.log(max(s, 1e-37)) for s in sig])
    t0, t1 = medium.clip(ops, o, d)
    seg = ops.maximum(ops.minimum(t1, D) - t0, 0.0)
    ok = seg > 0
    t0 = ops.where(ok, t0, 0.0)
    seg = ops.where(ok, seg, 0.0)
    oy, dy = o[1] + t0 * d[1], d[1]
    # m_l: the exact exponent for exponential layers (sun above the horizon); any other
    # profile (or a constant layer) gets m = 1, a truncated free flight: the proposal
    # stays a normalised closed form for any profile that inverts its optical depth.
    ms = [
        (1.0 - dy / w_[1]) if (wy > 0 and isinstance(L, ExpLayer) and L.falloff > 0) else 1.0 + 0.0 * dy
        for L in layers
    ]
    taus = [L.depth(ops, oy, dy, seg) for L in layers]
    s_mean = ops.param(sum(sig) / 3.0)
    mass = [s_mean * tl * phi(ops, m * s_mean * tl) for tl, m in zip(taus, ms)]
    total = sum(mass)
    # layer pick: cumulative masses
    pick = 0 * channel
    acc = 0.0
    for i in range(len(layers) - 1):
        acc = acc + mass[i]
        pick = ops.where(u_layer * total > acc, pick + 1, pick)
    c_l = [mi_ / ops.maximum(total, 1e-37) for mi_ in mass]
    s_ch = _pick(ops, channel, list(sig_p))
    m_sel, tau_sel = _pick(ops, pick, ms), _pick(ops, pick, taus)
    x = _invert_exp_integrand(ops, s_ch * tau_sel, m_sel, u)
    s_shape = x / ops.maximum(s_ch, 1e-30)
    t_rel = _pick(ops, pick, [L.sample(ops, oy, dy, s_shape) for L in layers])
    t_rel = ops.minimum(ops.maximum(t_rel, 0.0), seg)
    t = t0 + t_rel
    y = oy + t_rel * dy
    rho_l = [L.rho(ops, y) for L in layers]
    tau_l = [L.depth(ops, oy, dy, t_rel) for L in layers]
    # log of pdf_mix / rho (per unit length), log-sum-exp over layers x channels
    logs = []
    for rl, tl, tseg, m, c in zip(rho_l, tau_l, taus, ms, c_l):
        for s, log_s in zip(sig_p, log_sig):
            Xc = s * tseg
            logs.append(
                ops.log(ops.maximum(c * rl, 1e-37)) + log_s - m * s * tl - _log_x_phi(ops, Xc, m * Xc)
            )
    lmax = logs[0]
    for lg in logs[1:]:
        lmax = ops.maximum(lmax, lg)
    acc = 0.0
    for lg in logs:
        acc = acc + ops.exp(lg - lmax)
    log_pdf = lmax + ops.log(ops.maximum(acc / 3.0, 1e-37))
    rho = sum(rho_l)
    tau = medium._layers_depth(ops, oy, dy, t_rel)
    p = tuple(o[i] + t * d[i] for i in range(3))
    tau_sun = medium.sun_optical_depth(ops, p, w_)
    phase = medium.phase_value(ops, d[0] * w_[0] + d[1] * w_[1] + d[2] * w_[2])
    weights = []
    alb_e = [alb * e for alb, e in zip(medium.albedo, E)]
    for s, ae, s_p, log_s, ae_p in zip(sig, alb_e, sig_p, log_sig, ops.params(alb_e)):
        if s <= 0 or ae == 0:
            weights.append(0.0 * t)
            continue
        lw = log_s + ops.log(ops.maximum(rho, 1e-37)) - s_p * (tau + tau_sun) - log_pdf
        wc = ae_p * phase * ops.exp(ops.minimum(lw, ops.exp_limit))
        weights.append(ops.where(ok & (rho > 0) & (total > 0), wc, 0.0))
    return t, tuple(weights)


def sun_sampling_mode(medium: Real, w: Real, max_layers: int = 1, mixture: bool = True) -> Real:
    """How fogpath samples the sun's single scattering along camera rays (trace-time):
    ``"exact"`` (:func:`sample_sun_single_scatter`: unbounded exponential layers,
    at most ``max_layers``), ``"mixture"`` (:func:`sample_sun_single_scatter_mixture`:
    bounded fog, more layers, constant layers in a box) or None (NEE only; a Local Fog
    Volume, which neither sampler knows)."""
    if not medium.scatters or medium.volume is not None:
        return None
    if sun_sampling_applies(medium, w, max_layers):
        return "exact"
    if not mixture:
        return None
    if medium.bounds is None and (float(w[1]) <= 0 or any(L.is_constant for L in medium.layers)):
        return None  # unbounded: the sun is extinguished (zero single scattering)
    return "mixture"


def sun_sampling_applies(medium: Real, w: Real, max_layers: int = 1) -> bool:
    """Whether :func:`sample_sun_single_scatter` handles this medium and sun (trace-time).

    ``max_layers``: fogpath uses it for one layer only by default: with two
    layers the Newton inversion costs more time than the variance it removes
    (``reports/benchmarks/variance_reduction.md``).
    """
    return (
        medium.bounds is None
        and medium.volume is None
        and len(medium.layers) <= max_layers
        and all(isinstance(L, ExpLayer) and L.falloff > 0 for L in medium.layers)
        and float(w[1]) > 0
        and medium.scatters
    )


def hg_upper_fraction(g: float, mu0: Real) -> Real:
    """``H(mu0) = int_{w_y > 0} p_HG(w . d) dw`` with ``d_y = mu0``: the share of a
    Henyey–Greenstein lobe around ``d`` that lies above the horizon (numpy float64,
    adaptive quadrature over the lobe's polar angle; the azimuthal share is exact,
    ``arccos(-mu mu0 / (sqrt(1-mu^2) sqrt(1-mu0^2))) / pi``).  ``H(-mu0) = 1 - H(mu0)``.
    This is the uniform sky's single scattering per unit ``alpha L_sky (1 - T)``
    when everything below the horizon is dark (ground, or unbounded fog below).
    """
    from scipy import integrate

    g = float(g)

    def one(m0: Real) -> Real:
        s0 = math.sqrt(max(1.0 - m0 * m0, 0.0))

        def f(mu: Real) -> Real:
            pdf = (1 - g * g) / (2.0 * (1 + g * g - 2 * g * mu) ** 1.5)
            a, b = mu * m0, math.sqrt(max(1 - mu * mu, 0.0)) * s0
            if b <= abs(a):
                return pdf * (1.0 if a > 0 else 0.0)
            return pdf * math.acos(-a / b) / math.pi

        pts = sorted({-1.0, -s0, s0, 1.0})
        return sum(
            integrate.quad(f, lo, hi, epsabs=1e-13, epsrel=1e-12, limit=200)[0]
            for lo, hi in zip(pts[:-1], pts[1:])
            if hi > lo
        )

    mu0 = np.atleast_1d(np.asarray(mu0, dtype=np.float64))
    return np.array([one(float(m)) for m in mu0])


#: Degrees :func:`hg_upper_fraction_series` tries, lowest first.
UPPER_FRACTION_DEGREES = (15, 31, 63, 127, 255)


def hg_upper_fraction_series(g: float, tolerance: float = 1e-7) -> tuple[float, ...] | None:
    """``H(mu0)`` of :func:`hg_upper_fraction` as a polynomial: its Legendre coefficients
    ``c_0 .. c_n`` (evaluate with ``numpy.polynomial.legendre.legval(mu0, c)``), within
    ``tolerance`` of ``H`` on [-1, 1]; None when no degree ``n`` of :data:`UPPER_FRACTION_DEGREES`
    gets there (``|g|`` above about 0.945 at 1e-7).

    By the addition theorem, ``H(mu0) = sum_l (2l+1)/2 g^l P_l(mu0) int_0^1 P_l(x) dx``, and
    ``int_0^1 P_l = (P_{l-1}(0) - P_{l+1}(0)) / (2l+1)`` (0 for even ``l > 0``), so
    ``H(mu0) = 1/2 + sum_{odd l} g^l (P_{l-1}(0) - P_{l+1}(0)) / 2 P_l(mu0)``: the series truncated
    at degree ``n``.  Since ``|P_l| <= 1``, the sum of the left-out coefficients' magnitudes
    bounds the error; ``n`` is the lowest degree whose bound is at most ``tolerance``.  ``g`` in
    [-0.999, 0.999]; g = 0 is ``(0.5,)``.  About 1 ms.

    >>> c = hg_upper_fraction_series(0.6)
    >>> len(c) - 1, round(float(legendre.legval(0.3, c)), 7), round(float(hg_upper_fraction(0.6, 0.3)[0]), 7)
    (31, 0.6822318, 0.6822318)
    >>> hg_upper_fraction_series(0.0), hg_upper_fraction_series(0.99) is None
    ((0.5,), True)
    """
    g = float(g)
    if g == 0.0:
        return (0.5,)
    n_max = UPPER_FRACTION_DEGREES[-1]
    p0 = [1.0]  # P_0(0), P_2(0), ...: P_{2k}(0) = -(2k-1)/(2k) P_{2k-2}(0)
    for k in range(1, n_max // 2 + 2):
        p0.append(-p0[-1] * (2 * k - 1) / (2 * k))
    odd = np.arange(1, n_max + 1, 2)
    c = np.array([g ** int(l) * (p0[(l - 1) // 2] - p0[(l + 1) // 2]) / 2.0 for l in odd])
    # beyond n_max: |P_{2k}(0)| <= 1 / sqrt(pi k), so |c_l| <= |g|^l sqrt(2 / (pi (l - 1)))
    tail = abs(g) ** (n_max + 2) * math.sqrt(2.0 / (math.pi * (n_max + 1))) / (1.0 - g * g)
    for n in UPPER_FRACTION_DEGREES:
        if float(np.abs(c[odd > n]).sum()) + tail <= tolerance:
            full = np.zeros(n + 1)
            full[0], full[1::2] = 0.5, c[odd <= n]
            return tuple(float(v) for v in full)
    return None


#: Nodes of :func:`hg_upper_fraction_table`, uniform on [-1, 1].
UPPER_FRACTION_NODES = 8193


@functools.lru_cache(maxsize=16)
def hg_upper_fraction_table(g: float) -> tuple[float, ...] | None:
    """``H`` of :func:`hg_upper_fraction` at :data:`UPPER_FRACTION_NODES` heights uniform on
    [-1, 1] (:func:`hg_upper_fraction_series`' polynomial there), for linear interpolation
    (``ops.interp_uniform(mu0, -1.0, 1.0, table)``): within 5e-7 of ``H`` for ``|g| <= 0.94``
    (the interpolation's error is at most ``h^2 max|H''| / 8``, 4.2e-7 at ``g = 0.94``, plus the
    series' 1e-7; 7e-7 in float32), one table for every ``g`` where a kernel interpolates it.
    None where the series is.  A few milliseconds, kept for the last 16 values of ``g``.

    >>> t = hg_upper_fraction_table(0.6)
    >>> H = float(NP.interp_uniform(0.3, -1.0, 1.0, t))
    >>> len(t), abs(H - float(hg_upper_fraction(0.6, 0.3)[0])) < 5e-7
    (8193, True)
    """
    c = hg_upper_fraction_series(g)
    if c is None:
        return None
    return tuple(float(v) for v in legendre.legval(np.linspace(-1.0, 1.0, UPPER_FRACTION_NODES), c))


def _hg_mu(g: float, xi: Real) -> Real:
    """HG inverse CDF: ``mu``, the cosine of the angle to the lobe's axis, for ``xi`` in [0, 1]."""
    if abs(g) < 1e-4:
        return 2.0 * xi - 1.0
    s = (1.0 - g * g) / (1.0 - g + 2.0 * g * xi)
    return np.clip((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0)


def _hg_xi(g: float, mu: Real) -> Real:
    """The Henyey–Greenstein CDF in ``mu`` (the inverse of :func:`_hg_mu`), in [0, 1]."""
    if abs(g) < 1e-4:
        return (np.asarray(mu) + 1.0) / 2.0
    return np.clip(
        ((1.0 - g * g) / np.sqrt(1.0 + g * g - 2.0 * g * np.asarray(mu)) - (1.0 - g)) / (2.0 * g), 0, 1
    )


def sky_phase_projection(sky: Real, g: float, views: Real, n_xi: int = 48, n_phi: int = 96) -> Real:
    """``S(v) = int_{w_y > 0} L_sky(w) p_HG(w . v) dw``: a non-uniform sky projected onto the
    phase function, per view direction ``v`` (numpy float64, any sky radiance unit).

    ``sky``: callable, ``(N, 3)`` unit directions toward the sky -> ``(N, 3)`` RGB radiance
    (e.g. :func:`fogref.media.sky.sky_radiance`; called once per batch of views); it is only
    asked about directions above the horizon (``w_y > 0``: below it the ground or unbounded fog are dark).
    ``views``: ``(V, 3)`` unit view directions (away from the camera).  Returns ``(V, 3)``.

    Quadrature in the lobe's own frame: the HG inverse CDF maps ``xi`` in [0, 1] to the angle
    from ``v`` (so ``p dw = dxi dphi / 2 pi``, exact for any ``g`` in (-1, 1)), and for each
    azimuth the horizon cuts ``xi`` to one interval, found in closed form, on which
    Gauss–Legendre (``n_xi`` nodes) integrates a smooth sky; ``n_phi`` midpoint azimuths.
    For a uniform sky ``S = L H(v_y)`` (:func:`hg_upper_fraction`), to 1e-9 with the defaults
    (``tests/test_sunsky.py``), and the sky's single scattering is then
    ``alpha S(v) (1 - T(D))`` (:func:`single_scatter_sky_projected`).
    """
    V = np.atleast_2d(np.asarray(views, dtype=np.float64))
    V = V / np.linalg.norm(V, axis=1, keepdims=True)
    x, wx = np.polynomial.legendre.leggauss(int(n_xi))
    azimuths = (np.arange(int(n_phi)) + 0.5) * (2.0 * np.pi / int(n_phi))
    out = np.zeros((len(V), 3))
    chunk = max(1, 65536 // (len(azimuths) * len(x)))  # views per call of ``sky`` (one batch each)
    for k0 in range(0, len(V), chunk):
        ws, wts = [], []
        for v in V[k0 : k0 + chunk]:
            helper = np.array([1.0, 0.0, 0.0]) if abs(v[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
            t1 = np.cross(v, helper)
            t1 /= np.linalg.norm(t1)
            t2 = np.cross(v, t1)
            A = v[1]
            B = np.cos(azimuths) * t1[1] + np.sin(azimuths) * t2[1]  # w_y = mu A + sin(theta) B
            delta = np.arctan2(B, A)
            delta = np.where(delta < -np.pi / 2, delta + 2.0 * np.pi, delta)  # the interval meeting [0, pi]
            th_lo, th_hi = np.maximum(0.0, delta - np.pi / 2), np.minimum(np.pi, delta + np.pi / 2)
            ok = th_hi > th_lo
            xi_a, xi_b = _hg_xi(g, np.cos(th_hi)), _hg_xi(g, np.cos(th_lo))  # mu = cos(theta) falls
            xi = (xi_a[:, None] + xi_b[:, None]) / 2 + (xi_b - xi_a)[:, None] / 2 * x[None]
            mu = _hg_mu(g, xi)
            s = np.sqrt(np.maximum(1.0 - mu * mu, 0.0))
            cp, sp = np.cos(azimuths)[:, None], np.sin(azimuths)[:, None]
            w = mu[..., None] * v + s[..., None] * (cp[..., None] * t1 + sp[..., None] * t2)
            w[..., 1] = np.maximum(w[..., 1], 1e-9)
            w /= np.linalg.norm(w, axis=-1, keepdims=True)
            ws.append(w.reshape(-1, 3))
            wts.append(np.where(ok, (xi_b - xi_a) / 2, 0.0)[:, None] * wx[None])
        L_all = np.asarray(sky(np.concatenate(ws)), dtype=np.float64).reshape(
            len(ws), len(azimuths), len(x), 3
        )
        for j, wt in enumerate(wts):
            out[k0 + j] = (L_all[j] * wt[..., None]).sum((0, 1)) / len(azimuths)
    return out


def single_scatter_sky_projected(
    ops: Ops, medium: Real, o: Real, d: Real, D: Real, S: Real, tau: Real = None
) -> Real:
    """Single-scattered non-uniform sky along ``[0, D]``: ``alpha S(d) (1 - T(D))`` per channel.

    ``S``: RGB :func:`sky_phase_projection` for the view ``d`` (a 3-tuple of floats or arrays).
    Same approximation as :func:`single_scatter_sky`: the sky's light is neither occluded nor
    attenuated on its way to the ray (exact in the limit of thin fog: its relative error is at
    most the largest optical depth from the ray to the sky, ``sigma_t tau_in``).  ``tau``: as in
    :func:`single_scatter_sky`."""
    if tau is None:
        tau = medium.optical_depth(ops, o, d, D)
    sigs, albs = ops.params(medium.sigma_t), ops.params(medium.albedo)
    opacity = _opacities(ops, sigs, first_equal(medium.sigma_t), tau)
    return tuple(alb * S_c * op for alb, S_c, op in zip(albs, S, opacity))


def sun_disk_directions(w: Real, angular_diameter_deg: float, n_r: int = 4, n_phi: int = 8) -> Real:
    """Quadrature over a uniform sun disk: ``(directions (K, 3), weights (K,))``, the weights
    summing to 1 (the disk's mean), directions within ``angular_diameter_deg / 2`` of ``w``.
    Gauss–Legendre in ``cos`` of the angle to ``w`` times ``n_phi`` azimuths (exact for the
    uniform-cone measure that fogpath samples in next-event estimation).  Diameter 0: ``w``
    itself with weight 1 (the delta sun)."""
    w = np.asarray(w, dtype=np.float64)
    w = w / np.linalg.norm(w)
    if float(angular_diameter_deg) <= 0.0:
        return w[None], np.ones(1)
    c_max = math.cos(math.radians(float(angular_diameter_deg)) / 2.0)
    x, wx = np.polynomial.legendre.leggauss(int(n_r))
    c = (1.0 + c_max) / 2.0 + (1.0 - c_max) / 2.0 * x
    azimuths = (np.arange(int(n_phi)) + 0.5) * (2.0 * np.pi / int(n_phi))
    helper = np.array([1.0, 0.0, 0.0]) if abs(w[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    t1 = np.cross(w, helper)
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(w, t1)
    C, P = np.meshgrid(c, azimuths, indexing="ij")
    S = np.sqrt(np.maximum(1.0 - C * C, 0.0))
    dirs = C[..., None] * w + S[..., None] * (np.cos(P)[..., None] * t1 + np.sin(P)[..., None] * t2)
    wts = np.repeat(wx / 2.0, len(azimuths)) / len(azimuths)
    return dirs.reshape(-1, 3), wts


def single_scatter_sun_disk(
    medium: Real,
    o: Real,
    d: Real,
    D: Real,
    w: Real,
    E: Real,
    angular_diameter_deg: float,
    n_r: int = 4,
    n_phi: int = 8,
) -> Real:
    """:func:`single_scatter_sun` for a uniform sun disk of ``angular_diameter_deg`` [deg] and
    total irradiance ``E`` (radiance ``E / Omega``, ``Omega = 2 pi (1 - cos(diameter / 2))``):
    the closed form averaged over the disk by :func:`sun_disk_directions` (numpy).

    The delta sun (diameter 0) differs from it by the disk's second moment of the integrand:
    relative error ``~ (theta_s^2 / 4) |p''/p|`` with ``theta_s`` the disk's angular radius.
    At 0.53 deg, looking into the sun: 1.2e-4 at ``g = 0.6``, 1.5e-3 at 0.9, 6e-3 at 0.95 and
    14 % at 0.99; 30 deg away from the sun below 1e-4 for every ``g`` (``tests/test_sunsky.py``).
    The sun's optical depth changes by ``O(theta_s^2)`` relative over the disk (kept by the
    average here).
    """
    dirs, wts = sun_disk_directions(w, angular_diameter_deg, n_r, n_phi)
    total = np.zeros(3)
    for wi, wt in zip(dirs, wts):
        if wi[1] <= 0:
            continue
        L = single_scatter_sun(NP, medium, o, d, D, tuple(float(x) for x in wi), E)
        total += wt * np.array([float(np.asarray(c).reshape(-1)[0]) for c in L])
    return total
