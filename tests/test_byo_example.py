"""docs/byo.md's CI example, run as it is printed there (so it can never go stale)."""

from pathlib import Path

import pytest

# --- example start ---
import fogref


def test_fog_matches_truth(fogref_truth):
    truth = fogref_truth(fogref.scene_path("valley"), res=(32, 18), spp=64, seed=0)  # rendered once, cached
    model = fogref.build_model("ue4", scene_params=truth.params)  # yours: "my_pkg.fog:MyFog"
    fogref.assert_fog_matches(
        truth,
        model,
        distance_bands=(),
        tolerances={
            "T": 0.001,  # relative RMSE: Unreal's extinction is exact
            "inscatter": {"rel_rmse": None, "rel_bias": None},  # report only: Unreal has no fog shadows
            "inscatter/sky": {"rel_rmse": 0.4, "rel_bias": 0.1},
            "final": {"rel_rmse": None, "rel_bias": None},
            "final/sky": {"rel_rmse": 0.25, "rel_bias": 0.05},
        },
    )


# --- example end ---
test_fog_matches_truth = pytest.mark.render(test_fog_matches_truth)  # it renders (outside the docs' copy)


def test_the_docs_carry_this_example():
    text = Path(__file__).read_text()
    example = text.split("# --- example start ---\n")[1].split("# --- example end ---")[0]
    docs = (Path(__file__).resolve().parents[1] / "docs" / "byo.md").read_text()
    assert example.strip() in docs, "docs/byo.md must carry the example of tests/test_byo_example.py verbatim"
