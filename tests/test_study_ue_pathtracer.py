"""The UE path-traced fog study: quadrature of the sun's single scattering, the closed-form
split, and a render split on a tiny image."""

from __future__ import annotations

import numpy as np
import pytest

from fogref.gbuffer import covariance
from fogref.mapping.unreal import sample_views
from fogref.mapping.unreal_pathtracer import UEPathTracerSettings, exact_medium
from fogref.media import NP, single_scatter_sun
from fogref.models.ue4 import UE4FogParams
from fogref.study.ue_pathtracer import (
    closed_form_split,
    departure_row,
    render_split,
    split_stats,
    sun_single_scatter,
)

SUN = tuple(np.array([0.3, 0.35, 0.88]) / np.linalg.norm([0.3, 0.35, 0.88]))


def test_quadrature_matches_the_closed_form_on_the_exact_fog():
    """The quadrature used for the bounded fog, applied to the unbounded exact fog, against
    fogref's closed form: 1e-4 relative (the sweep's threshold is 1e-2)."""
    ue, pt = UE4FogParams(FogDensity=0.2, FogHeightFalloff=0.5), UEPathTracerSettings()
    m = exact_medium(ue, pt)
    views = sample_views((0.0, 2.0, 0.0), n_dirs=48, distances=[20.0, 300.0, 5000.0])
    got = sun_single_scatter(m, views, SUN)
    o = tuple(np.full(len(views.D), c) for c in views.camera)
    d = tuple(views.d[:, i] for i in range(3))
    D = np.where(views.sky, NP.largest, views.D)
    ref = single_scatter_sun(NP, m, o, d, D, SUN, (1.0, 1.0, 1.0))[0]
    assert ref.max() > 1e-3
    np.testing.assert_allclose(got, ref, rtol=1e-4, atol=1e-7 * ref.max())


def test_split_stats_is_the_shared_noise_model_written_out():
    """split_stats (through fogref.compare.metrics.mse_noise) against the formulas written here:
    RMSE, noise floor sqrt(mean var), debiased sqrt(max(mean(d^2) - mean(var), 0)) to 1e-12
    relative (float64 summation order), and below_noise: mean(d^2) - mean(var) <= 3 standard errors
    of a perfect model's, sqrt(2 sum_p tr(C_p C_p)) / n (the channels' full covariance); on a masked
    image with the channels' noise uncorrelated and correlated 0.9.  Seeded draws: the 0.1
    difference (~6 noise floors) is above the noise and noise alone below it (a 3-sigma test,
    99.9 % one-sided confidence)."""
    rng = np.random.default_rng(3)
    var = rng.uniform(1e-4, 4e-4, (6, 5, 3))
    mask = rng.uniform(size=(6, 5)) > 0.3
    for rho in (0.0, 0.9):
        cov = covariance(np.sqrt(var), np.full(var.shape, rho))
        for scale in (0.1, 0.0):  # a real difference, then noise alone
            diff = scale + np.sqrt(var) * rng.standard_normal(var.shape)
            d, v, C = diff[mask], var[mask], cov[mask]
            rmse, floor = np.sqrt(np.mean(d * d)), np.sqrt(np.mean(v))
            debiased = np.sqrt(max(np.mean(d * d) - np.mean(v), 0.0))
            s = split_stats(diff, cov, mask)
            np.testing.assert_allclose(
                [s["rmse"], s["noise_floor"], s["debiased"]], [rmse, floor, debiased], rtol=1e-12
            )
            null = np.sqrt(2.0 * np.einsum("pij,pji->", C, C)) / d.size
            assert s["below_noise"] == (np.mean(d * d) - np.mean(v) <= 3.0 * null)
            assert s["below_noise"] == (scale == 0.0)
    none = np.zeros((2, 2), bool)
    assert split_stats(np.ones((2, 2, 3)), np.ones((2, 2, 3, 3)), none)["rmse"] == 0.0


def test_closed_form_split_sees_the_cylinder_and_the_clamp():
    cam = (0.0, 2.0, 0.0)
    views = sample_views(cam, n_dirs=64, distances=[10.0, 50.0, 200.0, 2000.0])
    ue = UE4FogParams(FogDensity=0.05, FogHeightFalloff=1.0, FogHeight=3000.0)
    far_wall = UEPathTracerSettings(VolumetricFogDistance=1e7, FogDensityClamp=256)
    near = departure_row(closed_form_split(ue, far_wall, cam, views))
    # no wall in reach; what is left is the clamp far below (downward views) and the cylinder's top,
    # put by Unreal where the density falls to 1e-6 per cm (upward views): under 1 %
    assert 1e-4 < near["opacity_rel_max"] < 0.01
    wall_30m = UEPathTracerSettings(VolumetricFogDistance=3000.0, FogDensityClamp=256)
    wall = departure_row(
        closed_form_split(UE4FogParams(FogDensity=0.05, FogHeightFalloff=1.0), wall_30m, cam, views)
    )
    assert wall["opacity_rel_max"] > 0.01 and wall["opacity_nearest_departure_m"] == 50.0
    # fog height 30 m, radius 30 m: the cylinder's floor (FogMinZ = FogHeight - radius) is the ground,
    # so downward views already depart at 10 m
    floor = departure_row(closed_form_split(ue, wall_30m, cam, views))
    assert floor["opacity_nearest_departure_m"] == 10.0
    clamp_1 = UEPathTracerSettings(VolumetricFogDistance=1e7, FogDensityClamp=1.0)
    clamp = departure_row(closed_form_split(ue, clamp_1, cam, views))
    assert clamp["opacity_rel_max"] > 0.01  # clamp height = fog height 30 m, above the camera


@pytest.mark.render
def test_render_split_on_a_tiny_image(mitsuba, tmp_path):
    ue = UE4FogParams(FogDensity=0.05, FogHeightFalloff=2.0, FogHeight=2000.0)
    out = render_split(
        "scenes/valley.xml",
        ue,
        UEPathTracerSettings(FogDensityClamp=1.0),
        tmp_path,
        spp=16,
        overrides={"res": 16, "resy": 9, "max_depth": 2},
    )
    for k in ("raster_vs_pt", "pt_vs_exact", "raster_vs_exact"):
        s = out[k]
        assert np.isfinite(s["rmse"]) and np.isfinite(s["noise_floor"]) and s["noise_floor"] > 0
    # clamp 1: the density near the ground is 12x lower than the exact fog's, far above the noise
    assert out["pt_vs_exact"]["rmse"] > 3 * out["pt_vs_exact"]["noise_floor"]
    assert not out["pt_vs_exact"]["below_noise"]
    img = out["images"]
    assert all(v.shape == (9, 16, 3) for v in img.values())
