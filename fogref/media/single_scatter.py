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
"""

from __future__ import annotations

from fogref.errors import ParameterError
from fogref.media import closed_form as cf
from fogref.media.closed_form import phi, psi


def single_scatter_sun(ops, medium, o, d, D, w, E, tau=None):
    """Single-scattered sun radiance along ``[0, D]`` of ``o + t d`` (RGB tuple).

    medium: :class:`~fogref.media.FogMedium` without bounds.
    o, d:   camera position [m] and unit view direction (away from the camera).
    D:      distance to the first surface [m] (``ops.largest`` for the sky).
    w:      unit direction toward the sun (a 3-tuple of floats).
    E:      RGB sun irradiance on a plane facing the sun [W/m^2 or any unit].
    tau:    optional shape optical depth over ``[0, D]`` when the caller has it
            (saves recomputing it; default: computed here).

    Returns radiance in E's unit per steradian, no occlusion, no sky.  Zero when
    the sun is at or below the horizon (``w_y <= 0``) or a layer is homogeneous
    and unbounded (the sun is then fully extinguished).

    Examples
    --------
    >>> from fogref.media import NP, ExpLayer, FogMedium
    >>> fog = FogMedium(sigma_t=0.01, albedo=1.0, layers=(ExpLayer(1.0, 0.05, 0.0),))
    >>> L = single_scatter_sun(NP, fog, (0.0, 1.0, 0.0), (1.0, 0.0, 0.0), 100.0, (0.0, 1.0, 0.0), (1.0, 1.0, 1.0))
    >>> round(float(L[0]), 4)   # (1 - T) p T_sun = 0.61 * 1/(4 pi) * 0.83
    0.0404
    """
    if medium.bounds is not None:
        raise ParameterError(medium.source, "bounds", "closed-form single scattering needs an unbounded medium")
    wy = float(w[1])
    if wy <= 0 or any(L.is_constant for L in medium.layers):
        zero = 0.0 * d[0]
        return (zero, zero, zero)
    cos_theta = d[0] * w[0] + d[1] * w[1] + d[2] * w[2]
    phase = cf.hg_phase(ops, cos_theta, medium.g)
    if tau is None:
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


def _log_x_phi(ops, X, mX):
    """log(X * phi(m X)) for X > 0, stable for any sign and size of m X."""
    big_neg = mX < -20.0
    z = ops.where(big_neg, -1.0, mX)
    direct = ops.log(ops.maximum(X, 1e-37)) + ops.log(phi(ops, z))
    zneg = ops.minimum(mX, -20.0)
    via = ops.log(ops.maximum(X, 1e-37)) - zneg - ops.log(-zneg)
    return ops.where(big_neg, via, direct)


def sample_sun_single_scatter(ops, medium, o, d, D, w, E, u, channel):
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
    wy = float(w[1])
    m = 1.0 - d[1] / wy
    tau_D = medium.optical_depth(ops, o, d, D)
    sig = medium.sigma_t
    s_ch = ops.where(channel == 1, sig[1], ops.where(channel == 2, sig[2], sig[0]))
    X = s_ch * tau_D
    mX = m * X
    # m >= -eps: Y psi(mY); strongly rising (m X < -20): log form, no overflow.
    Y = u * X * phi(ops, ops.maximum(mX, -20.0))
    x_pos = Y * psi(ops, ops.minimum(m * Y, 0.999999))
    abs_m = ops.where(m < 0, -m, 1.0)
    x_neg = X + ops.log(ops.maximum(u + (1.0 - u) * ops.exp(-abs_m * X), 1e-37)) / abs_m
    x = ops.where(mX < -20.0, x_neg, x_pos)
    x = ops.minimum(ops.maximum(x, 0.0), X)
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
    weights = tuple(ops.where((mean_r > 0) & (tau_D > 0), cf_c * rc / mean_r, 0.0) for cf_c, rc in zip(closed, r))
    return t, weights


def sun_sampling_applies(medium, w, max_layers: int = 1) -> bool:
    """Whether :func:`sample_sun_single_scatter` handles this medium and sun (trace-time).

    ``max_layers``: fogpath uses it for one layer only by default: with two
    layers the Newton inversion costs more time than the variance it removes
    (``reports/benchmarks/variance_reduction.md``: 0.84x at equal error on the
    two-layer scene, 4.4x on the one-layer valley).
    """
    from fogref.media.medium import ExpLayer

    return (medium.bounds is None and len(medium.layers) <= max_layers
            and all(isinstance(L, ExpLayer) and L.falloff > 0 for L in medium.layers)
            and float(w[1]) > 0 and medium.scatters)
