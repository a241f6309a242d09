"""A scene's ``$default``s: the one reader of their declarations, values, substitution and use.

Mitsuba 3 scene files declare parameters as ``<default name="NAME" value="TEXT"/>``
and reference them as ``$NAME`` inside attribute values (``value="$sigma_t"``,
``origin="$camera_origin"``); ``mitsuba.load_file(path, NAME=TEXT)`` overrides a
declared value, like ``fogref render --set NAME=TEXT``.  Everything in fogref that
needs a scene's defaults (the scene description, the files a scene loads, the fit's
camera, the sweep's parameter check, the budget's sun-less renders, the geometry
templates) reads them here, with :mod:`xml.etree.ElementTree`: :func:`parse_scene` is
the one parse of scene XML and :func:`substitute` the one ``$NAME`` substitution
(Mitsuba's rule).

:func:`resolve` checks the scene's own values and every ``--set`` override against the
vocabulary's ranges (:data:`fogref.scene.vocabulary.RANGES`, through
:mod:`fogref.params`), the same table ``fogref scene`` checks what it writes against.
"""

from __future__ import annotations

import difflib
import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path

from fogref import params
from fogref.errors import FogrefError, ParameterError
from fogref.scene.vocabulary import RANGES

__all__ = [
    "check_camera",
    "check_overrides",
    "check_values",
    "declared",
    "overrides_used_by",
    "parse_scene",
    "references",
    "resolve",
    "substitute",
    "used_names",
]

#: ``$NAME`` references in an attribute value.
REFERENCE = re.compile(r"\$([A-Za-z_][A-Za-z0-9_]*)")


def parse_scene(path, comments: bool = False) -> ET.Element:
    """The root element of a scene file (with its ``<!-- -->`` comments as elements if ``comments``):
    the one parse of scene XML in fogref (a scene, its ``<include>``s, the valley template).

    Raises :class:`~fogref.errors.FogrefError` naming the file when it does not exist
    or is not well-formed XML.
    """
    path = params.path(path, "scene", source="fogref")
    if not path.is_file():
        raise FogrefError(f"{path}: no such scene file")
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True)) if comments else None
    try:
        return ET.parse(path, parser).getroot()
    except ET.ParseError as e:
        raise FogrefError(f"{path}: malformed XML ({e})") from None
    except OSError as e:
        raise FogrefError(f"{path}: cannot read ({e.strerror})") from None


def _root(scene) -> ET.Element:
    return scene if isinstance(scene, ET.Element) else parse_scene(scene)


def declared(scene) -> dict[str, str]:
    """The scene's ``<default>`` declarations: name -> value text, in file order.

    ``scene``: a path or a parsed root element.

    >>> root = ET.fromstring('<scene><default name="g" value="0.6"/><default name="res" value="64"/></scene>')
    >>> declared(root)
    {'g': '0.6', 'res': '64'}
    """
    return {d.get("name"): d.get("value", "") for d in _root(scene).iter("default")}


def references(text: str) -> list[str]:
    """The names referenced as ``$NAME`` in an attribute value, in order.

    >>> references("$sun_elevation, $sun")
    ['sun_elevation', 'sun']
    >>> references("0, 1, 0")
    []
    """
    return REFERENCE.findall(text or "")


def substitute(text: str, values) -> str:
    """``text`` with Mitsuba's ``$NAME`` substitution from ``values`` (a dict, or ``[(name, value)]``).

    Mitsuba 3's rule (``src/core/parser.cpp``, ``substitute_parameters``): the longest names
    first, each ``$NAME`` replaced wherever it occurs unless escaped as ``\\$``, which is then
    kept as a literal ``$``.  A reference to an undeclared name is left as it is (Mitsuba
    refuses it on load).

    >>> substitute("$camera_origin", {"camera_origin": "0, 2, 0"})
    '0, 2, 0'
    >>> substitute("$sun_elevation", {"sun": "1", "sun_elevation": "8"})
    '8'
    >>> substitute("$unknown", {})
    '$unknown'
    >>> substitute("$mesh_dir/$mesh.obj", [("mesh", "box"), ("mesh_dir", "meshes")])
    'meshes/box.obj'
    >>> substitute("price \\\\$5", [("5", "x")])
    'price $5'
    """
    if not text or "$" not in text:
        return text
    pairs = values.items() if isinstance(values, dict) else values
    for name, rep in sorted(((str(k), str(v)) for k, v in pairs), key=lambda p: len(p[0]), reverse=True):
        key, pos = "$" + name, 0
        while (pos := text.find(key, pos)) != -1:
            if pos > 0 and text[pos - 1] == "\\":
                pos += len(key)
            else:
                text = text[:pos] + rep + text[pos + len(key) :]
                pos += len(rep)
    return text.replace("\\$", "$")


def used_names(scene) -> set[str]:
    """The names a scene references with ``$NAME`` (outside the ``<default>`` declarations).

    >>> used_names(ET.fromstring('<scene><default name="g" value="0.6"/><default name="res" value="9"/>'
    ...                          '<float name="g" value="$g"/></scene>'))
    {'g'}
    """
    out: set[str] = set()
    for el in _root(scene).iter():
        if el.tag == "default":
            continue
        for v in el.attrib.values():
            out.update(references(v))
    return out


def overrides_used_by(scene, overrides: dict | None) -> dict:
    """The overrides whose ``$NAME`` the scene (a path or a parsed root) references: Mitsuba refuses
    the others, e.g. the sun's ``$default``s given to a sun-less copy
    (:func:`fogref.scene.edit.sunless_scene`).

    >>> root = ET.fromstring('<scene><float name="g" value="$g"/><float name="x" value="$sun"/></scene>')
    >>> overrides_used_by(root, {"g": 0.5, "sun_elevation": 4, "sun": 1})
    {'g': 0.5, 'sun': 1}
    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "s.xml"
    >>> _ = p.write_text(ET.tostring(root, encoding="unicode"))
    >>> overrides_used_by(p, {"g": 0.5, "sun_elevation": 4, "sun": 1})
    {'g': 0.5, 'sun': 1}
    """
    used = used_names(scene)
    return {k: v for k, v in (overrides or {}).items() if k in used}


def resolve(scene, overrides: dict | None = None, source=None) -> dict[str, str]:
    """The scene's ``$default`` values after ``--set``-style ``overrides`` (all as text).

    The overrides are checked first (:func:`check_overrides`; ``source`` names the
    file in messages, default the path).

    >>> root = ET.fromstring('<scene><default name="g" value="0.6"/><default name="res" value="64"/></scene>')
    >>> resolve(root, {"g": 0.2})
    {'g': '0.2', 'res': '64'}
    >>> resolve(root, {"gg": 0.2}, source="s.xml")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: s.xml: parameter 'gg': --set gg=0.2: the scene has no $default 'gg'...
    """
    if overrides is not None and not isinstance(overrides, dict):
        raise ParameterError(
            str(source or "scene"),
            "overrides",
            f"expected a dict of NAME: VALUE (like --set NAME=VALUE), got {overrides!r}",
        )
    values = declared(scene)
    where = source if source is not None else (scene if not isinstance(scene, ET.Element) else "scene")
    check_overrides(Path(str(where)), values, overrides)
    check_values(Path(str(where)), {k: v for k, v in values.items() if k not in (overrides or {})})
    values.update({k: str(v) for k, v in (overrides or {}).items()})
    return values


def check_values(path: Path, values: dict, how: str = "<default>") -> None:
    """Check each vocabulary name of ``values`` against :data:`RANGES` (through :mod:`fogref.params`),
    and the camera (:func:`check_camera`) when both its points are there.

    ``how`` says where the values came from in the message (``<default>``, or ``--set``:
    ``--set NAME=VALUE`` is quoted).

    >>> check_values(Path("s.xml"), {"sun_elevation": "1000", "title": "x"})
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: s.xml: <default>: parameter 'sun_elevation': 1000 is outside [-90, 90] deg
    >>> check_values(Path("s.xml"), {"max_depth": 0}, "--set")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: s.xml: parameter 'max_depth': --set max_depth=0: 0 is outside {-1} U [1, ...
    """
    source = f"{path}: {how}"
    checked = {}
    for name, v in values.items():
        if name not in RANGES:
            continue
        try:
            checked[name] = RANGES[name].check(v, name, source if how != "--set" else str(path))
        except ParameterError as e:
            if how != "--set":
                raise
            why = str(e).split(f"parameter '{name}': ", 1)[-1]
            raise ParameterError(str(path), name, f"--set {name}={v}: {why}") from None
    if "camera_origin" in checked and "camera_target" in checked:
        check_camera(checked["camera_origin"], checked["camera_target"], source)


def check_camera(origin, target, source: str, name: str = "camera_target") -> None:
    """Refuse a camera whose target is its origin or that looks straight up or down (its up is +y).

    >>> check_camera([0, 2, 0], [0, 5, 0], "s.xml")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: s.xml: parameter 'camera_target': the camera looks straight up ...
    """
    d = [float(b) - float(a) for a, b in zip(origin, target)]
    n = math.sqrt(sum(x * x for x in d))
    if n == 0:
        raise ParameterError(source, name, "must differ from camera_origin")
    if math.hypot(d[0], d[2]) <= 1e-9 * n:
        raise ParameterError(
            source,
            name,
            f"the camera looks straight {'up' if d[1] > 0 else 'down'} "
            f"(origin {list(origin)}, target {list(target)}); "
            "the camera's up vector is +y, so tilt the view a little",
        )


def check_overrides(path: Path, defaults: dict, overrides: dict | None) -> None:
    """Refuse ``--set`` names the scene does not declare and values that don't fit them.

    A name must be one of the scene's ``<default>``s (with a "did you mean"); a
    vocabulary name's value must be in its range (:data:`RANGES`, e.g. ``sun_elevation``
    in [-90, 90] deg, ``max_depth`` -1 or >= 1, ``res`` an integer in [1, 65536]
    pixels); any other value replacing a numeric default must be 1 or as many finite
    numbers as the default has.  The camera is checked with its other point from the
    scene when one of the two is set.
    """
    for name, value in (overrides or {}).items():
        if name not in defaults:
            close = difflib.get_close_matches(name, defaults, n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else ""
            raise ParameterError(
                str(path),
                name,
                f"--set {name}={value}: the scene has no $default '{name}'"
                f"{hint}; it has: {', '.join(sorted(defaults))}",
            )
        if name not in RANGES:
            _like_default(defaults[name], value, name, str(path))
    set_ = dict(overrides or {})
    check_values(
        path, {k: v for k, v in set_.items() if k != "camera_origin" and k != "camera_target"}, "--set"
    )
    if "camera_origin" in set_ or "camera_target" in set_:
        cam = {k: set_.get(k, defaults.get(k)) for k in ("camera_origin", "camera_target")}
        check_values(
            path,
            {k: v for k, v in cam.items() if v is not None},
            "--set" if all(k in set_ for k in cam) else "--set and <default>",
        )


def _like_default(default: str, value, name: str, source: str) -> None:
    """A value replacing a numeric default (outside the vocabulary): 1 or as many finite numbers."""
    try:
        old = [float(x) for x in default.replace(",", " ").split()]
    except ValueError:
        return  # a text default: Mitsuba checks it
    words = str(value).replace(",", " ").split()
    if not old:
        return
    try:
        if len(old) == 1 or len(words) == 1:
            params.number(value, name, source=source)
        else:
            params.vector(value, name, source=source, n=len(old))
    except ParameterError as e:
        why = str(e).split(f"parameter '{name}': ", 1)[-1]
        raise ParameterError(
            source, name, f"--set {name}={value}: {why} (like the scene's default '{default}')"
        ) from None
