"""numpy float64 and Dr.Jit float32 forms of every closed form agree.

Inputs are float32-representable, so both back ends see the same numbers.  The
bound, per element, away from saturation (reference < 1e28) and underflow::

    |f32 - f64| <= 8 * (sens + 4 eps32 |f64|) + 1e-37,   eps32 = 2**-24

where ``sens`` is the float64 change of the result when every input (and the
heights they are compared with) is perturbed by one float32 rounding (relative
eps32): the float32 form is thus backward stable.  With O(1) exponents this is
a relative error of ~1e-6; at |exponents| ~ 100 the conditioning dominates.
Saturated/escape cases must be saturated/escape in both or carry a large
``sens``.  Everything must be finite.
"""

from __future__ import annotations

import numpy as np
import pytest
from drjit.llvm import Float  # noqa: E402

import fogref
from fogref.media import NP, ExpLayer, HDRPLayer, PowerLawLayer, drjit_ops  # noqa: E402
from fogref.media import closed_form as cf  # noqa: E402

fogref.ensure_llvm()  # Dr.Jit's LLVM back end needs LLVM >= 16; before the first array
D = drjit_ops(Float)
EPS32 = 2.0**-24
L32 = float(np.finfo(np.float32).max)


def f32(x):
    return np.asarray(x, dtype=np.float32)


def to64(x):
    x = np.asarray(x, dtype=np.float64)
    return np.where(x >= L32, NP.largest, x)


def run32(fn, *args):
    out = fn(D, *[Float(f32(a)) for a in args])
    out = out.numpy() if hasattr(out, "numpy") else np.full(len(args[0]), out, np.float32)
    return np.asarray(out, dtype=np.float64)


def compare(fn, args, shift=None, name=""):
    """fn(ops, *args) in both back ends; args are float32 arrays.  ``shift[i]``:
    extra absolute perturbation scale of input i (e.g. |height| for oy)."""
    args = [f32(a) for a in args]
    a64 = [to64(a) for a in args]
    ref = np.asarray(fn(NP, *a64), dtype=np.float64)
    got = run32(fn, *args)
    assert np.all(np.isfinite(got)), (name, np.asarray(args)[:, ~np.isfinite(got)])
    assert np.all(np.isfinite(ref)), name
    sens = np.zeros_like(ref)
    for i in range(len(a64)):
        scale = np.abs(a64[i]) + (0.0 if shift is None else shift[i])
        for sgn in (1, -1):
            pert = list(a64)
            pert[i] = np.where(a64[i] >= NP.largest, a64[i], a64[i] + sgn * EPS32 * scale)
            sens = np.maximum(sens, np.abs(np.asarray(fn(NP, *pert)) - ref))
    ok_range = (np.abs(ref) < 1e28) & (np.abs(got) < 1e28)
    bound = 8 * (sens + 4 * EPS32 * np.abs(ref)) + 1e-37
    bad = ok_range & ~(np.abs(got - ref) <= bound)
    assert not bad.any(), (name, [a[bad][:5] for a in a64], got[bad][:5], ref[bad][:5], bound[bad][:5])
    # saturation/escape must agree unless ill-conditioned
    sat_mismatch = ((np.abs(ref) >= 1e28) != (np.abs(got) >= 1e28)) & (sens < 1e-3 * np.abs(ref))
    sat_mismatch &= ~((np.abs(ref) > 1e27) & (np.abs(got) > 1e27))
    assert not sat_mismatch.any(), (
        name,
        [a[sat_mismatch][:5] for a in a64],
        got[sat_mismatch][:5],
        ref[sat_mismatch][:5],
    )
    return np.max(np.where(ok_range & (ref != 0), np.abs(got - ref) / np.where(ref != 0, np.abs(ref), 1), 0))


def grid(rng, n):
    """Random rays including extreme inputs: heights, directions, distances."""
    oy = np.concatenate(
        [
            rng.uniform(-1e4, 1e6, n // 4),
            rng.uniform(-200, 400, n // 2),
            np.array([0, 10, 100, -20, 5, 300, 1e6, -1e4] * (n // 32 + 1))[: n - 3 * (n // 4)],
        ]
    )
    dy = rng.choice(np.array([0.0, 1e-7, -1e-7, 1.0, -1.0, 3e-4, -3e-4, 0.5, -0.5]), n)
    dy = np.where(rng.random(n) < 0.4, rng.uniform(-1, 1, n), dy)
    t = 10.0 ** rng.uniform(-4, 7, n)
    t = np.where(rng.random(n) < 0.1, L32, t)
    return f32(oy), f32(dy), f32(t)


def test_phi_psi_hg():
    x = f32(
        np.concatenate(
            [
                [0, 1e-30, -1e-30, 1e-7, -1e-7, 1, -1, 80, -80, -87, -88, -100, 1e30, L32],
                np.sign(np.random.default_rng(0).normal(size=400))
                * 10.0 ** np.random.default_rng(1).uniform(-8, 2.2, 400),
            ]
        )
    )
    compare(cf.phi, [x], name="phi")
    z = f32(
        np.concatenate(
            [
                [0, 1e-30, -1e-30, 1e-7, 0.5, 0.9, 0.999, -1, -1e6, 1.0, 2.0],
                np.random.default_rng(2).uniform(-5, 0.999, 400),
            ]
        )
    )
    compare(cf.psi, [z], name="psi")
    c = f32(np.random.default_rng(3).uniform(-1, 1, 300))
    for g in (0.0, 0.5, -0.7, 0.999):
        compare(lambda ops, c: cf.hg_phase(ops, c, g) + 0.0 * c, [c], name=f"hg g={g}")


def test_exp_layer_forms():
    rng = np.random.default_rng(4)
    n = 2000
    log_c = f32(np.concatenate([rng.uniform(-120, 120, n // 2), rng.uniform(-3, 3, n // 2)]))
    k = f32(rng.choice([0.0, 1e-9, -1e-9, 0.1, -0.1, 10.0, -10.0], n) * rng.uniform(0.5, 1, n))
    t = f32(np.where(rng.random(n) < 0.1, L32, 10.0 ** rng.uniform(-4, 7, n)))
    compare(cf.exp_layer_optical_depth, [log_c, k, t], name="exp_depth")
    s = f32(10.0 ** rng.uniform(-37, 10, n))
    compare(cf.exp_layer_sample, [log_c, k, s], name="exp_sample")


COMPONENTS = [
    ExpLayer(1.0, 0.05, 0.0),
    ExpLayer(2.0, 0.0, 0.0),
    ExpLayer(0.01, 10.0, 100.0),
    HDRPLayer(2.0, 10.0, 0.05),
    HDRPLayer(1e-3, 1000.0, 1e-3),
    HDRPLayer(1.0, 0.0, 0.0),
    PowerLawLayer(1.5, 0.0, 100.0, 2.3),
    PowerLawLayer(1.0, -10.0, 40.0, 0.0),
    PowerLawLayer(0.7, 5.0, 3000.0, 8.0),
]


def _heights(c):
    return max(
        abs(v)
        for v in (
            getattr(c, "height", 0),
            getattr(c, "base_height", 0),
            getattr(c, "start", 0),
            getattr(c, "end", 0),
        )
    )


@pytest.mark.parametrize("comp", COMPONENTS, ids=repr)
def test_component_twins(comp):
    rng = np.random.default_rng(5)
    oy, dy, t = grid(rng, 1500)
    h = _heights(comp)
    compare(comp.depth, [oy, dy, t], shift=[h, 0.0, 0.0], name="depth")
    # sample at fractions of the f64 depth (rounded to f32)
    tau = comp.depth(NP, to64(oy), to64(dy), to64(np.where(t >= L32, L32, t)))
    s = np.minimum(tau * rng.choice([1e-6, 0.3, 0.99, 1.0], len(tau)), 1e30)
    s = f32(np.where(s < np.finfo(np.float32).tiny, 0.0, s))  # normal numbers only
    compare(comp.sample, [oy, dy, s], shift=[h, 0.0, 0.0], name="sample")
    compare(comp.rho, [oy], shift=[h], name="rho")
