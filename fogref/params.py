"""fogref's one parameter validator: numbers, integers, angles, RGB, vectors, paths and choices.

Every door of fogref (command-line options, ``--set``, ``--param``, sweep files, scene
XML values and API arguments) checks its values with these functions, so one value gets
one message wherever it comes in.  Each returns the value converted (``float``, ``int``,
a tuple, a :class:`~pathlib.Path` or the chosen string) or raises
:class:`fogref.errors.ParameterError` naming the source, the parameter, the value and
what is allowed: the range with its unit, or the options with a did-you-mean.

Refused everywhere: NaN and infinities, ``True``/``False`` where a number is expected,
strings that do not parse, and values outside the range.  Ranges are written as in
mathematics: ``[0, 1]`` closed, ``(-1, 1)`` open, ``[0, inf)`` unbounded above.

This module imports only :mod:`fogref.errors` and the standard library, so every floor
may use it.

Examples
--------
>>> number("0.5", "g", source="scene.xml", lo=-1, hi=1, lo_open=True, hi_open=True)
0.5
>>> number(1.5, "g", source="scene.xml", lo=-1, hi=1, lo_open=True, hi_open=True)
Traceback (most recent call last):
...
fogref.errors.ParameterError: scene.xml: parameter 'g': 1.5 is outside (-1, 1)
>>> rgb("0.2, 0.3 0.5", "sky_radiance", source="<flags>", lo=0)
(0.2, 0.3, 0.5)
"""

from __future__ import annotations

import math
import numbers
import os
from pathlib import Path

from fogref.errors import ParameterError, did_you_mean

__all__ = [
    "angle",
    "choice",
    "format_number",
    "format_range",
    "integer",
    "number",
    "number_within",
    "path",
    "rgb",
    "vector",
]

INF = math.inf


def format_number(x) -> str:
    """A bound or value as short text: integers without a decimal point, ``inf``, else ``%g``.

    >>> [format_number(x) for x in (1e6, 0.0, -0.999, -math.inf, 1.0e-7, 0.1 + 0.2)]
    ['1000000', '0', '-0.999', '-inf', '1e-07', '0.30000000000000004']
    """
    x = float(x)
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    if x.is_integer() and abs(x) < 1e16:
        return str(int(x))
    short = f"{x:g}"
    return short if float(short) == x else repr(x)


def format_range(lo=-INF, hi=INF, lo_open=False, hi_open=False, unit="") -> str:
    """The allowed interval as text, with its unit: ``[0, 1]``, ``(-1, 1)``, ``[0, inf) m``.

    An infinite end is always open.

    >>> format_range(0, 1), format_range(-1, 1, True, True), format_range(0, unit="1/m")
    ('[0, 1]', '(-1, 1)', '[0, inf) 1/m')
    >>> format_range()
    '(-inf, inf)'
    """
    left = "(" if lo_open or math.isinf(lo) else "["
    right = ")" if hi_open or math.isinf(hi) else "]"
    return f"{left}{format_number(lo)}, {format_number(hi)}{right}" + (f" {unit}" if unit else "")


def _show(value) -> str:
    """``value`` as the user wrote it: strings quoted, numbers short."""
    if isinstance(value, str):
        return repr(value)
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        return format_number(value) if math.isfinite(float(value)) else str(float(value))
    return repr(value)


def _is_bool(value) -> bool:
    return isinstance(value, bool) or type(value).__name__ in ("bool", "bool_")  # numpy.bool_ too


def _to_float(value, name: str, source: str, what: str = "a number") -> float:
    """``value`` (a real number or a string that parses as one) as a float; not a bool."""
    if type(value) is float:  # the common case, before the slower checks below
        return value
    if _is_bool(value):
        raise ParameterError(source, name, f"{value!r} is not {what} (a bool)")
    if isinstance(value, str):
        try:
            return float(value.strip())
        except ValueError:
            raise ParameterError(source, name, f"{value!r} does not parse as {what}") from None
    if isinstance(value, numbers.Real) or (hasattr(value, "__float__") and getattr(value, "ndim", 0) == 0):
        try:
            return float(value)
        except (TypeError, ValueError, OverflowError):
            pass
    raise ParameterError(source, name, f"expected {what}, got {value!r}")


def _in_range(x: float, lo, hi, lo_open, hi_open) -> bool:
    return (x > lo if lo_open else x >= lo) and (x < hi if hi_open else x <= hi)


def number(
    value,
    name: str,
    *,
    source: str,
    lo: float = -INF,
    hi: float = INF,
    lo_open: bool = False,
    hi_open: bool = False,
    unit: str = "",
) -> float:
    """``value`` as a finite float in the interval from ``lo`` to ``hi`` (open ends where ``*_open``).

    Parameters
    ----------
    value : real number or str
        ``0.5``, ``numpy.float32(0.5)`` or ``"0.5"``; not a bool, NaN or an infinity.
    name, source : str
        The parameter and where it came from (a file, an option list), named in the error.
    lo, hi, lo_open, hi_open : the allowed interval (default: any finite number).
    unit : str
        Shown after the range (``"m"``, ``"1/m"``, ``"deg"``).

    Examples
    --------
    >>> number(2, "falloff", source="s.xml", lo=0)
    2.0
    >>> number("nan", "falloff", source="s.xml", lo=0, unit="1/m")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: s.xml: parameter 'falloff': nan is not finite: ... in [0, inf) 1/m
    >>> number(True, "g", source="api")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: api: parameter 'g': True is not a number (a bool)
    >>> number("abc", "--sky-distance", source="fogref compare", lo=0, lo_open=True, unit="m")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: fogref compare: parameter '--sky-distance': 'abc' does not parse as a number
    >>> number(-1, "--sky-distance", source="fogref compare", lo=0, lo_open=True, unit="m")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: fogref compare: parameter '--sky-distance': -1 is outside (0, inf) m
    """
    x = _to_float(value, name, source)
    if math.isfinite(x) and _in_range(x, lo, hi, lo_open, hi_open):
        return x
    rng = format_range(lo, hi, lo_open, hi_open, unit)  # the error's text only
    if not math.isfinite(x):
        raise ParameterError(source, name, f"{_show(x)} is not finite: must be a finite number in {rng}")
    shown = _show(value if not isinstance(value, str) else x)
    raise ParameterError(source, name, f"{shown} is outside {rng}")


def number_within(value, name: str, *, source: str, bounds) -> float:
    """:func:`number` with the interval and unit of ``bounds``: any object with the attributes
    ``lo``, ``hi``, ``lo_open``, ``hi_open`` and ``unit`` (a declared option's check, a spec).

    >>> from types import SimpleNamespace
    >>> b = SimpleNamespace(lo=0.0, hi=1.0, lo_open=False, hi_open=True, unit="")
    >>> number_within("0.25", "albedo", source="api", bounds=b)
    0.25
    >>> number_within(1, "albedo", source="api", bounds=b)
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: api: parameter 'albedo': 1 is outside [0, 1)
    """
    keys = ("lo", "hi", "lo_open", "hi_open", "unit")
    return number(value, name, source=source, **{k: getattr(bounds, k) for k in keys})


def angle(value, name: str, *, source: str, unit: str = "deg", **bounds) -> float:
    """An angle (default unit degrees): :func:`number` with ``unit="deg"``; ``bounds``: its ``lo``,
    ``hi``, ``lo_open``, ``hi_open``.

    >>> angle("8", "sun_elevation", source="--set", lo=-90, hi=90)
    8.0
    >>> angle(1000, "sun_elevation", source="--set", lo=-90, hi=90)
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: --set: parameter 'sun_elevation': 1000 is outside [-90, 90] deg
    """
    return number(value, name, source=source, unit=unit, **bounds)


def integer(value, name: str, *, source: str, lo: float = -INF, hi: float = INF, unit: str = "") -> int:
    """``value`` as an int in ``[lo, hi]``: an int, an integral float or a string of one; not a bool.

    >>> integer("64", "--spp", source="fogref render", lo=1, hi=1 << 20)
    64
    >>> integer(36.0, "resy", source="api", lo=1)
    36
    >>> integer(16.7, "res", source="api", lo=1, unit="pixels")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: api: parameter 'res': 16.7 is not an integer: ... [1, inf) pixels
    >>> integer(0, "--workers", source="fogref sweep", lo=1)
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: fogref sweep: parameter '--workers': 0 is outside [1, inf) (an integer)
    """
    rng = format_range(lo, hi, unit=unit)
    if _is_bool(value):
        raise ParameterError(source, name, f"{value!r} is not an integer (a bool)")
    if isinstance(value, numbers.Integral):
        n = int(value)
    else:
        if isinstance(value, str):
            try:
                n = int(value.strip())
                x = float(n)
            except ValueError:
                x = _to_float(value, name, source, "an integer")
                n = None
        else:
            x = _to_float(value, name, source, "an integer")
            n = None
        if n is None:
            if not (math.isfinite(x) and x.is_integer()):
                raise ParameterError(
                    source, name, f"{_show(x)} is not an integer: must be an integer in {rng}"
                )
            n = int(x)
    if not lo <= n <= hi:
        raise ParameterError(source, name, f"{n} is outside {rng} (an integer)")
    return n


def _parts(value, name: str, source: str, what: str) -> list:
    """The items of a number, a sequence or a string ``"a, b c"``."""
    if isinstance(value, str):
        return value.replace(",", " ").split()
    if isinstance(value, (numbers.Real, bool)) or getattr(value, "ndim", 1) == 0:
        return [value]
    try:
        return list(value)
    except TypeError:
        raise ParameterError(source, name, f"expected {what}, got {value!r}") from None


def vector(
    value, name: str, *, source: str, n: int = 3, lo: float = -INF, hi: float = INF, unit: str = ""
) -> tuple[float, ...]:
    """``n`` finite numbers (a sequence or ``"x, y, z"``), each in ``[lo, hi]``.

    >>> vector("0, 2, 0", "camera_origin", source="api", unit="m")
    (0.0, 2.0, 0.0)
    >>> vector([1, 2], "camera_origin", source="api")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: api: parameter 'camera_origin': expected 3 numbers, got 2 ([1, 2])
    """
    items = _parts(value, name, source, f"{n} numbers")
    if len(items) != n:
        raise ParameterError(source, name, f"expected {n} numbers, got {len(items)} ({value!r})")
    return _each(items, value, name, source, lo, hi, unit, "each component")


def _each(items, value, name, source, lo, hi, unit, which) -> tuple[float, ...]:
    xs = tuple(_to_float(x, name, source) for x in items)
    if all(math.isfinite(x) and lo <= x <= hi for x in xs):
        return xs
    shown = "(" + ", ".join(_show(x) for x in xs) + ")"
    rng = format_range(lo, hi, unit=unit)
    why = "is not finite" if not all(math.isfinite(x) for x in xs) else "is outside"
    raise ParameterError(source, name, f"{shown} {why}: {which} must be a finite number in {rng}")


def rgb(value, name: str, *, source: str, lo: float = -INF, hi: float = INF, unit: str = "") -> tuple:
    """An RGB triple from 3 numbers or 1 (broadcast), a sequence or ``"r, g b"``; each in ``[lo, hi]``.

    >>> rgb(0.5, "albedo", source="api", lo=0, hi=1)
    (0.5, 0.5, 0.5)
    >>> rgb([-0.18, 0.3, 0.5], "--sky", source="fogref fit", lo=0)
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: fogref fit: parameter '--sky': (-0.18, 0.3, 0.5) is outside: ... [0, inf)
    >>> rgb("1 2", "albedo", source="api")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: api: parameter 'albedo': expected 1 or 3 numbers, got 2 ('1 2')
    """
    items = _parts(value, name, source, "1 or 3 numbers")
    if len(items) == 1:
        items = items * 3
    if len(items) != 3:
        raise ParameterError(source, name, f"expected 1 or 3 numbers, got {len(items)} ({value!r})")
    return _each(items, value, name, source, lo, hi, unit, "each of R, G, B")


def choice(value, name: str, options, source: str) -> str:
    """``value`` if it is one of ``options``; else the options and a did-you-mean.

    >>> choice("box", "--pixel-filter", ("centre", "box"), "fogref render")
    'box'
    >>> choice("scalar_rgb", "--variant", ("llvm_ad_rgb", "cuda_ad_rgb"), "fogref render")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: fogref render: parameter '--variant': 'scalar_rgb' is not one of ...
    """
    options = tuple(options)
    if isinstance(value, str) and value in options:
        return value
    raise ParameterError(
        source,
        name,
        f"{value!r} is not one of {', '.join(map(str, options))}"
        f"{did_you_mean(str(value), [str(o) for o in options])}",
    )


def path(value, name: str, *, source: str, must_exist: bool = False, kind: str = "file") -> Path:
    """``value`` (a str or os.PathLike, not empty) as a Path; with ``must_exist``, an existing
    ``kind`` (``"file"``, ``"dir"`` or ``"any"``).

    >>> path("scenes/valley.xml", "scene", source="fogref render").as_posix()
    'scenes/valley.xml'
    >>> path("", "--out", source="fogref render")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: fogref render: parameter '--out': an empty path
    >>> path("no/such.xml", "scene", source="fogref render", must_exist=True)
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: fogref render: parameter 'scene': 'no/such.xml': no such file
    """
    if not isinstance(value, (str, os.PathLike)):
        raise ParameterError(source, name, f"expected a path, got {value!r}")
    if not str(value).strip():
        raise ParameterError(source, name, "an empty path")
    p = Path(value)
    if must_exist:
        ok = {"file": p.is_file, "dir": p.is_dir, "any": p.exists}[kind]()
        if not ok:
            what = {"file": "file", "dir": "folder", "any": "file or folder"}[kind]
            there = " (it is a folder)" if kind == "file" and p.is_dir() else ""
            raise ParameterError(source, name, f"{str(value)!r}: no such {what}{there}")
    return p
