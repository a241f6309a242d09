"""fogref.study.droplet_phase: what HG and the engines' lobe cost in droplet fog.

The ratio trick of ``sun_phase_error`` (the substitute's sun single scattering is the truth's
times ``p_sub / p``) against the closed form evaluated again with the substitute phase in the
medium; ``final_difference`` against known differences (zero, a 10 % scale) with and without
noise.  Synthetic truths (tests/budget_truth.py), no renders.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from budget_truth import synthetic_pixels

from fogref.mapping import PhysicalScene
from fogref.mapping.droplet_fog import droplet_fog
from fogref.mapping.lobe import lobe_fit
from fogref.media import NP, ExpLayer, FogMedium, single_scatter_sun
from fogref.media.phase import TabulatedPhase
from fogref.study.droplet_phase import final_difference, substitute_phase, sun_angle, sun_phase_error


def _scene(phase):
    med = FogMedium(sigma_t=0.004, albedo=1.0, layers=(ExpLayer(1.0, 0.02, 0.0),), phase=phase)
    w = np.array([0.4, 0.2, 0.894])
    return PhysicalScene(med, tuple(w / np.linalg.norm(w)), (3.2, 2.9, 2.4), (0.2, 0.3, 0.5), (0.0, 2.0, 0.0))


MIE = droplet_fog(300.0, "radiation").phase


def test_substitutes():
    from scipy.integrate import quad

    p = substitute_phase(0.83, "hg")
    assert 2 * math.pi * quad(lambda c: float(p(np.array([c]))[0]), -1, 1, points=[0.9, 0.99])[
        0
    ] == pytest.approx(1, abs=1e-8)
    fit = lobe_fit(0.83)
    lobe = substitute_phase(0.83, "lobe")
    c = np.linspace(-1, 1, 11)
    np.testing.assert_allclose(
        lobe(c) * 4 * math.pi, fit["iso"] + fit["lobe"] * np.maximum(c, 0) ** fit["exponent"]
    )
    with pytest.raises(Exception, match="parameter 'kind'"):
        substitute_phase(0.8, "rayleigh")


@pytest.mark.parametrize("kind", ["hg", "lobe"])
def test_sun_phase_error_against_the_closed_form(kind):
    pf = _scene(MIE)
    truth, _ = synthetic_pixels(pf)
    r = sun_phase_error(truth, pf, kind)
    # independent: the closed form again with the substitute in the medium
    o, d, D = truth.rays()
    w = pf.sun_direction
    L = np.stack(single_scatter_sun(NP, pf.medium, o, d, D, w, pf.sun_irradiance), -1)
    if kind == "hg":
        hg_medium = dataclasses.replace(pf.medium, phase=None)  # g stays the Mie mean cosine
        L_sub = np.stack(single_scatter_sun(NP, hg_medium, o, d, D, w, pf.sun_irradiance), -1)
    else:
        lobe = substitute_phase(pf.medium.g, "lobe")
        total = 4 * math.pi * float(np.mean(lobe(np.linspace(-1, 1, 200001))))  # the fit is not normalised
        sub = TabulatedPhase.from_function(lobe)  # renormalised to 1: scaled back by `total`
        L_sub = total * np.stack(
            single_scatter_sun(NP, dataclasses.replace(pf.medium, phase=sub), o, d, D, w, pf.sun_irradiance),
            -1,
        )
    ref = math.sqrt(np.mean((L_sub - L) ** 2)) / math.sqrt(np.mean(truth.final**2))
    assert r["rel_rmse"] == pytest.approx(ref, rel=2e-3)
    assert r["rel_rmse"] > 1e-3  # something is measured


def test_sun_phase_error_is_zero_for_its_own_phase():
    pf = _scene(None)
    truth, _ = synthetic_pixels(pf)
    assert sun_phase_error(truth, pf, "hg")["rel_rmse"] == pytest.approx(0.0, abs=1e-15)


def test_final_difference():
    pf = _scene(MIE)
    a, _ = synthetic_pixels(pf, rel_stderr=0.0)
    b = dataclasses.replace(a, final=a.final * 1.1)
    r = final_difference(a, b)
    assert r["rel_rmse"] == pytest.approx(0.1, rel=1e-9) and not r["below_noise"]
    noisy, _ = synthetic_pixels(pf, rel_stderr=0.01)
    r0 = final_difference(noisy, noisy)
    assert r0["rel_rmse"] == 0.0 and r0["below_noise"] and r0["stderr"] > 0


def test_masks_and_sun_angle():
    pf = _scene(MIE)
    truth, _ = synthetic_pixels(pf)
    ang = sun_angle(truth, pf.sun_direction)
    k = (3, 4)
    assert ang[k] == pytest.approx(
        math.degrees(math.acos(float(truth.view[k] @ np.asarray(pf.sun_direction))))
    )
    near = ang < np.median(ang)
    a, b = sun_phase_error(truth, pf, "hg", near), sun_phase_error(truth, pf, "hg", ~near)
    assert a["pixels"] + b["pixels"] == near.size
    assert sun_phase_error(truth, pf, "hg", np.zeros_like(near))["pixels"] == 0
    # the mean ratio is the substitute's mean over the droplets' (closed form, recomputed)
    o, d, D = truth.rays()
    L = np.stack(single_scatter_sun(NP, pf.medium, o, d, D, pf.sun_direction, pf.sun_irradiance), -1)
    cos = np.asarray(d).T @ np.asarray(pf.sun_direction)
    L_hg = L * (substitute_phase(pf.medium.g, "hg")(cos) / pf.medium.phase_value(NP, cos))[:, None]
    m = near.reshape(-1)
    assert a["mean_ratio"] == pytest.approx(L_hg[m].mean() / L[m].mean(), rel=1e-12)
