"""The real engines in the loop (fogref.engines): their camera is fogref's, their fog is the port's.

Each test that renders starts Debian's headless Chromium with an engine from node_modules (a few
seconds); they skip, saying why, only where Chromium cannot start.  The engines: three.js,
Babylon.js, PlayCanvas and Filament (every engine of :data:`fogref.engines.ENGINES`).  References:

* camera: the truth's G-buffer distance of the open plane (Mitsuba's pixel-centre rays, float32)
  against the engine's distance along the ray through each pixel centre.  Measured: 4.1e-7
  relative at most (float32; Filament 5.6e-7); the bound 1e-5 detects a camera off by 0.001 deg in pitch or a
  field of view off by 1e-4 relative (each moves a 16x9 view's plane distances by >= 1e-4).
* fog: the port (fogref.models.threejs, .babylon, .playcanvas, .filament) on the fog coordinate
  the engine's fog interpolated (eye depth, distance; Filament: its interpolated position), over
  the engine's own unfogged surface, against the engine's linear image: measured 7.5e-8
  (three.js), 1.2e-7 (Babylon, PlayCanvas), 8.3e-7 (Filament) (float32); the level is 1e-6
  relative (Filament's 6e-5: its shader's line integral cancels for a small height term, see
  fogref.engines.filament.LINEAR_LEVEL; 2.9e-6 measured at 96x54).  A density 1 % off gives
  2.8e-3 (Filament 4.0e-3) here: the test can fail.
* canvas: the port through the engine's canvas transform (three.js: sRGB transfer; Babylon: none;
  PlayCanvas: a 2.2 power; Filament: its default colour grading, ACES-legacy tone mapping and sRGB
  output, the port's ``output="canvas"``) and 8 bits: 0 code values measured (Filament 1), the
  level 1; an sRGB-encoded linear blend instead differs by 17 (three.js), 74 (Babylon) and 25
  (Filament) code values on the valley.
* lighting: without fog, on the open plane, the engine's image is the truth's (exact per sample
  there): 2.1e-7 (three.js), 7.0e-8 (Babylon, PlayCanvas), 2.5e-7 (Filament's unlit vertex
  colours, fogref's Lambert shading of each vertex) relative measured.
"""

from __future__ import annotations

import dataclasses
import subprocess
import sys

import numpy as np
import pytest

from conftest import ROOT, SCENES
from fogref.cli import main
from fogref.engines import ENGINES, engine_module
from fogref.engines.browser import Browser, EngineUnavailable, find_chromium

pytestmark = pytest.mark.browser  # headless Chromium (CONTRIBUTING.md, the tiers)

#: engine -> its model's density parameter (a 1 % change must be seen)
DENSITY = {"threejs": "density", "babylon": "fogDensity", "playcanvas": "density", "filament": "density"}
assert set(DENSITY) == set(ENGINES)


@pytest.fixture(scope="module")
def chromium():
    """Skip (saying why) where Chromium cannot start."""
    if find_chromium()[2]:
        pytest.skip(find_chromium()[2])
    try:
        Browser(timeout=120).close()
    except EngineUnavailable as e:
        pytest.skip(str(e))


@pytest.fixture(scope="module", params=sorted(ENGINES))
def valley(chromium, request):
    """The valley at 32x18, its fog mapped from the scene, rendered by each engine."""
    from fogref.cli.engine import engine_model
    from fogref.engines.render import render_engine
    from fogref.engines.view import view_from_scene

    view = view_from_scene(SCENES / "valley.xml", {"res": "32", "resy": "18"})
    model, _ = engine_model(request.param, None, view.params, view)
    return view, model, render_engine(view, model, request.param, timeout=120)


@pytest.fixture(scope="module")
def plane_truth(chromium, tmp_path_factory):
    """The open plane at 16x9, 2 spp, with a grey extinction (so that the three.js mapping applies)."""
    from fogref.gbuffer import load_truth
    from fogref.render.render import render

    overrides = {"res": 16, "resy": 9, "sigma_t": "0.002"}
    out = tmp_path_factory.mktemp("plane") / "plane.exr"
    return load_truth(
        render(SCENES / "open_plane.xml", out, spp=2, overrides=overrides, progress=False, png=False)
    )


@pytest.mark.render
@pytest.mark.parametrize("engine", sorted(ENGINES))
def test_engine_camera_is_the_truths(plane_truth, engine):
    from fogref.engines.render import render_engine, truth_agreement
    from fogref.engines.view import view_from_truth

    truth = plane_truth
    r = render_engine(view_from_truth(truth), None, engine, timeout=120)
    a = truth_agreement(r, truth)
    assert a["hit_mismatch_pixels"] == 0
    assert 0 < r.hit.sum() < r.hit.size  # ground and sky both in view
    assert a["distance_max_relative"] < 1e-5, a


def test_fog_settings_arrive(valley):
    from fogref.engines.port import port_vs_engine

    view, model, r = valley
    p = port_vs_engine(r, model)
    assert p["pixels"] > 100
    assert p["at_quantisation"], p["summary"]
    level = getattr(engine_module(r.engine), "LINEAR_LEVEL", 1e-6)  # Filament's: 6e-5 (its module)
    assert p["linear_max_relative"] <= level and p["canvas_max"] <= 1
    # three.js blends its fog in sRGB, Babylon writes linear values unconverted: neither canvas is
    # the sRGB encoding of the linear image (PlayCanvas's 2.2 power is within 2 code values of it)
    if r.engine != "playcanvas":
        assert p["linear_blend_canvas_max"] >= 5
    # the comparison can fail: the port with 1 % more density is not the engine
    key = DENSITY[r.engine]
    off = type(model)(dataclasses.replace(model.params, **{key: getattr(model.params, key) * 1.01}))
    q = port_vs_engine(r, off)
    assert not q["at_quantisation"] and q["linear_max"] > 1e-5


@pytest.mark.render
def test_filament_canvas_is_its_port_on_a_truths_view(plane_truth):
    """Filament on the open plane's truth view (16x9), its fog mapped from the scene with the sun
    term on: the 8-bit canvas as Filament ships it (its default colour grading: ACES-legacy tone
    mapping, sRGB output; FXAA and dithering off) is the port's ``output="canvas"``, 1 code value
    measured on the 80 surface pixels (RMS 0.065; level 1), the linear target 8.3e-8; the port
    without its sun term misses by 22 code values and fails, the port without the tone mapping
    (the sRGB encoding of its linear image) by 12."""
    from fogref.cli.engine import engine_model
    from fogref.engines.port import port_vs_engine
    from fogref.engines.render import render_engine
    from fogref.engines.view import view_from_truth

    view = view_from_truth(plane_truth)
    model, _ = engine_model("filament", None, view.params, view)
    assert model.params.inScatteringSize > 0
    r = render_engine(view, model, "filament", timeout=120)
    p = port_vs_engine(r, model)
    assert p["pixels"] == 80 and p["canvas_max"] <= 1 and p["at_quantisation"], p["summary"]
    no_sun = type(model)(dataclasses.replace(model.params, inScatteringSize=-1.0))
    q = port_vs_engine(r, no_sun)
    assert q["canvas_max"] > 5 and not q["at_quantisation"], q["summary"]
    assert p["linear_blend_canvas_max"] > 5, p["summary"]


def test_linear_fog_settings_arrive(chromium):
    """three.js ``Fog`` (smoothstep on eye depth) from --param values, on the open plane."""
    from fogref.engines.port import port_vs_engine
    from fogref.engines.render import render_engine
    from fogref.engines.view import view_from_scene
    from fogref.mapping.build import build_model

    view = view_from_scene(SCENES / "open_plane.xml", {"res": "16", "resy": "9"})
    model = build_model("threejs", {"mode": "Fog", "near": 3.0, "far": 40.0, "color": [0.3, 0.4, 0.6]})
    r = render_engine(view, model, timeout=120)
    p = port_vs_engine(r, model)
    assert p["at_quantisation"], p["summary"]
    assert np.ptp(r.transmittance[r.hit]) > 0.3  # the smoothstep ramp is in view


def test_engine_render_command_writes_images_compare_reads(chromium, tmp_path, capsys):
    from fogref.compare.foreign import load_engine_images
    from fogref.exrio import read_exr

    out = tmp_path / "engine"
    code = main(
        ["engine", "render", str(SCENES / "valley.xml"), "--set", "res=16", "--set", "resy=9", "--from-scene"]
        + ["--out", str(out)]
    )
    assert code == 0
    text = capsys.readouterr().out
    assert "at the quantisation level" in text and "threejs 0.187.0" in text
    imgs = load_engine_images(out / "final.exr", out / "T.exr", out / "inscatter.exr", shape=(9, 16))
    assert imgs.final.shape == (9, 16, 3) and np.all(imgs.transmittance <= 1.0)
    channels, attrs = read_exr(out / "final.exr")
    assert {"R", "G", "B", "distance", "hit"} <= set(channels)
    assert attrs["fogref.engine"]["version"] == "0.187.0"
    # the fog settings are the ones `compare --model threejs --from-scene` evaluates, and say so
    import json

    from fogref.engines.threejs import settings
    from fogref.engines.view import view_from_scene
    from fogref.mapping.build import build_model

    record = json.loads((out / "engine.json").read_text())
    params = view_from_scene(SCENES / "valley.xml", {"res": "16", "resy": "9"}).params
    model = build_model("threejs", None, params)
    assert record["fog_settings"] == settings(model)
    assert record["fog_settings_source"]["density"].endswith("threejs_from_physical (--from-scene)")
    assert set(record["fog_settings_source"]) >= {"mode", "density", "color", "camera_forward"}
    canvas = load_engine_images(out / "canvas.png", shape=(9, 16))
    assert canvas.encodings["final"] == "srgb"


@pytest.mark.render
def test_compare_engine_is_compare_image_of_its_files(plane_truth, tmp_path, capsys):
    """``compare --engine`` renders the engine and checks it exactly as ``--image`` checks its files."""
    import json

    truth = str(plane_truth.path)
    out = tmp_path / "cmp"
    code = main(["compare", truth, "--engine", "threejs", "--from-scene", "--out", str(out), "--no-figures"])
    assert code in (0, 1, 3)
    assert "port vs engine" in capsys.readouterr().out
    e = out / "engine"
    code2 = main(
        ["compare", truth, "--image", str(e / "final.exr"), "--transmittance", str(e / "T.exr")]
        + ["--inscatter", str(e / "inscatter.exr"), "--out", str(tmp_path / "img"), "--no-figures"]
    )
    assert code2 == code
    rows = json.loads((out / "check.json").read_text())
    assert rows == json.loads((tmp_path / "img" / "check.json").read_text())
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["engine"]["port_vs_engine"]["at_quantisation"]
    assert "port vs engine" in (out / "index.md").read_text()


def _fogref(*args, env=None):
    return subprocess.run(
        [sys.executable, "-m", "fogref.cli", *args], capture_output=True, text=True, cwd=ROOT, env=env
    )


def test_unknown_engine_gets_did_you_mean(tmp_path):
    r = _fogref("engine", "render", str(SCENES / "valley.xml"), "--engine", "three", "--out", str(tmp_path))
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and "did you mean 'threejs'" in r.stderr, r.stderr
    r = _fogref("engine", "rendr", str(SCENES / "valley.xml"), "--out", str(tmp_path))
    assert r.returncode == 2 and "did you mean 'render'" in r.stderr, r.stderr


def test_no_chromium_is_one_clear_line(tmp_path):
    import os

    env = dict(os.environ, PATH=str(tmp_path))  # neither chromium nor chromedriver on PATH
    r = _fogref(
        "engine",
        "render",
        str(SCENES / "valley.xml"),
        "--set",
        "res=16",
        "--set",
        "resy=9",
        "--out",
        str(tmp_path / "o"),
        env=env,
    )
    assert r.returncode == 2, r.stderr
    assert r.stderr.count("\n") == 1 and "no chromium and chromedriver on PATH" in r.stderr, r.stderr
    assert not (tmp_path / "o").exists()


def test_missing_engine_files_are_one_clear_error(chromium, tmp_path):
    """A page's import (a file, or a folder: the name ends in '/') that is not there is
    EngineUnavailable naming it and `npm ci`, before the page loads."""
    from fogref.engines import babylon, threejs

    with Browser(timeout=30) as b:
        for mod, missing in (
            (threejs, {"three": tmp_path / "three.module.js"}),
            (babylon, {"@babylonjs/core/": tmp_path / "core"}),
        ):
            with pytest.raises(
                EngineUnavailable, match=f"{missing[next(iter(missing))].name}: missing .*npm ci"
            ):
                b.run_page(mod.PAGE, missing, {})
        (tmp_path / "core").write_text("a file where the folder should be")
        with pytest.raises(EngineUnavailable, match="core: missing"):
            b.run_page(babylon.PAGE, {"@babylonjs/core/": tmp_path / "core"}, {})


def test_compare_engine_refuses_other_modes_options(tmp_path):
    exr = tmp_path / "t.exr"
    exr.write_bytes(b"")
    r = _fogref("compare", str(exr), "--engine", "threejs", "--precision", "float64")
    assert r.returncode == 2 and "--precision does not apply with --engine" in r.stderr, r.stderr
    r = _fogref("compare", str(exr), "--model", "ue4", "--engine-output", "canvas")
    assert r.returncode == 2 and "--engine-output does not apply" in r.stderr, r.stderr


def test_engine_output_never_replaces_an_input(tmp_path):
    scene = tmp_path / "canvas.png"  # an input where the engine would write its canvas
    scene.write_text((SCENES / "valley.xml").read_text())
    r = _fogref("engine", "render", str(scene), "--out", str(tmp_path))
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert "would overwrite" in r.stderr and scene.read_text() == (SCENES / "valley.xml").read_text()


def test_unsupported_shape_is_one_line(tmp_path):
    text = (SCENES / "open_plane.xml").read_text()
    disk = '<shape type="disk" id="pond"><ref id="g"/></shape>\n</scene>'
    scene = tmp_path / "pond.xml"
    scene.write_text(text.replace("</scene>", disk))
    r = _fogref(
        "engine", "render", str(scene), "--set", "res=16", "--set", "resy=9", "--out", str(tmp_path / "o")
    )
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert "shape 'pond'" in r.stderr and "rectangles and spheres" in r.stderr, r.stderr
    assert not (tmp_path / "o").exists()


@pytest.mark.render
def test_meshes_the_scene_loads_are_drawn(chromium, tmp_path):
    """An OBJ tetrahedron on a ground plane (``fogref scene --geometry``): the engine's hits are the
    truth's, and its distance is within 1e-5 on all but <= 1 % of the pixels (a silhouette pixel whose
    centre lies within rounding of an edge may show the surface behind; 1 of 547 measured)."""
    from fogref.engines.render import render_engine, truth_agreement
    from fogref.engines.view import view_from_truth
    from fogref.gbuffer import load_truth
    from fogref.render.render import render

    (tmp_path / "tet.obj").write_text(
        "v 0 0 0\nv 10 0 0\nv 0 0 10\nv 0 5 0\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
    )
    scene = tmp_path / "m.xml"
    args = ["scene", "--out", str(scene), "--geometry", str(tmp_path / "tet.obj"), "--mesh-scale", "3"]
    args += [
        "--mesh-translate=-10,0,25",
        "--ground",
        "--camera-origin",
        "0,5,0",
        "--camera-target",
        "0,4.7,1",
    ]
    assert main(args + ["--res", "32", "--resy", "18"]) == 0
    truth = load_truth(render(scene, tmp_path / "t.exr", spp=1, progress=False, png=False))
    assert (truth.position[..., 1] > 0.01).sum() > 50  # the tetrahedron is in view
    a = truth_agreement(render_engine(view_from_truth(truth), None, timeout=120), truth)
    assert a["hit_mismatch_pixels"] == 0
    assert a["both_hit_pixels"] - a["distance_within_1e-5"] <= 0.01 * a["both_hit_pixels"], a


@pytest.mark.render
@pytest.mark.parametrize("engine", sorted(ENGINES))
def test_engine_lighting_is_the_truths_without_fog(chromium, tmp_path, engine):
    """On the fog-free open plane the truth is exact per sample (delta sun by next-event estimation,
    constant sky by the cosine-weighted BSDF sample: stderr 0), and the engine's sun
    (three.js: DirectionalLight of colour E; Babylon, PlayCanvas: E / pi), sky (a hemisphere
    light; PlayCanvas: its ambient light, the sky's on this horizontal ground; the background L)
    and Lambert material give the same image (Filament: unlit, its vertex colours fogref's Lambert
    shading): 2.1e-7 (three.js), 7.0e-8 (Babylon, PlayCanvas), 2.5e-7 (Filament) relative measured
    (float32); the tolerance 1e-5 fails a sun or sky off by more than 0.001 %
    (a factor pi, the usual slip, is 200 %)."""
    from fogref.engines.render import render_engine
    from fogref.engines.view import view_from_truth
    from fogref.gbuffer import load_truth
    from fogref.render.render import render

    overrides = {"res": 16, "resy": 9, "sigma_t": "0"}
    truth = load_truth(
        render(
            SCENES / "open_plane.xml",
            tmp_path / "t.exr",
            spp=2,
            overrides=overrides,
            progress=False,
            png=False,
        )
    )
    assert truth.stderr["final"].max() == 0.0
    r = render_engine(view_from_truth(truth), None, engine, timeout=120)
    assert np.array_equal(r.hit, truth.hit) and r.hit.any() and (~r.hit).any()
    np.testing.assert_allclose(r.final, truth.final, rtol=1e-5, atol=0)


def test_engine_settings_say_where_they_came_from():
    """PlayCanvas's fog reads its camera's clip planes: ``fogref engine`` sets them from the view
    (nothing clipped) unless ``--param`` gives them, and says where each setting came from."""
    from fogref.cli.engine import engine_model
    from fogref.engines.view import view_from_scene

    view = view_from_scene(SCENES / "open_plane.xml", {"res": "16", "resy": "9"})
    model, src = engine_model("playcanvas", {"density": 0.01}, None, view)
    assert (model.params.nearClip, model.params.farClip) == view.clip_planes()
    assert src["nearClip"].startswith("the view") and src["farClip"].startswith("the view")
    assert src["density"] == "--param" and src["type"].startswith("the model's default")
    model, src = engine_model("playcanvas", {"farClip": 50.0}, None, view)
    assert model.params.farClip == 50.0 and src["farClip"] == "--param"
    assert model.params.nearClip == view.clip_planes()[0]
    model, src = engine_model("threejs", None, None, view)  # three.js's fog has no clip planes
    assert not any(v.startswith("the view") for v in src.values())
