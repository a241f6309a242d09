"""A :class:`FogMedium` with a Local Fog Volume: height fog plus sphere, the exact sum.

* parsing: the ``heightfog`` parameters ``lfv_*`` (and their errors, naming the parameter);
* density, optical depth: the layers' plus the volume's, term by term (float64, exact);
* free flight through the sum: a KS test of sampled distances against the closed-form CDF
  ``1 - exp(-sigma (tau_height(t) + tau_volume(t)))`` and the escape fraction at 4 sigma;
* the majorant bound (``max_density``) above the density at random points of the sphere;
* refusals: every closed form, sampler and mapping that knows height layers only.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from fogref.errors import ParameterError
from fogref.media import NP, ExpLayer, FogMedium, LocalFogVolume, medium_from_params
from fogref.media import single_scatter as ss

BALL = LocalFogVolume(centre=(0.0, 6.0, 30.0), radius=10.0, density=4.0, falloff=0.05, height=6.0)
HEIGHT = FogMedium(sigma_t=0.03, albedo=0.9, layers=(ExpLayer(1.0, 0.06, 0.0),))
SUM = FogMedium(sigma_t=0.03, albedo=0.9, layers=(ExpLayer(1.0, 0.06, 0.0),), volume=BALL)
O, D = (0.0, 4.0, 0.0), tuple(np.array([0.05, 0.04, 1.0]) / np.linalg.norm([0.05, 0.04, 1.0]))


def test_params_build_the_volume():
    m = medium_from_params(
        {"sigma_t": 0.03, "lfv_centre": "0, 6, 30", "lfv_radius": 10, "lfv_density": 4, "lfv_falloff": 0.05,
         "lfv_height": 6}
    )  # fmt: skip
    assert m.volume == BALL
    assert medium_from_params({"sigma_t": 0.03}).volume is None


@pytest.mark.parametrize(
    "params, name",
    [
        ({"lfv_density": 1.0}, "lfv_radius"),  # no radius
        ({"lfv_radius": -2.0}, "lfv_radius"),
        ({"lfv_radius": 2.0, "lfv_density": 1e7}, "lfv_density"),
        ({"lfv_radius": 2.0, "lfv_falloff": -1.0}, "lfv_falloff"),
        ({"lfv_radius": 2.0, "lfv_centre": "0, 1"}, "lfv_centre"),
        ({"lfv_radius": 2.0, "lfv_center": "0, 1, 0"}, "lfv_center"),  # a typo: unknown
    ],
)
def test_bad_volume_parameters_name_themselves(params, name):
    with pytest.raises(ParameterError, match=f"<doc>: parameter '{name}'"):
        medium_from_params(params, "<doc>")


def test_density_and_depth_are_the_sums():
    t = np.array([0.0, 15.0, 25.0, 30.0, 45.0, 1e3])
    o = tuple(np.full(t.shape, x) for x in O)
    d = tuple(np.full(t.shape, x) for x in D)
    p = tuple(o[a] + t * d[a] for a in range(3))
    assert np.array_equal(SUM.density(NP, p), HEIGHT.density(NP, p) + BALL.rho(NP, p))
    tau = SUM.optical_depth(NP, o, d, t)
    assert np.array_equal(tau, HEIGHT.optical_depth(NP, o, d, t) + BALL.optical_depth(NP, o, d, t))
    assert float(BALL.optical_depth(NP, O, D, NP.largest)) > 10.0  # the ray goes through the ball
    assert SUM.free_flight_variates == 2 and HEIGHT.free_flight_variates == 1
    assert not SUM.is_homogeneous and not SUM.is_vacuum


def test_free_flight_through_the_sum_ks():
    """Collisions ``min(t_height, t_volume)`` follow ``1 - exp(-sigma tau_sum(t))``.

    n = 20000 pairs of Exp(1) variates (seed fixed): the escape fraction within 4 sigma (smallest
    error detected 0.014) and a KS test of the collisions' CDF values, uniform on [0, F_max]
    (p > 1e-3; detects a CDF off by about 0.014).  Using one variate for both parts, or the
    volume's alone, fails both."""
    rng = np.random.default_rng(11)
    n, sigma = 20000, 0.012
    o = tuple(np.full(n, x) for x in O)
    d = tuple(np.full(n, x) for x in D)
    t_far = 60.0  # the ray's end (a surface)
    t = SUM.sample_distance(NP, o, d, [rng.exponential(size=n), rng.exponential(size=n)], sigma)
    f_max, f_height = (-math.expm1(-sigma * float(m.optical_depth(NP, O, D, t_far))) for m in (SUM, HEIGHT))
    assert 0.4 < f_max < 0.9 and f_max - f_height > 0.2  # the volume takes a large share
    hit = t < t_far
    assert abs(hit.mean() - f_max) < 4.0 * math.sqrt(f_max * (1 - f_max) / n)
    o, d = (tuple(x[hit] for x in v) for v in (o, d))
    cdf = -np.expm1(-sigma * SUM.optical_depth(NP, o, d, t[hit]))
    assert stats.kstest(cdf / f_max, "uniform").pvalue > 1e-3


def test_max_density_bounds_the_density():
    rng = np.random.default_rng(3)
    p = [BALL.centre[a] + rng.uniform(-BALL.radius, BALL.radius, 5000) for a in range(3)]
    y_lo = p[1] - rng.uniform(0.0, 3.0, 5000)
    bound = SUM.max_density(NP, y_lo, p[1] + rng.uniform(0.0, 3.0, 5000))
    assert np.all(SUM.density(NP, p) <= bound * (1 + 1e-12))
    far = BALL.centre[1] + BALL.radius + 1.0
    assert float(BALL.max_density(NP, far, far + 5.0)) == 0.0


def test_height_only_closed_forms_refuse_the_volume():
    """Each refuses with ParameterError naming 'lfv_radius'; fogpath's sun sampling falls back."""
    w, E = (0.0, 0.8, 0.6), (1.0, 1.0, 1.0)
    match = "parameter 'lfv_radius'.*Local Fog Volume"
    with pytest.raises(ParameterError, match=match):
        ss.single_scatter_sun(NP, SUM, O, D, 50.0, w, E)
    with pytest.raises(ParameterError, match=match):
        ss.sample_sun_single_scatter(NP, SUM, O, D, 50.0, w, E, 0.5, 0)
    with pytest.raises(ParameterError, match=match):
        ss.sample_sun_single_scatter_mixture(NP, SUM, O, D, 50.0, w, E, 0.5, 0.5, 0)
    with pytest.raises(ParameterError, match=match):
        SUM.invert_optical_depth(NP, O, D, 1.0, 50.0)
    assert ss.sun_sampling_mode(SUM, w) is None and ss.sun_sampling_mode(HEIGHT, w) == "exact"
    assert not ss.sun_sampling_applies(SUM, w)


def test_mappings_refuse_the_volume():
    """Every game-model mapping reads a PhysicalScene, which refuses a volume."""
    from fogref.mapping import PhysicalScene
    from fogref.study.ue_pathtracer import sun_single_scatter

    with pytest.raises(ParameterError, match="'lfv_radius'.*game-model mappings"):
        PhysicalScene(medium=SUM)
    assert not FogMedium(sigma_t=0.03, layers=(ExpLayer(1.0, 0.0, 0.0),), volume=BALL).is_homogeneous
    with pytest.raises(ParameterError, match="'lfv_radius'"):
        sun_single_scatter(SUM, None, (0.0, 1.0, 0.0))
