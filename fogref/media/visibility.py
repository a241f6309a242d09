"""Visibility (meteorological optical range) and extinction: Koschmieder's law.

A black object seen against the horizon sky through fog of uniform extinction
``sigma`` [1/m] keeps the contrast ``exp(-sigma V)`` at distance ``V``; the
visibility is the distance where that contrast falls to the threshold ``eps``::

    sigma = -ln(eps) / V

``eps = 0.02`` (Koschmieder 1924; Bevy's ``FogFalloff::from_visibility``) gives
``3.912 / V``; the WMO's meteorological optical range uses ``eps = 0.05``
(WMO-No. 8, *Guide to Instruments and Methods of Observation*, 2018, vol. I,
ch. 9), ``2.996 / V``.  The extinction is that of the fog at the observer's height
(a uniform horizontal path); for green light (the eye's, 550 nm).
"""

from __future__ import annotations

import math

from fogref.errors import ParameterError

__all__ = ["KOSCHMIEDER_CONTRAST", "WMO_CONTRAST", "extinction_from_visibility", "visibility_from_extinction"]

#: Koschmieder's contrast threshold (2 %): ``sigma = 3.912 / V``
KOSCHMIEDER_CONTRAST = 0.02
#: The WMO's threshold for the meteorological optical range (5 %): ``sigma = 2.996 / V``
WMO_CONTRAST = 0.05


def _check(src: str, name: str, value: float, lo: float, hi: float, unit: str) -> float:
    v = float(value)
    if not (math.isfinite(v) and lo < v <= hi):
        raise ParameterError(src, name, f"value {value} outside ({lo}, {hi}] {unit}".rstrip())
    return v


def extinction_from_visibility(
    visibility_m: float, contrast: float = KOSCHMIEDER_CONTRAST, src: str = "<visibility>"
) -> float:
    """Extinction [1/m] of fog with visibility ``V`` [m] (0 < V <= 1e6) at the contrast
    threshold ``eps`` (0 < eps < 1): ``-ln(eps) / V``.

    >>> round(extinction_from_visibility(1000.0), 6)
    0.003912
    >>> round(extinction_from_visibility(1000.0, WMO_CONTRAST), 6)
    0.002996
    """
    V = _check(src, "visibility", visibility_m, 0.0, 1e6, "m")
    eps = _check(src, "contrast", contrast, 0.0, 1.0 - 1e-12, "")
    return -math.log(eps) / V


def visibility_from_extinction(
    sigma_per_m: float, contrast: float = KOSCHMIEDER_CONTRAST, src: str = "<visibility>"
) -> float:
    """Visibility [m] of fog with extinction ``sigma`` [1/m] (0 < sigma <= 1e3):
    ``-ln(eps) / sigma``, the inverse of :func:`extinction_from_visibility`.

    >>> round(visibility_from_extinction(0.0391202), 1)
    100.0
    """
    s = _check(src, "sigma_t", sigma_per_m, 0.0, 1e3, "1/m")
    eps = _check(src, "contrast", contrast, 0.0, 1.0 - 1e-12, "")
    return -math.log(eps) / s
