"""Read a fogref XML scene: validate the fog before Mitsuba sees it, load it,
and describe its fog, sun, sky and camera for the EXR header and the studies.

Scenes are ordinary Mitsuba 3 XML (y-up, metres).  The fog is the sensor's
``<medium type="heightfog">``; the sun is a ``directional`` emitter (its
``direction`` is the direction light travels, i.e. *away* from the sun); the sky
is a ``constant`` (or ``envmap``) emitter.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

from fogref.errors import FogrefError, ParameterError
from fogref.media.params import medium_from_params


def _subst(value: str, defaults: dict) -> str:
    if value and "$" in value:
        for k in sorted(defaults, key=len, reverse=True):
            value = value.replace("$" + k, str(defaults[k]))
    return value


def _value(el, defaults):
    tag = el.tag
    v = _subst(el.get("value", ""), defaults)
    if tag in ("float", "integer"):
        try:
            return float(v)
        except ValueError:
            return v
    if tag == "boolean":
        return v.lower() == "true"
    if tag in ("rgb", "point", "vector", "spectrum"):
        if v == "" and tag in ("point", "vector"):
            return [float(_subst(el.get(c, "0"), defaults)) for c in "xyz"]
        parts = [float(x) for x in v.replace(",", " ").split()]
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


def describe_scene(path, overrides: dict | None = None) -> dict:
    """Fog, sun, sky and camera of a fogref XML scene, validated, as plain data.

    Raises :class:`~fogref.errors.ParameterError` naming the file and parameter
    for an out-of-range fog value, :class:`~fogref.errors.FogrefError` for XML
    that can't be parsed.
    """
    path = Path(path)
    if not path.is_file():
        raise FogrefError(f"{path}: no such scene file")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        raise FogrefError(f"{path}: malformed XML ({e})") from None
    defaults = {d.get("name"): d.get("value") for d in root.iter("default")}
    defaults.update({k: str(v) for k, v in (overrides or {}).items()})
    desc: dict = {"scene": path.name, "medium": None, "sun": None, "sky": None, "camera": None,
                  "integrator": None}
    integ = root.find("integrator")
    if integ is not None:
        desc["integrator"] = {"type": integ.get("type"), **_params(integ, defaults)}
    for med in root.iter("medium"):
        if med.get("type") == "heightfog":
            params = _params(med, defaults)
            medium_from_params(params, f"{path}: medium '{med.get('id') or med.get('name') or 'heightfog'}'")
            desc["medium"] = params
    for em in root.iter("emitter"):
        t, p = em.get("type"), _params(em, defaults)
        if t == "directional":
            d = p.get("direction", [0, 0, 1])
            n = math.sqrt(sum(x * x for x in d)) or 1.0
            E = p.get("irradiance", [1.0, 1.0, 1.0])
            if any((not math.isfinite(x)) or x < 0 for x in E):
                raise ParameterError(str(path), "sun.irradiance", f"values {E} must be finite and >= 0")
            desc["sun"] = {"direction": [-x / n for x in d], "irradiance": E}
        elif t in ("constant", "envmap"):
            desc["sky"] = {"type": t, **{k: v for k, v in p.items() if not isinstance(v, dict)}}
    return desc


def load_scene(path, overrides: dict | None = None):
    """``mi.load_file`` with fogref's plugins registered and errors made readable.

    Sets Mitsuba up first (:func:`fogref.render.variant.set_variant`: the variant
    already set, else ``$FOGREF_VARIANT``, else ``llvm_ad_rgb``).
    """
    from fogref.render.variant import set_variant

    set_variant()
    import mitsuba as mi

    desc = describe_scene(path, overrides)
    try:
        scene = mi.load_file(str(path), **{k: v for k, v in (overrides or {}).items()})
    except Exception as e:  # Mitsuba's message already names the file and line
        msg = str(e).strip().splitlines()
        raise FogrefError(f"{path}: Mitsuba could not load the scene: {msg[-1] if msg else e}") from None
    sensor = scene.sensors()[0]
    m = sensor.world_transform().matrix
    origin = [float(m[i][3][0]) if hasattr(m[i][3], "__len__") else float(m[i][3]) for i in range(3)]
    desc["camera"] = {"origin": origin}
    return scene, desc
