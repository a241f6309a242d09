"""fogpath renders a Local Fog Volume added to the height fog, against closed forms.

* ``T`` (the camera ray's closed-form transmittance, per sample, pixel-exact) equals
  ``exp(-sigma_t (tau_height + tau_volume))`` of :class:`fogref.media.FogMedium` and
  :meth:`~fogref.media.local_fog_volume.LocalFogVolume.optical_depth` in float64, on the render's
  own rays (``view``, ``distance``): float32 tolerance 2e-5 + 2e-4 T.
* Free flight through the sum: ``surface_coverage`` is 1 on the samples whose camera ray reached
  the surface or the sky without a collision (grey fog, no forced splitting with a volume), a
  Bernoulli variate of mean ``T``.  Pooled over pixels and 8 independent renders (own seeds), the
  count's z against the closed form, with the binomial standard error of the closed-form ``T``,
  must stay within |z| < 4 (two-sided 6e-5), over all pixels and over the pixels whose ray
  crosses the volume; the renders' empirical standard error agrees with the binomial one.
* fogpath's forced collision refuses a volume (fogpath then uses free flight).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from render_scenes import base_scene, render_runs

from fogref.errors import ParameterError
from fogref.media import NP, medium_from_params

pytestmark = pytest.mark.render
RES = (24, 16)
FOG = dict(sigma_t=0.03, albedo=0.9, g=0.5, falloff=0.06, height=0.0)
LFV = dict(lfv_radius=8.0, lfv_density=4.0, lfv_falloff=0.05, lfv_height=5.0)
CENTRE = (0.0, 5.0, 0.0)


def _scene(mi):
    medium = {"type": "heightfog", **FOG, **LFV, "lfv_centre": mi.ScalarPoint3f(*CENTRE)}
    integrator = {"type": "fogpath", "max_depth": 2, "pixel_exact": True}
    return mi.load_dict(
        base_scene(mi, integrator, medium, res=RES, sun=False, occluder=False), parallel=False
    )


def _closed_form_T(scene, img):
    """(T with the volume, T of the height fog alone) on the render's rays, float64."""
    names = ["R", "G", "B"] + list(scene.integrator().aov_names())
    view = np.stack([img[..., names.index(f"view.{a}")] for a in "XYZ"]).reshape(3, -1).astype(np.float64)
    dist = img[..., names.index("distance")].ravel()
    hit = img[..., names.index("hit")].ravel() > 0.5
    o = tuple(np.full(dist.shape, x) for x in (0.0, 4.0, -20.0))
    t = np.where(hit, dist, NP.largest)
    full = medium_from_params({**FOG, **LFV, "lfv_centre": CENTRE}, "test")
    height = medium_from_params(FOG, "test")
    T = [np.exp(-FOG["sigma_t"] * m.optical_depth(NP, o, tuple(view), t)) for m in (full, height)]
    return [x.reshape(img.shape[:2]) for x in T]


def test_T_channel_is_the_closed_form_of_the_sum(mitsuba):
    mi = mitsuba
    scene = _scene(mi)
    img = np.array(mi.render(scene, spp=1, seed=0), dtype=np.float64)
    names = ["R", "G", "B"] + list(scene.integrator().aov_names())
    T = img[..., names.index("T.R")]
    ref, ref_height = _closed_form_T(scene, img)
    assert np.max(1 - ref / ref_height) > 0.3  # the volume takes a large share of the light
    assert np.all(np.abs(T - ref) <= 2e-5 + 2e-4 * ref), np.max(np.abs(T - ref))


def test_free_flight_through_the_sum_gives_T(mitsuba):
    """Smallest error detected: 4 binomial standard errors of the pooled mean, 0.8 % of the mean T
    over all pixels and 2.4 % over the volume's 100 pixels (printed by the assertion).  Free flight
    that ignored the volume gives z = -42 and -86."""
    mi = mitsuba
    scene = _scene(mi)
    names = ["R", "G", "B"] + list(scene.integrator().aov_names())
    spp, n_runs = 128, 8
    runs = render_runs(mi, scene, n_runs, spp, aov=True)
    cover = np.stack([r[..., names.index("surface_coverage")] for r in runs])  # (runs, H, W)
    ref, ref_height = _closed_form_T(scene, runs[0])
    n = spp * n_runs
    for label, pix in (("all pixels", np.ones(ref.shape, bool)), ("volume", ref_height - ref > 0.02)):
        assert pix.sum() >= 20
        count = cover[:, pix].sum() * spp
        se = math.sqrt(float(np.sum(n * ref[pix] * (1 - ref[pix]))))
        z = (count - n * ref[pix].sum()) / se
        detect = 4 * se / (n * ref[pix].sum())
        assert abs(z) < 4, f"{label}: z = {z:.2f} (smallest relative error detected {detect:.2%})"
        per_run = cover[:, pix].sum(axis=1) * spp  # the renders' spread vs the binomial one
        ratio = per_run.std(ddof=1) / (se / math.sqrt(n_runs))
        assert 0.4 < ratio < 1.8, ratio  # chi-square with 7 dof: 0.4..1.8 is p > 1e-3 both sides


def test_forced_collision_refuses_the_volume(mitsuba):
    from types import SimpleNamespace

    from fogref_plugins.fogpath import FogPathIntegrator

    fog = medium_from_params({**FOG, **LFV}, "test")
    with pytest.raises(ParameterError, match="'lfv_radius'.*forced collision"):
        FogPathIntegrator._forced_collision(None, SimpleNamespace(fog=fog, ops=NP), None, None, 1.0, True)
