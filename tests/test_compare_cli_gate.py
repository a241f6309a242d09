"""``fogref compare`` gates CI: check()'s verdict as the exit code, --json/--junit, sRGB PNGs,
``fogref info``.

The truth is synthetic (:func:`fogref.compare.check.synthetic_truth`: 64x36 px, 2 % relative
noise on the inscatter and surface, T noise-free) written as a schema-2 EXR; the engine's
images are the model's exact fog on it, or its inscatter 5 % too bright.
"""

import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from truth_factory import synthetic_truth_exr, write_rgb

from fogref.cli import main
from fogref.gbuffer import load_truth
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams

MODEL = UE4ExponentialHeightFog(UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2))
#: the inscatter PNG holds exposure * inscatter (<= 0.53 for the 5 % case: no clipping at 1)
EXPOSURE = 0.5


def write_srgb_png(path, img):
    """8-bit sRGB PNG of a linear image in [0, 1] (colour-science's IEC 61966-2-1 encoding)."""
    import colour
    from PIL import Image

    enc = np.asarray(colour.cctf_encoding(np.clip(img, 0, 1), function="sRGB"))
    Image.fromarray(np.round(enc * 255).astype(np.uint8)).save(path)
    return path


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    d = tmp_path_factory.mktemp("gate")
    exr, p = synthetic_truth_exr(d / "truth.exr", MODEL)
    write_rgb(d / "T.exr", p["T"])
    for name, k in (("exact", 1.0), ("bright", 1.05), ("two", 1.02)):
        write_rgb(d / f"L_{name}.exr", k * p["inscatter"])
        write_srgb_png(d / f"L_{name}.png", EXPOSURE * k * p["inscatter"])
    return d, exr


def _run(capsys, *argv):
    code = main(["compare", *map(str, argv)])
    return code, capsys.readouterr()


def _rows(path):
    return {(r["part"], r["region"], r["metric"]): r for r in json.loads(path.read_text())["rows"]}


def test_exr_inscatter_five_percent_fails_exact_passes(scene, tmp_path, capsys):
    d, exr = scene
    for name, code in (("exact", 0), ("bright", 1)):
        out, js = tmp_path / name, tmp_path / f"{name}.json"
        got, _ = _run(
            capsys,
            exr,
            "--transmittance",
            d / "T.exr",
            "--inscatter",
            d / f"L_{name}.exr",
            "--out",
            out,
            "--json",
            js,
            "--no-figures",
        )
        assert got == code, name
        g = json.loads(js.read_text())
        assert g["exit_code"] == code and g["verdict"] == ("pass" if code == 0 else "fail")
        assert g["encodings"] == {"transmittance": "linear", "inscatter": "linear"}
        bias = _rows(js)[("inscatter", "all", "rel_bias")]
        assert bias["verdict"] == g["verdict"] and bias["low"] <= bias["estimate"] <= bias["high"]
        if code:
            assert 0.045 < bias["estimate"] < 0.055
        # the report holds the same rows
        assert json.loads((out / "metrics.json").read_text())["check"]["rows"] == g["rows"]
        assert "| inscatter | all | rel_bias |" in (out / "index.md").read_text()


def test_png_srgb_inscatter_five_percent_fails_exact_passes(scene, tmp_path, capsys):
    """8-bit sRGB PNG, read as sRGB by default (--encoding auto) and divided by --exposure.

    The exact PNG's error is its 8-bit quantisation only (inscatter rel_rmse ~0.3 %, |rel_bias| <
    0.1 %), within the default tolerances (rel_rmse 0.05, |rel_bias| 0.02): exit 0.  The 5 % brighter
    PNG's inscatter rel_bias (~0.05) is outside 0.02: exit 1.  Read as linear, the exact PNG fails.
    """
    d, exr = scene
    for name, code in (("exact", 0), ("bright", 1)):
        out, js = tmp_path / name, tmp_path / f"{name}.json"
        got, _ = _run(
            capsys,
            exr,
            "--transmittance",
            d / "T.exr",
            "--inscatter",
            d / f"L_{name}.png",
            "--exposure",
            EXPOSURE,
            "--out",
            out,
            "--json",
            js,
            "--no-figures",
        )
        assert got == code, name
        g = json.loads(js.read_text())
        assert g["encodings"] == {"transmittance": "linear", "inscatter": "srgb"}
        bias = _rows(js)[("inscatter", "all", "rel_bias")]
        assert (abs(bias["estimate"]) < 0.005) if code == 0 else (0.04 < bias["estimate"] < 0.06), bias
        metrics = json.loads((out / "metrics.json").read_text())
        assert metrics["images"]["encodings"]["inscatter"] == "srgb"
        assert "inscatter `" in (out / "index.md").read_text() and "(srgb)" in (out / "index.md").read_text()
    got, _ = _run(
        capsys,
        exr,
        "--transmittance",
        d / "T.exr",
        "--inscatter",
        d / "L_exact.png",
        "--exposure",
        EXPOSURE,
        "--encoding",
        "linear",
        "--out",
        tmp_path / "lin",
        "--no-figures",
    )
    assert got == 1


def test_image_run_gets_the_model_report(scene, tmp_path, capsys):
    """--image runs write the model report's figures, ΔE2000 and FLIP, plus the composite part."""
    d, exr = scene
    out = tmp_path / "r"
    assert (
        _run(capsys, exr, "--transmittance", d / "T.exr", "--inscatter", d / "L_bright.exr", "--out", out)[0]
        == 1
    )
    for part in ("transmittance", "inscatter", "attenuated_surface", "composite"):
        assert (out / "side_by_side" / f"{part}.png").is_file() and (
            out / "heatmaps" / f"{part}.png"
        ).is_file()
    assert (out / "error_vs_distance.png").is_file() and (out / "check.json").is_file()
    m = json.loads((out / "metrics.json").read_text())
    s = m["metrics"]["inscatter"]["all"]
    assert s["delta_e2000_mean"] > 0 and s["flip_mean"] > 0
    assert not list(out.rglob("*.tmp*"))


def test_inconclusive_exits_3_and_maps(scene, tmp_path, capsys):
    """Inscatter 2 % too bright against a |rel_bias| tolerance of 0.02: every interval straddles it."""
    d, exr = scene
    base = [
        exr,
        "--transmittance",
        d / "T.exr",
        "--inscatter",
        d / "L_two.exr",
        "--no-figures",
        "--distance-bands",
        "none",
        "--tolerance",
        "inscatter:rel_bias=0.02",
        "--tolerance",
        "composite:rel_bias=none",
    ]
    junit = tmp_path / "j.xml"
    code, out = _run(capsys, *base, "--out", tmp_path / "a", "--junit", junit, "--json", tmp_path / "a.json")
    assert code == 3, out.out
    assert json.loads((tmp_path / "a.json").read_text())["verdict"] == "inconclusive"
    suite = ET.parse(junit).getroot()
    cases = {(c.get("classname"), c.get("name")): c for c in suite.iter("testcase")}
    bias = cases[("fogref.inscatter.all", "rel_bias")]
    assert bias.find("failure").get("type") == "inconclusive"
    assert ("fogref.composite.all", "rel_bias") not in cases  # tolerance none: reported, not a testcase
    assert int(suite.get("tests")) == len(cases) and int(suite.get("failures")) >= 1
    assert _run(capsys, *base, "--out", tmp_path / "b", "--inconclusive", "fail")[0] == 1
    assert _run(capsys, *base, "--out", tmp_path / "c", "--inconclusive", "pass", "--junit", junit)[0] == 0
    bias = {(c.get("classname"), c.get("name")): c for c in ET.parse(junit).getroot().iter("testcase")}[
        ("fogref.inscatter.all", "rel_bias")
    ]
    assert bias.find("skipped") is not None and bias.find("failure") is None


def test_junit_and_json_of_a_failure(scene, tmp_path, capsys):
    d, exr = scene
    junit, js = tmp_path / "j.xml", tmp_path / "g.json"
    assert (
        _run(
            capsys,
            exr,
            "--transmittance",
            d / "T.exr",
            "--inscatter",
            d / "L_bright.exr",
            "--out",
            tmp_path / "r",
            "--no-figures",
            "--junit",
            junit,
            "--json",
            js,
            "--tolerance",
            "inscatter/sky=0.5",
            "--tolerance",
            "T:rel_bias=0.001",
            "--confidence",
            "0.95",
            "--distance-bands",
            "50,500",
        )[0]
        == 1
    )
    g = json.loads(js.read_text())
    assert g["confidence"] == 0.95 and g["settings"]["distance_bands_m"] == [50.0, 500.0]
    rows = _rows(js)
    assert rows[("inscatter", "sky", "rel_rmse")]["tolerance"] == 0.5
    assert rows[("T", "all", "rel_bias")]["tolerance"] == 0.001
    assert ("inscatter", "d50-500m", "rel_rmse") in rows
    suite = ET.parse(junit).getroot()
    failed = [c for c in suite.iter("testcase") if c.find("failure") is not None]
    assert {c.find("failure").get("type") for c in failed} <= {"fail", "inconclusive"}
    assert ("fogref.inscatter.all", "rel_bias") in {(c.get("classname"), c.get("name")) for c in failed}
    assert len(list(suite.iter("testcase"))) == sum(r["tolerance"] is not None for r in g["rows"])


def test_usage_errors_exit_2_with_one_line(scene, tmp_path, capsys):
    d, exr = scene
    img = ["--inscatter", d / "L_exact.exr", "--out", tmp_path / "r", "--no-figures"]
    for bad, says in (
        (["--tolerance", "foo"], "--tolerance foo: expected PART[/REGION][:METRIC]=VALUE"),
        (["--tolerance", "inscatter=-1"], "must be a finite number >= 0"),
        (["--tolerance", "inscatr=0.1"], "unknown part 'inscatr'"),
        (["--confidence", "1.5"], "'--confidence': 1.5 is outside (0, 1)"),
        (["--inconclusive", "maybe"], "'--inconclusive': 'maybe' is not one of fail, pass"),
        (["--distance-bands", "1000,100"], "--distance-bands 1000,100"),
    ):
        code, out = _run(capsys, exr, *img, *bad)
        assert code == 2, bad
        err = out.err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("fogref: error:") and says in err[0], err
        assert "Traceback" not in out.err


def test_help_documents_exit_codes(capsys):
    with pytest.raises(SystemExit):
        main(["compare", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "exit codes: 0 pass, 1 fail, 2 usage or input error, 3 inconclusive" in text


def test_default_out_is_git_ignored_out(scene, tmp_path, monkeypatch, capsys):
    d, exr = scene
    monkeypatch.chdir(tmp_path)
    assert (
        _run(capsys, exr, "--inscatter", d / "L_exact.exr", "--transmittance", d / "T.exr", "--no-figures")[0]
        == 0
    )
    assert (tmp_path / "out" / "compare" / "truth-L_exact" / "index.md").is_file()
    assert not (tmp_path / "reports").exists()


def test_model_run_gates_too(scene, tmp_path, capsys):
    """--model runs: the verdict is check()'s on the same truth (the exact model passes, another fails)."""
    from fogref.mapping.build import build_model as build
    from fogref.mapping.build import parse_param_assignments

    d, exr = scene
    p = parse_param_assignments(["FogDensity=0.02", "FogHeightFalloff=0.2"])
    assert build("ue4", p)  # the names exist
    js = tmp_path / "m.json"
    code, out = _run(
        capsys,
        exr,
        "--model",
        "ue4",
        "--param",
        "FogDensity=0.02",
        "--param",
        "FogHeightFalloff=0.2",
        "--precision",
        "float64",
        "--out",
        tmp_path / "m",
        "--no-figures",
        "--json",
        js,
    )
    assert code == 0, out.out
    assert {r["part"] for r in json.loads(js.read_text())["rows"]} == {"T", "inscatter", "final"}
    assert "## Verdict" in (tmp_path / "m" / "index.md").read_text()
    assert (
        _run(
            capsys,
            exr,
            "--model",
            "ue4",
            "--param",
            "FogDensity=0.03",
            "--param",
            "FogHeightFalloff=0.2",
            "--out",
            tmp_path / "m2",
            "--no-figures",
        )[0]
        == 1
    )


def test_info_json_camera_of_a_synthetic_truth_is_derived(scene, capsys):
    """A header with only camera.origin: the rest is fitted to the view channel."""
    d, exr = scene
    assert main(["info", str(exr), "--json"]) == 0
    cam = json.loads(capsys.readouterr().out)["camera"]
    assert cam["source"] == "derived from the view channel" and cam["near_clip"] is None
    truth = load_truth(exr)
    # synthetic_truth's image x grows along up x forward, the mirror of Mitsuba's: the fit says so
    assert cam["mirrored"]
    # its rays are tilted by a 0.02 principal-point shift, which a centred pinhole fits to ~1e-3
    # at the centre and ~3e-3 in the corners
    assert cam["fov_deg"] == pytest.approx(70.0, abs=0.05)
    for i, j, tol in ((32, 18, 1e-3), (0, 0, 5e-3), (63, 35, 5e-3)):
        assert _pixel_direction(cam, i, j, cam["right"]) == pytest.approx(truth.view[j, i], abs=tol)


def _pixel_direction(cam: dict, i: int, j: int, right=None) -> np.ndarray:
    """The view direction of pixel (column i, row j from the top), rebuilt from origin/target/up/fov
    (image x along ``forward x up``, as Mitsuba's; ``right`` overrides that)."""
    W, H = cam["resolution"]
    assert cam["fov_axis"] == "x"
    f = np.subtract(cam["target"], cam["origin"])
    f /= np.linalg.norm(f)
    right = np.cross(f, cam["up"]) if right is None else np.asarray(right, dtype=float)
    right /= np.linalg.norm(right)
    up = np.asarray(cam["up"], dtype=float) - np.dot(cam["up"], f) * f
    up /= np.linalg.norm(up)
    t = np.tan(np.radians(cam["fov_deg"]) / 2)
    u, v = 2 * (i + 0.5) / W - 1, 1 - 2 * (j + 0.5) / H
    d = f + u * t * right + v * t * H / W * up
    return d / np.linalg.norm(d)


@pytest.mark.render
def test_info_json_round_trips_the_rendered_camera(fogref_truth, capsys):
    """A real render (32x18, 16 spp): the header's camera rebuilds the truth's view channel."""
    truth = fogref_truth("scenes/valley.xml", res=(32, 18), spp=16, seed=0)
    assert main(["info", str(truth.path), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    cam, ue = d["camera"], d["camera_unreal"]
    assert cam["source"] == "header" and cam["resolution"] == [32, 18] and cam["near_clip"] > 0
    assert "mirrored" not in cam
    m = np.array(cam["to_world"])
    assert m.shape == (4, 4) and m[:3, 3] == pytest.approx(cam["origin"])
    W, H = cam["resolution"]
    assert _pixel_direction(cam, W // 2, H // 2) == pytest.approx(truth.view[H // 2, W // 2], abs=1e-5)
    for i, j in ((0, 0), (W - 1, 3), (5, H - 1)):
        assert _pixel_direction(cam, i, j) == pytest.approx(truth.view[j, i], abs=1e-5), (i, j)
    # Unreal: (x, y, z)_ue = 100 (x, z, y); FRotator's forward is the converted forward
    assert ue["location_cm"] == pytest.approx([100 * cam["origin"][k] for k in (0, 2, 1)])
    r = {k: np.radians(v) for k, v in ue["rotation"].items()}
    fwd = [np.cos(r["pitch"]) * np.cos(r["yaw"]), np.cos(r["pitch"]) * np.sin(r["yaw"]), np.sin(r["pitch"])]
    assert fwd == pytest.approx(ue["forward"], abs=1e-9) and abs(ue["rotation"]["roll"]) < 1e-6
    # the fit used for older files agrees with the header
    from fogref.info import camera_from_views

    fit = camera_from_views(truth.view, cam["origin"])
    assert fit["fov_deg"] == pytest.approx(cam["fov_deg"], abs=1e-3)
    assert fit["forward"] == pytest.approx(cam["forward"], abs=1e-4)
    assert fit["up"] == pytest.approx(cam["up"], abs=1e-4) and not fit["mirrored"]
