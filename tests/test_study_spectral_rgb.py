"""The spectral answer of fogref.study.spectral_rgb against an independent quadrature, and its RGB
side against what the droplet fog writes.  Seconds, no Mitsuba."""

from __future__ import annotations

import numpy as np
import pytest

from fogref.errors import ParameterError
from fogref.mapping.droplet_fog import droplet_fog
from fogref.media.droplets import droplet_preset
from fogref.study.spectral_rgb import (
    SPECTRUM_NM,
    angstrom_spectrum,
    droplet_spectrum,
    fog_spectrum,
    rgb_answer,
    spectral_answer,
    spectral_error,
)


def _quad_rgb(sigma, taus):
    """Linear sRGB by scipy's adaptive quadrature of D65 x CMF x exp(-tau sigma(l)) over
    380-780 nm, the tables linear between their 1 nm rows, then the IEC 61966-2-1 matrix
    (transcribed, 4 digits) and the white balance of the unfogged white."""
    import colour
    from scipy.integrate import quad

    lo, hi, _ = SPECTRUM_NM
    cmf = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(colour.SpectralShape(lo, hi, 1.0))
    wl = np.arange(lo, hi + 0.5)
    tables = [np.asarray(d65[wl]) * np.asarray(cmf[wl])[:, k] for k in range(3)]
    m = np.array([[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]])

    def xyz(tau):
        def one(row):
            f = lambda x: np.interp(x, wl, row) * np.exp(-tau * sigma(x))  # noqa: E731
            return quad(f, lo, hi, points=wl[1:-1], limit=1000)[0]

        return np.array([one(row) for row in tables])

    white = m @ xyz(0.0)
    return np.array([(m @ xyz(t)) / white for t in taus])


@pytest.mark.parametrize("alpha", [1.3, 4.0])
def test_spectral_transmittance_matches_scipy_quadrature(alpha):
    # The module sums the 1 nm rows (colour-science's "Integration") and uses colour-science's
    # sRGB matrix; quad integrates the rows' linear interpolant and the matrix is IEC's 4-digit
    # one: they differ by at most 2.4e-6 of the white (measured).  The bound 2e-5 sits 500
    # times below the three-band error the module measures here (over 1e-2).
    taus = [0.3, 3.0]
    s = angstrom_spectrum(alpha)
    got, _ = spectral_answer(s, taus)
    want = _quad_rgb(lambda x: (x / 549.1) ** -alpha, taus)
    np.testing.assert_allclose(got, want, rtol=0, atol=2e-5)
    # and the answer differs from the three-band one by far more than that bound
    assert np.abs(got - rgb_answer(s, taus)[0]).max() > 1e-2


def test_inscatter_is_white_minus_transmittance():
    s = angstrom_spectrum(4.0)
    t, i = spectral_answer(s, [0.5, 2.0])
    np.testing.assert_allclose(t + i, 1.0, rtol=0, atol=1e-12)


def test_grey_fog_has_no_error():
    e = spectral_error(angstrom_spectrum(0.0), np.logspace(-1, 1, 5))
    for k in ("transmittance", "inscatter"):
        assert np.abs(e[f"{k}_rel"]).max() < 1e-12
        assert np.abs(e[f"{k}_lum"]).max() < 1e-12
        assert e[f"{k}_de"].max() < 1e-9


def test_rgb_side_is_what_the_droplet_fog_writes():
    # The droplet spectrum's bands are droplet_optics' cross sections, as droplet_fog's sigma_t.
    s = droplet_spectrum(droplet_preset("radiation"), step_nm=100.0)
    f = droplet_fog(300.0, "radiation")
    np.testing.assert_allclose(s.rgb, np.asarray(f.sigma_t) / f.sigma_t[1], rtol=1e-12)
    assert s.wavelengths == (380.0, 480.0, 580.0, 680.0, 780.0)


def test_bad_input_names_the_parameter():
    with pytest.raises(ParameterError, match="alpha"):
        angstrom_spectrum(5.0)
    with pytest.raises(ParameterError, match="tau"):
        spectral_answer(angstrom_spectrum(1.0), [-1.0])
    with pytest.raises(ParameterError, match="tau"):
        spectral_error(angstrom_spectrum(1.0), [0.0])
    with pytest.raises(ParameterError, match="fog"):
        fog_spectrum("smog")
