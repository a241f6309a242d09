"""The generic fit (fogref.mapping.fit), the translator (fogref.mapping.translate) and their CLIs."""

import json
import math
import textwrap

import numpy as np
import pytest

from fogref.cli import main
from fogref.errors import FogrefError
from fogref.mapping.fit import fit_model, fit_to_targets, model_class, physical_targets, start_params
from fogref.mapping.free import FIT_SPECS, fit_spec
from fogref.mapping.physical import PhysicalScene
from fogref.mapping.translate import translate
from fogref.mapping.unreal import sample_views
from fogref.media import ExpLayer, FogMedium

SIGMA = 0.004


def _homogeneous(sun=False):
    med = FogMedium(sigma_t=SIGMA, albedo=0.8, g=0.5, layers=(ExpLayer(1.0, 0.0, 0.0),))
    E = (3.0, 2.8, 2.5) if sun else 0.0
    return PhysicalScene(med, (0.4, 0.3, 0.87), E, (0.2, 0.3, 0.5), (0.0, 2.0, 0.0))


def _valley():
    med = FogMedium(sigma_t=0.00096, albedo=0.9, g=0.6, layers=(ExpLayer(1.0, 0.0139, 0.0),))
    return PhysicalScene(med, (0.4, 0.139, 0.906), (3.2, 2.9, 2.4), (0.2, 0.3, 0.5), (0.0, 2.0, 0.0))


@pytest.mark.parametrize(
    "model,field", [("unity", "fogDensity"), ("godot", "fog_density"), ("threejs", None)]
)
def test_exact_models_recover_the_density_without_noise(model, field):
    pf = _homogeneous()
    # Unity's skybox is not fogged: its fog equals the medium on meshes only, so no sky views
    views = sample_views(pf.camera, n_dirs=64, sky_min_dy=1.0) if model == "unity" else 64
    r = fit_model(model, pf, views=views)
    if field is None:  # three.js FogExp2 is never exact: a real residual remains
        assert r.rel_rmse > 0.01
        return
    assert r.values[field] == pytest.approx(SIGMA, rel=1e-6)
    assert r.rel_rmse < 1e-6
    assert all(math.isfinite(u) for u in r.uncertainty.values())


@pytest.mark.parametrize(
    "model,field", [("unity", "fogDensity"), ("godot", "fog_density"), ("bevy", "extinction[1]")]
)
def test_density_equals_sigma_t_within_its_uncertainty_on_a_noisy_target(model, field):
    """Gaussian noise of known size on the exact target: the fit must land within 3 sigma of the truth,
    and its stated sigma must be of the right size (the covariance formula s^2 (J^T J)^-1)."""
    cls = model_class(model)
    pf = _homogeneous()
    # Bevy's and Unity's skyboxes are not fogged: their fog equals the medium on meshes only
    sky_min_dy = 1.0 if model in ("bevy", "unity") else 0.0
    targets = physical_targets(pf, sample_views(pf.camera, n_dirs=96, sky_min_dy=sky_min_dy))
    rng = np.random.default_rng(3)
    for t in targets:
        t.L = t.L + rng.normal(0.0, 0.01, t.L.shape)
    p0, _ = start_params(cls, pf)
    r = fit_to_targets(cls, targets, p0)
    u = r["uncertainty"][field]
    assert 0 < u < 0.05 * SIGMA
    assert abs(r["values"][field] - SIGMA) <= 3 * u


def test_uncertainties_are_finite_and_shrink_with_more_directions():
    pf = _valley()
    coarse = fit_model("unity", pf, views=48)
    fine = fit_model("unity", pf, views=384)
    for k, u in coarse.uncertainty.items():
        assert math.isfinite(u) and u > 0
        assert fine.uncertainty[k] < 0.6 * u, k  # ~ 1/sqrt(8) = 0.35 expected


def test_converged_fit_reports_spread_and_history():
    r = fit_model("threejs", _valley(), max_dirs=512)
    assert r.spread is not None and set(r.spread) == set(r.values)
    assert r.history["convergence"][0]["n_dirs"] == 128
    d = r.to_dict()
    json.dumps(d)
    assert set(d["parameters"]["density"]) >= {"value", "uncertainty", "spread"}


@pytest.mark.slow
def test_every_builtin_model_has_a_fit_spec_and_fits_the_valley_over_two_suns():
    for name in FIT_SPECS:
        r = fit_model(name, _valley(), views=24, sun_elevations=[10.0, 40.0])
        assert r.sun_elevations == [10.0, 40.0]
        assert np.isfinite(r.rmse) and all(np.isfinite(list(r.uncertainty.values())))


def test_a_user_model_fits_through_the_same_code(tmp_path, monkeypatch):
    (tmp_path / "my_beer_fog.py").write_text(
        textwrap.dedent("""
        from dataclasses import dataclass
        import numpy as np
        from fogref.models.base import FogResult

        @dataclass(frozen=True)
        class BeerParams:
            density: float = 0.01
            color: tuple = (0.5, 0.5, 0.5)

        class BeerFog:
            Params = BeerParams
            def __init__(self, params=None):
                self.params = params or BeerParams()
            def evaluate(self, camera, positions, precision="float32"):
                d = np.linalg.norm(np.asarray(positions, float) - np.asarray(camera, float), axis=-1)
                T = np.exp(-self.params.density * d)[..., None] * np.ones(3)
                return FogResult(inscatter=np.asarray(self.params.color) * (1 - T), transmittance=T)
    """)
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    r = fit_model("my_beer_fog:BeerFog", _homogeneous(), views=48)
    assert r.start == "defaults"
    assert r.values["density"] == pytest.approx(SIGMA, rel=1e-6)
    assert r.values["color[2]"] == pytest.approx(0.8 * 0.5, rel=1e-6)
    assert len(fit_spec(model_class("my_beer_fog:BeerFog")).free) == 4


def test_unknown_model_gets_did_you_mean():
    with pytest.raises(FogrefError, match="did you mean 'godot'"):
        fit_model("godt", _valley())


def test_translate_unity_to_unity_is_identity():
    pf = _homogeneous()  # meshes only: Unity's skybox is not fogged
    t = translate(
        "unity", "unity", {"fogDensity": 0.003}, pf, views=sample_views(pf.camera, 48, sky_min_dy=1.0)
    )
    assert t.physical["extinction"] == "exact"
    assert t.target.values["fogDensity"] == pytest.approx(0.003, rel=1e-5)
    assert t.residual_vs_source < 1e-4


def test_translate_ue4_to_ue4_is_identity_without_a_sun():
    pf = _valley()
    pf = PhysicalScene(pf.medium, pf.sun_direction, 0.0, pf.sky_radiance, pf.camera)
    src = {
        "FogDensity": 0.03,
        "FogHeightFalloff": 0.15,
        "FogInscatteringColor": [0.2, 0.25, 0.4],
        "DirectionalInscatteringColor": [0.0, 0.0, 0.0],
    }
    t = translate("ue4", "ue4", src, pf, views=48)
    v = t.target.values
    assert v["FogDensity"] == pytest.approx(0.03, rel=1e-3)
    assert v["FogHeightFalloff"] == pytest.approx(0.15, rel=1e-3)
    for i, c in enumerate(src["FogInscatteringColor"]):
        assert v[f"FogInscatteringColor[{i}]"] == pytest.approx(c, rel=1e-3)
    assert t.residual_vs_source < 1e-3


def test_translate_reports_the_error_no_setting_can_remove():
    t = translate("unity", "threejs", {"fogDensity": 0.003}, _homogeneous(), views=48)
    assert t.residual_vs_truth > 0.01  # exp^2 against exp
    d = t.to_dict()
    json.dumps(d)
    assert d["residual"]["cannot_represent"].startswith("exp(-(density depth)^2)")


def test_fit_cli_model_runs_and_refuses_bad_input(capsys):
    assert main(["fit", "--model", "godt"]) == 2
    assert "did you mean 'godot'" in capsys.readouterr().err
    assert main(["fit", "--model", "unity", "--sun-elevation", "91"]) == 2
    capsys.readouterr()
    assert main(["fit", "--model", "unity", "--directions", "24", "--sun-elevation", "20"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["model"] == "unity" and "uncertainty" in doc["parameters"]["fogDensity"]


def test_translate_cli_runs_and_refuses_bad_input(capsys):
    assert main(["translate", "--from", "ue4", "--to", "godt"]) == 2
    assert "did you mean 'godot'" in capsys.readouterr().err
    assert main(["translate", "--from", "unity", "--to", "godot", "--param", "fogDensty=0.01"]) == 2
    assert "did you mean 'fogDensity'" in capsys.readouterr().err
    assert (
        main(
            [
                "translate",
                "--from",
                "unity",
                "--to",
                "threejs",
                "--param",
                "fogDensity=0.003",
                "--param",
                "fogMode=exp",
                "--param",
                "fog_coordinate=distance",
                "--directions",
                "24",
            ]
        )
        == 0
    )
    doc = json.loads(capsys.readouterr().out)
    assert doc["target"]["model"] == "threejs" and doc["physical"]["extinction"] == "exact"
