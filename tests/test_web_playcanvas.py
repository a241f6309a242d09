"""fogref's PlayCanvas port against PlayCanvas 2.23.3 (npm ``playcanvas`` 2.23.3) in headless Chromium.

WebGL 2 on SwiftShader through selenium and Debian's chromium-driver (``tests/web_probe.py``,
``tests/web/playcanvas.html``, the UMD build): 16 fog set-ups (6 ``FOG_LINEAR``, 5 ``FOG_EXP``,
5 ``FOG_EXP2``) x 1024 probe pixels of 60 unlit ``StandardMaterial`` quads (emissive colour) and
4 background tiles, camera clip planes 0.1 and 500 m.  Measured (Chromium 156, SwiftShader):

* linear float32 target (``GAMMA_NONE``): worst |engine - port| 2.5e-7 (linear RGB), float32
  rounding;
* default canvas (``GAMMA_SRGB``, ``TONEMAP_LINEAR``): worst 0/255 with
  :func:`fogref.models.playcanvas.gamma_correct_output` (a 2.2 power).

The fog coordinate is ``gl_FragCoord.z / gl_FragCoord.w = far (z - near) / (far - near)``: the
same port with the plain eye depth (near clip 1e-6 m) misses by 0.059 (linear) and 34/255 (canvas).
Skipped, saying why, only where Chromium cannot start or ``npm ci`` has not run.
"""

from __future__ import annotations

import dataclasses

import pytest
import web_probe as wp

from fogref.models.playcanvas import PlayCanvasFog

pytestmark = pytest.mark.browser  # headless Chromium (CONTRIBUTING.md, the tiers)

LINEAR_TOL = 1e-6  # float32 rounding of the depth remap/exp/mix (measured 2.5e-7)
CANVAS_TOL = 1.0  # 8-bit steps


@pytest.fixture(scope="module")
def driver():
    d = wp.driver_or_skip("playcanvas")
    yield d
    d.quit()


def test_port_matches_playcanvas(driver):
    r = wp.measure(driver, wp.PLAYCANVAS)
    assert r["version"] == "2.23.3" and r["info"]["revision"] == "b7655d8"
    assert r["info"]["gammaCorrection"] == 1 and r["info"]["toneMapping"] == 0  # GAMMA_SRGB, TONEMAP_LINEAR
    assert r["pixels"] == 16 * 1024
    assert 0 <= r["linear"] <= LINEAR_TOL, r["linear_at"]
    assert 0 <= r["canvas"] <= CANVAS_TOL, r["canvas_at"]


def test_fog_depth_is_remapped(driver):
    def eye_depth(fog, out):
        m = wp.playcanvas_model(fog, out)
        return PlayCanvasFog(dataclasses.replace(m.params, nearClip=1e-6))

    assert wp.measure(driver, dataclasses.replace(wp.PLAYCANVAS, model=eye_depth))["linear"] > 0.01
