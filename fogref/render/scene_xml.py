"""The XML of a written fogref scene: ``$default`` declarations, integrator, sensor, fog, sun, sky, geometry.

The scene is built like the shipped ones (``scenes/*.xml``): every fog, sun, sky
and camera value is a ``<default>`` named in the one vocabulary
(:data:`fogref.render.scene_defaults.VOCABULARY` and its optional groups), so
``fogref render --set NAME=VALUE`` changes any of them; the ``fogpath`` integrator,
a ``heightfog`` medium inside the sensor, a box reconstruction filter, a
``directional`` sun oriented by ``$sun_elevation`` and ``$sun_azimuth``
(:mod:`fogref.render.sun`) and a ``constant`` sky.  Built with
:mod:`xml.etree.ElementTree`; no Mitsuba.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from fogref._version import __version__
from fogref.atomic import atomic_write
from fogref.mapping.fog_input import _fmt, _rgb3, _text, _vec
from fogref.render.scene_templates import Geometry, add_mesh, add_valley, diffuse, ground, sub

__all__ = ["FOG_DEFAULTS", "comment_text", "scene_defaults", "scene_element", "write_xml"]

#: The fog's ``$default``s in the order they are declared, and the ``heightfog`` tag of each
#: (None: "rgb" for three values, "float" for one).
FOG_DEFAULTS = (
    ("sigma_t", None),
    ("albedo", None),
    ("g", "float"),
    ("density", "float"),
    ("falloff", "float"),
    ("fog_height", "float"),
    ("density2", "float"),
    ("falloff2", "float"),
    ("height2", "float"),
    ("bounds_min", "point"),
    ("bounds_max", "point"),
    ("lfv_centre", "point"),
    ("lfv_radius", "float"),
    ("lfv_density", "float"),
    ("lfv_falloff", "float"),
    ("lfv_height", "float"),
)
#: The default reflectance of the plane and mesh templates' surfaces (the ``surface`` group's
#: ``$reflectance``; ``fogref scene --ground-reflectance``, ``--mesh-reflectance``).
DEFAULT_REFLECTANCE = 0.2
SURFACE_REFLECTANCE = _vec(_rgb3(DEFAULT_REFLECTANCE))


def scene_defaults(
    fog: dict,
    camera: dict,
    max_depth: int,
    sun_elevation: float,
    sun_azimuth: float,
    sun_irradiance,
    sky_radiance,
    geometry_kind: str,
    reflectance=None,
) -> dict[str, str]:
    """The ``<default>`` values (XML text) of a written scene, in declaration order.

    ``fog``: :func:`fogref.mapping.fog_input.fog_from_physical`'s output; ``camera``:
    ``res``, ``resy``, ``camera_origin``, ``camera_target``, ``fov``; ``sky_radiance``
    None declares no sky; the plane and mesh templates add ``reflectance`` (grey or RGB in
    [0, 1]; None: :data:`SURFACE_REFLECTANCE`): the plane's ground, or the mesh's surfaces.
    """
    d: dict[str, str] = {
        "res": str(camera["res"]),
        "resy": str(camera["resy"]),
        "max_depth": str(int(max_depth)),
    }
    for k, _ in FOG_DEFAULTS:
        if k in fog:
            d[k] = _text(fog[k])
    d.update(
        sun_elevation=_fmt(sun_elevation),
        sun_azimuth=_fmt(sun_azimuth),
        sun_irradiance=_vec(_rgb3(sun_irradiance)),
    )
    if sky_radiance is not None:
        d["sky_radiance"] = _vec(_rgb3(sky_radiance))
    d.update(
        camera_origin=_vec(camera["camera_origin"]),
        camera_target=_vec(camera["camera_target"]),
        fov=_fmt(camera["fov"]),
    )
    if geometry_kind != "valley":
        d["reflectance"] = SURFACE_REFLECTANCE if reflectance is None else _vec(_rgb3(reflectance))
    return d


def comment_text(text: str) -> str:
    """XML comments may not hold "--".

    >>> comment_text(" give --force ")
    ' give - -force '
    """
    while "--" in text:
        text = text.replace("--", "- -")
    return text


def _header(root, geo: Geometry, fog_source: str, notes) -> None:
    geo_text = geo.kind if geo.kind != "mesh" else f"mesh {geo.mesh.name}"
    root.append(
        ET.Comment(
            comment_text(
                f" Written by fogref scene (fogref {__version__}). Geometry: {geo_text}. Fog from "
                f"{fog_source}. Units: metres, y up; the sun's elevation is above the horizon and its "
                "azimuth is from +z toward +x [deg] (fogref/render/sun.py). Every default below can be "
                "changed by the set option of fogref render (NAME=VALUE). "
            )
        )
    )
    for n in notes:
        root.append(ET.Comment(comment_text(f" note: {n} ")))


def _sensor(root, fog: dict) -> None:
    sensor = sub(root, "sensor", type="perspective")
    sub(sensor, "float", name="fov", value="$fov")
    sub(sensor, "string", name="fov_axis", value="x")
    tw = sub(sensor, "transform", name="to_world")
    sub(tw, "lookat", origin="$camera_origin", target="$camera_target", up="0, 1, 0")
    film = sub(sensor, "film", type="hdrfilm")
    sub(film, "integer", name="width", value="$res")
    sub(film, "integer", name="height", value="$resy")
    sub(film, "rfilter", type="box")
    med = sub(sensor, "medium", type="heightfog", name="medium")
    sub(med, "string", name="profile", value="exponential")
    for k, tag in FOG_DEFAULTS:
        if k not in fog:
            continue
        if tag is None:  # grey: one number (like valley.xml); RGB: three (like above_fog.xml)
            tag = "rgb" if isinstance(fog[k], list) else "float"
        sub(med, tag, name="height" if k == "fog_height" else k, value=f"${k}")
    if "phase" in fog:  # a tabulated phase (fogtabphase): written as is, not a $default
        phase = fog["phase"]
        med.append(ET.Comment(f" the phase function: {phase['label']} (g above is its mean cosine) "))
        el = sub(med, "phase", type=phase["type"])
        for name in ("label", "cosines", "values"):
            sub(el, "string", name=name, value=phase[name])


def _lights(root, sky) -> None:
    """The sun and the sky: ``sky`` True (a ``constant`` sky), False (none) or ``"sunsky"``
    (Mitsuba's sunsky, turned y-up, with its own sun along ``$sun_elevation``, ``$sun_azimuth``:
    fogref/render/sunsky.py)."""
    if sky == "sunsky":
        root.append(
            ET.Comment(
                " Mitsuba's physical sun and sky. fogref sets its sun_direction from sun_elevation and "
                "sun_azimuth and splits it into a sky (sun_scale 0) and a directional sun with the disk's "
                "irradiance (fogref/render/sunsky.py); sun_irradiance is not used "
            )
        )
        el = sub(root, "emitter", type="sunsky", id="sky")
        sub(el, "float", name="turbidity", value="$turbidity")
        tw = sub(el, "transform", name="to_world")
        tw.append(ET.Comment(" sunsky is z-up, fogref y-up "))
        sub(tw, "rotate", x="1", angle="-90")
        return
    sun_el = sub(root, "emitter", type="directional", id="sun")
    tw = sub(sun_el, "transform", name="to_world")
    tw.append(ET.Comment(" light travels along -w(sun_elevation, sun_azimuth): fogref/render/sun.py "))
    sub(tw, "rotate", x="1", angle="$sun_elevation")
    sub(tw, "rotate", y="1", angle="$sun_azimuth")
    sub(tw, "rotate", y="1", angle="180")
    sub(sun_el, "rgb", name="irradiance", value="$sun_irradiance")
    if sky:
        sky_el = sub(root, "emitter", type="constant", id="sky")
        sub(sky_el, "rgb", name="radiance", value="$sky_radiance")
    else:
        root.append(ET.Comment(" no sky: the sky is black "))


def scene_element(
    defaults: dict[str, str],
    fog: dict,
    geo: Geometry,
    *,
    fog_source: str,
    notes=(),
    ground_size: float | None,
    with_ground: bool,
    out_dir: Path,
    mesh_scale: float = 1.0,
    mesh_up: str = "y",
    mesh_translate=(0.0, 0.0, 0.0),
    ground_reflectance=None,
    face_normals: bool = False,
) -> ET.Element:
    """The ``<scene>`` element: a header comment (``fog_source``, ``notes``), the ``defaults``,
    integrator, sensor with the fog, sun, sky (when ``defaults`` has ``sky_radiance``) and
    geometry (``out_dir``: the scene's folder, which a mesh's file name is relative to).

    The surfaces share ``$reflectance``; with a mesh, a ``ground_reflectance`` (grey or RGB)
    gives the ground its own diffuse BSDF with that value written as is.  ``face_normals``:
    the mesh is shaded with its faces' normals."""
    root = ET.Element("scene", version="3.0.0")
    _header(root, geo, fog_source, notes)
    for k, v in defaults.items():
        sub(root, "default", name=k, value=v)
    integ = sub(root, "integrator", type="fogpath")
    sub(integ, "integer", name="max_depth", value="$max_depth")
    if "sun_angular_diameter" in defaults:
        sub(integ, "float", name="sun_angular_diameter", value="$sun_angular_diameter")
    _sensor(root, fog)
    _lights(root, "sunsky" if "turbidity" in defaults else "sky_radiance" in defaults)
    if geo.kind == "valley":
        add_valley(root, ground_size)
    else:
        diffuse(root, "surface", "$reflectance", twosided=geo.kind == "mesh")
        own = geo.kind == "mesh" and ground_reflectance is not None
        if own:
            diffuse(root, "ground_surface", _vec(_rgb3(ground_reflectance)))
        if with_ground:
            ground(root, ground_size, "ground_surface" if own else "surface")
        if geo.kind == "mesh":
            add_mesh(root, geo, out_dir, mesh_scale, mesh_up, mesh_translate, face_normals=face_normals)
    ET.indent(root, space="    ")
    return root


def write_xml(out: Path, root: ET.Element) -> None:
    """Write ``root`` to ``out`` atomically, UTF-8 with an XML declaration."""
    tree = ET.ElementTree(root)
    atomic_write(out, lambda tmp: tree.write(tmp, encoding="utf-8", xml_declaration=True))
