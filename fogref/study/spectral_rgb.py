"""What rendering a spectral fog in RGB costs: three bands against the spectrum.

fogref's truth is RGB: a fog has one extinction ``sigma_t`` per channel, taken at one
wavelength per band (:data:`fogref.media.mie.RGB_WAVELENGTHS_NM`, the sRGB primaries'
dominant wavelengths 611.4, 549.1 and 464.3 nm).  A real fog's extinction is a function of
wavelength.  This module measures, in closed form (float64, no rendering), how far the
three-band answer is from the spectral one for a homogeneous path of optical depth ``tau``
(the green band's, ``sigma_t(549.1 nm) d``; ``tau = 3.912 d / V`` for a visibility ``V``
at Koschmieder's 2 %).

Geometry, both seen by a camera with CIE 1931 2 deg colour matching functions, in linear
sRGB (Rec. 709 primaries, D65 white; no OETF):

* **transmittance**: a white surface lit by D65 at distance ``d``:
  ``RGB = M int S(l) exp(-sigma(l) d) cmf(l) dl``, ``S`` = D65;
* **inscatter**: the sun's single scattering along the path, the sun of spectrum D65 and
  unattenuated (fog below a clear sky, the sun high): ``S(l) p a (1 - exp(-sigma(l) d))``.
  The phase value ``p`` and the albedo ``a`` are taken grey (droplets: albedo above 0.9999;
  the colour of the fogbow and the glory is another effect), so they scale both answers
  alike and the result is given for ``p a = 1``: the inscatter tends to white as ``tau``
  grows.

``M`` is colour-science's XYZ -> linear sRGB; the integral is colour-science's
``msds_to_XYZ`` ("Integration") on the CIE tables every 1 nm over 380-780 nm, and both
answers are white-balanced by the unfogged white (so a grey fog gives no error at all;
the balance moves each channel by under 5e-4).  The RGB answer is ``exp(-sigma_c d)``
and ``1 - exp(-sigma_c d)`` per channel ``c``, ``sigma_c`` the spectrum at the band's
wavelength: what :func:`fogref.mapping.droplet_fog.droplet_fog` writes for droplets.

Spectra (:func:`fog_spectrum`): the two droplet fogs of :mod:`fogref.media.droplets`
(Mie extinction of the size distribution, :func:`fogref.media.mie.droplet_optics`, every
10 nm and linear between; water's index outside 450-650 nm is held at the table's end
rows, where Hale & Querry's real part moves by about 0.003 at most: raising it by 0.003 moves
the radiation fog's extinction at 380 nm by 0.05 %), haze with Angstrom's law
``sigma(l) ~ l^-alpha`` with ``alpha = 1.3`` (Angstrom 1929's mean for continental
aerosol; Eck et al. 1999 measure 1-2.5 for fine-mode aerosol, under 1 for desert dust),
and Rayleigh's ``alpha = 4`` (clear air, the extreme).

References: A. Angstrom, "On the atmospheric transmission of sun radiation and on dust in
the air", Geografiska Annaler 11, 1929; T. F. Eck et al., "Wavelength dependence of the
optical depth of biomass burning, urban, and desert dust aerosols", J. Geophys. Res. 104,
1999; CIE 015:2018 *Colorimetry* (the 2 deg observer, D65).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fogref.compare.perceptual import delta_e2000_map
from fogref.display import luminance
from fogref.errors import ParameterError
from fogref.media.droplets import GammaDroplets, droplet_preset
from fogref.media.mie import RGB_WAVELENGTHS_NM, droplet_optics

__all__ = [
    "ANGSTROM_HAZE",
    "FOGS",
    "MIE_STEP_NM",
    "SPECTRUM_NM",
    "FogSpectrum",
    "angstrom_spectrum",
    "droplet_spectrum",
    "fog_spectrum",
    "rgb_answer",
    "spectral_answer",
    "spectral_error",
]

#: The visible range and step of the spectral answer [nm]: first, last, step
SPECTRUM_NM = (380.0, 780.0, 1.0)
#: Mie's wavelengths for droplet spectra, every this many nm (linear between) [nm]
MIE_STEP_NM = 10.0
#: Angstrom exponent of haze (Angstrom 1929; see module)
ANGSTROM_HAZE = 1.3
#: The fogs measured: droplet presets, haze, Rayleigh
FOGS = ("radiation", "advection", "haze", "rayleigh")
_GREEN = RGB_WAVELENGTHS_NM[1]


@dataclass(frozen=True)
class FogSpectrum:
    """A fog's extinction spectrum, relative to the green band's (549.1 nm).

    label:       its name in reports.
    wavelengths: [nm], increasing, covering :data:`SPECTRUM_NM`.
    extinction:  ``sigma(l) / sigma(549.1 nm)`` at each wavelength (> 0).
    rgb:         ``sigma_c / sigma(549.1 nm)`` at the bands' wavelengths (R, G, B): fogref's
                 three channels; G is 1.
    """

    label: str
    wavelengths: tuple
    extinction: tuple
    rgb: tuple

    def on(self, wavelengths_nm) -> np.ndarray:
        """The relative extinction at ``wavelengths_nm`` (linear between the tabulated ones)."""
        return np.interp(np.asarray(wavelengths_nm, float), self.wavelengths, self.extinction)


def angstrom_spectrum(alpha: float, label: str | None = None) -> FogSpectrum:
    """Angstrom's law ``(l / 549.1 nm)^-alpha``, ``alpha`` in [0, 4] (0 grey, 4 Rayleigh).

    >>> s = angstrom_spectrum(4.0)
    >>> round(s.rgb[2], 4), s.rgb[1]   # blue over green, Rayleigh
    (1.9562, 1.0)
    """
    a = float(alpha)
    if not (math.isfinite(a) and 0.0 <= a <= 4.0):
        raise ParameterError("<spectral_rgb>", "alpha", f"value {alpha} outside [0, 4]")
    lo, hi, step = SPECTRUM_NM
    wl = np.arange(lo, hi + step / 2, step)
    rgb = tuple(float((w / _GREEN) ** -a) for w in RGB_WAVELENGTHS_NM)
    return FogSpectrum(label or f"Angstrom alpha {a:g}", tuple(wl), tuple((wl / _GREEN) ** -a), rgb)


def droplet_spectrum(droplets: GammaDroplets, step_nm: float = MIE_STEP_NM) -> FogSpectrum:
    """Mie extinction of ``droplets`` every ``step_nm`` (1 to 100) over :data:`SPECTRUM_NM`,
    relative to the green band's; the bands as :func:`fogref.media.mie.droplet_optics` gives
    them (what the droplet fog writes).  A few seconds for the radiation fog, minutes for the
    advection fog (its drops are large in size parameter).
    """
    if not (math.isfinite(float(step_nm)) and 1.0 <= float(step_nm) <= 100.0):
        raise ParameterError("<spectral_rgb>", "step_nm", f"value {step_nm} outside [1, 100] nm")
    lo, hi, _ = SPECTRUM_NM
    wl = tuple(float(w) for w in np.arange(lo, hi + step_nm / 2, step_nm))
    bands = droplet_optics(droplets, RGB_WAVELENGTHS_NM, cosines=(-1.0, 1.0)).cross_section
    cs = droplet_optics(droplets, wl, cosines=(-1.0, 1.0)).cross_section
    g = bands[1]
    return FogSpectrum(droplets.label, wl, tuple(c / g for c in cs), tuple(b / g for b in bands))


def fog_spectrum(name: str) -> FogSpectrum:
    """The spectrum of one of :data:`FOGS`: a droplet preset, ``"haze"`` (Angstrom
    :data:`ANGSTROM_HAZE`) or ``"rayleigh"`` (alpha 4).

    >>> fog_spectrum("haze").label
    'haze (Angstrom alpha 1.3)'
    """
    if name == "haze":
        return angstrom_spectrum(ANGSTROM_HAZE, f"haze (Angstrom alpha {ANGSTROM_HAZE:g})")
    if name == "rayleigh":
        return angstrom_spectrum(4.0, "Rayleigh (alpha 4)")
    if name not in FOGS:
        raise ParameterError("<spectral_rgb>", "fog", f"'{name}' is not one of {', '.join(FOGS)}")
    return droplet_spectrum(droplet_preset(name))


def _taus(tau) -> np.ndarray:
    t = np.atleast_1d(np.asarray(tau, dtype=np.float64))
    if t.ndim != 1 or not np.all(np.isfinite(t)) or np.any(t < 0) or np.any(t > 50):
        raise ParameterError("<spectral_rgb>", "tau", "optical depths must be finite, in [0, 50]")
    return t


def spectral_answer(spectrum: FogSpectrum, tau) -> tuple[np.ndarray, np.ndarray]:
    """The spectral answer at the green optical depths ``tau`` (1-d, each in [0, 50]):
    ``(transmittance, inscatter)``, each ``(len(tau), 3)`` linear sRGB, white-balanced
    (see module).

    >>> t, i = spectral_answer(angstrom_spectrum(0.0), [0.0, 1.0])
    >>> np.round(t, 6).tolist()   # grey fog: exp(-tau) in every channel
    [[1.0, 1.0, 1.0], [0.367879, 0.367879, 0.367879]]
    """
    import colour

    t = _taus(tau)
    lo, hi, step = SPECTRUM_NM
    shape = colour.SpectralShape(lo, hi, step)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape)
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(shape)
    sigma = spectrum.on(shape.wavelengths)
    trans = np.exp(-t[:, None] * sigma[None, :])
    rows = np.vstack([np.ones_like(sigma), trans, 1.0 - trans])
    xyz = colour.msds_to_XYZ(rows, cmfs, d65, method="Integration", shape=shape) / 100.0
    white = colour.RGB_COLOURSPACES["sRGB"].whitepoint
    rgb = colour.XYZ_to_RGB(xyz, "sRGB", white, chromatic_adaptation_transform=None)
    rgb = rgb / rgb[0]
    n = len(t)
    return rgb[1 : n + 1], rgb[n + 1 :]


def rgb_answer(spectrum: FogSpectrum, tau) -> tuple[np.ndarray, np.ndarray]:
    """fogref's three-band answer: ``exp(-tau sigma_c)`` and ``1 - exp(-tau sigma_c)``,
    each ``(len(tau), 3)``.

    >>> t, i = rgb_answer(angstrom_spectrum(4.0), [1.0])
    >>> np.round(t, 4).tolist()
    [[0.5217, 0.3679, 0.1414]]
    """
    t = _taus(tau)
    trans = np.exp(-t[:, None] * np.asarray(spectrum.rgb)[None, :])
    return trans, 1.0 - trans


def spectral_error(spectrum: FogSpectrum, tau) -> dict[str, np.ndarray]:
    """The RGB answer's error against the spectral one at the green optical depths ``tau``
    (1-d, each in (0, 50]).  For ``q`` in ``transmittance``, ``inscatter``:

    ``q_rel``:  ``(rgb - spectral) / Y_spectral`` per channel, ``(len(tau), 3)``: relative to
                the spectral colour's luminance (a strongly filtered spectral colour can
                leave the sRGB gamut, a channel <= 0, where a channel's own ratio means
                nothing);
    ``q_lum``:  ``Y_rgb / Y_spectral - 1`` of the luminance (Rec. 709 weights), ``(len(tau),)``;
    ``q_de``:   CIEDE2000 between the two colours (unitless, 1 about just noticeable),
                the unfogged white at L* = 100, negative channels clipped to 0
                (:func:`fogref.compare.perceptual.delta_e2000_map`), ``(len(tau),)``;
    and ``tau``.

    >>> e = spectral_error(angstrom_spectrum(0.0), [1.0])   # grey: exact
    >>> float(abs(e["transmittance_rel"]).max()) < 1e-12, float(e["inscatter_de"][0]) < 1e-9
    (True, True)
    """
    t = _taus(tau)
    if np.any(t <= 0):
        raise ParameterError("<spectral_rgb>", "tau", "optical depths must be > 0 for a relative error")
    out: dict[str, np.ndarray] = {"tau": t}
    for name, spec, rgb in zip(
        ("transmittance", "inscatter"), spectral_answer(spectrum, t), rgb_answer(spectrum, t)
    ):
        y = luminance(spec)
        out[f"{name}_rel"] = (rgb - spec) / y[:, None]
        out[f"{name}_lum"] = luminance(rgb) / y - 1.0
        out[f"{name}_de"] = delta_e2000_map(spec, rgb, white=1.0)
    return out
