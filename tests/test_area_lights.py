"""fogpath with an area light, against stock Mitsuba (image means over independent runs).

Until this test, fogpath's shadow rays to lights at a finite distance started at
``spawn_ray``'s offset origin (``(1 + |p|) * 8.9e-5``, about 2 mm at 20 m) but stopped at
``dist * (1 - 1e-4)`` of the un-offset distance, i.e. past the light: every light sample of a
light within about 20 m of a surface was occluded by the light itself, and the light came
only from BSDF samples (30 % of the direct light of the scene below).  The sun and the sky,
at infinity, were never affected.
"""

import numpy as np
import pytest
from render_scenes import area_lamp, base_scene, heightfog
from stats import image_means_rgb

pytestmark = pytest.mark.render


def _scene(mi, integrator, fog):
    """A 8 x 8 m area light 3 m over the ground, facing down, and a camera 1.5 m under its
    centre looking down at the lit ground (no edges in view: little noise); no sun, sky or
    occluder."""
    T = mi.ScalarTransform4f()
    d = base_scene(mi, integrator, fog, res=(16, 9), sun=False, sky=False, occluder=False, fov=60)
    d["sensor"]["to_world"] = T.look_at(origin=[2, 1.5, 20], target=[2, 0, 20], up=[0, 0, 1])
    if fog is None:
        del d["sensor"]["medium"]
    d["lamp"] = area_lamp(mi)
    return mi.load_dict(d, parallel=False)


@pytest.mark.parametrize("fog", [False, True], ids=["no-fog-vs-path", "fog-vs-volpath"])
def test_area_light_matches_stock(mitsuba, fog):
    """16 runs of 128 spp each, stock with its own seeds; the difference must be within 4
    standard errors (from the runs' spread) plus 0.1 %.  The standard error of the
    difference is about 0.1 % of the mean, so a bias of 0.5 % or more fails; the bug above
    was a deficit of tens of percent."""
    mi = mitsuba
    medium = heightfog(mi) if fog else None
    stock = {"type": "volpath" if fog else "path", "max_depth": 3}
    ours = image_means_rgb(mi, _scene(mi, {"type": "fogpath", "max_depth": 3}, medium), 16, 128, 10)
    ref = image_means_rgb(mi, _scene(mi, stock, heightfog(mi) if fog else None), 16, 128, 5000)
    se = np.sqrt(ours.var(0, ddof=1) / len(ours) + ref.var(0, ddof=1) / len(ref))
    diff = ours.mean(0) - ref.mean(0)
    assert np.all(se < 2e-3 * ref.mean(0)), (se, ref.mean(0))
    assert np.all(np.abs(diff) < 4 * se + 1e-3 * ref.mean(0)), (diff, se, ref.mean(0))
