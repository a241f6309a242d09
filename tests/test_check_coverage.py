"""``check``'s intervals cover at their nominal rate on real renders (once 10 % missed at 99 %).

32 pairs of independent truths of the default scene (32x18 px, 16 spp, own seeds) are
checked against each other, so every statistic's true value is 0 (see
``coverage_harness``).  Renders at fixed seeds are deterministic, so the test's outcome
is too.

* **Miss rate.**  Over the 256 distinct statistics (8 per pair) the misses of the
  99 % intervals must stay below the binomial limit at alpha = 1 % for the nominal
  rate (0.75 %: the RMSEs miss one-sided); a true miss rate of 10 % (fogref 0.2 on
  this scene) is detected with power >= 0.99, a rate of 4 % with the power stated
  in the assertion.
* **z spread** of the signed metrics (``bias``, ``rel_bias``; linear statistics whose
  variance is exact under the delta method): 1 +- 0.15.  The RMSEs' variance uses a
  Gaussian fourth moment, which the heavy-tailed path samples make conservative (their
  z spread is below 1: they over-cover); the test asserts that side only.
* **The old noise model fails here**: the same renders with the channels' correlation
  set to 0 (what fogref 0.2's ``check`` assumed) fail the binomial test and the z spread.
* **False alarms of the verdicts**: with a tolerance of 0 on ``bias`` an exact
  candidate *fails* exactly when its interval misses 0, so the verdicts' false-alarm
  rate is the miss rate above (asserted through the verdicts themselves).
"""

from pathlib import Path

import coverage_harness as H
import numpy as np
import pytest

pytestmark = pytest.mark.render

ROOT = Path(__file__).resolve().parents[1]
N_TRUTHS = 64


@pytest.fixture(scope="module")
def truths(tmp_path_factory):
    import fogref

    fogref.set_variant()
    return H.render_truths(ROOT / "scenes" / "valley.xml", tmp_path_factory.mktemp("coverage"), N_TRUTHS)


def test_intervals_cover_at_nominal_rate(truths):
    s = H.summary(H.coverage_rows(truths))
    d = s["distinct"]
    assert d["n"] >= 200 and len(H.coverage_rows(truths)) >= 200
    assert s["power_at_10pct"] >= 0.99
    assert d["misses"] < s["binomial_limit"], (
        f"{d['misses']} of {d['n']} distinct 99 % intervals miss 0 (limit {s['binomial_limit']}, "
        f"nominal {s['distinct_expected_miss_rate']:.2%}, binomial p = {s['binomial_p']:.3g})"
    )
    assert abs(s["signed"]["z_sd"] - 1.0) <= 0.15, s["signed"]
    rmse_z = [r[5] for r in H.coverage_rows(truths) if r[3] == "rmse" and r[5] is not None]
    assert np.std(rmse_z, ddof=1) <= 1.15  # conservative side only (module docstring)


def test_old_noise_model_fails_the_same_test(truths):
    s = H.summary(H.coverage_rows(truths, channel_correlation="independent"))
    assert s["distinct"]["misses"] >= s["binomial_limit"] or abs(s["signed"]["z_sd"] - 1.0) > 0.15
    assert s["signed"]["z_sd"] > 1.3, s["signed"]


def test_verdicts_false_alarm_rate(truths):
    from fogref.compare.check import check

    fails = n = 0
    for k in range(len(truths) // 2):
        res = check(
            truths[2 * k],
            truths[2 * k + 1],
            {"inscatter/surface": {"bias": 0.0}},
            parts=["inscatter"],
            distance_bands=(),
        )
        row = res.row("inscatter", "surface", "bias")
        covered = row.low <= 0 <= row.high
        assert (row.verdict == "fail") == (not covered)
        fails += row.verdict == "fail"
        n += 1
    # at most 4 of 32 (P <= 0.5 % under the nominal 1 %); fogref 0.2 failed 10 % of such rows
    assert fails <= 3, f"{fails} of {n} exact candidates failed at a nominal 1 % false-alarm rate"
