"""The TOML values of a sweep file, checked: numbers, integers and booleans through
:mod:`fogref.params`, tables with their allowed keys, and the one-line errors that name the
file and the table (``SWEEP.toml: [render]``).
"""

from __future__ import annotations

from pathlib import Path

from fogref import params as P
from fogref.errors import FogrefError, ParameterError, did_you_mean


def err(path, key, msg) -> FogrefError:
    """The one-line error of a sweep file: ``"SWEEP.toml: [key]: msg"`` (no key: the file alone)."""
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


def src_of(path, key) -> str:
    """The source named in a ParameterError: ``"SWEEP.toml: [render]"``."""
    return f"{path}: [{key}]"


def _typed(v, name: str, src: str, what: str = "a number"):
    """``v`` unless it is a TOML string or boolean where a number is expected
    (``seed = "x"``, ``n = true``)."""
    if isinstance(v, (str, bool)):
        raise ParameterError(src, name, f"{v!r} is not {what} (write a TOML number, without quotes)")
    return v


def number(v, name: str, src: str, **kw) -> float:
    """A TOML number through :func:`fogref.params.number`."""
    return P.number(_typed(v, name, src), name, source=src, **kw)


def integer(v, name: str, src: str, **kw) -> int:
    """A TOML integer through :func:`fogref.params.integer`."""
    return P.integer(_typed(v, name, src, "an integer"), name, source=src, **kw)


def boolean(v, name: str, src: str) -> bool:
    """A TOML boolean (``true``/``false``), else a ParameterError naming ``src`` and ``name``."""
    if not isinstance(v, bool):
        raise ParameterError(src, name, f"{v!r} is not true or false")
    return v


def read_table(path: Path, doc: dict, name: str, allowed) -> dict:
    """``[name]`` of the parsed ``doc`` (``{}`` if absent); refused if not a table or a key is not allowed."""
    t = doc.get(name, {})
    if not isinstance(t, dict):
        raise err(path, name, "must be a table")
    bad = set(t) - set(allowed)
    if bad:
        raise err(
            path,
            name,
            f"unknown key(s) {sorted(bad)}{did_you_mean(sorted(bad)[0], allowed)}; "
            f"allowed: {sorted(allowed)}",
        )
    return t
