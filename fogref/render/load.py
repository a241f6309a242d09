"""Load a fogref scene into Mitsuba, and describe its fog, sun, sky and camera.

:func:`load_scene` hands Mitsuba the scene a :class:`~fogref.scene.parsed.ParsedScene`
holds: the file itself and its overrides (``mi.load_file``), or, for a ``sunsky`` scene,
the tree with the sunsky split into a sky and a sun (:mod:`fogref.render.sunsky`).  The
scene's values are checked before Mitsuba sees them (:func:`describe_scene`,
:func:`fogref.scene.describe.check_renderable`), and its camera is read back from
Mitsuba's sensor (:func:`sensor_camera`: the truth's header).
"""

from __future__ import annotations

import copy
import gc
import json
import math
import re
import weakref

import numpy as np

from fogref.errors import FogrefError
from fogref.render.sunsky import load_lowered, lower_sunsky
from fogref.render.variant import set_variant
from fogref.scene.describe import check_renderable, describe
from fogref.scene.parsed import ParsedScene, read_scene


def describe_scene(scene, overrides: dict | None = None) -> dict:
    """:func:`fogref.scene.describe.describe` of a fogref scene (a path, with ``overrides``, or a
    :class:`~fogref.scene.parsed.ParsedScene`), a ``sunsky`` split by
    :func:`fogref.render.sunsky.lower_sunsky` (which sets Mitsuba up).  Raises as
    :func:`~fogref.scene.parsed.read_scene` and :func:`~fogref.scene.describe.describe`.
    """
    return describe(scene if isinstance(scene, ParsedScene) else read_scene(scene, overrides), lower_sunsky)


def _mitsuba_reason(e: Exception) -> str:
    """Mitsuba's load error on one line: where it happened and, for a plugin that raised, the
    exception it raised (the last line of the traceback Mitsuba embeds)."""
    lines = [x.strip() for x in str(e).strip().splitlines() if x.strip()]
    if not lines:
        return type(e).__name__
    first = re.sub(r"^\[[^\]]*\]\s*", "", lines[0]).replace("Traceback (most recent call last):", "")
    first = first.strip().rstrip(":")
    return f"{first}: {lines[-1]}" if len(lines) > 1 else first


def load_scene(scene, overrides: dict | None = None):
    """``mi.load_file`` with fogref's plugins registered and errors made readable.

    ``scene``: a path (with ``overrides``, as ``fogref render --set``) or a
    :class:`~fogref.scene.parsed.ParsedScene`.  Sets Mitsuba up first
    (:func:`fogref.render.variant.set_variant`: the variant already set, else
    ``$FOGREF_VARIANT``, else ``llvm_ad_rgb``).  The scene's values are checked first
    (:func:`describe_scene`, :func:`~fogref.scene.describe.check_renderable`).  Returns the
    Mitsuba scene and the description with its ``camera`` (:func:`sensor_camera`).
    """
    set_variant()
    import mitsuba as mi

    s = scene if isinstance(scene, ParsedScene) else read_scene(scene, overrides)
    desc = describe_scene(s)
    check_renderable(s.path, s.root)
    lowered = None
    if any(e.get("type") == "sunsky" for e in s.root.iter("emitter")):  # sky and sun split, each once
        lowered = copy.deepcopy(s.root)
        lower_sunsky(lowered, s.defaults, s.path)
    try:
        if lowered is not None:
            mi_scene = load_lowered(s.path, lowered, s.overrides)
        else:
            mi_scene = mi.load_file(str(s.path), parallel=False, **s.overrides)
    except Exception as e:  # Mitsuba's message names the file and line: keep that and the reason
        raise FogrefError(f"{s.path}: Mitsuba could not load the scene: {_mitsuba_reason(e)}") from None
    desc["camera"] = sensor_camera(mi_scene.sensors()[0])
    return mi_scene, desc


#: The scene loaded in this process (:func:`loaded_scene`): ``(inputs digest, variant, overrides,
#: threads)`` -> ``(scene, description, the integrator's settings as loaded)``; one entry at most.
_LOADED: dict = {}


def loaded_scene(parsed: ParsedScene, threads: int | None = None):
    """:func:`load_scene` of ``parsed``, kept for later calls in this process: the same scene
    (the same digest of every input file, :attr:`~fogref.scene.parsed.ParsedScene.digest`, so an
    edited file is loaded again), variant and overrides, and thread count, returns the scene
    loaded before, whose integrator keeps its frozen passes.

    ``threads``: Dr.Jit's thread count to set first (None: unchanged).  Returns
    ``(scene, description)`` as :func:`load_scene` (the description a copy the caller may change).
    On every call the integrator's Python settings (``aovs``, ``max_depth``, ...; what a caller
    such as the render driver sets on it) are put back as loaded, so what one render set does not
    leak into the next.  The scene is shared: a caller that changes other values of it (its
    ``mi.traverse`` parameters, its medium) must use :func:`load_scene` instead.

    One scene is kept, and it is released *before* another is loaded (:func:`release_scene`).
    The path-tracing kernel calls the scene's shapes, BSDFs and emitters through Dr.Jit's
    instance registry, and its code holds their registry IDs, which are the lowest ones free
    when the scene is loaded.  Loaded into an empty registry, every scene of one structure gets
    the same IDs, so the kernels compiled for its first values serve every later value (a
    sweep's configurations).  With earlier scenes still alive, each new scene got other IDs and
    its kernels were compiled again: about 2.7 s per configuration of ``valley.xml`` on 2 cores,
    8 configurations 7.8 times slower (``reports/sweeps/kernel_reuse.md``).
    """
    variant = set_variant()
    if threads:
        import drjit as dr

        if dr.thread_count() != int(threads):
            dr.set_thread_count(int(threads))
    key = (parsed.digest, variant, json.dumps(parsed.overrides or {}, sort_keys=True, default=str), threads)
    hit = _LOADED.get(key)
    if hit is None:
        release_scene()
        scene, desc = load_scene(parsed)
        integrator = scene.integrator()
        hit = _LOADED[key] = (scene, desc, dict(vars(integrator)) if hasattr(integrator, "__dict__") else {})
    scene, desc, settings = hit
    for name, value in settings.items():
        if not name.startswith("_"):
            setattr(scene.integrator(), name, value)
    return scene, copy.deepcopy(desc)


def release_scene() -> None:
    """Drop the scene :func:`loaded_scene` keeps, so that its objects' Dr.Jit registry IDs are
    free for the next scene.  A scene that outlives the drop (held by a reference cycle, seen by
    a weak reference to its Python integrator) is collected now; a full collection costs about
    0.1 s in a process that has imported matplotlib and colour-science, so it is run only then."""
    if not _LOADED:
        return
    ((scene, _, _),) = _LOADED.values()
    try:
        integrator = weakref.ref(scene.integrator())
    except TypeError:  # a C++ integrator has no weak reference: collect
        integrator = None
    _LOADED.clear()
    del scene
    if integrator is None or integrator() is not None:
        gc.collect()


def held_scenes() -> list:
    """The Mitsuba scenes :func:`loaded_scene` keeps in this process (none or one)."""
    return [scene for scene, _, _ in _LOADED.values()]


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
