"""three.js Fog / FogExp2: fog_fragment.glsl.js transcription, the mapping, extremes."""

import dataclasses
import math

import numpy as np
import pytest

from fogref.errors import ParameterError
from fogref.mapping import PhysicalScene, from_physical
from fogref.mapping.engines import threejs_sigma
from fogref.media import ExpLayer, FogMedium
from fogref.models import SKY_DISTANCE, get
from fogref.models.threejs import ThreeFogParams, ThreeJSFog, srgb_transfer_oetf

f32 = np.float32


def fog_fragment(mode, color, near, far, density, fog_depth, frag):
    """mrdoob/three.js src/renderers/shaders/ShaderChunk/fog_fragment.glsl.js, float32, one pixel."""
    vFogDepth = f32(fog_depth)
    if mode == "FogExp2":
        fogDensity = f32(density)
        fogFactor = f32(1.0) - np.exp(-fogDensity * fogDensity * vFogDepth * vFogDepth)
    else:
        e0, e1 = f32(near), f32(far)
        t = min(max((vFogDepth - e0) / (e1 - e0), f32(0.0)), f32(1.0))
        fogFactor = t * t * (f32(3.0) - f32(2.0) * t)
    fogColor = np.asarray(color, f32)
    gl = np.asarray(frag, f32)
    return gl * (f32(1.0) - fogFactor) + fogColor * fogFactor  # mix(gl, fogColor, fogFactor)


@pytest.mark.parametrize("mode", ["Fog", "FogExp2"])
def test_float32_matches_fog_fragment(mode):
    rng = np.random.default_rng(0)
    fwd = np.array([0.2, -0.1, -1.0])
    fwd /= np.linalg.norm(fwd)
    p = ThreeFogParams(
        mode=mode, color=(0.4, 0.5, 0.6), near=5.0, far=150.0, density=0.013, camera_forward=tuple(fwd)
    )
    cam = np.array([1.0, 2.0, 3.0])
    wp = cam + rng.normal(size=(300, 3)) * 10 ** rng.uniform(-2, 3, (300, 1))
    scene = rng.uniform(0, 2, (300, 3))
    out = ThreeJSFog(p).evaluate(cam, wp, "float32").composite(scene.astype(f32))
    assert out.dtype == np.float32
    f = fwd.astype(f32)
    for i in range(300):
        v = (wp[i] - cam).astype(f32)
        depth = v[0] * f[0] + v[1] * f[1] + v[2] * f[2]  # vFogDepth = -mvPosition.z
        ref = fog_fragment(mode, (0.4, 0.5, 0.6), 5.0, 150.0, 0.013, depth, scene[i])
        np.testing.assert_allclose(out[i], ref, rtol=2e-6, atol=2e-6)


def test_depth_not_distance():
    fog = ThreeJSFog(ThreeFogParams(mode="FogExp2", density=0.01))
    r = fog.evaluate(np.zeros(3), np.array([[300.0, 0.0, -100.0], [0.0, 0.0, 100.0]]), "float64")
    assert r.transmittance[0, 0] == pytest.approx(math.exp(-1.0))  # depth 100, distance 316
    assert r.transmittance[1, 0] == pytest.approx(math.exp(-1.0))  # behind: depth -100, squared


def test_mapping_nearest_exp2():
    ps = PhysicalScene(
        FogMedium(sigma_t=0.02, albedo=0.5, layers=(ExpLayer(1.0, 0.0, 0.0),)),
        sky_radiance=(0.2, 0.4, 0.6),
        camera=(0.0, 0.0, 0.0),
    )
    fog = from_physical("threejs", ps)
    assert fog.params.mode == "FogExp2" and fog.params.density == pytest.approx(0.02)
    assert fog.params.color == pytest.approx((0.1, 0.2, 0.3))
    # the physical transmittance exp(-sigma z) is matched at z = 1/sigma on the axis only
    z = np.array([[0.0, 0.0, -1.0 / 0.02], [0.0, 0.0, -10.0], [0.0, 0.0, -200.0]])
    T = fog.evaluate(np.zeros(3), z, "float64").transmittance[:, 0]
    assert T[0] == pytest.approx(math.exp(-1.0))
    assert T[1] > math.exp(-0.2) and T[2] < math.exp(-4.0)
    assert threejs_sigma(fog.params) == pytest.approx(0.02)


def test_mapping_refuses_box_and_colour():
    from fogref.media import Box

    box = FogMedium(sigma_t=0.01, layers=(ExpLayer(1.0, 0.0, 0.0),), bounds=Box((0, 0, 0), (1, 1, 1)))
    with pytest.raises(ParameterError, match="profile"):
        from_physical("threejs", PhysicalScene(box))
    with pytest.raises(ParameterError, match="sigma_t"):
        from_physical("threejs", PhysicalScene(FogMedium(sigma_t=(0.01, 0.02, 0.03))))


def test_registered_and_bad_input():
    assert get("threejs") is ThreeJSFog
    with pytest.raises(ParameterError, match="density"):
        ThreeFogParams(density=-1.0)
    with pytest.raises(ParameterError, match="precision"):
        ThreeJSFog().evaluate(np.zeros(3), np.ones((1, 3)), "float16")


def test_extremes_are_finite():
    rng = np.random.default_rng(4)
    wp = rng.normal(size=(200, 3)) * 10 ** rng.uniform(-4, 9, (200, 1))
    wp = np.vstack([wp, np.zeros(3)])
    for p in (
        ThreeFogParams(mode="FogExp2", density=1e3),
        ThreeFogParams(mode="FogExp2", density=0.0),
        ThreeFogParams(mode="Fog", near=-1e6, far=1e7),
        ThreeFogParams(mode="Fog", near=0.0, far=1e-6),
    ):
        for prec in ("float32", "float64"):
            r = ThreeJSFog(p).evaluate(np.zeros(3), wp, prec)
            assert np.all(np.isfinite(r.transmittance)) and np.all(np.isfinite(r.inscatter))
            assert np.all((r.transmittance >= 0) & (r.transmittance <= 1)) and np.all(r.inscatter >= 0)


def test_canvas_blends_after_the_srgb_encoding():
    """meshbasic.glsl.js: colorspace_fragment (sRGBTransferOETF), then fog_fragment with the fog
    colour converted to sRGB on the CPU (LinearToSRGB), transcribed here per pixel in float32."""

    def oetf(x):  # colorspace_pars_fragment.glsl.js, float32
        x = f32(x)
        return x * f32(12.92) if x <= f32(0.0031308) else np.power(x, f32(0.41666)) * f32(1.055) - f32(0.055)

    rng = np.random.default_rng(2)
    color = (0.630, 0.026, 0.039)
    fog_srgb = [f32(c * 12.92 if c < 0.0031308 else 1.055 * c**0.41666 - 0.055) for c in color]
    p = ThreeFogParams(mode="FogExp2", color=color, density=0.3287, output="canvas")
    wp = np.stack([rng.uniform(-1, 1, 200), rng.uniform(-1, 1, 200), -rng.uniform(0.1, 8, 200)], -1)
    scene = rng.uniform(0, 1, (200, 3))
    r = ThreeJSFog(p).evaluate(np.zeros(3), wp, "float32")
    got = r.display(scene)
    for i in range(200):
        d = f32(-wp[i, 2])
        factor = f32(1.0) - np.exp(-f32(0.3287) * f32(0.3287) * d * d)
        ref = [oetf(scene[i, c]) * (f32(1) - factor) + fog_srgb[c] * factor for c in range(3)]
        np.testing.assert_allclose(got[i], ref, rtol=0, atol=3e-7)
    # the linear target's blend, encoded, is another colour (up to 40/255 on these pixels)
    linear = ThreeJSFog(dataclasses.replace(p, output="linear")).evaluate(np.zeros(3), wp, "float32")
    encoded = np.array([[oetf(v) for v in px] for px in linear.composite(scene.astype(f32))])
    assert np.abs(encoded - got).max() * 255 > 20
    # composite() is the canvas decoded back to linear (three.js's 0.41666 is not exactly 1/2.4)
    np.testing.assert_allclose(srgb_transfer_oetf(r.composite(scene), np.float64), got, atol=2e-5)


def test_background_gets_no_fog():
    """three.js draws scene.background as the clear colour or a mesh with fog: false."""
    for p in (ThreeFogParams(mode="FogExp2", density=1.0), ThreeFogParams(mode="Fog", near=0.0, far=1.0)):
        for out in ("linear", "canvas"):
            fog = ThreeJSFog(dataclasses.replace(p, output=out))
            sky = np.array([[0.6, 0.0, -0.8], [0.0, -0.6, -0.8]]) * SKY_DISTANCE
            r = fog.evaluate(np.zeros(3), sky, "float64")
            assert np.all(r.transmittance == 1.0) and np.all(r.inscatter == 0.0)
            near = fog.evaluate(np.zeros(3), sky * 0.999, "float64")
            assert np.all(near.transmittance == 0.0)
    with pytest.raises(ParameterError, match="output"):
        ThreeFogParams(output="srgb")


def test_canvas_reproduces_a_measured_threejs_pixel():
    """A pixel the real three.js 0.187.0 drew on its sRGB canvas (headless Chromium, SwiftShader):
    FogExp2 density 0.3287 at depth 3.404 m, fog colour (0.630, 0.026, 0.039), MeshBasicMaterial
    colour (0.137, 0.942, 0.128), both linear: the canvas shows (178, 103, 68).  The linear blend,
    encoded, would give (186, 146, 72)."""
    p = ThreeFogParams(mode="FogExp2", density=0.3287, color=(0.630, 0.026, 0.039), output="canvas")
    scene = np.array([[0.137, 0.942, 0.128]])
    r = ThreeJSFog(p).evaluate(np.zeros(3), [[0.0, 0.0, -3.404]])
    assert np.round(255 * r.display(scene)).tolist() == [[178.0, 103.0, 68.0]]
    linear = ThreeJSFog(dataclasses.replace(p, output="linear")).evaluate(np.zeros(3), [[0.0, 0.0, -3.404]])
    encoded = srgb_transfer_oetf(linear.composite(scene.astype(f32)), f32)
    assert np.round(255 * encoded).tolist() == [[186.0, 146.0, 72.0]]
