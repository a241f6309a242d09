"""PlayCanvas fog: a float32 transcription of the fog chunk with WebGL's gl_FragCoord, the mapping,
the canvas output, extremes.  The real engine is in tests/test_web_playcanvas.py."""

import math

import numpy as np
import pytest

from fogref.errors import ParameterError
from fogref.mapping import PhysicalScene, from_physical
from fogref.media import Box, ExpLayer, FogMedium
from fogref.models import SKY_DISTANCE, get
from fogref.models.playcanvas import PlayCanvasFog, PlayCanvasFogParams, gamma_correct_output

f32 = np.float32


f64 = np.float64


def frag_depth(z_eye, near, far):
    """gl_FragCoord.z / gl_FragCoord.w for an OpenGL perspective projection (Mat4.setPerspective),
    clip z in [-1, 1], depth range [0, 1]: the window depth times w_clip, step by step (float64)."""
    z_v = -f64(z_eye)
    z_clip = -(far + near) / (far - near) * z_v - 2.0 * far * near / (far - near)
    w_clip = -z_v
    z_window = 0.5 * (z_clip / w_clip) + 0.5
    return z_window * w_clip  # gl_FragCoord.w = 1 / w_clip


def get_fog_factor(kind, start, end, density, depth):
    """common/frag/fog.js getFogFactor(), float32."""
    depth = f32(depth)
    if kind == "linear":
        f = (f32(end) - depth) / (f32(end) - f32(start))
    elif kind == "exp":
        f = np.exp(-depth * f32(density))
    else:
        f = np.exp(-depth * depth * f32(density) * f32(density))
    return min(max(f, f32(0.0)), f32(1.0))


@pytest.mark.parametrize("kind", ["linear", "exp", "exp2"])
def test_float32_matches_fog_chunk(kind):
    rng = np.random.default_rng(3)
    p = PlayCanvasFogParams(
        type=kind, color=(0.3, 0.5, 0.7), density=0.04, start=2.0, end=70.0, nearClip=0.5, farClip=300.0
    )
    wp = np.stack([rng.uniform(-3, 3, 300), rng.uniform(-3, 3, 300), -np.exp(rng.uniform(0, 5.5, 300))], -1)
    scene = rng.uniform(0, 1, (300, 3)).astype(f32)
    out = PlayCanvasFog(p).evaluate(np.zeros(3), wp, "float32").composite(scene)
    fog_color = np.asarray([c**2.2 for c in (0.3, 0.5, 0.7)], f32)  # Color.linear on the CPU
    for i in range(300):
        f = get_fog_factor(kind, 2.0, 70.0, 0.04, frag_depth(-wp[i, 2], 0.5, 300.0))
        ref = fog_color * (f32(1) - f) + scene[i] * f  # mix(fog_color, color, fogFactor)
        np.testing.assert_allclose(out[i], ref, rtol=0, atol=2e-6)


def test_canvas_is_a_2_2_power():
    x = np.array([0.0, 0.001, 0.2, 0.5, 1.0, 3.0])
    ref = np.minimum((x + 1e-7) ** (1 / 2.2), 1.0)
    np.testing.assert_allclose(gamma_correct_output(x, np.float64), ref, rtol=1e-12)
    assert gamma_correct_output(-1.0, np.float32) == pytest.approx(1e-7 ** (1 / 2.2))


def test_background_gets_no_fog():
    fog = PlayCanvasFog(PlayCanvasFogParams(type="exp", density=1.0))
    r = fog.evaluate(np.zeros(3), np.array([[0.0, 0.6, -0.8]]) * SKY_DISTANCE, "float32")
    assert np.all(r.transmittance == 1.0) and np.all(r.inscatter == 0.0)


def test_mapping_nearest_exp():
    m = FogMedium(sigma_t=0.02, albedo=0.5, layers=(ExpLayer(1.0, 0.0, 0.0),))
    fog = from_physical("playcanvas", PhysicalScene(m, sky_radiance=(0.2, 0.4, 0.6), camera=(0.0, 0.0, 0.0)))
    assert fog.params.type == "exp" and fog.params.density == pytest.approx(0.02)
    lin = fog.evaluate(np.zeros(3), [[0.0, 0.0, -1e3]], "float64").inscatter[0]  # T = 2e-9
    assert lin == pytest.approx((0.1, 0.2, 0.3), rel=1e-8)
    # on the axis, exp(-sigma far (z - near)/(far - near)): near the physical exp(-sigma z)
    T = fog.evaluate(np.zeros(3), [[0.0, 0.0, -50.0]], "float64").transmittance[0, 0]
    assert T == pytest.approx(math.exp(-0.02 * 1000 * (50 - 0.1) / (1000 - 0.1)), rel=1e-12)
    box = FogMedium(sigma_t=0.01, layers=(ExpLayer(1.0, 0.0, 0.0),), bounds=Box((0, 0, 0), (1, 1, 1)))
    with pytest.raises(ParameterError, match="profile"):
        from_physical("playcanvas", PhysicalScene(box))


def test_registered_and_bad_input():
    assert get("playcanvas") is PlayCanvasFog
    for kw, name in (
        ({"type": "EXP"}, "type"),
        ({"density": -1.0}, "density"),
        ({"start": 3.0, "end": 3.0}, "end"),
        ({"nearClip": 0.0}, "nearClip"),
        ({"nearClip": 5.0, "farClip": 5.0}, "farClip"),
        ({"color": (1.0, math.inf, 0.0)}, "color"),
        ({"camera_forward": (0.0, 0.0, 0.0)}, "camera_forward"),
    ):
        with pytest.raises(ParameterError, match=name):
            PlayCanvasFogParams(**kw)


def test_extremes_are_finite():
    rng = np.random.default_rng(4)
    wp = rng.normal(size=(200, 3)) * 10 ** rng.uniform(-4, 9, (200, 1))
    wp = np.vstack([wp, np.zeros(3)])
    for p in (
        PlayCanvasFogParams(type="exp2", density=1e3),
        PlayCanvasFogParams(type="exp", density=0.0),
        PlayCanvasFogParams(type="linear", start=-1e6, end=1e7),
        PlayCanvasFogParams(type="linear", start=0.0, end=1e-6, nearClip=1e-6, farClip=1e9),
    ):
        for prec in ("float32", "float64"):
            r = PlayCanvasFog(p).evaluate(np.zeros(3), wp, prec)
            assert np.all(np.isfinite(r.transmittance)) and np.all(np.isfinite(r.inscatter))
            assert np.all((r.transmittance >= 0) & (r.transmittance <= 1)) and np.all(r.inscatter >= 0)
