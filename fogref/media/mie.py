"""Mie optics of fog droplets: extinction, albedo and phase per RGB band, averaged over a size
distribution (``miepython``).

For each band's wavelength, droplet radii every ``dx`` in size parameter (over all but 1e-8
of the distribution's cross section) get miepython's efficiencies and unpolarised phase
function; their means, weighted by the droplets' cross sections, give the fog's mean
extinction cross section per droplet, its albedo, its asymmetry ``g`` and its phase function
tabulated on :func:`fogref.media.phase.phase_cosines`.

The bands are represented by one wavelength each, the dominant wavelengths of the
sRGB (Rec. 709) primaries: 611.4, 549.1 and 464.3 nm (:data:`RGB_WAVELENGTHS_NM`;
``colour.dominant_wavelength`` of the primaries against D65 gives them,
``tests/test_media_mie.py``).  Water's refractive index: Hale & Querry's table (Appl. Opt.
12, 1973, table 1, 25 C; 450 to 650 nm every 50 nm), the real part linear and the
imaginary part log-linear in wavelength between its rows; the imaginary part sets the
albedo, which stays above 0.9999.

References: C. F. Bohren and D. R. Huffman, *Absorption and Scattering of Light by
Small Particles*, Wiley 1983 (ch. 4); S. Prahl, miepython (https://github.com/scottprahl/miepython).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from fogref.media.droplets import GammaDroplets
from fogref.media.phase import TabulatedPhase, phase_cosines

__all__ = ["RGB_WAVELENGTHS_NM", "DropletOptics", "droplet_optics", "mie_spheres", "water_index"]

#: One wavelength per RGB channel [nm]: the sRGB primaries' dominant wavelengths (R, G, B)
RGB_WAVELENGTHS_NM = (611.4, 549.1, 464.3)

#: Hale & Querry (1973), table 1 (water at 25 C): wavelength [nm], n, k
_HQ_NM = (450.0, 500.0, 550.0, 600.0, 650.0)
_HQ_N = (1.337, 1.335, 1.333, 1.332, 1.331)
_HQ_K = (1.02e-9, 1.0e-9, 1.96e-9, 1.09e-8, 1.64e-8)


def water_index(wavelength_nm: float) -> complex:
    """Water's complex refractive index ``n - i k`` at ``wavelength_nm`` (450 to 650 nm; see
    module), miepython's sign convention.

    >>> m = water_index(589.3)
    >>> round(m.real, 4), m.imag < 0
    (1.3322, True)
    """
    lam = float(wavelength_nm)
    n = float(np.interp(lam, _HQ_NM, _HQ_N))
    k = math.exp(float(np.interp(lam, _HQ_NM, np.log(_HQ_K))))
    return complex(n, -k)


@dataclass(frozen=True)
class DropletOptics:
    """A droplet fog's optics per channel (R, G, B; see module).

    cross_section: mean extinction cross section per droplet [um^2], per channel.
    albedo:        single-scattering albedo per channel.
    g:             asymmetry ``<cos theta>`` per channel.
    phases:        the phase function per channel (:class:`TabulatedPhase`).
    wavelengths:   the channels' wavelengths [nm].
    """

    cross_section: tuple
    albedo: tuple
    g: tuple
    phases: tuple
    wavelengths: tuple

    def extinction(self, number_per_cm3: float) -> tuple:
        """Extinction [1/m] per channel of ``number_per_cm3`` droplets per cm^3."""
        return tuple(c * 1e-12 * number_per_cm3 * 1e6 for c in self.cross_section)

    def grey_phase(self, label: str = "mie") -> TabulatedPhase:
        """One phase function for every channel: the channels' phases averaged with
        weights ``sigma_s`` (the mean over R, G, B of single scattering is then exact;
        the colour of the fogbow and the glory is lost)."""
        w = np.asarray(self.cross_section) * np.asarray(self.albedo)
        vals = sum(wi * np.asarray(p.values) for wi, p in zip(w, self.phases)) / w.sum()
        return TabulatedPhase(self.phases[0].cosines, tuple(vals), label=label)


@functools.lru_cache(maxsize=4)
def _pi_tau(mu: tuple, n_terms: int) -> tuple[np.ndarray, np.ndarray]:
    """miepython's angular functions ``pi_n``, ``tau_n`` (n = 1..n_terms) at each ``mu``:
    two ``(n_terms, len(mu))`` arrays."""
    import miepython

    pi, tau = np.zeros((len(mu), n_terms)), np.zeros((len(mu), n_terms))
    for k, m in enumerate(mu):
        miepython.pi_tau(m, pi[k], tau[k])
    return pi.T.copy(), tau.T.copy()


def _size_parameters(droplets: GammaDroplets, lam_um: float, dx: float) -> tuple[np.ndarray, np.ndarray]:
    """Size parameters every ``dx`` over the radii that hold all but 1e-8 of the droplets'
    cross section, and their weights (cross section times number, sum 1)."""
    from scipy.special import gammaincinv

    a, b = droplets.alpha, droplets.b
    lo, hi = (gammaincinv(a + 3.0, q) / b for q in (1e-8, 1.0 - 1e-8))  # radii [um]
    k = 2.0 * math.pi / lam_um
    x = np.arange(max(k * lo, dx), k * hi + dx, dx)
    w = np.exp((a + 2.0) * np.log(x) - b * x / k)  # r^2 n(r) dr, dr uniform
    return x, w / w.sum()


def mie_spheres(m: complex, x: np.ndarray, mu: tuple) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Extinction and scattering efficiencies of spheres of index ``m`` (``n - i k``) and size
    parameters ``x`` (1-d), and their unpolarised phase functions times ``Q_sca`` [1/sr] at the
    cosines ``mu`` (miepython's ``i_unpolarized(norm="qsca")``), ``(len(x), len(mu))``.

    miepython's Mie coefficients ``a_n, b_n`` and angular functions ``pi_n, tau_n``; the
    amplitudes ``S1, S2`` (Bohren & Huffman eq. 4.74) as one matrix product for all sizes.

    >>> qe, qs, i = mie_spheres(complex(1.33, -1e-5), np.array([100.0]), (-1.0, 1.0))
    >>> round(float(qs[0]), 6)   # Wiscombe's MIEV0 test case 10: 2.096594
    2.096594
    """
    import miepython

    x = np.asarray(x, dtype=np.float64)
    coeffs = [miepython.an_bn(m, float(xi)) for xi in x]
    n_terms = max(len(a) for a, _ in coeffs)
    n = np.arange(1, n_terms + 1)
    A = np.zeros((len(x), n_terms), complex)
    B = np.zeros((len(x), n_terms), complex)
    for i, (a, b) in enumerate(coeffs):
        A[i, : len(a)], B[i, : len(b)] = a, b
    qext = 2.0 / x**2 * ((2 * n + 1) * (A + B).real).sum(1)
    qsca = 2.0 / x**2 * ((2 * n + 1) * (abs(A) ** 2 + abs(B) ** 2)).sum(1)
    pi, tau = _pi_tau(tuple(float(c) for c in mu), n_terms)
    scale = (2.0 * n + 1.0) / (n * (n + 1.0))
    sa, sb = A * scale, B * scale
    S1, S2 = sa @ pi + sb @ tau, sa @ tau + sb @ pi
    intensity = (abs(S1) ** 2 + abs(S2) ** 2) / (2.0 * math.pi * x[:, None] ** 2)
    return qext, qsca, intensity


@functools.lru_cache(maxsize=16)
def droplet_optics(
    droplets: GammaDroplets,
    wavelengths_nm: tuple = RGB_WAVELENGTHS_NM,
    dx: float = 0.5,
    cosines: tuple | None = None,
) -> DropletOptics:
    """Mie optics of ``droplets`` at ``wavelengths_nm`` (see module): radii every ``dx`` in size
    parameter ``2 pi r / lambda`` (trapezoid rule over the distribution), the phase on
    ``cosines`` (default :func:`phase_cosines`).  Seconds per call for the presets (cached
    per arguments).

    >>> from fogref.media.droplets import GammaDroplets
    >>> d = GammaDroplets(3.0, 1 / 9)
    >>> o = droplet_optics(d, (549.1,), cosines=(-1.0, 0.0, 1.0))
    >>> round(o.cross_section[0] / (math.pi * d.moment(2)), 3)   # the mean Q_ext
    2.206
    """
    mu = tuple(float(c) for c in (phase_cosines() if cosines is None else cosines))
    mean_area = math.pi * droplets.moment(2.0)
    out: dict[str, list] = {"cs": [], "alb": [], "g": [], "ph": []}
    for lam in wavelengths_nm:
        x, w = _size_parameters(droplets, lam * 1e-3, dx)
        qext, qsca, intensity = mie_spheres(water_index(lam), x, mu)
        q_e, q_s = float(w @ qext), float(w @ qsca)
        phase = TabulatedPhase(mu, tuple((w @ intensity) / q_s), label=f"mie {lam} nm")
        out["cs"].append(mean_area * q_e)
        out["alb"].append(q_s / q_e)
        out["ph"].append(phase)
        out["g"].append(phase.mean_cosine)
    return DropletOptics(
        tuple(out["cs"]), tuple(out["alb"]), tuple(out["g"]), tuple(out["ph"]), tuple(wavelengths_nm)
    )
