"""The scene vocabulary: every ``$default`` name of a fogref scene and the declared range of each value.

:class:`Range` is one value's kind (number, angle, integer, path depth, grey-or-RGB,
point), allowed range and unit, and its check through :mod:`fogref.params` (fogref's
one validator).  :data:`VOCABULARY` is the one set of names every shipped and written
scene declares; :data:`OPTIONAL_GROUPS` are the names a scene declares only as a whole
group, where the concept applies (a second fog layer, fog bounds, a sky, a settable
surface reflectance).  :data:`RANGES` declares the kind, range and unit of each of them
once (the fog's from :data:`PHYSICAL` and :data:`SCATTERING`), so ``fogref scene``,
``fogref render --set``, a scene's own ``$default`` values and the mappings are checked
against the same ranges: a new scene option is one entry here.  :func:`float_text` writes a float as the
shortest text that reads back to the same float64.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Any

from fogref import params
from fogref.errors import ParameterError

__all__ = [
    "MAX_DEPTH",
    "OPTIONAL_GROUPS",
    "PHYSICAL",
    "RANGES",
    "SCATTERING",
    "SOURCE",
    "VOCABULARY",
    "Range",
    "check_option",
    "float_text",
    "rgb3",
    "value_text",
    "vector_text",
    "vocabulary_groups",
]

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
}
#: Shared by both fog inputs (Unreal has neither).
SCATTERING = {
    "albedo": Range("--albedo", "rgb", 0.0, 1.0),
    "g": Range("--g", "number", -0.999, 0.999),
}
#: Mitsuba's path depth (the vocabulary's ``max_depth``; fogpath refuses 0).
MAX_DEPTH = Range("--max-depth", "depth", -1, _DEPTH_MAX)

#: The ``$default`` names every fogref scene declares (shipped ``scenes/*.xml`` and
#: ``fogref scene``'s output): image, path depth, fog, sun, camera.
VOCABULARY = (
    "res",
    "resy",
    "max_depth",
    "sigma_t",
    "albedo",
    "g",
    "density",
    "falloff",
    "fog_height",
    "sun_elevation",
    "sun_azimuth",
    "sun_irradiance",
    "camera_origin",
    "camera_target",
    "fov",
)
#: Names a scene declares only all together, where the concept applies: group -> names.
OPTIONAL_GROUPS = {
    "sky": ("sky_radiance",),  # a uniform sky (none: a black sky)
    "second_layer": ("density2", "falloff2", "height2"),  # a second exponential fog layer
    "bounds": ("bounds_min", "bounds_max"),  # a box the fog is confined to
    "surface": ("reflectance",),  # one settable diffuse reflectance for all surfaces
    "turbidity": ("turbidity",),  # a sunsky's atmosphere (fogref/render/sunsky.py)
    "sun_size": ("sun_angular_diameter",),  # the sun's angular diameter (0: a delta)
}
#: The kind, range and unit of every vocabulary name, each declared once (the fog's in
#: :data:`PHYSICAL` and :data:`SCATTERING`).  The options are
#: ``fogref scene``'s.  ``sun_azimuth``: one turn either way; camera points within 1e7 m;
#: ``fov``: the horizontal field of view of a perspective camera.
RANGES: dict[str, Range] = {
    "res": Range("--res", "integer", 1, 65536, "pixels"),
    "resy": Range("--resy", "integer", 1, 65536, "pixels"),
    "max_depth": MAX_DEPTH,
    "sigma_t": PHYSICAL["sigma_t"],
    "albedo": SCATTERING["albedo"],
    "g": SCATTERING["g"],
    "density": PHYSICAL["density"],
    "falloff": PHYSICAL["falloff"],
    "fog_height": PHYSICAL["height"],
    "sun_elevation": Range("--sun-elevation", "angle", -90.0, 90.0, "deg"),
    "sun_azimuth": Range("--sun-azimuth", "angle", -360.0, 360.0, "deg"),
    "sun_irradiance": Range("--sun-irradiance", "rgb", 0.0),
    "camera_origin": Range("--camera-origin", "point", -1e7, 1e7, "m"),
    "camera_target": Range("--camera-target", "point", -1e7, 1e7, "m"),
    "fov": Range("--fov", "angle", 0.0, 180.0, "deg", lo_open=True, hi_open=True),
    "sky_radiance": Range("--sky-radiance", "rgb", 0.0),
    "density2": PHYSICAL["density2"],
    "falloff2": PHYSICAL["falloff2"],
    "height2": PHYSICAL["height2"],
    "bounds_min": PHYSICAL["bounds_min"],
    "bounds_max": PHYSICAL["bounds_max"],
    "reflectance": Range("--ground-reflectance", "rgb", 0.0, 1.0),
    "turbidity": Range("--turbidity", "number", 1.0, 10.0),
    "sun_angular_diameter": Range("--sun-angular-diameter", "number", 0.0, 10.0, "deg"),
}


def vocabulary_groups(names) -> tuple[list[str], list[str]]:
    """Check ``names`` (a scene's declared defaults) against the vocabulary.

    Returns ``(wrong, groups)``: the sorted :data:`VOCABULARY` names absent, the
    absent members of partly declared optional groups and the names outside the
    vocabulary (empty: the scene speaks the vocabulary); and the optional groups it
    declares in full.

    >>> vocabulary_groups(set(VOCABULARY) | {"sky_radiance"})
    ([], ['sky'])
    >>> vocabulary_groups(set(VOCABULARY) - {"fov"} | {"density2", "sun"})
    (['falloff2', 'fov', 'height2', 'sun'], [])
    """
    names = set(names)
    wrong = set(VOCABULARY) - names
    groups = []
    for group, members in OPTIONAL_GROUPS.items():
        present = names & set(members)
        if present == set(members):
            groups.append(group)
        elif present:
            wrong |= set(members) - present
    known = set(VOCABULARY).union(*OPTIONAL_GROUPS.values())
    return sorted(wrong | (names - known)), groups


def check_option(value: Any, name: str, rng: Range) -> Any:
    """``value`` checked against ``rng`` by ``fogref scene`` (messages name ``name (--option)``).

    >>> check_option("2", "fov", RANGES["fov"])
    2.0
    """
    return rng.check(value, rng.label(name), SOURCE)


def rgb3(v: Any) -> list:
    """A grey value as three; three as they are.

    >>> rgb3(0.5), rgb3([1.0, 2.0, 3.0])
    ([0.5, 0.5, 0.5], [1.0, 2.0, 3.0])
    """
    return list(v) if isinstance(v, list) else [v] * 3


def float_text(x: float) -> str:
    """A float as the shortest text that reads back to the same float64 (-0 as 0).

    >>> float_text(-0.0), float_text(2), float_text(0.1)
    ('0.0', '2.0', '0.1')
    """
    x = float(x)
    return repr(0.0 if x == 0 else x)


def vector_text(v: Any) -> str:
    """Numbers as XML text, comma-separated.

    >>> vector_text([1, 0.5, -0.0])
    '1.0, 0.5, 0.0'
    """
    return ", ".join(float_text(x) for x in v)


def value_text(v: Any) -> str:
    """A number or a list of numbers as XML text.

    >>> value_text(0.5), value_text([0.1, 0.2, 0.3])
    ('0.5', '0.1, 0.2, 0.3')
    """
    return vector_text(v) if isinstance(v, list) else float_text(v)
