"""Unity altitude fog ("积分解 Unity 高度雾", 2018): transcription, mpmath quadrature, linear blend."""

import math

import mpmath
import numpy as np
import pytest

from fogref.mapping.engines import altitude_to_medium
from fogref.media import NP, PowerLawLayer
from fogref.models.altitude import AltitudeFog, AltitudeFogParams

f32 = np.float32


def blog_get_altitude_fog(cam, wp, S, E, p):
    """Transcription of ``GetAltitudeFog`` from the blog post "积分解 Unity 高度雾"
    (2018-12-17) in float32, scalar branches."""
    _FogStart, _FogEnd, _FogPower = f32(S), f32(E), f32(p)

    def integral(x, k, b):
        s, e, pp = _FogStart, _FogEnd, _FogPower
        s_bk = (s - b) / k
        y = k * x + b
        if y <= s:
            return x - s_bk
        if y >= e:
            return (e - s) / ((pp + f32(1)) * k)
        return (np.power(e - s, pp + f32(1)) - np.power(e - y, pp + f32(1))) / (
            k * (pp + f32(1)) * np.power(e - s, pp)
        )

    def integralZeroK(x, b):
        if b >= _FogEnd:
            return f32(0)
        if b <= _FogStart:
            return x
        return x * np.power((_FogEnd - b) / (_FogEnd - _FogStart), _FogPower)

    viewPos = np.asarray(cam, f32)
    distDir = np.asarray(wp, np.float64).astype(f32) - viewPos
    distDir = (np.asarray(wp, np.float64) - np.asarray(cam, np.float64)).astype(f32)
    hDist = np.sqrt(distDir[0] * distDir[0] + distDir[2] * distDir[2])
    vDist = distDir[1]
    k = vDist / hDist
    b = viewPos[1]
    if k != 0:
        return np.sqrt(f32(1) + k * k) * (integral(hDist, k, b) - integral(f32(0), k, b))
    return np.sqrt(f32(1) + k * k) * integralZeroK(hDist, b)


def test_float32_matches_seed():
    rng = np.random.default_rng(0)
    P = AltitudeFogParams(_FogStart=2.0, _FogEnd=40.0, _FogPower=1.7, _FogColor=(0.5, 0.6, 0.7, 0.02))
    cam = np.array([0.0, 10.0, 0.0])
    d = rng.normal(size=(300, 3))
    d[:60, 1] = 0.0
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    wp = cam + d * rng.uniform(0.1, 300, (300, 1))
    I = AltitudeFog(P).path_integral(cam, wp, "float32")
    ref = np.array([blog_get_altitude_fog(cam, w, 2.0, 40.0, 1.7) for w in wp])
    np.testing.assert_allclose(I, ref, rtol=1e-5, atol=1e-4)
    r = AltitudeFog(P).evaluate(cam, wp, "float32")
    op = np.clip(ref * f32(0.02), 0, 1)
    np.testing.assert_allclose(r.transmittance[:, 0], 1 - op, atol=1e-5)
    np.testing.assert_allclose(r.inscatter, np.outer(op, [0.5, 0.6, 0.7]), atol=1e-5)


def _quad(cam, wp, S, E, p):
    mpmath.mp.dps = 30
    cam = [mpmath.mpf(float(c)) for c in cam]
    w = [mpmath.mpf(float(c)) for c in wp]
    L = mpmath.sqrt(sum((a - b) ** 2 for a, b in zip(w, cam)))
    dy = (w[1] - cam[1]) / L

    def T(s):
        y = cam[1] + s * dy
        u = min(max((E - y) / (E - S), 0), 1)
        return u**p

    pts = [0, L]
    if dy != 0:
        for yb in (S, E):
            sb = (yb - cam[1]) / dy
            if 0 < sb < L:
                pts.append(sb)
    return float(mpmath.quad(T, sorted(pts)))


def test_integral_against_mpmath_quadrature():
    rng = np.random.default_rng(1)
    S, E, p = 1.0, 25.0, 2.5
    fog = AltitudeFog(AltitudeFogParams(S, E, p, (1, 1, 1, 0.01)))
    m = altitude_to_medium(fog.params)
    for cam_y in (-5.0, 10.0, 60.0):
        cam = np.array([0.0, cam_y, 0.0])
        d = rng.normal(size=(8, 3))
        d[0, 1] = 0.0
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        L = rng.uniform(1, 200, 8)
        wp = cam + d * L[:, None]
        I64 = fog.path_integral(cam, wp, "float64")
        I32 = fog.path_integral(cam, wp, "float32")
        tau = m.optical_depth(NP, tuple(cam), tuple(d.T), L) * m.sigma_t[0]
        for i in range(8):
            q = _quad(cam, wp[i], S, E, p)
            assert I64[i] == pytest.approx(q, rel=1e-9, abs=1e-12)
            assert I32[i] == pytest.approx(q, rel=2e-3, abs=2e-3)
            assert tau[i] == pytest.approx(0.01 * q, rel=1e-9, abs=1e-14)  # medium optical depth = a * I


def test_linear_blend_not_beer_lambert():
    P = AltitudeFogParams(0.0, 10.0, 1.0, (1, 1, 1, 0.05))
    cam = np.array([0.0, -1.0, 0.0])
    wp = np.array([[8.0, -1.0, 0.0]])  # fully dense: I = 8, tau = 0.4
    r = AltitudeFog(P).evaluate(cam, wp, "float64")
    assert r.transmittance[0, 0] == pytest.approx(1 - 0.4)
    T_phys = altitude_to_medium(P).transmittance(NP, tuple(cam), (1.0, 0.0, 0.0), 8.0)[0]
    assert T_phys == pytest.approx(math.exp(-0.4))


def test_power_layer_sampling_inverts_depth():
    L = PowerLawLayer(density=1.0, start=0.0, end=30.0, power=1.5)
    oy = np.array([-5.0, 5.0, 20.0, 40.0, 5.0])
    dy = np.array([0.3, -0.6, 0.9, -0.2, 0.0])
    s = np.array([3.0, 4.0, 0.5, 2.0, 0.7])
    t = L.sample(NP, oy, dy, s)
    np.testing.assert_allclose(L.depth(NP, oy, dy, t), s, rtol=1e-9)
    assert L.sample(NP, np.array(20.0), np.array(0.9), np.array(1.0)) == NP.largest  # escapes (depth 0.855)


def test_vertical_and_extreme_rays_are_finite():
    fog = AltitudeFog()
    rng = np.random.default_rng(2)
    for cam_y in (-1e4, 0.0, 25.0, 1e5):
        cam = np.array([0.0, cam_y, 0.0])
        d = rng.normal(size=(100, 3))
        d[:10] = [0.0, 1.0, 0.0]
        d[10:20] = [0.0, -1.0, 0.0]
        d[20:30, 1] = 0.0
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        wp = np.vstack([cam + d * 10 ** rng.uniform(-4, 7, (100, 1)), cam])
        for prec in ("float32", "float64"):
            r = fog.evaluate(cam, wp, prec)
            assert np.all(np.isfinite(r.transmittance)) and np.all(np.isfinite(r.inscatter))


def _mp_power_integral(cam, wp, S, E, p):
    """I = int T ds in 60 digits, the power piece without G(y1) - G(y0) cancellation."""
    mpmath.mp.dps = 60
    c = [mpmath.mpf(float(x)) for x in cam]
    w = [mpmath.mpf(float(x)) for x in wp]
    S, E, p = mpmath.mpf(S), mpmath.mpf(E), mpmath.mpf(p)
    L = mpmath.sqrt(sum((a - b) ** 2 for a, b in zip(w, c)))
    dy = w[1] - c[1]
    if dy == 0:
        return L * (1 if c[1] <= S else (0 if c[1] >= E else ((E - c[1]) / (E - S)) ** p))
    lo, hi = min(c[1], w[1]), max(c[1], w[1])
    ya, yb = max(lo, S), min(hi, E)
    power = 0
    if yb > ya:
        power = (E - S) / (p + 1) * ((E - ya) / (E - S)) ** (p + 1) * (1 - ((E - yb) / (E - ya)) ** (p + 1))
    return (max(0, min(hi, S) - lo) + power) * L / abs(dy)


def test_float64_near_fog_end_and_near_horizontal():
    """Regressions: G(y1) - G(y0) cancelled near _FogEnd (100 % error, camera at 1e6 m)
    and the old midpoint rule for near-horizontal rays (25 % error)."""
    fog = AltitudeFog(AltitudeFogParams(0.0, 1e6, 2.0, (1, 1, 1, 1.0)))
    cam = np.array([0.0, 1e6, 0.0])
    wp = np.array(
        [
            [0.0, 1e6 - 0.2, 0.0],
            [30.0, 1e6 - 1e-6, 0.0],
            [1e3, 1e6 - 1e-4, 0.0],
            [1e6, 1e6 - 0.1, 0.0],
            [0.0, 5e5, 0.0],
        ]
    )
    I = fog.path_integral(cam, wp, "float64")
    for i in range(len(wp)):
        assert I[i] == pytest.approx(float(_mp_power_integral(cam, wp[i], 0.0, 1e6, 2.0)), rel=1e-13, abs=0)
    fog = AltitudeFog(AltitudeFogParams(0.0, 10.0, 2.0, (1, 1, 1, 1.0)))
    cam = np.array([0.0, 5.0, 0.0])
    wp = np.array([[1e7, 5.0 + 5e-7 * s, 0.0] for s in (-9.0, -1.0, 0.0, 1.0, 9.0)])  # cross 0 and 10 m
    I = fog.path_integral(cam, wp, "float64")
    for i in range(len(wp)):
        assert I[i] == pytest.approx(float(_mp_power_integral(cam, wp[i], 0.0, 10.0, 2.0)), rel=1e-13, abs=0)
