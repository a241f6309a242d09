"""fogref.study.budget: the Shapley budget of a non-Unreal model (run_budget, model_engine)."""

import numpy as np
import pytest
from budget_truth import budget_scene, synthetic_pixels

from fogref.mapping import from_physical
from fogref.study import budget as B


@pytest.mark.parametrize("name", ["godot", "unity"])
def test_budget_of_a_non_unreal_model_sums_to_its_error(name):
    pf = budget_scene()
    px, sky = synthetic_pixels(pf)
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
    pf = budget_scene()
    px, sky = synthetic_pixels(pf)
    godot = from_physical("godot", pf)
    T, L_sun, L_sky = B.model_engine(godot)(
        px, {"refit": True, "start_distance": False, "opacity_cutoff": False, "float32": False}, 1.0e5
    )
    assert float(np.max(L_sun)) > 0 and np.all(np.isfinite(L_sky))
    T2, L_sun2, _ = B.model_engine(from_physical("unity", pf))(
        px, {"refit": True, "start_distance": False, "opacity_cutoff": False, "float32": True}, 1.0e5
    )
    assert float(np.max(np.abs(L_sun2))) == 0.0
    ue4 = from_physical("ue4", pf)
    assert B.applicable_effects(ue4, ue4) == B.EFFECTS


def test_budget_states_port_vs_engine():
    """The "port vs engine" line: a model with a runnable web engine carries the size measured by
    ``fogref compare --engine`` (engine.json's port_vs_engine) and whether it is at the quantisation
    level; one without (Godot) says there is none; the Unreal study's report says so for Unreal."""
    pf = budget_scene()
    px, sky = synthetic_pixels(pf)
    measured = {"linear_rms": 2.5e-8, "linear_max": 8.3e-8, "canvas_max": 0, "at_quantisation": True}
    sh = B.run_budget(px, sky, pf, "filament", resamples=0, port_vs_engine=measured)
    assert "RMSE 2.5e-08 (max 8.3e-08) radiance" in sh["port_vs_engine"]
    assert "at the quantisation level, as expected" in B.shapley_markdown(sh)
    above = {**measured, "at_quantisation": False}
    off = B.run_budget(px, sky, pf, "filament", resamples=0, port_vs_engine=above)
    assert "ABOVE the quantisation level" in off["port_vs_engine"]
    assert "not measured" in B.run_budget(px, sky, pf, "filament", resamples=0)["port_vs_engine"]
    godot = B.run_budget(px, sky, pf, "godot", resamples=0)
    assert godot["port_vs_engine"] == "Port vs engine (godot): no runnable engine here."
    assert godot["port_vs_engine"] in B.shapley_markdown(godot)
