"""fogref.study.budget: the Shapley budget of a non-Unreal model (run_budget, model_engine)."""

import numpy as np
import pytest

from fogref.gbuffer import Truth
from fogref.mapping import PhysicalScene, from_physical
from fogref.media import ExpLayer, FogMedium
from fogref.study import budget as B


def _pf():
    med = FogMedium(sigma_t=0.001, albedo=0.9, g=0.6, layers=(ExpLayer(1.0, 0.014, 0.0),))
    return PhysicalScene(med, (0.4, 0.14, 0.906), (3.2, 2.9, 2.4), (0.2, 0.3, 0.5), (0.0, 2.0, 0.0))


def _pixels(pf, h=12, w=20, seed=0):
    """A synthetic Truth consistent with the closed forms of ``pf``, and a sun-less ``single``."""
    rng = np.random.default_rng(seed)
    cam = np.asarray(pf.camera)
    v = rng.normal(size=(h, w, 3))
    v[..., 2] = np.abs(v[..., 2]) + 1.0
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    hit = v[..., 1] < 0.05
    D = np.where(hit, rng.uniform(5, 3000, (h, w)), 0.0)
    z3 = np.zeros((h, w, 3))
    px = Truth(path="<synthetic>", final=z3, transmittance=z3, attenuated_surface=z3, inscatter=z3, single=z3,
               multiple=z3, surface=rng.uniform(0, 0.5, (h, w, 3)), stderr={},
               surface_coverage=np.ones((h, w)), distance=D, position=cam + v * D[..., None], view=v,
               hit_fraction=hit.astype(float), camera=cam,
               sun_direction=np.asarray(pf.sun_direction), params={})
    cf = B.closed_forms(px, pf)
    px.transmittance = cf["T"]
    px.attenuated_surface = px.transmittance * px.surface
    sky_single = cf["sky"] * rng.uniform(0.5, 1.0, (h, w, 1))
    px.single = cf["sun_att"] * rng.uniform(0.0, 1.0, (h, w, 1)) + sky_single
    px.multiple = rng.uniform(0, 0.05, (h, w, 3))
    px.inscatter = px.single + px.multiple
    px.final = px.attenuated_surface + px.inscatter
    px.stderr = {k: np.zeros((h, w, 3)) for k in ("final", "transmittance", "attenuated_surface", "inscatter",
                                                  "single", "multiple", "surface")}
    return px, sky_single


@pytest.mark.parametrize("name", ["godot", "unity"])
def test_budget_of_a_non_unreal_model_sums_to_its_error(name):
    pf = _pf()
    px, sky = _pixels(pf)
    model = from_physical(name, pf)
    sh = B.run_budget(px, sky, pf, model, resamples=20)
    keys = [r["key"] for r in sh["effects"]]
    assert keys == [k for k in B.EFFECTS if k not in ("refit", "start_distance", "opacity_cutoff")]
    assert sh["model"] == name and sh["coalitions"] == 2 ** len(keys)
    assert sh["share_sum"] == pytest.approx(1.0, abs=1e-12)
    r = model.evaluate(px.camera, px.world_positions(1.0e5), "float32")
    img = px.surface * np.asarray(r.transmittance, float) + np.asarray(r.inscatter, float)
    valid = px.surface_valid
    assert sh["total_sq"] == pytest.approx(float(np.sum((img - px.final)[valid] ** 2)), rel=1e-9)
    assert all(np.isfinite(r["share"]) and r["share_noise"] >= 0 for r in sh["effects"])


def test_model_engine_splits_the_sun_lobe_and_unreal_keeps_all_effects():
    pf = _pf()
    px, sky = _pixels(pf)
    godot = from_physical("godot", pf)
    T, L_sun, L_sky = B.model_engine(godot)(px, {"refit": True, "start_distance": False,
                                                 "opacity_cutoff": False, "float32": False}, 1.0e5)
    assert float(np.max(L_sun)) > 0 and np.all(np.isfinite(L_sky))
    T2, L_sun2, _ = B.model_engine(from_physical("unity", pf))(px, {"refit": True, "start_distance": False,
                                                                    "opacity_cutoff": False,
                                                                    "float32": True}, 1.0e5)
    assert float(np.max(np.abs(L_sun2))) == 0.0
    ue4 = from_physical("ue4", pf)
    assert B.applicable_effects(ue4, ue4) == B.EFFECTS
