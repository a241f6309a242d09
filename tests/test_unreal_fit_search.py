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
from fogref.media import ExpLayer
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


def full_start_search(loss: ColourLoss) -> tuple[float, float]:
    """ColourLoss.minimise without its shortcut: the start grid, then always the bounded Brent search
    between the best grid start's neighbours, the best start of all it tried."""
    from scipy.optimize import minimize_scalar

    from fogref.mapping.unreal_basis import START_GRID_CM, START_XATOL_CM

    memo = {}

    def profile(start):
        if start not in memo:
            memo[start] = loss.best_exponent(start)
        return memo[start]

    k = int(np.argmin([profile(s)[1] for s in START_GRID_CM]))
    bounds = (START_GRID_CM[max(k - 1, 0)], START_GRID_CM[min(k + 1, len(START_GRID_CM) - 1)])
    minimize_scalar(
        lambda s: profile(float(s))[1], bounds=bounds, method="bounded", options={"xatol": START_XATOL_CM}
    )
    start = min(memo, key=lambda s: memo[s][1])
    return memo[start][0], start


def shortcut_scenes():
    """Scenes whose fitted start is 0 (the valley, sun 8 and 30 degrees high), between grid starts
    (dense fog), on inner grid starts (a camera 291 m up in a slow falloff: 300 m at 512 directions)
    and on the grid's largest (a black sky): each place the start search can end."""
    valley = physical_from_scene(VALLEY)

    def fog(scale, g, falloff, height, camera_y, sun_elevation, sky):
        layer = ExpLayer(1.0, falloff, height)
        medium = replace(valley.medium, sigma_t=tuple(scale * c for c in valley.medium.sigma_t), g=g)
        pf = replace(
            valley, medium=replace(medium, layers=(layer,)), sky_radiance=sky, camera=(0.0, camera_y, 0.0)
        )
        return with_sun_elevation(pf, sun_elevation)

    return {
        "valley": valley,
        "sun30": with_sun_elevation(valley, 30.0),
        "dense_sun30": scenes()["dense_sun30"],
        "start_grid": fog(5.955, 0.33, 1.144e-4, -0.643, 291.5, 20.69, (0.216, 0.385, 0.229)),
        "start_max": fog(8.281, 0.2585, 2.002e-3, -2.293, 38.72, 15.03, (0.0, 0.0, 0.0)),
    }


@pytest.mark.parametrize("name", ["valley", "sun30", "dense_sun30", "start_grid", "start_max"])
def test_start_search_shortcut_returns_the_full_searchs_fit_bitwise(name):
    """ColourLoss.minimise skips the Brent search over the start when the best grid start is no
    worse than the starts 1 cm beside it; its (log10 n, start) must be the full search's bit for bit
    at 128-1024 directions (one ulp is detected), and the shortcut must have been taken in some of
    them (it saves work: fewer exponent searches)."""
    pf = shortcut_scenes()[name]
    taken = 0  # levels where the shortcut was taken
    for n_dirs in (128, 256, 512, 1024):
        views = sample_views(pf.camera, n_dirs=n_dirs)
        target = physical_single_scattering(pf, views)
        fast, full = ColourLoss(pf, views, target), ColourLoss(pf, views, target)
        assert fast.minimise() == full_start_search(full), n_dirs
        taken += fast.colour_solves < full.colour_solves
    assert (taken > 0) == (name != "dense_sun30")


def test_start_search_shortcut_on_random_fogs_returns_the_full_searchs_fit_bitwise():
    """As above, on 24 random fogs at 128 directions (density 0.03-30x the valley's, g in
    [-0.3, 0.95], falloff 1e-4-0.3 /m, camera 0.5-300 m up, sun -5 to 85 degrees, black or blue
    skies): every (log10 n, start) equal bit for bit, the shortcut taken in some and not in others."""
    rng = np.random.default_rng(1)
    valley = physical_from_scene(VALLEY)
    taken = []
    for _ in range(24):
        scale = 10 ** rng.uniform(-1.5, 1.5)
        medium = replace(
            valley.medium,
            sigma_t=tuple(scale * c for c in valley.medium.sigma_t),
            g=float(rng.uniform(-0.3, 0.95)),
            layers=(ExpLayer(1.0, float(10 ** rng.uniform(-4, -0.5)), float(rng.uniform(-50, 50))),),
        )
        sky = tuple(float(x) for x in rng.uniform(0.0, 0.6, 3) * rng.choice([0.0, 1.0], p=[0.15, 0.85]))
        pf = replace(valley, medium=medium, sky_radiance=sky, camera=(0.0, float(rng.uniform(0.5, 300)), 0.0))
        pf = with_sun_elevation(pf, float(rng.uniform(-5, 85)))
        views = sample_views(pf.camera, n_dirs=128)
        target = physical_single_scattering(pf, views)
        fast, full = ColourLoss(pf, views, target), ColourLoss(pf, views, target)
        assert fast.minimise() == full_start_search(full)
        taken.append(fast.colour_solves < full.colour_solves)
    assert any(taken) and not all(taken)


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


def nnls2_arrays(g00, g01, g11, b0, b1, yy):
    """The two-column NNLS in NumPy arrays over the channels: the form ColourLoss used before its
    per-channel Python floats, kept as the reference of bitwise equality."""
    zero = np.zeros_like(b0)
    cands = [(zero, zero)]
    if g00 > 0:
        cands.append((np.maximum(b0, 0.0) / g00, zero))
    if g11 > 0:
        cands.append((zero, np.maximum(b1, 0.0) / g11))
    det = g00 * g11 - g01 * g01
    if det > 1e-12 * g00 * g11:
        x0, x1 = (g11 * b0 - g01 * b1) / det, (g00 * b1 - g01 * b0) / det
        ok = (x0 >= 0) & (x1 >= 0)
        cands.append((np.where(ok, x0, 0.0), np.where(ok, x1, 0.0)))
    best = (zero, zero, yy)
    for x0, x1 in cands:
        sse = yy - 2.0 * (x0 * b0 + x1 * b1) + g00 * x0 * x0 + 2.0 * g01 * x0 * x1 + g11 * x1 * x1
        take = sse < best[2]
        best = (np.where(take, x0, best[0]), np.where(take, x1, best[1]), np.where(take, sse, best[2]))
    return best[0], best[1], np.maximum(best[2], 0.0)


def test_two_column_nnls_per_channel_equals_the_array_form_bitwise():
    """The per-channel NNLS (Python floats) against the array form on 3000 random problems: both
    columns free, one clamped, both, singular and zero Gram matrices; every returned value equal bit
    for bit (the smallest difference detected is one ulp of one value)."""
    from fogref.mapping.unreal_basis import nnls2

    rng = np.random.default_rng(7)
    for k in range(3000):
        a = rng.normal(size=(50, 2)) * rng.choice([1e-6, 1.0, 1e6])
        if k % 7 == 0:
            a[:, 1] = a[:, 0] * rng.uniform(0.5, 2.0)  # collinear: det ~ 0
        if k % 11 == 0:
            a[:, int(rng.integers(2))] = 0.0  # a zero column
        y = rng.normal(size=(50, 3)) + a @ rng.normal(size=(2, 3))
        g00, g01, g11 = float(a[:, 0] @ a[:, 0]), float(a[:, 0] @ a[:, 1]), float(a[:, 1] @ a[:, 1])
        args = (g00, g01, g11, a[:, 0] @ y, a[:, 1] @ y, np.sum(y * y, axis=0))
        got, want = nnls2(*args), nnls2_arrays(*args)
        assert all(g.tobytes() == w.tobytes() for g, w in zip(got, want)), k


@pytest.mark.parametrize("name", ["valley", "dense_sun30"])
def test_colour_loss_start_sums_equal_the_full_models_bitwise(name):
    """ColourLoss runs, per start distance, only the opacity beyond the start on the lit views; its
    per-direction sums must be those of the whole model evaluated on every view (unreal_basis at
    exponent 1) and restricted to the lit ones, bit for bit, and so must its loss (one ulp of any
    sum is detected)."""
    pf = scenes()[name]
    views = sample_views(pf.camera, n_dirs=256)
    target = physical_single_scattering(pf, views)
    loss, ref = ColourLoss(pf, views, target), ColourLoss(pf, views, target)
    for start in (0.0, 1.0e3, 12345.678, MAX_START_CM):
        ref._sums.pop(start, None)
        ref._add_start(start, unreal_basis(pf, views, 1.0, start).lobe[ref._lit])
        for got, want in zip(loss.sums(start), ref._sums[start]):
            assert got.tobytes() == want.tobytes(), start
        for ln in (-1.0, 0.3, 1.7):
            assert loss.solve(ln, start)[2] == ref.solve(ln, start)[2]


@pytest.mark.parametrize("seed", [0, 1])
def test_colour_loss_sse_is_the_solves_bitwise(seed):
    """ColourLoss.sse (what the searches call: the three channels' sse added in Python) against
    solve's np.sum of them, for targets with random signs and scales (clamped colours, sse over
    ten decades): equal bit for bit at 200 random exponents and starts (one ulp is detected)."""
    rng = np.random.default_rng(seed)
    pf = scenes()["sun30"]
    views = sample_views(pf.camera, n_dirs=64)
    base = physical_single_scattering(pf, views)
    for _ in range(4):
        target = base * rng.uniform(-1.0, 2.0, 3) * 10.0 ** rng.uniform(-5, 5, 3)
        target += rng.normal(0.0, 0.05, target.shape) * np.abs(target).mean()
        loss = ColourLoss(pf, views, target)
        for _ in range(50):
            ln, start = rng.uniform(*LOG_N_RANGE), float(rng.choice([0.0, rng.uniform(0.0, 5e4)]))
            assert loss.sse(ln, start) == loss.solve(ln, start)[2]


def test_direction_groups_number_as_numpy_unique():
    """direction_groups (a lexsort) against np.unique(axis=0)'s inverse on the lit views of 64 to 2048
    Fibonacci directions and on rows with repeated values, -0.0 and ties in the first columns: the
    same index for every row (one differing index is detected)."""
    from fogref.mapping.unreal_basis import direction_groups

    rng = np.random.default_rng(3)
    cases = [sample_views((0.0, 2.0, 0.0), n_dirs=n).d for n in (64, 300, 2048)]
    cases.append(rng.integers(-2, 3, size=(500, 3)).astype(float) * 0.5)
    cases.append(np.array([[0.0, 1.0, 0.0], [-0.0, 1.0, 0.0], [0.0, -0.0, 1.0], [0.0, 0.0, 1.0]]))
    cases.append(np.zeros((0, 3)))
    for d in cases:
        want = np.unique(d, axis=0, return_inverse=True)[1].reshape(-1)
        assert direction_groups(d).tolist() == want.tolist()


@pytest.mark.parametrize("name", ["valley", "dense_sun30"])
def test_colour_loss_basis_is_the_models_bitwise(name):
    """ColourLoss.basis (the lit views' shading, zeros elsewhere; fit_unreal's final colour solve
    uses it) against unreal_basis (the whole model on every view) at exponents and starts
    across their ranges: both images equal bit for bit (one ulp of one view is detected), so the
    fitted colours are those of the model's own basis."""
    pf = scenes()[name]
    views = sample_views(pf.camera, n_dirs=256)
    loss = ColourLoss(pf, views, physical_single_scattering(pf, views))
    for ln, start in (
        (-2.0, 0.0),
        (0.0, 0.0),
        (0.3010299956639812, 0.0),
        (1.1, 12345.678),
        (3.0, MAX_START_CM),
    ):
        got, want = loss.basis(ln, start), unreal_basis(pf, views, 10.0**ln, start)
        assert got.iso.tobytes() == want.iso.tobytes(), (ln, start)
        assert got.lobe.tobytes() == want.lobe.tobytes(), (ln, start)
