"""Verdicts that cannot be right are refused; intervals are honest at their edges.

Each test states the error it detects.  Synthetic truths (no renders): the noise and
its channel correlation are known exactly.
"""

import numpy as np
import pytest
from scipy.stats import norm
from scipy.stats import t as student_t

from fogref.compare.candidate import evaluate_model
from fogref.compare.check import check
from fogref.compare.intervals import bootstrap_interval
from fogref.compare.synthetic import synthetic_truth
from fogref.errors import FogrefError
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams

MODEL = UE4ExponentialHeightFog(UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2))


def _fog_free():
    t = synthetic_truth(MODEL, noise=0.01, seed=3)
    t.inscatter = np.zeros_like(t.inscatter)
    t.stderr["inscatter"] = np.zeros_like(t.inscatter)
    t.transmittance = np.ones_like(t.transmittance)
    return t


def test_fog_free_truth_fails_any_nonzero_inscatter():
    # detects: a relative tolerance against a zero reference (fogref 0.2 passed inscatter 100)
    t = _fog_free()
    res = check(t, {"inscatter": np.full(t.inscatter.shape, 100.0)}, {"inscatter": 0.05})
    assert res.verdict == "fail"
    row = res.row("inscatter", "all", "rel_rmse")
    assert row.verdict == "fail" and row.estimate is None and "absolute tolerance" in row.note
    # with an absolute tolerance the user states, the verdict is about the size of the error
    res = check(
        t,
        {"inscatter": np.full(t.inscatter.shape, 1e-3)},
        {"inscatter": {"rel_rmse": None, "rel_bias": None, "rmse": 1e-2}},
    )
    assert res.row("inscatter", "all", "rmse").verdict == "pass"
    res = check(
        t,
        {"inscatter": np.full(t.inscatter.shape, 100.0)},
        {"inscatter": {"rel_rmse": None, "rel_bias": None, "rmse": 1e-2}},
    )
    assert res.verdict == "fail"


def test_unknown_tolerance_keys_are_errors_with_did_you_mean():
    t = synthetic_truth(MODEL)
    for key, word in (("T/skyy", "did you mean 'sky'"), ("inscater", "did you mean 'inscatter'")):
        with pytest.raises(FogrefError, match=word):
            check(t, MODEL, {key: 0.1})
    with pytest.raises(FogrefError, match="did you mean 'rel_rmse'"):
        check(t, MODEL, {"T": {"rel_rsme": 0.1}})
    # a band that the chosen distance_bands do not make is unknown too
    with pytest.raises(FogrefError, match="unknown region 'd<50m'"):
        check(t, MODEL, {"T/d<50m": 0.1})


def test_named_tolerance_on_an_empty_region_fails():
    # detects: a vacuous pass (fogref 0.2: a tolerance on final/surface with no surface pixels passed)
    t = synthetic_truth(MODEL)
    with pytest.raises(FogrefError, match="unknown region"):
        check(t, MODEL, {"inscatter/d>1000m": {"rel_rmse": 0.05}}, distance_bands=(1e6,))
    res = check(t, MODEL, {"inscatter/d>1e+06m": {"rel_rmse": 0.05}}, distance_bands=(1e6,))
    row = res.row("inscatter", "d>1e+06m")
    assert row.pixels == 0 and row.verdict == "fail" and "no pixels" in row.note
    assert res.row("T", "d>1e+06m").verdict == "empty"  # part-wide defaults over no pixels: not a failure


def test_rmse_interval_is_one_sided_never_zero_width():
    # the debiased MSE of an exact candidate clips at 0: the interval is [0, upper > 0]
    t = synthetic_truth(MODEL, noise=0.02, seed=5, channel_correlation=0.9)
    res = check(t, MODEL)
    for region in ("all", "surface", "sky"):
        row = res.row("inscatter", region, "rel_rmse")
        assert row.low == 0.0 and row.high > 0.0, row


def test_exact_extinction_matches_within_rounding():
    # T of a pixel-exact truth has no noise: the rounding floor (4 ulp) makes an exact
    # float32 model "match" (its interval holds 0) while a 1e-5 relative error does not
    t = synthetic_truth(MODEL)
    T32 = evaluate_model(t, MODEL, precision="float32")["T"]
    row = check(t, {"T": T32}).row("T", "all", "rel_bias")
    assert row.low <= 0.0 <= row.high
    row = check(t, {"T": T32 * (1 + 1e-5)}).row("T", "all", "rel_bias")
    assert row.low > 0.0


@pytest.mark.parametrize("rho", [0.0, 0.9])
def test_synthetic_coverage_with_correlated_channels(rho):
    # 200 synthetic truths: the rel_bias z spread is 1 +- 0.15 whatever the channels' correlation
    # (independent channels assumed for rho = 0.9 gave a spread of ~1.6)
    zs = []
    for seed in range(200):
        t = synthetic_truth(MODEL, noise=0.02, seed=seed, channel_correlation=rho)
        zs.append(
            check(t, MODEL, parts=["inscatter"], distance_bands=()).row("inscatter", "all", "rel_bias").z
        )
    assert abs(np.std(zs, ddof=1) - 1.0) < 0.15


def test_models_receive_hit_and_distance():
    seen = {}

    class Masked(UE4ExponentialHeightFog):
        def evaluate(self, camera, positions, precision="float32", hit=None, distance=None):
            seen["hit"], seen["distance"] = hit, distance
            return super().evaluate(camera, positions, precision)

    t = synthetic_truth(MODEL)
    evaluate_model(t, Masked(MODEL.params))
    assert seen["hit"].shape == t.shape and seen["hit"].dtype == bool
    assert np.array_equal(seen["distance"], t.distance)


@pytest.mark.parametrize("confidence", [0.8, 0.95, 0.99, 0.999])
def test_interval_quantiles_are_scipy_stats(confidence):
    # detects: a wrong quantile behind the intervals' half widths (a normal quantile off by 1e-12
    # relative, or Student's t with the wrong degrees of freedom), against scipy.stats' norm and t
    truth = synthetic_truth(MODEL, noise=0.02, seed=7)
    row = check(truth, MODEL, confidence=confidence, parts=["inscatter"], distance_bands=())
    r = row.row("inscatter", "all", "rel_bias")
    half_width_in_sd = (r.high - r.low) / 2.0 / (r.estimate / r.z)
    assert half_width_in_sd == pytest.approx(norm.ppf(0.5 + confidence / 2.0), rel=1e-12)
    reps = np.array([0.0, 1.0, 2.0, 4.0])
    for k in (2, 5, 40):
        lo, hi = bootstrap_interval(0.0, reps, k, (1.0 - confidence) / 2.0)
        sd = np.std(reps, ddof=1) * np.sqrt(k / (k - 1))
        assert hi / sd == pytest.approx(student_t.ppf(0.5 + confidence / 2.0, k - 1), rel=1e-12)
        assert lo == -hi
