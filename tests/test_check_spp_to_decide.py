"""An inconclusive row says how many samples per pixel would decide it
(:attr:`fogref.compare.results.Row.spp_to_decide`), checked against the noise model written
out here.

On a synthetic truth (Gaussian noise of known standard error, independent channels) the
noise variance of each metric scales with the sample count ``n`` of the truth as follows, the
estimate and the error pattern ``delta`` held:

* ``bias``, ``rel_bias``: variance ``V * S / n`` (``S`` the truth's count): the interval's half
  width ``h`` scales as ``sqrt(S / n)``, so a row at distance ``m`` from its tolerance decides
  at ``n = ceil(S (h / m)^2)`` (exact);
* ``rmse``, ``rel_rmse`` (squared scale): ``Var sum(e^2 - s^2) = sum 4 delta^2 s^2 k + 2 s^4 k^2
  (1 + 1 / (n - 1))`` with ``k = S / n`` (Gaussian moments: ``Var e^2 = 4 delta^2 s^2 + 2 s^4``,
  the last factor for ``s^2`` estimated from ``n`` samples), scanned over ``n`` here.

Both agree exactly (the integer count); the rows are chosen inconclusive with the estimate
0.37 of a half width from the tolerance, on both sides (a pass and a fail to come).
"""

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.stats import norm

from fogref.compare.check import check
from fogref.compare.gate import gate_dict, junit_xml
from fogref.compare.synthetic import synthetic_truth
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams

S = 64
CONF = 0.99
PARAMS = UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2)


def setup(noise=0.05, spp=S):
    truth = synthetic_truth(UE4ExponentialHeightFog(PARAMS), noise=noise, seed=3)
    truth.attrs["fogref.spp"] = spp
    off = replace(PARAMS, FogInscatteringColor=tuple(1.01 * c for c in PARAMS.FogInscatteringColor))
    return truth, UE4ExponentialHeightFog(off)


def row_at(truth, cand, metric, tol=None, method="noise"):
    tols = {"inscatter": {m: None for m in ("rel_rmse", "rel_bias", "rmse", "bias")}}
    tols["inscatter"][metric] = tol
    res = check(truth, cand, tols, distance_bands=(), confidence=CONF, method=method)
    return res, res.row("inscatter", "all", metric)


@pytest.mark.parametrize("metric", ["bias", "rel_bias"])
@pytest.mark.parametrize("side", [+1, -1])  # +1: the tolerance above the estimate (a pass to come)
def test_signed_metrics_decide_at_the_inverse_square_count(metric, side):
    truth, cand = setup()
    _, free = row_at(truth, cand, metric)
    h = (free.high - free.low) / 2
    m = 0.37 * h
    res, row = row_at(truth, cand, metric, abs(free.estimate) + side * m)
    assert row.verdict == "inconclusive"
    assert row.spp_to_decide == math.ceil(S * (h / m) ** 2)
    assert f"decided at {row.spp_to_decide} spp" in row.describe()
    # the same figure in the JSON and JUnit outputs of fogref compare
    (jrow,) = [
        r
        for r in gate_dict(res, 3)["rows"]
        if (r["part"], r["region"], r["metric"]) == ("inscatter", "all", metric)
    ]
    assert jrow["spp_to_decide"] == row.spp_to_decide
    assert f"decided at {row.spp_to_decide} spp" in junit_xml(res)


def expected_rmse_count(truth, cand, metric, tol):
    """The smallest n at which the RMSE row decides, from the Gaussian moments (module doc)."""
    L = truth.inscatter
    e = cand.evaluate(
        truth.camera,
        np.where(truth.hit[..., None], truth.position, truth.camera + truth.view * 1e5),
        "float64",
    )
    e = np.broadcast_to(np.asarray(e.inscatter, float), L.shape) - L
    s2 = truth.stderr["inscatter"] ** 2
    Q = float(np.sum(e * e - s2))
    d2 = np.maximum(e * e - s2, 0.0)
    scale = float(np.sum(L * L - s2)) if metric == "rel_rmse" else float(e.size)
    z, z_one = norm.ppf(1 - (1 - CONF) / 2), norm.ppf(CONF)
    for n in range(S + 1, 1 << 22):
        k = S / n
        sd = math.sqrt(np.sum(4 * d2 * s2) * k + np.sum(2 * s2 * s2) * k * k * (1 + 1 / (n - 1))) / scale
        lo, hi = Q / scale - z * sd, Q / scale + z * sd
        hi = max(hi, z_one * sd) if lo <= 0 else hi
        if math.sqrt(max(hi, 0)) <= tol or math.sqrt(max(lo, 0)) > tol:
            return n
    return None


@pytest.mark.parametrize("metric", ["rmse", "rel_rmse"])
@pytest.mark.parametrize("side", [+1, -1])
def test_rmse_metrics_decide_where_the_gaussian_moments_say(metric, side):
    truth, cand = setup()
    _, free = row_at(truth, cand, metric)
    tol = free.estimate + side * 0.37 * (free.high - free.estimate if side > 0 else free.estimate - free.low)
    _, row = row_at(truth, cand, metric, tol)
    assert row.verdict == "inconclusive"
    assert row.spp_to_decide == expected_rmse_count(truth, cand, metric, tol)


def test_no_count_without_the_truths_count_or_with_the_block_bootstrap():
    truth, cand = setup(spp=0)  # a truth whose noise is taken as exact: nothing scales
    _, free = row_at(truth, cand, "bias")
    tol = abs(free.estimate) + 0.37 * (free.high - free.low) / 2
    _, row = row_at(truth, cand, "bias", tol)
    assert row.verdict == "inconclusive" and row.spp_to_decide is None
    truth, cand = setup()  # the bootstrap's interval also holds the error's spatial spread
    _, row = row_at(truth, cand, "bias", abs(free.estimate), method="block")
    assert row.verdict == "inconclusive" and row.spp_to_decide is None
