"""The view an engine renders: the truth's camera, geometry, sun and sky, read from the scene file.

:func:`view_from_scene` reads a fogref scene through the one scene reader
(:func:`fogref.render.load.load_scene`: Mitsuba loads it, so meshes, cubes and transforms are
exactly the truth's) and :func:`view_from_truth` reads the scene a truth was rendered from
(header ``fogref.scene`` and ``fogref.overrides``), refusing a scene whose fog, sun, sky or
camera no longer match the truth's header.  Shapes become world-space triangles
(:class:`Triangles`): meshes as Mitsuba holds them, a ``rectangle`` as two triangles, a
``sphere`` tessellated (:data:`SPHERE_SEGMENTS`), then every edge split until it is short against
its distance from the camera (:data:`EDGE_RATIO`); other shape types and area lights are refused.

Units: metres, y-up, right-handed (three.js's frame too).  Colours: linear RGB.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fogref.errors import FogrefError
from fogref.render.load import load_scene

__all__ = ["EngineView", "Triangles", "pixel_directions", "view_from_scene", "view_from_truth"]

#: Longitude and latitude segments of a tessellated sphere (its silhouette is within
#: ``1 - cos(pi / 96)`` = 5.4e-4 of the radius).
SPHERE_SEGMENTS = (96, 48)
#: Largest triangle edge, relative to its distance from the camera, that the engine is given.
#: A rasteriser interpolates across a triangle from its clipped, sub-pixel-snapped corners: on
#: the 1e5 m ground plane of ``scenes/open_plane.xml`` drawn as two triangles, the view distance
#: SwiftShader interpolated (what three.js's fog sees) was off by a factor of up to 4e4; with edges
#: within 0.5 of their distance (1796 triangles), by 0.1-0.3 % (median) and 3 % at most at 16x9
#: (0.25 did no better).
EDGE_RATIO = 0.5
#: Most triangles one mesh may be subdivided into.
MAX_TRIANGLES = 400_000


@dataclass
class Triangles:
    """One shape: ``positions`` (N, 3) float32 [m], ``normals`` (N, 3) float32 unit or None (the
    engine computes them), ``indices`` (M, 3) uint32, ``reflectance`` linear RGB in [0, 1]."""

    positions: np.ndarray
    normals: np.ndarray | None
    indices: np.ndarray
    reflectance: tuple


@dataclass
class EngineView:
    """What an engine needs to render the truth's view.

    camera: :func:`fogref.render.load.sensor_camera`'s dict (origin, forward, up, right,
    fov_y_deg, resolution [W, H], near_clip, far_clip).  shapes: :class:`Triangles`.
    params: the scene's description (``fogref.params``: medium, sun, sky, camera).
    source: the scene file; notes: what the engine draws differently, said once.
    """

    camera: dict
    shapes: list[Triangles]
    params: dict
    source: str
    notes: list[str] = field(default_factory=list)

    @property
    def shape(self) -> tuple[int, int]:
        """``(H, W)`` pixels."""
        W, H = self.camera["resolution"]
        return int(H), int(W)

    def extent(self) -> tuple[float, float]:
        """The smallest and the largest distance [m] from the camera to a vertex (1 m each without shapes)."""
        o = np.asarray(self.camera["origin"], dtype=np.float64)
        d = [np.linalg.norm(s.positions.astype(np.float64) - o, axis=-1) for s in self.shapes]
        if not d:
            return 1.0, 1.0
        return float(min(x.min() for x in d)), float(max(x.max() for x in d))

    def clip_planes(self) -> tuple[float, float]:
        """The engine camera's ``(near, far)`` [m]: half the nearest vertex's distance (at least the
        scene's ``near_clip``, else 0.01 m) and twice the farthest's, so that nothing in view is
        clipped and the depth buffer's precision is not spent in front of the nearest surface."""
        nearest, farthest = self.extent()
        return max(float(self.camera.get("near_clip") or 0.01), 0.5 * nearest), 2.0 * farthest


def pixel_directions(camera: dict) -> np.ndarray:
    """``(H, W, 3)`` unit directions [world, y-up] through the pixel centres of ``camera``
    (:func:`fogref.render.load.sensor_camera`'s dict and its formula).

    >>> cam = {"forward": [0, 0, 1], "up": [0, 1, 0], "right": [-1, 0, 0], "fov_deg": 90.0,
    ...        "resolution": [2, 1]}
    >>> pixel_directions(cam).round(4).tolist()
    [[[0.4472, 0.0, 0.8944], [-0.4472, 0.0, 0.8944]]]
    """
    W, H = (int(x) for x in camera["resolution"])
    t = math.tan(math.radians(float(camera["fov_deg"])) / 2)
    u = 2 * (np.arange(W) + 0.5) / W - 1
    v = 1 - 2 * (np.arange(H) + 0.5) / H
    f, up, r = (np.asarray(camera[k], dtype=np.float64) for k in ("forward", "up", "right"))
    d = f + (u[None, :, None] * t) * r + (v[:, None, None] * t * H / W) * up
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def _reflectance(shape, source: str, what: str) -> tuple:
    import mitsuba as mi

    bsdf = shape.bsdf()
    p = mi.traverse(bsdf) if bsdf is not None else {}
    keys = [k for k in p.keys() if k.endswith("reflectance.value")]
    if not keys:
        raise FogrefError(
            f"{source}: shape '{what}': its BSDF has no constant diffuse reflectance (the engines draw "
            "diffuse surfaces with one reflectance; textures and other BSDFs are not supported)"
        )
    v = np.asarray(p[keys[0]], dtype=np.float64).reshape(-1)
    v = np.broadcast_to(v, (3,)) if v.size == 1 else v[:3]
    return tuple(float(x) for x in v)


def _sphere(to_world: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    n_lon, n_lat = SPHERE_SEGMENTS
    th = np.linspace(0, np.pi, n_lat + 1)
    ph = np.linspace(0, 2 * np.pi, n_lon + 1)
    T, Ph = np.meshgrid(th, ph, indexing="ij")
    unit = np.stack([np.sin(T) * np.cos(Ph), np.cos(T), np.sin(T) * np.sin(Ph)], -1).reshape(-1, 3)
    pos = unit @ to_world[:3, :3].T + to_world[:3, 3]
    k = np.arange(n_lat)[:, None] * (n_lon + 1) + np.arange(n_lon)[None, :]
    a, b, c, d = k, k + 1, k + n_lon + 1, k + n_lon + 2
    tri = np.concatenate([np.stack([a, c, b], -1), np.stack([b, c, d], -1)]).reshape(-1, 3)
    nrm = unit @ np.linalg.inv(to_world[:3, :3])
    return pos, nrm / np.linalg.norm(nrm, axis=-1, keepdims=True), tri


def _subdivide(pos: np.ndarray, nrm: np.ndarray | None, tri: np.ndarray, origin: np.ndarray) -> tuple:
    """Split every edge longer than :data:`EDGE_RATIO` times the distance of its nearer end from
    ``origin`` at its midpoint, and each triangle into 2, 3 or 4 accordingly, until no edge is that
    long or the mesh would pass :data:`MAX_TRIANGLES`.  Whether an edge splits, and where, depends
    on its two corners alone (``(a + b) / 2``), so both triangles of an edge agree and no crack
    opens.  Returns ``(pos, nrm, tri, done)``."""
    while True:
        c = pos[tri]  # (M, 3 corners, 3); edge k runs from corner k to corner k + 1
        nxt = np.roll(c, -1, axis=1)
        dist = np.linalg.norm(c - origin, axis=-1)
        near = np.minimum(dist, np.roll(dist, -1, axis=1))
        split = np.linalg.norm(nxt - c, axis=-1) > EDGE_RATIO * near
        count = split.sum(axis=1)
        if not count.any() or len(tri) + 3 * int(count.sum()) > MAX_TRIANGLES:
            used, tri = np.unique(tri, return_inverse=True)  # drop the midpoints no triangle uses
            return pos[used], None if nrm is None else nrm[used], tri.reshape(-1, 3), not count.any()
        # rotate each triangle so that its split edges come first (one: edge 0; two: edges 0, 1)
        first = np.where(count == 1, np.argmax(split, axis=1), (np.argmin(split, axis=1) + 1) % 3)
        first = np.where(count == 3, 0, first)
        rows = np.arange(len(tri))[:, None]
        tri = tri[rows, (first[:, None] + np.arange(3)) % 3]
        c = pos[tri]
        mids = (c + np.roll(c, -1, axis=1)) * 0.5  # ab, bc, ca
        ids = len(pos) + np.arange(3 * len(tri)).reshape(-1, 3)
        pos = np.concatenate([pos, mids.reshape(-1, 3)])
        if nrm is not None:
            nm = nrm[tri] + np.roll(nrm[tri], -1, axis=1)
            nm /= np.maximum(np.linalg.norm(nm, axis=-1, keepdims=True), 1e-30)
            nrm = np.concatenate([nrm, nm.reshape(-1, 3)])
        a, b, cc = tri.T
        ab, bc, ca = ids.T
        out = [tri[count == 0]]
        one, two, three = count == 1, count == 2, count == 3
        out += [np.stack(t, -1)[one] for t in ((a, ab, cc), (ab, b, cc))]
        out += [np.stack(t, -1)[two] for t in ((ab, b, bc), (a, ab, bc), (a, bc, cc))]
        out += [np.stack(t, -1)[three] for t in ((a, ab, ca), (ab, b, bc), (ca, bc, cc), (ab, bc, ca))]
        tri = np.concatenate(out)


def _triangles(shape, source: str, origin: np.ndarray, notes: list) -> Triangles:
    import mitsuba as mi

    what = shape.id() or mi.ShapeType(shape.shape_type()).name.lower()
    if shape.is_emitter():
        raise FogrefError(
            f"{source}: shape '{what}' is an area light; the engine renderer draws only the sun and sky"
        )
    kind = mi.ShapeType(shape.shape_type())
    p = mi.traverse(shape)
    if kind == mi.ShapeType.Mesh and "vertex_positions" in p:
        pos = np.asarray(p["vertex_positions"], dtype=np.float64).reshape(-1, 3)
        tri = np.asarray(p["faces"], dtype=np.int64).reshape(-1, 3)
        vn = np.asarray(p["vertex_normals"] if "vertex_normals" in p else [], dtype=np.float64).reshape(-1, 3)
        nrm = vn if "vertex_normals" in p and vn.shape == pos.shape else None
    elif kind in (mi.ShapeType.Rectangle, mi.ShapeType.Sphere):
        m = np.asarray(p["to_world"].matrix, dtype=np.float64).reshape(4, 4, -1)[..., 0]
        if kind == mi.ShapeType.Sphere:
            pos, nrm, tri = _sphere(m)
        else:  # Mitsuba's rectangle: local [-1, 1]^2 at z = 0, normal +z
            local = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype=np.float64)
            pos = local @ m[:3, :3].T + m[:3, 3]
            n = np.linalg.inv(m[:3, :3]).T @ np.array([0.0, 0.0, 1.0])
            nrm = np.repeat((n / np.linalg.norm(n))[None], 4, 0)
            tri = np.array([[0, 1, 2], [0, 2, 3]])
    else:
        raise FogrefError(
            f"{source}: shape '{what}' ({kind}): the engine renderer draws meshes (obj, ply, cube), "
            "rectangles and spheres"
        )
    pos, nrm, tri, done = _subdivide(pos, nrm, tri, origin)
    if not done:
        notes.append(
            f"shape '{what}': some triangles stay longer than {EDGE_RATIO} of their distance "
            f"({len(tri)} triangles): its depth there is less exact"
        )
    return Triangles(
        positions=pos.astype(np.float32),
        normals=None if nrm is None else nrm.astype(np.float32),
        indices=tri.astype(np.uint32),
        reflectance=_reflectance(shape, source, what),
    )


def _notes(params: dict) -> list[str]:
    notes = []
    sky = params.get("sky") or {}
    if sky and sky.get("type") != "constant":
        notes.append(
            f"the {sky.get('type')} sky is drawn as a uniform radiance (its isotropic projection, "
            "fogref.mapping.PhysicalScene.sky_radiance)"
        )
    sun = params.get("sun") or {}
    if float(sun.get("angular_diameter", 0.0) or 0.0) > 0:
        notes.append("the sun's disk is drawn as a directional light (a delta)")
    return notes


def view_from_scene(path, overrides: dict | None = None) -> EngineView:
    """The view of the fogref scene ``path`` with ``overrides`` (``$default`` name -> value).

    FogrefError (one line, naming the file) for a scene the truth renderer refuses, a shape type
    other than meshes, rectangles and spheres, an area light or a textured BSDF.
    """
    scene, desc = load_scene(path, overrides)
    origin = np.asarray(desc["camera"]["origin"], dtype=np.float64)
    notes = _notes(desc)
    shapes = [_triangles(s, str(path), origin, notes) for s in scene.shapes()]
    return EngineView(camera=desc["camera"], shapes=shapes, params=desc, source=str(path), notes=notes)


def _same(a: Any, b: Any) -> bool:
    """Equal as JSON numbers to 1e-6 relative (a header stores float32-rounded values as text)."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, int | float) and isinstance(b, int | float):
        return math.isclose(float(a), float(b), rel_tol=1e-6, abs_tol=1e-9)
    return a == b


def view_from_truth(truth, scene=None) -> EngineView:
    """The view of a truth (a :class:`fogref.gbuffer.Truth`): its scene file (``scene``, else the
    header's ``fogref.scene``) with the header's overrides.

    FogrefError when the scene file is missing or its fog, sun, sky or camera differ from the
    truth's header (the file changed since the render).
    """
    attrs = truth.attrs
    path = Path(scene if scene is not None else attrs.get("fogref.scene", ""))
    if not str(path) or not path.is_file():
        raise FogrefError(
            f"{truth.path}: its scene file '{path}' (header fogref.scene) is not there; "
            "give the scene with --scene FILE"
        )
    overrides = attrs.get("fogref.overrides") or {}
    if isinstance(overrides, str):
        overrides = json.loads(overrides)
    view = view_from_scene(path, overrides)
    for key in ("medium", "sun", "sky", "camera"):
        have, want = view.params.get(key), truth.params.get(key)
        if key == "camera":
            have = (
                {k: have[k] for k in ("origin", "forward", "up", "fov_deg", "resolution")} if have else None
            )
            want = (
                {k: want.get(k) for k in ("origin", "forward", "up", "fov_deg", "resolution")}
                if want
                else None
            )
        if not _same(have, want):
            raise FogrefError(
                f"{path}: its {key} differs from the one {truth.path} was rendered with "
                f"(the scene changed since); render the truth again or give its scene with --scene FILE"
            )
    return view
