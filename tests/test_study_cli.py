"""``fogref fit`` prints valid JSON; ``fogref study`` is wired into the CLI."""

import json

from fogref.cli import build_parser, main


def test_fit_cli_prints_json(capsys):
    rc = main(["fit", "--scene", "scenes/valley.xml", "--directions", "60"])
    assert rc == 0
    out = capsys.readouterr()
    doc = json.loads(out.out)
    ed = doc["unreal_editor"]
    for k in ("Fog Inscattering Color", "Directional Inscattering Color", "Directional Inscattering Exponent",
              "Directional Inscattering Start Distance", "Fog Density", "Fog Height Falloff", "Fog Height Offset"):
        assert k in ed
    assert abs(ed["Fog Density"] - 0.02) < 1e-6 and abs(ed["Fog Height Falloff"] - 0.2) < 1e-5
    assert "Directional Inscattering Exponent" in out.err


def test_fit_cli_from_flags(capsys):
    rc = main(["fit", "--sigma-t", "0.002", "--falloff", "0.02", "--g", "0.0", "--directions", "40",
               "--no-sun-attenuation", "--no-start-distance"])
    assert rc == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["error"]["rel_rmse"] < 1e-6


def test_study_subcommand_exists():
    a = build_parser().parse_args(["study", "out/valley.exr", "--no-compare"])
    assert a.cmd == "study" and a.no_compare
