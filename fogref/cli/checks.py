"""The checks of command-line options: each converts an option's text to its value through
:mod:`fogref.params` (fogref's one validator) and describes its allowed range for the help.

A field of a command's ``Options`` (:func:`fogref.cli.spec.option`) names its check; a
value the check refuses is a ParameterError naming the option, its value and its range.

Examples
--------
>>> Number(0.0, lo_open=True, unit="m").parse("10", "--sky-distance", "fogref compare")
10.0
>>> Integer(1, 1 << 20).describe()
'an integer in [1, 1048576]'
"""

from __future__ import annotations

import dataclasses
import math

from fogref import params
from fogref.cluster import check_scheduler
from fogref.errors import ParameterError
from fogref.shipped_scenes import resolve_scene

__all__ = [
    "Address",
    "Assignments",
    "Check",
    "Choice",
    "Integer",
    "Number",
    "PathArg",
    "RGB",
    "SceneArg",
    "Text",
    "Vector",
]

INF = math.inf


class Check:
    """Converts an option's text to its value through :mod:`fogref.params`; describes its range."""

    metavar: str | None = None
    #: True: a repeated option's check gets the whole list (to refuse a NAME given twice)
    takes_list: bool = False

    def parse(self, raw, name: str, source: str):
        return raw

    def describe(self) -> str:
        return ""


class Text(Check):
    """Any non-empty text."""

    def parse(self, raw, name, source):
        if not str(raw).strip():
            raise ParameterError(source, name, "an empty value")
        return raw


@dataclasses.dataclass(frozen=True)
class Number(Check):
    """A finite number in a range (:func:`fogref.params.number`)."""

    lo: float = -INF
    hi: float = INF
    lo_open: bool = False
    hi_open: bool = False
    unit: str = ""

    def parse(self, raw, name, source):
        return params.number_within(raw, name, source=source, bounds=self)

    def describe(self):
        if self.lo == -INF and self.hi == INF:
            return f"[{self.unit}]" if self.unit else ""
        return f"in {params.format_range(self.lo, self.hi, self.lo_open, self.hi_open, self.unit)}"


@dataclasses.dataclass(frozen=True)
class Integer(Check):
    """An integer in ``[lo, hi]`` (:func:`fogref.params.integer`)."""

    lo: float = -INF
    hi: float = INF
    unit: str = ""

    def parse(self, raw, name, source):
        return params.integer(raw, name, source=source, lo=self.lo, hi=self.hi, unit=self.unit)

    def describe(self):
        return f"an integer in {params.format_range(self.lo, self.hi, unit=self.unit)}"


@dataclasses.dataclass(frozen=True)
class RGB(Check):
    """1 (grey) or 3 numbers ``R,G,B``, each in ``[lo, hi]`` (:func:`fogref.params.rgb`)."""

    lo: float = -INF
    hi: float = INF
    unit: str = ""
    metavar = "R,G,B"

    def parse(self, raw, name, source):
        return params.rgb(raw, name, source=source, lo=self.lo, hi=self.hi, unit=self.unit)

    def describe(self):
        return f"each of R, G, B in {params.format_range(self.lo, self.hi, unit=self.unit)}"


@dataclasses.dataclass(frozen=True)
class Vector(Check):
    """``n`` numbers, each in ``[lo, hi]`` (:func:`fogref.params.vector`)."""

    n: int = 3
    lo: float = -INF
    hi: float = INF
    unit: str = ""

    def parse(self, raw, name, source):
        return params.vector(raw, name, source=source, n=self.n, lo=self.lo, hi=self.hi, unit=self.unit)

    def describe(self):
        if self.lo == -INF and self.hi == INF:
            return f"[{self.unit}]" if self.unit else ""
        return f"each in {params.format_range(self.lo, self.hi, unit=self.unit)}"


@dataclasses.dataclass(frozen=True)
class Choice(Check):
    """One of ``options`` (:func:`fogref.params.choice`, with a did-you-mean)."""

    options: tuple = ()

    @property
    def metavar(self):
        return "{" + ",".join(self.options) + "}"

    def parse(self, raw, name, source):
        return params.choice(raw, name, self.options, source)

    def describe(self):
        return "one of " + ", ".join(self.options)


@dataclasses.dataclass(frozen=True)
class PathArg(Check):
    """A path (:func:`fogref.params.path`); with ``must_exist`` an existing file or folder.

    ``role``: ``"input"`` (a file the command reads; implied by ``must_exist``) or ``"output"`` (a
    file it writes): before any work, :func:`fogref.cli.spec.check_paths` refuses an output that
    is a folder or one of the inputs.
    """

    must_exist: bool = False
    kind: str = "file"
    role: str = ""

    def parse(self, raw, name, source):
        return str(params.path(raw, name, source=source, must_exist=self.must_exist, kind=self.kind))


@dataclasses.dataclass(frozen=True)
class SceneArg(PathArg):
    """A scene: a path, or the bare name of a shipped scene (:func:`fogref.shipped_scenes.resolve_scene`).

    >>> SceneArg().parse("valley", "--scene", "fogref fit").endswith("valley.xml")
    True
    """

    role: str = "input"

    def parse(self, raw, name, source):
        return str(resolve_scene(super().parse(raw, name, source)))


class Assignments(Check):
    """Repeated ``NAME=VALUE`` options as a dict of strings; a NAME given twice is refused.

    >>> Assignments().parse(["res=64", "title=a=b"], "--set", "fogref render")
    {'res': '64', 'title': 'a=b'}
    >>> Assignments().parse(["spp=4", "spp=8"], "--set", "fogref render")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: fogref render: parameter '--set': 'spp' is given twice ...
    """

    metavar = "NAME=VALUE"
    takes_list = True

    def parse(self, raw, name, source):
        out: dict[str, str] = {}
        for item in raw:
            key, eq, value = str(item).partition("=")
            key = key.strip()
            if not eq or not key:
                raise ParameterError(source, name, f"expected NAME=VALUE, got {item!r}")
            if key in out:
                raise ParameterError(
                    source,
                    name,
                    f"{key!r} is given twice ({key + '=' + out[key]!r}, {item!r}); give each NAME once",
                )
            out[key] = value
        return out


class Address(Check):
    """A Dask scheduler address, checked by :func:`fogref.cluster.check_scheduler` (the one
    definition, which ``fogref render`` and ``fogref sweep`` also apply through the API).

    >>> Address().parse("tcp://10.0.0.5:8786", "--scheduler", "fogref sweep")
    'tcp://10.0.0.5:8786'
    >>> Address().parse("not an address", "--scheduler", "fogref sweep")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: fogref sweep: parameter '--scheduler': 'not an address' is not ...
    """

    def parse(self, raw, name, source):
        return check_scheduler(str(raw), source, name)

    def describe(self):
        return "[PROTOCOL://]HOST[:PORT]"
