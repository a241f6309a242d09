"""The sky control variate's closed form: ``H(mu0)``, the share of a Henyey–Greenstein
lobe around a direction of height ``mu0`` that lies above the horizon.

fogpath adds ``H(d_y) alpha L_sky (1 - T(D))`` per camera ray and subtracts the
Monte Carlo estimate of the same integrand at the first medium vertex, so any error
in ``H`` is a bias of the same relative size in the sky's single scattering.  The
table (elliptic-integral route, linear interpolation) is checked against two
independent oracles: adaptive quadrature over the lobe's polar angle, and the share
of HG samples above the horizon.  The estimator itself is checked by the white
furnace with occluders (``tests/test_render_bias.py``).
"""

import numpy as np
import pytest

from fogref.media.single_scatter import hg_upper_fraction, hg_upper_fraction_table


@pytest.mark.parametrize("g", [0.0, 0.6, -0.5, 0.85, 0.95])
def test_table_against_quadrature(g):
    """Between nodes (worst case for linear interpolation) and at nodes: |error| <= 1e-6,
    i.e. a relative bias <= 2e-6 of the sky's single scattering where H >= 0.5."""
    T = np.array(hg_upper_fraction_table(g))
    mu = np.linspace(-1, 1, len(T))
    idx = np.arange(0, len(T) - 1, (len(T) - 1) // 40)
    mid = (mu[idx] + mu[idx + 1]) / 2
    assert np.abs(hg_upper_fraction(g, mid) - (T[idx] + T[idx + 1]) / 2).max() <= 1e-6
    assert np.abs(hg_upper_fraction(g, mu[idx]) - T[idx]).max() <= 1e-6
    assert np.allclose(T + T[::-1], 1.0, atol=1e-12)  # H(-mu0) = 1 - H(mu0)


@pytest.mark.parametrize("g", [0.6, -0.3])
def test_quadrature_against_hg_samples(g):
    """Share of 2e6 HG samples above the horizon; binomial z-test, |z| < 4.4 (family-wise
    alpha 1e-4); detects an error of 1.7e-3 in H with 95 % power."""
    rng = np.random.default_rng(11)
    n = 2_000_000
    for m0 in (-0.9, -0.4, 0.0, 0.15, 0.7, 0.99):
        u = rng.random(n)
        if g == 0:
            mu = 1 - 2 * u
        else:
            sq = (1 - g * g) / (1 - g + 2 * g * u)
            mu = (1 + g * g - sq * sq) / (2 * g)
        phi = 2 * np.pi * rng.random(n)
        wy = mu * m0 + np.sqrt(np.maximum(1 - mu**2, 0)) * np.cos(phi) * np.sqrt(1 - m0**2)
        share = (wy > 0).mean()
        H = hg_upper_fraction(g, [m0])[0]
        assert abs(share - H) <= 4.4 * np.sqrt(H * (1 - H) / n), (g, m0, share, H)
