"""Box fog (Jim's GameDev Blog, "体积雾", 2016): slab transcription, homogeneous box medium."""

import math

import numpy as np
import pytest

from fogref.mapping.engines import box_to_medium
from fogref.media import NP
from fogref.models.box import BoxFog, BoxFogParams

f32 = np.float32


def blog_box_fog(cam, wp, lo, hi, k):
    """Transcription of the box fog of Jim's GameDev Blog, "体积雾" (2016) (float32): e = camera,
    c = pixel, a/b = entry/exit of the eye ray with the box (RaySlabIntersection);
    t = |ac|, d = |cb|; fog = k t/(t+d)."""
    e = np.asarray(cam, f32)
    c = np.asarray(wp, f32)
    ray = c - e
    ray_len = np.sqrt(np.sum(ray * ray))
    dirn = ray / ray_len
    tn, tf = f32(-3e38), f32(3e38)
    for i in range(3):
        if dirn[i] == 0:
            if e[i] < lo[i] or e[i] > hi[i]:
                return f32(0)
            continue
        t1 = (f32(lo[i]) - e[i]) / dirn[i]
        t2 = (f32(hi[i]) - e[i]) / dirn[i]
        tn, tf = max(tn, min(t1, t2)), min(tf, max(t1, t2))
    if tf <= max(tn, f32(0)):
        return f32(0)
    f_ = max(tn, f32(0))  # |ea|
    s = tf  # |eb|
    lc = min(max(ray_len, f_), s)  # c clamped into [a, b]
    t, d = lc - f_, s - lc
    return np.clip(f32(k) * t / (t + d), 0, 1)


def test_float32_matches_seed_transcription():
    rng = np.random.default_rng(0)
    lo, hi = (-10.0, 0.0, -20.0), (15.0, 8.0, 5.0)
    fog = BoxFog(BoxFogParams(lo, hi, density=0.8, fog_color=(1.0, 0.5, 0.25)))
    for cam in (np.array([0.0, 2.0, 0.0]), np.array([-30.0, 4.0, 1.0]), np.array([0.0, 20.0, -3.0])):
        d = rng.normal(size=(200, 3))
        d[:30, 1] = 0.0
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        wp = cam + d * rng.uniform(0.1, 80, (200, 1))
        r = fog.evaluate(cam, wp, "float32")
        ref = np.array([blog_box_fog(cam, w, lo, hi, 0.8) for w in wp])
        np.testing.assert_allclose(1 - r.transmittance[:, 0], ref, rtol=1e-4, atol=2e-6)
        np.testing.assert_allclose(r.inscatter[:, 1], 0.5 * ref, rtol=1e-4, atol=2e-6)


def test_thickness_mode_is_the_box_medium_optical_depth():
    p = BoxFogParams((-5.0, 0.0, -5.0), (5.0, 3.0, 5.0), density=0.07, mode="beer")
    m = box_to_medium(p)
    rng = np.random.default_rng(1)
    for cam in (np.array([0.0, 1.0, 0.0]), np.array([-20.0, 2.0, 3.0]), np.array([1.0, 10.0, 1.0])):
        d = rng.normal(size=(100, 3))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        L = rng.uniform(0.1, 50, 100)
        wp = cam + d * L[:, None]
        t, _ = BoxFog(p).fog_lengths(cam, wp, "float64")
        tau = m.optical_depth(NP, tuple(cam), tuple(d.T), L)
        np.testing.assert_allclose(t, tau, rtol=1e-9, atol=1e-12)
        T = BoxFog(p).evaluate(cam, wp, "float64").transmittance[:, 0]
        np.testing.assert_allclose(T, m.transmittance(NP, tuple(cam), tuple(d.T), L)[0], rtol=1e-9)


def test_ratio_fit_matches_far_wall():
    p = BoxFogParams((0.0, 0.0, 0.0), (10.0, 4.0, 10.0), density=0.6)
    m = box_to_medium(p)
    assert 1 - math.exp(-m.sigma_t[0] * 4.0) == pytest.approx(0.6)


def test_extremes_are_finite():
    rng = np.random.default_rng(2)
    fog = BoxFog()
    for cam in (
        np.zeros(3),
        np.array([0.0, 20.0, 0.0]),
        np.array([1e5, -1e5, 3.0]),
        np.array([50.0, 10.0, 0.0]),
    ):
        d = rng.normal(size=(100, 3))
        d[:20, 1] = 0.0
        d[20:30] = [1.0, 0.0, 0.0]
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        wp = np.vstack([cam + d * 10 ** rng.uniform(-4, 7, (100, 1)), cam])
        for mode in ("ratio", "thickness", "beer"):
            for prec in ("float32", "float64"):
                r = BoxFog(BoxFogParams(mode=mode)).evaluate(cam, wp, prec)
                assert np.all(np.isfinite(r.transmittance)) and np.all(np.isfinite(r.inscatter))
