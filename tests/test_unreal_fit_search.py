"""Unreal's fit search (:class:`fogref.mapping.unreal_basis.ColourLoss`: Brent over the exponent
inside Brent over the start distance, the colours in closed form) against the Nelder–Mead search
it replaced, kept here as the reference: a grid of 21 exponents x 4 start distances, then
Nelder–Mead on ``(log10 n, start / 1e4 cm)`` (``xatol`` 1e-4), the colours by scipy's NNLS on
the model's own basis at every point.

Both minimise the same loss on the same views (256 Fibonacci directions), for scenes whose best
start distance is 0 (valley.xml) and positive (dense fog, a higher sun).  They must agree within
the fit's own convergence criterion (``FIT_RTOL`` = 5e-3: the exponent relatively, each colour
to 5e-3 of its largest channel, the start to 5e-3 of max(start, 100 m)), and the new search's
loss must be no larger than Nelder–Mead's beyond 1e-9 relative (it detects a search that stops
in a worse minimum).
"""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import minimize

from fogref.mapping import FIT_RTOL, fit_unreal, sample_views
from fogref.mapping.fit import with_sun_elevation
from fogref.mapping.unreal import (
    LOG_N_RANGE,
    MAX_START_CM,
    physical_single_scattering,
    solve_colours,
    unreal_basis,
)
from fogref.mapping.unreal_basis import ColourLoss
from fogref.study.fit import physical_from_scene

VALLEY = Path(__file__).resolve().parents[1] / "scenes" / "valley.xml"


def nelder_mead_fit(pf, views, target):
    """The search fit_unreal used before ColourLoss: ``(log10 n, start [cm], sse)``."""
    memo = {}

    def sse(ln, s):
        ln, s = float(np.clip(ln, *LOG_N_RANGE)), float(np.clip(s, 0.0, MAX_START_CM))
        if (ln, s) not in memo:
            memo[ln, s] = solve_colours(unreal_basis(pf, views, 10.0**ln, s), target)[2]
        return memo[ln, s]

    grid = [(ln, s, sse(ln, s)) for ln in np.linspace(*LOG_N_RANGE, 21) for s in (0.0, 2e3, 1e4, 3e4)]
    ln0, s0, _ = min(grid, key=lambda r: r[2])

    def f(x):
        s = x[1] * 1e4
        return sse(x[0], max(s, 0.0)) * (1.0 + (s * s if s < 0 else 0.0))

    res = minimize(
        f,
        np.array([ln0, s0 / 1e4]),
        method="Nelder-Mead",
        options={"xatol": 1e-4, "fatol": 1e-12 * max(1.0, float(np.sum(target**2))), "maxiter": 400},
    )
    ln, s = float(np.clip(res.x[0], *LOG_N_RANGE)), float(np.clip(res.x[1] * 1e4, 0.0, MAX_START_CM))
    return ln, s, sse(ln, s)


def scenes():
    valley = physical_from_scene(VALLEY)
    dense = replace(
        valley, medium=replace(valley.medium, sigma_t=tuple(10 * c for c in valley.medium.sigma_t))
    )
    return {
        "valley": valley,
        "dense_sun30": with_sun_elevation(dense, 30.0),
        "sun30": with_sun_elevation(valley, 30.0),
    }


@pytest.mark.parametrize("name", ["valley", "dense_sun30", "sun30"])
def test_brent_search_agrees_with_nelder_mead(name):
    pf = scenes()[name]
    views = sample_views(pf.camera, n_dirs=256)
    target = physical_single_scattering(pf, views)
    ln_nm, s_nm, sse_nm = nelder_mead_fit(pf, views, target)
    r = fit_unreal(pf, views)
    p = r.params
    sse_new = r.rmse**2 * 3 * len(views.D)
    assert sse_new <= sse_nm * (1 + 1e-9)
    n_nm = 10.0**ln_nm
    assert p.DirectionalInscatteringExponent == pytest.approx(n_nm, rel=FIT_RTOL)
    assert abs(p.DirectionalInscatteringStartDistance - s_nm) <= FIT_RTOL * max(s_nm, 1e4)
    b = unreal_basis(pf, views, n_nm, s_nm)
    cf, cd, _ = solve_colours(b, target)
    for new, old in ((p.FogInscatteringColor, cf), (p.DirectionalInscatteringColor, cd)):
        assert max(abs(x - y) for x, y in zip(new, old)) <= FIT_RTOL * max(old)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_colour_loss_equals_the_colour_solve_on_the_models_basis(seed):
    """ColourLoss's factorised basis and two-column NNLS against scipy's NNLS on the model's own
    basis (solve_colours), at random exponents and starts and for targets whose best colours
    are partly clamped at 0 (random signs): colours to 1e-7 of the largest, sse to 1e-7
    relative (float64 normal equations)."""
    rng = np.random.default_rng(seed)
    pf = scenes()["sun30"]
    views = sample_views(pf.camera, n_dirs=64)
    target = physical_single_scattering(pf, views) * rng.uniform(-1.0, 2.0, 3)
    target += rng.normal(0.0, 0.05, target.shape)
    loss = ColourLoss(pf, views, target)
    for _ in range(4):
        ln, start = rng.uniform(*LOG_N_RANGE), float(rng.choice([0.0, rng.uniform(0.0, 5e4)]))
        cf, cd, sse = loss.solve(ln, start)
        cf0, cd0, sse0 = solve_colours(unreal_basis(pf, views, 10.0**ln, start), target)
        scale = max(np.max(np.abs(cf0)), np.max(np.abs(cd0)), 1e-300)
        np.testing.assert_allclose(np.concatenate([cf, cd]), np.concatenate([cf0, cd0]), atol=1e-7 * scale)
        assert sse == pytest.approx(sse0, rel=1e-7)
