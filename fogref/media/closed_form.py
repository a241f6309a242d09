"""Closed forms for exponential fog, written once for numpy and Dr.Jit.

Conventions (all of ``fogref.media``): world space is **y-up, metres**.  A ray is
``p(t) = o + t d`` with ``|d| = 1``.  One exponential layer has relative density
``rho(y) = exp(-b (y - h))``; along a ray this is ``c exp(-k t)`` with
``log_c = -b (o_y - h)`` and ``k = b d_y``.  "Shape" optical depth is the integral
of the relative density (metres); multiply by the extinction ``sigma_t`` [1/m] to
get the optical depth of a colour channel.

Every function takes an array back end ``ops`` (:mod:`fogref.media.ops`) first.
Optical depths saturate at :data:`TAU_MAX` (where the transmittance is exactly 0
in any float format) so that no Inf leaves; "infinite distance" is written as
``ops.largest``.
"""

from __future__ import annotations

from fogref.media.ops import Ops, Real

#: optical depths are clamped here; exp(-TAU_MAX) == 0 in float32 and float64.
TAU_MAX = 1.0e30


def exp_times(ops: Ops, log_a: Real, m: Real) -> Real:
    """``exp(log_a) * m`` for ``m >= 0`` without spurious underflow or overflow.

    When ``|log_a| <= ops.exp_limit`` this is the plain product; otherwise it is
    evaluated as ``exp(log_a + log m)`` so that, e.g., a tiny density times a long
    distance stays accurate instead of going through a subnormal.  The result
    is clamped to ``ops.largest``; ``m == 0`` gives 0.
    """
    lim = ops.exp_limit
    direct = ops.exp(ops.minimum(ops.maximum(log_a, -lim), lim)) * m
    lm = ops.log(ops.maximum(m, ops.tiny))
    via_log = ops.exp(ops.minimum(ops.maximum(log_a + lm, -2.0 * lim), ops.log_largest))
    out = ops.where(ops.abs(log_a) <= lim, direct, via_log)
    out = ops.minimum(out, ops.largest)
    return ops.where(m > 0, out, 0.0)


def phi(ops: Ops, x: Real) -> Real:
    """``phi(x) = (1 - exp(-x)) / x`` with ``phi(0) = 1``; stable for all finite x.

    For ``x -> +inf`` it tends to ``1/x``; for very negative x (where the true
    value overflows) it saturates at ``ops.largest`` instead of Inf.
    Accuracy: see the table in ``tests/test_media_stress.py`` (relative error
    <= 4e-16 (float64), 3e-7 (float32) for |x| <= exp_limit; for x < -exp_limit
    the log form exp(-x - log(-x)) adds eps*|x|).
    """
    x = ops.minimum(x, ops.largest)
    xc = ops.maximum(x, -ops.exp_limit)
    r = -ops.expm1(-xc) / ops.where(xc == 0, 1.0, xc)
    r = ops.where(xc == 0, 1.0, r)
    # x < -exp_limit: exp(-x) / (-x) in log form (saturates at largest)
    xn = ops.minimum(x, -1.0)
    r_neg = ops.exp(ops.minimum(-xn - ops.log(-xn), ops.log_largest))
    r = ops.where(x < -ops.exp_limit, r_neg, r)
    return ops.minimum(r, ops.largest)


def psi(ops: Ops, z: Real) -> Real:
    """``psi(z) = -log(1 - z) / z`` for ``z < 1`` with ``psi(0) = 1``.

    ``z >= 1`` (no finite answer) gives ``ops.largest``.
    Accuracy: relative error <= 4e-16 (float64), 4e-7 (float32) for z <= 1 - 1e-3;
    near z = 1 the condition number is 1/((1-z)|log(1-z)|).
    """
    zc = ops.minimum(z, 0.5)
    r = -ops.log1p(-zc) / ops.where(zc == 0, 1.0, zc)
    r = ops.where(zc == 0, 1.0, r)
    # 0.5 < z < 1: direct; the log1p argument is exact there (Sterbenz)
    zb = ops.minimum(ops.maximum(z, 0.5), 1.0)
    rb = -ops.log(ops.maximum(1.0 - zb, ops.tiny)) / zb
    r = ops.where(z > 0.5, rb, r)
    r = ops.where(z >= 1.0, ops.largest, r)
    return ops.minimum(r, ops.largest)


def exp_layer_optical_depth(ops: Ops, log_c: Real, k: Real, t: Real) -> Real:
    """Shape optical depth ``int_0^t exp(log_c - k s) ds`` of one layer [m].

    ``t`` may be ``ops.largest`` (to infinity).  Saturates at TAU_MAX; ``t <= 0``
    gives 0.  Relative error (against mpmath, over the stress domain of
    ``tests/test_media_stress.py``, where the true value lies in
    [smallest normal, TAU_MAX])::

        err <= 8 eps (2 + |log_c| + |k t|)     eps = 1.1e-16 (float64), 6e-8 (float32)

    i.e. a few ulp when the exponents are O(1); the ``|log_c| + |k t|`` term is
    the condition number of exp() and already present when the inputs are rounded.
    Measured worst case on the grid of ``benchmarks/stress_map.py``: 5.0e-15
    (float64), 1.2e-6 (float32), both at falloff 0.1, oy = 1000, dy = -0.3,
    t = 1000 (|log_c| = 100, |k t| = 30); sun depth (t = infinity, k > 0):
    3.7e-16 (float64), 1.3e-7 (float32).  A ray to infinity with ``k <= 0``
    gives TAU_MAX when ``log_c > -1e4`` (c > 0), else 0.
    """
    big = 1.0e30
    log_c = ops.minimum(ops.maximum(log_c, -big), big)
    x = k * t
    xa = ops.maximum(x, -1.0)
    # x >= -1: c t phi(x)
    m_a = ops.minimum(t * phi(ops, xa), ops.largest)
    tau_a = exp_times(ops, log_c, m_a)
    # to infinity upwards: c / k
    up_inf = (t >= ops.largest) & (k > 0)
    inv_k = ops.minimum(1.0 / ops.where(k > 0, k, 1.0), ops.largest)
    tau_a = ops.where(up_inf, exp_times(ops, log_c, inv_k), tau_a)
    # x < -1 (density grows along the ray): exp(log_c - x) (1 - e^x) / |k|
    abs_k = ops.where(k < 0, -k, 1.0)
    xb = ops.minimum(ops.maximum(x, -ops.largest), -1.0)
    m_b = ops.minimum(-ops.expm1(xb) / abs_k, ops.largest)
    tau_b = exp_times(ops, log_c - xb, m_b)
    tau = ops.where(x < -1.0, tau_b, tau_a)
    # to infinity level or downwards: infinite for any c > 0 (log_c <= -1e4 means c = 0)
    tau = ops.where((t >= ops.largest) & (k <= 0) & (log_c > -1.0e4), TAU_MAX, tau)
    tau = ops.where(t > 0, tau, 0.0)
    return ops.minimum(tau, TAU_MAX)


def exp_layer_sample(ops: Ops, log_c: Real, k: Real, s: Real) -> Real:
    """Distance ``t`` at which the layer's shape optical depth reaches ``s`` >= 0.

    Exact inversion of :func:`exp_layer_optical_depth`.  Returns ``ops.largest``
    when the ray escapes first (``k > 0`` and ``s >= c / k``, or ``s / c``
    beyond the float range).  Relative error (stress domain)::

        err <= 8 eps (2 + |log_c| + |log s|) * cond,   cond = 1 + 1/((1-z)|log(1-z)|)

    with ``z = k s / c`` (cond is the inherent condition number near escape, z -> 1).
    Measured worst case (stress_map grid): 8.1e-15 (float64, falloff 0.1,
    oy = 1000, dy = 1, s = 1.9e-43), 2.1e-6 (float32, falloff 0.1, oy = 1000,
    dy = 1e-7, s = 1.9e-36).  ``s`` below the smallest normal is treated as it.
    """
    big = 1.0e30
    log_c = ops.minimum(ops.maximum(log_c, -big), big)
    s_pos = ops.maximum(s, ops.tiny)
    lr = ops.log(s_pos) - log_c  # log(s / c)
    r = exp_times(ops, -log_c, s_pos)  # s / c (clamped at largest)
    abs_k = ops.abs(k)
    lz = ops.log(ops.maximum(abs_k, ops.tiny)) + lr  # log|z|
    kz = k != 0
    r_ok = lr < ops.log_largest - 1.0
    z_direct = k * ops.where(r_ok, r, 0.0)
    sign_k = ops.where(k < 0, -1.0, 1.0)
    z_log = sign_k * ops.exp(ops.minimum(lz, 0.0))
    small = ops.where(r_ok, ops.abs(z_direct) <= 1.0, lz <= 0.0) | ~kz
    z = ops.where(r_ok, z_direct, z_log)
    z_s = ops.where(small & kz, ops.minimum(ops.maximum(z, -1.0), 1.0), 0.0)
    t_small = ops.minimum(r * psi(ops, z_s), ops.largest)
    # |z| > 1 and k < 0 (descending into thicker fog): log(1 + |z|) / |k|
    inv_abs_k = 1.0 / ops.where(kz, abs_k, 1.0)
    abs_z = ops.minimum(ops.abs(z), ops.largest)
    lz_pos = ops.maximum(lz, 0.0)
    log1p_z = ops.where(r_ok & (abs_z < ops.largest), ops.log1p(abs_z), lz_pos + ops.log1p(ops.exp(-lz_pos)))
    t_big = ops.minimum(log1p_z * inv_abs_k, ops.largest)
    t = ops.where(small, t_small, t_big)
    escape_up = (k > 0) & ops.where(r_ok, z >= 1.0, lz >= 0.0)
    escape = escape_up | (t >= ops.largest) | ~ops.isfinite(t)
    t = ops.where(escape, ops.largest, t)
    return ops.where(s > 0, t, 0.0)


def hg_phase(ops: Ops, cos_theta: Real, g: Real) -> Real:
    """Henyey–Greenstein phase function [1/sr].

    ``cos_theta = dot(d, w)``, where ``d`` is the camera ray's direction (away
    from the camera) and ``w`` points toward the light, so ``g > 0`` (forward
    scattering) peaks when looking into the sun.  Same convention as Mitsuba's
    ``hg`` plugin evaluated with ``wi = -d``, ``wo = w``.
    """
    # ``g`` (a Python number) enters as three opaque constants formed in float64:
    # ``1 - g^2`` in float32 would cancel for |g| near 1.
    one_p_g2, two_g = ops.param(1.0 + g * g), ops.param(2.0 * g)
    numerator = ops.param((1.0 - g * g) / (4.0 * 3.141592653589793))
    denom = one_p_g2 - two_g * cos_theta
    return numerator / (denom * ops.sqrt(denom))
