"""check(): verdicts, intervals and false-alarm rates on synthetic truths with known noise (no render)."""

import numpy as np
import pytest

from fogref.compare.candidate import evaluate_model
from fogref.compare.check import assert_fog_matches, check
from fogref.compare.regions import region_masks
from fogref.compare.synthetic import synthetic_truth
from fogref.errors import FogrefError
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams

MODEL = UE4ExponentialHeightFog(UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2))


def test_exact_model_passes_and_five_percent_inscatter_fails():
    truth = synthetic_truth(MODEL, shape=(36, 64), noise=0.05, seed=3)
    assert check(truth, MODEL).verdict == "pass"
    p = evaluate_model(truth, MODEL)
    r = check(truth, {"T": p["T"], "inscatter": 1.05 * p["inscatter"]})
    assert r.row("inscatter", "all", "rel_bias").verdict == "fail"
    assert r.row("inscatter", "all", "rel_rmse").estimate == pytest.approx(0.05, abs=0.01)
    assert r.row("T", "all").verdict == "pass"
    assert 0 < r.row("composite", "all", "rel_bias").estimate < 0.05  # inscatter is part of the final image


def test_noise_is_taken_out_of_the_rmse():
    """At 20 % per-pixel noise an exact candidate's rel_rmse is ~0, not ~0.2."""
    truth = synthetic_truth(MODEL, shape=(36, 64), noise=0.2, seed=4)
    row = check(truth, MODEL, tolerances={"inscatter": 0.1}).row("inscatter", "all")
    assert row.estimate < 0.05 and row.verdict == "pass"


@pytest.mark.parametrize("method", ["noise", "block"])
def test_false_alarm_rate_at_most_nominal(method):
    """200 truths, exact candidate, tolerance 0: the two-sided 99 % bias interval excludes 0
    in <= ~1 % of them (binomial: <= 6 of 200 at the 0.1 % level for p = 1 %)."""
    fails = 0
    for s in range(200):
        truth = synthetic_truth(MODEL, shape=(36, 64), noise=0.05, seed=100 + s)
        r = check(
            truth,
            evaluate_model(truth, MODEL),
            {"inscatter": {"rel_bias": 0.0, "rel_rmse": 0.0}},
            parts=["inscatter"],
            distance_bands=(),
            method=method,
            n_boot=300,
            seed=s,
        )
        fails += r.row("inscatter", "all", "rel_bias").verdict == "fail"
    assert fails <= 6, f"{fails}/200 false alarms ({method})"


def test_block_bootstrap_holds_under_correlated_noise():
    """Noise shared by 2x2 pixel groups: the block bootstrap keeps its false-alarm rate."""
    fails = 0
    for s in range(200):
        truth = synthetic_truth(MODEL, shape=(36, 64), noise=0.05, seed=500 + s, correlated=True)
        r = check(
            truth,
            evaluate_model(truth, MODEL),
            {"inscatter": {"rel_bias": 0.0}},
            parts=["inscatter"],
            distance_bands=(),
            method="block",
            n_boot=300,
            seed=s,
        )
        fails += r.row("inscatter", "all", "rel_bias").verdict == "fail"
    assert fails <= 8, f"{fails}/200 false alarms"


def test_inconclusive_between_and_tolerances_per_region():
    truth = synthetic_truth(MODEL, shape=(18, 32), noise=0.3, seed=5)
    p = evaluate_model(truth, MODEL)
    r = check(
        truth,
        {"inscatter": 1.02 * p["inscatter"]},
        tolerances={"inscatter": {"rel_bias": 0.02}, "inscatter/sky": {"rel_bias": 0.5}},
    )
    assert r.row("inscatter", "all", "rel_bias").verdict == "inconclusive"
    assert r.row("inscatter", "sky", "rel_bias").tolerance == 0.5
    assert r.row("inscatter", "sky", "rel_bias").verdict == "pass"


def test_regions_and_empty_region():
    truth = synthetic_truth(MODEL, shape=(18, 32))
    masks = region_masks(truth, (50.0,))
    assert list(masks) == ["all", "surface", "sky", "d<50m", "d>50m"]
    assert (masks["d<50m"] | masks["d>50m"]).sum() == masks["surface"].sum()
    r = check(truth, MODEL, distance_bands=(1e6,))
    assert r.row("T", "d>1e+06m").verdict == "empty"


def test_assertion_message_names_part_region_confidence_and_maps(tmp_path):
    truth = synthetic_truth(MODEL, shape=(36, 64), noise=0.02)
    p = evaluate_model(truth, MODEL)
    with pytest.raises(AssertionError) as e:
        assert_fog_matches(truth, {"T": p["T"], "inscatter": 1.05 * p["inscatter"]}, errors_dir=tmp_path)
    msg = str(e.value)
    assert "inscatter/all rel_bias = 0.05" in msg and "99% confidence" in msg and "fail" in msg
    assert str(tmp_path / "errors.exr") in msg and (tmp_path / "errors.exr").is_file()
    assert (tmp_path / "check.json").is_file()


def test_bad_arguments_are_named():
    truth = synthetic_truth(MODEL)
    with pytest.raises(FogrefError, match="unknown part 'fog'"):
        check(truth, MODEL, {"fog": 0.1})
    with pytest.raises(FogrefError, match="unknown metric 'rmse2'"):
        check(truth, MODEL, {"T": {"rmse2": 0.1}})
    with pytest.raises(FogrefError, match="shape"):
        check(truth, {"T": np.ones((4, 4, 3))})
    with pytest.raises(FogrefError, match="non-finite"):
        check(truth, {"T": np.full((18, 32, 3), np.nan)})
    with pytest.raises(FogrefError, match="confidence"):
        check(truth, MODEL, confidence=1.5)
