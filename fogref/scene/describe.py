"""Describe a fogref XML scene: its fog, sun, sky, integrator and camera, validated, as plain data.

Scenes are ordinary Mitsuba 3 XML (y-up, metres).  The fog is the sensor's
``<medium type="heightfog">``; the sun is a ``directional`` emitter (its
``direction`` is the direction light travels, i.e. *away* from the sun); the sky
is a ``constant`` (or ``envmap``) emitter, or Mitsuba's ``sunsky`` (split into a sky
and a sun by :mod:`fogref.render.sunsky`, which needs Mitsuba, so the loader hands its
lowering in).  Everything here reads the parsed tree of a
:class:`~fogref.scene.parsed.ParsedScene`; no Mitsuba.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from pathlib import Path

from fogref import params as P
from fogref.errors import FogrefError, ParameterError
from fogref.media.params import medium_from_params
from fogref.scene.defaults import substitute
from fogref.scene.parsed import ParsedScene, read_scene
from fogref.scene.sun import sun_direction_from_to_world
from fogref.scene.vocabulary import RANGES


def _value(el, defaults):
    tag = el.tag
    v = substitute(el.get("value", ""), defaults)
    if tag in ("float", "integer"):
        try:
            return float(v)
        except ValueError:
            return v
    if tag == "boolean":
        return v.lower() == "true"
    if tag in ("rgb", "point", "vector", "spectrum"):
        try:
            if v == "" and tag in ("point", "vector"):
                return [float(substitute(el.get(c, "0"), defaults)) for c in "xyz"]
            parts = [float(x) for x in v.replace(",", " ").split()]
        except ValueError:  # left as text: the check of the value names it (fogref.params)
            return v
        return parts * 3 if len(parts) == 1 else parts
    return v


def element_params(el, defaults) -> dict:
    """The named children of ``el`` (``<float name=...>``, ``<rgb>``, ...) as Python values, ``$name``s
    replaced from ``defaults``: numbers as floats, booleans, 3-lists for colours and points, else text."""
    out = {}
    for c in el:
        name = c.get("name")
        if name is None:
            continue
        if c.tag == "texture" and c.get("type") == "rgb":  # <texture type="rgb"><rgb name="value"/>
            inner = c.find("rgb")
            if inner is not None:
                out[name] = _value(inner, defaults)
            continue
        out[name] = _value(c, defaults)
    return out


def phase_params(med, defaults, src: str) -> dict:
    """The heightfog's ``<phase>`` child as medium parameters: an ``hg``'s ``g``, a
    ``fogtabphase``'s table (``{"phase": {...}}``); other phase plugins are refused (the
    ``heightfog`` plugin's rule)."""
    out: dict = {}
    for ph in med.findall("phase"):
        kind, p = ph.get("type"), element_params(ph, defaults)
        if kind == "hg":
            out["g"] = p.get("g", 0.8)  # Mitsuba's hg default
        elif kind == "fogtabphase":
            out["phase"] = {"type": kind, **p}
        else:
            raise ParameterError(src, "phase", f"'{kind}': heightfog takes hg or fogtabphase")
    return out


def _check_sensor_literals(path: Path, root, defaults) -> None:
    """The sensor's ``fov`` and the film's ``width``/``height`` (as written, or via ``$default``s),
    against the vocabulary's ``fov``, ``res`` and ``resy`` ranges."""
    for sensor in root.findall("sensor"):
        p = element_params(sensor, defaults)
        if "fov" in p:
            RANGES["fov"].check(p["fov"], "sensor.fov", str(path))
        film = sensor.find("film")
        size = element_params(film, defaults) if film is not None else {}
        for key, name in (("width", "res"), ("height", "resy")):
            if key in size:
                RANGES[name].check(size[key], f"film.{key}", str(path))


#: Emitters the renderer and the physical description (sun + sky) both handle.
SUPPORTED_EMITTERS = {
    "directional": "the sun",
    "constant": "a uniform sky",
    "envmap": "an environment-map sky",
    "sunsky": "Mitsuba's physical sun and sky (fogref/render/sunsky.py: split into a sky and a sun)",
}


def check_supported(path: Path, root) -> None:
    """Refuse scene features that fogpath or the physical description would ignore.

    Emitters other than one ``directional`` sun and one ``constant``/``envmap``/``sunsky`` sky
    (e.g. point or area lights: the models' physical description has no place for them; a
    ``sunsky`` brings its own sun, so no ``directional`` beside it), media other than the
    sensor's ``heightfog``, and shapes with interior/exterior media.
    """
    counts: dict = {}
    for em in root.iter("emitter"):
        t = em.get("type")
        if t not in SUPPORTED_EMITTERS:
            what = ", ".join(f"'{k}' ({v})" for k, v in SUPPORTED_EMITTERS.items())
            raise FogrefError(
                f"{path}: emitter '{t}' is not supported: fogref's ground truth and its "
                f"physical description take {what}. Express the lights with those"
            )
        kind = "sun" if t == "directional" else "sky"
        if t == "sunsky" and any(e.get("type") == "directional" for e in root.iter("emitter")):
            raise FogrefError(f"{path}: a sunsky brings its own sun: remove the directional emitter")
        counts[kind] = counts.get(kind, 0) + 1
        if counts[kind] > 1:
            raise FogrefError(
                f"{path}: more than one {kind} emitter; fogref takes at most one sun and one sky"
            )
    sensors = root.findall("sensor")
    for med in root.iter("medium"):
        if med.get("type") != "heightfog" or not any(med in list(s) for s in sensors):
            name = med.get("name") or med.get("id") or "unnamed"
            raise FogrefError(
                f"{path}: medium '{med.get('type')}' ({name}):"
                f" fogref supports one 'heightfog' medium inside the <sensor> only"
            )
    for shape in root.iter("shape"):
        if any(
            c.tag == "medium" or (c.tag == "ref" and c.get("name") in ("interior", "exterior")) for c in shape
        ):
            what = shape.get("id") or shape.get("type")
            raise FogrefError(
                f"{path}: shape '{what}' has a medium attached; "
                f"fogpath's fog fills all space outside surfaces (no interfaces)"
            )


def check_renderable(path, root) -> None:
    """Refuse a scene that fogref cannot render as a truth: it needs exactly one ``<sensor>``
    (the truth's camera) holding one ``<medium type="heightfog">`` (the fog; a fog-free truth
    is ``sigma_t`` 0, not a missing medium).

    >>> import xml.etree.ElementTree as ET
    >>> check_renderable("s.xml", ET.fromstring('<scene><sensor type="perspective"/></scene>'))
    Traceback (most recent call last):
    ...
    fogref.errors.FogrefError: s.xml: no fog: fogref renders a <medium type="heightfog"> inside the ...
    """
    sensors = root.findall("sensor")
    if len(sensors) != 1:
        raise FogrefError(
            f"{path}: {len(sensors)} <sensor> elements: fogref renders a truth through exactly "
            f'one camera (one <sensor> with a <medium type="heightfog"> inside it)'
        )
    fogs = [m for m in sensors[0].findall("medium") if m.get("type") == "heightfog"]
    if len(fogs) != 1:
        what = "no fog" if not fogs else f"{len(fogs)} heightfog media"
        raise FogrefError(
            f'{path}: {what}: fogref renders a <medium type="heightfog"> inside the '
            f"<sensor> (exactly one; for a fog-free truth give it sigma_t 0)"
        )


def describe(scene: ParsedScene, sunsky: Callable | None = None) -> dict:
    """Fog, sun, sky and integrator of a parsed fogref scene, validated, as plain data
    (``camera`` None: the loader fills it from Mitsuba's sensor).

    ``sunsky``: how a ``sunsky`` emitter is split into a sky and a sun
    (:func:`fogref.render.sunsky.lower_sunsky`, called on a copy of the tree with the
    scene's defaults and path; it needs Mitsuba); None refuses a sunsky scene.

    Raises :class:`~fogref.errors.ParameterError` naming the file and parameter
    for an out-of-range value (the fog, the sun's irradiance, the sky's radiance, and the
    integrator's ``max_depth``, the sensor's ``fov`` and the film's size as written in the
    XML, against :data:`~fogref.scene.vocabulary.RANGES`; the ``$default``s and overrides
    were checked when the scene was read), :class:`~fogref.errors.FogrefError` for an
    unsupported scene.
    """
    path, root, defaults = scene.path, scene.root, scene.defaults
    check_supported(path, root)
    desc: dict = {
        "scene": path.name,
        "medium": None,
        "sun": None,
        "sky": None,
        "camera": None,
        "integrator": None,
    }
    integ = root.find("integrator")
    if integ is not None:
        desc["integrator"] = {"type": integ.get("type"), **element_params(integ, defaults)}
        if "max_depth" in desc["integrator"]:
            RANGES["max_depth"].check(desc["integrator"]["max_depth"], "integrator.max_depth", str(path))
    _check_sensor_literals(path, root, defaults)
    for med in root.iter("medium"):
        if med.get("type") == "heightfog":
            params = element_params(med, defaults)
            params.update(phase_params(med, defaults, f"{path}: medium"))
            medium_from_params(params, f"{path}: medium '{med.get('id') or med.get('name') or 'heightfog'}'")
            desc["medium"] = params
    for em in root.iter("emitter"):
        t, p = em.get("type"), element_params(em, defaults)
        if t == "directional":
            w = sun_toward(em, defaults, path)
            E = list(P.rgb(p.get("irradiance", [1.0, 1.0, 1.0]), "sun.irradiance", source=str(path), lo=0))
            desc["sun"] = {"direction": w, "irradiance": E}
        elif t in ("constant", "envmap"):
            if isinstance(p.get("radiance"), list) or (isinstance(p.get("radiance"), str) and p["radiance"]):
                P.rgb(p["radiance"], "sky.radiance", source=str(path), lo=0)
            desc["sky"] = {"type": t, **{k: v for k, v in p.items() if not isinstance(v, dict)}}
        elif t == "sunsky":  # the sky (sun removed) and its sun, each once (fogref/render/sunsky.py)
            if sunsky is None:
                raise FogrefError(
                    f"{path}: a sunsky is split into a sky and a sun by Mitsuba: load the scene"
                )
            parts = sunsky(copy.deepcopy(root), defaults, path)
            if parts is not None:
                desc["sky"], desc["sun"] = parts["sky"], parts["sun"]
    if desc["sun"] is not None and "sun_angular_diameter" in defaults:
        desc["sun"]["angular_diameter"] = RANGES["sun_angular_diameter"].check(
            defaults["sun_angular_diameter"], "sun_angular_diameter", str(path)
        )
    return desc


def sun_toward(emitter, defaults: dict, path) -> list[float]:
    """The unit direction toward the sun [world, y-up] of a ``directional`` emitter: minus its
    ``direction`` vector, else minus the light's travel direction of its ``to_world``
    (:func:`fogref.scene.sun.sun_direction_from_to_world`; the shipped scenes' ``$sun_elevation``,
    ``$sun_azimuth``), else +z's opposite (Mitsuba's default travel direction is +z)."""
    p = element_params(emitter, defaults)
    d = p.get("direction")
    if d is not None:
        d = list(P.vector(d, "sun.direction", source=str(path)))
    else:  # oriented by to_world (the shipped scenes: $sun_elevation, $sun_azimuth)
        tw = emitter.find("transform[@name='to_world']")
        d = (
            [0.0, 0.0, 1.0]
            if tw is None
            else [-x for x in sun_direction_from_to_world(tw, lambda s: substitute(s, defaults), str(path))]
        )
    n = math.sqrt(sum(x * x for x in d))
    if n == 0:
        raise FogrefError(f"{path}: the sun's direction is the zero vector")
    return [-x / n for x in d]


def lookat_camera(scene) -> dict | None:
    """The first sensor of a fogref scene (a path or a :class:`~fogref.scene.parsed.ParsedScene`)
    with a ``lookat``, read without Mitsuba, its ``$defaults`` substituted (the one camera reader
    of a scene's XML; a loaded scene's full camera is :func:`fogref.render.load.sensor_camera`):
    ``origin``, ``target``, ``up`` [m, fogref frame], the horizontal field of view ``fov_deg``
    [deg] (a ``fov_axis`` "y" is converted) and ``resolution`` ``[W, H]`` [px].  None without
    such a sensor.

    >>> from fogref.shipped_scenes import scene_path
    >>> c = lookat_camera(scene_path("valley"))
    >>> c["origin"], c["fov_deg"], c["resolution"]
    ((0.0, 2.0, 0.0), 70.0, (320, 180))
    """
    s = scene if isinstance(scene, ParsedScene) else read_scene(scene)
    root, defaults = s.root, s.defaults

    def value(el, kind, name, default):
        node = el.find(f"{kind}[@name='{name}']")
        return substitute(node.get("value"), defaults) if node is not None else default

    def vec(text):
        return tuple(float(x) for x in text.replace(",", " ").split())

    for sensor in root.iter("sensor"):
        la = sensor.find(".//lookat")
        if la is None or not la.get("origin"):
            continue
        film = sensor.find("film")
        res = (
            int(value(film, "integer", "width", 768)) if film is not None else 768,
            int(value(film, "integer", "height", 576)) if film is not None else 576,
        )
        fov = float(value(sensor, "float", "fov", 45.0))
        if value(sensor, "string", "fov_axis", "x") == "y":
            fov = math.degrees(2 * math.atan(math.tan(math.radians(fov) / 2) * res[0] / res[1]))
        return {
            "origin": vec(substitute(la.get("origin"), defaults)),
            "target": vec(substitute(la.get("target", "0, 0, 1"), defaults)),
            "up": vec(substitute(la.get("up", "0, 1, 0"), defaults)),
            "fov_deg": fov,
            "resolution": res,
        }
    return None
