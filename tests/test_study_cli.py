"""``fogref fit`` prints valid JSON; ``fogref study`` is wired into the CLI."""

import json

from fogref.cli import build_parser, main


def test_fit_cli_prints_json(capsys):
    rc = main(["fit", "--scene", "scenes/valley.xml", "--directions", "60"])
    assert rc == 0
    out = capsys.readouterr()
    doc = json.loads(out.out)
    ed = doc["unreal_editor"]
    for k in (
        "Fog Inscattering Color",
        "Directional Inscattering Color",
        "Directional Inscattering Exponent",
        "Directional Inscattering Start Distance",
        "Fog Density",
        "Fog Height Falloff",
        "Fog Height Offset",
    ):
        assert k in ed
    assert abs(ed["Fog Density"] - 0.02) < 1e-6 and abs(ed["Fog Height Falloff"] - 0.2) < 1e-5
    assert "Directional Inscattering Exponent" in out.err


def test_fit_cli_from_flags(capsys):
    rc = main(
        [
            "fit",
            "--sigma-t",
            "0.002",
            "--falloff",
            "0.02",
            "--g",
            "0.0",
            "--directions",
            "40",
            "--no-sun-attenuation",
            "--no-start-distance",
        ]
    )
    assert rc == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["error"]["rel_rmse"] < 1e-6


def test_study_subcommand_exists():
    a = build_parser().parse_args(["study", "out/valley.exr", "--no-compare"])
    assert a.cmd == "study" and a.no_compare


# ---------------------------------------------------------------- errors instead of tracebacks

import hashlib  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from truth_factory import truth_attrs, truth_channels  # noqa: E402

from fogref.exrio import write_exr  # noqa: E402


def _run(capsys, argv):
    rc = main(argv)
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return rc, err


@pytest.mark.parametrize(
    "argv, words",
    [
        (["fit", "--directions", "0"], ["--directions", "[8, 100000]"]),
        (["fit", "--directions", "-3"], ["--directions"]),
        (["fit", "--sun-irradiance", "nan", "1", "1"], ["--sun-irradiance", "finite"]),
        (["fit", "--sky", "-0.18", "0.3", "0.5"], ["--sky", "[0, inf)", "-0.18"]),
        (["fit", "--albedo", "1.5"], ["--albedo", "[0, 1]"]),
        (["fit", "--g", "1"], ["--g", "(-1, 1)"]),
        (["fit", "--sigma-t", "inf"], ["--sigma-t"]),
        (["study", "x.exr", "--max-opacity", "2"], ["--max-opacity", "[0, 1]"]),
    ],
)
def test_out_of_range_flags_are_clear_errors(capsys, argv, words):
    rc, err = _run(capsys, argv)
    assert rc == 2, err
    for w in words:
        assert w in err, (w, err)


def _synthetic_truth_files(tmp_path, scene_text="<scene version='3.0.0'/>", recorded_text=None, sky=0.5):
    """A tiny schema-2 truth whose header records ``scene.xml`` with the hash of ``recorded_text``."""
    h, w = 4, 6
    view = np.zeros((h, w, 3))
    view[..., 2] = -1.0
    ones = np.ones((h, w, 3))
    scene = tmp_path / "scene.xml"
    scene.write_text(scene_text)
    sha = hashlib.sha256((recorded_text if recorded_text is not None else scene_text).encode()).hexdigest()
    ch = truth_channels(
        T=0.5 * ones,
        surface=0.2 * ones,
        inscatter=0.1 * ones,
        distance=np.full((h, w), 10.0),
        position=view * 10.0,
        view=view,
        hit=np.ones((h, w)),
    )
    params = {
        "scene": str(scene),
        "camera": {"origin": [0.0, 2.0, 0.0]},
        "medium": {"sigma_t": 0.01, "falloff": 0.02, "albedo": 0.9, "g": 0.6},
        "sun": {"direction": [0.4, 0.5, 0.7], "irradiance": [3.0, 3.0, 3.0]},
        "sky": {"type": "constant", "radiance": sky},
    }
    exr = tmp_path / "t.exr"
    write_exr(exr, ch, truth_attrs(params, scene=str(scene), scene_sha256=sha, overrides={"res": w}))
    return exr, scene, sha


def test_fit_refuses_a_foreign_exr(tmp_path, capsys):
    write_exr(tmp_path / "foreign.exr", {c: np.zeros((2, 2)) for c in "RGB"})
    rc, err = _run(capsys, ["fit", "--exr", str(tmp_path / "foreign.exr"), "--directions", "40"])
    assert rc == 2 and "not a fogref ground truth" in err and "foreign.exr" in err


def test_fit_refuses_a_negative_sky_radiance_from_the_truth(tmp_path, capsys):
    exr, _, _ = _synthetic_truth_files(tmp_path, sky=-0.18)
    rc, err = _run(capsys, ["fit", "--exr", str(exr), "--directions", "40"])
    assert rc == 2 and "radiance" in err and "-0.18" in err


def test_study_refuses_a_scene_changed_since_the_truth(tmp_path, capsys):
    exr, scene, sha = _synthetic_truth_files(
        tmp_path,
        scene_text="<scene version='3.0.0'><!-- edited --></scene>",
        recorded_text="<scene version='3.0.0'/>",
    )
    now = hashlib.sha256(scene.read_bytes()).hexdigest()
    for extra in ([], ["--scene", str(scene)]):
        rc, err = _run(
            capsys,
            ["study", str(exr), "--out", str(tmp_path / "o"), "--renders", str(tmp_path / "r"), *extra],
        )
        assert rc == 2 and sha in err and now in err and str(scene) in err, err
    assert not (tmp_path / "r").exists(), "nothing may be rendered from a changed scene"


def test_scene_of_truth_accepts_the_recorded_scene(tmp_path):
    from fogref.gbuffer import load_truth
    from fogref.study.unreal import scene_of_truth

    exr, scene, _ = _synthetic_truth_files(tmp_path)
    assert scene_of_truth(load_truth(exr)) == scene


def test_study_refuses_an_old_schema_truth(tmp_path, capsys):
    exr, _, _ = _synthetic_truth_files(tmp_path)
    from fogref.exrio import read_exr

    ch, attrs = read_exr(exr)
    attrs = {k: v for k, v in attrs.items() if k.startswith("fogref.") and k != "fogref.schema"}
    write_exr(tmp_path / "old.exr", ch, attrs)
    rc, err = _run(
        capsys,
        ["study", str(tmp_path / "old.exr"), "--out", str(tmp_path / "o"), "--renders", str(tmp_path / "r")],
    )
    assert rc == 2 and "schema" in err


def test_study_text_comes_from_the_data():
    from fogref.study.unreal_report import readme, reproduce_command

    prov = {
        "scene": "scenes/lake.xml",
        "spp": 32,
        "seed": 5,
        "overrides": {"res": 64, "sun_elevation": 10},
        "truth": "out/lake.exr",
        "pixel_filter": "centre",
    }
    cmd = reproduce_command(prov)
    assert cmd == (
        "fogref render scenes/lake.xml --spp 32 --seed 5 --set res=64 --set sun_elevation=10 "
        "--out out/lake.exr && fogref study out/lake.exr"
    )
    steps = [
        {
            "key": k,
            "effect": e,
            "label": lab,
            "rmse": {"all": 0.01, "surface": 0.01, "sky": 0.01},
            "share": 1 / 9,
            "rmse_noise_floor": 0.02,
            "below_noise": True,
        }
        for k, e, lab in __import__("fogref.study.budget", fromlist=["STEPS"]).STEPS
    ]
    res = {
        "total": {
            "rmse": {"all": 0.1, "surface": 0.1, "sky": 0.1},
            "truth_rms": 1.0,
            "noise_rmse": 0.01,
            "rmse_noise_floor": 0.02,
            "below_noise": False,
        },
        "steps": steps,
        "inputs": {**prov, "resolution": [64, 36]},
        "excluded_pixels": 7,
        "open_plane_check": {"scene": "scenes/open_plane.xml", "shadows_rmse": 0.001, "noise_rmse": 0.001},
    }
    summary = {
        "exr": "out/lake.exr",
        "scene": "scenes/lake.xml",
        "provenance": prov,
        "compare": None,
        "fit": {"unreal_editor": {"Fog Density": 0.02}, "error": {"n_views": 100, "rel_rmse": 0.1}},
    }
    text = readme(summary, res)
    assert "valley" not in text
    assert cmd in text and "`res=64`" in text and "32 spp, seed 5" in text and "`lake`" in text
    assert "below the noise" in text and "7 pixel(s) are excluded" in text
