"""The fog a user gives ``fogref scene``, in physical units: checked parameters of a ``heightfog``.

:func:`fog_from_physical` validates extinction, falloff, heights, a second layer
and box bounds (y-up, metres) plus albedo and the Henyey-Greenstein ``g``, and
returns the ``heightfog`` XML parameters.  ``_check`` and ``_numbers`` are the
scene writer's validators (every value is finite and in its documented range;
bad input is one :class:`~fogref.errors.ParameterError` line naming the parameter,
its command-line option and the range); ``_fmt`` writes a float as the shortest
text that reads back to the same float64.
"""

from __future__ import annotations

import math

from fogref.errors import ParameterError
from fogref.media.params import medium_from_params
from fogref.models.ue4 import unreal_to_sigma

__all__ = ["PHYSICAL", "SCATTERING", "SOURCE", "fog_from_physical"]

#: Where messages say a bad value came from.
SOURCE = "fogref scene"

#: Physical fog parameters: name -> (command-line option, kind, lo, hi, unit).
PHYSICAL = {
    "sigma_t": ("--sigma-t", "rgb", 0.0, 1e2, "1/m"),
    "density": ("--density", "number", 0.0, 1e6, "relative"),
    "falloff": ("--falloff", "number", 0.0, 1e3, "1/m"),
    "height": ("--height", "number", -1e7, 1e7, "m"),
    "density2": ("--density2", "number", 0.0, 1e6, "relative to sigma_t"),
    "falloff2": ("--falloff2", "number", 0.0, 1e3, "1/m"),
    "height2": ("--height2", "number", -1e7, 1e7, "m"),
    "bounds_min": ("--bounds-min", "point", -1e7, 1e7, "m"),
    "bounds_max": ("--bounds-max", "point", -1e7, 1e7, "m"),
}
#: Shared by both fog inputs (Unreal has neither).
SCATTERING = {
    "albedo": ("--albedo", "rgb", 0.0, 1.0, ""),
    "g": ("--g", "number", -0.999, 0.999, ""),
}


def _label(name: str, option: str | None) -> str:
    return f"{name} ({option})" if option else name


def _range(lo: float, hi: float, unit: str) -> str:
    return f"[{lo:g}, {hi:g}]" + (f" {unit}" if unit else "")


def _numbers(value, name: str, option: str | None, counts: tuple) -> list[float]:
    """1 or 3 finite numbers from a number, a sequence or a string ``"a, b, c"``."""
    label = _label(name, option)
    if isinstance(value, str):
        parts = value.replace(",", " ").split()
    elif isinstance(value, (int, float)) and not isinstance(value, bool):
        parts = [value]
    else:
        try:
            parts = list(value)
        except TypeError:
            raise ParameterError(SOURCE, label,
                                 f"expected a number or {counts[-1]} numbers, got {value!r}") from None
    try:
        nums = [float(x) for x in parts]
    except (TypeError, ValueError):
        raise ParameterError(SOURCE, label, f"expected numbers, got {value!r}") from None
    if len(nums) not in counts:
        want = " or ".join(str(c) for c in counts)
        raise ParameterError(SOURCE, label, f"expected {want} number(s), got {len(nums)} ({value!r})")
    if not all(math.isfinite(x) for x in nums):
        raise ParameterError(SOURCE, label, f"values {nums} must be finite")
    return nums


def _check(value, name: str, option: str | None, kind: str, lo: float = -math.inf, hi: float = math.inf,
           unit: str = ""):
    """A validated number (kind "number"), grey or RGB value ("rgb": a float for 1 value,
    a list for 3) or 3-vector ("point", a list), each component in [lo, hi]."""
    counts = {"number": (1,), "rgb": (1, 3), "point": (3,)}[kind]
    nums = _numbers(value, name, option, counts)
    for x in nums:
        if not lo <= x <= hi:
            shown = nums[0] if kind == "number" else nums
            raise ParameterError(SOURCE, _label(name, option),
                                 f"value {shown} outside {_range(lo, hi, unit)}")
    return nums[0] if kind == "number" or (kind == "rgb" and len(nums) == 1) else nums


def _rgb3(v) -> list:
    return list(v) if isinstance(v, list) else [v] * 3


def _fmt(x: float) -> str:
    """A float as the shortest text that reads back to the same float64."""
    x = float(x)
    return repr(0.0 if x == 0 else x)


def _vec(v) -> str:
    return ", ".join(_fmt(x) for x in v)

def fog_from_physical(fog: dict | None = None, *, albedo=0.9, g: float = 0.6) -> dict:
    """The ``heightfog`` parameters of a fog given in physical units, validated.

    Parameters
    ----------
    fog : dict, optional
        ``sigma_t`` [1/m] (1 grey or 3 RGB values, 0..1e2; extinction at ``height``),
        ``falloff`` [1/m] (0..1e3), ``height`` [m], ``density`` (relative, default 1),
        an optional second layer ``density2`` (relative to ``sigma_t``; 0 = none),
        ``falloff2`` [1/m], ``height2`` [m], and optional box bounds ``bounds_min``,
        ``bounds_max`` (3 values each [m], both or none). Missing values take the
        shipped valley's fog (Unreal's FogDensity 0.02, FogHeightFalloff 0.2 at 0 m).
    albedo : float or 3 floats
        Single-scattering albedo in [0, 1].
    g : float
        Henyey-Greenstein asymmetry in [-0.999, 0.999].

    Returns
    -------
    dict
        XML parameter name -> value (floats, lists of floats): ``sigma_t``, ``albedo``,
        ``g``, ``density``, ``falloff``, ``fog_height``, ``density2``, ``falloff2``,
        ``height2`` and, when given, ``bounds_min``, ``bounds_max``.

    Raises
    ------
    fogref.errors.ParameterError
        Naming the parameter, its command-line option and the allowed range.

    Examples
    --------
    >>> p = fog_from_physical({"sigma_t": [0.001, 0.002, 0.003], "falloff": 0.05, "height": 10})
    >>> p["sigma_t"], p["falloff"], p["fog_height"], p["density2"]
    ([0.001, 0.002, 0.003], 0.05, 10.0, 0.0)
    >>> fog_from_physical({"falloff": -1})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: fogref scene: parameter 'falloff (--falloff)': value -1.0 outside ...
    """
    fog = dict(fog or {})
    unknown = sorted(set(fog) - set(PHYSICAL) - set(SCATTERING))
    if unknown:
        raise ParameterError(SOURCE, unknown[0],
                             f"not a physical fog parameter; known: {', '.join(PHYSICAL)}")
    albedo = fog.pop("albedo", albedo)
    g = fog.pop("g", g)
    sigma0, falloff0 = unreal_to_sigma(0.02, 0.2)  # the shipped valley's fog
    defaults = {"sigma_t": sigma0, "density": 1.0, "falloff": falloff0, "height": 0.0,
                "density2": 0.0, "falloff2": 0.002, "height2": 100.0}
    out = {}
    for name, (opt, kind, lo, hi, unit) in PHYSICAL.items():
        v = fog.get(name, defaults.get(name))
        if v is not None:
            out[name] = _check(v, name, opt, kind, lo, hi, unit)
    out["albedo"] = _check(albedo, "albedo", SCATTERING["albedo"][0], "rgb", 0.0, 1.0)
    out["g"] = _check(g, "g", SCATTERING["g"][0], "number", -0.999, 0.999)
    if ("bounds_min" in out) != ("bounds_max" in out):
        missing = "bounds_max" if "bounds_min" in out else "bounds_min"
        raise ParameterError(SOURCE, _label(missing, PHYSICAL[missing][0]), "give both bounds or none")
    if "bounds_min" in out and not all(a < b for a, b in zip(out["bounds_min"], out["bounds_max"])):
        raise ParameterError(SOURCE, _label("bounds_max", "--bounds-max"),
                             f"{out['bounds_max']} must exceed bounds_min {out['bounds_min']} on every axis")
    out["fog_height"] = out.pop("height")
    _check_medium(out)
    return out


def _medium_params(fog: dict) -> dict:
    """``heightfog`` XML parameter names (``height`` for ``fog_height``)."""
    p = {k: v for k, v in fog.items() if k != "fog_height"}
    p["height"] = fog["fog_height"]
    return p


def _check_medium(fog: dict) -> None:
    """The medium parser that ``fogref render`` uses must accept the values too."""
    medium_from_params(_medium_params(fog), f"{SOURCE}: fog")


def _text(v) -> str:
    return _vec(v) if isinstance(v, list) else _fmt(v)

