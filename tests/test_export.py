"""``fogref export``: each engine's snippet parses with its ecosystem's tool (or a grammar check where
none runs here) and its numbers, read back, are the fit's in the engine's units, axes and spaces.

References: the fit table reports/fit/engines.json (the values), colour-science's sRGB curve
(the colour spaces), the frame conversions written out here (Unreal (x, z, y) * 100 cm; Unity
z -> -z); three.js itself runs the JavaScript and reports what it set.
"""

import ast
import json
import math
import re
import shutil
import subprocess
from pathlib import Path

import colour
import numpy as np
import pytest

from fogref.cli import export as cli_export
from fogref.cli import main
from fogref.mapping.export import ENGINES
from fogref.mapping.fit import with_sun_elevation
from fogref.scene.describe import lookat_camera
from fogref.shipped_scenes import scene_path
from fogref.study.fit import physical_from_scene

ROOT = Path(__file__).resolve().parents[1]
TABLE = ROOT / "reports" / "fit" / "engines.json"
NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


def _row(model):
    doc = json.loads(TABLE.read_text())
    return next(r for r in doc["fits"] if r["model"] == model)


def _export(tmp_path, engine, *extra, suffix=".txt"):
    out = tmp_path / f"fogref_{engine}{suffix}"
    assert main(["export", "--engine", engine, "--json", str(TABLE), "--out", str(out), *extra]) == 0
    return out


def _nums(text):
    """The numbers of a value: of ``Name(a, b, ...)`` its arguments."""
    return [float(x) for x in re.findall(NUM, text.partition("(")[2] or text)]


def _srgb(lin):
    return colour.cctf_encoding(np.asarray(lin, float), function="sRGB")


def _linear(srgb):
    return colour.cctf_decoding(np.asarray(srgb, float), function="sRGB")


def _sun():
    pf = physical_from_scene(scene_path("valley"))
    ps = with_sun_elevation(pf, _row("ue4")["fit"]["sun_elevations_deg"][0])
    w = np.asarray(ps.sun_direction, float)
    return w / np.linalg.norm(w), np.asarray(pf.sun_irradiance, float)


def _camera():
    c = lookat_camera(scene_path("valley"))
    f = np.subtract(c["target"], c["origin"])
    return c, f / np.linalg.norm(f)


def test_the_engine_names_are_the_exporters():
    assert cli_export.ENGINE_NAMES == tuple(ENGINES)


def test_unreal_python_parses_and_holds_the_fit_in_unreals_units(tmp_path):
    text = _export(tmp_path, "unreal", suffix=".py").read_text()
    ast.parse(text)
    s = _row("ue4")["settings"]

    def prop(name):
        return float(re.search(rf'\["{name}"\], ({NUM})\)', text).group(1))

    for name in ("FogDensity", "FogHeightFalloff", "DirectionalInscatteringExponent", "FogMaxOpacity"):
        snake = re.sub(r"(?<!^)(?=[A-Z])", "_", name).lower()
        assert prop(snake) == pytest.approx(s[name], rel=1e-8)
    lin = re.search(rf"'fog_inscattering_luminance'\], unreal.LinearColor\(({NUM}), ({NUM}), ({NUM})", text)
    np.testing.assert_allclose([float(x) for x in lin.groups()], s["FogInscatteringColor"], rtol=1e-8)
    # Unreal multiplies DirectionalInscatteringColor by the sun light's luminance: the product is the fit's
    d = re.search(
        rf"'directional_inscattering_luminance'\], unreal.LinearColor\(({NUM}), ({NUM}), ({NUM})", text
    )
    c8 = re.search(r"unreal.Color\(r=(\d+), g=(\d+), b=(\d+)", text).groups()
    lux = float(re.search(rf"'intensity', ({NUM})\)", text).group(1))
    light = _linear(np.array([int(x) for x in c8]) / 255.0) * lux
    y = float(light @ [0.3, 0.59, 0.11])  # FLinearColor::ComputeLuminance
    np.testing.assert_allclose(
        np.array([float(x) for x in d.groups()]) * y,
        np.array(s["DirectionalInscatteringColor"]) * s["SunLuminance"],
        rtol=1e-6,
    )
    w, E = _sun()
    np.testing.assert_allclose(light, E, rtol=0.01)  # 8-bit sRGB light colour: within 1 %
    assert lux == pytest.approx(E.max(), rel=1e-8)
    rot = re.search(rf"DirectionalLight, .*?pitch=({NUM}), yaw=({NUM})", text).groups()
    assert float(rot[0]) == pytest.approx(-math.degrees(math.asin(w[1])), abs=1e-6)  # light travels down
    assert float(rot[1]) == pytest.approx(math.degrees(math.atan2(-w[2], -w[0])), abs=1e-6)
    c, f = _camera()
    loc = re.search(rf"CameraActor, unreal.Vector\(({NUM}), ({NUM}), ({NUM})\)", text).groups()
    np.testing.assert_allclose([float(x) for x in loc], 100.0 * np.array(c["origin"])[[0, 2, 1]], atol=1e-9)
    cam = re.search(rf"CameraActor, .*?pitch=({NUM}), yaw=({NUM})", text).groups()
    assert float(cam[0]) == pytest.approx(math.degrees(math.asin(f[1])), abs=1e-6)
    assert float(cam[1]) == pytest.approx(math.degrees(math.atan2(f[2], f[0])), abs=1e-6)


def _godot_file(text):
    """A small grammar of Godot's text resources: ``[section attr=value ...]`` headers and
    ``key = value`` lines, a value being a number, true/false, a quoted string or
    ``Constructor(args)``; ';' starts a comment.  Returns [(section, {key: value text})]."""
    value = rf'(?:{NUM}|true|false|"[^"]*"|[A-Za-z0-9]+\((?:\s*(?:{NUM}|"[^"]*")\s*,?)*\))'
    sections = []
    for raw in text.splitlines():
        line = raw.strip()
        if not line or line.startswith(";"):
            continue
        if line.startswith("["):
            assert re.fullmatch(rf'\[[a-z_]+(?: [a-z_]+=(?:"[^"]*"|{NUM}))*\]', line), line
            sections.append((line, {}))
            continue
        m = re.fullmatch(rf"([a-z_0-9]+) = ({value})", line)
        assert m, f"not key = value: {line}"
        sections[-1][1][m.group(1)] = m.group(2)
    return sections


def test_godot_resources_parse_and_hold_the_fit_in_srgb(tmp_path):
    tres = _export(tmp_path, "godot", suffix=".tres")
    env = _godot_file(tres.read_text())
    assert env[0][0].startswith('[gd_resource type="Environment"') and env[1][0] == "[resource]"
    r, s = env[1][1], _row("godot")["settings"]
    np.testing.assert_allclose(_nums(r["fog_light_color"])[:3], _srgb(s["fog_light_color"]), rtol=1e-7)
    for k in ("fog_density", "fog_sky_affect", "fog_height", "fog_light_energy"):
        assert float(r[k]) == pytest.approx(s[k], rel=1e-8, abs=1e-12)
    scene = dict(_godot_file(tres.with_suffix(".tscn").read_text()))
    sun = scene['[node name="Sun" type="DirectionalLight3D" parent="."]']
    w, E = _sun()
    # Godot's shader light: linear colour x light_energy x pi (light_storage.cpp, no physical units)
    light = _linear(_nums(sun["light_color"])[:3]) * float(sun["light_energy"]) * math.pi
    np.testing.assert_allclose(light, E, rtol=1e-7)  # the light is the sun
    z = np.array(_nums(sun["transform"])[:9]).reshape(3, 3)[:, 2]
    np.testing.assert_allclose(z, w, atol=1e-8)  # it shines along -Z, away from the sun
    lobe = light * float(r["fog_sun_scatter"])
    stated = float(re.search(rf"differs from E's by ({NUM})", tres.read_text()).group(1))
    err = np.linalg.norm(lobe - s["sun_color"]) / np.linalg.norm(s["sun_color"])
    assert err == pytest.approx(stated, rel=0.01) and err < 0.05
    cam = scene['[node name="Camera3D" type="Camera3D" parent="."]']
    m = _nums(cam["transform"])
    c, f = _camera()
    np.testing.assert_allclose(-np.array(m[:9]).reshape(3, 3)[:, 2], f, atol=1e-8)
    np.testing.assert_allclose(m[9:], c["origin"], atol=1e-12)
    fov_y = 2 * math.degrees(math.atan(math.tan(math.radians(c["fov_deg"]) / 2) * 180 / 320))
    assert float(cam["fov"]) == pytest.approx(fov_y, rel=1e-8)


RUSTC = shutil.which("rustc")


def test_bevy_rust_is_valid_items_and_holds_the_fit(tmp_path):
    text = _export(tmp_path, "bevy", suffix=".rs").read_text()
    s = _row("bevy")["settings"]
    ext = re.search(rf"extinction: Vec3::new\(({NUM}), ({NUM}), ({NUM})\)", text).groups()
    np.testing.assert_allclose([float(x) for x in ext], s["extinction"], rtol=1e-8)
    col = re.search(rf"  color: Color::linear_rgba\(({NUM}), ({NUM}), ({NUM}), ({NUM})\)", text).groups()
    np.testing.assert_allclose([float(x) for x in col], s["color"], rtol=1e-8)
    dl = [
        float(x)
        for x in re.search(r"directional_light_color: Color::linear_rgba\(([^)]*)\)", text)
        .group(1)
        .split(",")
    ]
    lc = [float(x) for x in re.search(r"color: Color::linear_rgb\(([^)]*)\)", text).group(1).split(",")]
    lux = float(re.search(rf"illuminance: ({NUM})", text).group(1))
    ev100 = float(re.search(rf"ev100: ({NUM})", text).group(1))
    exposure = 2.0 ** (-ev100) / 1.2  # Bevy's Exposure::exposure()
    w, E = _sun()
    np.testing.assert_allclose(np.array(lc) * lux * exposure, E, rtol=1e-7)
    # Bevy's lobe: light colour x illuminance x exposure x directional_light_color, the fit's product
    np.testing.assert_allclose(
        np.array(lc) * lux * exposure * dl[:3],
        np.array(s["light_color"]) * s["directional_light_color"][:3],
        rtol=1e-6,
    )
    if RUSTC is None:
        pytest.skip("rustc not installed: the values are checked, the Rust grammar is not")
    run = rustc_items(text, tmp_path)
    assert run.returncode == 0, run.stderr


def rustc_items(text: str, tmp_path) -> subprocess.CompletedProcess:
    """rustc parses every item of ``text`` (the macro's ``$i:item`` matcher) without resolving names."""
    crate = tmp_path / "items.rs"
    crate.write_text("macro_rules! items { ($($i:item)*) => {}; }\nitems! {\n" + text + "\n}\n")
    out = str(tmp_path / "items.rmeta")
    cmd = [RUSTC, "--edition", "2021", "--crate-type", "lib", "--emit=metadata", "-o", out, str(crate)]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=300)


def test_rusts_item_check_refuses_a_broken_snippet(tmp_path):
    """The grammar check above can fail: a missing brace is refused."""
    if RUSTC is None:
        pytest.skip("rustc not installed")
    assert rustc_items("pub fn f() { let x = (1, ;", tmp_path).returncode != 0


NODE = shutil.which("node")
THREE = ROOT / "node_modules" / "three"


@pytest.mark.skipif(NODE is None, reason="node not installed")
def test_threejs_module_runs_in_three_and_sets_the_fit(tmp_path):
    snippet = _export(tmp_path, "threejs", suffix=".mjs")
    subprocess.run([NODE, "--check", str(snippet)], check=True, timeout=120)
    if not THREE.is_dir():
        pytest.skip("node_modules/three missing (scripts/setup.sh installs it): syntax checked only")
    (tmp_path / "node_modules").symlink_to(ROOT / "node_modules")
    probe = tmp_path / "probe.mjs"
    probe.write_text(
        "import * as THREE from 'three';\n"
        f"import {{ applyFogref }} from './{snippet.name}';\n"
        "const scene = new THREE.Scene();\n"
        "const { camera, sun } = applyFogref(scene);\n"
        "camera.updateMatrixWorld();\n"
        "const d = new THREE.Vector3(); camera.getWorldDirection(d);\n"
        "const c = scene.fog.color; const l = sun.color;\n"
        "console.log(JSON.stringify({type: scene.fog.isFogExp2 ? 'FogExp2' : 'Fog',\n"
        "  density: scene.fog.density,\n"
        "  color: [c.r, c.g, c.b], light: [l.r * sun.intensity, l.g * sun.intensity, l.b * sun.intensity],\n"
        "  sun: sun.position.toArray(), fov: camera.fov, dir: d.toArray(),\n"
        "  pos: camera.position.toArray()}));\n"
    )
    out = subprocess.run([NODE, str(probe)], capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout)
    s = _row("threejs")["settings"]
    assert got["type"] == s["mode"] and got["density"] == pytest.approx(s["density"], rel=1e-7)
    np.testing.assert_allclose(got["color"], s["color"], rtol=1e-6)  # linear working space
    w, E = _sun()
    np.testing.assert_allclose(got["light"], E, rtol=1e-6)
    np.testing.assert_allclose(np.array(got["sun"]) / np.linalg.norm(got["sun"]), w, atol=1e-7)
    c, f = _camera()
    np.testing.assert_allclose(got["dir"], f, atol=1e-6)
    np.testing.assert_allclose(got["pos"], c["origin"], atol=1e-12)


def _csharp_balanced(text):
    """Brackets balance and every statement line ends with ';' (no C# compiler runs here)."""
    code = re.sub(r"//.*", "", text)
    pairs, stack = {")": "(", "]": "[", "}": "{"}, []
    for ch in code:
        if ch in "([{":
            stack.append(ch)
        elif ch in pairs:
            assert stack and stack.pop() == pairs[ch], "unbalanced"
    assert not stack
    for line in code.splitlines():
        t = line.strip()
        if t and not t.startswith(("using ", "public ", "if ", "{", "}")) and not t.endswith("{"):
            assert t.endswith(";"), t


@pytest.mark.parametrize("engine", ["unity", "hdrp"])
def test_unity_csharp_is_balanced_and_holds_the_fit_left_handed(tmp_path, engine):
    text = _export(tmp_path, engine, suffix=".cs").read_text()
    _csharp_balanced(text)
    s = _row(engine)["settings"]
    if engine == "unity":
        assert float(re.search(rf"fogDensity = ({NUM})f", text).group(1)) == pytest.approx(
            s["fogDensity"], rel=1e-8
        )
        fc = re.search(rf"fogColor = new Color\(({NUM})f, ({NUM})f, ({NUM})f\).gamma", text).groups()
        np.testing.assert_allclose([float(x) for x in fc], s["fogColor"], rtol=1e-8)
    else:
        mfp = float(re.search(rf"meanFreePath.Override\(({NUM})f\)", text).group(1))
        assert mfp == pytest.approx(s["meanFreePath"], rel=1e-8)
        fc = re.search(rf"fog.color.Override\(new Color\(({NUM})f, ({NUM})f, ({NUM})f\)\)", text).groups()
        np.testing.assert_allclose([float(x) for x in fc], s["color"], rtol=1e-8)
    c, f = _camera()
    look = re.search(
        rf"camera.transform.rotation = Quaternion.LookRotation\(new Vector3\(({NUM})f, ({NUM})f, ({NUM})f\)",
        text,
    )
    np.testing.assert_allclose([float(x) for x in look.groups()], f * [1, 1, -1], atol=1e-8)
    w, E = _sun()
    lux = float(re.search(rf"sun.intensity = ({NUM})f", text).group(1))
    # HDRP: lux; the built-in Standard BRDF leaves out the diffuse 1/pi (UnityStandardBRDF.cginc)
    assert lux * (math.pi if engine == "unity" else 1.0) == pytest.approx(E.max(), rel=1e-8)
    sun = re.search(
        rf"sun.transform.rotation = Quaternion.LookRotation\(new Vector3\(({NUM})f, ({NUM})f, ({NUM})f\)",
        text,
    )
    np.testing.assert_allclose([float(x) for x in sun.groups()], -w * [1, 1, -1], atol=1e-8)


@pytest.mark.skipif(NODE is None, reason="node not installed")
def test_filament_module_parses_and_holds_the_fit(tmp_path):
    snippet = _export(tmp_path, "filament", suffix=".mjs")
    subprocess.run([NODE, "--check", str(snippet)], check=True, timeout=120)
    text = snippet.read_text()
    s = _row("filament")["settings"]
    for k in ("density", "heightFalloff", "inScatteringSize"):
        assert float(re.search(rf"    {k}: ({NUM}),", text).group(1)) == pytest.approx(s[k], rel=1e-8)
    col = [float(x) for x in re.search(r"    color: \[([^\]]*)\]", text).group(1).split(",")]
    np.testing.assert_allclose(col, s["color"], rtol=1e-8)
    lc = [float(x) for x in re.search(r"\.color\(\[([^\]]*)\]\)", text).group(1).split(",")]
    lux = float(re.search(rf"\.intensity\(({NUM})\)", text).group(1))
    want = np.array(s["lightColorIntensity"][:3]) * s["lightColorIntensity"][3]
    np.testing.assert_allclose(np.array(lc) * lux, want, rtol=1e-7)  # the fog's lobe as fitted


def test_export_refuses_bad_input(tmp_path, capsys):
    assert main(["export", "--engine", "unreel"]) == 2
    assert "did you mean 'unreal'" in capsys.readouterr().err
    assert main(["export", "--engine", "godot", "--param", "fog_densty=0.1"]) == 2
    assert "did you mean 'fog_density'" in capsys.readouterr().err
    assert main(["export", "--engine", "bevy", "--json", str(TABLE), "--sun-elevation", "45"]) == 2
    assert "no fit of 'bevy' at 45 deg" in capsys.readouterr().err
    assert main(["export", "--engine", "unreal", "--json", str(TABLE), "--out", str(TABLE)]) == 2
    assert "is an input" in capsys.readouterr().err


def test_the_committed_snippets_are_the_exports_of_the_committed_fit_table(monkeypatch):
    """reports/fit/snippets/ never goes stale: each file is what `fogref export` writes from
    reports/fit/engines.json today (scripts/fit_table.py --from-json rewrites them)."""
    import importlib.util

    from fogref.study.export import export_engine

    spec = importlib.util.spec_from_file_location("fit_table", ROOT / "scripts" / "fit_table.py")
    fit_table = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(fit_table)
    monkeypatch.chdir(ROOT)
    scene = json.loads(TABLE.read_text())["scene"]
    for engine, names in fit_table.SNIPPET_FILES.items():
        files = export_engine(engine, json_path=Path("reports/fit/engines.json"), scene=scene)
        for suffix, name in names.items():
            committed = (ROOT / "reports" / "fit" / "snippets" / name).read_text()
            assert files[suffix] == committed, f"reports/fit/snippets/{name} is stale"


def test_export_reads_fit_and_translate_json(tmp_path, capsys):
    """The JSON of `fogref fit` (Unreal's own) and of `fogref translate` are export's input too."""
    assert main(["fit", "--directions", "16", "--no-start-distance"]) == 0
    fit = tmp_path / "fit.json"
    fit.write_text(capsys.readouterr().out)
    assert main(["export", "--engine", "unreal", "--json", str(fit)]) == 0
    text = capsys.readouterr().out
    ast.parse(text)
    s = json.loads(fit.read_text())["settings"]
    n = float(re.search(rf'\["directional_inscattering_exponent"\], ({NUM})\)', text).group(1))
    assert n == pytest.approx(s["DirectionalInscatteringExponent"], rel=1e-8)
    argv = ["translate", "--from", "unity", "--to", "threejs", "--param", "fogDensity=0.003"]
    assert main([*argv, "--directions", "16"]) == 0
    tr = tmp_path / "translate.json"
    tr.write_text(capsys.readouterr().out)
    assert main(["export", "--engine", "threejs", "--json", str(tr)]) == 0
    text = capsys.readouterr().out
    density = float(re.search(rf"new THREE.FogExp2\(fogColor, ({NUM})\)", text).group(1))
    assert density == pytest.approx(json.loads(tr.read_text())["target"]["settings"]["density"], rel=1e-8)
    assert main(["export", "--engine", "bevy", "--json", str(tr)]) == 2
    assert "translates to 'threejs', not 'bevy'" in capsys.readouterr().err
