"""Fog from physical quantities: visibility, droplet distributions, Mie optics and phase functions.

References, each independent of the code under test: Koschmieder's law in closed form;
Shettle & Fenn's (1979) modified-gamma parameters; Wiscombe's MIEV0 test cases (NCAR
TN-140, 1979, as quoted by miepython's own tests); scipy's adaptive quadrature of
miepython's efficiencies over the size distribution; Draine's normalisation.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from drjit.llvm import Float

import fogref
from fogref.errors import ParameterError
from fogref.media import NP, drjit_ops
from fogref.media.droplets import DROPLET_PRESETS, GammaDroplets, droplet_preset
from fogref.media.mie import RGB_WAVELENGTHS_NM, droplet_optics, mie_spheres, water_index
from fogref.media.phase import TabulatedPhase, approx_mie_phase, draine_phase, phase_cosines
from fogref.media.visibility import (
    KOSCHMIEDER_CONTRAST,
    WMO_CONTRAST,
    extinction_from_visibility,
    visibility_from_extinction,
)

RADIATION = DROPLET_PRESETS["radiation"]


# ---------------------------------------------------------------- visibility
@pytest.mark.parametrize("V", [50.0, 300.0, 1000.0, 1e5])
def test_koschmieder(V):
    assert extinction_from_visibility(V) == pytest.approx(3.912023005 / V, rel=1e-9)
    assert extinction_from_visibility(V, WMO_CONTRAST) == pytest.approx(2.995732274 / V, rel=1e-9)
    for eps in (KOSCHMIEDER_CONTRAST, WMO_CONTRAST, 0.3):
        sigma = extinction_from_visibility(V, eps)
        assert math.exp(-sigma * V) == pytest.approx(eps, rel=1e-12)  # the contrast left at V
        assert visibility_from_extinction(sigma, eps) == pytest.approx(V, rel=1e-12)


@pytest.mark.parametrize(
    "V, eps, name",
    [
        (0.0, 0.02, "visibility"),
        (-5, 0.02, "visibility"),
        (float("nan"), 0.02, "visibility"),
        (100, 1.0, "contrast"),
        (100, 0.0, "contrast"),
    ],
)
def test_visibility_bad_input(V, eps, name):
    with pytest.raises(ParameterError, match=f"parameter '{name}'"):
        extinction_from_visibility(V, eps, "<t>")


# ---------------------------------------------------------------- droplets
@pytest.mark.parametrize(
    "name, a, alpha, b, N, mode",
    [("advection", 0.027, 3, 0.3, 20, 10.0), ("radiation", 607.5, 6, 3.0, 200, 2.0)],
)
def test_presets_are_shettle_fenn(name, a, alpha, b, N, mode):
    d = droplet_preset(name)
    assert d.alpha == pytest.approx(alpha, rel=1e-12) and d.b == pytest.approx(b, rel=1e-12)
    assert d.mode_radius == pytest.approx(mode, rel=1e-12)
    # N = a Gamma(alpha + 1) / b^(alpha + 1): the table's number density follows from (a, alpha, b)
    assert a * math.gamma(alpha + 1) / b ** (alpha + 1) == pytest.approx(N, rel=1e-12)
    assert d.number == N


def test_liquid_water_and_moments():
    adv = DROPLET_PRESETS["advection"]
    assert adv.liquid_water == pytest.approx(0.37, rel=0.01)  # Shettle & Fenn: 0.37 g/m^3
    # <r^k> against a numerical integral of r^alpha exp(-b r)
    from scipy.integrate import quad

    for d in DROPLET_PRESETS.values():
        norm = quad(lambda r: r**d.alpha * math.exp(-d.b * r), 0, np.inf)[0]
        for k in (1, 2, 3):
            num = quad(lambda r: r ** (d.alpha + k) * math.exp(-d.b * r), 0, np.inf)[0]
            assert d.moment(k) == pytest.approx(num / norm, rel=1e-9)
        assert d.moment(3) / d.moment(2) == pytest.approx(d.r_eff, rel=1e-12)


def test_droplets_bad_input():
    with pytest.raises(ParameterError, match="parameter 'v_eff'"):
        GammaDroplets(5.0, 0.5)
    with pytest.raises(ParameterError, match="parameter 'droplets': 'haze' is not one of"):
        droplet_preset("haze", "<t>")


# ---------------------------------------------------------------- Mie of one sphere
@pytest.mark.parametrize(
    "m, x, qsca, g",
    [
        (complex(1.33, -1e-5), 1.0, 0.093923, 0.184517),  # MIEV0 case 9
        (complex(1.33, -1e-5), 100.0, 2.096594, 0.868959),  # MIEV0 case 10
        (complex(0.75, 0.0), 10.0, 2.232265, 0.896473),
    ],  # MIEV0 case 7
)
def test_mie_spheres_wiscombe(m, x, qsca, g):
    mu = phase_cosines()
    qe, qs, inten = mie_spheres(m, np.array([x]), tuple(mu))
    assert qs[0] == pytest.approx(qsca, abs=1e-6)
    # the phase function integrates to Q_sca; its mean cosine is g (piecewise-linear table: 2e-3)
    p = TabulatedPhase(tuple(mu), tuple(inten[0]))
    assert 2 * math.pi * np.trapezoid(inten[0], mu) == pytest.approx(qsca, rel=3e-3)
    assert p.mean_cosine == pytest.approx(g, abs=2e-3)


def test_mie_spheres_wiscombe_angles():
    """MIEV0's S1, S2 for m = 1.5 - 1i, x = 1 at 0, 30, ..., 180 deg: |S1|^2 + |S2|^2."""
    S1 = [
        0.584080 + 0.190515j,
        0.565702 + 0.187200j,
        0.517525 + 0.178443j,
        0.456340 + 0.167167j,
        0.400212 + 0.156643j,
        0.362157 + 0.149391j,
        0.348844 + 0.146829j,
    ]
    S2 = [
        0.584080 + 0.190515j,
        0.500161 + 0.145611j,
        0.287964 + 0.041054j,
        0.0362285 - 0.0618265j,
        -0.174875 - 0.122959j,
        -0.305682 - 0.143846j,
        -0.348844 - 0.146829j,
    ]
    mu = tuple(np.cos(np.radians(np.arange(0, 181, 30))))
    _, _, inten = mie_spheres(complex(1.5, -1.0), np.array([1.0]), mu)
    ref = (np.abs(S1) ** 2 + np.abs(S2) ** 2) / (2 * math.pi)
    np.testing.assert_allclose(inten[0], ref, rtol=2e-5)


def test_water_index():
    # the sodium D line (589.3 nm): 1.3330 at 20 C, within the table's 3 digits (and 25 C)
    assert water_index(589.3).real == pytest.approx(1.3330, abs=1e-3)
    assert 0 < -water_index(550.0).imag < 1e-8


def test_rgb_wavelengths_are_dominant_wavelengths():
    colour = pytest.importorskip("colour")
    prim = colour.RGB_COLOURSPACES["sRGB"].primaries
    white = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
    for xy, lam in zip(prim, RGB_WAVELENGTHS_NM):
        assert float(colour.dominant_wavelength(xy, white)[0]) == pytest.approx(lam, abs=0.5)


# ---------------------------------------------------------------- averaged over the droplets
def test_radiation_fog_against_quadrature():
    """The size average (trapezoid every dx = 0.5 in x over cross-section weights, Q from Mie
    coefficients) against an independent route: 8-point Gauss-Legendre on 400 panels of
    radius over n(r), with miepython's own efficiencies.  Extinction within 0.3 %, g within
    3e-3, albedo within 1e-6."""
    import miepython

    d, lam = RADIATION, 549.1
    o = droplet_optics(d, (lam,))
    m = water_index(lam)
    edges = np.linspace(0.02, 14.0, 401)
    u, wu = np.polynomial.legendre.leggauss(8)
    h = np.diff(edges)[:, None] / 2
    r = ((edges[:-1, None] + edges[1:, None]) / 2 + h * u).ravel()
    w = (h * wu).ravel() * r**d.alpha * np.exp(-d.b * r)
    qe, qs, _, g = (np.asarray(v) for v in miepython.efficiencies_mx(m, 2 * math.pi * r / (lam * 1e-3)))
    area = math.pi * r * r * w
    assert o.cross_section[0] == pytest.approx(area @ qe / w.sum(), rel=3e-3)
    assert o.g[0] == pytest.approx(area @ (qs * g) / (area @ qs), abs=3e-3)
    assert o.albedo[0] == pytest.approx(area @ qs / (area @ qe), abs=1e-6)


def test_preset_visibility():
    """Koschmieder visibility (2 %) of the presets at 549 nm, from their droplet numbers: the
    radiation fog's 0.0086 /m is 454 m; Shettle & Fenn list 450 m (their moderate radiation fog)."""
    o = droplet_optics(RADIATION)
    V = visibility_from_extinction(o.extinction(RADIATION.number)[1])
    assert V == pytest.approx(450.0, rel=0.03)
    # droplet extinction is nearly grey: within 3 % over R, G, B
    ext = o.extinction(1.0)
    assert max(ext) / min(ext) < 1.03


def test_phase_tables_resolve_the_peak():
    """The 752-node table against Mie at the midpoints of its intervals (radiation fog, 549 nm):
    within 3 % everywhere, 0.5 % rms."""
    c = phase_cosines()
    mid = 0.5 * (c[1:] + c[:-1])
    o = droplet_optics(RADIATION, (549.1,))
    om = droplet_optics(RADIATION, (549.1,), cosines=tuple(np.concatenate([[-1.0], mid, [1.0]])))
    direct = np.asarray(om.phases[0].values)[1:-1]
    interp = o.phases[0].eval(NP, mid)
    rel = interp / direct - 1.0
    assert np.max(np.abs(rel)) < 0.03 and np.sqrt(np.mean(rel**2)) < 0.005


# ---------------------------------------------------------------- phase functions
def test_tabulated_phase_twins():
    fogref.ensure_llvm()
    p = droplet_optics(RADIATION, (549.1,)).phases[0]
    x = np.concatenate([np.linspace(-1, 1, 2001), 1 - np.geomspace(1e-7, 1e-2, 200), [-1.0, 1.0]])
    x32 = x.astype(np.float32)
    ref = p.eval(NP, x32.astype(np.float64))
    got = np.asarray(p.eval(drjit_ops(Float), Float(x32)))
    np.testing.assert_allclose(got, ref, rtol=2e-5, atol=0)


@pytest.mark.parametrize("g, alpha", [(0.0, 0.0), (0.5, 1.0), (0.9, 5.0), (-0.3, 20.0)])
def test_draine_normalised(g, alpha):
    from scipy.integrate import quad

    total = 2 * math.pi * quad(lambda c: float(draine_phase(NP, c, g, alpha)), -1, 1, limit=200)[0]
    assert total == pytest.approx(1.0, abs=1e-9)


def test_approx_mie_against_mie():
    """Jendersie and d'Eon's fit (d = 2 r_eff = 6 um) against the radiation fog's Mie phase
    (549 nm; the fit is for one droplet size, the fog has a spread of sizes): the mean cosines
    agree within 0.02, and the share scattered within 10 deg of forward within 0.05."""
    mie = droplet_optics(RADIATION, (549.1,)).phases[0]
    fit = TabulatedPhase.from_function(lambda c: approx_mie_phase(NP, c, 2 * RADIATION.r_eff))
    assert fit.mean_cosine == pytest.approx(mie.mean_cosine, abs=0.02)
    c = np.asarray(mie.cosines)
    fwd = c >= math.cos(math.radians(10))
    share = lambda p: 2 * math.pi * np.trapezoid(np.asarray(p.values)[fwd], c[fwd])
    assert share(fit) == pytest.approx(share(mie), abs=0.05)


def test_tabulated_phase_bad_input():
    with pytest.raises(ParameterError, match="parameter 'cosines'"):
        TabulatedPhase((-1.0, 0.5), (1.0, 1.0), source="<t>")
    with pytest.raises(ParameterError, match="parameter 'values'"):
        TabulatedPhase((-1.0, 1.0), (1.0, float("nan")), source="<t>")
    with pytest.raises(ParameterError, match="parameter 'diameter'"):
        approx_mie_phase(NP, 0.0, 60.0)
