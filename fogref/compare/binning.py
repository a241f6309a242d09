"""Errors binned against a per-pixel coordinate (distance, angle to the sun).

Each bin reports, over its pixels: ``rmse`` (image units), ``rmse_noise_floor``
(the RMSE a perfect model would get from the truth's noise, image units),
``mean_error`` (signed, image units), ``relmse`` (1), ``delta_e2000_mean`` (1) and
``flip_mean`` (0..1) where the comparison made their maps, and ``pixels``: how many of its
pixels each part used (a part's excluded pixels, see :class:`~fogref.compare.error_maps.ErrorMaps`, are left
out).  Bins empty for every part are dropped; a bin empty for one part holds None
for it, so no value is ever NaN.
"""

from __future__ import annotations

import numpy as np

from fogref.compare.error_maps import ErrorMaps


def log_distance_edges(distance, n_bins: int = 24) -> np.ndarray:
    """``n_bins + 1`` log-spaced bin edges covering the positive finite ``distance`` [m].

    Returns an empty array when no distance is positive and finite.
    """
    d = np.asarray(distance, dtype=np.float64).ravel()
    d = d[np.isfinite(d) & (d > 0)]
    if d.size == 0:
        return np.empty(0)
    lo, hi = float(d.min()), float(d.max())
    if hi <= lo * (1 + 1e-9):
        lo, hi = lo / 1.1, hi * 1.1
    edges = np.geomspace(lo, hi, n_bins + 1)
    edges[0], edges[-1] = lo, hi  # exact ends, so min and max fall inside
    return edges


def angle_edges(step_deg: float = 5.0) -> np.ndarray:
    """Bin edges over [0, 180] degrees with ``step_deg`` spacing."""
    n = max(1, round(180.0 / step_deg))
    return np.linspace(0.0, 180.0, n + 1)


def binned_errors(coordinate, errors: dict[str, ErrorMaps], edges, mask=None) -> dict:
    """Per-bin error statistics of every part against ``coordinate``.

    ``coordinate``: ``(H, W)`` values (e.g. distance [m] or angle [deg]);
    ``errors``: part name -> :class:`ErrorMaps`; ``edges``: increasing bin edges
    (the last bin includes its right edge); ``mask``: ``(H, W)`` bool of pixels to use.
    Returns a JSON-ready dict: ``edges``, ``bin_lo``, ``bin_hi``, ``center`` (geometric
    mean for positive log bins, else midpoint), ``pixels`` and ``parts[part][metric]``,
    lists over the non-empty bins only.
    """
    edges = np.asarray(edges, dtype=np.float64)
    c = np.asarray(coordinate, dtype=np.float64)
    sel = np.isfinite(c) if mask is None else (np.asarray(mask, dtype=bool) & np.isfinite(c))
    out: dict = {"edges": edges.tolist(), "bin_lo": [], "bin_hi": [], "center": [], "pixels": [], "parts": {}}
    if edges.size < 2:
        return out
    sel &= (c >= edges[0]) & (c <= edges[-1])
    idx = np.clip(np.searchsorted(edges, c[sel], side="right") - 1, 0, edges.size - 2)
    nb = edges.size - 1
    counts = np.bincount(idx, minlength=nb)
    keep = counts > 0
    lo, hi = edges[:-1][keep], edges[1:][keep]
    center = np.where(lo > 0, np.sqrt(np.abs(lo * hi)), 0.5 * (lo + hi))
    out.update(bin_lo=lo.tolist(), bin_hi=hi.tolist(), center=center.tolist(), pixels=counts[keep].tolist())

    for part, e in errors.items():
        use = e.valid[sel]
        n = np.bincount(idx[use], minlength=nb)[keep]

        def mean(m: np.ndarray, use=use, n=n) -> list:
            v = np.asarray(m)[sel]
            if v.ndim > 1:
                v = v.mean(-1)
            tot = np.bincount(idx[use], weights=v[use], minlength=nb)[keep]
            return [float(t / k) if k else None for t, k in zip(tot, n)]

        def root(values: list) -> list:
            return [None if v is None else float(np.sqrt(v)) for v in values]

        out["parts"][part] = {
            "pixels": n.tolist(),
            "rmse": root(mean(e.squared)),
            "rmse_noise_floor": root(mean(e.sigma**2)),
            "mean_error": mean(e.signed),
            "relmse": mean(e.relative_squared),
        }
        for key, m in (("delta_e2000_mean", e.delta_e2000), ("flip_mean", e.flip)):
            if m is not None:  # computed unless the comparison left the perceptual metrics out
                out["parts"][part][key] = mean(m)
    return out
