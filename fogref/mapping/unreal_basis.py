"""Unreal's inscatter as a linear model in its two colours, and the colour solve.

Unreal's Exponential Height Fog adds, per pixel (start distances 0, see
:mod:`fogref.models.ue4`)::

    inscatter = FogInscatteringColor (1 - T) + DirectionalInscatteringColor max(cos, 0)^n (1 - T_dir)

where ``T_dir`` is the transmittance of the part of the ray beyond
DirectionalInscatteringStartDistance.  Given the exponent ``n`` and the start
distance, the model is **linear** in the two colours, so each colour channel is a
2-parameter non-negative least-squares problem (:func:`solve_colours`) on two basis
images (:func:`unreal_basis`: the model evaluated with unit colours, in float64).
Density, falloff and height come from the exact mapping :func:`base_params` (the inverse of
:func:`fogref.models.ue4.ue4_to_medium`).

Only the exponent and the start distance are nonlinear, and the lobe image factorises:
``max(cos, 0)^n (1 - T_dir(start))`` is the ``n = 1`` image times ``max(cos, 0)^(n - 1)``.
:class:`ColourLoss` evaluates the model once per start distance, and each exponent costs a
power and three dot products; it finds the best ``(n, start)`` by a bounded Brent search over
``log10 n`` inside a bounded Brent search over the start distance (:meth:`ColourLoss.minimise`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from fogref.errors import ParameterError
from fogref.mapping.physical import PhysicalScene
from fogref.mapping.views import Views
from fogref.media import ExpLayer
from fogref.models.base import SKY_DISTANCE
from fogref.models.ue4 import (
    CM_PER_M,
    SecondFogData,
    UE4ExponentialHeightFog,
    UE4FogParams,
    directional_lobe,
    directional_opacity,
    directional_start_uniform,
    fog_constants,
    shade_geometry,
    sigma_to_unreal,
)

__all__ = [
    "Basis",
    "ColourLoss",
    "LOG_N_RANGE",
    "MAX_START_CM",
    "base_params",
    "direction_groups",
    "nnls2",
    "solve_colours",
    "unreal_basis",
    "unreal_inscatter",
]

#: Search range of log10(exponent) in the fits.
LOG_N_RANGE = (-2.0, 3.0)
#: Upper bound of the fitted DirectionalInscatteringStartDistance [cm] (1 km).
MAX_START_CM = 1.0e5
#: Start distances [cm] :meth:`ColourLoss.minimise` tries before refining between the best
#: one's neighbours.
START_GRID_CM = (0.0, 1.0e3, 3.0e3, 1.0e4, 3.0e4, MAX_START_CM)
#: The start search's tolerance [cm] (its ``xatol``).
START_XATOL_CM = 1.0


def base_params(pf: PhysicalScene, **kw: Any) -> UE4FogParams:
    """Unreal parameters with the exact density/falloff/height of ``pf.medium``, the
    sun direction, and ``kw`` (other fields; start distances default to 0).

    The medium must be unbounded (ParameterError naming 'bounds'), grey (equal sigma_t per
    channel, else naming 'sigma_t') and made of 1 or 2 :class:`~fogref.media.ExpLayer` (else
    naming 'layers'): each layer ``a exp(-b (y - h))`` [1/m] becomes FogDensity/FogHeightFalloff
    (:func:`fogref.models.ue4.sigma_to_unreal`) and its height ``100 h`` [cm], the second one
    SecondFogData with its offset from the first.

    Examples
    --------
    >>> from fogref.media import ExpLayer, FogMedium
    >>> p = base_params(PhysicalScene(FogMedium(sigma_t=0.002, layers=(ExpLayer(1.0, 0.02, 3.0),))))
    >>> round(p.FogDensity, 6), round(p.FogHeightFalloff, 6), p.FogHeight
    (0.041627, 0.288539, 300.0)
    """
    defaults: dict[str, Any] = dict(
        DirectionalInscatteringStartDistance=0.0,
        StartDistance=0.0,
        FogMaxOpacity=1.0,
        FogCutoffDistance=0.0,
        SunLuminance=1.0,
    )
    defaults.update(kw)
    base = replace(UE4FogParams(), **defaults)
    medium = pf.medium
    if medium.bounds is not None:
        raise ParameterError(medium.source, "bounds", "Unreal's height fog is unbounded")
    sigma = medium.grey_sigma_t("Unreal")
    layers = [L for L in medium.layers if isinstance(L, ExpLayer)]
    if len(layers) != len(medium.layers) or not 1 <= len(layers) <= 2:
        raise ParameterError(medium.source, "layers", "need 1 or 2 ExpLayer")
    vals = [(*sigma_to_unreal(sigma * L.density, L.falloff), L.height * CM_PER_M) for L in layers]
    second = SecondFogData(FogDensity=0.0, FogHeightFalloff=base.SecondFogData.FogHeightFalloff)
    if len(vals) == 2:
        second = SecondFogData(
            FogDensity=vals[1][0], FogHeightFalloff=vals[1][1], FogHeightOffset=vals[1][2] - vals[0][2]
        )
    p = replace(
        base, FogDensity=vals[0][0], FogHeightFalloff=vals[0][1], FogHeight=vals[0][2], SecondFogData=second
    )
    return p.with_sun(pf.sun_direction, p.SunLuminance)


def unreal_inscatter(
    params: UE4FogParams, camera: Any, world_pos: Any, precision: str = "float64"
) -> np.ndarray:
    """Unreal's inscatter (N, 3) for the given parameters."""
    fog = UE4ExponentialHeightFog(params)
    return np.asarray(fog.evaluate(camera, world_pos, precision).inscatter, dtype=float)


@dataclass
class Basis:
    """The two basis images of Unreal's inscatter at fixed exponent and start distance."""

    iso: np.ndarray  # (N,) 1 - T
    lobe: np.ndarray  # (N,) max(cos,0)^n (1 - T_dir)


def unreal_basis(
    pf: PhysicalScene, views: Views, exponent: float, start_cm: float, sky_distance: float = SKY_DISTANCE
) -> Basis:
    """Unreal (float64) evaluated with unit colours: the isotropic and lobe images."""
    ins = _unit_inscatter(_unit_params(pf), pf, views.world_positions(sky_distance), exponent, start_cm)
    return Basis(iso=ins[:, 0], lobe=ins[:, 1])


def _unit_params(pf: PhysicalScene) -> UE4FogParams:
    """:func:`base_params` of ``pf`` with the unit colours of :func:`unreal_basis` (FogInscatteringColor
    red, DirectionalInscatteringColor green)."""
    return base_params(pf, FogInscatteringColor=(1.0, 0.0, 0.0), DirectionalInscatteringColor=(0.0, 1.0, 0.0))


def _unit_inscatter(
    unit: UE4FogParams, pf: PhysicalScene, wp: np.ndarray, exponent: float, start_cm: float
) -> np.ndarray:
    """Unreal's inscatter (N, 3) at the world positions ``wp`` with :func:`_unit_params`'s ``unit``, the
    exponent and the start distance [cm] (every field but those two is ``unit``'s, already checked)."""
    p = replace(unit, DirectionalInscatteringExponent=exponent, DirectionalInscatteringStartDistance=start_cm)
    return unreal_inscatter(p, np.asarray(pf.camera), wp)


def solve_colours(
    basis: Basis, target: np.ndarray, weights: Any = None
) -> tuple[np.ndarray, np.ndarray, float]:
    """Non-negative least squares per channel: ``target ≈ C_fog iso + C_dir lobe``.

    Returns ``(C_fog (3,), C_dir (3,), sse)`` with ``sse`` the weighted sum of
    squared residuals over all channels.
    """
    from scipy.optimize import nnls

    A = np.stack([basis.iso, basis.lobe], axis=-1)
    sw = np.ones(len(A)) if weights is None else np.sqrt(np.asarray(weights, dtype=float))
    Aw = A * sw[:, None]
    cf, cd, sse = np.zeros(3), np.zeros(3), 0.0
    for c in range(3):
        x, r = nnls(Aw, target[:, c] * sw)
        cf[c], cd[c] = x
        sse += r * r
    return cf, cd, float(sse)


def nnls2(
    g00: float, g01: float, g11: float, b0: Any, b1: Any, yy: Any
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Two-column non-negative least squares from its normal equations, per channel.

    ``G = [[g00, g01], [g01, g11]] = A^T A``, ``b0``, ``b1`` (3,) ``= A^T y``, ``yy`` (3,) ``= y.y``.
    The optimum is the best of the four candidates (both columns, one, none) that are
    feasible.  Returns ``(x0, x1, sse)``, each (3,).  Each channel is solved in Python floats
    (the same IEEE operations, in the same order, as the array form: three values are too few
    for NumPy to pay for its calls).

    >>> x0, x1, sse = nnls2(2.0, 0.0, 1.0, [4.0, -1.0, 0.0], [1.0, 2.0, 0.0], [9.0, 4.0, 0.0])
    >>> x0.tolist(), x1.tolist(), sse.tolist()
    ([2.0, 0.0, 0.0], [1.0, 2.0, 0.0], [0.0, 0.0, 0.0])
    """
    lists = (np.asarray(v, dtype=np.float64).tolist() for v in (b0, b1, yy))
    out = np.array(_nnls2_channels(g00, g01, g11, *lists)).T.copy()
    return out[0], out[1], out[2]


def _nnls2_channels(
    g00: float, g01: float, g11: float, b0: list, b1: list, yy: list
) -> list[tuple[float, float, float]]:
    """:func:`nnls2` on Python floats: ``(x0, x1, sse)`` per channel of ``b0``, ``b1``, ``yy``."""
    det = g00 * g11 - g01 * g01
    both = det > 1e-12 * g00 * g11
    out = []
    for p, q, r in zip(b0, b1, yy):
        cands = []
        if g00 > 0:  # np.maximum's rule: the first value when it is >= or NaN
            cands.append(((p if p >= 0.0 or p != p else 0.0) / g00, 0.0))
        if g11 > 0:
            cands.append((0.0, (q if q >= 0.0 or q != q else 0.0) / g11))
        if both:
            x0, x1 = (g11 * p - g01 * q) / det, (g00 * q - g01 * p) / det
            cands.append((x0, x1) if x0 >= 0 and x1 >= 0 else (0.0, 0.0))
        # the candidate (0, 0) scores r exactly; it starts as the best
        b_x0, b_x1, b_sse = 0.0, 0.0, r
        for x0, x1 in cands:
            sse = r - 2.0 * (x0 * p + x1 * q) + g00 * x0 * x0 + 2.0 * g01 * x0 * x1 + g11 * x1 * x1
            if sse < b_sse:
                b_x0, b_x1, b_sse = x0, x1, sse
        out.append((b_x0, b_x1, b_sse if b_sse >= 0.0 or b_sse != b_sse else 0.0))
    return out


def direction_groups(d: np.ndarray) -> np.ndarray:
    """Per row of ``d`` (N, 3) finite, the index of its value among the distinct rows sorted
    lexicographically: the numbering of ``np.unique(d, axis=0, return_inverse=True)``, from a
    lexsort of the three columns (``np.unique`` sorts the rows as records, about ten times slower).

    >>> direction_groups(np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])).tolist()
    [1, 0, 1]
    """
    d = np.asarray(d, dtype=np.float64)
    group = np.zeros(len(d), dtype=np.intp)
    if len(d):
        order = np.lexsort((d[:, 2], d[:, 1], d[:, 0]))
        s = d[order]
        new = np.zeros(len(d), dtype=np.intp)
        new[1:] = np.any(s[1:] != s[:-1], axis=1)
        group[order] = np.cumsum(new)
    return group


class ColourLoss:
    """The squared error of the best colours (:func:`solve_colours`) as a function of
    ``(log10 n, start)``, with Unreal's basis factorised (module doc).

    Parameters
    ----------
    pf : PhysicalScene
    views : Views
    target : ndarray (N, 3) or (N, 1)
        The inscatter to match on ``views`` (radiance).
    sky_distance : float
        Where the model fogs sky views [m].

    Attributes ``model_evaluations`` and ``colour_solves`` count the work done.  The colours
    solved here come from the normal equations; :func:`solve_colours` on the model's own basis
    gives the final ones.

    Examples
    --------
    >>> from fogref.media import ExpLayer, FogMedium
    >>> from fogref.mapping.views import sample_views
    >>> pf = PhysicalScene(FogMedium(sigma_t=0.01, albedo=1.0, layers=(ExpLayer(1.0, 0.0, 0.0),)),
    ...                    (1.0, 0.3, 0.0), (1.0, 1.0, 1.0))
    >>> v = sample_views(pf.camera, n_dirs=64)
    >>> b = unreal_basis(pf, v, 8.0, 0.0)
    >>> loss = ColourLoss(pf, v, 0.5 * b.iso[:, None] + 2.0 * b.lobe[:, None])
    >>> ln, start = loss.minimise(fit_start=False)
    >>> round(10.0**ln, 4), start
    (8.0, 0.0)
    """

    def __init__(
        self, pf: PhysicalScene, views: Views, target: np.ndarray, sky_distance: float = SKY_DISTANCE
    ):
        self.pf, self.views, self.sky_distance = pf, views, float(sky_distance)
        y = np.broadcast_to(np.asarray(target, dtype=float), (len(views.D), 3))
        # the parameters and positions every model evaluation shares, made once
        self._unit, wp = _unit_params(pf), views.world_positions(sky_distance)
        one = Basis(*_unit_inscatter(self._unit, pf, wp, 1.0, 0.0)[:, :2].T)
        self.model_evaluations = 1
        self.colour_solves = 0
        self._lit = one.lobe > 0  # the lobe is 0 elsewhere for every exponent and start
        self._iso = one.iso  # and the isotropic image is the same for every exponent and start
        # the lit views grouped by direction: max(cos, 0) is a function of the direction
        self._group = direction_groups(views.d[self._lit])
        self._iso_lit, self._y_lit = one.iso[self._lit], y[self._lit]
        # a start distance's lobe is needed on the lit views only, and of the model's shading only the
        # opacity beyond the start changes with it: the rest is computed once, on the lit views (no
        # operation of the model mixes views, so each value is the one of the whole evaluation)
        p1 = replace(
            self._unit, DirectionalInscatteringExponent=1.0, DirectionalInscatteringStartDistance=0.0
        )
        dt, self._cam_z_cm, rel = UE4ExponentialHeightFog.receivers(
            np.asarray(pf.camera), wp[self._lit], "float64"
        )
        self._C1 = fog_constants(p1, self._cam_z_cm, dt)
        with np.errstate(all="ignore"):
            self._geo = shade_geometry(self._C1, self._cam_z_cm, rel, dt, exact=True)
            self._lobe1 = directional_lobe(self._C1, self._geo, dt)
        # max(cos, 0) per direction: the lobe at exponent 2 over the one at exponent 1
        self._cos = np.zeros(int(self._group.max(initial=-1)) + 1)
        self._cos[self._group] = self._lit_lobe(2.0, 0.0) / one.lobe[self._lit]
        # numpy's pairwise sums, not BLAS dots over the views: a threaded BLAS splits a dot's sum over
        # its threads, so the fit's last digits would depend on their number (a Dask worker has one)
        self._g00 = float(np.sum(one.iso * one.iso))
        self._b0_list = np.sum(one.iso[:, None] * y, axis=0).tolist()
        self._yy_list = np.sum(y * y, axis=0).tolist()
        self._sums: dict[float, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        # cos^n and cos^2n per direction at the exponent grid's values, which every start's search
        # evaluates (made on the first search)
        self._grid_powers: dict[float, tuple[np.ndarray, np.ndarray]] = {}
        self._add_start(0.0, one.lobe[self._lit])

    def _lit_lobe(self, exponent: float, start_cm: float) -> np.ndarray:
        """The model's lobe channel on the lit views at ``exponent`` and ``start_cm`` [cm]: the
        angular factor times the opacity beyond the start (times a unit colour, plus 0)."""
        p = replace(
            self._unit,
            DirectionalInscatteringExponent=exponent,
            DirectionalInscatteringStartDistance=start_cm,
        )
        C = fog_constants(p, self._cam_z_cm, np.float64)
        with np.errstate(all="ignore"):
            return directional_lobe(C, self._geo, np.float64) * directional_opacity(C, self._geo, np.float64)

    def basis(self, log_n: float, start_cm: float) -> Basis:
        """:func:`unreal_basis` at exponent ``10**log_n`` and ``start_cm`` [cm] on the loss's views,
        bit for bit, from the lit views' shading (one model evaluation's cost on those views)."""
        lobe = np.zeros(len(self._iso))
        lobe[self._lit] = self._lit_lobe(10.0**log_n, start_cm)
        return Basis(iso=self._iso, lobe=lobe)

    def _add_start(self, start_cm: float, lobe1: np.ndarray) -> None:
        """Per direction, the sums over its views of ``iso g``, ``g^2`` and ``g y`` (``g = lobe1 / cos``)."""
        g = lobe1 / self._cos[self._group]
        n = len(self._cos)

        def per_direction(w: np.ndarray) -> np.ndarray:
            return np.bincount(self._group, weights=w, minlength=n)

        ygc = np.stack([per_direction(g * self._y_lit[:, c]) for c in range(3)], axis=-1)
        self._sums[start_cm] = (per_direction(self._iso_lit * g), per_direction(g * g), ygc)

    def sums(self, start_cm: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The per-direction sums of the lobe at ``start_cm`` [cm] (one model evaluation, once)."""
        if start_cm not in self._sums:
            # the model's lobe channel at exponent 1 (lobe * (1 - T_dir) times a unit colour, plus 0);
            # of the uniforms only the start distance differs from those of start 0
            light = self._unit.InscatteringLightDirection is not None
            w = directional_start_uniform(start_cm, light, self._C1["match"], np.float64)
            C = {**self._C1, "light": (*self._C1["light"][:3], w)}
            with np.errstate(all="ignore"):
                lobe = self._lobe1 * directional_opacity(C, self._geo, np.float64)
            self.model_evaluations += 1
            self._add_start(start_cm, lobe)
        return self._sums[start_cm]

    def _channels(self, log_n: float, start_cm: float) -> list[tuple[float, float, float]]:
        """:func:`nnls2`'s ``(C_fog, C_dir, sse)`` per channel at exponent ``10**log_n`` and ``start_cm``."""
        iso_g, gg, yg = self.sums(start_cm)
        cn, cn2 = self._grid_powers.get(log_n) or self._powers(log_n)
        self.colour_solves += 1
        g01, g11 = float(cn @ iso_g), float(cn2 @ gg)
        return _nnls2_channels(self._g00, g01, g11, self._b0_list, (cn @ yg).tolist(), self._yy_list)

    def _powers(self, log_n: float) -> tuple[np.ndarray, np.ndarray]:
        """``(cos^n, cos^2n)`` per direction at ``n = 10**log_n``."""
        cn = self._cos ** (10.0**log_n)
        return cn, cn * cn

    def solve(self, log_n: float, start_cm: float) -> tuple[np.ndarray, np.ndarray, float]:
        """``(C_fog (3,), C_dir (3,), sse)`` at exponent ``10**log_n`` and ``start_cm`` [cm]."""
        out = np.array(self._channels(log_n, start_cm)).T.copy()
        return out[0], out[1], float(np.sum(out[2]))

    def sse(self, log_n: float, start_cm: float) -> float:
        """:meth:`solve`'s ``sse`` alone (the searches need no colours): the channels' sum in
        ``np.sum``'s order for three values, ``(R + G) + B``."""
        (_, _, r), (_, _, g), (_, _, b) = self._channels(log_n, start_cm)
        return r + g + b

    def best_exponent(self, start_cm: float, log_n: float | None = None) -> tuple[float, float]:
        """``(log10 n, sse)`` of the best exponent at ``start_cm``: a grid of 21 in
        :data:`LOG_N_RANGE`, then a bounded Brent search between the best point's neighbours
        (``xatol`` 1e-6).  ``log_n`` given: that one (clipped to the range)."""
        from scipy.optimize import minimize_scalar

        if log_n is not None:
            ln = float(np.clip(log_n, *LOG_N_RANGE))
            return ln, self.sse(ln, start_cm)
        grid = np.linspace(*LOG_N_RANGE, 21)
        if not self._grid_powers:
            self._grid_powers = {float(g): self._powers(g) for g in grid}
        values = [self.sse(g, start_cm) for g in grid]
        k = int(np.argmin(values))
        res = minimize_scalar(
            lambda ln: self.sse(ln, start_cm),
            bounds=(grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]),
            method="bounded",
            options={"xatol": 1e-6},
        )
        return (float(res.x), float(res.fun)) if res.fun < values[k] else (float(grid[k]), values[k])

    def minimise(self, log_n: float | None = None, fit_start: bool = True) -> tuple[float, float]:
        """The best ``(log10 n, start [cm])``: for each start distance the best exponent
        (:meth:`best_exponent`); the start from :data:`START_GRID_CM`, then a bounded Brent
        search between the best one's neighbours (``xatol`` 1 cm); 0 without ``fit_start``.
        ``log_n``: a fixed exponent.

        The search is skipped when the best grid start is no worse than the starts 1 cm (its
        ``xatol``) on either side of it inside the search's bounds: for a loss with one minimum
        between those neighbours, the search would end within 1 cm of that grid start.  It then
        returns the grid start, as the search does whenever it finds nothing better (a start of 0:
        the lobe from the camera on, what most fog scenes fit).  Those probes are not candidates:
        when they find a better start, the search runs as if they had not been made."""
        from scipy.optimize import minimize_scalar

        memo: dict[float, tuple[float, float]] = {}

        def profile(start: float) -> tuple[float, float]:
            if start not in memo:
                memo[start] = self.best_exponent(start, log_n)
            return memo[start]

        if not fit_start:
            return profile(0.0)[0], 0.0
        starts = START_GRID_CM
        k = int(np.argmin([profile(s)[1] for s in starts]))
        lo, hi = starts[max(k - 1, 0)], starts[min(k + 1, len(starts) - 1)]
        beside = [s for s in (starts[k] - START_XATOL_CM, starts[k] + START_XATOL_CM) if lo <= s <= hi]
        if all(self.best_exponent(s, log_n)[1] >= memo[starts[k]][1] for s in beside):
            return memo[starts[k]][0], starts[k]
        minimize_scalar(
            lambda s: profile(float(s))[1],
            bounds=(lo, hi),
            method="bounded",
            options={"xatol": START_XATOL_CM},
        )
        start = min(memo, key=lambda s: memo[s][1])
        return memo[start][0], start
