"""fogref.study.budget: the droplets' phase as a Shapley player ("phase" [p]).

Synthetic truths consistent with the closed forms (tests/budget_truth.py) of a fog with the
radiation fog's tabulated Mie phase.  The player's image is checked against the closed form
recomputed with HG in the medium (the sun's single scattering is then exactly the truth's
times ``HG / p``: the synthetic ``sun_render`` is the closed form times a per-pixel factor);
the budget still sums to the model's squared error; an HG fog has no such player, and its
budget is unchanged.
"""

import dataclasses

import numpy as np
import pytest
from budget_truth import budget_scene, synthetic_pixels

from fogref.mapping import from_physical
from fogref.mapping.droplet_fog import droplet_fog
from fogref.media import NP, single_scatter_sun
from fogref.study import budget as B


def _droplet_scene():
    pf = budget_scene()
    return dataclasses.replace(
        pf, medium=dataclasses.replace(pf.medium, phase=droplet_fog(None, "radiation").phase)
    )


def test_phase_player_switches_the_sun_to_hg():
    pf = _droplet_scene()
    px, sky = synthetic_pixels(pf)
    parts = B.shapley_parts(px, sky, pf, B.model_engine(from_physical("godot", pf)))
    img = B.coalition_image(parts, {"phase", "shadows"}, fixed=("refit",))
    hg = dataclasses.replace(pf.medium, phase=None)  # g: the Mie phase's mean cosine
    o, d, D = px.rays()
    sun_hg = np.stack(single_scatter_sun(NP, hg, o, d, D, pf.sun_direction, pf.sun_irradiance), -1)
    ref = px.attenuated_surface + sun_hg.reshape(px.final.shape) + sky + parts["multiple"]
    np.testing.assert_allclose(img, ref, rtol=1e-9, atol=1e-15)
    assert np.max(np.abs(img - B.coalition_image(parts, {"shadows"}, fixed=("refit",)))) > 1e-6


@pytest.mark.parametrize("name", ["godot"])
def test_budget_with_the_phase_player_sums_to_the_error(name):
    pf = _droplet_scene()
    px, sky = synthetic_pixels(pf)
    model = from_physical(name, pf)
    sh = B.run_budget(px, sky, pf, model, resamples=10)
    keys = [r["key"] for r in sh["effects"]]
    assert keys[-1] == "phase" and sh["coalitions"] == 2 ** len(keys)
    assert sh["share_sum"] == pytest.approx(1.0, abs=1e-12)
    row = sh["effects"][-1]
    assert row["effect"] == "p" and row["label"] == B.PHASE[2] and row["share"] != 0.0


def test_hg_fog_has_no_phase_player():
    pf = budget_scene()
    godot = from_physical("godot", pf)
    assert "phase" not in B.applicable_effects(godot, None, pf)
    assert B.phase_effect(pf) == () and B.phase_effect(_droplet_scene()) == ("phase",)
