"""Every scene door refuses bad input in one line, through ``fogref.cli.main`` and the Python API.

The doors: ``fogref render --set`` (and ``render(overrides=...)``), a scene's own ``$default``
values, ``fogref scene`` (and :func:`~fogref.scene.writer.write_scene`) with its
``--ue-*`` values, the scene loaded for rendering (one sensor, one heightfog) and the
Mitsuba variant.  Also: a mesh without normals is shaded flat, the ground's and the mesh's
reflectance are options, and ``fogref scene --out`` never replaces one of its inputs.
Renders are tiny (8x6, 1 spp).
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from conftest import SCENES
from fogref.cli import main
from fogref.errors import FogrefError

VALLEY = SCENES / "valley.xml"


def tiny(skip: str = "") -> list:
    """A tiny render's options (8x6, 1 spp), without the ``--set`` of ``skip`` (a case that sets it)."""
    sets = [a for x in ("res=8", "resy=6") if not x.startswith(f"{skip}=") for a in ("--set", x)]
    return ["--spp", "1", *sets, "--quiet", "--no-png"]


TINY = tiny()


def cli(capsys, argv) -> tuple[int, str]:
    """Run ``fogref argv``; the exit code and stderr, checked to be at most one line, no traceback."""
    rc = main([str(a) for a in argv])
    err = capsys.readouterr().err
    if rc != 0:
        assert err.startswith("fogref: error: ") and err.count("\n") == 1, err
        assert "Traceback" not in err and 'File "' not in err, err
    return rc, err


def api_error(call, *args, **kw) -> str:
    """The one-line message of the FogrefError ``call`` raises."""
    with pytest.raises(FogrefError) as e:
        call(*args, **kw)
    msg = str(e.value)
    assert "\n" not in msg and "Traceback" not in msg, msg
    return msg


def render_api(scene, out, **kw):
    from fogref.render.render import render

    return render(scene, out, spp=1, progress=False, png=False, **kw)


# --------------------------------------------------------------------------- --set and defaults

#: (vocabulary name, a value out of range, text of the allowed range): accepted (or Mitsuba's
#: traceback) before the vocabulary had ranges
SET_CASES = [
    ("sun_elevation", "1000", "[-90, 90] deg"),
    ("sun_azimuth", "1000", "[-360, 360] deg"),
    ("max_depth", "0", "{-1} U [1, 2147483647]"),
    ("max_depth", "-5", "{-1} U [1, 2147483647]"),
    ("fov", "180", "(0, 180) deg"),
    ("sun_irradiance", "-1", "[0, inf)"),
    ("sky_radiance", "0.2, -0.3, 0.5", "[0, inf)"),
    ("sigma_t", "-1", "[0, 100] 1/m"),
    ("camera_origin", "0, 2", "expected 3 numbers"),
    ("camera_target", "0, 9, 0", "looks straight up"),
]
#: refused before too (res by the old --set check, albedo and g by the medium parser): kept as regressions
SET_KEPT = [
    ("res", "0", "[1, 65536] pixels"),
    ("resy", "2.5", "[1, 65536] pixels"),
    ("albedo", "1.5", "[0, 1]"),
    ("g", "1", "[-0.999, 0.999]"),
]


@pytest.mark.parametrize("name, value, allowed", SET_CASES + SET_KEPT)
def test_set_out_of_range_is_refused(tmp_path, capsys, name, value, allowed):
    out = tmp_path / "x.exr"
    rc, err = cli(capsys, ["render", VALLEY, "--out", out, *tiny(name), "--set", f"{name}={value}"])
    assert rc == 2 and f"'{name}'" in err and allowed in err and str(VALLEY) in err, err
    msg = api_error(render_api, VALLEY, out, overrides={"res": 8, "resy": 6, name: value})
    assert f"'{name}'" in msg and allowed in msg, msg
    assert not out.exists()


def test_max_depth_zero_is_not_mitsubas_traceback(tmp_path, capsys):
    rc, err = cli(capsys, ["render", VALLEY, "--out", tmp_path / "x.exr", *TINY, "--set", "max_depth=0"])
    assert rc == 2 and "Mitsuba could not load" not in err and "-1: no limit" in err, err


def _valley_with(tmp_path, name: str, edit) -> str:
    text = edit(VALLEY.read_text())
    p = tmp_path / name
    p.write_text(text)
    return p


@pytest.mark.render
def test_a_scenes_own_default_out_of_range_is_refused(tmp_path, capsys):
    bad = _valley_with(
        tmp_path,
        "bad_sun.xml",
        lambda t: re.sub(r'(<default name="sun_elevation" value=")[^"]*"', r'\g<1>1000"', t),
    )
    rc, err = cli(capsys, ["render", bad, "--out", tmp_path / "x.exr", *TINY])
    assert rc == 2 and "bad_sun.xml: <default>" in err and "[-90, 90] deg" in err, err
    from fogref.render.load import describe_scene

    assert "[-90, 90] deg" in api_error(describe_scene, bad)
    assert "[-90, 90] deg" in api_error(render_api, bad, tmp_path / "x.exr", overrides={"res": 8, "resy": 6})
    # --set can bring it back into range
    fixed = ["render", bad, "--out", tmp_path / "x.exr", *TINY, "--set", "sun_elevation=8"]
    assert cli(capsys, fixed)[0] == 0


#: (write_scene keyword, fogref scene option, vocabulary name, value, allowed): both doors, one range
AGREE = [
    ("sun_elevation", "--sun-elevation", "sun_elevation", "95", "[-90, 90] deg"),
    ("sun_azimuth", "--sun-azimuth", "sun_azimuth", "400", "[-360, 360] deg"),
    ("fov", "--fov", "fov", "0", "(0, 180) deg"),
    ("res", "--res", "res", "70000", "[1, 65536] pixels"),
    ("max_depth", "--max-depth", "max_depth", "0", "{-1} U [1, 2147483647]"),
    ("sky_radiance", "--sky-radiance", "sky_radiance", "-1", "[0, inf)"),
    ("albedo", "--albedo", "albedo", "1.5", "[0, 1]"),
    ("g", "--g", "g", "-1", "[-0.999, 0.999]"),
]


@pytest.mark.parametrize("kw, option, name, value, allowed", AGREE)
def test_writer_and_set_agree_on_ranges(tmp_path, capsys, kw, option, name, value, allowed):
    from fogref.scene.writer import write_scene

    rc, err = cli(capsys, ["scene", "--out", tmp_path / "w.xml", f"{option}={value}"])
    assert rc == 2 and allowed in err, err
    assert allowed in api_error(write_scene, tmp_path / "w.xml", **{kw: value})
    out = tmp_path / "x.exr"
    rc, err = cli(capsys, ["render", VALLEY, "--out", out, *tiny(name), "--set", f"{name}={value}"])
    assert rc == 2 and allowed in err, err
    assert not (tmp_path / "w.xml").exists()


LITERAL = (
    '<scene version="3.0.0"><integrator type="fogpath">{integ}</integrator>'
    '<sensor type="perspective"><float name="fov" value="{fov}"/><film type="hdrfilm">'
    '<integer name="width" value="8"/><integer name="height" value="6"/></film>'
    '<medium type="heightfog" name="medium"><float name="sigma_t" value="0.01"/></medium></sensor>'
    '<shape type="sphere"/></scene>'
)


@pytest.mark.parametrize(
    "integ, fov, words",
    [
        ('<integer name="max_depth" value="0"/>', "70", ["'integrator.max_depth'", "{-1} U [1, 2147483647]"]),
        ('<integer name="max_depth" value="4"/>', "190", ["'sensor.fov'", "(0, 180) deg"]),
        ('<integer name="rr_depth" value="-3"/>', "70", ["Mitsuba could not load", "fogpath", "'rr_depth'"]),
        (
            '<integer name="sun_sampling_rays" value="0"/>',
            "70",
            ["fogpath", "'sun_sampling_rays'", "{-1} U [1, 2147483647]"],
        ),
        ('<string name="sky_at_surfaces" value="cos"/>', "70", ["fogpath", "'sky_at_surfaces'", "mis, bsdf"]),
        ('<integer name="sun_samples" value="4"/>', "70", ["fogpath", "unreferenced", "sun_samples"]),
        ('<string name="sky_cv" value="all"/>', "70", ["fogpath", "unreferenced", "sky_cv"]),
    ],
)
def test_values_written_in_the_xml_are_one_line_errors(tmp_path, capsys, integ, fov, words):
    scene = tmp_path / "literal.xml"
    scene.write_text(LITERAL.format(integ=integ, fov=fov))
    rc, err = cli(capsys, ["render", scene, "--out", tmp_path / "x.exr", "--spp", "1", "--quiet", "--no-png"])
    assert rc == 2 and all(w in err for w in words), err
    msg = api_error(render_api, scene, tmp_path / "x.exr")
    assert all(w in msg for w in words), msg


SKY = 'name="radiance" value="$sky_radiance"'


@pytest.mark.parametrize(
    "old, new, words",
    [
        (SKY, 'name="radiance" value="abc"', ["'sky.radiance'", "'abc'"]),
        (SKY, 'name="radiance" value="0.2, nan, 0.5"', ["sky.radiance", "finite"]),  # refused before too
        (
            '<rotate x="1" angle="$sun_elevation"/>',
            '<rotate x="1" angle="$sun_elev"/>',
            ["<rotate>", "'$sun_elev'"],
        ),
    ],
)
def test_text_in_xml_values_is_a_one_line_error(tmp_path, capsys, old, new, words):
    scene = _valley_with(tmp_path, "text.xml", lambda t: t.replace(old, new))
    rc, err = cli(capsys, ["render", scene, "--out", tmp_path / "x.exr", *TINY])
    assert rc == 2 and "text.xml" in err and all(w in err for w in words), err
    msg = api_error(render_api, scene, tmp_path / "x.exr", overrides={"res": 8, "resy": 6})
    assert all(w in msg for w in words), msg


# --------------------------------------------------------------------------- --ue-* values

UE = [
    ("FogMaxOpacity", "--ue-fog-max-opacity", "5", "[0, 1]"),
    ("FogMaxOpacity", "--ue-fog-max-opacity", "-0.1", "[0, 1]"),
    ("DirectionalInscatteringExponent", "--ue-directional-inscattering-exponent", "-5", "[0, inf)"),
    ("FogInscatteringColor", "--ue-fog-inscattering-color", "-1,0,0", "[0, inf)"),
    ("DirectionalInscatteringColor", "--ue-directional-inscattering-color", "0,-1,0", "[0, inf)"),
    ("StartDistance", "--ue-start-distance", "-1", "[0, inf) cm"),
    (
        "DirectionalInscatteringStartDistance",
        "--ue-directional-inscattering-start-distance",
        "-1",
        "[0, inf) cm",
    ),
    ("FogCutoffDistance", "--ue-fog-cutoff-distance", "-1", "[0, inf) cm"),
    ("EndDistance", "--ue-end-distance", "-1", "[0, inf) cm"),
    ("FogHeight", "--ue-fog-height", "1e400", "finite"),  # refused before too: a regression
]


@pytest.mark.parametrize("key, option, value, allowed", UE)
def test_unreal_values_are_range_checked(tmp_path, capsys, key, option, value, allowed):
    from fogref.scene.writer import write_scene

    rc, err = cli(capsys, ["scene", "--out", tmp_path / "u.xml", f"{option}={value}"])
    assert rc == 2 and allowed in err and option in err, err
    v = [float(x) for x in value.split(",")]
    msg = api_error(write_scene, tmp_path / "u.xml", unreal={key: v[0] if len(v) == 1 else v})
    assert allowed in msg and key in msg, msg
    assert not (tmp_path / "u.xml").exists()


@pytest.mark.parametrize(
    "kw, words",
    [
        ({"out": 123}, ["'out (--out)'", "expected a path"]),
        ({"fog": "abc"}, ["'fog'", "expected a dict"]),
        ({"res": 16.7}, ["'res (--res)'", "not an integer"]),  # refused before too
        ({"mesh_up": 5}, ["'mesh_up (--mesh-up)'", "y, z, unreal"]),  # refused before too
    ],
)
def test_write_scene_api_arguments_are_checked(tmp_path, kw, words):
    from fogref.scene.writer import write_scene

    msg = api_error(write_scene, **{"out": tmp_path / "w.xml", **kw})
    assert all(w in msg for w in words), msg


def test_scene_api_arguments_are_checked(tmp_path):
    from fogref.render.load import describe_scene, load_scene

    assert "expected a path" in api_error(describe_scene, 123)
    assert "expected a dict" in api_error(load_scene, VALLEY, "res=8")
    assert "expected an integer" in api_error(describe_scene, VALLEY, {"res": [8]})


# --------------------------------------------------------------------------- what a truth needs


def _no_fog(t: str) -> str:
    return re.sub(r"<medium type=\"heightfog\".*?</medium>", "", t, flags=re.S)


def _two_sensors(t: str) -> str:
    sensor = re.search(r"<sensor .*?</sensor>", t, flags=re.S).group(0)
    return t.replace(sensor, sensor + "\n" + sensor)


@pytest.mark.parametrize(
    "edit, words",
    [(_no_fog, ["no fog", "heightfog", "<sensor>"]), (_two_sensors, ["2 <sensor> elements", "exactly one"])],
)
def test_scene_without_fog_or_with_two_sensors_is_refused(tmp_path, capsys, edit, words):
    scene = _valley_with(tmp_path, "odd.xml", edit)
    out = tmp_path / "x.exr"
    rc, err = cli(capsys, ["render", scene, "--out", out, *TINY])
    assert rc == 2 and "odd.xml" in err and all(w in err for w in words), err
    msg = api_error(render_api, scene, out, overrides={"res": 8, "resy": 6})
    assert "odd.xml" in msg and all(w in msg for w in words), msg
    assert not out.exists()


# --------------------------------------------------------------------------- variants


def test_variant_outside_the_list_is_refused_by_the_api(tmp_path, capsys):
    import fogref

    rc, err = cli(capsys, ["render", VALLEY, "--out", tmp_path / "x.exr", *TINY, "--variant", "scalar_rgb"])
    assert rc == 2 and "llvm_ad_rgb, cuda_ad_rgb" in err
    assert "llvm_ad_rgb, cuda_ad_rgb" in api_error(fogref.set_variant, "scalar_rgb")
    msg = api_error(render_api, VALLEY, tmp_path / "x.exr", variant="scalar_rgb")
    assert "llvm_ad_rgb, cuda_ad_rgb" in msg
    assert not (tmp_path / "x.exr").exists()


def test_cuda_variant_without_cuda_is_one_plain_line(tmp_path, capsys):
    import drjit as dr

    if dr.has_backend(dr.JitBackend.CUDA):
        pytest.skip("this machine has CUDA")
    import fogref

    line = "cuda_ad_rgb needs an NVIDIA GPU with CUDA; none found here: use llvm_ad_rgb"
    rc, err = cli(capsys, ["render", VALLEY, "--out", tmp_path / "x.exr", *TINY, "--variant", "cuda_ad_rgb"])
    assert rc == 2 and err == f"fogref: error: {line}\n", err
    assert api_error(fogref.set_variant, "cuda_ad_rgb") == line
    assert api_error(render_api, VALLEY, tmp_path / "x.exr", variant="cuda_ad_rgb") == line


# --------------------------------------------------------------------------- meshes


def _box_obj(path, normals: bool = False):
    """A 2 m box centred at the origin, 12 triangles sharing 8 corners (with ``normals``: vn per face)."""
    corners = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    index = {c: i + 1 for i, c in enumerate(corners)}
    quads = [
        ((-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)),
        ((1, -1, -1), (-1, -1, -1), (-1, 1, -1), (1, 1, -1)),
        ((1, -1, 1), (1, -1, -1), (1, 1, -1), (1, 1, 1)),
        ((-1, -1, -1), (-1, -1, 1), (-1, 1, 1), (-1, 1, -1)),
        ((-1, 1, 1), (1, 1, 1), (1, 1, -1), (-1, 1, -1)),
        ((-1, -1, -1), (1, -1, -1), (1, -1, 1), (-1, -1, 1)),
    ]
    lines = [f"v {x} {y} {z}" for x, y, z in corners]
    for k, q in enumerate(quads):
        a, b, c, d = (index[p] for p in q)
        if normals:
            n = np.cross(np.subtract(q[1], q[0]), np.subtract(q[2], q[0]))
            lines.append("vn " + " ".join(str(x) for x in n / np.linalg.norm(n)))
            a, b, c, d = (f"{i}//{k + 1}" for i in (a, b, c, d))
        lines += [f"f {a} {b} {c}", f"f {a} {c} {d}"]
    path.write_text("\n".join(lines) + "\n")
    return path


#: one face (+z) filling the image, lit by a delta sun, no fog, no sky
BOX_VIEW = {
    "sigma_t": "0",
    "sky_radiance": "none",
    "camera_origin": "0.3,0.4,6",
    "camera_target": "0,0,0",
    "fov": "20",
    "res": "8",
    "resy": "6",
    "sun_elevation": "30",
    "sun_azimuth": "20",
}


def _face_spread(exr) -> float:
    from fogref.gbuffer import load_truth

    t = load_truth(exr)
    assert t.hit.all()
    s = t.surface[..., 0]
    return float(s.max() - s.min()) / float(s.mean())


def _face_normals(xml) -> list:
    booleans = ET.parse(xml).getroot().iter("boolean")
    return [b.get("value") for b in booleans if b.get("name") == "face_normals"]


@pytest.mark.render
def test_mesh_without_normals_renders_flat_faces_cli(tmp_path, capsys):
    box = _box_obj(tmp_path / "box.obj")
    scene = tmp_path / "box.xml"
    opts = [x for k, v in BOX_VIEW.items() for x in (f"--{k.replace('_', '-')}", v)]
    rc, err = cli(capsys, ["scene", "--out", scene, "--geometry", box, *opts])
    assert rc == 0 and "face normals" in err, err
    assert _face_normals(scene) == ["true"]
    rc, _ = cli(capsys, ["render", scene, "--out", tmp_path / "b.exr", "--spp", "1", "--quiet", "--no-png"])
    assert rc == 0 and _face_spread(tmp_path / "b.exr") < 1e-6


@pytest.mark.render
def test_mesh_without_normals_renders_flat_faces_api(tmp_path):
    from fogref.scene.writer import write_scene

    box = _box_obj(tmp_path / "box.obj")
    kw = {k: v for k, v in BOX_VIEW.items() if k != "sigma_t"}
    kw["sky_radiance"] = None
    r = write_scene(tmp_path / "box.xml", fog={"sigma_t": 0.0}, geometry=box, on_note=lambda n: None, **kw)
    assert _face_normals(r.path) == ["true"] and any("face normals" in n for n in r.notes)
    render_api(r.path, tmp_path / "b.exr")
    assert _face_spread(tmp_path / "b.exr") < 1e-6


def test_mesh_with_normals_keeps_them_and_ply_without_gets_face_normals(tmp_path):
    from fogref.scene.writer import write_scene

    smooth = _box_obj(tmp_path / "n.obj", normals=True)
    r = write_scene(tmp_path / "n.xml", geometry=smooth, on_note=lambda n: None)
    assert _face_normals(r.path) == [] and any("the file's vertex normals" in n for n in r.notes)
    ply = tmp_path / "p.ply"
    ply.write_text(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
    )
    r = write_scene(tmp_path / "p.xml", geometry=ply, on_note=lambda n: None)
    assert _face_normals(r.path) == ["true"]


def test_ground_and_mesh_reflectance(tmp_path, capsys):
    from fogref.scene.writer import write_scene

    rc, _ = cli(capsys, ["scene", "--out", tmp_path / "p.xml", "--ground-reflectance", "0.5"])
    assert rc == 0
    d = {e.get("name"): e.get("value") for e in ET.parse(tmp_path / "p.xml").getroot().iter("default")}
    assert d["reflectance"] == "0.5, 0.5, 0.5"
    rc, err = cli(capsys, ["scene", "--out", tmp_path / "q.xml", "--ground-reflectance", "0.1,1.5,0"])
    assert rc == 2 and "--ground-reflectance" in err and "[0, 1]" in err
    rc, err = cli(capsys, ["scene", "--out", tmp_path / "q.xml", "--mesh-reflectance", "0.5"])
    assert rc == 2 and "applies to a mesh file" in err
    box = _box_obj(tmp_path / "box.obj")
    r = write_scene(
        tmp_path / "m.xml",
        geometry=box,
        ground=True,
        mesh_reflectance=0.7,
        ground_reflectance=[0.1, 0.2, 0.3],
        on_note=lambda n: None,
    )
    assert r.defaults["reflectance"] == "0.7, 0.7, 0.7"
    root = ET.parse(r.path).getroot()
    own = root.find("bsdf[@id='ground_surface']/rgb[@name='reflectance']")
    assert own is not None and own.get("value") == "0.1, 0.2, 0.3"
    assert root.find("shape[@id='ground']/ref").get("id") == "ground_surface"
    assert "[0, 1]" in api_error(write_scene, tmp_path / "z.xml", geometry=box, mesh_reflectance=-0.1)


# --------------------------------------------------------------------------- --out never an input


def test_scene_out_is_never_an_input(tmp_path, capsys, monkeypatch):
    from fogref.scene import templates as scene_templates
    from fogref.scene import writer as scene_writer
    from fogref.scene.writer import write_scene

    box = _box_obj(tmp_path / "box.obj")
    before = box.read_bytes()
    link = tmp_path / "link.xml"
    link.symlink_to(box)
    rc, err = cli(capsys, ["scene", "--out", link, "--force", "--geometry", box])
    assert rc == 2 and "an input of this scene" in err, err
    assert "an input" in api_error(write_scene, link, geometry=box, overwrite=True)
    assert link.is_symlink() and box.read_bytes() == before
    valley = tmp_path / "valley_copy.xml"  # the valley template's source, not the shipped file
    valley.write_bytes(VALLEY.read_bytes())
    monkeypatch.setattr(scene_templates, "VALLEY_SCENE", valley)
    monkeypatch.setattr(scene_writer, "VALLEY_SCENE", valley, raising=False)
    rc, err = cli(capsys, ["scene", "--out", valley, "--force", "--geometry", "valley"])
    assert rc == 2 and "an input of this scene" in err, err
    assert "an input" in api_error(write_scene, valley, geometry="valley", overwrite=True)
    assert valley.read_bytes() == VALLEY.read_bytes()
