"""``fogref scene`` / :func:`fogref.scene.writer.write_scene`: scene XML from fog
(physical or Unreal editor values), sun, sky, camera and a geometry template.

The written scene must be loadable, expose every fog/sun/sky/camera value as a
``$default`` and describe (``fogref.params``) exactly what was asked for: the sun
direction from its angles, and sigma_t/falloff from Unreal values through the exact
mapping of :mod:`fogref.models.ue4`.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from conftest import SCENES
from fogref.cli import main
from fogref.errors import FogrefError, ParameterError
from fogref.media.params import medium_from_params
from fogref.models.ue4 import SecondFogData, UE4FogParams, ue4_to_medium, unreal_to_sigma
from fogref.render.load import describe_scene
from fogref.scene import templates as scene_templates
from fogref.scene.defaults import declared, used_names
from fogref.scene.fog_input import UNREAL_IGNORED, fog_from_unreal
from fogref.scene.sun import sun_direction_from_angles
from fogref.scene.vocabulary import OPTIONAL_GROUPS, VOCABULARY, vocabulary_groups
from fogref.scene.writer import write_scene

UE = {
    "FogDensity": 0.05,
    "FogHeightFalloff": 0.1,
    "FogHeight": 250.0,
    "SecondFogData": {"FogDensity": 0.01, "FogHeightFalloff": 0.4, "FogHeightOffset": 5000.0},
}
EXPOSED = {
    "res",
    "resy",
    "max_depth",
    "sigma_t",
    "albedo",
    "g",
    "density",
    "falloff",
    "fog_height",
    "density2",
    "falloff2",
    "height2",
    "sun_elevation",
    "sun_azimuth",
    "sun_irradiance",
    "sky_radiance",
    "camera_origin",
    "camera_target",
    "fov",
}


def tiny_obj(path):
    """A tetrahedron, z-up in the file: (0,0,0), (10,0,0), (0,0,10), (0,5,0)."""
    path.write_text(
        "# tetrahedron\nv 0 0 0\nv 10 0 0\nv 0 0 10\nv 0 5 0\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
    )
    return path


def structure(path):
    root = ET.parse(path).getroot()
    defaults = {d.get("name"): d.get("value") for d in root.findall("default")}
    refs = {v[1:] for el in root.iter() for v in el.attrib.values() if v.startswith("$")}
    return root, defaults, refs


def assert_fogref_scene(path):
    """fogpath, heightfog in the sensor, box filter, sun by angles; every default used and every $ defined."""
    root, defaults, refs = structure(path)
    assert root.find("integrator").get("type") == "fogpath"
    assert root.find("sensor/medium").get("type") == "heightfog"
    assert root.find("sensor/film/rfilter").get("type") == "box"
    rot = root.findall("emitter[@type='directional']/transform/rotate")
    assert [r.get("angle") for r in rot] == ["$sun_elevation", "$sun_azimuth", "180"]
    assert refs <= set(defaults), refs - set(defaults)
    assert set(defaults) <= refs, set(defaults) - refs
    return defaults


# --------------------------------------------------------------------------- physical input


def test_physical_rgb_fog_plane(tmp_path):
    fog = {
        "sigma_t": [0.001, 0.002, 0.003],
        "falloff": 0.02,
        "height": 5.0,
        "density2": 0.3,
        "falloff2": 0.001,
        "height2": 300.0,
    }
    out = tmp_path / "phys.xml"
    r = write_scene(
        out,
        fog=fog,
        albedo=[0.8, 0.85, 0.9],
        g=0.3,
        sun_elevation=20,
        sun_azimuth=-45,
        sun_irradiance=2.0,
        sky_radiance=[0.1, 0.2, 0.4],
        camera_origin=(1, 3, 2),
        camera_target=(1, 3, 50),
        fov=60,
        res=64,
        resy=32,
    )
    assert r.path == out and r.notes == []
    defaults = assert_fogref_scene(out)
    assert EXPOSED | {"reflectance"} == set(defaults)
    assert defaults["sigma_t"] == "0.001, 0.002, 0.003" and defaults["sun_irradiance"] == "2.0, 2.0, 2.0"
    d = describe_scene(out)
    m = d["medium"]
    assert m["sigma_t"] == fog["sigma_t"] and m["albedo"] == [0.8, 0.85, 0.9] and m["g"] == 0.3
    assert (m["falloff"], m["height"], m["density2"], m["falloff2"], m["height2"]) == (
        0.02,
        5.0,
        0.3,
        0.001,
        300.0,
    )
    np.testing.assert_allclose(d["sun"]["direction"], sun_direction_from_angles(20, -45), rtol=0, atol=1e-12)
    assert d["sun"]["irradiance"] == [2.0, 2.0, 2.0] and d["sky"]["radiance"] == [0.1, 0.2, 0.4]
    root = ET.parse(out).getroot()
    assert {s.get("type") for s in root.findall("shape")} == {"rectangle"}  # the ground's tiles


def test_set_changes_every_exposed_value(tmp_path):
    out = tmp_path / "s.xml"
    write_scene(out)
    d = describe_scene(
        out,
        {
            "sun_elevation": "33",
            "sun_azimuth": "120",
            "sigma_t": "0.004",
            "falloff": "0.5",
            "fog_height": "7",
            "sky_radiance": "1, 1, 1",
            "sun_irradiance": "5, 5, 5",
        },
    )
    np.testing.assert_allclose(d["sun"]["direction"], sun_direction_from_angles(33, 120), atol=1e-12)
    assert (d["medium"]["sigma_t"], d["medium"]["falloff"], d["medium"]["height"]) == (0.004, 0.5, 7.0)
    assert d["sky"]["radiance"] == [1.0, 1.0, 1.0] and d["sun"]["irradiance"] == [5.0, 5.0, 5.0]


def test_bounded_fog_and_no_sky(tmp_path):
    out = tmp_path / "box.xml"
    write_scene(
        out,
        fog={"sigma_t": 0.01, "falloff": 0.0, "bounds_min": [-50, 0, 10], "bounds_max": [50, 20, 200]},
        sky_radiance=None,
    )
    d = describe_scene(out)
    assert d["sky"] is None and d["medium"]["bounds_min"] == [-50.0, 0.0, 10.0]
    med = medium_from_params(d["medium"])
    assert med.bounds is not None and med.bounds.hi == (50.0, 20.0, 200.0)
    assert ET.parse(out).getroot().find("emitter[@type='constant']") is None


# --------------------------------------------------------------------------- Unreal input


def test_unreal_values_map_exactly():
    fog, notes = fog_from_unreal(UE, albedo=0.7, g=0.2)
    assert notes == []
    a, b = unreal_to_sigma(UE["FogDensity"], UE["FogHeightFalloff"])
    a2, b2 = unreal_to_sigma(UE["SecondFogData"]["FogDensity"], UE["SecondFogData"]["FogHeightFalloff"])
    assert fog["sigma_t"] == a and fog["falloff"] == b and fog["fog_height"] == 2.5
    assert (
        fog["density2"] * a == pytest.approx(a2, rel=1e-15)
        and fog["falloff2"] == b2
        and fog["height2"] == 52.5
    )
    ref = ue4_to_medium(
        UE4FogParams(
            FogDensity=0.05,
            FogHeightFalloff=0.1,
            FogHeight=250.0,
            SecondFogData=SecondFogData(0.01, 0.4, 5000.0),
        ),
        albedo=0.7,
        g=0.2,
    )
    params = {("height" if k == "fog_height" else k): v for k, v in fog.items()}
    got = medium_from_params(params)
    assert (
        got.sigma_t == ref.sigma_t
        and got.layers == ref.layers
        and got.albedo == ref.albedo
        and got.g == ref.g
    )


def test_unreal_defaults_are_the_valley_fog():
    fog, _ = fog_from_unreal({})
    valley = describe_scene(SCENES / "valley.xml")["medium"]
    assert fog["sigma_t"] == pytest.approx(valley["sigma_t"], rel=1e-5)  # the file keeps 6 digits
    assert fog["falloff"] == pytest.approx(valley["falloff"], rel=1e-5)


def test_unreal_without_physical_counterpart_is_noted(tmp_path, capsys):
    out = tmp_path / "ue.xml"
    args = [
        "scene",
        "--out",
        str(out),
        "--ue-fog-density",
        "0.03",
        "--ue-fog-inscattering-color",
        "0.4,0.5,0.6",
        "--ue-directional-inscattering-exponent",
        "8",
        "--ue-fog-max-opacity",
        "0.9",
        "--ue-start-distance",
        "100",
    ]
    assert main(args) == 0
    err = capsys.readouterr().err
    for key in ("FogInscatteringColor", "DirectionalInscatteringExponent", "FogMaxOpacity", "StartDistance"):
        assert f"note: Unreal {key} = " in err and "is ignored" in err, key
    assert "no albedo or phase function" in err
    text = out.read_text()
    assert "FogInscatteringColor = 0.4, 0.5, 0.6 is ignored" in text  # recorded in the scene too
    assert float(structure(out)[1]["sigma_t"]) == unreal_to_sigma(0.03, 0.2)[0]
    # the Python API warns about ignored values when nobody listens to the notes
    with pytest.warns(UserWarning, match="DirectionalInscatteringExponent"):
        write_scene(tmp_path / "w.xml", unreal={"DirectionalInscatteringExponent": 4.0})
    assert set(UNREAL_IGNORED) >= {"FogInscatteringColor", "DirectionalInscatteringExponent"}


# --------------------------------------------------------------------------- geometry


def _geometry_text(root):
    """The BSDFs and shapes of a scene as canonical XML text."""
    return [ET.canonicalize(ET.tostring(el), strip_text=True) for el in root if el.tag in ("bsdf", "shape")]


def test_valley_template_reads_the_shipped_valley(tmp_path, monkeypatch):
    """The template copies scenes/valley.xml's geometry (no second copy to keep in sync);
    ``ground_size`` changes only the ground's scale."""
    out = tmp_path / "v.xml"
    write_scene(out, geometry="valley")
    assert_fogref_scene(out)
    shipped = ET.parse(SCENES / "valley.xml").getroot()
    assert _geometry_text(ET.parse(out).getroot()) == _geometry_text(shipped)
    write_scene(out, geometry="valley", ground_size=500, overwrite=True)
    assert ET.parse(out).getroot().find("shape[@id='ground']/transform/scale").get("value") == "500.0"
    # a changed valley.xml changes the template
    other = tmp_path / "valley.xml"
    text = (SCENES / "valley.xml").read_text()
    other.write_text(text.replace('x="15" y="0" z="90"', 'x="16" y="0" z="90"'))
    monkeypatch.setattr(scene_templates, "VALLEY_SCENE", other)
    write_scene(out, geometry="valley", overwrite=True)
    assert ET.parse(out).getroot().find("shape[@type='sphere']/point").get("x") == "16"


# --------------------------------------------------------------------------- one vocabulary


def _written_scenes(tmp_path):
    mesh = tiny_obj(tmp_path / "m.obj")
    kinds = {
        "plane": {},
        "valley": {"geometry": "valley"},
        "no_sky": {"sky_radiance": None},
        "bounds": {"fog": {"bounds_min": [-1, 0, -1], "bounds_max": [1, 1, 1]}},
        "unreal": {"unreal": UE},
        "mesh": {"geometry": str(mesh)},
    }
    for name, kw in kinds.items():
        out = tmp_path / f"{name}.xml"
        write_scene(out, on_note=lambda n: None, **kw)
        yield out


def test_every_scene_speaks_one_vocabulary(tmp_path):
    """Every shipped scene and every written scene declares the same $default names:
    :data:`VOCABULARY` exactly, plus only whole optional groups (a second fog layer,
    fog bounds, a sky, a settable surface reflectance) where the concept applies.
    Every declared name is used and every used name declared."""
    scenes = sorted(SCENES.glob("*.xml")) + list(_written_scenes(tmp_path))
    assert len(scenes) >= 10
    for path in scenes:
        names = set(declared(path))
        wrong, groups = vocabulary_groups(names)
        assert wrong == [], f"{path.name}: {wrong}"
        assert names == set(VOCABULARY).union(*(OPTIONAL_GROUPS[g] for g in groups)), path.name
        assert names == used_names(path), f"{path.name}: {names ^ used_names(path)}"
    shipped = {p.name: vocabulary_groups(declared(p))[1] for p in SCENES.glob("*.xml")}
    assert all("sky" in g for g in shipped.values()), shipped
    assert "second_layer" in shipped["two_layer_sun.xml"]


def test_obj_mesh_template(tmp_path):
    (tmp_path / "meshes").mkdir()
    mesh = tiny_obj(tmp_path / "meshes" / "tet.obj")
    out = tmp_path / "scene" / "m.xml"
    assert (
        main(
            [
                "scene",
                "--out",
                str(out),
                "--geometry",
                str(mesh),
                "--mesh-up",
                "z",
                "--mesh-scale",
                "2",
                "--mesh-translate",
                "1,0,0",
                "--ground",
            ]
        )
        == 0
    )
    assert_fogref_scene(out)
    root = ET.parse(out).getroot()
    shape = root.find("shape[@type='obj']")
    assert shape.find("string[@name='filename']").get("value") == "../meshes/tet.obj"  # relative to the scene
    ops = [(op.tag, dict(op.attrib)) for op in shape.find("transform")]
    assert ops == [
        ("scale", {"value": "2.0"}),
        ("rotate", {"x": "1", "angle": "-90"}),
        ("translate", {"x": "1.0", "y": "0.0", "z": "0.0"}),
    ]
    assert root.find("shape[@type='rectangle']") is not None  # --ground
    write_scene(tmp_path / "ue_mesh.xml", geometry=mesh, mesh_up="unreal", mesh_scale=0.01)
    tw = ET.parse(tmp_path / "ue_mesh.xml").getroot().find("shape[@type='obj']/transform")
    M = np.array([float(x) for x in tw.find("matrix").get("value").split()]).reshape(4, 4)
    np.testing.assert_array_equal(
        M[:3, :3] @ [100.0, 200.0, 300.0], [100.0, 300.0, 200.0]
    )  # Unreal (X,Y,Z) -> (X,Z,Y)
    # a mesh alone: no ground unless asked
    write_scene(tmp_path / "alone.xml", geometry=mesh)
    assert ET.parse(tmp_path / "alone.xml").getroot().find("shape[@type='rectangle']") is None


def test_ply_is_a_ply_shape(tmp_path):
    mesh = tmp_path / "t.PLY"
    mesh.write_text(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
    )
    write_scene(tmp_path / "p.xml", geometry=mesh)
    assert ET.parse(tmp_path / "p.xml").getroot().find("shape[@type='ply']") is not None


@pytest.mark.render
def test_written_mesh_scene_loads_with_the_mesh_in_place(tmp_path, mitsuba):
    mi = mitsuba
    from fogref.render.load import load_scene

    mesh = tiny_obj(tmp_path / "tet.obj")
    out = tmp_path / "m.xml"
    write_scene(
        out, geometry=mesh, mesh_up="z", mesh_scale=2.0, camera_origin=(0, 3, -20), camera_target=(0, 3, 0)
    )
    scene, desc = load_scene(out, {"res": 16, "resy": 9})
    objs = [s for s in scene.shapes() if s.is_mesh()]
    assert len(objs) == 1
    bb = objs[0].bbox()
    # z-up file scaled by 2 and rotated into y-up: (x, y, z) -> 2 (x, z, -y)
    np.testing.assert_allclose([list(bb.min), list(bb.max)], [[0, 0, -10], [20, 20, 0]], atol=1e-5)
    write_scene(out, geometry=mesh, mesh_up="unreal", mesh_scale=2.0, overwrite=True)  # swap: 2 (x, z, y)
    bb = [s for s in load_scene(out, {"res": 16, "resy": 9})[0].shapes() if s.is_mesh()][0].bbox()
    np.testing.assert_allclose([list(bb.min), list(bb.max)], [[0, 0, 0], [20, 20, 10]], atol=1e-5)
    assert isinstance(scene, mi.Scene) and desc["camera"]["origin"] == pytest.approx([0, 3, -20])


# --------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    "args, words",
    [
        (["--sigma-t", "-0.01"], ["sigma_t (--sigma-t)", "outside [0, 100] 1/m"]),
        (["--ue-fog-density", "-1"], ["FogDensity (--ue-fog-density)", "outside [0, "]),
        (
            ["--ue-second-fog-density", "-0.5"],
            ["SecondFogData.FogDensity (--ue-second-fog-density)", "outside [0, "],
        ),
        (["--sun-elevation", "95"], ["sun_elevation (--sun-elevation)", "outside [-90, 90] deg"]),
        (["--sun-elevation", "-90.5"], ["--sun-elevation", "[-90, 90]"]),
        (["--geometry", "{tmp}/missing.obj"], ["--geometry", "mesh file", "not found"]),
        (["--geometry", "hills"], ["unknown template 'hills'", "plane, valley or a mesh file (.obj, .ply)"]),
        (["--geometry", "{tmp}/level.fbx"], ["--geometry", ".obj, .ply files only", "'.fbx'"]),
        (["--albedo", "1.5"], ["albedo (--albedo)", "outside [0, 1]"]),
        (["--g", "1"], ["g (--g)", "[-0.999, 0.999]"]),
        (["--sun-irradiance", "1,2"], ["--sun-irradiance", "expected 1 or 3 numbers"]),
        (["--sky-radiance", "-1"], ["--sky-radiance", "outside [0, inf)"]),
        (["--camera-target", "0,2,0"], ["--camera-target", "must differ from camera_origin"]),
        (["--camera-target", "0,10,0"], ["--camera-target", "looks straight up"]),
        (["--fov", "180"], ["fov (--fov)", "(0, 180) deg"]),
        (["--res", "0"], ["res (--res)", "[1, 65536] pixels"]),
        (["--mesh-scale", "2"], ["--mesh-scale", "applies to a mesh file"]),
        (["--mesh-up", "z"], ["--mesh-up", "applies to a mesh file"]),
        (["--bounds-min", "0,0,0"], ["bounds_max (--bounds-max)", "both bounds or none"]),
        (["--sigma-t", "0.01", "--ue-fog-density", "0.02"], ["not both", "--sigma-t", "--ue-fog-density"]),
        (["--bounds-min", "0,0,0", "--bounds-max", "1,1,1", "--ue-fog-density", "0.02"], ["not both"]),
    ],
)
def test_bad_input_is_a_clear_error(tmp_path, capsys, args, words):
    (tmp_path / "level.fbx").write_text("not a mesh")
    out = tmp_path / "bad.xml"
    argv = ["scene", "--out", str(out)] + [a.replace("{tmp}", str(tmp_path)) for a in args]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("fogref: error: fogref scene") and err.count("\n") == 1, err
    for w in words:
        assert w in err, (w, err)
    assert not out.exists()


def test_output_is_not_overwritten_without_force(tmp_path, capsys):
    out = tmp_path / "s.xml"
    assert main(["scene", "--out", str(out)]) == 0
    first = out.read_text()
    assert main(["scene", "--out", str(out), "--sun-elevation", "40"]) == 2
    assert "exists; pass --force" in capsys.readouterr().err and out.read_text() == first
    assert main(["scene", "--out", str(out), "--sun-elevation", "40", "--force"]) == 0
    assert structure(out)[1]["sun_elevation"] == "40.0"
    assert main(["scene", "--out", str(tmp_path / "s.txt")]) == 2
    assert "must end in .xml" in capsys.readouterr().err


def test_python_api_errors():
    with pytest.raises(ParameterError, match=r"'FogDensty'.*did you mean 'FogDensity'"):
        fog_from_unreal({"FogDensty": 0.02})
    with pytest.raises(FogrefError, match="not both"):
        write_scene("x.xml", fog={"sigma_t": 0.01}, unreal={"FogDensity": 0.02})
    with pytest.raises(ParameterError, match=r"mesh_up \(--mesh-up\).*'x' is not one of y, z"):
        write_scene("x.xml", geometry="plane", mesh_up="x")


# --------------------------------------------------------------------------- render round trip


@pytest.mark.render
def test_render_round_trip_reproduces_the_input(tmp_path, mitsuba):
    """Write from Unreal values + sun angles, render 16x9 at 4 spp, read fogref.params back."""
    from fogref.exrio import read_exr
    from fogref.render.render import render

    scene = tmp_path / "ue.xml"
    write_scene(
        scene,
        unreal=UE,
        albedo=0.8,
        g=0.5,
        sun_elevation=17.5,
        sun_azimuth=-62.0,
        sun_irradiance=(3.0, 2.5, 2.0),
        sky_radiance=(0.2, 0.3, 0.5),
        camera_origin=(0, 2, 0),
        camera_target=(0.2, 2.1, 1.0),
        fov=80,
        res=16,
        resy=9,
        on_note=lambda n: None,
    )
    exr = render(scene, tmp_path / "ue.exr", spp=4, seed=1, progress=False, png=False)
    channels, attrs = read_exr(exr)
    assert channels["R"].shape == (9, 16) and all(np.isfinite(v).all() for v in channels.values())
    p = attrs["fogref.params"]
    np.testing.assert_allclose(
        p["sun"]["direction"], sun_direction_from_angles(17.5, -62.0), rtol=0, atol=1e-6
    )
    a, b = unreal_to_sigma(UE["FogDensity"], UE["FogHeightFalloff"])
    a2, b2 = unreal_to_sigma(UE["SecondFogData"]["FogDensity"], UE["SecondFogData"]["FogHeightFalloff"])
    m = p["medium"]
    assert m["sigma_t"] == pytest.approx(a, rel=1e-6) and m["falloff"] == pytest.approx(b, rel=1e-6)
    assert m["height"] == pytest.approx(2.5, abs=1e-9) and m["height2"] == pytest.approx(52.5, abs=1e-9)
    assert m["sigma_t"] * m["density2"] == pytest.approx(a2, rel=1e-6) and m["falloff2"] == pytest.approx(
        b2, rel=1e-6
    )
    assert (m["albedo"], m["g"]) == (0.8, 0.5)
    assert p["sun"]["irradiance"] == [3.0, 2.5, 2.0] and p["sky"]["radiance"] == [0.2, 0.3, 0.5]
    assert p["camera"]["origin"] == pytest.approx([0.0, 2.0, 0.0], abs=1e-6)
    assert math.isclose(float(structure(scene)[1]["fov"]), 80.0)


# --------------------------------------------------------------------------- the docs


def test_docs_examples_run(tmp_path, capsys):
    """docs/byo.md's "Your own scene" commands and Python example work as printed."""
    import shlex

    from conftest import ROOT

    text = (ROOT / "docs" / "byo.md").read_text().split("## 7. Your own scene", 1)[1]
    tiny_obj(tmp_path / "level.obj")

    def local(s: str) -> str:
        return s.replace("scenes/", f"{tmp_path}/").replace("level.obj", str(tmp_path / "level.obj"))

    commands = [c for c in text.replace("\\\n", " ").splitlines() if c.startswith(".venv/bin/fogref scene")]
    assert len(commands) == 2
    for c in commands:
        assert main(shlex.split(local(c))[1:]) == 0, capsys.readouterr().err
    assert "Unreal has no albedo" in capsys.readouterr().err
    code = text.split("```python\n", 1)[1].split("```", 1)[0]
    exec(local(code.replace('"scenes/mine.xml"', '"scenes/mine2.xml"')), {})
    assert describe_scene(tmp_path / "mine2.xml")["medium"] == describe_scene(tmp_path / "mine.xml")["medium"]
