"""What the phase function costs in droplet fog: the droplets' phase against Henyey–Greenstein
and an engine's cosine lobe.

A droplet fog's truth (``fogref scene --droplets``: a tabulated Mie phase) is compared with
the same fog seen through a substitute phase of the same mean cosine ``g``
(:data:`SUBSTITUTES`):

* ``"hg"``: Henyey–Greenstein with ``g``, what fogref's truth and most path tracers use;
* ``"lobe"``: the engines' phase, an isotropic term plus a cosine lobe ``max(mu, 0)^n``
  fitted to ``HG(g)`` (:func:`fogref.mapping.lobe.lobe_fit`; Unreal's directional
  inscattering, with its isotropic part in the ambient inscattering).

Two measures.  :func:`sun_phase_error` is exact and noise-free for the sun's single
scattering: the sun is a delta, so along a camera ray the phase is one factor ``p(d.w)``
and the substitute's image is ``L_ss p_sub / p`` per pixel (closed form with sun
attenuation, no shadows: an upper bound where the ground shadows the fog).
:func:`final_difference` measures everything, multiple scattering included, from two
truths (the droplet phase and a substitute), with its Monte Carlo noise
(:func:`fogref.compare.metrics.mse_noise`).  Both are relative RMSEs over the pixels
against the truth's final image (linear RGB, the mean over channels), so they read as
"how far off the picture is".
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from fogref.compare.metrics import mse_noise
from fogref.errors import ParameterError
from fogref.gbuffer import Truth
from fogref.mapping.lobe import lobe_fit
from fogref.media import NP, hg_phase, single_scatter_sun

__all__ = ["SUBSTITUTES", "final_difference", "substitute_phase", "sun_angle", "sun_phase_error"]

#: The substitute phases: Henyey–Greenstein with the droplets' g, and the engines' lobe fitted to it
SUBSTITUTES = ("hg", "lobe")


def substitute_phase(g: float, kind: str) -> Callable[[np.ndarray], np.ndarray]:
    """The phase [1/sr] of ``kind`` (:data:`SUBSTITUTES`) with mean cosine ``g`` (HG; the lobe is
    fitted to that HG), a function of ``cos_theta`` (numpy).

    >>> p = substitute_phase(0.8, "lobe")
    >>> round(float(p(np.array([1.0]))[0]) / float(substitute_phase(0.8, "hg")(np.array([1.0]))[0]), 2)
    0.82
    """
    if kind == "hg":
        return lambda c: hg_phase(NP, c, float(g))
    if kind == "lobe":
        fit = lobe_fit(float(g), isotropic=True)
        n, iso, lobe = fit["exponent"] or 0.0, fit["iso"], fit["lobe"]
        return lambda c: (iso + lobe * np.maximum(c, 0.0) ** n) / (4.0 * math.pi)
    raise ParameterError("<droplet_phase>", "kind", f"'{kind}' is not one of {', '.join(SUBSTITUTES)}")


def _rel(num_sq: float, truth: Truth, mask: np.ndarray) -> float:
    return math.sqrt(num_sq) / math.sqrt(float(np.mean(truth.final[mask] ** 2)))


def sun_angle(truth: Truth, w) -> np.ndarray:
    """``(H, W)`` angle [deg] between each pixel's view and the direction ``w`` toward the sun."""
    return np.degrees(np.arccos(np.clip(truth.view @ np.asarray(w, dtype=np.float64), -1.0, 1.0)))


def sun_phase_error(truth: Truth, pf, kind: str, mask: np.ndarray | None = None) -> dict:
    """The sun's single scattering with the fog's phase against ``kind``'s, at every pixel's
    distance (closed form, see module), over the ``(H, W)`` pixels of ``mask`` (default all;
    e.g. by :func:`sun_angle`).
    ``pf``: the truth's :class:`~fogref.mapping.PhysicalScene`.

    Returns ``{"rel_rmse": relative RMSE against the final image, "rel_rmse_sun": against the
    sun's single scattering itself, "mean_ratio": the substitute's mean sun single scattering
    over the droplets', "pixels": how many}`` (0, 0, 1 without a sun above the horizon).
    """
    m = pf.medium
    w = pf.sun_direction
    ok = np.isfinite(truth.final).all(-1)
    mask = ok if mask is None else ok & mask
    if not pf.has_sun or w[1] <= 0:
        return {"rel_rmse": 0.0, "rel_rmse_sun": 0.0, "mean_ratio": 1.0, "pixels": int(mask.sum())}
    o, d, D = truth.rays()
    L = np.stack(single_scatter_sun(NP, m, o, d, D, w, tuple(pf.sun_irradiance)), -1)
    cos = d[0] * w[0] + d[1] * w[1] + d[2] * w[2]
    ratio = substitute_phase(m.g, kind)(cos) / m.phase_value(NP, cos)
    L = L.reshape(truth.final.shape)
    dL = L * (ratio - 1.0).reshape(truth.final.shape[:2])[..., None]
    if not mask.any():
        return {"rel_rmse": 0.0, "rel_rmse_sun": 0.0, "mean_ratio": 1.0, "pixels": 0}
    ms = float(np.mean(dL[mask] ** 2))
    sun_ms = float(np.mean(L[mask] ** 2))
    sun_mean = float(np.mean(L[mask]))
    return {
        "rel_rmse": _rel(ms, truth, mask),
        "rel_rmse_sun": math.sqrt(ms / sun_ms) if sun_ms > 0 else 0.0,
        "mean_ratio": float(np.mean(L[mask] + dL[mask])) / sun_mean if sun_mean > 0 else 1.0,
        "pixels": int(mask.sum()),
    }


def final_difference(truth: Truth, other: Truth, mask: np.ndarray | None = None) -> dict:
    """The relative RMSE of ``other``'s final image against ``truth``'s (same camera; over the
    ``(H, W)`` pixels of ``mask``, default all), the Monte
    Carlo noise removed: ``sqrt(debiased MSE) / rms(truth)``, with its standard error (the
    delta method on the MSE's, bounded by ``sqrt(stderr(MSE)) / rms(truth)``) and whether it is
    below the noise."""
    if truth.final.shape != other.final.shape:
        raise ParameterError(str(other.path), "final", f"shape {other.final.shape} != {truth.final.shape}")
    ok = np.isfinite(truth.final).all(-1) & np.isfinite(other.final).all(-1)
    mask = ok if mask is None else ok & mask
    sigma = np.sqrt(truth.stderr["final"] ** 2 + other.stderr["final"] ** 2)
    r = mse_noise(other.final - truth.final, sigma, mask=mask)
    if r is None:
        raise ParameterError(str(other.path), "final", "no finite pixels")
    deb = float(r["debiased"])
    rel = _rel(deb, truth, mask)
    # the delta method, d sqrt(x) = dx / (2 sqrt(x)), bounded by |sqrt(a) - sqrt(b)| <= sqrt(|a - b|)
    # (near 0, where the delta method diverges)
    bound = _rel(float(r["stderr"]), truth, mask)
    se = min(bound**2 / (2.0 * rel), bound) if rel > 0 else bound
    return {"rel_rmse": rel, "stderr": se, "below_noise": bool(r["below_noise"]), "pixels": int(mask.sum())}
