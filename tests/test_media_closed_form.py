"""Closed forms of fogref.media against independent references.

References: mpmath quadrature (``mp.quad`` with breakpoints at the profile's
boundaries, 30 digits) for optical depth and single scattering; the inverse
property ``depth(sample(s)) == s``; a Kolmogorov–Smirnov test (alpha = 1e-3,
fixed seed) of the exact free-flight sampler including the escape probability.
"""

from __future__ import annotations

import math

import mpmath as mp
import numpy as np
import pytest
from scipy import stats

from fogref.errors import ParameterError
from fogref.media import NP, Box, ExpLayer, FogMedium, HDRPLayer, PowerLawLayer, single_scatter_sun
from fogref.media.closed_form import hg_phase

mp.mp.dps = 30


# ---------------------------------------------------------------- references
def mp_rho(layer, y):
    """Relative density of one component at height y (mpmath)."""
    y = mp.mpf(y)
    if isinstance(layer, ExpLayer):
        return mp.mpf(layer.density) * mp.exp(-mp.mpf(layer.falloff) * (y - layer.height))
    if isinstance(layer, HDRPLayer):
        h = max(y - layer.base_height, 0)
        return mp.mpf(layer.density) * mp.exp(-mp.mpf(layer.falloff) * h)
    if isinstance(layer, PowerLawLayer):
        if y <= layer.start:
            return mp.mpf(layer.density)
        if y >= layer.end:
            return mp.mpf(0)
        u = (mp.mpf(layer.end) - y) / (mp.mpf(layer.end) - layer.start)
        return mp.mpf(layer.density) * u ** mp.mpf(layer.power)
    raise TypeError(layer)


def breaks(layer):
    if isinstance(layer, HDRPLayer):
        return [layer.base_height]
    if isinstance(layer, PowerLawLayer):
        return [layer.start, layer.end]
    return []


def mp_depth_quad(layers, oy, dy, t, t0=0.0):
    """int_{t0}^{t} sum rho(oy + s dy) ds by mp.quad with breakpoints."""
    oy, dy = mp.mpf(oy), mp.mpf(dy)
    pts = {mp.mpf(t0), mp.mpf(t)}
    for L in layers:
        for yb in breaks(L):
            if dy != 0:
                sb = (yb - oy) / dy
                if t0 < sb < t:
                    pts.add(sb)
    pts = sorted(pts)
    return mp.quad(lambda s: sum(mp_rho(L, oy + s * dy) for L in layers), pts)


# ---------------------------------------------------------------- helpers
def a1(x):
    return np.asarray(x, dtype=np.float64)


def rel(a, b):
    b = float(b)
    return abs(float(a) - b) / abs(b) if b != 0 else abs(float(a))


PROFILES = [
    ExpLayer(1.0, 0.05, 0.0),
    ExpLayer(0.3, 0.002, 50.0),
    ExpLayer(2.0, 0.0, 0.0),
    HDRPLayer(2.0, 10.0, 0.05),
    HDRPLayer(0.5, -20.0, 0.0),
    PowerLawLayer(1.5, 0.0, 100.0, 2.3),
    PowerLawLayer(1.0, -10.0, 40.0, 0.0),
    PowerLawLayer(0.7, 5.0, 300.0, 1.0),
]

RAYS = [  # oy, dy, t
    (-5.0, 1.0, 100.0),
    (50.0, -1.0, 200.0),
    (150.0, -0.5, 400.0),
    (50.0, 0.0, 40.0),
    (5.0, 0.3, 150.0),
    (5.0, 1e-7, 1e5),
    (60.0, -1e-7, 3e4),
    (10.0, 0.7, 20.0),
    (0.0, 1.0, 120.0),
    (100.0, -1.0, 120.0),
    (-20.0, 0.0, 10.0),
    (300.0, -0.9, 700.0),
    (45.0, -0.05, 800.0),
    (250.0, 0.02, 500.0),
]


@pytest.mark.parametrize("layer", PROFILES, ids=repr)
def test_component_depth_vs_quadrature(layer):
    for oy, dy, t in RAYS:
        got = layer.depth(NP, a1(oy), a1(dy), a1(t))
        ref = mp_depth_quad([layer], oy, dy, t)
        assert rel(got, ref) <= 1e-12, (layer, oy, dy, t, float(got), float(ref))


@pytest.mark.parametrize(
    "layers",
    [
        (ExpLayer(1.0, 0.05, 0.0),),
        (ExpLayer(1.0, 0.05, 0.0), ExpLayer(0.2, 0.004, 30.0)),
        (HDRPLayer(1.0, 10.0, 0.02), PowerLawLayer(0.5, 0.0, 80.0, 1.7)),
    ],
    ids=["exp1", "exp2", "hdrp+power"],
)
def test_medium_depth_vs_quadrature(layers):
    med = FogMedium(sigma_t=0.02, layers=layers)
    for oy, dy, t in RAYS:
        dx = math.sqrt(max(1 - dy * dy, 0.0))
        got = med.optical_depth(NP, (a1(0.0), a1(oy), a1(0.0)), (a1(dx), a1(dy), a1(0.0)), a1(t))
        ref = mp_depth_quad(layers, oy, dy, t)
        assert rel(got, ref) <= 1e-12, (oy, dy, t)


def test_depth_to_infinity():
    L = ExpLayer(1.0, 0.05, 0.0)
    assert rel(L.depth(NP, a1(10.0), a1(0.5), a1(NP.largest)), math.exp(-0.5) / 0.025) <= 1e-15
    H = HDRPLayer(2.0, 10.0, 0.05)
    # from y=0 up at dy=1: 2*10 + 2/0.05
    assert rel(H.depth(NP, a1(0.0), a1(1.0), a1(NP.largest)), 20 + 40) <= 1e-15
    P = PowerLawLayer(1.5, 0.0, 100.0, 2.0)
    assert rel(P.depth(NP, a1(-10.0), a1(0.5), a1(NP.largest)), 1.5 * (20 + 100 / 3 / 0.5)) <= 1e-14
    # downward or horizontal in fog: saturates, finite
    for comp in (L, H, P):
        for dy in (-1.0, 0.0, -1e-7):
            v = comp.depth(NP, a1(-20.0), a1(dy), a1(NP.largest))
            assert float(v) == 1e30


def test_medium_box_vs_quadrature():
    layers = (ExpLayer(1.0, 0.03, 0.0), ExpLayer(0.5, 0.0, 0.0))
    box = Box((-50.0, -10.0, -50.0), (50.0, 40.0, 50.0))
    med = FogMedium(sigma_t=0.05, layers=layers, bounds=box)
    rng = np.random.default_rng(3)
    for _ in range(30):
        o = rng.uniform(-80, 80, 3)
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        t = rng.uniform(0, 300)
        got = med.optical_depth(NP, tuple(a1(v) for v in o), tuple(a1(v) for v in d), a1(t))
        t0, t1 = med.clip(NP, tuple(a1(v) for v in o), tuple(a1(v) for v in d))
        t0, t1 = float(t0), min(float(t1), t)
        if t1 <= t0:
            assert float(got) == 0.0
            continue
        ref = mp_depth_quad(layers, o[1], d[1], t1, t0=t0)
        assert rel(got, ref) <= 1e-11


@pytest.mark.parametrize("layer", PROFILES, ids=repr)
def test_sample_inverts_depth(layer):
    """depth(sample(s)) == s within 32 eps (s + t rho(y(t))) (a few ulp of t)."""
    rng = np.random.default_rng(11)
    eps = np.finfo(np.float64).eps
    for oy, dy, _ in RAYS:
        total = float(layer.depth(NP, a1(oy), a1(dy), a1(NP.largest)))
        for s in rng.uniform(0, min(total, 1e4), 8) * rng.choice([1.0, 1e-6, 1e-12], 8):
            t = float(layer.sample(NP, a1(oy), a1(dy), a1(s)))
            assert t < NP.largest
            back = float(layer.depth(NP, a1(oy), a1(dy), a1(t)))
            rho_end = max(float(layer.rho(NP, a1(oy + t * f * dy))) for f in (1 - 8 * eps, 1.0, 1 + 8 * eps))
            assert abs(back - s) <= 32 * eps * (s + t * rho_end), (layer, oy, dy, s, t, back)
        if total < 1e29:  # finite total: beyond it the ray escapes
            assert float(layer.sample(NP, a1(oy), a1(dy), a1(total * 1.000001 + 1e-300))) == NP.largest


def test_validate_errors():
    with pytest.raises(ParameterError, match=r"layer1\.falloff.*outside"):
        FogMedium(layers=(ExpLayer(), HDRPLayer(1.0, 0.0, -1.0)))
    with pytest.raises(ParameterError, match=r"layer0\.power"):
        FogMedium(layers=(PowerLawLayer(1.0, 0.0, 10.0, -0.5),))
    with pytest.raises(ParameterError, match=r"layer0\.end"):
        FogMedium(layers=(PowerLawLayer(1.0, 10.0, 10.0, 1.0),))
    with pytest.raises(ParameterError, match=r"layer0\.density"):
        FogMedium(layers=(HDRPLayer(float("nan"), 0.0, 1.0),))


# ---------------------------------------------------------------- free flight
def test_free_flight_ks_two_layers():
    """KS test (alpha = 1e-3, seed 1234) of FogMedium.sample_distance, escape included.

    Each sample is mapped through the closed-form CDF F(t) = 1 - exp(-sigma tau(t));
    escaped samples (t = largest) are mapped uniformly onto [F(inf), 1].  The
    result must be U(0, 1); the escape count must match exp(-sigma tau(inf)).
    """
    layers = (ExpLayer(1.0, 0.02, 0.0), ExpLayer(0.5, 0.005, 20.0))
    sigma = 0.002
    med = FogMedium(sigma_t=sigma, layers=layers)
    n = 20000
    rng = np.random.default_rng(1234)
    dy = 0.3
    o = (np.zeros(n), np.full(n, 5.0), np.zeros(n))
    d = (np.full(n, math.sqrt(1 - dy * dy)), np.full(n, dy), np.zeros(n))
    e = [-np.log1p(-rng.random(n)) for _ in layers]
    t = med.sample_distance(NP, o, d, e, sigma)
    assert np.all(np.isfinite(t))
    esc = t >= NP.largest
    tau_inf = float(
        med.optical_depth(NP, tuple(a[:1] for a in o), tuple(a[:1] for a in d), a1(NP.largest))[0]
    )
    F_inf = -math.expm1(-sigma * tau_inf)
    tf = np.where(esc, 0.0, t)
    F = -np.expm1(-sigma * med.optical_depth(NP, o, d, tf))
    v = np.where(esc, F_inf + (1 - F_inf) * rng.random(n), F)
    assert stats.kstest(v, "uniform").pvalue > 1e-3
    p_esc = 1 - F_inf
    assert 0.05 < p_esc < 0.95  # the escape branch is really exercised
    assert stats.binomtest(int(esc.sum()), n, p_esc).pvalue > 1e-3


# ---------------------------------------------------------------- single scattering
def mp_exp_antider(L, y):
    """G(y) with G' = rho for an ExpLayer with falloff > 0 (mpmath)."""
    b = mp.mpf(L.falloff)
    return -mp.mpf(L.density) * mp.exp(-b * (mp.mpf(y) - L.height)) / b


def mp_single_scatter(layers, sigma, albedo, g, o_y, d, D, w, E):
    """mp.quad over [0, D] of alpha p E sigma rho(t) T(t) T_sun(x(t)).

    T and T_sun come from the exponential layers' antiderivatives in mpmath
    (independent of fogref's phi/psi forms); the outer integral is quadrature.
    """
    wy, dy = mp.mpf(w[1]), mp.mpf(d[1])
    o_y = mp.mpf(o_y)

    def tau(s):
        if dy == 0:
            return s * sum(mp_rho(L, o_y) for L in layers)
        return sum(mp_exp_antider(L, o_y + s * dy) - mp_exp_antider(L, o_y) for L in layers) / dy

    def tau_sun(y):
        return sum(-mp_exp_antider(L, y) for L in layers) / wy

    cos_t = sum(a * b for a, b in zip(d, w))
    phase = hg_phase(NP, a1(cos_t), g)
    f = lambda s: (
        sigma
        * sum(mp_rho(L, o_y + s * dy) for L in layers)
        * mp.exp(-sigma * tau(s) - sigma * tau_sun(o_y + s * dy))
    )
    return albedo * float(phase) * E * mp.quad(f, mp.linspace(0, D, 5))


@pytest.mark.parametrize(
    "layers",
    [(ExpLayer(1.0, 0.01, 0.0),), (ExpLayer(1.0, 0.01, 0.0), ExpLayer(0.4, 0.002, 30.0))],
    ids=["one", "two"],
)
@pytest.mark.parametrize("view", [(0.8, 0.6, 0.0), (0.6, -0.8, 0.0), (0.0, 1.0, 0.0), (1.0, 0.0, 0.0)])
def test_single_scatter_vs_quadrature(layers, view):
    if True:
        sigma, albedo, g, E = 0.02, 0.8, 0.6, 3.0
        w = (0.6, 0.8, 0.0)
        d = view
        D, oy = 150.0, 20.0
        med = FogMedium(sigma_t=sigma, albedo=albedo, g=g, layers=layers)
        got = single_scatter_sun(
            NP, med, (a1(0.0), a1(oy), a1(0.0)), tuple(a1(v) for v in d), a1(D), w, (E,) * 3
        )
        ref = mp_single_scatter(layers, sigma, albedo, g, oy, d, D, w, E)
        for c in got:
            assert rel(c, ref) <= 1e-12, (float(c), ref)


def test_single_scatter_channels_with_equal_extinctions():
    """A channel whose extinction equals an earlier one's reuses that channel's integral
    (``first_equal``); each channel must still be its own: the sun's single scattering against
    mpmath with that channel's extinction and irradiance (relative 1e-12; a reuse of the wrong
    channel is off by tens of percent), the sky's opacity bitwise against its per-channel form."""
    from fogref.media.single_scatter import first_equal, single_scatter_sky

    layers = (ExpLayer(1.0, 0.01, 0.0), ExpLayer(0.4, 0.002, 30.0))
    sigma, albedo, g, E, L = (0.02, 0.035, 0.02), 0.8, 0.6, (3.0, 2.0, 1.0), (0.5, 1.0, 2.0)
    assert first_equal(sigma) == [0, 1, 0]
    med = FogMedium(sigma_t=sigma, albedo=albedo, g=g, layers=layers)
    o, D, w = (a1(0.0), a1(20.0), a1(0.0)), a1(150.0), (0.6, 0.8, 0.0)
    for view in [(0.8, 0.6, 0.0), (0.6, -0.8, 0.0)]:
        d = tuple(a1(v) for v in view)
        got = single_scatter_sun(NP, med, o, d, D, w, E)
        for c in range(3):
            ref = mp_single_scatter(layers, sigma[c], albedo, g, 20.0, view, 150.0, w, E[c])
            assert rel(got[c], ref) <= 1e-12, (c, float(got[c]), ref)
        tau = med.optical_depth(NP, o, d, D)
        sky = single_scatter_sky(NP, med, o, d, D, L)
        for c in range(3):
            assert np.array_equal(sky[c], albedo * L[c] * -np.expm1(-sigma[c] * tau)), c


# -- the height-profile protocol and its registry ---------------------------------------

PROTOCOL_LAYERS = [
    ExpLayer(2.0, 0.05, 3.0),
    ExpLayer(1.0, 0.0, 0.0),
    HDRPLayer(1.5, 10.0, 0.02),
    HDRPLayer(1.0, 0.0, 0.0),
    PowerLawLayer(1.0, 0.0, 80.0, 2.0),
    PowerLawLayer(0.5, -5.0, 5.0, 0.0),
]


@pytest.mark.parametrize("layer", PROTOCOL_LAYERS, ids=repr)
def test_profiles_follow_the_protocol(layer):
    from fogref.media import HeightProfile

    assert isinstance(layer, HeightProfile)
    layer.validate("<test>", 0)
    y = np.linspace(-50.0, 150.0, 41)
    rho = layer.rho(NP, y)
    # max_density bounds the density on every height range [y_lo, y_hi]
    for i in range(0, len(y), 5):
        for j in range(i, len(y), 7):
            assert layer.max_density(NP, y[i], y[j]) >= rho[i : j + 1].max() * (1 - 1e-12)
    assert layer.is_constant == bool(np.all(rho == rho[0]))
    assert not layer.is_empty
    assert np.isfinite(layer.reference_height)


@pytest.mark.parametrize(
    "params, layers",
    [
        (
            {"profile": "exponential", "falloff": 0.02, "height": 1.0, "density2": 0.5, "falloff2": 0.1},
            (ExpLayer(1.0, 0.02, 1.0), ExpLayer(0.5, 0.1, 0.0)),
        ),
        ({"profile": "homogeneous", "density": 2.0}, (ExpLayer(2.0, 0.0, 0.0),)),
        ({"profile": "hdrp", "base_height": 4.0, "falloff": 0.03}, (HDRPLayer(1.0, 4.0, 0.03),)),
        (
            {"profile": "powerlaw", "start": 1.0, "end": 9.0, "power": 3.0},
            (PowerLawLayer(1.0, 1.0, 9.0, 3.0),),
        ),
    ],
)
def test_profile_registry_parses_each_profile(params, layers):
    from fogref.media import PROFILES, medium_from_params

    assert set(PROFILES) >= {"exponential", "homogeneous", "box", "hdrp", "powerlaw"}
    assert medium_from_params(params).layers == layers


def test_profile_registry_errors_name_the_parameter():
    from fogref.media import medium_from_params

    for params, name in [
        ({"profile": "fractal"}, "profile"),
        ({"profile": "box"}, "bounds_min"),
        ({"profile": "hdrp", "falloff": -1}, "falloff"),
        ({"sigma_t": [1, 2]}, "sigma_t"),
        ({"bounds_min": [0, 0, 0]}, "bounds_max"),
    ]:
        with pytest.raises(ParameterError) as e:
            medium_from_params(params, "<test>")
        assert e.value.name == name


def test_medium_asks_the_protocol():
    m = FogMedium(sigma_t=0.01, layers=(HDRPLayer(1.0, 5.0, 0.0), PowerLawLayer(0.0, 0.0, 10.0, 1.0)))
    assert m.layers == (HDRPLayer(1.0, 5.0, 0.0),) and m.is_homogeneous and not m.is_vacuum
    assert float(m.max_density(NP, 0.0, 100.0)) == 1.0
    with pytest.raises(ParameterError, match="sigma_t"):
        FogMedium(sigma_t=(0.01, 0.02, 0.03)).grey_sigma_t("test")
