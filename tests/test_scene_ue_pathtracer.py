"""``fogref scene --ue-pathtracer``: the fog Unreal's path tracer renders, written from Unreal values.

The scene is written through :func:`fogref.cli.main` and rendered by ``fogref render`` (8x6, 2 spp,
pixel centres); its T channel equals the ``ue_pathtracer`` profile's closed form
(:func:`fogref.mapping.unreal_pathtracer.pathtracer_medium`) on the rays the render reports, with
the camera below the clamp height and rays leaving through the cylinder's wall.
"""

from __future__ import annotations

import numpy as np
import pytest

from fogref.cli import main
from fogref.mapping.unreal_pathtracer import UEPathTracerSettings, exact_medium, pathtracer_medium
from fogref.media import NP
from fogref.models.ue4 import UE4FogParams

UE = ["--ue-fog-density", "0.05", "--ue-fog-height-falloff", "2", "--ue-fog-height", "2000"]
PT = [
    "--ue-volumetric-fog-distance", "3000", "--ue-fog-density-clamp", "4",
    "--ue-volumetric-fog-albedo", "0.8,0.7,0.6", "--ue-volumetric-fog-scattering-distribution", "0.3",
    "--ue-volumetric-fog-extinction-scale", "1.5",
]  # fmt: skip


@pytest.mark.render
def test_scene_renders_the_path_traced_fog(tmp_path, capsys):
    from fogref.gbuffer import load_truth

    xml, exr = tmp_path / "pt.xml", tmp_path / "pt.exr"
    assert main(["scene", "--out", str(xml), "--ue-pathtracer", *UE, *PT, "--res", "8", "--resy", "6"]) == 0
    assert "Unreal has no albedo" not in capsys.readouterr().err
    args = ["render", str(xml), "--spp", "2", "--seed", "0", "--pixel-filter", "centre"]
    assert main([*args, "--out", str(exr), "--quiet"]) == 0
    t = load_truth(exr)
    ue = UE4FogParams(FogDensity=0.05, FogHeightFalloff=2.0, FogHeight=2000.0)
    pt = UEPathTracerSettings(
        VolumetricFogDistance=3000.0,
        FogDensityClamp=4.0,
        VolumetricFogAlbedo=(0.8, 0.7, 0.6),
        VolumetricFogScatteringDistribution=0.3,
        VolumetricFogExtinctionScale=1.5,
    )
    cam = [float(x) for x in t.params["camera"]["origin"]]
    m = pathtracer_medium(ue, pt, cam)
    assert t.params["medium"]["profile"] == "ue_pathtracer" and t.params["medium"]["clamp"] == 4.0
    assert t.params["medium"]["albedo"] == [0.8, 0.7, 0.6] and t.params["medium"]["g"] == 0.3
    assert cam[1] < m.layers[0].clamp_height and m.bounds.radius == 30.0
    view = np.asarray(t.view, dtype=float).reshape(-1, 3)
    view = view / np.linalg.norm(view, axis=1, keepdims=True)
    hit = np.asarray(t.hit).reshape(-1) > 0.5
    D = np.where(hit, np.asarray(t.distance, dtype=float).reshape(-1), NP.largest)
    o = tuple(np.full(len(D), c) for c in cam)
    d = tuple(view[:, i] for i in range(3))
    T_ref = np.asarray(m.transmittance(NP, o, d, D)[0])
    T_exact = np.asarray(exact_medium(ue, pt).transmittance(NP, o, d, D)[0])
    assert (~hit).any() and np.abs(T_exact - T_ref).max() > 1e-2  # the wall and the clamp show
    T = np.asarray(t.transmittance, dtype=float).reshape(-1, 3)[:, 0]
    np.testing.assert_allclose(T, T_ref, rtol=1e-5, atol=1e-7)


def test_ue_exact_writes_the_fog_without_clamp_and_cylinder(tmp_path):
    """``--ue-exact``: the medium holds :func:`exact_fog_params` of the Unreal and path-tracer values
    (profile exponential, no clamp, no cylinder), to the written digits."""
    import xml.etree.ElementTree as ET

    from fogref.mapping.unreal_pathtracer import exact_fog_params

    xml = tmp_path / "exact.xml"
    assert main(["scene", "--out", str(xml), "--ue-exact", *UE, *PT]) == 0
    medium = next(m for m in ET.parse(xml).getroot().iter("medium"))
    got = {e.get("name"): e.get("value") for e in medium if e.get("name")}
    ue = UE4FogParams(FogDensity=0.05, FogHeightFalloff=2.0, FogHeight=2000.0)
    pt = UEPathTracerSettings(
        VolumetricFogDistance=3000.0,
        FogDensityClamp=4.0,
        VolumetricFogAlbedo=(0.8, 0.7, 0.6),
        VolumetricFogScatteringDistribution=0.3,
        VolumetricFogExtinctionScale=1.5,
    )
    want = exact_fog_params(ue, pt)
    assert got["profile"] == "exponential" and not {"clamp", "radius", "center"} & set(got)
    assert set(got) == set(want)
    for k, v in want.items():
        if k != "profile":
            np.testing.assert_allclose([float(x) for x in got[k].split(",")], np.ravel(v), rtol=1e-12)


@pytest.mark.parametrize(
    "extra, words",
    [
        (
            ["--ue-fog-density-clamp", "4"],
            ["--ue-fog-density-clamp", "only with --ue-pathtracer or --ue-exact"],
        ),
        (["--ue-exact", "--visibility", "500"], ["--visibility", "--ue-exact"]),
        (["--ue-exact", "--g", "0.5"], ["--ue-pathtracer", "--g"]),
        (["--ue-pathtracer", "--sigma-t", "0.01"], ["--ue-pathtracer", "--sigma-t"]),
        (["--ue-pathtracer", "--g", "0.5"], ["--ue-pathtracer", "--g"]),
        (["--ue-pathtracer", "--ue-fog-density-clamp", "400"], ["--ue-fog-density-clamp", "[1, 256]"]),
        (["--ue-pathtracer", "--ue-volumetric-fog-distance", "0"], ["--ue-volumetric-fog-distance", "cm"]),
        (["--ue-pathtracer", "--ue-volumetric-fog-albedo", "1.5"], ["--ue-volumetric-fog-albedo", "[0, 1]"]),
        (
            ["--ue-pathtracer", "--ue-volumetric-fog-scattering-distribution", "-1"],
            ["--ue-volumetric-fog-scattering-distribution", "[-0.99, 0.99]"],
        ),
        (["--ue-pathtracer", "--ue-volumetric-fog-extinction-scale", "-1"], ["extinction-scale", "[0, inf)"]),
    ],
)
def test_refusals_are_one_line(tmp_path, capsys, extra, words):
    out = tmp_path / "s.xml"
    assert main(["scene", "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and all(w in err for w in words), err
    assert not out.exists()


@pytest.mark.render
def test_every_value_of_the_path_traced_fog_is_a_default_that_set_changes(tmp_path, capsys):
    """The fog's values are ``$default``s (``fogref scene --help``: every value becomes one): the scene
    renders with ``--set g=0.9`` and each fog value it was written with, and says so in the header."""
    import xml.etree.ElementTree as ET

    from fogref.gbuffer import load_truth

    xml, exr = tmp_path / "pt.xml", tmp_path / "pt.exr"
    assert main(["scene", "--out", str(xml), "--ue-pathtracer", *UE, *PT, "--res", "8", "--resy", "6"]) == 0
    medium = next(m for m in ET.parse(xml).getroot().iter("medium"))
    values = {e.get("name"): e.get("value") for e in medium if e.get("name") != "profile"}
    assert values and all(v.startswith("$") for v in values.values()), values
    sets = {"g": "0.9", "fog_clamp": "2", "fog_radius": "20", "albedo": "0.5, 0.5, 0.5", "falloff": "0.05"}
    args = ["render", str(xml), "--spp", "1", "--quiet", "--no-png", "--out", str(exr)]
    given = [x for k, v in sets.items() for x in ("--set", f"{k}={v}")]
    assert main([*args, *given]) == 0, capsys.readouterr()
    med = load_truth(exr).params["medium"]
    assert (med["g"], med["clamp"], med["radius"], med["albedo"]) == (0.9, 2.0, 20.0, [0.5] * 3)
    assert med["falloff"] == 0.05
