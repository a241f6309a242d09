"""Mitsuba 3.9's ``sunsky`` emitter as fogref's sky and sun, counted once each.

``sunsky`` (``src/emitters/sunsky.cpp``; Hosek & Wilkie 2012 sky, Hosek & Wilkie 2013
sun) is one infinite emitter whose radiance is the sky plus a sun disk of aperture
``sun_aperture`` (default 0.5358 deg), with zero radiance below its horizon.  Its frame
is z-up (``Frame3f::cos_theta``); fogref is y-up, so fogref's sunsky scenes rotate it
with ``<rotate x="1" angle="-90"/>`` (local +z -> world +y, :data:`Z_UP_TO_Y_UP`).  Its
``sun_direction`` is in world space, toward the sun.

fogref splits it (:func:`lower_sunsky`, before Mitsuba loads the scene):

* **the sky**: the same ``sunsky`` with ``sun_scale = 0`` (its sampling then picks the sky
  alone: ``estimate_sky_sun_ratio`` returns 1); fogpath sees it as a smooth infinite
  emitter, and the closed forms ask :func:`sky_radiance`;
* **the sun**: a ``directional`` emitter along ``sun_direction`` whose irradiance is the
  sunsky sun's radiance integrated over its disk (:func:`sun_irradiance`), times the
  scene's ``sun_scale``; fogpath gives it the size ``sun_angular_diameter`` (its integrator
  parameter; 0: a delta).

So neither is counted twice.  A camera ray that reaches the sky through a sun with a size sees
its disk (fogpath adds ``E / Omega`` there; a delta sun is not seen); every other path counts it
once, through next-event estimation.  Mitsuba's RGB sun radiance is uniform over the disk (the
limb darkening of its RGB dataset cancels at these angles: the disk quadrature equals the centre
radiance times the disk's solid angle to 1e-6); its own next-event weight ``eval / pdf`` uses a float32 solid
angle, 0.2 % below the float64 integral at 0.5358 deg.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from fogref import params as P
from fogref.errors import FogrefError
from fogref.media.single_scatter import sky_phase_projection
from fogref.media.sky import SUNSKY_APERTURE, eval_emitter, sky_radiance, sunsky_dict
from fogref.render.variant import set_variant
from fogref.scene.defaults import overrides_used_by, substitute
from fogref.scene.sun import sun_direction_from_angles

__all__ = [
    "SUNSKY_APERTURE",
    "Z_UP_TO_Y_UP",
    "lower_sunsky",
    "sky_radiance",
    "sun_from_time_and_place",
    "sun_irradiance",
    "sunsky_dict",
    "sunsky_from_element",
]

#: The sunsky's ``to_world`` in fogref scenes: a rotation of -90 deg about +x (z-up -> y-up).
Z_UP_TO_Y_UP = (("x", -90.0),)
#: sunsky parameters that fix the sun by date and place (where it has no ``sun_direction``).
_TIME_PLACE = ("latitude", "longitude", "timezone", "year", "month", "day", "hour", "minute", "second")


def sun_irradiance(desc: dict, n_gamma: int = 8, n_phi: int = 16) -> np.ndarray:
    """RGB irradiance of the sunsky's sun (a plane facing it): its radiance integrated over
    the disk, ``int L dw``, by Gauss–Legendre in the angle ``gamma`` to the disk's centre
    (``sin gamma dgamma dphi``) and ``n_phi`` azimuths; times ``desc["sun_scale"]``.

    ``desc``: :func:`sunsky_dict`.  The nodes stay 2 % inside the rim, where Mitsuba's float32
    test of the disk is exact.  Zero for a sun below the horizon.
    """
    import mitsuba as mi

    sun_only = mi.load_dict({**desc, "sky_scale": 0.0, "sun_scale": 1.0}, parallel=False)
    w = np.asarray(desc["sun_direction"], dtype=np.float64)
    w /= np.linalg.norm(w)
    half = math.radians(float(desc.get("sun_aperture", SUNSKY_APERTURE))) / 2.0
    x, wx = np.polynomial.legendre.leggauss(int(n_gamma))
    gam = half * (x + 1.0) / 2.0
    wg = wx * half / 2.0 * np.sin(gam)
    phi = (np.arange(int(n_phi)) + 0.5) * (2.0 * math.pi / int(n_phi))
    helper = np.array([1.0, 0.0, 0.0]) if abs(w[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    t1 = np.cross(w, helper)
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(w, t1)
    G, F = np.meshgrid(gam, phi, indexing="ij")
    dirs = np.cos(G)[..., None] * w + np.sin(G)[..., None] * (
        np.cos(F)[..., None] * t1 + np.sin(F)[..., None] * t2
    )
    L = eval_emitter(sun_only, dirs.reshape(-1, 3)).reshape(len(gam), len(phi), 3)
    E = (L * wg[:, None, None]).sum((0, 1)) * (2.0 * math.pi / len(phi))
    return np.maximum(E, 0.0) * float(desc.get("sun_scale", 1.0))


def _float_param(el: ET.Element, name: str, defaults: dict, default: float, source: str) -> float:
    c = el.find(f"float[@name='{name}']")
    if c is None:
        return default
    return P.number(substitute(c.get("value", ""), defaults), name, source=source)


def sun_from_time_and_place(el: ET.Element, defaults: dict, source: str) -> list[float]:
    """The unit world direction toward the sun [y-up] that Mitsuba's ``sunsky`` computes from the
    place and time of ``el`` (its ``latitude`` ... ``second``, Mitsuba's defaults for the rest), in
    fogref's frame (``to_world`` :data:`Z_UP_TO_Y_UP`): read from the loaded emitter itself.  A
    value Mitsuba refuses is a one-line FogrefError naming ``source``.  Needs the variant set."""
    import mitsuba as mi

    probe = ET.Element("emitter", type="sunsky", version="3.0.0")
    for c in el:
        if c.get("name") in _TIME_PLACE:
            probe.append(
                ET.Element(c.tag, name=c.get("name", ""), value=substitute(c.get("value", ""), defaults))
            )
    tw = ET.SubElement(probe, "transform", name="to_world")
    for axis, angle in Z_UP_TO_Y_UP:
        ET.SubElement(tw, "rotate", {axis: "1", "angle": repr(angle)})
    try:
        emitter = mi.load_string(ET.tostring(probe, encoding="unicode"), parallel=False)
    except RuntimeError as e:
        why = str(e).strip().splitlines()[-1] if str(e).strip() else type(e).__name__
        raise FogrefError(f"{source}: its place and time: {why}") from None
    return [float(x) for x in np.asarray(mi.traverse(emitter)["sun_direction"], dtype=np.float64).ravel()]


def sunsky_from_element(el: ET.Element, defaults: dict, source: str) -> dict:
    """The :func:`sunsky_dict` of a scene's ``<emitter type="sunsky">`` (``$default``s resolved).

    The sun's direction is its ``sun_direction`` vector; else, where the emitter gives a place or a
    time (``latitude`` ... ``second``) or the scene has no ``$sun_elevation`` and ``$sun_azimuth``,
    the direction Mitsuba's own sunsky takes from them and its defaults (latitude 35.6894,
    longitude 139.692, timezone 9, 2010-07-10 15:00: :func:`sun_from_time_and_place`); else the
    scene's ``$sun_elevation`` and ``$sun_azimuth``
    (:func:`fogref.scene.sun.sun_direction_from_angles`).  Its ``to_world`` must be fogref's
    z-up -> y-up rotation (or absent, then it is added)."""
    src = f"{source}: sunsky"
    v = el.find("vector[@name='sun_direction']")
    by_time = any(c.get("name") in _TIME_PLACE for c in el)
    if v is not None:
        text = substitute(v.get("value", ""), defaults)
        if text:
            w = list(P.vector(text, "sun_direction", source=src))
        else:
            w = [P.number(substitute(v.get(c, "0"), defaults), c, source=src) for c in "xyz"]
    elif by_time or not ("sun_elevation" in defaults and "sun_azimuth" in defaults):
        w = sun_from_time_and_place(el, defaults, src)
    else:
        w = list(
            sun_direction_from_angles(
                P.number(defaults["sun_elevation"], "sun_elevation", source=src),
                P.number(defaults["sun_azimuth"], "sun_azimuth", source=src),
            )
        )
    n = math.sqrt(sum(x * x for x in w))
    if not math.isfinite(n) or n == 0:
        raise FogrefError(f"{src}: sun_direction {w} is not a direction")
    tw = el.find("transform[@name='to_world']")
    if tw is not None and [(op.tag, dict(op.attrib)) for op in tw] != [
        ("rotate", {"x": "1", "angle": "-90"})
    ]:
        raise FogrefError(
            f'{src}: to_world must be <rotate x="1" angle="-90"/> (sunsky is z-up, fogref y-up), or absent'
        )
    albedo = _float_param(el, "albedo", defaults, 0.3, src)
    turb = _float_param(el, "turbidity", defaults, 3.0, src)
    if not 1.0 <= turb <= 10.0:
        raise FogrefError(f"{src}: parameter 'turbidity': {turb} is outside [1, 10]")
    size = P.number(defaults.get("sun_angular_diameter", 0.0), "sun_angular_diameter", source=src)
    ap = _float_param(el, "sun_aperture", defaults, size if size > 0 else SUNSKY_APERTURE, src)
    if not 0.0 < ap < 180.0:
        raise FogrefError(f"{src}: parameter 'sun_aperture': {ap} is outside (0, 180) deg")
    return {
        "sun_direction": [float(x) / n for x in w],
        "turbidity": turb,
        "albedo": albedo,
        "sun_aperture": ap,
        "sky_scale": _float_param(el, "sky_scale", defaults, 1.0, src),
        "sun_scale": _float_param(el, "sun_scale", defaults, 1.0, src),
    }


def lower_sunsky(root: ET.Element, defaults: dict, source) -> dict | None:
    """Split the scene's ``sunsky`` (if any) into fogref's sky and sun, in place (see module).

    Returns ``{"sky": ..., "sun": ...}`` for the scene description (None without a sunsky):
    ``sky`` the sunsky's parameters (``type`` "sunsky", ``radiance``: the isotropic
    projection ``(1/4 pi) int_{up} L dw``, the uniform sky with the same single scattering at
    ``g = 0``), ``sun`` its direction and disk-integrated irradiance.  A second sun (a
    ``directional`` emitter beside the sunsky) is refused: the sunsky has its own.
    """
    ems = [e for e in root.iter("emitter") if e.get("type") == "sunsky"]
    if not ems:
        return None
    if len(ems) > 1 or any(e.get("type") == "directional" for e in root.iter("emitter")):
        raise FogrefError(f"{source}: a sunsky brings its own sun: no second sunsky or directional sun")
    set_variant()
    el = ems[0]
    d = sunsky_from_element(el, defaults, str(source))
    desc = sunsky_dict(**d)
    E = sun_irradiance(desc)
    for c in list(el):
        if c.get("name") in ("sun_direction", "sun_scale", "to_world", *_TIME_PLACE):
            el.remove(c)
    ET.SubElement(
        el, "vector", name="sun_direction", value=", ".join(repr(float(x)) for x in d["sun_direction"])
    )
    ET.SubElement(el, "float", name="sun_scale", value="0")
    tw = ET.SubElement(el, "transform", name="to_world")
    ET.SubElement(tw, "rotate", x="1", angle="-90")
    sun = ET.Element("emitter", type="directional", id="sunsky_sun")
    ET.SubElement(
        sun, "vector", name="direction", value=", ".join(repr(-float(x)) for x in d["sun_direction"])
    )
    ET.SubElement(sun, "rgb", name="irradiance", value=", ".join(repr(float(x)) for x in E))
    root.append(sun)
    # isotropic projection of the sky: the g = 0 single scattering per unit alpha (1 - T)
    L_iso = sky_phase_projection(sky_radiance(desc), 0.0, [[0.0, 1.0, 0.0]])[0]
    sky = {"type": "sunsky", **d, "radiance": [float(x) for x in L_iso]}
    return {"sky": sky, "sun": {"direction": d["sun_direction"], "irradiance": [float(x) for x in E]}}


def load_lowered(path: Path, root: ET.Element, overrides: dict | None):
    """``mi.load_string`` of a lowered scene, relative files resolved against the scene's folder."""
    import mitsuba as mi

    fr = mi.file_resolver()
    before = [str(fr[i]) for i in range(len(fr))]
    fr.prepend(str(Path(path).resolve().parent))
    try:
        return mi.load_string(
            ET.tostring(root, encoding="unicode"), parallel=False, **overrides_used_by(root, overrides)
        )
    finally:
        fr.clear()
        for folder in before:
            fr.append(folder)
