"""Closed-form single scattering along an unoccluded camera ray.

This is exactly the term that Unreal's cosine-lobe directional inscattering
approximates: sunlight scattered once toward the camera, attenuated on the way in
and on the way out, with the true phase function.

For exponential layers sharing one albedo, along ``p(t) = o + t d`` and toward the
sun ``w`` (unit, ``w_y > 0``)::

    tau_sun(p(t)) = tau_sun(o) - (d_y / w_y) tau(t)          (every layer)
    L_ss = alpha p(d.w) E T_sun(o) int_0^D sigma e^{-m tau} dt,   m = 1 - d_y / w_y
         = alpha p(d.w) E T_sun(o) tau(D) phi(m tau(D))

which is stable everywhere through ``phi`` (see DESIGN.md).
"""

from __future__ import annotations

from fogref.errors import ParameterError
from fogref.media import closed_form as cf


def single_scatter_sun(ops, medium, o, d, D, w, E):
    """Single-scattered sun radiance along ``[0, D]`` of ``o + t d`` (RGB tuple).

    medium: :class:`~fogref.media.FogMedium` without bounds.
    o, d:   camera position [m] and unit view direction (away from the camera).
    D:      distance to the first surface [m] (``ops.largest`` for the sky).
    w:      unit direction toward the sun (a 3-tuple of floats).
    E:      RGB sun irradiance on a plane facing the sun [W/m^2 or any unit].

    Returns radiance in E's unit per steradian, no occlusion, no sky.  Zero when
    the sun is at or below the horizon (``w_y <= 0``) or a layer is homogeneous
    and unbounded (the sun is then fully extinguished).
    """
    if medium.bounds is not None:
        raise ParameterError(medium.source, "bounds", "closed-form single scattering needs an unbounded medium")
    wy = float(w[1])
    if wy <= 0 or any(getattr(L, "falloff", 1.0) == 0 for L in medium.layers):
        zero = 0.0 * d[0]
        return (zero, zero, zero)
    cos_theta = d[0] * w[0] + d[1] * w[1] + d[2] * w[2]
    phase = cf.hg_phase(ops, cos_theta, medium.g)
    tau = medium.optical_depth(ops, o, d, D)
    tau_sun_o = medium.sun_optical_depth(ops, o, w)
    m = 1.0 - d[1] / wy
    tau_sun_end = medium.sun_optical_depth(ops, tuple(o[i] + D * d[i] for i in range(3)), w)
    out = []
    for sig, alb, e in zip(medium.sigma_t, medium.albedo, E):
        tc = sig * tau
        # m >= 0: T_sun(o) * tc * phi(m tc), all factors bounded.
        pos = ops.exp(-sig * tau_sun_o) * ops.minimum(tc * cf.phi(ops, ops.maximum(m, 0.0) * tc), ops.largest)
        # m < 0 (looking up more steeply than the sun): fold both exponentials,
        # exp(-sig (tau_sun(D) + tau)) (1 - exp(m tc)) / (-m), whose exponent is <= 0.
        neg_m = ops.where(m < 0, -m, 1.0)
        neg = ops.exp(-sig * (tau_sun_end + tau)) * (-ops.expm1(-neg_m * tc)) / neg_m
        integral = ops.where(m < 0, neg, pos)
        out.append(alb * e * phase * integral)
    return tuple(out)


def single_scatter_sky(ops, medium, o, d, D, L_sky):
    """Single-scattered uniform sky, unoccluded and unattenuated: alpha L (1 - T(D))."""
    tau = medium.optical_depth(ops, o, d, D)
    return tuple(alb * L * -ops.expm1(-sig * tau) for sig, alb, L in zip(medium.sigma_t, medium.albedo, L_sky))
