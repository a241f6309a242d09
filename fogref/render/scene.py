"""Read a fogref XML scene: validate the fog before Mitsuba sees it, load it,
and describe its fog, sun, sky and camera for the EXR header and the studies.

Scenes are ordinary Mitsuba 3 XML (y-up, metres).  The fog is the sensor's
``<medium type="heightfog">``; the sun is a ``directional`` emitter (its
``direction`` is the direction light travels, i.e. *away* from the sun); the sky
is a ``constant`` (or ``envmap``) emitter.
"""

from __future__ import annotations

import copy
import math
import re
from pathlib import Path

import numpy as np

from fogref import params as P
from fogref.errors import FogrefError, ParameterError
from fogref.media.params import medium_from_params
from fogref.render.scene_defaults import RANGES, parse_scene, resolve, substitute
from fogref.render.sun import sun_direction_from_to_world
from fogref.render.variant import set_variant


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


def _params(el, defaults) -> dict:
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


def _phase_params(med, defaults, src: str) -> dict:
    """The heightfog's ``<phase>`` child as medium parameters: an ``hg``'s ``g``, a
    ``fogtabphase``'s table (``{"phase": {...}}``); other phase plugins are refused (the
    ``heightfog`` plugin's rule)."""
    out: dict = {}
    for ph in med.findall("phase"):
        kind, p = ph.get("type"), _params(ph, defaults)
        if kind == "hg":
            out["g"] = p.get("g", 0.8)  # Mitsuba's hg default
        elif kind == "fogtabphase":
            out["phase"] = {"type": kind, **p}
        else:
            raise ParameterError(src, "phase", f"'{kind}': heightfog takes hg or fogtabphase")
    return out


def describe_scene(path, overrides: dict | None = None) -> dict:
    """Fog, sun, sky and camera of a fogref XML scene, validated, as plain data.

    Raises :class:`~fogref.errors.ParameterError` naming the file and parameter
    for an out-of-range value (the ``$default``s and ``overrides`` against
    :data:`~fogref.render.scene_defaults.RANGES`; the fog, the sun's irradiance, the
    sky's radiance, and the integrator's ``max_depth``, the sensor's ``fov`` and the
    film's size as written in the XML), :class:`~fogref.errors.FogrefError` for XML
    that can't be parsed.
    """
    path = P.path(path, "scene", source="fogref")
    root = parse_scene(path)
    defaults = resolve(root, overrides, source=path)
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
        desc["integrator"] = {"type": integ.get("type"), **_params(integ, defaults)}
        if "max_depth" in desc["integrator"]:
            RANGES["max_depth"].check(desc["integrator"]["max_depth"], "integrator.max_depth", str(path))
    _check_sensor_literals(path, root, defaults)
    for med in root.iter("medium"):
        if med.get("type") == "heightfog":
            params = _params(med, defaults)
            params.update(_phase_params(med, defaults, f"{path}: medium"))
            medium_from_params(params, f"{path}: medium '{med.get('id') or med.get('name') or 'heightfog'}'")
            desc["medium"] = params
    for em in root.iter("emitter"):
        t, p = em.get("type"), _params(em, defaults)
        if t == "directional":
            d = p.get("direction")
            if d is not None:
                d = list(P.vector(d, "sun.direction", source=str(path)))
            else:  # oriented by to_world (the shipped scenes: $sun_elevation, $sun_azimuth)
                tw = em.find("transform[@name='to_world']")
                d = (
                    [0.0, 0.0, 1.0]
                    if tw is None
                    else [
                        -x
                        for x in sun_direction_from_to_world(tw, lambda s: substitute(s, defaults), str(path))
                    ]
                )
            n = math.sqrt(sum(x * x for x in d))
            if n == 0:
                raise FogrefError(f"{path}: the sun's direction is the zero vector")
            E = list(P.rgb(p.get("irradiance", [1.0, 1.0, 1.0]), "sun.irradiance", source=str(path), lo=0))
            desc["sun"] = {"direction": [-x / n for x in d], "irradiance": E}
        elif t in ("constant", "envmap"):
            if isinstance(p.get("radiance"), list) or (isinstance(p.get("radiance"), str) and p["radiance"]):
                P.rgb(p["radiance"], "sky.radiance", source=str(path), lo=0)
            desc["sky"] = {"type": t, **{k: v for k, v in p.items() if not isinstance(v, dict)}}
        elif t == "sunsky":  # the sky (sun removed) and its sun, each once (fogref/render/sunsky.py)
            from fogref.render.sunsky import lower_sunsky

            parts = lower_sunsky(copy.deepcopy(root), defaults, path)
            if parts is not None:
                desc["sky"], desc["sun"] = parts["sky"], parts["sun"]
    if desc["sun"] is not None and "sun_angular_diameter" in defaults:
        desc["sun"]["angular_diameter"] = RANGES["sun_angular_diameter"].check(
            defaults["sun_angular_diameter"], "sun_angular_diameter", str(path)
        )
    return desc


def _check_sensor_literals(path: Path, root, defaults) -> None:
    """The sensor's ``fov`` and the film's ``width``/``height`` (as written, or via ``$default``s),
    against the vocabulary's ``fov``, ``res`` and ``resy`` ranges."""
    for sensor in root.findall("sensor"):
        p = _params(sensor, defaults)
        if "fov" in p:
            RANGES["fov"].check(p["fov"], "sensor.fov", str(path))
        film = sensor.find("film")
        size = _params(film, defaults) if film is not None else {}
        for key, name in (("width", "res"), ("height", "resy")):
            if key in size:
                RANGES[name].check(size[key], f"film.{key}", str(path))


def _mitsuba_reason(e: Exception) -> str:
    """Mitsuba's load error on one line: where it happened and, for a plugin that raised, the
    exception it raised (the last line of the traceback Mitsuba embeds)."""
    lines = [x.strip() for x in str(e).strip().splitlines() if x.strip()]
    if not lines:
        return type(e).__name__
    first = re.sub(r"^\[[^\]]*\]\s*", "", lines[0]).replace("Traceback (most recent call last):", "")
    first = first.strip().rstrip(":")
    return f"{first}: {lines[-1]}" if len(lines) > 1 else first


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


def load_scene(path, overrides: dict | None = None):
    """``mi.load_file`` with fogref's plugins registered and errors made readable.

    Sets Mitsuba up first (:func:`fogref.render.variant.set_variant`: the variant
    already set, else ``$FOGREF_VARIANT``, else ``llvm_ad_rgb``).  The scene's values are
    checked first (:func:`describe_scene`, :func:`check_renderable`).
    """
    set_variant()
    import mitsuba as mi

    desc = describe_scene(path, overrides)
    root = parse_scene(path)
    check_renderable(path, root)
    lowered = None
    if any(e.get("type") == "sunsky" for e in root.iter("emitter")):  # sky and sun split, each once
        from fogref.render.sunsky import load_lowered, lower_sunsky

        lower_sunsky(root, resolve(root, overrides, source=path), path)
        lowered = root
    try:
        if lowered is not None:
            scene = load_lowered(path, lowered, overrides)
        else:
            scene = mi.load_file(str(path), parallel=False, **{k: v for k, v in (overrides or {}).items()})
    except Exception as e:  # Mitsuba's message names the file and line: keep that and the reason
        raise FogrefError(f"{path}: Mitsuba could not load the scene: {_mitsuba_reason(e)}") from None
    desc["camera"] = sensor_camera(scene.sensors()[0])
    return scene, desc


def sensor_camera(sensor) -> dict:
    """The full camera of a Mitsuba perspective sensor, as plain data (what a truth's header stores).

    World frame y-up, right-handed, metres.  ``origin`` [m]; ``forward``, ``up`` (the
    camera's orthonormal up) and ``right`` (``forward x up``: pixel x grows along it)
    unit vectors; ``target = origin + forward`` (a point 1 m along the view axis);
    ``fov_deg`` the horizontal field of view [deg] (``fov_axis`` ``"x"``: Mitsuba stores
    the x field of view, whatever axis the scene gave), ``fov_y_deg`` the vertical one;
    ``to_world`` the 4x4 camera-to-world matrix (rows; columns: Mitsuba's camera +x =
    left, +y = up, +z = forward, origin); ``near_clip``/``far_clip`` [m]; ``resolution``
    ``[W, H]`` px.  A pixel ``(i, j)`` (column, row from the top) looks along
    ``forward + u tan(fov/2) right + v tan(fov/2) (H/W) up``, ``u = 2 (i + 0.5)/W - 1``,
    ``v = 1 - 2 (j + 0.5)/H``.
    """
    import mitsuba as mi

    m = np.asarray(sensor.world_transform().matrix, dtype=np.float64).reshape(4, 4, -1)[..., 0]
    params = mi.traverse(sensor)
    fov = params["x_fov"] if "x_fov" in params else 0.0
    fov = float(fov[0] if hasattr(fov, "__len__") else fov)
    W, H = (int(x) for x in sensor.film().crop_size())
    origin, up, forward = m[:3, 3], m[:3, 1], m[:3, 2]
    fov_y = math.degrees(2 * math.atan(math.tan(math.radians(fov) / 2) * H / W))
    return {
        "origin": origin.tolist(),
        "target": (origin + forward).tolist(),
        "up": up.tolist(),
        "forward": forward.tolist(),
        "right": np.cross(forward, up).tolist(),
        "fov_deg": fov,
        "fov_axis": "x",
        "fov_y_deg": fov_y,
        "to_world": m.tolist(),
        "near_clip": float(sensor.near_clip()),
        "far_clip": float(sensor.far_clip()),
        "resolution": [W, H],
    }
