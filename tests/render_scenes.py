"""Small scenes built with mi.load_dict for the render tests (y-up, metres).

The fog is bounded by a box well inside twice the scene's bounding-sphere radius,
so that stock Mitsuba's directional light (whose shadow rays stop at 2R) sees all
of it, and fogpath and volpath solve the same problem.
"""

import numpy as np

BOX_LO, BOX_HI = [-60.0, -1.0, -60.0], [60.0, 40.0, 60.0]


def base_scene(mi, integrator, medium, res=(24, 16), sun=True, sky=True, occluder=True, fov=70):
    T = mi.ScalarTransform4f()
    d = {
        "type": "scene",
        "integrator": integrator,
        "sensor": {
            "type": "perspective",
            "fov": fov,
            "fov_axis": "x",
            # fogpath's camera rays start at the camera and have no far limit; give
            # stock Mitsuba clip planes that make the same difference negligible
            "near_clip": 1e-5,
            "far_clip": 1e7,
            "to_world": T.look_at(origin=[0, 4, -20], target=[0, 6, 30], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": res[0], "height": res[1], "rfilter": {"type": "box"}},
            "medium": medium,
        },
        "ground": {
            "type": "rectangle",
            "to_world": T.rotate([1, 0, 0], -90).scale(150),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.3, 0.3, 0.25]}},
        },
    }
    if occluder:
        d["block"] = {
            "type": "cube",
            "to_world": T.translate([5, 6, 25]).scale([4, 6, 4]),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.5, 0.4, 0.3]}},
        }
    if sun:
        d["sun"] = {
            "type": "directional",
            "direction": [-0.3, -0.45, -0.84],
            "irradiance": {"type": "rgb", "value": [2.0, 1.9, 1.7]},
        }
    if sky:
        d["sky"] = {"type": "constant", "radiance": {"type": "rgb", "value": [0.2, 0.3, 0.5]}}
    return d


def area_lamp(mi):
    """An 8 x 8 m ``area`` light 3 m over the ground at (2, 3, 20), facing down (radiance 20, 18, 15)."""
    T = mi.ScalarTransform4f()
    return {
        "type": "rectangle",
        "to_world": T.translate([2, 3, 20]).rotate([1, 0, 0], 90).scale(4.0),
        "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [20.0, 18.0, 15.0]}},
    }


FOG = dict(sigma_t=0.03, albedo=0.9, g=0.5, falloff=0.06, height=0.0)


def heightfog(mi, **kw):
    p = {"type": "heightfog", **FOG, "bounds_min": BOX_LO, "bounds_max": BOX_HI}
    p.update(kw)
    for k in ("bounds_min", "bounds_max"):
        p[k] = mi.ScalarPoint3f(*p[k])
    return p


def grid_medium(mi, n=256, **kw):
    """Mitsuba's built-in heterogeneous medium holding the same fog on a 2 x n x 2 grid."""
    f = dict(FOG, **kw)
    lo, hi = np.array(BOX_LO), np.array(BOX_HI)
    y = lo[1] + (np.arange(n) + 0.5) / n * (hi[1] - lo[1])  # cell centres
    rho = np.exp(-f["falloff"] * (y - f["height"]))
    grid = np.repeat(np.repeat(rho[None, :, None, None], 2, axis=0), 2, axis=2).astype(np.float32)
    T = mi.ScalarTransform4f()
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


#: the first seed of the stock methods' runs: their own seeds, apart from fogpath's
STOCK_SEED0 = 500_000


def render_runs(mi, scene, n_runs, spp, aov=False, seed0=1000):
    """n independent renders (seeds seed0 .. seed0 + n - 1) as float64 arrays (H, W, C)."""
    out = []
    for s in range(n_runs):
        img = np.array(mi.render(scene, spp=spp, seed=seed0 + s), dtype=np.float64)
        out.append(img if aov else img[..., :3])
    return out
