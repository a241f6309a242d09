"""Units and colour spaces of the models' parameters (fogref.models.terms) in fit and translate,
where translate's unset settings come from, and the shipped scenes found by name."""

import dataclasses
import json

import colour
import numpy as np
import pytest

from fogref.cli import main
from fogref.mapping.fit import start_params
from fogref.mapping.free import fit_spec
from fogref.models.resolve import available_models, resolve_model
from fogref.models.terms import DEFAULTS_FROM, TERMS, annotate, term
from fogref.models.ue4 import UE4FogParams
from fogref.shipped_scenes import resolve_scene, scene_path, shipped_scene_names
from fogref.study.fit import physical_from_scene


@pytest.mark.parametrize("name", available_models())
def test_every_parameter_of_every_builtin_model_has_a_term(name):
    params = resolve_model(name).Params
    fields = {f.name for f in dataclasses.fields(params) if f.init}
    assert fields == set(TERMS[name]), name
    assert name in DEFAULTS_FROM


@pytest.mark.parametrize("name", sorted(TERMS))
def test_the_engine_space_of_each_colour_is_colour_sciences_srgb_where_the_ui_is_srgb(name):
    """Reference: colour-science's IEC 61966-2-1 encoding (to 1e-12 on [0, 1])."""
    for field, t in TERMS[name].items():
        if t.colour is None:
            continue
        lin = (0.002, 0.2311, 0.9)
        got = annotate(name, field, lin)["engine_value"]
        if t.colour == "sRGB":
            want = colour.cctf_encoding(np.array(lin), function="sRGB")
        elif t.colour == "gamma 2.2":
            want = colour.cctf_encoding(np.array(lin), function="Gamma 2.2")
        else:
            want = lin
        np.testing.assert_allclose(got, want, atol=1e-6, err_msg=f"{name}.{field}")


def test_fit_prints_units_and_the_engines_colour_space(capsys):
    assert main(["fit", "--model", "godot", "--directions", "24", "--sun-elevation", "8"]) == 0
    cap = capsys.readouterr()
    doc = json.loads(cap.out)
    c = doc["parameters"]["fog_light_color[0]"]
    assert c["space"] == "linear" and c["engine_space"] == "sRGB"
    assert c["engine_value"] == pytest.approx(
        float(colour.cctf_encoding(c["value"], function="sRGB")), abs=1e-6
    )
    assert doc["parameters"]["fog_density"]["unit"].startswith("1/m")
    assert doc["settings_units"]["fog_height"] == {"unit": "m"}
    assert "linear; sRGB in the engine:" in cap.err


def test_unreal_fit_prints_cm_for_its_distances(capsys):
    assert main(["fit", "--directions", "16", "--no-start-distance"]) == 0
    cap = capsys.readouterr()
    line = next(s for s in cap.err.splitlines() if "Directional Inscattering Start Distance" in s)
    assert line.rstrip().endswith(" cm")
    units = json.loads(cap.out)["unreal_editor_units"]
    assert units["Fog Inscattering Color"]["engine_space"] == "linear"
    assert units["Start Distance"] == {"unit": "cm"}


def _translate(capsys, *extra):
    argv = ["translate", "--from", "ue4", "--to", "unity", "--param", "FogDensity=0.02"]
    assert main([*argv, "--directions", "16", *extra]) == 0
    cap = capsys.readouterr()
    return json.loads(cap.out), cap.err


def test_translate_without_a_scene_fills_in_the_engines_defaults_and_says_so(capsys):
    doc, err = _translate(capsys)
    filled = doc["source"]["not_given"]
    assert "FogDensity" not in filled
    d = UE4FogParams()
    assert filled["FogInscatteringColor"]["value"] == list(d.FogInscatteringColor)
    assert filled["DirectionalInscatteringExponent"]["value"] == d.DirectionalInscatteringExponent
    assert "ExponentialHeightFogComponent.cpp" in filled["FogInscatteringColor"]["from"]
    assert filled["InscatteringLightDirection"]["from"].startswith("the sun of the default scene")
    assert "from the default of Unreal's UExponentialHeightFogComponent constructor" in err
    assert "FogInscatteringColor" in err and "(0.447, 0.638, 1) linear" in err


def test_translate_with_a_scene_fills_in_that_scenes_fit_and_says_so(capsys):
    doc, err = _translate(capsys, "--scene", "valley")
    filled = doc["source"]["not_given"]
    cls = resolve_model("ue4")
    pf = physical_from_scene(scene_path("valley"))
    want, how = start_params(cls, pf, fit_spec(cls), {"FogDensity": 0.02})
    assert how == "mapping"
    np.testing.assert_allclose(filled["FogInscatteringColor"]["value"], want.FogInscatteringColor, rtol=1e-12)
    origin = filled["FogInscatteringColor"]["from"]
    assert "valley.xml" in origin and "fit" in origin
    assert "from the fit of" in err


def test_shipped_scenes_are_found_by_name_from_any_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert {"valley", "open_plane", "above_fog", "two_layer_sun"} <= set(shipped_scene_names())
    assert resolve_scene("valley") == scene_path("valley") and scene_path("valley").is_file()
    assert resolve_scene("valley.xml").as_posix() == "valley.xml"  # a suffix: a path, not a name
    assert term("ue4", "FogHeight").unit == "cm"
    assert main(["scene", "--out", "studio.xml", "--geometry", "valley"]) == 0
    assert "<shape" in (tmp_path / "studio.xml").read_text()
