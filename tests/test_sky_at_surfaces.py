"""fogpath's ``sky_at_surfaces = "bsdf"``: a constant sky at surfaces from the BSDF sample alone.

Checked against a closed form (no fog: a Lambertian plane under a constant sky reflects
``albedo * L`` exactly, with zero variance per sample) and against stock ``volpath`` on a
fog scene with a sun, a constant sky and an occluder (image means over independent runs,
stock with its own seeds, standard error from the spread of runs).
"""

import numpy as np
import pytest
from render_scenes import area_lamp, base_scene, heightfog
from stats import image_means_rgb

pytestmark = pytest.mark.render

SKY = (0.2, 0.3, 0.5)
ALBEDO = (0.3, 0.3, 0.25)


SUN_DIRECTION = np.array([-0.3, -0.45, -0.84])  # render_scenes.base_scene's sun
SUN_IRRADIANCE = np.array([2.0, 1.9, 1.7])


def _plane_under_sky(mi, mode, sun):
    """A camera looking straight down at a Lambertian plane, a constant sky, no fog, a sun or not."""
    T = mi.ScalarTransform4f()
    d = base_scene(mi, {"type": "fogpath", "max_depth": 4, "sky_at_surfaces": mode}, None, res=(8, 8))
    d["sensor"]["to_world"] = T.look_at(origin=[0, 5, 0], target=[0, 0, 0], up=[0, 0, 1])
    d["sensor"]["fov"] = 40
    del d["sensor"]["medium"], d["block"]
    if not sun:
        del d["sun"]
    return mi.load_dict(d, parallel=False)


@pytest.mark.parametrize("sun", [False, True], ids=["sky", "sun+sky"])
def test_bsdf_sky_on_a_plane_is_exact_with_zero_variance(mitsuba, sun):
    """Every pixel sees only the plane: ``L = albedo * L_sky + albedo / pi * E cos`` per
    channel (closed form).  With ``bsdf`` every sample is that value (float32 rounding: 1e-5
    relative): the light sample never picks the sky, so the sun is not diluted by the
    choice between sun and sky.  With ``mis`` the same image has per-sample noise, so the
    test sees any change that adds variance."""
    mi = mitsuba
    exact = np.array(ALBEDO) * np.array(SKY)
    if sun:
        cos = -SUN_DIRECTION[1] / np.linalg.norm(SUN_DIRECTION)
        exact = exact + np.array(ALBEDO) / np.pi * SUN_IRRADIANCE * cos
    img = np.array(mi.render(_plane_under_sky(mi, "bsdf", sun), spp=4, seed=3))[..., :3]
    assert np.allclose(img, exact, rtol=1e-5, atol=0), (img.min((0, 1)), img.max((0, 1)), exact)
    noisy = np.array(mi.render(_plane_under_sky(mi, "mis", sun), spp=4, seed=3))[..., :3]
    assert noisy.std() > 1e-3 * exact.mean()  # mis is unbiased but not exact per sample
    assert abs(noisy.mean() / exact.mean() - 1) < 0.05


def _fog_scene(mi, integrator):
    return mi.load_dict(base_scene(mi, integrator, heightfog(mi), res=(16, 9)), parallel=False)


def test_bsdf_sky_in_fog_matches_mis_and_stock_volpath(mitsuba):
    """Fog, sun, constant sky and an occluder.  Image means of 12 runs each.

    * Against fogpath with ``mis`` on the same seeds (paired: the two draw the same random
      numbers, so their difference has a standard error of about 0.005 % of the mean): the
      mean difference must be within 4 of its standard errors plus 0.01 %, so a bias of
      0.03 % or more fails.
    * Against stock ``volpath`` (its own seeds, 128 spp): within 4 standard errors (about
      0.22 % together) plus 0.2 % (the two estimators' float32 differences), so a bias of
      1.1 % or more fails even if ``mis`` were wrong too."""
    mi = mitsuba
    fogpath = {"type": "fogpath", "max_depth": 6}
    bsdf = image_means_rgb(mi, _fog_scene(mi, {**fogpath, "sky_at_surfaces": "bsdf"}), 12, 64, 100)
    mis = image_means_rgb(mi, _fog_scene(mi, {**fogpath, "sky_at_surfaces": "mis"}), 12, 64, 100)
    d = bsdf - mis
    se_d = d.std(0, ddof=1) / np.sqrt(len(d))
    assert np.all(np.abs(d.mean(0)) < 4 * se_d + 1e-4 * mis.mean(0)), (d.mean(0), se_d)
    stock = image_means_rgb(mi, _fog_scene(mi, {"type": "volpath", "max_depth": 6}), 12, 128, 9000)
    se = np.sqrt(bsdf.var(0, ddof=1) / len(bsdf) + stock.var(0, ddof=1) / len(stock))
    diff = bsdf.mean(0) - stock.mean(0)
    assert np.all(np.abs(diff) < 4 * se + 2e-3 * stock.mean(0)), (diff, se, stock.mean(0))


def test_bsdf_sky_with_an_area_light_matches_mis(mitsuba):
    """A sun, a constant sky and a small area light over the ground, no fog: with ``bsdf``
    the light sample picks the sun or the area light with probability ``p / (1 - p_sky)``
    and a BSDF sample that hits the area light is MIS-weighted with that same probability.
    Paired image means of 24 runs against ``mis`` (same seeds): within 4 standard errors of
    the paired difference plus 0.01 %; that standard error is about 0.15 % of the mean, so
    a bias of 0.6 % or more fails (leaving out the ``1 / (1 - p_sky)`` in the hit's MIS
    weight makes one of 1-2 % here)."""
    mi = mitsuba

    def scene(mode):
        d = base_scene(mi, {"type": "fogpath", "max_depth": 4, "sky_at_surfaces": mode}, None, res=(16, 9))
        del d["sensor"]["medium"]
        d["lamp"] = area_lamp(mi)
        return mi.load_dict(d, parallel=False)

    bsdf, mis = image_means_rgb(mi, scene("bsdf"), 24, 64, 40), image_means_rgb(mi, scene("mis"), 24, 64, 40)
    d = bsdf - mis
    se_d = d.std(0, ddof=1) / np.sqrt(len(d))
    assert np.all(se_d < 3e-3 * mis.mean(0)), se_d
    assert np.all(np.abs(d.mean(0)) < 4 * se_d + 1e-4 * mis.mean(0)), (d.mean(0), se_d, mis.mean(0))
