"""``split_study`` (``fogref study TRUTH --ue-pathtracer``): what a UE user sees, split, in the report.

A tiny truth (8x6, 2 spp) of a scene written by ``fogref scene``; the split renders it with UE's
path-traced fog and the exact fog and writes the section of ``budget.md``, the JSON and
``summary.json``'s key.
"""

from __future__ import annotations

import json

import pytest

from fogref.cli import main
from fogref.mapping.unreal_pathtracer import UEPathTracerSettings
from fogref.study.ue_pathtracer import SECTION_BEGIN, SECTION_END, split_study


@pytest.fixture(scope="module")
def tiny_truth(tmp_path_factory):
    d = tmp_path_factory.mktemp("tiny_truth")
    xml, exr = d / "s.xml", d / "t.exr"
    assert main(["scene", "--out", str(xml), "--res", "8", "--resy", "6", "--max-depth", "2"]) == 0
    args = ["render", str(xml), "--spp", "2", "--seed", "0", "--pixel-filter", "centre"]
    assert main([*args, "--out", str(exr), "--quiet"]) == 0
    return exr


@pytest.mark.render
def test_split_study_writes_its_section_and_json(tiny_truth, tmp_path):
    out = tmp_path / "study"
    out.mkdir()
    (out / "budget.md").write_text("# budget\n\ntable\n")
    (out / "summary.json").write_text('{"truth": "t.exr"}\n')
    pt = UEPathTracerSettings(FogDensityClamp=1.0, VolumetricFogDistance=3000.0, VolumetricFogAlbedo=0.9)
    doc = split_study(tiny_truth, out, pt=pt, spp=8)
    for key in ("raster_vs_pt", "pt_vs_exact", "raster_vs_exact"):
        s = doc[key]
        assert s["rmse"] >= 0 and s["noise_floor"] > 0 and s["debiased"] <= s["rmse"]
    # clamp 1 and a 30 m cylinder: the path tracer's own fog departs from the exact fog beyond its noise
    assert not doc["pt_vs_exact"]["below_noise"] and doc["pathtracer"]["density_clamp"] == 1.0
    assert doc["spp"] == 8 and doc["pathtracer"]["radius_cm"] == 3000.0
    assert json.loads((out / "ue_pathtracer_split.json").read_text()) == doc
    assert json.loads((out / "summary.json").read_text())["ue_pathtracer_split"] == doc
    md = (out / "budget.md").read_text()
    assert md.startswith("# budget\n\ntable\n") and "UE path-traced fog - exact fog" in md
    split_study(tiny_truth, out, pt=pt, spp=8)  # run again: the section is replaced, not repeated
    md2 = (out / "budget.md").read_text()
    assert md2.count(SECTION_BEGIN) == 1 and md2.count(SECTION_END) == 1 and md2 == md


def test_cli_study_flag_calls_the_split(tiny_truth, tmp_path, monkeypatch):
    import fogref.cli.study as cs

    calls = []
    monkeypatch.setattr(cs, "run_study", lambda *a, **k: calls.append("study"))
    monkeypatch.setattr(cs, "write_study_html", lambda *a, **k: "x.html")
    monkeypatch.setattr(cs, "split_study", lambda exr, out, renders, scene=None: calls.append(("split", out)))
    out = str(tmp_path / "s")
    assert main(["study", str(tiny_truth), "--out", out, "--ue-pathtracer"]) == 0
    assert calls == ["study", ("split", out)]


def test_cli_study_draws_the_figures_on_every_core_unless_told(tiny_truth, tmp_path, monkeypatch):
    """``fogref study`` passes ``--processes`` to run_study (default None: one worker per core, as
    ``fogref compare``); run_study refuses a bad count before any work, naming the parameter."""
    import fogref.cli.study as cs
    from fogref.errors import FogrefError
    from fogref.study.unreal import run_study

    seen = []
    monkeypatch.setattr(cs, "run_study", lambda *a, **k: seen.append(k["processes"]))
    monkeypatch.setattr(cs, "write_study_html", lambda *a, **k: "x.html")
    out = str(tmp_path / "s")
    assert main(["study", str(tiny_truth), "--out", out]) == 0
    assert main(["study", str(tiny_truth), "--out", out, "--processes", "3"]) == 0
    assert seen == [None, 3]
    assert main(["study", str(tiny_truth), "--out", out, "--processes", "0"]) == 2
    for bad in (0, 1.5, True):
        with pytest.raises(FogrefError, match="processes"):
            run_study(tiny_truth, tmp_path / "bad", processes=bad)
    assert not (tmp_path / "bad").exists()
