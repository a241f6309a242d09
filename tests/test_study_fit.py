"""fogref.mapping's fits (Unreal, cosine lobe): recovering known Unreal parameters, the lobe table's
limits."""

import math

import numpy as np
import pytest

from fogref.mapping import (
    PhysicalScene,
    base_params,
    fit_unreal,
    lobe_fit,
    physical_single_scattering,
    sample_views,
    unreal_inscatter,
)
from fogref.media import ExpLayer, FogMedium


def _pf(g=0.6):
    med = FogMedium(sigma_t=0.002, albedo=0.9, g=g, layers=(ExpLayer(1.0, 0.02, 0.0),))
    return PhysicalScene(med, (0.4, 0.3, 0.87), (3.0, 2.8, 2.4), (0.2, 0.3, 0.5), (0.0, 2.0, 0.0))


def test_fit_recovers_parameters_of_synthetic_unreal_data():
    pf = _pf()
    views = sample_views(pf.camera, n_dirs=200)
    true = base_params(
        pf,
        FogInscatteringColor=(0.3, 0.4, 0.6),
        DirectionalInscatteringColor=(1.5, 1.2, 0.9),
        DirectionalInscatteringExponent=8.0,
        DirectionalInscatteringStartDistance=5000.0,
    )
    target = unreal_inscatter(true, np.asarray(pf.camera), views.world_positions())
    r = fit_unreal(pf, views, target=target)
    p = r.params
    assert p.DirectionalInscatteringExponent == pytest.approx(8.0, rel=1e-3)
    assert p.DirectionalInscatteringStartDistance == pytest.approx(5000.0, rel=1e-2, abs=20.0)
    np.testing.assert_allclose(p.FogInscatteringColor, (0.3, 0.4, 0.6), rtol=1e-3)
    np.testing.assert_allclose(p.DirectionalInscatteringColor, (1.5, 1.2, 0.9), rtol=1e-3)
    assert r.rel_rmse < 1e-3


def test_fit_recovers_exponent_without_start_distance():
    pf = _pf()
    views = sample_views(pf.camera, n_dirs=150)
    true = base_params(
        pf,
        FogInscatteringColor=(0.1, 0.2, 0.3),
        DirectionalInscatteringColor=(2.0, 1.0, 0.5),
        DirectionalInscatteringExponent=30.0,
    )
    target = unreal_inscatter(true, np.asarray(pf.camera), views.world_positions())
    r = fit_unreal(pf, views, target=target, fit_start=False)
    assert r.params.DirectionalInscatteringExponent == pytest.approx(30.0, rel=1e-3)
    np.testing.assert_allclose(r.params.DirectionalInscatteringColor, (2.0, 1.0, 0.5), rtol=1e-3)


def test_isotropic_fog_needs_no_lobe():
    # g = 0 and no sun attenuation: the physics is exactly alpha (E/(4 pi) + L_sky) (1 - T).
    pf = _pf(g=0.0)
    views = sample_views(pf.camera, n_dirs=120)
    r = fit_unreal(pf, views, sun_attenuation=False, fit_start=False)
    assert r.rel_rmse < 1e-6
    assert max(r.params.DirectionalInscatteringColor) < 1e-6
    expect = 0.9 * (np.array([3.0, 2.8, 2.4]) / (4 * math.pi) + np.array([0.2, 0.3, 0.5]))
    np.testing.assert_allclose(r.params.FogInscatteringColor, expect, rtol=1e-6)


def test_lobe_fit_limits():
    r0 = lobe_fit(0.0)
    assert r0["rel_error"] < 1e-9 and r0["lobe"] < 1e-9 and r0["exponent"] is None
    assert r0["iso"] == pytest.approx(1.0)
    errs = [lobe_fit(g)["rel_error"] for g in (0.1, 0.3, 0.6, 0.9)]
    assert errs[0] < 0.05 and all(a < b for a, b in zip(errs, errs[1:]))  # grows with g
    ns = [lobe_fit(g)["exponent"] for g in (0.3, 0.6, 0.9)]
    assert all(a < b for a, b in zip(ns, ns[1:]))  # sharper lobe for larger g
    back = lobe_fit(-0.5)  # backscatter: lobe can't help
    assert back["lobe"] < 1e-9


def test_physical_target_no_attenuation_matches_hg_formula():
    pf = _pf()
    views = sample_views(pf.camera, n_dirs=50)
    a = physical_single_scattering(pf, views, sun_attenuation=True)
    b = physical_single_scattering(pf, views, sun_attenuation=False)
    assert np.all(np.isfinite(a)) and np.all(a >= 0)
    assert np.all(a <= b * (1 + 1e-9) + 1e-12) or np.mean(a) < np.mean(b)  # attenuation removes light
