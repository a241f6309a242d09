"""fogref's Babylon.js port against Babylon.js 9.35.0 (npm ``@babylonjs/core`` 9.35.0) in headless Chromium.

WebGL 2 on SwiftShader through selenium and Debian's chromium-driver (``tests/web_probe.py``,
``tests/web/babylon.html``, ES modules from ``file://``): 16 fog set-ups (6 ``FOGMODE_LINEAR``,
5 ``FOGMODE_EXP``, 5 ``FOGMODE_EXP2``) x 1024 probe pixels of 60 unlit ``StandardMaterial``
quads (emissive colour) and 4 background tiles.  Measured (Chromium 156, SwiftShader):

* linear float32 target: worst |engine - port| 3.0e-7 (the material's colour units), float32
  rounding;
* default canvas: worst 0/255 (Babylon writes the blend unconverted).

The fog coordinate is the distance: the same port fed the eye depth instead misses by 0.17
(linear) and 44/255 (canvas).
Skipped, saying why, only where Chromium cannot start or ``npm ci`` has not run.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import web_probe as wp

pytestmark = pytest.mark.browser  # headless Chromium (CONTRIBUTING.md, the tiers)

LINEAR_TOL = 1e-6  # float32 rounding of length/pow/mix (measured 3.0e-7)
CANVAS_TOL = 1.0  # 8-bit steps


@pytest.fixture(scope="module")
def driver():
    d = wp.driver_or_skip("@babylonjs/core")
    yield d
    d.quit()


def test_port_matches_babylon(driver):
    r = wp.measure(driver, wp.BABYLON)
    assert r["version"] == "9.35.0" and r["info"]["toneMapping"] is False
    assert r["pixels"] == 16 * 1024
    assert 0 <= r["linear"] <= LINEAR_TOL, r["linear_at"]
    assert 0 <= r["canvas"] <= CANVAS_TOL, r["canvas_at"]


class _OnDepth:
    """The Babylon port fed the eye depth (0, 0, -z) instead of the point (background pixels
    kept): a fog on depth."""

    def __init__(self, model):
        self.model = model

    def evaluate(self, camera, positions, precision="float32"):
        p = np.asarray(positions, float)
        sky = np.linalg.norm(p, axis=-1, keepdims=True) > 1e4
        on_axis = np.stack([0 * p[..., 0], 0 * p[..., 1], p[..., 2]], -1)
        return self.model.evaluate(camera, np.where(sky, p, on_axis), precision)


def test_fog_is_on_distance_not_depth(driver):
    on_depth = dataclasses.replace(wp.BABYLON, model=lambda fog, out: _OnDepth(wp.babylon_model(fog, out)))
    assert wp.measure(driver, on_depth)["linear"] > 0.01
