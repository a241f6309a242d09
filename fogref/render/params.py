"""Build a :class:`~fogref.media.FogMedium` from flat scene parameters.

One parser serves the Mitsuba plugin (its ``Properties``) and the XML pre-check
of ``fogref render``, so a bad value gets the same clear message either way:
``<file>: parameter '<name>': value ... outside [lo, hi]``.
"""

from __future__ import annotations

import math

from fogref.errors import ParameterError
from fogref.media import Box, ExpLayer, FogMedium

PROFILES = ("exponential", "homogeneous", "box", "hdrp", "powerlaw")


def _num(params, key, default, src, lo=-math.inf, hi=math.inf):
    v = params.get(key, default)
    try:
        v = float(v)
    except (TypeError, ValueError):
        raise ParameterError(src, key, f"expected a number, got {v!r}") from None
    if not (lo <= v <= hi) or math.isnan(v):
        raise ParameterError(src, key, f"value {v} outside [{lo}, {hi}]")
    return v


def _vec(params, key, src, n=3):
    v = params.get(key)
    if v is None:
        return None
    if isinstance(v, str):
        v = [float(x) for x in v.replace(",", " ").split()]
    if isinstance(v, (int, float)):
        v = [float(v)] * n
    v = [float(x) for x in v]
    if len(v) not in (1, n):
        raise ParameterError(src, key, f"expected {n} values, got {len(v)}")
    return v * n if len(v) == 1 else v


def medium_from_params(params: dict, src: str = "<params>") -> FogMedium:
    """FogMedium from a flat dict (the XML parameter names of ``heightfog``)."""
    profile = str(params.get("profile", "exponential"))
    if profile not in PROFILES:
        raise ParameterError(src, "profile", f"'{profile}' is not one of {PROFILES}")
    sigma_t = _vec(params, "sigma_t", src) or [0.01] * 3
    albedo = _vec(params, "albedo", src) or [0.9] * 3
    g = _num(params, "g", 0.0, src, -0.999, 0.999)
    density = _num(params, "density", 1.0, src, 0.0, 1e6)
    if profile in ("exponential",):
        layers = [ExpLayer(density, _num(params, "falloff", 0.01, src, 0.0, 1e3),
                           _num(params, "height", 0.0, src, -1e7, 1e7))]
        d2 = _num(params, "density2", 0.0, src, 0.0, 1e6)
        if d2 > 0:
            layers.append(ExpLayer(d2, _num(params, "falloff2", 0.01, src, 0.0, 1e3),
                                   _num(params, "height2", 0.0, src, -1e7, 1e7)))
    elif profile in ("homogeneous", "box"):
        layers = [ExpLayer(density, 0.0, 0.0)]
    elif profile == "hdrp":
        from fogref.media.profiles import HDRPLayer

        layers = [HDRPLayer(density, _num(params, "base_height", 0.0, src, -1e7, 1e7),
                            _num(params, "falloff", 0.01, src, 0.0, 1e3))]
    else:
        from fogref.media.profiles import PowerLawLayer

        layers = [PowerLawLayer(density, _num(params, "start", 0.0, src, -1e7, 1e7),
                                _num(params, "end", 100.0, src, -1e7, 1e7),
                                _num(params, "power", 1.0, src, 0.0, 1e3))]
    lo, hi = _vec(params, "bounds_min", src), _vec(params, "bounds_max", src)
    if profile == "box" and (lo is None or hi is None):
        raise ParameterError(src, "bounds_min", "profile 'box' needs bounds_min and bounds_max")
    if (lo is None) != (hi is None):
        raise ParameterError(src, "bounds_max" if hi is None else "bounds_min", "give both bounds or none")
    bounds = Box(tuple(lo), tuple(hi)) if lo is not None else None
    return FogMedium(sigma_t=tuple(sigma_t), albedo=tuple(albedo), g=g, layers=tuple(layers),
                     bounds=bounds, source=src)
