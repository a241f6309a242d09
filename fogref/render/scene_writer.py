"""Write a fogref scene XML from fog, sun, sky, camera and a geometry template.

``fogref scene`` (and :func:`write_scene`) turns what a user has, fog parameters in
physical units **or** Unreal's editor values, a sun angle, a sky colour, a camera
and a level's geometry, into a Mitsuba 3 XML scene that ``fogref render`` takes as
is. The written scene is built like the shipped ones (``scenes/*.xml``):

* every fog, sun, sky and camera parameter is an XML ``<default>``
  (``sigma_t``, ``albedo``, ``g``, ``density``, ``falloff``, ``fog_height``,
  ``density2``, ``falloff2``, ``height2``, [``bounds_min``, ``bounds_max``],
  ``sun_elevation``, ``sun_azimuth``, ``sun_irradiance``, [``sky_radiance``],
  ``camera_origin``, ``camera_target``, ``fov``, ``res``, ``resy``, ``max_depth``),
  so ``fogref render --set NAME=VALUE`` changes any of them;
* the ``fogpath`` integrator, a ``heightfog`` medium inside the sensor, a box
  reconstruction filter, a ``directional`` sun oriented by ``$sun_elevation`` and
  ``$sun_azimuth`` (:mod:`fogref.render.sun`) and a ``constant`` sky.

Units: fogref is **y-up, metres**. Unreal is z-up, centimetres: its editor values go
through the exact mapping of :func:`fogref.models.ue4.ue4_to_medium`
(``sigma_t = 100 (ln 2)^2 FogDensity/1000`` per metre at ``FogHeight/100`` m,
``falloff = 100 ln 2 FogHeightFalloff/1000`` per metre; see ``docs/design.md`` §3.1).
Unreal editor values with no physical counterpart (FogInscatteringColor,
DirectionalInscattering*, StartDistance, FogMaxOpacity, FogCutoffDistance,
EndDistance) are accepted, recorded in an XML comment and reported as notes: they
are never silently dropped.

Geometry templates: ``"plane"`` (a ground plane at y = 0), ``"valley"`` (the
shipped default scene's ground, ridges and boulders) or a mesh file (``.obj`` or
``.ply``, loaded by Mitsuba's ``obj``/``ply`` shape plugins) with its scale
(``mesh_scale``: metres per file unit) and up axis (``mesh_up="z"`` turns a z-up
file into fogref's y-up frame by a -90 deg rotation about +x, which keeps the
handedness; ``mesh_up="unreal"`` swaps y and z like fogref's Unreal position mapping,
``(x, y, z)_fogref = (X, Z, Y)_Unreal / 100`` with ``mesh_scale=0.01``, so a level exported
in Unreal's world coordinates lines up with cameras converted the same way).

Writing needs no Mitsuba; the XML is built with :mod:`xml.etree.ElementTree`.
"""

from __future__ import annotations

import math
import os
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from fogref.errors import FogrefError, ParameterError

__all__ = ["MESH_PLUGINS", "MESH_UP", "TEMPLATES", "UNREAL_IGNORED", "UNREAL_MAPPED", "SceneWriteResult",
           "fog_from_physical", "fog_from_unreal", "write_scene"]

SOURCE = "fogref scene"
#: Built-in geometry templates (anything else must be a mesh file).
TEMPLATES = ("plane", "valley")
#: Mesh file extensions and the Mitsuba shape plugin that loads each.
MESH_PLUGINS = {".obj": "obj", ".ply": "ply"}
#: Frames a mesh file may have: "y" (fogref's, y-up), "z" (z-up, rotated -90 deg about +x into
#: y-up) or "unreal" (Unreal's z-up left-handed frame, swapped (x, y, z) -> (x, z, y) as
#: :func:`fogref.models.ue4.world_to_unreal` maps positions: a mirror).
MESH_UP = ("y", "z", "unreal")
#: Half-size [m] of the ground plane of each template (the valley's is the shipped scene's).
GROUND_SIZE = {"plane": 1.0e5, "valley": 3000.0, "mesh": 1.0e5}

#: Unreal editor values that map exactly onto the physical fog: name -> command-line option.
UNREAL_MAPPED = {
    "FogDensity": "--ue-fog-density",
    "FogHeightFalloff": "--ue-fog-height-falloff",
    "FogHeight": "--ue-fog-height",
    "SecondFogData.FogDensity": "--ue-second-fog-density",
    "SecondFogData.FogHeightFalloff": "--ue-second-fog-height-falloff",
    "SecondFogData.FogHeightOffset": "--ue-second-fog-height-offset",
}
#: Unreal editor values with no physical counterpart: name -> (option, kind, why it is ignored).
UNREAL_IGNORED = {
    "FogInscatteringColor": ("--ue-fog-inscattering-color", "rgb",
                             "it stands for albedo x sky radiance (a fit output, fogref fit); the truth's sky is "
                             "sky_radiance and its albedo is albedo"),
    "DirectionalInscatteringExponent": ("--ue-directional-inscattering-exponent", "number",
                                        "a cosine lobe is not a phase function; the truth scatters with "
                                        "Henyey-Greenstein g"),
    "DirectionalInscatteringColor": ("--ue-directional-inscattering-color", "rgb",
                                     "it stands for albedo x sun irradiance x phase; the truth's sun is "
                                     "sun_irradiance"),
    "DirectionalInscatteringStartDistance": ("--ue-directional-inscattering-start-distance", "number",
                                             "physical fog scatters sunlight from the camera on"),
    "StartDistance": ("--ue-start-distance", "number", "physical fog starts at the camera"),
    "FogMaxOpacity": ("--ue-fog-max-opacity", "number", "physical transmittance has no clamp"),
    "FogCutoffDistance": ("--ue-fog-cutoff-distance", "number", "physical fog has no cutoff distance"),
    "EndDistance": ("--ue-end-distance", "number", "physical fog does not end at a distance"),
}

#: Physical fog parameters: name -> (command-line option, kind, lo, hi, unit).
PHYSICAL = {
    "sigma_t": ("--sigma-t", "rgb", 0.0, 1e2, "1/m"),
    "density": ("--density", "number", 0.0, 1e6, "relative"),
    "falloff": ("--falloff", "number", 0.0, 1e3, "1/m"),
    "height": ("--height", "number", -1e7, 1e7, "m"),
    "density2": ("--density2", "number", 0.0, 1e6, "relative to sigma_t"),
    "falloff2": ("--falloff2", "number", 0.0, 1e3, "1/m"),
    "height2": ("--height2", "number", -1e7, 1e7, "m"),
    "bounds_min": ("--bounds-min", "point", -1e7, 1e7, "m"),
    "bounds_max": ("--bounds-max", "point", -1e7, 1e7, "m"),
}
#: Shared by both fog inputs (Unreal has neither).
SCATTERING = {
    "albedo": ("--albedo", "rgb", 0.0, 1.0, ""),
    "g": ("--g", "number", -0.999, 0.999, ""),
}
_SCALAR_LIMIT = 1e7  # [m] coordinates of cameras and mesh offsets


# --------------------------------------------------------------------------- validation

def _label(name: str, option: str | None) -> str:
    return f"{name} ({option})" if option else name


def _range(lo: float, hi: float, unit: str) -> str:
    return f"[{lo:g}, {hi:g}]" + (f" {unit}" if unit else "")


def _numbers(value, name: str, option: str | None, counts: tuple) -> list[float]:
    """1 or 3 finite numbers from a number, a sequence or a string ``"a, b, c"``."""
    label = _label(name, option)
    if isinstance(value, str):
        parts = value.replace(",", " ").split()
    elif isinstance(value, (int, float)) and not isinstance(value, bool):
        parts = [value]
    else:
        try:
            parts = list(value)
        except TypeError:
            raise ParameterError(SOURCE, label, f"expected a number or {counts[-1]} numbers, got {value!r}") from None
    try:
        nums = [float(x) for x in parts]
    except (TypeError, ValueError):
        raise ParameterError(SOURCE, label, f"expected numbers, got {value!r}") from None
    if len(nums) not in counts:
        want = " or ".join(str(c) for c in counts)
        raise ParameterError(SOURCE, label, f"expected {want} number(s), got {len(nums)} ({value!r})")
    if not all(math.isfinite(x) for x in nums):
        raise ParameterError(SOURCE, label, f"values {nums} must be finite")
    return nums


def _check(value, name: str, option: str | None, kind: str, lo: float = -math.inf, hi: float = math.inf,
           unit: str = ""):
    """A validated number (kind "number"), grey or RGB value ("rgb": a float for 1 value,
    a list for 3) or 3-vector ("point", a list), each component in [lo, hi]."""
    counts = {"number": (1,), "rgb": (1, 3), "point": (3,)}[kind]
    nums = _numbers(value, name, option, counts)
    for x in nums:
        if not lo <= x <= hi:
            shown = nums[0] if kind == "number" else nums
            raise ParameterError(SOURCE, _label(name, option), f"value {shown} outside {_range(lo, hi, unit)}")
    return nums[0] if kind == "number" or (kind == "rgb" and len(nums) == 1) else nums


def _rgb3(v) -> list:
    return list(v) if isinstance(v, list) else [v] * 3


def _fmt(x: float) -> str:
    """A float as the shortest text that reads back to the same float64."""
    x = float(x)
    return repr(0.0 if x == 0 else x)


def _vec(v) -> str:
    return ", ".join(_fmt(x) for x in v)


# --------------------------------------------------------------------------- fog inputs

def fog_from_physical(fog: dict | None = None, *, albedo=0.9, g: float = 0.6) -> dict:
    """The ``heightfog`` parameters of a fog given in physical units, validated.

    Parameters
    ----------
    fog : dict, optional
        ``sigma_t`` [1/m] (1 grey or 3 RGB values, 0..1e2; extinction at ``height``),
        ``falloff`` [1/m] (0..1e3), ``height`` [m], ``density`` (relative, default 1),
        an optional second layer ``density2`` (relative to ``sigma_t``; 0 = none),
        ``falloff2`` [1/m], ``height2`` [m], and optional box bounds ``bounds_min``,
        ``bounds_max`` (3 values each [m], both or none). Missing values take the
        shipped valley's fog (Unreal's FogDensity 0.02, FogHeightFalloff 0.2 at 0 m).
    albedo : float or 3 floats
        Single-scattering albedo in [0, 1].
    g : float
        Henyey-Greenstein asymmetry in [-0.999, 0.999].

    Returns
    -------
    dict
        XML parameter name -> value (floats, lists of floats): ``sigma_t``, ``albedo``,
        ``g``, ``density``, ``falloff``, ``fog_height``, ``density2``, ``falloff2``,
        ``height2`` and, when given, ``bounds_min``, ``bounds_max``.

    Raises
    ------
    fogref.errors.ParameterError
        Naming the parameter, its command-line option and the allowed range.

    Examples
    --------
    >>> p = fog_from_physical({"sigma_t": [0.001, 0.002, 0.003], "falloff": 0.05, "height": 10})
    >>> p["sigma_t"], p["falloff"], p["fog_height"], p["density2"]
    ([0.001, 0.002, 0.003], 0.05, 10.0, 0.0)
    >>> fog_from_physical({"falloff": -1})
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: fogref scene: parameter 'falloff (--falloff)': value -1.0 outside [0, 1000] 1/m
    """
    from fogref.models.ue4 import unreal_to_sigma

    fog = dict(fog or {})
    unknown = sorted(set(fog) - set(PHYSICAL) - set(SCATTERING))
    if unknown:
        raise ParameterError(SOURCE, unknown[0], f"not a physical fog parameter; known: {', '.join(PHYSICAL)}")
    albedo = fog.pop("albedo", albedo)
    g = fog.pop("g", g)
    sigma0, falloff0 = unreal_to_sigma(0.02, 0.2)  # the shipped valley's fog
    defaults = {"sigma_t": sigma0, "density": 1.0, "falloff": falloff0, "height": 0.0,
                "density2": 0.0, "falloff2": 0.002, "height2": 100.0}
    out = {}
    for name, (opt, kind, lo, hi, unit) in PHYSICAL.items():
        v = fog.get(name, defaults.get(name))
        if v is not None:
            out[name] = _check(v, name, opt, kind, lo, hi, unit)
    out["albedo"] = _check(albedo, "albedo", SCATTERING["albedo"][0], "rgb", 0.0, 1.0)
    out["g"] = _check(g, "g", SCATTERING["g"][0], "number", -0.999, 0.999)
    if ("bounds_min" in out) != ("bounds_max" in out):
        missing = "bounds_max" if "bounds_min" in out else "bounds_min"
        raise ParameterError(SOURCE, _label(missing, PHYSICAL[missing][0]), "give both bounds or none")
    if "bounds_min" in out and not all(a < b for a, b in zip(out["bounds_min"], out["bounds_max"])):
        raise ParameterError(SOURCE, _label("bounds_max", "--bounds-max"),
                             f"{out['bounds_max']} must exceed bounds_min {out['bounds_min']} on every axis")
    out["fog_height"] = out.pop("height")
    _check_medium(out)
    return out


def _medium_params(fog: dict) -> dict:
    """``heightfog`` XML parameter names (``height`` for ``fog_height``)."""
    p = {k: v for k, v in fog.items() if k != "fog_height"}
    p["height"] = fog["fog_height"]
    return p


def _check_medium(fog: dict) -> None:
    """The medium parser that ``fogref render`` uses must accept the values too."""
    from fogref.media.params import medium_from_params

    medium_from_params(_medium_params(fog), f"{SOURCE}: fog")


def _unreal_value(unreal: dict, key: str):
    if key.startswith("SecondFogData."):
        sfd = unreal.get("SecondFogData") or {}
        if not isinstance(sfd, dict):
            raise ParameterError(SOURCE, "SecondFogData", "expected a dict of FogDensity, FogHeightFalloff, "
                                                          "FogHeightOffset")
        return sfd.get(key.split(".", 1)[1])
    return unreal.get(key)


def fog_from_unreal(unreal: dict, *, albedo=0.9, g: float = 0.6) -> tuple[dict, list[str]]:
    """The ``heightfog`` parameters of Unreal editor values, through the exact mapping.

    Parameters
    ----------
    unreal : dict
        Unreal's Exponential Height Fog component, in the editor's names and units:
        ``FogDensity`` (default 0.02), ``FogHeightFalloff`` (default 0.2),
        ``FogHeight`` [cm, Unreal z-up world Z; default 0] and ``SecondFogData``, a
        dict of ``FogDensity`` (default 0: no second layer), ``FogHeightFalloff``
        (default 0.2) and ``FogHeightOffset`` [cm, relative to FogHeight]. These map
        exactly (:func:`fogref.models.ue4.ue4_to_medium`). The values of
        :data:`UNREAL_IGNORED` (FogInscatteringColor, DirectionalInscatteringExponent,
        ...) have no physical counterpart: they are checked, kept out of the fog
        and reported in the notes.
    albedo : float or 3 floats
        Single-scattering albedo in [0, 1] (Unreal has none).
    g : float
        Henyey-Greenstein asymmetry in [-0.999, 0.999] (Unreal has none).

    Returns
    -------
    (dict, list of str)
        The fog as :func:`fog_from_physical` returns it, and one note per ignored
        Unreal value (what it was and why it is ignored).

    Raises
    ------
    fogref.errors.ParameterError
        Naming the Unreal value, its command-line option and the allowed range.

    Examples
    --------
    >>> from fogref.models.ue4 import unreal_to_sigma
    >>> fog, notes = fog_from_unreal({"FogDensity": 0.02, "FogHeightFalloff": 0.2, "FogHeight": 150.0,
    ...                               "DirectionalInscatteringExponent": 4.0})
    >>> (fog["sigma_t"], fog["falloff"]) == unreal_to_sigma(0.02, 0.2), fog["fog_height"]
    (True, 1.5)
    >>> print(notes[0])
    Unreal DirectionalInscatteringExponent = 4.0 is ignored: a cosine lobe is not a phase function; the truth scatters with Henyey-Greenstein g
    """
    from fogref.models.ue4 import (
        CM_PER_M,
        SecondFogData,
        UE4FogParams,
        sigma_to_unreal,
        ue4_to_medium,
        unreal_to_sigma,
    )

    if not isinstance(unreal, dict):
        raise ParameterError(SOURCE, "unreal", f"expected a dict of Unreal editor values, got {unreal!r}")
    known = {k.split(".")[0] for k in UNREAL_MAPPED} | set(UNREAL_IGNORED)
    unknown = sorted(set(unreal) - known)
    if unknown:
        import difflib

        close = difflib.get_close_matches(unknown[0], sorted(known), n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        raise ParameterError(SOURCE, unknown[0], f"not an Unreal Exponential Height Fog value{hint}; "
                                                 f"known: {', '.join(sorted(known))}")
    # the editor ranges that keep the physical fog inside what fogref renders (sigma_t <= 1e2, falloff <= 1e3)
    d_max, f_max = sigma_to_unreal(PHYSICAL["sigma_t"][3], PHYSICAL["falloff"][3])
    h_max = PHYSICAL["height"][3] * CM_PER_M
    limits = {"FogDensity": (0.0, d_max, "", 0.02), "FogHeightFalloff": (0.0, f_max, "", 0.2),
              "FogHeight": (-h_max, h_max, "cm", 0.0),
              "SecondFogData.FogDensity": (0.0, d_max, "", 0.0),
              "SecondFogData.FogHeightFalloff": (0.0, f_max, "", 0.2),
              "SecondFogData.FogHeightOffset": (-h_max, h_max, "cm", 0.0)}
    v = {}
    for key, opt in UNREAL_MAPPED.items():
        lo, hi, unit, default = limits[key]
        raw = _unreal_value(unreal, key)
        v[key] = _check(default if raw is None else raw, key, opt, "number", lo, hi, unit)
    sfd = unreal.get("SecondFogData") or {}
    extra = sorted(set(sfd) - {"FogDensity", "FogHeightFalloff", "FogHeightOffset"})
    if extra:
        raise ParameterError(SOURCE, f"SecondFogData.{extra[0]}", "SecondFogData has FogDensity, "
                                                                  "FogHeightFalloff and FogHeightOffset")
    notes = []
    for key, (opt, kind, why) in UNREAL_IGNORED.items():
        if unreal.get(key) is None:
            continue
        val = _check(unreal[key], key, opt, "rgb" if kind == "rgb" else "number")
        shown = _vec(val) if isinstance(val, list) else _fmt(val)
        notes.append(f"Unreal {key} = {shown} is ignored: {why}")
    params = UE4FogParams(FogDensity=v["FogDensity"], FogHeightFalloff=v["FogHeightFalloff"],
                          FogHeight=v["FogHeight"],
                          SecondFogData=SecondFogData(v["SecondFogData.FogDensity"],
                                                      v["SecondFogData.FogHeightFalloff"],
                                                      v["SecondFogData.FogHeightOffset"]))
    medium = ue4_to_medium(params)
    layers = medium.layers
    if params.FogDensity == 0 and params.SecondFogData.FogDensity == 0:  # no fog: keep layer 1's shape
        _, b = unreal_to_sigma(0.0, params.FogHeightFalloff)
        fog = {"sigma_t": 0.0, "density": 1.0, "falloff": b, "height": params.FogHeight / CM_PER_M}
    else:
        fog = {"sigma_t": medium.sigma_t[0], "density": layers[0].density, "falloff": layers[0].falloff,
               "height": layers[0].height}
    if len(layers) > 1:
        fog.update(density2=layers[1].density, falloff2=layers[1].falloff, height2=layers[1].height)
    else:  # no second layer (density2 = 0), but its shape stays settable with --set
        _, b2 = unreal_to_sigma(0.0, params.SecondFogData.FogHeightFalloff)
        fog.update(density2=0.0, falloff2=b2,
                   height2=(params.FogHeight + params.SecondFogData.FogHeightOffset) / CM_PER_M)
    return fog_from_physical(fog, albedo=albedo, g=g), notes


# --------------------------------------------------------------------------- geometry

@dataclass(frozen=True)
class _Geometry:
    kind: str                    # "plane", "valley" or "mesh"
    mesh: Path | None = None
    plugin: str | None = None


def _geometry(template) -> _Geometry:
    t = str(template)
    if t in TEMPLATES:
        return _Geometry(t)
    path = Path(t)
    ext = path.suffix.lower()
    choices = f"choose {', '.join(TEMPLATES)} or a mesh file ({', '.join(MESH_PLUGINS)})"
    if ext not in MESH_PLUGINS:
        if path.is_file():
            raise ParameterError(SOURCE, "geometry (--geometry)",
                                 f"'{t}': Mitsuba loads meshes from {', '.join(MESH_PLUGINS)} files only, not "
                                 f"'{ext or 'no extension'}'; convert it, or {choices}")
        raise ParameterError(SOURCE, "geometry (--geometry)", f"unknown template '{t}': {choices}")
    if not path.is_file():
        raise ParameterError(SOURCE, "geometry (--geometry)", f"mesh file '{t}' not found")
    return _Geometry("mesh", path, MESH_PLUGINS[ext])


def _sub(parent, tag: str, **attrs):
    return ET.SubElement(parent, tag, {k: str(v) for k, v in attrs.items()})


def _diffuse(parent, bsdf_id: str, reflectance: str, twosided: bool = False):
    if twosided:
        outer = _sub(parent, "bsdf", type="twosided", id=bsdf_id)
        inner = _sub(outer, "bsdf", type="diffuse")
    else:
        inner = _sub(parent, "bsdf", type="diffuse", id=bsdf_id)
    _sub(inner, "rgb", name="reflectance", value=reflectance)


def _ground(parent, size: float, bsdf_id: str, shape_id: str = "ground"):
    s = _sub(parent, "shape", type="rectangle", id=shape_id)
    tw = _sub(s, "transform", name="to_world")
    _sub(tw, "rotate", x="1", angle="-90")
    _sub(tw, "scale", value=_fmt(size))
    _sub(s, "ref", id=bsdf_id)


#: The shipped valley (scenes/valley.xml): cubes (scale x, y, z [m], rotation about +y [deg],
#: translation [m]) and one sphere (centre [m], radius [m]); tests check them against the file.
VALLEY_CUBES = (
    ("left ridge", (60, 90, 200), 10, (-220, 0, 600)),
    (None, (80, 140, 250), -5, (-300, 0, 1300)),
    ("right ridge", (70, 110, 220), -12, (260, 0, 800)),
    (None, (90, 180, 300), 8, (420, 0, 1800)),
    ("distant wall closing the valley", (900, 260, 60), None, (0, 0, 2600)),
    ("near boulders", (4, 3, 4), 30, (-12, 0, 45)),
)
VALLEY_SPHERES = (((15, 0, 90), 9),)
VALLEY_BSDFS = {"grass": "0.12, 0.16, 0.08", "rock": "0.25, 0.23, 0.20"}


def _valley(root, ground_size: float):
    for name, refl in VALLEY_BSDFS.items():
        _diffuse(root, name, refl)
    _ground(root, ground_size, "grass")
    for comment, scale, angle, t in VALLEY_CUBES:
        if comment:
            root.append(ET.Comment(f" {comment} "))
        s = _sub(root, "shape", type="cube")
        tw = _sub(s, "transform", name="to_world")
        _sub(tw, "scale", x=_fmt(scale[0]), y=_fmt(scale[1]), z=_fmt(scale[2]))
        if angle is not None:
            _sub(tw, "rotate", y="1", angle=_fmt(angle))
        _sub(tw, "translate", x=_fmt(t[0]), y=_fmt(t[1]), z=_fmt(t[2]))
        _sub(s, "ref", id="rock")
    for c, r in VALLEY_SPHERES:
        s = _sub(root, "shape", type="sphere")
        _sub(s, "point", name="center", x=_fmt(c[0]), y=_fmt(c[1]), z=_fmt(c[2]))
        _sub(s, "float", name="radius", value=_fmt(r))
        _sub(s, "ref", id="rock")


def _mesh(root, geo: _Geometry, out_dir: Path, scale: float, up: str, translate):
    # Mitsuba resolves a relative filename against the scene file's folder
    try:
        filename = os.path.relpath(geo.mesh.resolve(), out_dir.resolve())
    except ValueError:  # another drive (Windows)
        filename = str(geo.mesh.resolve())
    root.append(ET.Comment(f" mesh: {geo.mesh.name}, {_fmt(scale)} m per file unit, {up}-up in the file "
                           f"(fogref is y-up) "))
    s = _sub(root, "shape", type=geo.plugin, id="mesh")
    _sub(s, "string", name="filename", value=filename.replace(os.sep, "/"))
    tw = _sub(s, "transform", name="to_world")
    _sub(tw, "scale", value=_fmt(scale))
    if up == "z":  # (x, y, z) -> (x, z, -y): the file's +z becomes +y, a proper rotation
        _sub(tw, "rotate", x="1", angle="-90")
    elif up == "unreal":  # (x, y, z) -> (x, z, y): the inverse of world_to_unreal's swap (a mirror)
        _sub(tw, "matrix", value="1 0 0 0 0 0 1 0 0 1 0 0 0 0 0 1")
    if any(translate):
        _sub(tw, "translate", x=_fmt(translate[0]), y=_fmt(translate[1]), z=_fmt(translate[2]))
    _sub(s, "ref", id="surface")


# --------------------------------------------------------------------------- the scene

@dataclass
class SceneWriteResult:
    """What :func:`write_scene` wrote.

    path: the XML file; defaults: its ``<default>`` values by name (XML text);
    notes: the Unreal values that have no physical counterpart and other remarks
    (also in the XML's comments).
    """

    path: Path
    defaults: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)


def _camera(origin, target, fov, res, resy) -> dict:
    o = _check(origin, "camera_origin", "--camera-origin", "point", -_SCALAR_LIMIT, _SCALAR_LIMIT, "m")
    t = _check(target, "camera_target", "--camera-target", "point", -_SCALAR_LIMIT, _SCALAR_LIMIT, "m")
    d = [b - a for a, b in zip(o, t)]
    n = math.sqrt(sum(x * x for x in d))
    if n == 0:
        raise ParameterError(SOURCE, "camera_target (--camera-target)", "must differ from camera_origin")
    if math.hypot(d[0], d[2]) <= 1e-9 * n:
        raise ParameterError(SOURCE, "camera_target (--camera-target)",
                             f"the camera looks straight {'up' if d[1] > 0 else 'down'} (origin {o}, target {t}); "
                             f"the camera's up vector is +y, so tilt the view a little")
    f = _check(fov, "fov", "--fov", "number", 0.0, 180.0, "deg")
    if not 0 < f < 180:
        raise ParameterError(SOURCE, "fov (--fov)", f"value {f} outside (0, 180) deg (horizontal field of view)")
    out = {"camera_origin": o, "camera_target": t, "fov": f}
    for name, v in (("res", res), ("resy", resy)):
        x = _check(v, name, f"--{name}", "number", 1, 65536, "pixels")
        if not float(x).is_integer():
            raise ParameterError(SOURCE, f"{name} (--{name})", f"value {x} must be an integer in [1, 65536] pixels")
        out[name] = int(x)
    return out


def write_scene(out, *, fog: dict | None = None, unreal: dict | None = None, albedo=None, g=None,
                sun_elevation: float = 8.0, sun_azimuth: float = 24.0, sun_irradiance=(3.2, 2.9, 2.4),
                sky_radiance=(0.2, 0.3, 0.5), camera_origin=(0.0, 2.0, 0.0),
                camera_target=(0.15, 2.35, 1.0), fov: float = 70.0, res: int = 320, resy: int = 180,
                geometry="plane", mesh_scale: float = 1.0, mesh_up: str = "y", mesh_translate=(0.0, 0.0, 0.0),
                ground: bool | None = None, ground_size: float | None = None, max_depth: int = 16,
                overwrite: bool = False, on_note: Callable[[str], None] | None = None) -> SceneWriteResult:
    """Write a fogref scene XML (fogpath + heightfog) from fog, sun, sky, camera and geometry.

    Parameters
    ----------
    out : str or Path
        The scene file to write (``.xml``); an existing file is kept unless ``overwrite``.
    fog : dict, optional
        Fog in physical units (:func:`fog_from_physical`: ``sigma_t`` [1/m], ``falloff``
        [1/m], ``height`` [m], ``density2``/``falloff2``/``height2``, ``bounds_min``/
        ``bounds_max`` [m]). Not together with ``unreal``. Neither: the valley's fog.
    unreal : dict, optional
        Fog as Unreal editor values (:func:`fog_from_unreal`: ``FogDensity``,
        ``FogHeightFalloff``, ``FogHeight`` [cm, z-up], ``SecondFogData``, and values
        with no physical counterpart, which are reported as notes).
    albedo : float or 3 floats, optional
        Single-scattering albedo in [0, 1] (default 0.9).
    g : float, optional
        Henyey-Greenstein asymmetry in [-0.999, 0.999] (default 0.6).
    sun_elevation, sun_azimuth : float
        The sun [deg]: elevation above the horizon in [-90, 90], azimuth from +z toward +x
        (:func:`fogref.render.sun.sun_direction_from_angles`).
    sun_irradiance : float or 3 floats
        RGB sun irradiance on a plane facing the sun, >= 0 (relative linear units).
    sky_radiance : float, 3 floats or None
        RGB radiance of a uniform sky, >= 0; None: no sky emitter (black sky).
    camera_origin, camera_target : 3 floats
        Camera position and a point it looks at [m], y-up.
    fov : float
        Horizontal field of view in (0, 180) [deg].
    res, resy : int
        Image width and height [pixels], 1 to 65536.
    geometry : str or Path
        ``"plane"``, ``"valley"`` or a mesh file (``.obj``/``.ply``).
    mesh_scale : float
        Metres per mesh file unit, > 0 (0.01 for a file in centimetres).
    mesh_up : {"y", "z", "unreal"}
        The mesh file's frame: y-up; z-up (rotated by -90 deg about +x into y-up); or
        Unreal's z-up left-handed frame (y and z swapped, a mirror).
    mesh_translate : 3 floats
        Offset [m] added after scaling and rotating the mesh.
    ground : bool, optional
        Add a ground plane at y = 0 (default: yes for plane and valley, no for a mesh).
    ground_size : float, optional
        Half-size of the ground plane [m], > 0 (default 1e5; the valley's 3000).
    max_depth : int
        Mitsuba's path depth (2 = single scattering, -1 = unlimited).
    overwrite : bool
        Replace an existing ``out``.
    on_note : callable, optional
        Called with each note (the command line prints them); default: a
        :class:`UserWarning` for each ignored Unreal value.

    Returns
    -------
    SceneWriteResult

    Raises
    ------
    fogref.errors.ParameterError
        Naming the parameter, its command-line option and the allowed range.
    fogref.errors.FogrefError
        For an output that exists or is not ``.xml``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from fogref.models.ue4 import unreal_to_sigma
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "my_fog.xml"
    >>> r = write_scene(out, unreal={"FogDensity": 0.05, "FogHeightFalloff": 0.1, "FogHeight": 250.0},
    ...                 sun_elevation=12, sun_azimuth=-30, geometry="valley")
    >>> float(r.defaults["sigma_t"]) == unreal_to_sigma(0.05, 0.1)[0], r.defaults["fog_height"]
    (True, '2.5')
    >>> r.defaults["sun_elevation"], r.defaults["sun_azimuth"], r.notes
    ('12.0', '-30.0', ['Unreal has no albedo or phase function: the fog uses albedo 0.9 and Henyey-Greenstein g 0.6 (the albedo and g parameters)'])
    """
    from fogref.render.sun import sun_direction_from_angles

    out = Path(out)
    if out.suffix.lower() != ".xml":
        raise FogrefError(f"{SOURCE}: --out '{out}': a scene file must end in .xml")
    if out.exists() and not overwrite:
        raise FogrefError(f"{SOURCE}: --out '{out}' exists; pass --force (overwrite=True) to replace it")
    if out.is_dir():
        raise FogrefError(f"{SOURCE}: --out '{out}' is a folder")
    scatter = {"albedo": 0.9 if albedo is None else albedo, "g": 0.6 if g is None else g}
    if fog is not None and unreal is not None:
        raise FogrefError(f"{SOURCE}: give the fog either in physical units (sigma_t, falloff, ...) or as Unreal "
                          f"editor values (FogDensity, ...), not both")
    ignored: list[str] = []
    if unreal is not None:
        fogp, ignored = fog_from_unreal(unreal, **scatter)
    else:
        fogp = fog_from_physical(fog, **scatter)
    notes = list(ignored)
    if unreal is not None:
        notes.append(f"Unreal has no albedo or phase function: the fog uses albedo {_text(fogp['albedo'])} and "
                     f"Henyey-Greenstein g {_fmt(fogp['g'])} (the albedo and g parameters)")
    el = _check(sun_elevation, "sun_elevation", "--sun-elevation", "number", -90.0, 90.0, "deg")
    az = _check(sun_azimuth, "sun_azimuth", "--sun-azimuth", "number", -360.0, 360.0, "deg")
    sun_direction_from_angles(el, az)
    sun = _check(sun_irradiance, "sun_irradiance", "--sun-irradiance", "rgb", 0.0, math.inf)
    sky = None if sky_radiance is None else _check(sky_radiance, "sky_radiance", "--sky-radiance", "rgb",
                                                   0.0, math.inf)
    cam = _camera(camera_origin, camera_target, fov, res, resy)
    depth = _check(max_depth, "max_depth", "--max-depth", "number", -1, 1 << 20)
    if not float(depth).is_integer() or depth == 0:
        raise ParameterError(SOURCE, "max_depth (--max-depth)", f"value {depth}: an integer >= 1, or -1 (no limit)")
    geo = _geometry(geometry)
    scale = _check(mesh_scale, "mesh_scale", "--mesh-scale", "number", 0.0, 1e6)
    if scale <= 0:
        raise ParameterError(SOURCE, "mesh_scale (--mesh-scale)", f"value {scale} must be > 0 (metres per file unit)")
    if mesh_up not in MESH_UP:
        raise ParameterError(SOURCE, "mesh_up (--mesh-up)", f"'{mesh_up}' is not one of {', '.join(MESH_UP)}")
    shift = _check(mesh_translate, "mesh_translate", "--mesh-translate", "point", -_SCALAR_LIMIT, _SCALAR_LIMIT,
                   "m")
    if geo.kind != "mesh":
        for name, given in (("mesh_scale", scale != 1.0), ("mesh_up", mesh_up != "y"), ("mesh_translate", any(shift))):
            if given:
                raise ParameterError(SOURCE, f"{name} (--{name.replace('_', '-')})",
                                     f"applies to a mesh file, not to the '{geo.kind}' template")
    gsize = GROUND_SIZE[geo.kind] if ground_size is None else _check(
        ground_size, "ground_size", "--ground-size", "number", 0.0, 1e7, "m")
    if gsize <= 0:
        raise ParameterError(SOURCE, "ground_size (--ground-size)", f"value {gsize} must be > 0 m")
    with_ground = (geo.kind != "mesh") if ground is None else bool(ground)
    if geo.kind == "valley" and not with_ground:
        raise ParameterError(SOURCE, "ground (--no-ground)", "the valley template has its own ground")

    # ---- the XML
    defaults: dict[str, str] = {"res": str(cam["res"]), "resy": str(cam["resy"]), "max_depth": str(int(depth))}
    for k in ("sigma_t", "albedo", "g", "density", "falloff", "fog_height", "density2", "falloff2", "height2",
              "bounds_min", "bounds_max"):
        if k in fogp:
            defaults[k] = _text(fogp[k])
    defaults.update(sun_elevation=_fmt(el), sun_azimuth=_fmt(az), sun_irradiance=_vec(_rgb3(sun)))
    if sky is not None:
        defaults["sky_radiance"] = _vec(_rgb3(sky))
    defaults.update(camera_origin=_vec(cam["camera_origin"]), camera_target=_vec(cam["camera_target"]),
                    fov=_fmt(cam["fov"]))
    if geo.kind != "valley":
        defaults["reflectance"] = "0.2, 0.2, 0.2"

    from fogref._version import __version__

    root = ET.Element("scene", version="3.0.0")
    what = ("Unreal editor values " + ", ".join(f"{k}={v}" for k, v in _flat_unreal(unreal).items())
            if unreal is not None else "physical units")
    geo_text = geo.kind if geo.kind != "mesh" else f"mesh {geo.mesh.name}"
    root.append(ET.Comment(_comment(
        f" Written by fogref scene (fogref {__version__}). Geometry: {geo_text}. Fog from {what}. "
        "Units: metres, y up; the sun's elevation is above the horizon and its azimuth is from +z toward +x "
        "[deg] (fogref/render/sun.py). Every default below can be changed by the set option of fogref render (NAME=VALUE). ")))
    for n in notes:
        root.append(ET.Comment(_comment(f" note: {n} ")))
    for k, v in defaults.items():
        _sub(root, "default", name=k, value=v)

    integ = _sub(root, "integrator", type="fogpath")
    _sub(integ, "integer", name="max_depth", value="$max_depth")

    sensor = _sub(root, "sensor", type="perspective")
    _sub(sensor, "float", name="fov", value="$fov")
    _sub(sensor, "string", name="fov_axis", value="x")
    tw = _sub(sensor, "transform", name="to_world")
    _sub(tw, "lookat", origin="$camera_origin", target="$camera_target", up="0, 1, 0")
    film = _sub(sensor, "film", type="hdrfilm")
    _sub(film, "integer", name="width", value="$res")
    _sub(film, "integer", name="height", value="$resy")
    _sub(film, "rfilter", type="box")
    med = _sub(sensor, "medium", type="heightfog", name="medium")
    _sub(med, "string", name="profile", value="exponential")
    for k, tag in (("sigma_t", None), ("albedo", None), ("g", "float"), ("density", "float"),
                   ("falloff", "float"), ("fog_height", "float"), ("density2", "float"), ("falloff2", "float"),
                   ("height2", "float"), ("bounds_min", "point"), ("bounds_max", "point")):
        if k not in fogp:
            continue
        if tag is None:  # grey: one number (like valley.xml); RGB: three (like above_fog.xml)
            tag = "rgb" if isinstance(fogp[k], list) else "float"
        _sub(med, tag, name="height" if k == "fog_height" else k, value=f"${k}")

    sun_el = _sub(root, "emitter", type="directional", id="sun")
    tw = _sub(sun_el, "transform", name="to_world")
    tw.append(ET.Comment(" light travels along -w(sun_elevation, sun_azimuth): fogref/render/sun.py "))
    _sub(tw, "rotate", x="1", angle="$sun_elevation")
    _sub(tw, "rotate", y="1", angle="$sun_azimuth")
    _sub(tw, "rotate", y="1", angle="180")
    _sub(sun_el, "rgb", name="irradiance", value="$sun_irradiance")
    if sky is not None:
        sky_el = _sub(root, "emitter", type="constant", id="sky")
        _sub(sky_el, "rgb", name="radiance", value="$sky_radiance")
    else:
        root.append(ET.Comment(" no sky: the sky is black "))

    if geo.kind == "valley":
        _valley(root, gsize)
    else:
        _diffuse(root, "surface", "$reflectance", twosided=geo.kind == "mesh")
        if with_ground:
            _ground(root, gsize, "surface")
        if geo.kind == "mesh":
            _mesh(root, geo, out.parent, scale, mesh_up, shift)

    ET.indent(root, space="    ")
    from fogref.atomic import atomic_write

    tree = ET.ElementTree(root)
    atomic_write(out, lambda tmp: tree.write(tmp, encoding="utf-8", xml_declaration=True))
    if on_note is not None:
        for n in notes:
            on_note(n)
    else:  # Python callers: the ignored Unreal values are warnings (never silent)
        for n in ignored:
            warnings.warn(n, UserWarning, stacklevel=2)
    return SceneWriteResult(out, defaults, notes)


def _text(v) -> str:
    return _vec(v) if isinstance(v, list) else _fmt(v)


def _comment(text: str) -> str:
    """XML comments may not hold "--"."""
    while "--" in text:
        text = text.replace("--", "- -")
    return text


def _flat_unreal(unreal: dict) -> dict:
    flat = {}
    for k, v in unreal.items():
        if isinstance(v, dict):
            flat.update({f"{k}.{kk}": vv for kk, vv in v.items()})
        else:
            flat[k] = v
    return flat
