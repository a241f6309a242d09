"""``fogref scene`` / :func:`write_scene`: a fogref scene XML from fog, sun, sky, camera and geometry.

It turns what a user has, fog parameters in physical units **or** Unreal's editor
values, a sun angle, a sky colour, a camera and a level's geometry, into a Mitsuba 3
XML scene that ``fogref render`` takes as is, built like the shipped ones
(``scenes/*.xml``) and declaring the same ``$default`` vocabulary
(:data:`fogref.render.scene_defaults.VOCABULARY`), so ``fogref render --set
NAME=VALUE`` changes any fog, sun, sky or camera value.

The concepts live beside it: the physical fog and the validators in
:mod:`fogref.mapping.fog_input`, the exact Unreal -> physical mapping in
:mod:`fogref.mapping.unreal_editor`, the geometry templates (``"plane"``,
``"valley"`` read from ``scenes/valley.xml``, ``.obj``/``.ply`` meshes) in
:mod:`fogref.render.scene_templates` and the XML in :mod:`fogref.render.scene_xml`.
This module checks the sun, sky, camera and geometry arguments and writes the file.
Units: fogref is **y-up, metres**; Unreal is z-up, centimetres.  Writing needs no Mitsuba.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from fogref.errors import FogrefError, ParameterError
from fogref.mapping.fog_input import PHYSICAL, SCATTERING, SOURCE, _check, _fmt, _text, fog_from_physical
from fogref.mapping.unreal_editor import UNREAL_IGNORED, UNREAL_MAPPED, fog_from_unreal
from fogref.mapping.unreal_editor import flat_unreal as _flat_unreal
from fogref.render.scene_templates import GROUND_SIZE, MESH_PLUGINS, MESH_UP, TEMPLATES
from fogref.render.scene_templates import geometry as resolve_geometry
from fogref.render.scene_xml import scene_defaults, scene_element, write_xml
from fogref.render.sun import sun_direction_from_angles

__all__ = ["MESH_PLUGINS", "MESH_UP", "PHYSICAL", "SCATTERING", "TEMPLATES", "UNREAL_IGNORED",
           "UNREAL_MAPPED", "SceneWriteResult", "fog_from_physical", "fog_from_unreal",
           "write_scene"]

_SCALAR_LIMIT = 1e7  # [m] coordinates of cameras and mesh offsets


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
                             f"the camera looks straight {'up' if d[1] > 0 else 'down'} "
                             f"(origin {o}, target {t}); "
                             f"the camera's up vector is +y, so tilt the view a little")
    f = _check(fov, "fov", "--fov", "number", 0.0, 180.0, "deg")
    if not 0 < f < 180:
        raise ParameterError(SOURCE, "fov (--fov)",
                             f"value {f} outside (0, 180) deg (horizontal field of view)")
    out = {"camera_origin": o, "camera_target": t, "fov": f}
    for name, v in (("res", res), ("resy", resy)):
        x = _check(v, name, f"--{name}", "number", 1, 65536, "pixels")
        if not float(x).is_integer():
            raise ParameterError(SOURCE, f"{name} (--{name})",
                                 f"value {x} must be an integer in [1, 65536] pixels")
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
    >>> r.defaults["sun_elevation"], r.defaults["sun_azimuth"]
    ('12.0', '-30.0')
    >>> print(r.notes[0].replace(": ", ":\\n"))
    Unreal has no albedo or phase function:
    the fog uses albedo 0.9 and Henyey-Greenstein g 0.6 (the albedo and g parameters)
    """
    out = Path(out)
    if out.suffix.lower() != ".xml":
        raise FogrefError(f"{SOURCE}: --out '{out}': a scene file must end in .xml")
    if out.exists() and not overwrite:
        raise FogrefError(f"{SOURCE}: --out '{out}' exists; pass --force (overwrite=True) to replace it")
    if out.is_dir():
        raise FogrefError(f"{SOURCE}: --out '{out}' is a folder")
    scatter = {"albedo": 0.9 if albedo is None else albedo, "g": 0.6 if g is None else g}
    if fog is not None and unreal is not None:
        raise FogrefError(f"{SOURCE}: give the fog either in physical units (sigma_t, falloff, ...) or as "
                          f"Unreal editor values (FogDensity, ...), not both")
    ignored: list[str] = []
    if unreal is not None:
        fogp, ignored = fog_from_unreal(unreal, **scatter)
    else:
        fogp = fog_from_physical(fog, **scatter)
    notes = list(ignored)
    if unreal is not None:
        notes.append(f"Unreal has no albedo or phase function: the fog uses albedo {_text(fogp['albedo'])} "
                     f"and Henyey-Greenstein g {_fmt(fogp['g'])} (the albedo and g parameters)")
    el = _check(sun_elevation, "sun_elevation", "--sun-elevation", "number", -90.0, 90.0, "deg")
    az = _check(sun_azimuth, "sun_azimuth", "--sun-azimuth", "number", -360.0, 360.0, "deg")
    sun_direction_from_angles(el, az)
    sun = _check(sun_irradiance, "sun_irradiance", "--sun-irradiance", "rgb", 0.0, math.inf)
    sky = None if sky_radiance is None else _check(sky_radiance, "sky_radiance", "--sky-radiance", "rgb",
                                                   0.0, math.inf)
    cam = _camera(camera_origin, camera_target, fov, res, resy)
    depth = _check(max_depth, "max_depth", "--max-depth", "number", -1, 1 << 20)
    if not float(depth).is_integer() or depth == 0:
        raise ParameterError(SOURCE, "max_depth (--max-depth)",
                             f"value {depth}: an integer >= 1, or -1 (no limit)")
    geo = resolve_geometry(geometry)
    scale = _check(mesh_scale, "mesh_scale", "--mesh-scale", "number", 0.0, 1e6)
    if scale <= 0:
        raise ParameterError(SOURCE, "mesh_scale (--mesh-scale)",
                             f"value {scale} must be > 0 (metres per file unit)")
    if mesh_up not in MESH_UP:
        raise ParameterError(SOURCE, "mesh_up (--mesh-up)", f"'{mesh_up}' is not one of {', '.join(MESH_UP)}")
    shift = _check(mesh_translate, "mesh_translate", "--mesh-translate", "point", -_SCALAR_LIMIT,
                   _SCALAR_LIMIT, "m")
    if geo.kind != "mesh":
        given_args = (("mesh_scale", scale != 1.0), ("mesh_up", mesh_up != "y"),
                      ("mesh_translate", any(shift)))
        for name, given in given_args:
            if given:
                raise ParameterError(SOURCE, f"{name} (--{name.replace('_', '-')})",
                                     f"applies to a mesh file, not to the '{geo.kind}' template")
    gsize = GROUND_SIZE.get(geo.kind) if ground_size is None else _check(
        ground_size, "ground_size", "--ground-size", "number", 0.0, 1e7, "m")
    if gsize is not None and gsize <= 0:
        raise ParameterError(SOURCE, "ground_size (--ground-size)", f"value {gsize} must be > 0 m")
    with_ground = (geo.kind != "mesh") if ground is None else bool(ground)
    if geo.kind == "valley" and not with_ground:
        raise ParameterError(SOURCE, "ground (--no-ground)", "the valley template has its own ground")

    defaults = scene_defaults(fogp, cam, depth, el, az, sun, sky, geo.kind)
    fog_source = ("Unreal editor values " + ", ".join(f"{k}={v}" for k, v in _flat_unreal(unreal).items())
                  if unreal is not None else "physical units")
    root = scene_element(defaults, fogp, geo, fog_source=fog_source, notes=notes, ground_size=gsize,
                         with_ground=with_ground, out_dir=out.parent, mesh_scale=scale, mesh_up=mesh_up,
                         mesh_translate=shift)
    write_xml(out, root)
    if on_note is not None:
        for n in notes:
            on_note(n)
    else:  # Python callers: the ignored Unreal values are warnings (never silent)
        for n in ignored:
            warnings.warn(n, UserWarning, stacklevel=2)
    return SceneWriteResult(out, defaults, notes)
