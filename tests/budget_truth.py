"""A synthetic Truth for the budget tests: consistent with the closed forms of a physical scene."""

import numpy as np

from fogref.gbuffer import Truth
from fogref.mapping import PhysicalScene
from fogref.media import ExpLayer, FogMedium
from fogref.study import budget as B


def synthetic_pixels(pf, h=12, w=20, seed=0, rel_stderr=0.0):
    """A synthetic schema-2 Truth consistent with the closed forms of ``pf``, and a sun-less ``single``."""
    rng = np.random.default_rng(seed)
    cam = np.asarray(pf.camera)
    v = rng.normal(size=(h, w, 3))
    v[..., 2] = np.abs(v[..., 2]) + 1.0
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    hit = v[..., 1] < 0.05
    D = np.where(hit, rng.uniform(5, 3000, (h, w)), 0.0)
    z3 = np.zeros((h, w, 3))
    px = Truth(
        path="<synthetic>",
        final=z3,
        transmittance=z3,
        attenuated_surface=z3,
        inscatter=z3,
        single=z3,
        multiple=z3,
        surface=rng.uniform(0, 0.5, (h, w, 3)),
        stderr={},
        surface_coverage=np.ones((h, w)),
        distance=D,
        position=cam + v * D[..., None],
        view=v,
        hit_fraction=hit.astype(float),
        camera=cam,
        sun_direction=np.asarray(pf.sun_direction),
        params={},
    )
    cf = B.closed_forms(px, pf)
    px.transmittance = cf["T"]
    px.attenuated_surface = px.transmittance * px.surface
    sky_single = cf["sky"] * rng.uniform(0.5, 1.0, (h, w, 1))
    px.single = cf["sun_att"] * rng.uniform(0.0, 1.0, (h, w, 1)) + sky_single
    px.multiple = rng.uniform(0, 0.05, (h, w, 3))
    px.inscatter = px.single + px.multiple
    px.final = px.attenuated_surface + px.inscatter
    px.stderr = {
        k: rel_stderr * np.abs(getattr(px, k))
        for k in (
            "final",
            "transmittance",
            "attenuated_surface",
            "inscatter",
            "single",
            "multiple",
            "surface",
        )
    }
    return px, sky_single


def budget_scene():
    """One exponential layer (sigma_t 1e-3 /m, albedo 0.9, g 0.6), a sun, a sky, the camera 2 m up."""
    med = FogMedium(sigma_t=0.001, albedo=0.9, g=0.6, layers=(ExpLayer(1.0, 0.014, 0.0),))
    return PhysicalScene(med, (0.4, 0.14, 0.906), (3.2, 2.9, 2.4), (0.2, 0.3, 0.5), (0.0, 2.0, 0.0))
