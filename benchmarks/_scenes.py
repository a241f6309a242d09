"""Benchmark scenes (``mi.load_dict``), each rendered by several methods.

Every scene's fog is **bounded** by an axis-aligned box that lies well inside the
scene's bounding sphere (a large ground plane sets it), so that the stock
``directional`` emitter, whose shadow rays reach only 2x the bounding-sphere
radius, sees all of the fog, and ``fogpath`` and stock ``volpath`` solve exactly the
same problem.  Units: metres, y up.

Scenes (96x54 by default):

``valley``
    ``scenes/valley.xml`` (one exponential layer, Unreal FogDensity 0.02 /
    FogHeightFalloff 0.2, low 8-degree sun, blue sky, boxes along a valley), fog
    box x, z in [-1500, 1500] x [-100, 2800], y in [-1, 300].
``two_layer``
    ``scenes/two_layer_sun.xml`` (dense ground layer + thin high haze, g = 0.85,
    sun 12 degrees up, ahead), fog box y in [-1, 600].  Extinction is **grey**
    (0.0045 /m) here instead of the XML's RGB (0.004, 0.0045, 0.005): stock
    ``heterogeneous`` with ``has_spectral_extinction = false`` (needed: with
    spectral extinction a ray that escapes gets weight 0, see docs/design.md)
    takes one scalar extinction.
``zero_falloff``
    a homogeneous fog (falloff 0, sigma_t 0.03 /m, albedo 0.9, g 0.5) in a
    120 x 41 x 120 m box around the camera, ground 300 x 300 m, one occluder
    (as in ``tests/render_scenes.py``); the only scene where stock
    ``homogeneous`` applies.

Methods (``METHODS``):

``fogpath``      fogref's integrator with the ``heightfog`` medium (analytic free flight).
``fogpath_prev`` fogpath with the earlier sky and sun defaults (``sky_at_surfaces = "mis"``,
                 ``sky_at_media = "mis"``,
                 ``sun_sampling_rays = 1``), measured beside today's defaults.
``volpath_hf``   stock ``volpath`` with the ``heightfog`` medium (delta tracking
                 against heightfog's tight per-ray majorant).
``grid64``,      stock ``volpath`` with Mitsuba's ``heterogeneous`` medium on a
``grid256``      1 x N x 1 ``gridvolume`` over the fog box (density sampled at cell
                 **centres**, trilinear interpolation, clamped at the box's
                 top and bottom half cells), ``has_spectral_extinction = false``,
                 ``scale`` = extinction, same albedo, ``hg`` phase.
``homogeneous``  stock ``volpath`` with the ``homogeneous`` medium as the interior
                 of a ``null``-BSDF cube (the fog box) and as the camera's medium
                 (zero-falloff scene only).

All methods use the same ``max_depth`` (Mitsuba's convention: 2 = single
scattering) and the default ``rr_depth`` (5).
"""

from __future__ import annotations

import math

import numpy as np

SCENES = ("valley", "valley_open", "two_layer", "zero_falloff")
METHODS = (
    "fogpath",
    "fogpath_before",
    "fogpath_split",
    "fogpath_nosplit",
    "fogpath_prev",
    "volpath_hf",
    "grid64",
    "grid256",
    "homogeneous",
)
#: fogpath's sun samplers' settings that only ``fogpath_knobs`` (``_fogpath_knobs.py``) reads
KNOBS = {
    "sun_sampling_layers",
    "sun_sampling_mixture",
    "sun_samples",
    "sun_guiding",
    "sun_guiding_g",
    "ms_split",
    "ms_split_by",
    "ms_split_max",
    "sky_along_segments",
    "surface_control",
}
#: fogpath without its variance reduction (one sun sample, sun sampling only in unbounded
#: one-layer fog, no forced splitting, MIS for the sky at surfaces, one sun-sampled segment),
#: measured beside today's defaults
FOGPATH_BEFORE = {
    "sun_samples": 1,
    "sun_sampling_mixture": False,
    "forced_split": False,
    "sky_at_surfaces": "mis",
    "sky_at_media": "mis",
    "sun_sampling_rays": 1,
}
#: fogpath with forced splitting on the camera ray on / off (all else default): the
#: benchmarks measure the one that is not fogpath's default beside ``fogpath``
SPLIT = {"fogpath_split": {"forced_split": True}, "fogpath_nosplit": {"forced_split": False}}
#: fogpath with one option changed (all else default), measured beside ``fogpath``
VARIANTS = {"fogpath_prev": {"sky_at_surfaces": "mis", "sky_at_media": "mis", "sun_sampling_rays": 1}}


def split_method() -> str:
    """The forced-splitting variant that differs from fogpath's default."""
    from fogref_plugins.fogpath import FORCED_SPLIT_DEFAULT

    return "fogpath_nosplit" if FORCED_SPLIT_DEFAULT else "fogpath_split"


def _rgb(v):
    return {"type": "rgb", "value": list(v)}


def _diffuse(v):
    return {"type": "diffuse", "reflectance": _rgb(v)}


def scene_spec(name: str) -> dict:
    """Camera, fog, lights and shapes of a benchmark scene, as plain data.  ``name`` is a scene of
    :data:`SCENES`, optionally with changes after ``+``: ``sunNN`` (the sun NN degrees up, same
    azimuth), ``nosun`` (no sun), ``groundX`` (the ground and rocks grey with reflectance X),
    ``fogX`` (the fog's extinction times X): ``valley_open+sun60+ground0.4``.

    >>> s = scene_spec("valley_open+sun30+ground0.4+fog2")
    >>> round(-s["sun_dir"][1], 3), s["ground"][1], s["bounds"] is None
    (0.5, [0.4, 0.4, 0.4], True)
    >>> s["fog"]["sigma_t"] / scene_spec("valley_open")["fog"]["sigma_t"]
    2.0
    """
    base, *changes = name.split("+")
    spec = _base_spec(base)
    for c in changes:
        if c == "nosun":
            spec["sun"] = None
        elif c.startswith("sun"):
            x, y, z = spec["sun_dir"]
            e, h = math.radians(float(c[3:])), math.hypot(x, z)
            spec["sun_dir"] = [x / h * math.cos(e), -math.sin(e), z / h * math.cos(e)]
        elif c.startswith("ground"):
            rho = float(c[6:])
            spec["ground"], spec["rock"] = (spec["ground"][0], [rho] * 3), [rho] * 3
        elif c.startswith("fog"):
            spec["fog"] = dict(spec["fog"], sigma_t=spec["fog"]["sigma_t"] * float(c[3:]))
        else:
            raise KeyError(f"{name}: unknown change {c!r} (sunNN, nosun, groundX, fogX)")
    return spec


def _base_spec(name: str) -> dict:
    if name == "valley":
        a = 100 * math.log(2) ** 2 * 0.02 / 1000  # Unreal FogDensity 0.02 -> 1/m
        b = 100 * math.log(2) * 0.2 / 1000  # FogHeightFalloff 0.2 -> 1/m
        boxes = [  # (scale, rotate_y_deg, translate)
            ((60, 90, 200), 10, (-220, 0, 600)),
            ((80, 140, 250), -5, (-300, 0, 1300)),
            ((70, 110, 220), -12, (260, 0, 800)),
            ((90, 180, 300), 8, (420, 0, 1800)),
            ((900, 260, 60), 0, (0, 0, 2600)),
            ((4, 3, 4), 30, (-12, 0, 45)),
        ]
        return dict(
            origin=[0, 2, 0],
            target=[0.15, 2.35, 1],
            fov=70,
            fog=dict(sigma_t=a, albedo=0.9, g=0.6, layers=[(1.0, b, 0.0)]),
            bounds=([-1500.0, -1.0, -100.0], [1500.0, 300.0, 2800.0]),
            sun_dir=[-0.4, -0.139173, -0.906],
            sun=[3.2, 2.9, 2.4],
            sky=[0.20, 0.30, 0.50],
            ground=(3000, [0.12, 0.16, 0.08]),
            rock=[0.25, 0.23, 0.20],
            boxes=boxes,
            spheres=[((15, 0, 90), 9)],
        )
    if name == "valley_open":
        # The default scene as fogpath renders it: unbounded fog, where fogpath
        # samples the sun's single scattering from its exact integrand.  Stock
        # volpath + heightfog is fair here too: its sun shadow rays stop at 2R
        # (~8.5 km), where the fog they would still cross has density < 1e-7.
        spec = _base_spec("valley")
        spec["bounds"] = None
        return spec
    if name == "two_layer":
        boxes = [
            ((6, 25, 6), 0, (-20, 0, 150)),
            ((6, 35, 6), 0, (30, 0, 320)),
            ((8, 45, 8), 0, (-60, 0, 600)),
        ]
        return dict(
            origin=[0, 5, 0],
            target=[0, 5.12, 1],
            fov=75,
            fog=dict(sigma_t=0.0045, albedo=0.92, g=0.85, layers=[(1.0, 0.04, 0.0), (0.15, 0.002, 200.0)]),
            bounds=([-1500.0, -1.0, -200.0], [1500.0, 600.0, 2500.0]),
            sun_dir=[0.1, -0.2079, -0.9730],
            sun=[3.3, 3.0, 2.5],
            sky=[0.20, 0.30, 0.52],
            ground=(4000, [0.14, 0.15, 0.10]),
            rock=[0.14, 0.15, 0.10],
            boxes=boxes,
            spheres=[],
        )
    if name == "zero_falloff":
        return dict(
            origin=[0, 4, -20],
            target=[0, 6, 30],
            fov=70,
            fog=dict(sigma_t=0.03, albedo=0.9, g=0.5, layers=[(1.0, 0.0, 0.0)]),
            bounds=([-60.0, -1.0, -60.0], [60.0, 40.0, 60.0]),
            sun_dir=[-0.3, -0.45, -0.84],
            sun=[2.0, 1.9, 1.7],
            sky=[0.2, 0.3, 0.5],
            ground=(150, [0.3, 0.3, 0.25]),
            rock=[0.5, 0.4, 0.3],
            boxes=[((4, 6, 4), 0, (5, 6, 25))],
            spheres=[],
        )
    raise KeyError(name)


def methods_for(name: str) -> list[str]:
    """The methods that apply to a scene (``homogeneous`` needs zero falloff)."""
    spec = scene_spec(name)
    homog = all(L[1] == 0 for L in spec["fog"]["layers"])
    if spec["bounds"] is None:  # grids and stock homogeneous need a box
        return ["fogpath", "fogpath_before", split_method(), *VARIANTS, "volpath_hf"]
    skip = set(SPLIT) - {split_method()}
    return [m for m in METHODS if (m != "homogeneous" or homog) and m not in skip]


def _density_np(spec, y):
    rho = np.zeros_like(y)
    for dens, fall, h in spec["fog"]["layers"]:
        rho += dens * np.exp(-fall * (y - h))
    return rho


def heightfog_dict(mi, spec, **over):
    f = dict(spec["fog"])
    f.update(over)
    layers = f.pop("layers")
    d = {
        "type": "heightfog",
        "profile": "exponential",
        "sigma_t": f["sigma_t"],
        "albedo": f["albedo"],
        "g": f["g"],
        "density": layers[0][0],
        "falloff": layers[0][1],
        "height": layers[0][2],
    }
    if spec["bounds"] is not None:
        d.update(
            bounds_min=mi.ScalarPoint3f(*spec["bounds"][0]), bounds_max=mi.ScalarPoint3f(*spec["bounds"][1])
        )
    if len(layers) > 1:
        d.update(density2=layers[1][0], falloff2=layers[1][1], height2=layers[1][2])
    return d


def grid_medium(mi, spec, n: int):
    """Stock ``heterogeneous`` holding the scene's fog on a 1 x n x 1 grid over the box
    (density at cell centres)."""
    lo, hi = np.array(spec["bounds"][0]), np.array(spec["bounds"][1])
    y = lo[1] + (np.arange(n) + 0.5) / n * (hi[1] - lo[1])
    rho = _density_np(spec, y)
    grid = rho[None, :, None, None].astype(np.float32)  # (z, y, x, channels)
    T = mi.ScalarTransform4f()
    f = spec["fog"]
    return mi.load_dict(
        {
            "type": "heterogeneous",
            "has_spectral_extinction": False,
            "albedo": f["albedo"],
            "scale": f["sigma_t"],
            "sigma_t": {
                "type": "gridvolume",
                "grid": mi.VolumeGrid(grid),
                "to_world": T.translate(lo.tolist()).scale((hi - lo).tolist()),
            },
            "phase": {"type": "hg", "g": f["g"]},
        },
        parallel=False,
    )


def build(
    mi,
    name: str,
    method: str,
    res=(96, 54),
    max_depth: int = 8,
    sun: bool = True,
    sky: bool = True,
    fog_over: dict | None = None,
    integrator_over: dict | None = None,
):
    """A loaded ``mi.Scene`` for (scene, method)."""
    spec = scene_spec(name)
    T = mi.ScalarTransform4f()
    f = spec["fog"]
    integ = {"type": "fogpath" if method.startswith("fogpath") else "volpath", "max_depth": max_depth}
    if method == "fogpath_before":
        integ.update(FOGPATH_BEFORE)
    integ.update(SPLIT.get(method, {}))
    integ.update(VARIANTS.get(method, {}))
    integ.update(integrator_over or {})
    if integ["type"] == "fogpath" and KNOBS & integ.keys():
        import _fogpath_knobs  # noqa: F401  (registers fogpath_knobs)

        integ["type"] = "fogpath_knobs"
    extra = {}
    if method.startswith("fogpath") or method == "volpath_hf":
        medium = mi.load_dict(heightfog_dict(mi, spec, **(fog_over or {})), parallel=False)
    elif method.startswith("grid"):
        medium = grid_medium(mi, spec, int(method[4:]))
    elif method == "homogeneous":
        assert all(L[1] == 0 for L in f["layers"]), "homogeneous needs zero falloff"
        rho = sum(L[0] for L in f["layers"])
        medium = mi.load_dict(
            {
                "type": "homogeneous",
                "sigma_t": f["sigma_t"] * rho,
                "albedo": f["albedo"],
                "phase": {"type": "hg", "g": f["g"]},
            },
            parallel=False,
        )
        lo, hi = np.array(spec["bounds"][0]), np.array(spec["bounds"][1])
        extra["fogbox"] = {
            "type": "cube",
            "to_world": T.translate(((lo + hi) / 2).tolist()).scale(((hi - lo) / 2).tolist()),
            "bsdf": {"type": "null"},
            "interior": medium,
        }
    else:
        raise KeyError(method)
    d = {
        "type": "scene",
        "integrator": integ,
        "sensor": {
            "type": "perspective",
            "fov": spec["fov"],
            "fov_axis": "x",
            "to_world": T.look_at(origin=spec["origin"], target=spec["target"], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": res[0], "height": res[1], "rfilter": {"type": "box"}},
            "sampler": {"type": "independent"},
            "medium": medium,
        },
        "ground": {
            "type": "rectangle",
            "to_world": T.rotate([1, 0, 0], -90).scale(spec["ground"][0]),
            "bsdf": _diffuse(spec["ground"][1]),
        },
    }
    for i, (s, ang, t) in enumerate(spec["boxes"]):
        d[f"box{i}"] = {
            "type": "cube",
            "to_world": T.translate(list(t)).rotate([0, 1, 0], ang).scale(list(s)),
            "bsdf": _diffuse(spec["rock"]),
        }
    for i, (c, r) in enumerate(spec["spheres"]):
        d[f"sphere{i}"] = {"type": "sphere", "center": list(c), "radius": r, "bsdf": _diffuse(spec["rock"])}
    if sun and spec["sun"] is not None:
        d["sun"] = {"type": "directional", "direction": spec["sun_dir"], "irradiance": _rgb(spec["sun"])}
    if sky:
        d["sky"] = {"type": "constant", "radiance": _rgb(spec["sky"])}
    d.update(extra)
    # optimize=False: Mitsuba 3.9.1 merges meshes sharing a BSDF and the merged
    # mesh keeps a wrong bbox (the ground rectangle drops out of scene.bbox()), so
    # the directional emitter's shadow rays (2x bounding-sphere radius) fall short.
    return mi.load_dict(d, optimize=False, parallel=False)
