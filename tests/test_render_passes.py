"""``mi.render`` with fogpath renders in passes, as the driver does.

Each pass holds every sample's outputs in memory, so ``mi.render`` splits the samples
with :func:`fogref_plugins.passes.pass_sizes` under ``MAX_LANES`` (here shrunk so that a
12x8 image needs two passes).  Smallest error detected: any pass missing, counted twice,
mis-seeded or mis-weighted changes the mean by a whole pass's share (~50 %), far above
float32 rounding (1e-6 relative, the tolerance).
"""

import numpy as np
import pytest
from render_scenes import base_scene, heightfog

RES = (12, 8)


def _scene(mi):
    return mi.load_dict(base_scene(mi, {"type": "fogpath", "max_depth": 4}, heightfog(mi), res=RES))


@pytest.mark.render
def test_one_pass_is_one_render_moments_call(mitsuba):
    mi = mitsuba
    scene = _scene(mi)
    img = np.array(mi.render(scene, spp=4, seed=3))
    sums, squares = scene.integrator().render_moments(scene, seed=3, spp=4, squares=False)
    assert squares is None
    np.testing.assert_allclose(img, np.array(sums) / 4, rtol=1e-6, atol=1e-7)


@pytest.mark.render
def test_mi_render_splits_into_seeded_passes(mitsuba, monkeypatch):
    import fogref_plugins.passes as passes

    mi = mitsuba
    monkeypatch.setattr(passes, "MAX_LANES", {"llvm": RES[0] * RES[1] * 4, "cuda": RES[0] * RES[1] * 4})
    assert passes.pass_sizes(RES[0] * RES[1], 8, passes.max_lanes(mi.variant())) == [4, 4]
    scene = _scene(mi)
    img = np.array(mi.render(scene, spp=8, seed=3))
    integ = scene.integrator()
    expected = (
        sum(np.array(integ.render_moments(scene, seed=passes.pass_seed(3, k), spp=4)[0]) for k in range(2))
        / 8
    )
    np.testing.assert_allclose(img, expected, rtol=1e-6, atol=1e-7)
    one_pass = np.array(integ.render_moments(scene, seed=3, spp=8)[0]) / 8
    assert not np.allclose(img, one_pass), "the two passes were not seeded apart from one 8-spp call"
