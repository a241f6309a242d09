"""Geometry templates of ``fogref scene``: a ground plane, the shipped valley, or a mesh file.

``"plane"`` is a ground plane at y = 0; ``"valley"`` is the geometry of the
shipped default scene, read from ``scenes/valley.xml`` (its BSDFs, ground and
ridges are copied from the file, so the template and the scene cannot drift); a
mesh file (``.obj`` or ``.ply``) is loaded by Mitsuba's ``obj``/``ply`` shape
plugins with its scale (metres per file unit) and up axis: ``"z"`` turns a z-up
file into fogref's y-up frame by a -90 deg rotation about +x (keeping the
handedness); ``"unreal"`` swaps y and z like fogref's Unreal position mapping,
``(x, y, z)_fogref = (X, Z, Y)_Unreal / 100`` with scale 0.01, so a level exported
in Unreal's world coordinates lines up with cameras converted the same way.

A mesh is shaded as it is: a file with vertex normals (OBJ ``vn`` lines, PLY
``nx``/``ny``/``nz`` vertex properties) keeps them; a file without them is written
with ``face_normals`` (Mitsuba's ``obj``/``ply`` plugins would otherwise compute
smooth normals by averaging at each shared vertex, which rounds a box's corners:
normals (±0.577, ±0.577, ±0.577) and faces shaded up to half too dark).

Each function adds elements to an :class:`xml.etree.ElementTree.Element`; nothing
here needs Mitsuba.
"""

from __future__ import annotations

import copy
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

from fogref.errors import ParameterError
from fogref.scene.defaults import parse_scene
from fogref.scene.vocabulary import SOURCE, float_text
from fogref.shipped_scenes import SCENES_DIR

__all__ = [
    "GROUND_SIZE",
    "MESH_PLUGINS",
    "MESH_UP",
    "TEMPLATES",
    "VALLEY_SCENE",
    "Geometry",
    "add_mesh",
    "mesh_files",
    "mesh_has_normals",
    "add_valley",
    "diffuse",
    "geometry",
    "ground",
    "ground_tiles",
    "sub",
]

#: Built-in geometry templates (anything else must be a mesh file).
TEMPLATES = ("plane", "valley")
#: Mesh file extensions and the Mitsuba shape plugin that loads each.
MESH_PLUGINS = {".obj": "obj", ".ply": "ply"}
#: Frames a mesh file may have: "y" (fogref's, y-up), "z" (z-up, rotated -90 deg about +x into
#: y-up) or "unreal" (Unreal's z-up left-handed frame, swapped (x, y, z) -> (x, z, y) as
#: :func:`fogref.models.ue4.world_to_unreal` maps positions: a mirror).
MESH_UP = ("y", "z", "unreal")
#: Default half-size [m] of the ground plane of the plane and mesh templates (the valley keeps its file's).
GROUND_SIZE = {"plane": 1.0e5, "mesh": 1.0e5}
#: The shipped scene whose geometry the "valley" template copies.
VALLEY_SCENE = SCENES_DIR / "valley.xml"


@dataclass(frozen=True)
class Geometry:
    """A resolved ``geometry`` argument: ``kind`` "plane", "valley" or "mesh"; a mesh's file and plugin."""

    kind: str
    mesh: Path | None = None
    plugin: str | None = None


def geometry(template) -> Geometry:
    """The template named ``template`` ("plane", "valley") or a mesh file path, checked.

    >>> geometry("valley")
    Geometry(kind='valley', mesh=None, plugin=None)
    >>> geometry("hills")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: fogref scene: parameter 'geometry (--geometry)': unknown template...
    """
    t = str(template)
    if t in TEMPLATES:
        return Geometry(t)
    path = Path(t)
    ext = path.suffix.lower()
    choices = f"choose {', '.join(TEMPLATES)} or a mesh file ({', '.join(MESH_PLUGINS)})"
    if ext not in MESH_PLUGINS:
        if path.is_file():
            raise ParameterError(
                SOURCE,
                "geometry (--geometry)",
                f"'{t}': Mitsuba loads meshes from {', '.join(MESH_PLUGINS)} files only, "
                f"not '{ext or 'no extension'}'; convert it, or {choices}",
            )
        raise ParameterError(SOURCE, "geometry (--geometry)", f"unknown template '{t}': {choices}")
    if not path.is_file():
        raise ParameterError(SOURCE, "geometry (--geometry)", f"mesh file '{t}' not found")
    return Geometry("mesh", path, MESH_PLUGINS[ext])


def mesh_has_normals(path: Path) -> bool:
    """Whether a mesh file carries vertex normals: an OBJ ``vn`` line, a PLY vertex property ``nx``.

    >>> import tempfile
    >>> f = Path(tempfile.mkdtemp()) / "t.obj"
    >>> _ = f.write_text("v 0 0 0\\nv 1 0 0\\nv 0 1 0\\nf 1 2 3\\n")
    >>> mesh_has_normals(f)
    False
    """
    if path.suffix.lower() == ".ply":
        with open(path, "rb") as fh:
            for raw in fh:  # the header is ASCII lines up to end_header, for binary PLYs too
                words = raw.decode("ascii", "replace").split()
                if words[:1] == ["end_header"]:
                    return False
                if words[:1] == ["property"] and words[-1:] == ["nx"]:
                    return True
        return False
    with open(path, "rb") as fh:
        return any(line.lstrip().startswith(b"vn ") or line.lstrip().startswith(b"vn\t") for line in fh)


def mesh_files(path: Path) -> list[Path]:
    """The files a mesh brings: the mesh and, for an OBJ, the material libraries it names
    (``mtllib``, beside it).  ``fogref scene --out`` must replace none of them."""
    files = [path]
    if path.suffix.lower() == ".obj":
        with open(path, "rb") as fh:
            for line in fh:
                words = line.decode("utf-8", "replace").split()
                if words[:1] == ["mtllib"]:
                    files += [path.parent / w for w in words[1:]]
    return files


def sub(parent, tag: str, **attrs):
    """A child element of ``parent`` with the attributes as text."""
    return ET.SubElement(parent, tag, {k: str(v) for k, v in attrs.items()})


def diffuse(parent, bsdf_id: str, reflectance: str, twosided: bool = False):
    """A diffuse BSDF ``bsdf_id`` (wrapped in ``twosided`` for meshes of unknown orientation)."""
    if twosided:
        outer = sub(parent, "bsdf", type="twosided", id=bsdf_id)
        inner = sub(outer, "bsdf", type="diffuse")
    else:
        inner = sub(parent, "bsdf", type="diffuse", id=bsdf_id)
    sub(inner, "rgb", name="reflectance", value=reflectance)


#: Half-size [m] of the ground's central tile (:func:`ground`).
GROUND_TILE = 8.0
#: Each ring of ground tiles is this many times wider than the one inside it.
GROUND_GROWTH = 4.0


def ground_tiles(size: float) -> list[tuple[float, float, float, float]]:
    """The rectangles ``(cx, cz, hx, hz)`` [m] (centre and half-sizes in x and z) that tile the
    ground ``[-size, size]^2``: a square of half-size :data:`GROUND_TILE` (or ``size``) at the
    origin, then square rings, each :data:`GROUND_GROWTH` times wider than the last, of four
    rectangles each.  A point at ``(x, z)`` lies in a rectangle whose half-sizes are at most
    ``GROUND_GROWTH * max(|x|, |z|, GROUND_TILE)``.

    >>> ground_tiles(8.0)
    [(0.0, 0.0, 8.0, 8.0)]
    >>> len(ground_tiles(1e5)), ground_tiles(32.0)[1]
    (29, (0.0, 20.0, 32.0, 12.0))
    """
    edges = [min(GROUND_TILE, float(size))]
    while edges[-1] < size:
        edges.append(min(edges[-1] * GROUND_GROWTH, float(size)))
    tiles = [(0.0, 0.0, edges[0], edges[0])]
    for r, R in zip(edges, edges[1:]):
        mid, half = (r + R) / 2, (R - r) / 2
        tiles += [(0.0, mid, R, half), (0.0, -mid, R, half), (mid, 0.0, half, r), (-mid, 0.0, half, r)]
    return tiles


def ground(parent, size: float, bsdf_id: str, shape_id: str = "ground"):
    """A ground at y = 0 over ``[-size, size]^2`` [m], of the rectangles of :func:`ground_tiles`
    (ids ``ground``, ``ground_1``, ...).

    One rectangle of half-size 1e5 m put its hit points up to 1 cm off the plane's true
    intersection (float32 Mitsuba, LLVM): the error scales with the size of the shape that is hit.
    Tiles keep it at float32 rounding of the hit point's own coordinates."""
    for k, (cx, cz, hx, hz) in enumerate(ground_tiles(size)):
        s = sub(parent, "shape", type="rectangle", id=shape_id if k == 0 else f"{shape_id}_{k}")
        tw = sub(s, "transform", name="to_world")
        sub(tw, "scale", x=float_text(hx), y=float_text(hz), z="1")
        sub(tw, "rotate", x="1", angle="-90")
        if cx or cz:
            sub(tw, "translate", x=float_text(cx), y="0", z=float_text(cz))
        sub(s, "ref", id=bsdf_id)


def add_valley(root, ground_size: float | None = None):
    """The valley's BSDFs and shapes (with the comments among them), copied from ``scenes/valley.xml``.

    ``ground_size`` [m] replaces the ground's half-size (None: the file's).
    """
    if not VALLEY_SCENE.is_file():
        raise ParameterError(
            SOURCE,
            "geometry (--geometry)",
            f"the valley template reads {VALLEY_SCENE}, which is missing "
            "(fogref installs it with the package: reinstall fogref)",
        )
    started = False
    for el in parse_scene(VALLEY_SCENE, comments=True):  # its comments label the ridges
        started = started or el.tag == "bsdf"
        if started and el.tag in ("bsdf", "shape", ET.Comment):
            root.append(copy.deepcopy(el))
    if ground_size is not None:
        scale = root.find("shape[@id='ground']/transform[@name='to_world']/scale")
        scale.set("value", float_text(ground_size))


def add_mesh(
    root, geo: Geometry, out_dir: Path, scale: float, up: str, translate, face_normals: bool = False
):
    """The mesh shape of ``geo``, its file named relative to ``out_dir`` (where the scene is written);
    ``face_normals``: flat faces (for a file without vertex normals, :func:`mesh_has_normals`)."""
    # Mitsuba resolves a relative filename against the scene file's folder
    try:
        filename = os.path.relpath(geo.mesh.resolve(), out_dir.resolve())
    except ValueError:  # another drive (Windows)
        filename = str(geo.mesh.resolve())
    root.append(
        ET.Comment(
            f" mesh: {geo.mesh.name}, {float_text(scale)} m per file unit, "
            f"{up}-up in the file (fogref is y-up) "
        )
    )
    s = sub(root, "shape", type=geo.plugin, id="mesh")
    sub(s, "string", name="filename", value=filename.replace(os.sep, "/"))
    if face_normals:
        sub(s, "boolean", name="face_normals", value="true")
    tw = sub(s, "transform", name="to_world")
    sub(tw, "scale", value=float_text(scale))
    if up == "z":  # (x, y, z) -> (x, z, -y): the file's +z becomes +y, a proper rotation
        sub(tw, "rotate", x="1", angle="-90")
    elif up == "unreal":  # (x, y, z) -> (x, z, y): the inverse of world_to_unreal's swap (a mirror)
        sub(tw, "matrix", value="1 0 0 0 0 0 1 0 0 1 0 0 0 0 0 1")
    if any(translate):
        sub(tw, "translate", **{a: float_text(v) for a, v in zip("xyz", translate)})
    sub(s, "ref", id="surface")
