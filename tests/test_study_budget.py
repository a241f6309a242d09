"""fogref.study.budget: the chain telescopes exactly; closed-form steps vanish where they should."""

import numpy as np
import pytest

from fogref.mapping import PhysicalScene as PhysicalFog
from fogref.mapping import base_params
from fogref.media import ExpLayer, FogMedium
from fogref.study import budget as B


def _pixels(pf, h=12, w=20, seed=0):
    rng = np.random.default_rng(seed)
    cam = np.asarray(pf.camera)
    v = rng.normal(size=(h, w, 3))
    v[..., 2] = np.abs(v[..., 2]) + 1.0
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    hit = v[..., 1] < 0.05
    D = np.where(hit, rng.uniform(5, 3000, (h, w)), 0.0)
    px = B.Pixels(final=None, T=None, surface=rng.uniform(0, 0.5, (h, w, 3)), single=None, multiple=None,
                  distance=D, position=cam + v * D[..., None], view=v, hit=hit, camera=cam)
    cf = B.closed_forms(px, pf)
    px.T = cf["T"]
    sky_single = cf["sky"] * rng.uniform(0.5, 1.0, (h, w, 1))
    px.single = cf["sun_att"] * rng.uniform(0.0, 1.0, (h, w, 1)) + sky_single
    px.multiple = rng.uniform(0, 0.05, (h, w, 3))
    px.final = px.T * px.surface + px.single + px.multiple
    return px, sky_single


def _pf():
    med = FogMedium(sigma_t=0.001, albedo=0.9, g=0.6, layers=(ExpLayer(1.0, 0.014, 0.0),))
    return PhysicalFog(med, (0.4, 0.14, 0.906), (3.2, 2.9, 2.4), (0.2, 0.3, 0.5), (0.0, 2.0, 0.0))


def test_budget_telescopes_exactly():
    pf = _pf()
    px, sky = _pixels(pf)
    lobe = base_params(pf, DirectionalInscatteringColor=(1, 1, 1), DirectionalInscatteringExponent=5.0)
    model = base_params(pf, DirectionalInscatteringColor=(1.4, 1.3, 1.1), DirectionalInscatteringExponent=14.0,
                        DirectionalInscatteringStartDistance=3000.0, FogMaxOpacity=0.95, FogCutoffDistance=150000.0)
    S = B.chain(px, sky, pf, lobe, model)
    assert len(S) == len(B.STEPS) + 1
    r = B.attribute(S, px.hit)
    assert r["telescoping_residual"] < 1e-12
    assert r["share_sum"] == pytest.approx(1.0, abs=1e-12)
    E = S[-1] - S[0]
    assert r["total"]["rmse"]["all"] == pytest.approx(np.sqrt(np.mean(E ** 2)))
    keys = [s["key"] for s in r["steps"]]
    assert keys[0] == "multiple" and keys[-1] == "float32"
    # every effect is switched on here, so the engine-setting steps are not zero
    by = {s["key"]: s for s in r["steps"]}
    assert by["start_distance"]["rmse"]["all"] > 0 and by["opacity_cutoff"]["rmse"]["all"] > 0
    # a second chain gives noise estimates; identical chains give zero noise
    B.add_noise(r, S, S, px.hit)
    assert all(s["noise"]["pixel_rms"] == 0 for s in r["steps"])


def test_steps_vanish_for_an_unshadowed_closed_form_truth():
    pf = _pf()
    px, _ = _pixels(pf)
    cf = B.closed_forms(px, pf)
    px.single = cf["sun_att"] + cf["sky"]      # no shadows, unoccluded sky
    px.multiple[:] = 0.0
    px.final = px.T * px.surface + px.single
    model = base_params(pf)
    S = B.chain(px, cf["sky"], pf, model, model)
    r = B.attribute(S, px.hit)
    by = {s["key"]: s for s in r["steps"]}
    for k in ("multiple", "shadows", "sky", "refit", "start_distance", "opacity_cutoff"):
        assert by[k]["rmse"]["all"] < 1e-12, k
    assert by["float32"]["rmse"]["all"] < 1e-5


def test_markdown_and_plot(tmp_path):
    pf = _pf()
    px, sky = _pixels(pf)
    p = base_params(pf, DirectionalInscatteringColor=(1, 1, 1))
    S = B.chain(px, sky, pf, p, p)
    r = B.add_noise(B.attribute(S, px.hit), S, S, px.hit)
    md = B.markdown(r)
    assert "| 9 | [h]" in md and "100.000000 %" in md
    B.plot(r, tmp_path / "b.png")
    assert (tmp_path / "b.png").stat().st_size > 1000
