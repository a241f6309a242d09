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

#: optical depths are clamped here; exp(-TAU_MAX) == 0 in float32 and float64.
TAU_MAX = 1.0e30


def phi(ops, x):
    """``phi(x) = (1 - exp(-x)) / x`` with ``phi(0) = 1``; stable for all finite x.

    For ``x -> +inf`` it tends to ``1/x``; for very negative x it overflows to
    ``ops.largest`` instead of Inf.
    """
    x = ops.minimum(ops.maximum(x, -ops.exp_limit), ops.largest)
    r = -ops.expm1(-x) / ops.where(x == 0, 1.0, x)
    return ops.minimum(ops.where(x == 0, 1.0, r), ops.largest)


def psi(ops, z):
    """``psi(z) = -log(1 - z) / z`` for ``z < 1`` with ``psi(0) = 1``."""
    r = -ops.log1p(-z) / ops.where(z == 0, 1.0, z)
    return ops.where(z == 0, 1.0, r)


def exp_layer_optical_depth(ops, log_c, k, t):
    """Shape optical depth ``int_0^t exp(log_c - k s) ds`` of one layer [m].

    ``t`` may be ``ops.largest`` (to infinity).  Saturates at TAU_MAX.
    """
    lim = ops.exp_limit
    x = k * t
    # x >= -1: c t phi(x); the rising-density case uses the log form below.
    c = ops.exp(ops.minimum(log_c, lim))
    tau_a = c * t * phi(ops, ops.maximum(x, -1.0))
    # to infinity upwards: c / k
    up_inf = (t >= ops.largest) & (k > 0)
    tau_a = ops.where(up_inf, c / ops.where(k > 0, k, 1.0), tau_a)
    # x < -1 (density grows along the ray): exp(log_c - x) (1 - e^x) / |k|
    abs_k = ops.where(k < 0, -k, 1.0)
    tau_b = ops.exp(ops.minimum(log_c - x, lim)) * (-ops.expm1(ops.minimum(x, 0.0))) / abs_k
    tau = ops.where(x < -1.0, tau_b, tau_a)
    tau = ops.where(t > 0, tau, 0.0)
    return ops.minimum(tau, TAU_MAX)


def exp_layer_sample(ops, log_c, k, s):
    """Distance ``t`` at which the layer's shape optical depth reaches ``s`` >= 0.

    Exact inversion of :func:`exp_layer_optical_depth`.  Returns ``ops.largest``
    when the ray escapes first (``k > 0`` and ``s >= c / k``).
    """
    lim = ops.exp_limit
    inv_c = ops.exp(ops.minimum(-log_c, lim))
    z = k * s * inv_c
    small = ops.abs(z) <= 1.0
    z_s = ops.where(small, z, 0.0)
    t_small = s * inv_c * psi(ops, ops.minimum(z_s, 0.9999999))
    t_small = ops.where(z_s >= 0.9999999, -ops.log1p(-z_s) / ops.where(k > 0, k, 1.0), t_small)
    # z < -1 (descending into thicker fog): log1p(|z|)/|k| in log form
    abs_k = ops.where(k < 0, -k, 1.0)
    lz = ops.log(ops.maximum(abs_k * s, 1e-300 if ops.exp_limit > 100 else 1e-37)) - log_c
    t_big = (lz + ops.log1p(ops.exp(-ops.maximum(lz, 0.0)))) / abs_k
    t = ops.where(small, t_small, t_big)
    escape = (z >= 1.0) | (t >= ops.largest) | ~ops.isfinite(t)
    t = ops.where(escape, ops.largest, t)
    return ops.where(s > 0, t, 0.0)


def hg_phase(ops, cos_theta, g):
    """Henyey–Greenstein phase function [1/sr].

    ``cos_theta = dot(d, w)``, where ``d`` is the camera ray's direction (away
    from the camera) and ``w`` points toward the light, so ``g > 0`` (forward
    scattering) peaks when looking into the sun.  Same convention as Mitsuba's
    ``hg`` plugin evaluated with ``wi = -d``, ``wo = w``.
    """
    denom = 1.0 + g * g - 2.0 * g * cos_theta
    return (1.0 - g * g) / (4.0 * 3.141592653589793 * denom * ops.sqrt(denom))
