"""The TOML values of a sweep file, checked: numbers, integers and booleans through
:mod:`fogref.params`, tables with their allowed keys, and the one-line errors that name the
file and the table (``SWEEP.toml: [render]``).

>>> src = toml_src("S.toml", "render")
>>> src, toml_num(2, "spp", src, lo=1), toml_int(16, "spp", src), toml_bool(True, "cache", src)
('S.toml: [render]', 2.0, 16, True)
>>> toml_num("2", "spp", src)
Traceback (most recent call last):
fogref.errors.ParameterError: S.toml: [render]: parameter 'spp': '2' is not a number (write a TOML ...)
>>> toml_table(Path("S.toml"), {"render": {"sp": 4}}, "render", ["spp", "seed"])
Traceback (most recent call last):
fogref.errors.FogrefError: S.toml: [render]: unknown key(s) ['sp']; did you mean 'spp'?; ...
"""

from __future__ import annotations

from pathlib import Path

from fogref import params as P
from fogref.errors import FogrefError, ParameterError, did_you_mean


def toml_error(path, key, msg) -> FogrefError:
    """The one-line error about table ``key`` of the sweep file ``path`` (no table: the file)."""
    return FogrefError(f"{path}: [{key}]: {msg}" if key else f"{path}: {msg}")


def as_str(v) -> str:
    """A TOML value as an XML ``$default`` string (lists -> ``"a, b, c"``).

    >>> as_str([1, 2.5, True]), as_str(0.1)
    ('1, 2.5, true', '0.1')
    """
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (list, tuple)):
        return ", ".join(as_str(x) for x in v)
    if isinstance(v, float):
        return repr(v)
    return str(v)


def toml_src(path, key) -> str:
    """The source named in a ParameterError: ``"SWEEP.toml: [render]"``."""
    return f"{path}: [{key}]"


def _typed(v, name: str, src: str, what: str = "a number"):
    """``v`` unless it is a TOML string or boolean where a number is expected
    (``seed = "x"``, ``n = true``)."""
    if isinstance(v, (str, bool)):
        raise ParameterError(src, name, f"{v!r} is not {what} (write a TOML number, without quotes)")
    return v


def toml_num(v, name: str, src: str, **kw) -> float:
    """A TOML number through :func:`fogref.params.number` (``**kw``: its range), not a string."""
    return P.number(_typed(v, name, src), name, source=src, **kw)


def toml_int(v, name: str, src: str, **kw) -> int:
    """A TOML integer through :func:`fogref.params.integer` (``**kw``: its range)."""
    return P.integer(_typed(v, name, src, "an integer"), name, source=src, **kw)


def toml_bool(v, name: str, src: str) -> bool:
    """A TOML boolean; anything else is refused."""
    if not isinstance(v, bool):
        raise ParameterError(src, name, f"{v!r} is not true or false")
    return v


def toml_table(path: Path, doc: dict, name: str, allowed) -> dict:
    """The table ``[name]`` of the parsed ``doc`` (``{}`` when absent), its keys among ``allowed``."""
    t = doc.get(name, {})
    if not isinstance(t, dict):
        raise toml_error(path, name, "must be a table")
    bad = set(t) - set(allowed)
    if bad:
        raise toml_error(
            path,
            name,
            f"unknown key(s) {sorted(bad)}{did_you_mean(sorted(bad)[0], allowed)}; "
            f"allowed: {sorted(allowed)}",
        )
    return t
