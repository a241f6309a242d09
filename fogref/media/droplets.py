"""Fog droplet size distributions: the gamma distribution and named fogs from the literature.

The number of droplets per radius is a gamma distribution (Hansen & Travis 1974,
eq. 2.56), set by its effective radius ``r_eff = <r^3> / <r^2>`` and effective
variance ``v_eff``::

    n(r) = N c r^((1 - 3 v_eff) / v_eff) exp(-r / (r_eff v_eff))

which is Deirmendjian's modified gamma ``a r^alpha exp(-b r^gamma)`` with
``gamma = 1``, ``alpha = (1 - 3 v_eff) / v_eff`` and ``b = 1 / (r_eff v_eff)``.

:data:`DROPLET_PRESETS` holds the two fogs of Shettle & Fenn (1979, table 3, after
Tampieri & Tomasi 1976): "heavy advection fog" (``a = 0.027``, ``alpha = 3``,
``b = 0.3``; N = 20 cm^-3, liquid water 0.37 g/m^3, mode radius 10 um) and
"moderate radiation fog" (``a = 607.5``, ``alpha = 6``, ``b = 3``; N = 200 cm^-3,
0.02 g/m^3, mode radius 2 um), radii in um and ``n`` in cm^-3 um^-1.  Their stated
numbers and mode radii follow from ``(a, alpha, b)``, and so does the advection fog's
liquid water; the radiation fog's is 0.0156 g/m^3, which the table rounds to 0.02
(checked in ``tests/test_media_mie.py``).

References: J. E. Hansen and L. D. Travis, "Light scattering in planetary
atmospheres", Space Sci. Rev. 16, 1974; E. P. Shettle and R. W. Fenn, "Models for
the aerosols of the lower atmosphere and the effects of humidity variations on their
optical properties", AFGL-TR-79-0214, 1979; F. Tampieri and C. Tomasi, "Size
distribution models of fog and cloud droplets in terms of the modified gamma
function", Tellus 28, 1976.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from fogref.errors import ParameterError

__all__ = ["DROPLET_PRESETS", "GammaDroplets", "droplet_preset"]


@dataclass(frozen=True)
class GammaDroplets:
    """A gamma distribution of droplet radii (see module).

    r_eff:  effective radius [um], 0.1 to 100.
    v_eff:  effective variance (dimensionless), 0.01 to 0.3 (``alpha >= 0.33``).
    number: droplets per cm^3 (> 0): only :attr:`liquid_water` uses it.
    label:  its name in reports, with its source.

    Examples
    --------
    >>> d = GammaDroplets(r_eff=3.0, v_eff=1 / 9, number=200.0)
    >>> round(d.alpha, 6), round(d.b, 6), round(d.mode_radius, 6)
    (6.0, 3.0, 2.0)
    >>> round(d.liquid_water, 4)   # g/m^3
    0.0156
    """

    r_eff: float
    v_eff: float
    number: float = 100.0
    label: str = "gamma"

    def __post_init__(self) -> None:
        src = f"droplets '{self.label}'"
        for name, v, lo, hi in (("r_eff", self.r_eff, 0.1, 100.0), ("v_eff", self.v_eff, 0.01, 0.3)):
            if not (math.isfinite(float(v)) and lo <= float(v) <= hi):
                raise ParameterError(src, name, f"value {v} outside [{lo}, {hi}]")
        if not (math.isfinite(float(self.number)) and float(self.number) > 0):
            raise ParameterError(src, "number", f"value {self.number} must be > 0 (per cm^3)")

    @property
    def alpha(self) -> float:
        """The modified gamma's exponent ``(1 - 3 v_eff) / v_eff``."""
        return (1.0 - 3.0 * self.v_eff) / self.v_eff

    @property
    def b(self) -> float:
        """The modified gamma's rate ``1 / (r_eff v_eff)`` [1/um]."""
        return 1.0 / (self.r_eff * self.v_eff)

    @property
    def mode_radius(self) -> float:
        """The most frequent radius ``alpha / b`` [um]."""
        return self.alpha / self.b

    def moment(self, k: float) -> float:
        """``<r^k>`` [um^k] over the distribution."""
        a, b = self.alpha, self.b
        return math.exp(math.lgamma(a + 1.0 + k) - math.lgamma(a + 1.0)) / b**k

    @property
    def liquid_water(self) -> float:
        """Liquid water content [g/m^3] of :attr:`number` droplets per cm^3 (water 1 g/cm^3)."""
        return self.number * 4.0 / 3.0 * math.pi * self.moment(3.0) * 1e-6


#: Named fogs (see module): ``radiation`` and ``advection`` (Shettle & Fenn 1979, table 3)
DROPLET_PRESETS: dict[str, GammaDroplets] = {
    "radiation": GammaDroplets(
        r_eff=3.0, v_eff=1.0 / 9.0, number=200.0, label="moderate radiation fog (Shettle & Fenn 1979)"
    ),
    "advection": GammaDroplets(
        r_eff=20.0, v_eff=1.0 / 6.0, number=20.0, label="heavy advection fog (Shettle & Fenn 1979)"
    ),
}


def droplet_preset(name: str, src: str = "<droplets>") -> GammaDroplets:
    """The named droplet distribution of :data:`DROPLET_PRESETS`.

    >>> droplet_preset("advection").mode_radius
    10.0
    >>> droplet_preset("drizzle", "<doc>")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: <doc>: parameter 'droplets': 'drizzle' is not one of advection, radiation
    """
    if name not in DROPLET_PRESETS:
        raise ParameterError(src, "droplets", f"'{name}' is not one of {', '.join(sorted(DROPLET_PRESETS))}")
    return DROPLET_PRESETS[name]
