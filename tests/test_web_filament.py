"""fogref's Filament port against Filament 1.53.4's web build (npm ``filament`` 1.53.4) in headless Chromium.

WebGL 2 on SwiftShader through selenium and Debian's chromium-driver (``tests/web_probe.py``,
``tests/web/filament.html``; the wasm loads from ``file://``): 16 ``View.FogOptions`` set-ups
(height fog with falloff 0..1 1/m, start distance, maximum opacity; half with the sun term of a
directional light) x 960 probe pixels of 60 unlit glTF quads (gltfio's ubershaders,
``KHR_materials_unlit``), exposure 1 and an indirect light of intensity 1 (the shader scales
the fog colour by their product).  Filament's JS API has no float read-back: the default canvas
is compared, as Filament ships it (post-processing on: its default colour grading, ACES-legacy
tone mapping, sRGB output) but FXAA and temporal dithering (off, see
:mod:`fogref.engines.filament`), against the port's ``output="canvas"``
(:class:`fogref.models.filament.CanvasGrade`), within one 8-bit step.  Measured (Chromium 156,
SwiftShader): worst 1/255, on 1243 of the 46080 values (2.7 %).

Background tiles are left out: Filament clears to the clear colour without fog, while the
port (like Filament's skybox) fogs a sky pixel.  The same port without its height term
(falloff 0) misses by 127/255, without its sun term by 132/255, without the tone mapping (the
sRGB encoding of the linear blend) by 113/255.  Skipped, saying why, only where Chromium
cannot start or ``npm ci`` has not run.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import web_probe as wp

from fogref.display import srgb_encode
from fogref.models.filament import FilamentFog

pytestmark = pytest.mark.browser  # headless Chromium (CONTRIBUTING.md, the tiers)

CANVAS_TOL = 1.0  # 8-bit steps


@pytest.fixture(scope="module")
def driver():
    d = wp.driver_or_skip("filament")
    yield d
    d.quit()


def test_port_matches_filament(driver):
    r = wp.measure(driver, wp.FILAMENT)
    assert wp.npm_version("filament") == "1.53.4"
    assert r["pixels"] == 16 * 960
    assert 0 <= r["canvas"] <= CANVAS_TOL, r["canvas_at"]


def test_height_term_is_seen(driver):
    def no_height(fog, out):
        return FilamentFog(dataclasses.replace(wp.filament_model(fog, out).params, heightFalloff=0.0))

    assert wp.measure(driver, dataclasses.replace(wp.FILAMENT, model=no_height))["canvas"] > 5


def test_sun_term_is_seen(driver):
    def no_sun(fog, out):
        return FilamentFog(dataclasses.replace(wp.filament_model(fog, out).params, inScatteringSize=-1.0))

    assert wp.measure(driver, dataclasses.replace(wp.FILAMENT, model=no_sun))["canvas"] > 5


def test_tone_mapping_is_seen(driver):
    """A port without Filament's default tone mapping (the linear blend, sRGB-encoded) fails."""
    untoned = dataclasses.replace(
        wp.FILAMENT,
        model=lambda fog, out: wp.filament_model(fog, "linear"),
        canvas=lambda res, scene: srgb_encode(res.composite(scene.astype(np.float32))),
    )
    assert wp.measure(driver, untoned)["canvas"] > 5
