"""HTML reports, ``fogref diff`` and batch ``fogref compare`` (no browser; see test_html_browser.py).

Tiny truths of the default scene (16x9 px, 16 spp) rendered once per session.
"""

from __future__ import annotations

import csv
import json
import re
from types import SimpleNamespace

import numpy as np
import pytest

from conftest import SCENES
from fogref.cli import main
from fogref.html.inline import decode_half, decode_mask, encode_half, encode_mask

TINY = {"res": 16, "resy": 9}


@pytest.fixture(scope="session")
def truths(tmp_path_factory, mitsuba):
    """Three 16x9, 16 spp truths: seeds 0 and 1 at the default sun, seed 0 with the sun at 30 deg."""
    from fogref.render.render import render

    d = tmp_path_factory.mktemp("html_truths")
    out = {}
    for name, seed, extra in (("s0", 0, {}), ("s1", 1, {}), ("sun30", 0, {"sun_elevation": 30})):
        out[name] = render(
            SCENES / "valley.xml",
            d / f"{name}.exr",
            spp=16,
            seed=seed,
            overrides={**TINY, **extra},
            progress=False,
            png=False,
        )
    return out


def _data(html: str) -> dict:
    m = re.search(r'<script type="application/json" id="fr-data">(.*?)</script>', html, re.S)
    return json.loads(m.group(1).replace("<\\/", "</"))


def test_half_encoding_round_trip_is_half_rounding():
    rng = np.random.default_rng(0)
    a = rng.lognormal(size=(5, 7, 3)) * 10.0 ** rng.integers(-3, 3, size=(5, 7, 1))
    got = decode_half(encode_half(a))
    assert np.array_equal(got, a.astype(np.float16).astype(np.float64))
    assert np.max(np.abs(got / a - 1)) <= 2.0**-11
    bad = decode_half(encode_half(np.array([[np.nan, np.inf, 1e9]])))
    assert bad[0, :2].tolist() == [[0.0], [0.0]]  # not finite: 0
    assert abs(bad[0, 2, 0] / 1e9 - 1) <= 2.0**-11  # beyond the half range: scaled, not clipped
    m = rng.integers(0, 32, size=(4, 6))
    assert np.array_equal(decode_mask(encode_mask(m)), m)


@pytest.mark.render
def test_diff_same_scene_different_seeds_equal_within_noise(truths, tmp_path, capsys):
    js = tmp_path / "d.json"
    code = main(
        ["diff", str(truths["s0"]), str(truths["s1"]), "--json", str(js), "--out", str(tmp_path / "r")]
    )
    out = capsys.readouterr().out
    assert code == 0, out
    assert "verdict: equal within noise" in out
    d = json.loads(js.read_text())
    assert d["verdict"] == "equal within noise" and d["exit_code"] == 0 and d["kinds"] == ["truth", "truth"]
    assert {r["part"] for r in d["rows"]} == {"T", "inscatter", "final"}
    assert (tmp_path / "r" / "report.html").is_file()


@pytest.mark.render
def test_diff_different_sun_elevation_differs(truths, capsys):
    code = main(["diff", str(truths["s0"]), str(truths["sun30"])])
    out = capsys.readouterr().out
    assert code == 1, out
    assert "verdict: differ" in out and "differs: " in out


@pytest.mark.render
def test_diff_images_and_usage(truths, tmp_path, capsys):
    from fogref.exrio import write_exr
    from fogref.gbuffer import load_truth

    t = load_truth(truths["s0"])
    a, b = tmp_path / "a.exr", tmp_path / "b.exr"
    write_exr(a, {c: t.final[..., i] for i, c in enumerate("RGB")})
    write_exr(b, {c: t.final[..., i] * 1.01 for i, c in enumerate("RGB")})
    assert main(["diff", str(a), str(a)]) == 0
    assert main(["diff", str(a), str(b)]) == 1
    assert main(["diff", str(a), str(b), "--tolerance", "1e3"]) == 0
    # a truth against its own final image: no difference beyond the truth's noise
    assert main(["diff", str(truths["s0"]), str(a)]) == 0
    capsys.readouterr()
    assert main(["diff", str(a), str(tmp_path / "missing.exr")]) == 2
    assert "fogref: error:" in capsys.readouterr().err


@pytest.mark.render
def test_compare_writes_report_html(truths, tmp_path, capsys):
    out = tmp_path / "cmp"
    main(["compare", str(truths["s0"]), "--model", "ue4", "--from-scene", "--out", str(out), "--no-figures"])
    # what --help says --no-figures writes: these files, no PNG, and the page without its plots
    written = sorted(str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert written == ["check.json", "errors.exr", "index.md", "metrics.json", "report.html"]
    assert "data:image/png" not in (out / "report.html").read_text()
    capsys.readouterr()
    with pytest.raises(SystemExit):
        main(["compare", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    said = help_text[help_text.index("--no-figures no figures") :][:300]
    assert all(name in said for name in written) and "no PNGs" in said, said
    html = (out / "report.html").read_text()
    assert "http://" not in html and "https://" not in html
    d = _data(html)
    assert (d["width"], d["height"]) == (16, 9)
    parts = [layer["part"] for layer in d["layers"]]
    assert parts[:6] == ["final", "T", "inscatter", "single", "multiple", "surface"]
    final = d["layers"][0]
    from fogref.gbuffer import load_truth

    t = load_truth(truths["s0"])
    assert np.array_equal(decode_half(final["truth"]), t.final.astype(np.float16).astype(np.float64))
    assert d["regions"][:2] == ["surface", "sky"]
    assert "v-fail" in html or "v-pass" in html or "v-inconclusive" in html


@pytest.mark.render
def test_compare_batch_three_images_one_table(truths, tmp_path, capsys):
    from fogref.exrio import write_exr
    from fogref.gbuffer import load_truth

    t = load_truth(truths["s0"])
    imgs = []
    for name, scale in (("exact", 1.0), ("bright", 1.2), ("dark", 0.7)):
        p = tmp_path / "engine" / f"{name}.exr"
        p.parent.mkdir(exist_ok=True)
        write_exr(p, {c: t.final[..., i] * scale for i, c in enumerate("RGB")})
        imgs.append(str(p))
    out = tmp_path / "batch"
    code = main(["compare", str(truths["s0"]), "--image", *imgs, "--out", str(out), "--no-figures"])
    text = capsys.readouterr().out
    assert code == 1, text  # the scaled images fail
    rows = list(csv.DictReader(open(out / "batch.csv")))
    assert [r["image"] for r in rows] == imgs
    assert [r["verdict"] for r in rows][1:] == ["fail", "fail"]
    assert rows[0]["verdict"] != "fail"
    for key in ("final/all:rel_rmse", "final/all:rel_rmse.low", "final/all:rel_rmse.high", "final.all.rmse"):
        assert key in rows[0]
    assert float(rows[1]["final/all:rel_bias"]) == pytest.approx(0.2, abs=0.02)
    d = json.loads((out / "batch.json").read_text())
    assert d["exit_code"] == 1 and len(d["rows"]) == 3
    assert (out / "report.html").is_file() and all(
        (out / n / "report.html").is_file() for n in ("exact", "bright", "dark")
    )
    # a pattern gives the same three images (sorted)
    code = main(
        [
            "compare",
            str(truths["s0"]),
            "--image",
            str(tmp_path / "engine" / "*.exr"),
            "--out",
            str(tmp_path / "batch2"),
            "--no-figures",
        ]
    )
    assert code == 1
    assert len(list(csv.DictReader(open(tmp_path / "batch2" / "batch.csv")))) == 3
    capsys.readouterr()
    assert main(["compare", str(truths["s0"]), "--image", str(tmp_path / "none*.exr")]) == 2
    assert "matches no file" in capsys.readouterr().err


@pytest.mark.render
def test_notebook_displays(truths):
    from fogref.compare.check import check
    from fogref.gbuffer import load_truth
    from fogref.html.notebook import load_ipython_extension, sweep_table

    shown = {}  # what %load_ext registers with IPython's HTML formatter (type -> function)
    html_formatter = SimpleNamespace(for_type=shown.__setitem__)
    load_ipython_extension(
        SimpleNamespace(display_formatter=SimpleNamespace(formatters={"text/html": html_formatter}))
    )
    t = load_truth(truths["s0"])
    html = shown[type(t)](t)
    assert html.count("data:image/png;base64,") == 6 and "16×9 px" in html
    r = check(t, load_truth(truths["sun30"]))
    h = shown[type(r)](r)
    assert r.verdict in h and "v-" in h and h.count("data:image/png") == len(r.errors)
    s = sweep_table("reports/sweeps/unreal_sun_falloff_g")._repr_html_()
    assert "<table" in s and "FogHeightFalloff" in s and "data:image/png" in s


def test_study_and_sweep_pages_from_committed_data(tmp_path):
    """The study page (fit, budget, the comparison's viewer and tables) and the sweep page (plots,
    table) from the committed example data, with no network reference."""
    import shutil

    from conftest import ROOT
    from fogref.html.reports import write_study_html, write_sweep_html

    study = tmp_path / "study"
    (study / "compare").mkdir(parents=True)
    for rel in ("summary.json", "budget.json", "budget.png", "compare/metrics.json", "compare/errors.exr"):
        shutil.copy(ROOT / "reports/unreal_study" / rel, study / rel)
    html = write_study_html(study).read_text()
    d = _data(html)
    assert [layer["part"] for layer in d["layers"]] == ["final", "T", "inscatter", "attenuated_surface"]
    assert (d["width"], d["height"]) == (320, 180)
    assert "Error budget" in html and "FogHeightFalloff" in html and html.count("data:image/png") == 1
    assert "http://" not in html and "https://" not in html
    sweep = tmp_path / "sweep"
    shutil.copytree(
        ROOT / "reports/sweeps/unreal_sun_falloff_g",
        sweep,
        ignore=shutil.ignore_patterns("report.*", "configs"),
    )
    html = write_sweep_html(sweep).read_text()
    assert html.count("data:image/png") == len(list((sweep / "plots").glob("*.png"))) > 0
    assert html.count("<tr") == 48 + 1 and "sun_elevation" in html


def test_the_study_page_explains_its_budget_with_numbers_rounded_to_their_noise(tmp_path):
    """The budget on the study page is for a reader, from the committed study: the total with its
    noise, the Shapley shares with how to read them (a negative share, a share over 100 %), each
    share rounded to its noise, and none of budget.json's raw keys or 17-digit floats."""
    import re
    import shutil

    from conftest import ROOT
    from fogref.html.reports import write_study_html

    study = tmp_path / "study"
    study.mkdir()
    for rel in ("summary.json", "budget.json", "budget.png"):
        shutil.copy(ROOT / "reports/unreal_study" / rel, study / rel)
    html = write_study_html(study).read_text()
    text = re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", html[html.index("Error budget") :]))
    assert "RMSE 0.14481 ± 0.00007" in text  # 0.144808... ± 7e-05 (reports/unreal_study/budget.json)
    assert "A negative share: the effect cancels part of the other effects' error" in text
    assert "can exceed 100 % or fall below −100 %" in text and "How the budget was checked" in text
    assert "Port vs engine (ue4): no runnable engine here." in text
    # about 1.02 ± 0.06 and -1.15 ± 0.15 as fractions of the squared error
    assert "[e] geometric shadows (sun) 102 ± 6 % adds error" in text
    assert "[a/b] colours/exponent re-fitted to the attenuated target -115 ± 15 % cancels part" in text
    for raw in ("total_sq", "share_sum", "share_noise", "rmse_vs_truth_after", "phi"):
        assert raw not in text, raw
    assert not re.search(r"\d\.\d{9,}", text), re.search(r".{40}\d\.\d{9,}.{20}", text)


def test_a_large_truth_is_shown_as_block_means_so_the_page_stays_small(monkeypatch):
    """Above MAX_PIXELS the viewer embeds k x k block means (and their standard errors, from the
    pixels' independent noise), says so on the page, and the page is no larger than one of a truth
    of the shown size: here a 64x36 truth with the limit at 16x9 is shown at 16x9 (k = 4)."""
    import fogref.html.viewer as V
    from fogref.compare.synthetic import synthetic_truth
    from fogref.html.page import page
    from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams

    model = UE4ExponentialHeightFog(UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2))
    small = page("t", [], V.viewer_data(synthetic_truth(model, shape=(9, 16), noise=0.05)))
    monkeypatch.setattr(V, "MAX_PIXELS", 16 * 9)
    t = synthetic_truth(model, shape=(36, 65), noise=0.05)  # one column more: left out
    d = V.viewer_data(t)
    assert (d["width"], d["height"], d["scale"], d["full_size"]) == (16, 9, 4, [65, 36])
    final = next(layer for layer in d["layers"] if layer["part"] == "final")
    blocks = t.final[:, :64].reshape(9, 4, 16, 4, 3).mean(axis=(1, 3))
    assert np.array_equal(decode_half(final["truth"]), blocks.astype(np.float16).astype(np.float64))
    se = np.sqrt((t.stderr["final"][:, :64] ** 2).reshape(9, 4, 16, 4, 3).sum(axis=(1, 3))) / 16
    assert np.array_equal(decode_half(final["stderr"]), se.astype(np.float16).astype(np.float64))
    html = page("t", [], d)
    assert (
        "The image is 65×36 px" in html
        and "mean of 4×4 pixels" in html
        and "last 0 rows and 1 columns" in html
    )
    assert len(html) < 1.25 * len(small), (len(html), len(small))


def test_every_truth_layer_of_the_viewer_carries_its_standard_error():
    """The viewer's layers embed the truth's per-pixel standard error for every part that has one,
    the transmittance (schema group ``T``, ``stderr["transmittance"]``) included: a lookup under
    the group name would leave T without its noise."""
    import fogref.html.viewer as V
    from fogref.compare.synthetic import synthetic_truth
    from fogref.gbuffer import part_attribute
    from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams

    model = UE4ExponentialHeightFog(UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2))
    t = synthetic_truth(model, shape=(9, 16), noise=0.05)
    layers = {layer["part"]: layer for layer in V.viewer_data(t)["layers"]}
    noisy = [p for p in layers if t.stderr.get(part_attribute(p)) is not None]
    assert "T" in noisy, sorted(t.stderr)
    for p in noisy:
        se = np.asarray(t.stderr[part_attribute(p)], np.float64)
        assert layers[p]["stderr"] is not None, p
        assert np.array_equal(decode_half(layers[p]["stderr"]), se.astype(np.float16).astype(np.float64)), p
