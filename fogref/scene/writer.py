"""``fogref scene`` / :func:`write_scene`: a fogref scene XML from fog, sun, sky, camera and geometry.

It turns what a user has, fog parameters in physical units **or** Unreal's editor
values, a sun angle, a sky colour, a camera and a level's geometry, into a Mitsuba 3
XML scene that ``fogref render`` takes as is, built like the shipped ones
(``scenes/*.xml``) and declaring the same ``$default`` vocabulary
(:data:`fogref.scene.vocabulary.VOCABULARY`), so ``fogref render --set
NAME=VALUE`` changes any fog, sun, sky or camera value.

The concepts live beside it: the declared range of each value in
:mod:`fogref.scene.vocabulary` (checked through :mod:`fogref.params`; the same
declarations that ``fogref render --set`` is checked against), the physical fog and the exact
Unreal -> physical mapping in :mod:`fogref.scene.fog_input`, the geometry templates
(``"plane"``, ``"valley"`` read from ``scenes/valley.xml``, ``.obj``/``.ply`` meshes) in
:mod:`fogref.scene.templates`.  This module builds the XML: every fog, sun, sky and camera
value a ``<default>``, the ``fogpath`` integrator, a ``heightfog`` medium inside the sensor, a
box reconstruction filter, a ``directional`` sun oriented by ``$sun_elevation`` and
``$sun_azimuth`` (:mod:`fogref.scene.sun`) and a ``constant`` sky, with
:mod:`xml.etree.ElementTree`, after checking the sun, sky, camera and geometry arguments.
Units: fogref is **y-up, metres**; Unreal is z-up, centimetres.  Writing needs no Mitsuba.
"""

from __future__ import annotations

import dataclasses
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from fogref import params
from fogref._version import __version__
from fogref.atomic import atomic_write
from fogref.errors import FogrefError, ParameterError
from fogref.media.params import medium_from_params
from fogref.media.phase import TabulatedPhase
from fogref.scene.defaults import check_camera
from fogref.scene.fog_input import flat_unreal, fog_from_physical, fog_from_unreal
from fogref.scene.sun import sun_direction_from_angles
from fogref.scene.templates import (
    GROUND_SIZE,
    MESH_UP,
    VALLEY_SCENE,
    Geometry,
    add_mesh,
    add_valley,
    diffuse,
    ground,
    mesh_files,
    mesh_has_normals,
    sub,
)
from fogref.scene.templates import geometry as resolve_geometry
from fogref.scene.vocabulary import (
    RANGES,
    SOURCE,
    Range,
    check_option,
    float_text,
    rgb3,
    value_text,
    vector_text,
)

__all__ = [
    "FOG_DEFAULTS",
    "SceneWriteResult",
    "comment_text",
    "scene_defaults",
    "scene_element",
    "write_scene",
    "write_xml",
]

#: The writer's own values (not scene $defaults); the vocabulary's are RANGES.
MESH_SCALE = Range("--mesh-scale", "number", 0.0, 1e6, "m per file unit", lo_open=True)
MESH_TRANSLATE = Range("--mesh-translate", "point", -1e7, 1e7, "m")
GROUND_SIZE_RANGE = Range("--ground-size", "number", 0.0, 1e7, "m", lo_open=True)
#: ``reflectance`` (RANGES) as the ground's and the mesh's options.
GROUND_REFLECTANCE = RANGES["reflectance"]
MESH_REFLECTANCE = dataclasses.replace(RANGES["reflectance"], option="--mesh-reflectance")


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
SURFACE_REFLECTANCE = vector_text(rgb3(DEFAULT_REFLECTANCE))


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

    ``fog``: :func:`fogref.scene.fog_input.fog_from_physical`'s output; ``camera``:
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
            d[k] = value_text(fog[k])
    d.update(
        sun_elevation=float_text(sun_elevation),
        sun_azimuth=float_text(sun_azimuth),
        sun_irradiance=vector_text(rgb3(sun_irradiance)),
    )
    if sky_radiance is not None:
        d["sky_radiance"] = vector_text(rgb3(sky_radiance))
    d.update(
        camera_origin=vector_text(camera["camera_origin"]),
        camera_target=vector_text(camera["camera_target"]),
        fov=float_text(camera["fov"]),
    )
    if geometry_kind != "valley":
        d["reflectance"] = SURFACE_REFLECTANCE if reflectance is None else vector_text(rgb3(reflectance))
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
                "azimuth is from +z toward +x [deg] (fogref/scene/sun.py). Every default below can be "
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
    tw.append(ET.Comment(" light travels along -w(sun_elevation, sun_azimuth): fogref/scene/sun.py "))
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
            diffuse(root, "ground_surface", vector_text(rgb3(ground_reflectance)))
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


def _camera(origin, target, fov, res, resy) -> dict:
    out = {
        name: check_option(v, name, RANGES[name])
        for name, v in (
            ("camera_origin", origin),
            ("camera_target", target),
            ("fov", fov),
            ("res", res),
            ("resy", resy),
        )
    }
    check_camera(out["camera_origin"], out["camera_target"], SOURCE, "camera_target (--camera-target)")
    return out


def _check_inputs(out: Path, inputs) -> None:
    """Refuse an ``out`` that is (resolving symlinks) one of the files the scene is made from."""
    target = out.resolve()
    for f in inputs:
        if Path(f).resolve() == target:
            raise FogrefError(
                f"{SOURCE}: --out '{out}' is '{f}', an input of this scene; "
                f"writing it would replace that file: choose another --out"
            )


def write_scene(
    out,
    *,
    fog: dict | None = None,
    unreal: dict | None = None,
    albedo=None,
    g=None,
    sun_elevation: float = 8.0,
    sun_azimuth: float = 24.0,
    sun_irradiance=(3.2, 2.9, 2.4),
    sky_radiance=(0.2, 0.3, 0.5),
    sky: str = "constant",
    turbidity: float = 3.0,
    sun_angular_diameter: float | None = None,
    camera_origin=(0.0, 2.0, 0.0),
    camera_target=(0.15, 2.35, 1.0),
    fov: float = 70.0,
    res: int = 320,
    resy: int = 180,
    geometry="plane",
    mesh_scale: float = 1.0,
    mesh_up: str = "y",
    mesh_translate=(0.0, 0.0, 0.0),
    ground: bool | None = None,
    ground_size: float | None = None,
    max_depth: int = 16,
    ground_reflectance=None,
    mesh_reflectance=None,
    overwrite: bool = False,
    on_note: Callable[[str], None] | None = None,
    phase: TabulatedPhase | None = None,
    notes: tuple = (),
) -> SceneWriteResult:
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
        (:func:`fogref.scene.sun.sun_direction_from_angles`).
    sun_irradiance : float or 3 floats
        RGB sun irradiance on a plane facing the sun, >= 0 (relative linear units).
    sky_radiance : float, 3 floats or None
        RGB radiance of a uniform sky, >= 0; None: no sky emitter (black sky).
    sky : str
        ``"constant"`` (the uniform sky of ``sky_radiance``) or ``"sunsky"``: Mitsuba's
        physical sun and sky with its own sun (``sun_irradiance`` and ``sky_radiance`` are
        then not used; :mod:`fogref.render.sunsky`).
    turbidity : float
        The sunsky's atmospheric turbidity in [1, 10] (the ``$turbidity`` default).
    sun_angular_diameter : float or None
        The sun's angular diameter [deg] in [0, 10] (``$sun_angular_diameter``: fogpath's
        disk sun; 0 a delta); None declares none (a delta sun).
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
        Mitsuba's path depth (2 = single scattering, -1 = unlimited), -1 or >= 1.
    ground_reflectance, mesh_reflectance : float or 3 floats, optional
        Diffuse reflectance in [0, 1] of the ground plane and of the mesh (default 0.2).
        The scene's ``$reflectance`` is the plane's ground, or the mesh's surfaces (the
        ground then shares it, or has its own BSDF when ``ground_reflectance`` is given).
        The valley keeps its file's BSDFs.  A mesh file without vertex normals is written
        with ``face_normals`` (flat faces); one with normals keeps them (a note says which).
    overwrite : bool
        Replace an existing ``out``.
    on_note : callable, optional
        Called with each note (the command line prints them); default: a
        :class:`UserWarning` for each ignored Unreal value.
    phase : TabulatedPhase, optional
        A tabulated phase function (e.g. a droplet fog's Mie phase,
        :func:`fogref.mapping.droplet_fog.droplet_fog`), written as the medium's
        ``fogtabphase``; ``g`` must then be its mean cosine (within 1e-3).
    notes : sequence of str
        More notes for the scene's comments (e.g. where the fog's values come from).

    Returns
    -------
    SceneWriteResult

    Raises
    ------
    fogref.errors.ParameterError
        Naming the parameter, its command-line option and the allowed range.
    fogref.errors.FogrefError
        For an output that exists or is not ``.xml``, or that is one of the scene's
        inputs (the mesh, its material libraries, the valley template).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from fogref.models.ue4 import unreal_to_sigma
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "my_fog.xml"
    >>> r = write_scene(out, unreal={"FogDensity": 0.05, "FogHeightFalloff": 0.1, "FogHeight": 250.0},
    ...                 sun_elevation=12, sun_azimuth=-30, geometry="valley")
    >>> float(r.defaults["sigma_t"]) == unreal_to_sigma(0.05, 0.1)[0], r.defaults["fog_height"]
    (True, '2.5')
    >>> r.defaults["sun_elevation"], r.defaults["sun_azimuth"]
    ('12.0', '-30.0')
    >>> print(r.notes[0].replace(": ", ":\\n"))
    Unreal has no albedo or phase function:
    the fog uses albedo 0.9 and Henyey-Greenstein g 0.6 (the albedo and g parameters)
    """
    out = params.path(out, "out (--out)", source=SOURCE)
    if out.suffix.lower() != ".xml":
        raise FogrefError(f"{SOURCE}: --out '{out}': a scene file must end in .xml")
    if out.exists() and not overwrite:
        raise FogrefError(f"{SOURCE}: --out '{out}' exists; pass --force (overwrite=True) to replace it")
    if out.is_dir():
        raise FogrefError(f"{SOURCE}: --out '{out}' is a folder")
    scatter = {"albedo": 0.9 if albedo is None else albedo, "g": 0.6 if g is None else g}
    if fog is not None and unreal is not None:
        raise FogrefError(
            f"{SOURCE}: give the fog either in physical units (sigma_t, falloff, ...) or as "
            f"Unreal editor values (FogDensity, ...), not both"
        )
    ignored: list[str] = []
    if unreal is not None:
        fogp, ignored = fog_from_unreal(unreal, **scatter)
    else:
        fogp = fog_from_physical(fog, **scatter)
    notes = list(ignored) + list(notes)
    if phase is not None:
        fogp["phase"] = phase.as_params()
        medium_from_params(fogp, SOURCE)  # g against the phase's mean cosine
    if unreal is not None:
        notes.append(
            f"Unreal has no albedo or phase function: the fog uses albedo {value_text(fogp['albedo'])} "
            f"and Henyey-Greenstein g {float_text(fogp['g'])} (the albedo and g parameters)"
        )
    el = check_option(sun_elevation, "sun_elevation", RANGES["sun_elevation"])
    az = check_option(sun_azimuth, "sun_azimuth", RANGES["sun_azimuth"])
    sun_direction_from_angles(el, az)
    sun = check_option(sun_irradiance, "sun_irradiance", RANGES["sun_irradiance"])
    sky_kind = sky
    sky = None if sky_radiance is None else check_option(sky_radiance, "sky_radiance", RANGES["sky_radiance"])
    cam = _camera(camera_origin, camera_target, fov, res, resy)
    depth = check_option(max_depth, "max_depth", RANGES["max_depth"])
    geo = resolve_geometry(geometry)
    scale = check_option(mesh_scale, "mesh_scale", MESH_SCALE)
    params.choice(mesh_up, "mesh_up (--mesh-up)", MESH_UP, SOURCE)
    shift = check_option(mesh_translate, "mesh_translate", MESH_TRANSLATE)
    if geo.kind != "mesh":
        given_args = (
            ("mesh_scale", scale != 1.0),
            ("mesh_up", mesh_up != "y"),
            ("mesh_translate", any(shift)),
            ("mesh_reflectance", mesh_reflectance is not None),
        )
        for name, given in given_args:
            if given:
                raise ParameterError(
                    SOURCE,
                    f"{name} (--{name.replace('_', '-')})",
                    f"applies to a mesh file, not to the '{geo.kind}' template",
                )
    gsize = (
        GROUND_SIZE.get(geo.kind)
        if ground_size is None
        else check_option(ground_size, "ground_size", GROUND_SIZE_RANGE)
    )
    with_ground = (geo.kind != "mesh") if ground is None else bool(ground)
    if geo.kind == "valley" and not with_ground:
        raise ParameterError(SOURCE, "ground (--no-ground)", "the valley template has its own ground")
    if ground_reflectance is not None and (geo.kind == "valley" or not with_ground):
        why = (
            "the valley template keeps the BSDFs of scenes/valley.xml"
            if geo.kind == "valley"
            else "there is no ground plane (add one with --ground)"
        )
        raise ParameterError(SOURCE, "ground_reflectance (--ground-reflectance)", f"does not apply: {why}")
    g_refl, m_refl = (
        None if v is None else check_option(v, name, rng)
        for v, name, rng in (
            (ground_reflectance, "ground_reflectance", GROUND_REFLECTANCE),
            (mesh_reflectance, "mesh_reflectance", MESH_REFLECTANCE),
        )
    )
    inputs = mesh_files(geo.mesh) if geo.kind == "mesh" else [VALLEY_SCENE] if geo.kind == "valley" else []
    _check_inputs(out, inputs)
    flat = geo.kind == "mesh" and not mesh_has_normals(geo.mesh)
    if geo.kind == "mesh":
        notes.append(
            f"mesh {geo.mesh.name}: "
            + (
                "no vertex normals in the file: shaded with face normals (face_normals, flat faces)"
                if flat
                else "shaded with the file's vertex normals"
            )
        )
    # $reflectance: the plane's ground, or the mesh's surfaces (its ground shares it unless given its own)
    refl = g_refl if geo.kind == "plane" else m_refl
    own_ground = (
        geo.kind == "mesh"
        and g_refl is not None
        and (rgb3(g_refl) != rgb3(DEFAULT_REFLECTANCE if m_refl is None else m_refl))
    )
    if own_ground:
        notes.append(
            f"the ground's reflectance {value_text(g_refl)} is written in its BSDF; "
            "the reflectance default is the mesh's"
        )

    params.choice(sky_kind, "sky (--sky)", ("constant", "sunsky"), SOURCE)
    if sky_kind == "sunsky":
        sky = None
    defaults = scene_defaults(fogp, cam, depth, el, az, sun, sky, geo.kind, reflectance=refl)
    if sky_kind == "sunsky":
        defaults["turbidity"] = float_text(check_option(turbidity, "turbidity", RANGES["turbidity"]))
        if el < 0:
            notes.append(
                f"the sun is {float_text(-el)} deg below the horizon: Mitsuba's sunsky then gives no light "
                "(no sun, a black sky): the truth is black"
            )
        if sun_angular_diameter is None:
            sun_angular_diameter = 0.0
    if sun_angular_diameter is not None:
        size = check_option(sun_angular_diameter, "sun_angular_diameter", RANGES["sun_angular_diameter"])
        defaults["sun_angular_diameter"] = float_text(size)
    fog_source = (
        "Unreal editor values " + ", ".join(f"{k}={v}" for k, v in flat_unreal(unreal).items())
        if unreal is not None
        else "physical units"
    )
    root = scene_element(
        defaults,
        fogp,
        geo,
        fog_source=fog_source,
        notes=notes,
        ground_size=gsize,
        with_ground=with_ground,
        out_dir=out.parent,
        mesh_scale=scale,
        mesh_up=mesh_up,
        mesh_translate=shift,
        ground_reflectance=g_refl if own_ground else None,
        face_normals=flat,
    )
    write_xml(out, root)
    if on_note is not None:
        for n in notes:
            on_note(n)
    else:  # Python callers: the ignored Unreal values are warnings (never silent)
        for n in ignored:
            warnings.warn(n, UserWarning, stacklevel=2)
    return SceneWriteResult(out, defaults, notes)
