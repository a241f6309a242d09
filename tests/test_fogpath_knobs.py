"""The benchmarks' ``fogpath_knobs`` (``benchmarks/_fogpath_knobs.py``): its continuation
splitting runs fogpath's own path loop, and agrees with fogpath.

Continuation splitting (``ms_split``) traces the camera ray's depth-0 stage once and the
continuation after it (fogpath's ``_continuation`` and ``_trace``) N times on a wavefront of its
own, weighted back per camera ray.  Each method renders with its own seeds; its image means must
agree with fogpath's (validated against stock Mitsuba in tests/test_render_vs_stock.py).
"""

import sys
from pathlib import Path

import drjit as dr
import numpy as np
import pytest
from render_scenes import base_scene, heightfog
from stats import image_means_rgb

pytestmark = pytest.mark.render

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.fixture(scope="module")
def knobs(mitsuba):
    """The module that registers ``fogpath_knobs`` (it sets the same variant as ``mitsuba``)."""
    sys.path.insert(0, str(BENCHMARKS))
    try:
        import _fogpath_knobs
    finally:  # the benchmarks' module names stay off the other tests' path
        sys.path.remove(str(BENCHMARKS))
    return _fogpath_knobs


@pytest.fixture(scope="module")
def fogpath_means(mitsuba):
    """fogpath's image means (24 renders, 16x9, 64 spp), the reference of every method here."""
    return image_means_rgb(mitsuba, _scene(mitsuba, "fogpath"), 24, 64, 9000)


def _scene(mi, integrator_type, **integrator):
    d = base_scene(mi, {"type": integrator_type, "max_depth": 6, **integrator}, heightfog(mi), res=(16, 9))
    return mi.load_dict(d, parallel=False)


@pytest.mark.parametrize(
    "over",
    [{"ms_split": 2}, {"ms_split": 3, "ms_split_by": "branch"}, {"ms_split": 2, "ms_split_by": "stddev"}],
    ids=["split2", "branch3", "stddev2"],
)
def test_continuation_splitting_runs_fogpaths_loop_and_agrees_with_fogpath(
    mitsuba, knobs, fogpath_means, monkeypatch, over
):
    """The first render traces fogpath's ``_trace`` on the wavefront of continuations (at least
    2 lanes per camera ray), not a loop of the subclass's own.  Then image means of 24 renders
    each (16x9, 64 spp, independent seeds) against fogpath's: the difference must be within 4
    standard errors (from the renders' spread) plus 0.05 %.  The standard error is 0.09-0.11 %
    of the mean (asserted below 0.2 %), so a bias of about 0.5 % or more fails: the continuations'
    ``multiple`` weighted 3 % too high fails, and so does ``branch``'s medium continuations
    weighted ``1 / N`` instead of ``1 / (N - 1)``."""
    mi = mitsuba
    widths = []
    trace = knobs.FogPathIntegrator._trace

    def counted(self, tr, sampler, p):
        widths.append(dr.width(p.ray.d))
        return trace(self, tr, sampler, p)

    monkeypatch.setattr(knobs.FogPathIntegrator, "_trace", counted)
    split = _scene(mi, "fogpath_knobs", **over)
    a = image_means_rgb(mi, split, 24, 64, 100)
    lanes = 16 * 9 * 64
    assert widths and min(widths) >= 2 * lanes, (widths, lanes)
    b = fogpath_means
    se = np.sqrt(a.var(0, ddof=1) / len(a) + b.var(0, ddof=1) / len(b))
    assert np.all(se < 2e-3 * b.mean(0)), (se, b.mean(0))  # the power stated above
    diff = a.mean(0) - b.mean(0)
    assert np.all(np.abs(diff) < 4 * se + 5e-4 * b.mean(0)), (diff, se, b.mean(0))


@pytest.mark.parametrize(
    "over",
    [{"sky_along_segments": False}, {"surface_control": "false"}],
    ids=["sky-at-vertices", "no-surface-control"],
)
def test_the_skys_older_ways_agree_with_fogpath(mitsuba, knobs, fogpath_means, over):
    """The knobs that ``benchmarks/sky_along.py`` and ``cycles_peer.py`` measure fogpath's sky on
    segments against (the residual's closed form and sample at every vertex; no control variate
    at surfaces, given as the string ``cycles_peer.py --fogpath`` passes) render the same image:
    image means of 24 renders each (16x9, 64 spp, own seeds) against fogpath's, within 4 standard
    errors plus 0.05 % (a bias of about 0.5 % fails, as above).  The scene takes the residual
    (``auto``), so both knobs change what is traced."""
    mi = mitsuba
    scene = _scene(mi, "fogpath_knobs", **over)
    assert scene.integrator().sky_at_media_for(scene) == "residual"
    a = image_means_rgb(mi, scene, 24, 64, 300)
    b = fogpath_means
    se = np.sqrt(a.var(0, ddof=1) / len(a) + b.var(0, ddof=1) / len(b))
    assert np.all(se < 2e-3 * b.mean(0)), (se, b.mean(0))
    diff = a.mean(0) - b.mean(0)
    assert np.all(np.abs(diff) < 4 * se + 5e-4 * b.mean(0)), (diff, se, b.mean(0))


def test_a_knob_that_is_not_a_flag_is_named(mitsuba, knobs):
    """``sky_along_segments`` given something else than true or false: the plugin's ParameterError
    names fogpath_knobs, the parameter and what it got (Mitsuba's loader raises it inside its own
    RuntimeError, as for any plugin)."""
    want = r"fogpath_knobs: parameter 'sky_along_segments': expected true or false, got 'maybe'"
    with pytest.raises(RuntimeError, match=want):
        _scene(mitsuba, "fogpath_knobs", sky_along_segments="maybe")
