"""A scene's ``$default``s: the one reader of their declarations, values, substitution and use.

Mitsuba 3 scene files declare parameters as ``<default name="NAME" value="TEXT"/>``
and reference them as ``$NAME`` inside attribute values (``value="$sigma_t"``,
``origin="$camera_origin"``); ``mitsuba.load_file(path, NAME=TEXT)`` overrides a
declared value, like ``fogref render --set NAME=TEXT``.  Everything in fogref that
needs a scene's defaults (the scene description, the fit's camera, the sweep's
parameter check, the budget's sun-less renders, the geometry templates) reads them
here, with :mod:`xml.etree.ElementTree`.

A reference is ``$`` followed by the longest run of letters, digits and ``_``
(``$sun_elevation`` names ``sun_elevation``, never ``sun``).

:data:`VOCABULARY` is the one set of names every shipped and written scene
declares; :data:`OPTIONAL_GROUPS` are the names a scene declares only as a whole
group, where the concept applies (a second fog layer, fog bounds, a sky, a
settable surface reflectance).
"""

from __future__ import annotations

import difflib
import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path

from fogref.errors import FogrefError, ParameterError

__all__ = ["OPTIONAL_GROUPS", "VOCABULARY", "check_overrides", "declared", "overrides_used_by", "parse_scene",
           "references", "resolve", "substitute", "used_names", "vocabulary_groups"]

#: ``$NAME`` references in an attribute value.
REFERENCE = re.compile(r"\$([A-Za-z_][A-Za-z0-9_]*)")

#: The ``$default`` names every fogref scene declares (shipped ``scenes/*.xml`` and
#: ``fogref scene``'s output): image, path depth, fog, sun, camera.
VOCABULARY = ("res", "resy", "max_depth",
              "sigma_t", "albedo", "g", "density", "falloff", "fog_height",
              "sun_elevation", "sun_azimuth", "sun_irradiance",
              "camera_origin", "camera_target", "fov")
#: Names a scene declares only all together, where the concept applies: group -> names.
OPTIONAL_GROUPS = {
    "sky": ("sky_radiance",),                            # a uniform sky (none: a black sky)
    "second_layer": ("density2", "falloff2", "height2"),  # a second exponential fog layer
    "bounds": ("bounds_min", "bounds_max"),              # a box the fog is confined to
    "surface": ("reflectance",),                         # one settable diffuse reflectance for all surfaces
}
#: Integer $defaults that size the image.
_RESOLUTION = ("res", "resy")


def parse_scene(path, comments: bool = False) -> ET.Element:
    """The root element of a scene file (with its ``<!-- -->`` comments as elements if ``comments``).

    Raises :class:`~fogref.errors.FogrefError` naming the file when it does not exist
    or is not well-formed XML.
    """
    path = Path(path)
    if not path.is_file():
        raise FogrefError(f"{path}: no such scene file")
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True)) if comments else None
    try:
        return ET.parse(path, parser).getroot()
    except ET.ParseError as e:
        raise FogrefError(f"{path}: malformed XML ({e})") from None


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


def substitute(text: str, values: dict) -> str:
    """``text`` with each ``$NAME`` whose name is in ``values`` replaced by its value.

    A reference to an undeclared name is left as it is (Mitsuba refuses it on load).

    >>> substitute("$camera_origin", {"camera_origin": "0, 2, 0"})
    '0, 2, 0'
    >>> substitute("$sun_elevation", {"sun": "1", "sun_elevation": "8"})
    '8'
    >>> substitute("$unknown", {})
    '$unknown'
    """
    if not text or "$" not in text:
        return text
    return REFERENCE.sub(lambda m: str(values[m.group(1)]) if m.group(1) in values else m.group(0), text)


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
    """The overrides whose ``$NAME`` the scene references (Mitsuba refuses the others).

    >>> root = ET.fromstring('<scene><float name="g" value="$g"/><float name="x" value="$sun"/></scene>')
    >>> overrides_used_by(root, {"g": 0.5, "sun_elevation": 4, "sun": 1})
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
    values = declared(scene)
    where = source if source is not None else (scene if not isinstance(scene, ET.Element) else "scene")
    check_overrides(Path(str(where)), values, overrides)
    values.update({k: str(v) for k, v in (overrides or {}).items()})
    return values


def check_overrides(path: Path, defaults: dict, overrides: dict | None) -> None:
    """Refuse ``--set`` names the scene does not declare and values that don't fit them.

    A name must be one of the scene's ``<default>``s (with a "did you mean");
    a value replacing a numeric default must be numeric (as many numbers as the
    default has); ``res``/``resy`` must be integers in [1, 65536].
    """
    for name, value in (overrides or {}).items():
        if name not in defaults:
            close = difflib.get_close_matches(name, defaults, n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else ""
            raise ParameterError(str(path), name, f"--set {name}={value}: the scene has no $default '{name}'"
                                 f"{hint}; it has: {', '.join(sorted(defaults))}")
        old, new = _numbers(defaults[name]), _numbers(str(value))
        if old is not None and (new is None or len(new) not in (1, len(old))):
            count = f"1 or {len(old)} numbers" if len(old) > 1 else "1 number"
            raise ParameterError(str(path), name, f"--set {name}={value}: expected {count} like the "
                                 f"scene's default '{defaults[name]}'")
        if new is not None and not all(math.isfinite(x) for x in new):
            raise ParameterError(str(path), name, f"--set {name}={value}: values must be finite")
        if name in _RESOLUTION and not (new and float(new[0]).is_integer() and 1 <= new[0] <= 65536):
            raise ParameterError(str(path), name, f"--set {name}={value}: an integer in [1, 65536] pixels")


def _numbers(text: str):
    try:
        return [float(x) for x in text.replace(",", " ").split()] or None
    except ValueError:
        return None


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
