"""An engine's images made outside fogref, compared through ``fogref compare --image`` and ``check``."""

import json

import numpy as np
import pytest
from truth_factory import synthetic_truth_exr, write_rgb

from fogref.cli import main
from fogref.compare.check import check
from fogref.compare.foreign import load_engine_images, read_image
from fogref.errors import FogrefError
from fogref.gbuffer import load_truth
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams

MODEL = UE4ExponentialHeightFog(UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2))


def write_hdr(path, img, rle=False):
    """Radiance RGBE written with numpy (flat, or run-length encoded scanlines)."""
    H, W, _ = img.shape
    m = img.max(-1)
    mant, e = np.frexp(m)
    scale = np.where(m > 1e-32, mant * 256.0 / np.where(m > 1e-32, m, 1), 0.0)
    rgbe = np.zeros((H, W, 4), np.uint8)
    rgbe[..., :3] = np.clip(img * scale[..., None], 0, 255).astype(np.uint8)
    rgbe[..., 3] = np.where(m > 1e-32, e + 128, 0)
    out = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {H} +X {W}\n".encode())
    for y in range(H):
        if not rle:
            out += rgbe[y].tobytes()
            continue
        out += bytes([2, 2, W >> 8, W & 255])
        for c in range(4):
            row = rgbe[y, :, c]
            out += bytes([128 + 2, row[0]])  # a run of two (pixel 1 := pixel 0), then literals
            rest = row[2:]
            for k in range(0, len(rest), 128):
                chunk = rest[k : k + 128]
                out += bytes([len(chunk)]) + chunk.tobytes()
    path.write_bytes(bytes(out))
    return path


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    d = tmp_path_factory.mktemp("byo")
    exr, parts = synthetic_truth_exr(d / "truth.exr", MODEL)
    return d, load_truth(exr), parts


def test_truth_roundtrip(scene):
    d, truth, parts = scene
    assert truth.shape == (36, 64) and truth.pixel_exact


def test_cli_image_detects_five_percent_inscatter_and_passes_exact(scene, capsys):
    d, truth, p = scene
    T = write_rgb(d / "T.exr", p["T"])
    for name, k, verdict, code in (("exact", 1.0, "pass", 0), ("bright", 1.05, "fail", 1)):
        L = write_rgb(d / f"L_{name}.exr", k * p["inscatter"])
        final = write_rgb(d / f"final_{name}.exr", truth.surface * p["T"] + k * p["inscatter"])
        out = d / f"report_{name}"
        assert (
            main(
                [
                    "compare",
                    str(d / "truth.exr"),
                    "--image",
                    str(final),
                    "--transmittance",
                    str(T),
                    "--inscatter",
                    str(L),
                    "--out",
                    str(out),
                    "--no-figures",
                ]
            )
            == code
        )
        report = json.loads((out / "check.json").read_text())
        rows = {(r["part"], r["region"], r["metric"]): r for r in report["rows"]}
        assert rows[("inscatter", "all", "rel_bias")]["verdict"] == verdict, name
        assert report["verdict"] == verdict
        assert (out / "errors.exr").is_file() and "verdict: " + verdict in capsys.readouterr().out
    # the same through check(), from the files
    eng = load_engine_images(d / "final_bright.exr", d / "T.exr", d / "L_bright.exr", shape=truth.shape)
    assert check(truth, eng).row("inscatter", "all", "rel_bias").verdict == "fail"


def test_png_srgb_exposure_and_hdr(scene, tmp_path):
    from PIL import Image

    d, truth, p = scene
    img = np.clip(truth.surface * p["T"] + p["inscatter"], 0, 1)
    import colour

    enc = np.round(np.asarray(colour.cctf_encoding(img * 0.5, function="sRGB")) * 255).astype(np.uint8)
    Image.fromarray(enc).save(tmp_path / "e.png")
    back = read_image(tmp_path / "e.png", encoding="srgb", exposure=0.5)
    assert np.abs(back - img).max() < 0.02
    for rle in (False, True):
        h = read_image(write_hdr(tmp_path / f"e{rle}.hdr", img, rle=rle))
        want = img.copy()
        if rle:
            want[:, 1] = want[:, 0]
        assert np.abs(h - want).max() <= want.max() / 128


def test_errors_name_file_and_sizes(scene, tmp_path):
    d, truth, p = scene
    small = write_rgb(tmp_path / "small.exr", np.ones((18, 32, 3)))
    with pytest.raises(FogrefError, match=r"small.exr: 32x18 px, but .* is 64x36 px"):
        load_engine_images(small, shape=truth.shape, truth_name="truth.exr")
    with pytest.raises(FogrefError, match="encoding 'gamma'"):
        read_image(small, encoding="gamma")
    with pytest.raises(FogrefError, match="exposure"):
        read_image(small, exposure=0)
    (tmp_path / "x.tga").write_bytes(b"x")
    with pytest.raises(FogrefError, match="unknown image type"):
        read_image(tmp_path / "x.tga")
    assert main(["compare", str(d / "truth.exr"), "--image", str(small)]) == 2


def test_fog_colour_becomes_inscatter(scene, tmp_path):
    d, truth, p = scene
    T = write_rgb(tmp_path / "T.exr", p["T"])
    C = write_rgb(tmp_path / "C.exr", p["inscatter"] / np.maximum(1 - p["T"], 1e-6))
    eng = load_engine_images(transmittance=T, fog_colour=C, shape=truth.shape)
    assert check(truth, eng).row("inscatter", "all", "rel_bias").verdict == "pass"


@pytest.mark.render
def test_rendered_truth_engine_image_five_percent_caught_exact_not(fogref_truth, tmp_path, capsys):
    """Real renders (32x18, 64 spp): an independent render is the 'exact engine'; its inscatter
    x 1.05, written as EXR outside fogref, fails through ``fogref compare --image``; the exact
    one is not rejected (both truths' noise removed); Unreal's exact extinction passes T."""
    from fogref.mapping.build import build_model as build

    truth = fogref_truth("scenes/valley.xml", res=(32, 18), spp=64, seed=0)
    other = fogref_truth("scenes/valley.xml", res=(32, 18), spp=64, seed=1)
    exact = check(truth, other, distance_bands=())
    for part in ("T", "inscatter", "final"):
        assert exact.row(part, "all", "rel_bias").verdict != "fail", exact.summary()
    T = write_rgb(tmp_path / "T.exr", other.transmittance)
    L = write_rgb(tmp_path / "L.exr", 1.05 * other.inscatter)
    out = tmp_path / "report"
    assert (
        main(
            [
                "compare",
                str(truth.path),
                "--transmittance",
                str(T),
                "--inscatter",
                str(L),
                "--out",
                str(out),
                "--no-figures",
            ]
        )
        == 1
    )
    rows = {
        (r["part"], r["region"], r["metric"]): r for r in json.loads((out / "check.json").read_text())["rows"]
    }
    bias = rows[("inscatter", "all", "rel_bias")]
    assert bias["verdict"] == "fail" and 0.03 < bias["estimate"] < 0.08, bias
    ue4 = build("ue4", scene_params=truth.params)
    assert check(truth, ue4, distance_bands=()).row("T", "all").verdict == "pass"
