"""The fog a user gives ``fogref scene``, in physical units, and the declared range of each value.

:class:`Range` is one value's kind (number, angle, integer, path depth, grey-or-RGB,
point), allowed range and unit, and its check through :mod:`fogref.params` (fogref's
one validator).  :data:`PHYSICAL` and :data:`SCATTERING` declare the fog's values
once; the scene vocabulary's table (:data:`fogref.render.scene_defaults.RANGES`) takes
them from here, so ``fogref scene``, ``fogref render --set`` and a scene's own
``$default`` values are checked against the same ranges.

:func:`fog_from_physical` validates extinction, falloff, heights, a second layer
and box bounds (y-up, metres) plus albedo and the Henyey-Greenstein ``g``, and
returns the ``heightfog`` XML parameters.  ``_fmt`` writes a float as the shortest
text that reads back to the same float64.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Any

from fogref import params
from fogref.errors import ParameterError
from fogref.media import local_fog_volume as lfv
from fogref.media.params import medium_from_params
from fogref.models.ue4 import unreal_to_sigma

__all__ = ["PHYSICAL", "SCATTERING", "SOURCE", "Range", "fog_from_physical"]

#: Where messages say a bad value came from.
SOURCE = "fogref scene"

#: Mitsuba's path depth: -1 (no limit) or 1 .. 2^31 - 1 (fogpath's ``max_depth``, a 32-bit int).
_DEPTH_MAX = (1 << 31) - 1


@dataclass(frozen=True)
class Range:
    """A value's kind, allowed range and unit, declared once, and its check.

    ``kind``: ``"number"``, ``"angle"``, ``"integer"``, ``"depth"`` (an integer in
    ``{-1} U [1, hi]``, -1 meaning no limit), ``"rgb"`` (1 grey or 3 numbers) or
    ``"point"`` (3 numbers).  ``option``: the ``fogref scene`` option that sets it
    (None: none).  Ranges as in :func:`fogref.params.format_range`.

    >>> Range("--fov", "angle", 0, 180, "deg", lo_open=True, hi_open=True).text()
    '(0, 180) deg'
    >>> Range(None, "depth", -1, 8).check("0", "max_depth", "s.xml")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: s.xml: parameter 'max_depth': 0 is outside {-1} U [1, 8] (-1: no limit)
    >>> Range(None, "rgb", 0, 1).check("0.5", "albedo", "s.xml")
    0.5
    >>> Range(None, "rgb", 0).check("1 2 3", "sun_irradiance", "s.xml")
    [1.0, 2.0, 3.0]
    """

    option: str | None
    kind: str
    lo: float = -math.inf
    hi: float = math.inf
    unit: str = ""
    lo_open: bool = False
    hi_open: bool = False

    def text(self) -> str:
        """The allowed values as text: ``[0, 1]``, ``(0, 180) deg``, ``{-1} U [1, 8]``."""
        if self.kind == "depth":
            return f"{{-1}} U {params.format_range(1, self.hi, unit=self.unit)}"
        return params.format_range(self.lo, self.hi, self.lo_open, self.hi_open, self.unit)

    def label(self, name: str) -> str:
        """``name (--option)``: how the writer's messages name the value."""
        return f"{name} ({self.option})" if self.option else name

    def check(self, value: Any, name: str, source: str) -> float | int | list[float]:
        """``value`` converted and checked: a float (number, angle, grey rgb), an int (integer,
        depth) or a list of 3 floats (rgb, point); else a ParameterError naming ``source``,
        ``name``, the value and :meth:`text`."""
        k = self.kind
        if k in ("number", "angle"):
            return params.number_within(value, name, source=source, bounds=self)
        if k == "integer":
            return params.integer(value, name, source=source, lo=self.lo, hi=self.hi, unit=self.unit)
        if k == "depth":
            n = params.integer(value, name, source=source)
            if n != -1 and not 1 <= n <= self.hi:
                raise ParameterError(source, name, f"{n} is outside {self.text()} (-1: no limit)")
            return n
        if k == "point":
            v = params.vector(value, name, source=source, n=3, lo=self.lo, hi=self.hi, unit=self.unit)
            return list(v)
        if k == "rgb":
            if _count(value) == 1:  # grey: one number, shown as given
                one = value if isinstance(value, (str, numbers.Real)) else list(value)[0]
                return params.number(one, name, source=source, lo=self.lo, hi=self.hi, unit=self.unit)
            return list(params.rgb(value, name, source=source, lo=self.lo, hi=self.hi, unit=self.unit))
        raise ValueError(f"unknown kind {k!r}")


def _count(value: Any) -> int:
    """How many numbers ``value`` holds (a number: 1; text ``"a, b c"``: its words)."""
    if isinstance(value, str):
        return len(value.replace(",", " ").split())
    if isinstance(value, numbers.Real) or getattr(value, "ndim", 1) == 0:
        return 1
    return len(list(value))


#: Physical fog parameters (y-up, metres), each declared once.
PHYSICAL = {
    "sigma_t": Range("--sigma-t", "rgb", 0.0, 1e2, "1/m"),
    "density": Range("--density", "number", 0.0, 1e6, "relative"),
    "falloff": Range("--falloff", "number", 0.0, 1e3, "1/m"),
    "height": Range("--height", "number", -1e7, 1e7, "m"),
    "density2": Range("--density2", "number", 0.0, 1e6, "relative to sigma_t"),
    "falloff2": Range("--falloff2", "number", 0.0, 1e3, "1/m"),
    "height2": Range("--height2", "number", -1e7, 1e7, "m"),
    "bounds_min": Range("--bounds-min", "point", -1e7, 1e7, "m"),
    "bounds_max": Range("--bounds-max", "point", -1e7, 1e7, "m"),
    **{  # a Local Fog Volume (fogref.media.local_fog_volume: its ranges)
        "lfv_centre": Range("--lfv-centre", "point", -1e7, 1e7, "m"),
        **{
            f"lfv_{name}": Range(f"--lfv-{name}", "number", lo, hi, unit or "relative", lo_open=lo_open)
            for name, lo, lo_open, hi, unit in lfv.RANGES
        },
    },
}
#: Shared by both fog inputs (Unreal has neither).
SCATTERING = {
    "albedo": Range("--albedo", "rgb", 0.0, 1.0),
    "g": Range("--g", "number", -0.999, 0.999),
}
#: Mitsuba's path depth (the vocabulary's ``max_depth``; fogpath refuses 0).
MAX_DEPTH = Range("--max-depth", "depth", -1, _DEPTH_MAX)


def _check(value: Any, name: str, rng: Range) -> Any:
    """``value`` checked against ``rng`` by the writer (messages name ``name (--option)``)."""
    return rng.check(value, rng.label(name), SOURCE)


def _rgb3(v: Any) -> list:
    return list(v) if isinstance(v, list) else [v] * 3


def _fmt(x: float) -> str:
    """A float as the shortest text that reads back to the same float64."""
    x = float(x)
    return repr(0.0 if x == 0 else x)


def _vec(v: Any) -> str:
    return ", ".join(_fmt(x) for x in v)


def fog_from_physical(fog: dict | None = None, *, albedo: Any = 0.9, g: float = 0.6) -> dict:
    """The ``heightfog`` parameters of a fog given in physical units, validated.

    Parameters
    ----------
    fog : dict, optional
        ``sigma_t`` [1/m] (1 grey or 3 RGB values, 0..1e2; extinction at ``height``),
        ``falloff`` [1/m] (0..1e3), ``height`` [m], ``density`` (relative, default 1),
        an optional second layer ``density2`` (relative to ``sigma_t``; 0 = none),
        ``falloff2`` [1/m], ``height2`` [m], and optional box bounds ``bounds_min``,
        ``bounds_max`` (3 values each [m], both or none), and an optional Local Fog Volume:
        ``lfv_radius`` [m] with ``lfv_centre`` [m], ``lfv_density``, ``lfv_falloff`` [1/m],
        ``lfv_height`` [m] (:class:`~fogref.media.local_fog_volume.LocalFogVolume`; those not
        given take its defaults). Missing values take the shipped valley's fog (Unreal's
        FogDensity 0.02, FogHeightFalloff 0.2 at 0 m).
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
    fogref.errors.ParameterError: fogref scene: parameter 'falloff (--falloff)': -1 is outside [0, 1000] 1/m
    """
    if fog is not None and not isinstance(fog, dict):
        raise ParameterError(SOURCE, "fog", f"expected a dict of physical fog values, got {fog!r}")
    fog = dict(fog or {})
    unknown = sorted(set(fog) - set(PHYSICAL) - set(SCATTERING))
    if unknown:
        raise ParameterError(
            SOURCE, unknown[0], f"not a physical fog parameter; known: {', '.join(PHYSICAL)}"
        )
    albedo = fog.pop("albedo", albedo)
    g = fog.pop("g", g)
    sigma0, falloff0 = unreal_to_sigma(0.02, 0.2)  # the shipped valley's fog
    defaults = {
        "sigma_t": sigma0,
        "density": 1.0,
        "falloff": falloff0,
        "height": 0.0,
        "density2": 0.0,
        "falloff2": 0.002,
        "height2": 100.0,
    }
    out = {}
    for name, rng in PHYSICAL.items():
        v = fog.get(name, defaults.get(name))
        if v is not None:
            out[name] = _check(v, name, rng)
    out["albedo"] = _check(albedo, "albedo", SCATTERING["albedo"])
    out["g"] = _check(g, "g", SCATTERING["g"])
    if ("bounds_min" in out) != ("bounds_max" in out):
        missing = "bounds_max" if "bounds_min" in out else "bounds_min"
        raise ParameterError(SOURCE, PHYSICAL[missing].label(missing), "give both bounds or none")
    if "bounds_min" in out and not all(a < b for a, b in zip(out["bounds_min"], out["bounds_max"])):
        raise ParameterError(
            SOURCE,
            PHYSICAL["bounds_max"].label("bounds_max"),
            f"{out['bounds_max']} must exceed bounds_min {out['bounds_min']} on every axis",
        )
    if "lfv_radius" in out:  # a volume is written whole (its scene $defaults are one group)
        whole = lfv.LocalFogVolume(radius=out["lfv_radius"])
        for name in lfv.PARAMS:
            out.setdefault(name, _check(getattr(whole, name[4:]), name, PHYSICAL[name]))
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


def _text(v: Any) -> str:
    return _vec(v) if isinstance(v, list) else _fmt(v)
