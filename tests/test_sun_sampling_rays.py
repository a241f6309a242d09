"""fogpath's ``sun_sampling_rays``: the sun also sampled along the segments after the camera ray.

The sun's scattering along each such segment (every one with the default, -1; the segment after
the first vertex with 2) is estimated from its exact integrand (one sample and shadow ray) instead
of by next-event estimation at the segment's medium vertex.  Checked against fogpath with
``sun_sampling_rays = 1`` (validated against stock Mitsuba in tests/test_render_vs_stock.py),
with independent seeds.
"""

import numpy as np
import pytest
from render_scenes import base_scene, heightfog
from stats import image_means_rgb

pytestmark = pytest.mark.render


def _scene(mi, fog, **integrator):
    d = base_scene(mi, {"type": "fogpath", **integrator}, fog, res=(16, 9))
    return mi.load_dict(d, parallel=False)


@pytest.mark.parametrize(
    "bounded, disk, rays",
    [(True, 0.0, -1), (True, 0.0, 2), (False, 0.0, -1), (False, 3.0, -1)],
    ids=["box-mixture", "box-mixture-two", "unbounded-exact", "disk-sun"],
)
def test_sun_sampled_segments_agree_with_one(mitsuba, bounded, disk, rays):
    """Image means of 32 runs each (independent seeds); the difference must be within 4
    standard errors (from the runs' spread) plus 0.05 %.  The standard error is about
    0.07 % (box: the mixture sampler) and 0.12 % (unbounded: the exact sampler) of the
    mean, so a bias of 0.35 % (box) or 0.55 % (unbounded) or more fails.  ``disk``: a 3-degree
    sun disk (the exact sampler aims at a point of the disk; its NEE samples are skipped too).
    ``rays``: every segment (-1) or the two first (2), against the camera ray's alone."""
    mi = mitsuba
    fog = heightfog(mi)
    if not bounded:  # unbounded fog: the exact sampler
        fog = {k: v for k, v in fog.items() if not k.startswith("bounds")}
    kw = {"max_depth": 6, "sun_angular_diameter": disk}
    two = image_means_rgb(mi, _scene(mi, fog, sun_sampling_rays=rays, **kw), 32, 64, 100)
    one = image_means_rgb(mi, _scene(mi, fog, sun_sampling_rays=1, **kw), 32, 64, 7000)
    se = np.sqrt(two.var(0, ddof=1) / len(two) + one.var(0, ddof=1) / len(one))
    diff = two.mean(0) - one.mean(0)
    assert np.all(np.abs(diff) < 4 * se + 5e-4 * one.mean(0)), (diff, se, one.mean(0))


def test_single_scattering_only_is_unchanged(mitsuba):
    """With ``max_depth = 2`` no segment after the camera ray scatters: sampling the sun along
    them must change nothing (bitwise), not add double scattering."""
    mi = mitsuba
    fog = heightfog(mi)
    a = np.array(mi.render(_scene(mi, fog, max_depth=2, sun_sampling_rays=-1), spp=8, seed=1))
    b = np.array(mi.render(_scene(mi, fog, max_depth=2, sun_sampling_rays=1), spp=8, seed=1))
    assert np.array_equal(a, b)
