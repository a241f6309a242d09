"""The best cosine lobe for a Henyey–Greenstein phase function (Unreal, Filament).

:func:`lobe_fit` asks, for the phase function alone, the question that
:func:`fogref.mapping.unreal.fit_unreal` asks for a whole scene: the best
``a + c max(mu, 0)^n`` for Henyey–Greenstein ``p_g(mu)``, with relative L2 error
over the sphere of directions (uniform in ``mu``).  With no sun attenuation and
start distance 0 the scene fit reduces exactly to it (both terms carry ``1 - T``).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np

from fogref.mapping.physical import PhysicalScene
from fogref.mapping.unreal import LOG_N_RANGE, Views, fit_unreal
from fogref.media import NP, hg_phase

__all__ = ["lobe_fit", "lobe_table"]


def _mu_quadrature(n: int = 256) -> Any:
    """Gauss–Legendre nodes/weights on [-1, 0] and [0, 1] (the lobe has a kink at 0)."""
    x, w = np.polynomial.legendre.leggauss(n)
    mu = np.concatenate([0.5 * (x - 1.0), 0.5 * (x + 1.0)])
    return mu, np.concatenate([0.5 * w, 0.5 * w])


def lobe_fit(g: float, isotropic: bool = True, n_quad: int = 256) -> dict:
    """Best ``a + c max(mu, 0)^n`` (``a`` = 0 when not ``isotropic``) for HG ``p_g(mu)``.

    Least squares over the sphere (uniform in ``mu``), ``a, c >= 0``.  Returns
    ``{"g", "exponent", "lobe" (c * 4 pi), "iso" (a * 4 pi), "rel_error"}``:
    coefficients relative to the isotropic phase 1/(4 pi) (so DirectionalInscatteringColor
    = alpha E c and FogInscatteringColor = alpha (L_sky + E a) when sun attenuation
    is ignored), rel_error = ||fit - p|| / ||p||.  ``exponent`` is None when the
    best lobe is 0 (the fit is flat).
    """
    from scipy.optimize import minimize_scalar, nnls

    mu, w = _mu_quadrature(n_quad)
    p = hg_phase(NP, mu, float(g))
    sw = np.sqrt(w)
    norm = math.sqrt(float(np.sum(w * p * p)))

    def solve(log_n: Any) -> Any:
        lobe = np.maximum(mu, 0.0) ** (10.0**log_n)
        A = np.stack([np.ones_like(mu), lobe], -1) if isotropic else lobe[:, None]
        x, r = nnls(A * sw[:, None], p * sw)
        return x, r

    grid = np.linspace(*LOG_N_RANGE, 51)
    rs = [solve(ln)[1] for ln in grid]
    k = int(np.argmin(rs))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    res = minimize_scalar(lambda ln: solve(ln)[1], bounds=(lo, hi), method="bounded", options={"xatol": 1e-6})
    ln = float(res.x) if res.fun <= rs[k] else float(grid[k])
    x, r = solve(ln)
    a, c = (x[0], x[1]) if isotropic else (0.0, x[0])
    flat = c * 4 * math.pi < 1e-9
    return {
        "g": float(g),
        "exponent": None if flat else 10.0**ln,
        "lobe": float(c * 4 * math.pi),
        "iso": float(a * 4 * math.pi),
        "rel_error": float(r / norm) if norm > 0 else 0.0,
    }


def lobe_table(gs: Any = None, pf: PhysicalScene | None = None, views: Views | None = None) -> list[dict]:
    """:func:`lobe_fit` for each g (default -0.9 to 0.9 step 0.1), with and without
    the isotropic term; with ``pf`` also the full scene fit (sun attenuation on,
    start distance fitted) for that g: its exponent and relative RMSE."""
    if gs is None:
        gs = np.round(np.arange(-0.9, 0.9001, 0.1), 10)
    rows = []
    for g in gs:
        g = float(round(float(g), 10)) + 0.0  # no "-0.0"
        row = lobe_fit(g)
        only = lobe_fit(g, isotropic=False)
        row["lobe_only_exponent"] = only["exponent"]
        row["lobe_only_rel_error"] = only["rel_error"]
        if pf is not None:
            m = replace(pf.medium, g=float(g))
            r = fit_unreal(replace(pf, medium=m), views)
            p = r.params
            lobe_on = max(p.DirectionalInscatteringColor) > 1e-6 * max(max(p.FogInscatteringColor), 1e-300)
            row["scene_exponent"] = p.DirectionalInscatteringExponent if lobe_on else None
            row["scene_start_distance_cm"] = p.DirectionalInscatteringStartDistance if lobe_on else 0.0
            row["scene_fog_colour"] = list(r.params.FogInscatteringColor)
            row["scene_dir_colour"] = list(r.params.DirectionalInscatteringColor)
            row["scene_rel_rmse"] = r.rel_rmse
        rows.append(row)
    return rows
