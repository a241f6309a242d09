"""Filament fog: a surface_fog.fs (1.53.4) transcription and the exponential medium (exp, not exp2)."""

import math

import numpy as np
import pytest

from fogref.display import srgb_encode
from fogref.mapping import PhysicalScene
from fogref.mapping.engines import filament_from_physical, filament_to_medium
from fogref.media import NP
from fogref.models.filament import FilamentFog, FilamentFogParams, aces_legacy, colour_grade

f32 = np.float32


def filament_fog_fs(cam, wp, o, scene):
    """surface_fog.fs (Filament 1.53.4, the GLSL in its filament.wasm) + prepareFog, float32, one pixel."""
    y = f32(-o["heightFalloff"]) * (f32(cam[1]) - f32(o["height"]))
    density = (f32(o["density"]), y, f32(o["density"]) * np.exp(y))  # frameUniforms.fogDensity
    view = (np.asarray(wp) - np.asarray(cam)).astype(f32)
    falloff = f32(o["heightFalloff"])
    fi = density[2]  # fogOpticalPathAtOneMeter
    h = falloff * view[1]
    if abs(h) > f32(0.00125):
        with np.errstate(over="ignore"):  # exp overflows far below the camera: inf, as on the GPU
            fi = (density[2] - density[0] * np.exp(density[1] - h)) / h
    d = np.sqrt(np.sum(view * view))
    fogIntegral = fi * max(d - f32(o["distance"]), f32(0))
    fogOpacity = min(f32(1) - np.exp(-fogIntegral), f32(o["maximumOpacity"]))
    fogColor = np.asarray(o["color"], f32) * fogOpacity
    if o["inScatteringSize"] > 0:
        insc = fi * max(d - f32(o["inScatteringStart"]), f32(0))
        inscOpacity = f32(1) - np.exp(-insc)
        sunColor = np.asarray(o["sun"], f32)
        sunAmount = max(f32(np.dot(view, np.asarray(o["l"], f32))) / d, f32(0))
        fogColor = fogColor + sunColor * (np.power(sunAmount, f32(o["inScatteringSize"])) * inscOpacity)
    return np.asarray(scene, f32) * (f32(1) - fogOpacity) + fogColor


def test_float32_matches_fog_fs():
    rng = np.random.default_rng(0)
    l = np.array([0.2, 0.7, -0.3])
    l /= np.linalg.norm(l)
    o = dict(
        density=0.05,
        heightFalloff=0.3,
        height=2.0,
        distance=4.0,
        maximumOpacity=0.9,
        color=(0.5, 0.6, 0.7),
        inScatteringStart=10.0,
        inScatteringSize=8.0,
        l=l,
        sun=(2.0, 1.8, 1.5),
    )
    p = FilamentFogParams(
        density=0.05,
        heightFalloff=0.3,
        height=2.0,
        distance=4.0,
        maximumOpacity=0.9,
        color=(0.5, 0.6, 0.7),
        inScatteringStart=10.0,
        inScatteringSize=8.0,
        lightDirection=tuple(l),
        lightColorIntensity=(1.0, 0.9, 0.75, 2.0),
    )
    cam = np.array([0.0, 3.0, 0.0])
    d = rng.normal(size=(200, 3))
    d[:40, 1] = 0
    d[40:80, 1] *= 1e-3
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    wp = cam + d * 10 ** rng.uniform(-1, 3, (200, 1))
    scene = rng.uniform(0, 1, (200, 3))
    out = FilamentFog(p).evaluate(cam, wp, "float32").composite(scene.astype(f32))
    for i in range(200):
        np.testing.assert_allclose(out[i], filament_fog_fs(cam, wp[i], o, scene[i]), rtol=2e-5, atol=2e-6)


def test_float64_equals_exponential_medium():
    p = FilamentFogParams(density=0.02, heightFalloff=0.15, height=-1.0)
    m = filament_to_medium(p)
    rng = np.random.default_rng(1)
    cam = np.array([0.0, 4.0, 0.0])
    d = rng.normal(size=(300, 3))
    d[:50, 1] = 0
    d[50:100, 1] *= 1e-5
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    L = 10 ** rng.uniform(-2, 3, 300)
    T = FilamentFog(p).evaluate(cam, cam + d * L[:, None], "float64").transmittance[:, 0]
    np.testing.assert_allclose(T, m.transmittance(NP, tuple(cam), tuple(d.T), L)[0], rtol=1e-9, atol=1e-300)
    q = filament_from_physical(PhysicalScene(m)).params
    assert (q.density, q.heightFalloff, q.height) == pytest.approx((0.02, 0.15, -1.0))
    # exp, not exp2: a horizontal ray at the fog height has T = exp(-density L)
    T1 = (
        FilamentFog(FilamentFogParams(density=0.02, heightFalloff=0.15, height=0.0))
        .evaluate(np.zeros(3), np.array([[100.0, 0, 0]]), "float64")
        .transmittance[0, 0]
    )
    assert T1 == pytest.approx(math.exp(-2.0))


def test_extremes_are_finite():
    rng = np.random.default_rng(2)
    fog = FilamentFog(FilamentFogParams(inScatteringSize=4.0, cutOffDistance=1e6))
    for cam_y in (-1e3, 0.0, 50.0, 1e5):
        cam = np.array([0.0, cam_y, 0.0])
        d = rng.normal(size=(100, 3))
        d[:20, 1] = 0
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        wp = np.vstack([cam + d * 10 ** rng.uniform(-4, 7, (100, 1)), cam])
        for prec in ("float32", "float64"):
            r = fog.evaluate(cam, wp, prec)
            assert np.all(np.isfinite(r.transmittance)) and np.all(np.isfinite(r.inscatter))


# --- the canvas: Filament's default colour grading (ACES legacy), an independent transcription ---


def _npm(primaries, white):
    """RGB -> XYZ of the primaries' and white's xy chromaticities (SMPTE RP 177), float64."""
    xyz = np.array([[x / y, 1.0, (1.0 - x - y) / y] for x, y in primaries]).T
    w = np.array([white[0] / white[1], 1.0, (1.0 - white[0] - white[1]) / white[1]])
    return xyz * np.linalg.solve(xyz, w)


D65, ACES_WHITE = (0.3127, 0.3290), (0.32168, 0.33767)
SRGB = _npm([(0.64, 0.33), (0.30, 0.60), (0.15, 0.06)], D65)
REC2020 = _npm([(0.708, 0.292), (0.170, 0.797), (0.131, 0.046)], D65)
AP0 = _npm([(0.7347, 0.2653), (0.0, 1.0), (0.0001, -0.077)], ACES_WHITE)
AP1 = _npm([(0.713, 0.293), (0.165, 0.830), (0.128, 0.044)], ACES_WHITE)


def aces_legacy_reference(rec2020):
    """Filament's ``ACESLegacyToneMapper`` (``aces::ACES(c, 1/0.6)``) of one Rec.2020 colour, float64,
    written from the ACES 1.0 RRT (CTL ``ACESlib.RRT_Common``: glow, red modifier, RRT_SAT 0.96),
    the RRT + ODT rational fit ``x (a x + b) / (x (c x + d) + e)`` of colour-science's colour-unity
    notebook (a..e = 2.785085, 0.107772, 2.936045, 0.887122, 0.806889), the dim-surround gamma 0.9811
    on Y and ODT_SAT 0.93; matrices from the primaries' chromaticities (Filament converts between
    Rec.2020 and AP0/AP1 without a white-point adaptation, so neither does this)."""
    ap0 = np.linalg.solve(AP0, REC2020 @ np.asarray(rec2020, float))
    sat = (max(ap0.max(), 1e-5) - max(ap0.min(), 1e-5)) / max(ap0.max(), 1e-2)
    r, g, b = ap0
    yc = (r + g + b + 1.75 * math.sqrt(max(b * (b - g) + g * (g - r) + r * (r - b), 0.0))) / 3.0
    x = (sat - 0.4) / 0.2
    s = (1.0 + math.copysign(1.0, x) * (1.0 - max(1.0 - abs(x) / 2.0, 0.0) ** 2)) / 2.0 if x else 0.5
    gain = 0.05 * s
    glow = gain if yc <= 0.08 * 2 / 3 else 0.0 if yc >= 0.16 else gain * (0.08 / yc - 0.5)
    ap0 = ap0 * (1.0 + glow)
    r, g, b = ap0
    hue = 0.0 if r == g == b else math.degrees(math.atan2(math.sqrt(3.0) * (g - b), 2 * r - g - b)) % 360.0
    hue = hue - 360.0 if hue > 180.0 else hue
    t = min(max(1.0 - abs(2.0 * hue / 135.0), 0.0), 1.0)
    ap0[0] += (t * t * (3 - 2 * t)) ** 2 * sat * (0.03 - ap0[0]) * (1.0 - 0.82)
    ap1 = np.clip(np.linalg.solve(AP1, AP0 @ ap0), 0.0, 65504.0)
    lum = AP1[1]  # AP1's luminance weights: the Y row of its RGB -> XYZ
    ap1 = (lum @ ap1 + 0.96 * (ap1 - lum @ ap1)) / 0.6
    post = ap1 * (2.785085 * ap1 + 0.107772) / (ap1 * (2.936045 * ap1 + 0.887122) + 0.806889)
    X, Y, Z = AP1 @ post
    cx, cy = X / max(X + Y + Z, 1e-5), Y / max(X + Y + Z, 1e-5)
    Y = min(max(Y, 0.0), 65504.0) ** 0.9811
    lin = np.linalg.solve(AP1, np.array([cx * Y / max(cy, 1e-5), Y, (1 - cx - cy) * Y / max(cy, 1e-5)]))
    lin = lum @ lin + 0.93 * (lin - lum @ lin)
    return np.linalg.solve(REC2020, AP1 @ lin)


COLOURS = [(0.0, 0.0, 0.0), (0.18, 0.18, 0.18), (1.0, 1.0, 1.0), (0.9, 0.1, 0.05), (0.02, 0.3, 0.8),
           (0.5, 0.45, 0.01), (6.0, 4.0, 3.0), (0.001, 0.002, 0.0015), (40.0, 1.0, 0.2)]  # fmt: skip


def test_aces_legacy_matches_an_independent_transcription():
    """The port's ``aces_legacy`` (float32, Filament's 7-digit matrices) against the float64 reference
    above (matrices from chromaticities): within 2e-4 absolute on outputs in [0, 1] (1.2e-4
    measured; a twentieth of an 8-bit step of the sRGB canvas at mid-grey).  A slip is seen:
    Filament's brightness 1 (its non-legacy ACES) instead of 1/0.6 moves them by 0.19."""
    got = aces_legacy(np.array(COLOURS)).astype(np.float64)
    want = np.array([aces_legacy_reference(c) for c in COLOURS])
    assert np.abs(got - want).max() < 2e-4, np.abs(got - want).max()
    # a slip is seen: Filament's non-legacy ACES (brightness 1, the input scaled by 0.6 here)
    assert np.abs(got - [aces_legacy_reference(np.array(c) * 0.6) for c in COLOURS]).max() > 1e-2


def test_canvas_is_the_tone_mapped_srgb_image_at_the_lut_nodes():
    """``colour_grade`` (LogC-indexed 32^3 LUT, 10-bit entries, trilinear) at colours on the LUT's
    nodes (Alexa LogC EI 1000, ``(10^((i/31 - d)/c) - b)/a``, floored at 0) against the curve it
    samples, ``OETF_sRGB(saturate(Rec2020_to_sRGB * aces_legacy(sRGB_to_Rec2020 * x)))`` evaluated
    directly (float64, the matrices from chromaticities; ``aces_legacy`` the port's, held to the
    reference above by the test before): within 0.3 of an 8-bit step (0.15 measured; the entries'
    10-bit rounding is 0.125) where the tone-mapped linear sRGB is >= 0.02 in every channel (below,
    matrices 1e-4 apart are magnified by the OETF's toe).  Between nodes the trilinear LUT departs
    from the curve by up to ~5 steps on saturated colours, as the engine's does.  Without the tone
    mapping (the sRGB encoding of the clamped linear colour) the canvas differs by more than 20
    steps (255 measured); nodes half a texel off, by more than 1 (24 measured)."""

    def node(i):
        return (10.0 ** ((np.asarray(i) / 31 - 0.386036) / 0.244161) - 0.047996) / 5.555556

    i = np.random.default_rng(5).integers(0, 32, (300, 3))
    x = np.maximum(node(i), 0.0)  # nodes 0 and 1 are below 0: Filament's LUT floors them
    to2020 = np.linalg.solve(REC2020, SRGB)
    linear = np.linalg.solve(to2020, aces_legacy(x @ to2020.T).astype(np.float64).T).T
    keep = linear.min(axis=-1) >= 0.02
    assert keep.sum() > 100
    want = srgb_encode(linear[keep])
    got = colour_grade(x[keep]).astype(np.float64)
    assert np.abs(got - want).max() * 255 < 0.3, np.abs(got - want).max() * 255
    assert np.abs(srgb_encode(x[keep]) - got).max() * 255 > 20
    assert np.abs(colour_grade(node(i[keep] + 0.5)).astype(np.float64) - want).max() * 255 > 1
