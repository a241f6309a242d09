"""The Local Fog Volume's closed-form optical depth and free flight against independent references.

* optical depth: mpmath quadrature (50 digits) of the density written out here, over rays
  through, tangent to and missing the sphere, starting inside and outside, ending inside,
  level, rising and falling, falloff 0 and not; agreement to 1e-11 relative (float64);
* free flight: the round trip ``depth(sample(s)) == s`` to 1e-13 of the ray's total depth, and a KS test of
  sampled distances against the closed-form CDF ``1 - exp(-sigma tau(t))``;
* float32 (Dr.Jit): the same depths within 1e-4 relative of float64, distances within 1e-5 R;
  free flight's symbolic loop (``iterate``, leaving at a fixed point) bit for bit the steps
  unrolled, on rays whose lanes stop early and rays that run every step;
* Unreal's volume (``ue5_lfv``) with only its radial term visible: the same transmittance as the
  sphere mapped from its parameters (centre, radius, axes), 1e-9 relative.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
from scipy import stats

from fogref.errors import ParameterError
from fogref.media import NP, local_fog_volume
from fogref.media.local_fog_volume import LocalFogVolume, exp_moments, iterate

mpmath.mp.dps = 50


def density_mp(v: LocalFogVolume, o, d, t):
    """The density along the ray, written from the definition (independent of the module)."""
    p = [mpmath.mpf(o[a]) + t * mpmath.mpf(d[a]) for a in range(3)]
    r2 = sum((p[a] - mpmath.mpf(v.centre[a])) ** 2 for a in range(3))
    radial = max(1 - r2 / mpmath.mpf(v.radius) ** 2, 0)
    return v.density * radial * mpmath.exp(-mpmath.mpf(v.falloff) * (p[1] - v.height))


def depth_mp(v: LocalFogVolume, o, d, t_end) -> float:
    """Quadrature over [0, t_end] split at the chord ends (where the integrand has a kink)."""
    q = [mpmath.mpf(o[a]) - v.centre[a] for a in range(3)]
    b = sum(q[a] * d[a] for a in range(3))
    disc = b * b - (sum(x * x for x in q) - mpmath.mpf(v.radius) ** 2)
    if disc <= 0:
        return 0.0
    lo, hi = max(-b - mpmath.sqrt(disc), 0), min(-b + mpmath.sqrt(disc), mpmath.mpf(t_end))
    if hi <= lo:
        return 0.0
    return float(mpmath.quad(lambda t: density_mp(v, o, d, t), [lo, (lo + hi) / 2, hi]))


def unit(*xs):
    n = math.sqrt(sum(x * x for x in xs))
    return tuple(x / n for x in xs)


VOLUMES = [
    LocalFogVolume(centre=(1.0, 2.0, -3.0), radius=5.0, density=0.7, falloff=0.0, height=0.0),
    LocalFogVolume(centre=(1.0, 2.0, -3.0), radius=5.0, density=0.7, falloff=0.3, height=1.5),
    LocalFogVolume(centre=(0.0, 50.0, 0.0), radius=40.0, density=2.0, falloff=0.2, height=30.0),
    LocalFogVolume(centre=(0.0, 0.0, 0.0), radius=1.0, density=1.0, falloff=1e-9, height=0.0),
]
# (origin, direction, end): relative to a volume of centre c and radius R, in units of R
RAYS = [
    ((-3.0, 0.0, 0.0), (1.0, 0.0, 0.0), math.inf),  # level, through the centre
    ((-3.0, -2.0, 0.2), unit(1.0, 0.7, 0.0), math.inf),  # rising, off centre
    ((-3.0, 2.0, 0.2), unit(1.0, -0.7, 0.1), math.inf),  # falling
    ((0.0, -3.0, 0.0), (0.0, 1.0, 0.0), math.inf),  # vertical up
    ((0.0, 3.0, 0.1), (0.0, -1.0, 0.0), math.inf),  # vertical down
    ((0.2, 0.1, -0.3), unit(0.3, -0.5, 1.0), math.inf),  # starts inside
    ((0.2, 0.1, -0.3), unit(0.3, 0.5, 1.0), 0.4),  # starts and ends inside
    ((-3.0, 0.3, 0.0), (1.0, 0.0, 0.0), 2.5),  # ends inside
    ((-3.0, 0.999, 0.0), (1.0, 0.0, 0.0), math.inf),  # grazing: a short chord
    ((-3.0, 1.0, 0.0), (1.0, 0.0, 0.0), math.inf),  # tangent: nothing
    ((-3.0, 1.5, 0.0), (1.0, 0.0, 0.0), math.inf),  # misses
    ((3.0, 0.0, 0.0), (1.0, 0.0, 0.0), math.inf),  # sphere behind the origin
    ((-3.0, 0.0, 0.0), (1.0, 0.0, 0.0), 1.0),  # stops before the sphere
]


def ray_in(v, ray):
    o_u, d, end = ray
    o = tuple(v.centre[a] + v.radius * o_u[a] for a in range(3))
    return o, d, (NP.largest if math.isinf(end) else end * v.radius)


@pytest.mark.parametrize("v", VOLUMES)
def test_optical_depth_matches_quadrature(v):
    for ray in RAYS:
        o, d, t = ray_in(v, ray)
        got = float(v.optical_depth(NP, o, d, t))
        ref = depth_mp(v, o, d, 1e300 if t == NP.largest else t)
        assert got == pytest.approx(ref, rel=1e-11, abs=1e-300), (v, ray, got, ref)
        assert math.isfinite(got) and got >= 0.0


def test_chord_depth_known_values():
    """A level ray through the centre of a constant sphere: 4/3 R density (1 - x^2 integrated)."""
    v = LocalFogVolume(centre=(0.0, 0.0, 0.0), radius=2.0, density=3.0)
    assert float(v.optical_depth(NP, (-5.0, 0.0, 0.0), (1.0, 0.0, 0.0), NP.largest)) == pytest.approx(8.0)
    assert float(v.optical_depth(NP, (-5.0, 2.0, 0.0), (1.0, 0.0, 0.0), NP.largest)) == 0.0


def test_exp_moments_series_and_closed_forms_join():
    """E_n from mpmath on both sides of the switch and far out (relative 1e-13)."""
    for x in (0.0, 1e-6, 0.5, 1.999999, 2.0, 2.000001, 7.0, 80.0, 800.0):
        got = exp_moments(NP, np.float64(x))
        for n in range(3):
            ref = mpmath.quad(lambda u, n=n: u**n * mpmath.exp(-x * u), [0, 1])
            assert float(got[n]) == pytest.approx(float(ref), rel=1e-13), (x, n)


@pytest.mark.parametrize("v", VOLUMES[:3])
def test_sample_round_trip(v):
    """``depth(sample(s)) == s`` below the ray's total depth, ``largest`` above it."""
    for ray in RAYS:
        o, d, _ = ray_in(v, ray)
        total = float(v.optical_depth(NP, o, d, NP.largest))
        s = np.array([0.0, 1e-30, 1e-9, 0.1, 0.5, 0.9, 0.999999, 1.5]) * total
        t = v.sample(NP, o, d, s)
        inside = s < total
        assert np.all(t[~inside] == NP.largest)
        back = v.optical_depth(NP, o, d, np.where(inside, t, 0.0))
        assert np.all(np.abs(back[inside] - s[inside]) <= 1e-13 * total)


def test_free_flight_distribution_ks():
    """Sampled collision distances follow ``P(t_c <= t) = 1 - exp(-sigma tau(t))``.

    n = 20000 Exp(1) variates (seed fixed); the escape fraction and the KS statistic of the
    collisions' CDF values (uniform on [0, F_max]) are checked.  Smallest error detected: a
    CDF off by 0.014 (KS, p < 1e-3), an escape probability off by 0.011 (4 sigma).
    """
    v = VOLUMES[2]
    o, d, _ = ray_in(v, RAYS[2])
    sigma = 0.05  # [1/m]
    rng = np.random.default_rng(7)
    n = 20000
    t = v.sample(NP, o, d, rng.exponential(size=n) / sigma)
    f_max = 1.0 - math.exp(-sigma * float(v.optical_depth(NP, o, d, NP.largest)))
    assert 0.2 < f_max < 0.8  # the test ray meets a useful amount of fog
    hit = t < NP.largest
    p_hit = hit.mean()
    assert abs(p_hit - f_max) < 4.0 * math.sqrt(f_max * (1 - f_max) / n)
    cdf = -np.expm1(-sigma * v.optical_depth(NP, o, d, t[hit])) / f_max
    assert stats.kstest(cdf, "uniform").pvalue > 1e-3


def test_drjit_float32_matches_float64():
    """The Dr.Jit float32 form agrees with numpy float64: depths to 1e-4 relative (plus 1e-7 R),
    free-flight distances to 1e-5 R (measured: 3e-7 R)."""
    pytest.importorskip("drjit")
    from drjit.llvm import Float

    import fogref
    from fogref.media import drjit_ops

    fogref.ensure_llvm()
    D = drjit_ops(Float)
    for v in VOLUMES[:3]:
        rays = [ray_in(v, r) for r in RAYS]
        o = [np.array([r[0][a] for r in rays], np.float32) for a in range(3)]
        d = [np.array([r[1][a] for r in rays], np.float32) for a in range(3)]
        o64, d64 = [x.astype(np.float64) for x in o], [x.astype(np.float64) for x in d]
        ref = v.optical_depth(NP, o64, d64, NP.largest)
        got = v.optical_depth(D, [Float(x) for x in o], [Float(x) for x in d], D.largest).numpy()
        assert np.all(np.isfinite(got))
        assert np.allclose(got, ref, rtol=1e-4, atol=1e-7 * v.radius * v.density), (got, ref)
        s = (0.4 * ref).astype(np.float32)  # free flight to 40 % of each ray's depth
        t32 = v.sample(D, [Float(x) for x in o], [Float(x) for x in d], Float(s)).numpy()
        t64 = v.sample(NP, o64, d64, s.astype(np.float64))
        meets = ref > 0
        assert np.all(t32[~meets] >= D.largest) and np.all(t64[~meets] == NP.largest)
        assert np.allclose(t32[meets], t64[meets], rtol=0.0, atol=1e-5 * v.radius), (t32, t64)


def _llvm_ops():
    pytest.importorskip("drjit")
    from drjit.llvm import Float

    import fogref
    from fogref.media import drjit_ops

    fogref.ensure_llvm()
    return drjit_ops(Float), Float


def _unrolled(ops, step, state, iterations):
    """``iterate``'s numpy form (a Python loop) on Dr.Jit arrays: the steps traced one after another."""
    for _ in range(iterations):
        state = step(*state)
    return state


def test_iterate_drjit_counts_steps_and_stops_at_a_fixed_point():
    """Dr.Jit's loop runs exactly ``iterations`` steps where no fixed point comes (a counter:
    one step more or less shows), and stops at one bit for bit where the steps unrolled end
    (Newton for sqrt(a), float32, 24 steps: fixed after about 6)."""
    D, Float = _llvm_ops()
    (n,) = iterate(D, lambda x: (x + 1.0,), (Float([0.0, 5.0]),), 64)
    assert n.numpy().tolist() == [64.0, 69.0]
    a = Float(np.geomspace(1e-6, 1e6, 101, dtype=np.float32))

    def newton(x):
        return (0.5 * (x + a / x),)

    (loop,) = iterate(D, newton, (a,), 24)
    (unrolled,) = _unrolled(D, newton, (a,), 24)
    assert np.array_equal(loop.numpy().view(np.uint32), unrolled.numpy().view(np.uint32))
    assert np.allclose(loop.numpy(), np.sqrt(a.numpy()), rtol=2e-7)


def test_drjit_free_flight_loop_is_the_unrolled_steps_bit_for_bit(monkeypatch):
    """``sample`` in Dr.Jit's loop equals the same steps unrolled, every bit, on 4096 random
    rays from inside and around each volume with free-flight depths from 0 and 1e-8 to 10
    (24 steps, so that some lanes leave the loop at a fixed point and tiny depths run all 24).
    Detects one differing bit in one lane."""
    D, Float = _llvm_ops()
    rng = np.random.default_rng(7)
    n = 4096
    for v in VOLUMES[:3]:
        o = [(v.centre[a] + v.radius * rng.uniform(-2.0, 2.0, n)).astype(np.float32) for a in range(3)]
        d = rng.normal(size=(3, n))
        d = (d / np.linalg.norm(d, axis=0)).astype(np.float32)
        s = (v.radius * v.density * 10.0 ** rng.uniform(-8.0, 1.0, n)).astype(np.float32)
        s[:64] = 0.0
        args = ([Float(x) for x in o], [Float(x) for x in d], Float(s))
        loop = v.sample(D, *args, iterations=24).numpy()
        with monkeypatch.context() as m:
            m.setattr(local_fog_volume, "iterate", _unrolled)
            unrolled = v.sample(D, *args, iterations=24).numpy()
        assert np.sum(loop < D.largest) > n // 20  # enough rays collide in the volume
        assert np.array_equal(loop.view(np.uint32), unrolled.view(np.uint32))


@pytest.mark.parametrize(
    "kw, name",
    [
        ({"radius": 0.0}, "radius"),
        ({"density": -1.0}, "density"),
        ({"falloff": math.nan}, "falloff"),
        ({"centre": (0.0, math.inf, 0.0)}, "centre"),
        ({"height": 1e8}, "height"),
    ],
)
def test_bad_parameters_name_themselves(kw, name):
    with pytest.raises(ParameterError, match=f"parameter '{name}'"):
        LocalFogVolume(**kw)


def test_unreal_radial_term_maps_to_the_sphere():
    """Unreal's volume (``ue5_lfv``, float64) with a height term so thick that its coverage is 1
    shows only the radial term, ``T = exp(-3/4 RadialFogExtinction int (1 - |u|^2) dt)``: the
    same as a :class:`LocalFogVolume` with ``centre = (X, Z, Y) / 100``, ``radius = S / 100`` and
    ``density = 3/4 RadialFogExtinction`` (falloff 0), for rays in several directions (rel 1e-9)."""
    from fogref.models.ue_local_fog_volume import UELocalFogVolume, UELocalFogVolumeParams

    ue = UELocalFogVolume(
        UELocalFogVolumeParams(
            Location=(300.0, -200.0, 500.0),
            FogUniformScale=400.0,
            RadialFogExtinction=0.8,
            HeightFogExtinction=1e6,
            GlobalStartDistance=0.0,
        )
    )
    v = LocalFogVolume(centre=(3.0, 5.0, -2.0), radius=4.0, density=0.6)
    camera = np.array([-4.0, 3.0, 1.0])
    # through the sphere at several offsets from its centre, ending beyond it and inside it
    aims = np.array([[3.0, 5.0, -2.0], [4.0, 6.5, -1.0], [2.0, 3.0, -3.5], [3.5, 7.0, 0.0]])
    ends = np.concatenate([camera + 2.0 * (aims - camera), camera + 0.9 * (aims - camera)])
    T_ue = ue.evaluate(camera, ends, "float64").transmittance[:, 0]
    for end, t_ue in zip(ends, T_ue):
        d = (end - camera) / np.linalg.norm(end - camera)
        tau = float(v.optical_depth(NP, tuple(camera), tuple(d), float(np.linalg.norm(end - camera))))
        assert 0.05 < tau < 20.0
        assert t_ue == pytest.approx(math.exp(-tau), rel=1e-9)
