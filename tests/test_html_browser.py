"""The HTML reports in a real browser: Debian's headless Chromium through selenium and chromium-driver.

Skipped, with the reason, only where no browser is installed (``scripts/setup.sh`` installs it
where it can).  Each report loads with no console error and no request beyond ``file:``,
``data:`` and ``blob:``; the viewer's readout of a probe pixel equals the EXR; its canvas equals
:func:`fogref.display.tone_map` of the half-float data at the probe; the exposure slider changes
the canvas; flipping A/B shows the other image.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from browser_util import console_errors, find_browser, load, requests, screenshot, start

from conftest import ROOT, SCENES

_, _, WHY = find_browser()
pytestmark = [pytest.mark.browser, pytest.mark.skipif(bool(WHY), reason=f"no browser: {WHY}")]
LOCAL = ("file:", "data:", "blob:")
PROBE = (11, 6)  # x, y of the probe pixel (a surface pixel of the 16x9 default scene)


@pytest.fixture(scope="module")
def driver():
    d = start()
    yield d
    d.quit()


@pytest.fixture(scope="module")
def tiny_report(tmp_path_factory, mitsuba):
    """A compare report (ue4 from the scene) of a 16x9, 16 spp truth of the default scene."""
    from fogref.cli import main
    from fogref.render.render import render

    d = tmp_path_factory.mktemp("browser")
    exr = render(
        SCENES / "valley.xml",
        d / "t.exr",
        spp=16,
        seed=0,
        overrides={"res": 16, "resy": 9},
        progress=False,
        png=False,
    )
    main(["compare", str(exr), "--model", "ue4", "--from-scene", "--out", str(d / "cmp"), "--no-figures"])
    return exr, d / "cmp" / "report.html"


def _data(html_path) -> dict:
    html = Path(html_path).read_text()
    m = re.search(r'<script type="application/json" id="fr-data">(.*?)</script>', html, re.S)
    return json.loads(m.group(1).replace("<\\/", "</"))


def _canvas(drv) -> str:
    return drv.execute_script("return document.getElementById('fr-canvas').toDataURL()")


def _pixel(drv, x, y) -> list[int]:
    return drv.execute_script(
        "var c=document.getElementById('fr-canvas');"
        "return Array.from(c.getContext('2d').getImageData(arguments[0],arguments[1],1,1).data);",
        x,
        y,
    )


#: wall-clock limit [s] of a wait for the page, for a hang only (a loaded machine is slow)
HANG_S = 300


def _rendered(drv) -> int:
    return int(drv.execute_script("return +document.body.getAttribute('data-rendered')"))


def _point_at(drv, x, y):
    """Move the real mouse over pixel (x, y) of the canvas and click (pins the readout)."""
    from selenium.webdriver.common.action_chains import ActionChains

    cv = drv.find_element("id", "fr-canvas")
    w, h = drv.execute_script("var c=arguments[0];return [c.width,c.height];", cv)
    cw, ch = cv.size["width"], cv.size["height"]
    dx, dy = (x + 0.5) * cw / w - cw / 2, (y + 0.5) * ch / h - ch / 2
    ActionChains(drv).move_to_element_with_offset(cv, int(round(dx)), int(round(dy))).click().perform()


def _expected_8bit(values, exposure) -> list[int]:
    from fogref.display import tone_map

    half = np.asarray(values, np.float64).astype(np.float16).astype(np.float64)
    return [int(v) for v in np.floor(tone_map(half, exposure) * 255)]


def test_compare_report_loads_offline_without_errors(driver, tiny_report):
    load(driver, tiny_report[1])
    assert console_errors(driver) == []
    urls = requests(driver)
    assert urls and all(u.startswith(LOCAL) for u in urls), urls
    assert driver.find_element("id", "fr-canvas").size["width"] > 16


def test_probe_pixel_readout_and_canvas_match_the_exr(driver, tiny_report):
    from fogref.gbuffer import load_truth

    exr, html = tiny_report
    t = load_truth(exr)
    load(driver, html)
    x, y = PROBE
    _point_at(driver, x, y)
    assert driver.find_element("id", "ro-xy").text == f"({x}, {y})"
    for i, c in enumerate("RGB"):
        cell = driver.find_element("id", f"ro-truth-{c}")
        value, err = (float(s) for s in cell.text.split(" ± "))
        assert value == pytest.approx(t.final[y, x, i], rel=2.0**-11 + 1e-4), c
        assert err == pytest.approx(t.stderr["final"][y, x, i], rel=2.0**-11 + 1e-4), c
        # the model and error cells: candidate = truth + error, error = candidate - truth
        model = float(driver.find_element("id", f"ro-model-{c}").text)
        error = float(driver.find_element("id", f"ro-error-{c}").text)
        assert model == pytest.approx(value + error, rel=1e-3, abs=1e-6)
    # another part: the pinned readout follows it (T: no Monte Carlo noise in a pixel-exact truth)
    from selenium.webdriver.support.ui import Select

    Select(driver.find_element("id", "fr-part")).select_by_value("T")
    t_r = float(driver.find_element("id", "ro-truth-R").get_attribute("data-value"))
    assert t_r == pytest.approx(t.transmittance[y, x, 0], rel=2.0**-11)
    Select(driver.find_element("id", "fr-part")).select_by_value("final")
    # the canvas is fogref.display.tone_map of the half-float truth at the part's exposure (JS == Python)
    ex = _data(html)["layers"][0]["exposure"]
    assert _pixel(driver, x, y)[:3] == _expected_8bit(t.final[y, x], ex)
    js = driver.execute_script(
        "return [0.0, 0.001, 0.0031308, 0.2, 0.7, 1.5, NaN].map(function(v)"
        "{return window.fogrefToneMap(v, 1.3);})"
    )
    from fogref.display import tone_map

    py = tone_map(np.array([0.0, 0.001, 0.0031308, 0.2, 0.7, 1.5, np.nan]), 1.3)
    assert np.allclose(js, py, rtol=1e-12, atol=0)
    assert console_errors(driver) == []


def test_exposure_slider_changes_the_canvas(driver, tiny_report):
    from selenium.webdriver.common.keys import Keys

    load(driver, tiny_report[1])
    before, n = _canvas(driver), _rendered(driver)
    slider = driver.find_element("id", "fr-exposure")
    slider.click()  # the middle: 0 stops
    for _ in range(4):
        slider.send_keys(Keys.ARROW_RIGHT)
    assert float(slider.get_attribute("value")) > 0
    assert _rendered(driver) > n
    assert _canvas(driver) != before
    ex = _data(tiny_report[1])["layers"][0]["exposure"] * 2 ** float(slider.get_attribute("value"))
    from fogref.gbuffer import load_truth

    t = load_truth(tiny_report[0])
    x, y = PROBE
    assert _pixel(driver, x, y)[:3] == _expected_8bit(t.final[y, x], ex)


def test_flip_ab_shows_the_other_image(driver, tiny_report):
    from fogref.html.inline import decode_half

    exr, html = tiny_report
    load(driver, html)
    layer = _data(html)["layers"][0]
    truth, error = decode_half(layer["truth"]), decode_half(layer["error"])
    x, y = PROBE
    a = _canvas(driver)
    assert driver.find_element("id", "fr-showing").text == "truth"
    assert _pixel(driver, x, y)[:3] == _expected_8bit(truth[y, x], layer["exposure"])
    driver.find_element("id", "fr-flip").click()
    assert driver.find_element("id", "fr-showing").text == "model"
    assert _canvas(driver) != a
    model = np.float32(truth[y, x]) + np.float32(error[y, x])  # what the page adds, in float32
    from fogref.display import tone_map

    want = [int(v) for v in np.floor(tone_map(model.astype(np.float64), layer["exposure"]) * 255)]
    got = _pixel(driver, x, y)[:3]
    assert all(abs(g - w) <= 1 for g, w in zip(got, want)), (got, want)
    driver.find_element("id", "fr-flip").click()
    assert _canvas(driver) == a
    # the swipe shows A left, B right; every part of the truth is in the part list
    parts = [o.get_attribute("value") for o in driver.find_elements("css selector", "#fr-part option")]
    assert parts[:6] == ["final", "T", "inscatter", "single", "multiple", "surface"]
    assert console_errors(driver) == []


@pytest.mark.parametrize(
    "rel", ["reports/unreal_study/report.html", "reports/sweeps/unreal_sun_falloff_g/report.html"]
)
def test_committed_example_reports_load_offline(driver, rel, tmp_path):
    path = ROOT / rel
    if not path.is_file():
        pytest.fail(f"{rel} is missing: run scripts/make_html_examples.py")
    load(driver, path)
    assert console_errors(driver) == []
    assert all(u.startswith(LOCAL) for u in requests(driver))
    assert not math.isnan(float(driver.execute_script("return document.images.length")))
    shot = screenshot(driver, tmp_path / "shot.png")
    assert shot.stat().st_size > 10_000


def test_flicker_swipe_and_false_colours(driver, tiny_report):
    import time

    from selenium.webdriver.support.ui import Select

    from fogref.html.inline import decode_half

    exr, html = tiny_report
    load(driver, html)
    layer = _data(html)["layers"][0]
    truth, error = decode_half(layer["truth"]), decode_half(layer["error"])
    n = _rendered(driver)
    Select(driver.find_element("id", "fr-mode")).select_by_value("flicker")
    # the event: three more frames (one every 0.6 s); the clock only catches a page that stopped
    deadline = time.monotonic() + HANG_S
    while _rendered(driver) < n + 3:
        assert time.monotonic() < deadline, f"flicker drew {_rendered(driver) - n} frames in {HANG_S} s"
        time.sleep(0.1)
    Select(driver.find_element("id", "fr-mode")).select_by_value("swipe")
    Select(driver.find_element("id", "fr-b")).select_by_value("error")
    w = int(driver.execute_script("return document.getElementById('fr-canvas').width"))
    assert _pixel(driver, 0, 2)[:3] == _expected_8bit(truth[2, 0], layer["exposure"])  # left: A, the truth
    # right: B, the signed error in false colour: red where the candidate is too bright, blue too dark
    e = error[2, w - 1].mean()
    r, _, b, _ = _pixel(driver, w - 1, 2)
    assert (r > b) == (e > 0) or abs(e) < 1e-6
    assert console_errors(driver) == []


def test_diff_and_batch_pages_load_offline(driver, tiny_report, tmp_path):
    from fogref.cli import main
    from fogref.exrio import write_exr
    from fogref.gbuffer import load_truth

    exr = tiny_report[0]
    t = load_truth(exr)
    imgs = []
    for k, scale in enumerate((1.0, 1.1)):
        imgs.append(tmp_path / f"e{k}.exr")
        write_exr(imgs[-1], {c: t.final[..., i] * scale for i, c in enumerate("RGB")})
    main(["diff", str(exr), str(imgs[1]), "--out", str(tmp_path / "diff")])
    main(["diff", str(imgs[0]), str(imgs[1]), "--out", str(tmp_path / "diff2")])
    main(["compare", str(exr), "--image", *map(str, imgs), "--out", str(tmp_path / "b"), "--no-figures"])
    for page in ("diff/report.html", "diff2/report.html", "b/report.html", "b/e1/report.html"):
        load(driver, tmp_path / page)
        assert console_errors(driver) == [], page
        assert all(u.startswith(LOCAL) for u in requests(driver)), page
