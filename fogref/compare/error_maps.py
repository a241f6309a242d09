"""Every per-pixel error of a part at once (:func:`error_maps`) and its summaries (:class:`ErrorMaps`).

The maps of :mod:`fogref.compare.metrics` and :mod:`fogref.compare.perceptual` for one
part (e.g. the final image), with the pixels where the comparison is undefined or the
model is not finite marked invalid, counted and left out of every summary, and the
noise floors of the truth's Monte Carlo noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fogref.compare import noise
from fogref.compare.metrics import (
    NOISE_Z,
    RELMSE_EPS,
    abs_error_map,
    check_pair,
    count_nonfinite,
    finite_pixels,
    mean_noise,
    mse_noise,
    relative_squared_error_map,
    squared_error_map,
)
from fogref.compare.perceptual import FLIP_PPD, delta_e2000_maps, flip_map
from fogref.display import exposure_white


@dataclass
class ErrorMaps:
    """Every per-pixel error of one part (e.g. the final image), shape ``(H, W)`` each.

    ``signed``: ``test - reference`` per channel ``(H, W, 3)`` [image units];
    ``absolute``: ``mean_c |x - r|`` [image units]; ``squared``: ``mean_c (x - r)²``
    [units²]; ``relative_squared``: relMSE's per-pixel term [1]; ``delta_e2000`` [1];
    ``flip`` [0..1] (both None when the perceptual metrics were not asked for).  ``white``: the
    ΔE exposure white [image units] (None without ΔE2000, unless given); ``flip_params``: what
    FLIP used (empty without FLIP).

    ``valid``: ``(H, W)`` bool, the pixels that count.  An invalid pixel (its
    reference undefined, e.g. ``surface`` with zero coverage, or a non-finite model
    value) holds error 0 in every map and is excluded from every summary, which
    counts it.  ``nonfinite``: ``(H, W)`` bool, the model was not finite there.
    ``sigma``: ``(H, W, 3)`` standard error of ``signed`` from the reference's noise
    (0: noise-free).  ``relative_weight``: ``1 / (r² + eps)``, relMSE's weight.
    ``delta_e2000_noise`` / ``flip_noise``: the maps of a perfect model plus one
    seeded draw of that noise (the colour metrics' noise floors), or None.
    ``noise_cov``: ``(H, W, 3, 3)`` covariance of ``signed``'s noise (its diagonal is
    ``sigma²``), or None (channels then taken as fully correlated); ``spp``: the truth's
    samples per pixel behind it.
    """

    signed: np.ndarray
    absolute: np.ndarray
    squared: np.ndarray
    relative_squared: np.ndarray
    delta_e2000: np.ndarray | None
    flip: np.ndarray | None
    white: float | None
    flip_params: dict
    valid: np.ndarray | None = None
    nonfinite: np.ndarray | None = None
    sigma: np.ndarray | None = None
    relative_weight: np.ndarray | None = None
    delta_e2000_noise: np.ndarray | None = None
    flip_noise: np.ndarray | None = None
    noise_cov: np.ndarray | None = None
    spp: int = 0

    def __post_init__(self):
        shape = self.absolute.shape
        if self.valid is None:
            self.valid = np.ones(shape, dtype=bool)
        if self.nonfinite is None:
            self.nonfinite = np.zeros(shape, dtype=bool)
        if self.sigma is None:
            self.sigma = np.zeros(self.signed.shape)

    def summary(self, mask=None, z: float = NOISE_Z) -> dict:
        """Scalar metrics over the valid pixels of ``mask`` (pixel-shaped bool, None = all).

        Keys: ``pixels`` (used), ``excluded_pixels`` (in ``mask`` but invalid),
        ``model_nonfinite_pixels``; then, when a pixel is used: ``rmse``,
        ``rmse_stderr`` (half-width of the MSE's ±1 standard error mapped through
        the square root), ``rmse_noise_floor`` (the RMSE of a perfect model),
        ``rmse_debiased``, ``rmse_below_noise``; ``relmse`` with the same suffixes;
        ``mean_error`` (signed, > 0: too bright), ``mean_error_stderr``,
        ``mean_error_below_noise``; ``mean_abs_error`` and its
        ``mean_abs_error_noise_floor`` (``sqrt(2/pi) mean sigma``);
        ``max_abs_error``; ``delta_e2000_mean``, ``delta_e2000_p95``, ``flip_mean``
        (where their maps exist) and their ``*_noise_floor`` where noise maps exist.
        """
        region = np.ones(self.absolute.shape, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
        sel = region & self.valid
        n = int(np.count_nonzero(sel))
        out = {
            "pixels": n,
            "excluded_pixels": int(np.count_nonzero(region & ~self.valid)),
            "model_nonfinite_pixels": int(np.count_nonzero(region & self.nonfinite)),
        }
        if n == 0:
            return out
        # the region's pixels of the noise summaries' inputs, selected once for the three
        signed = np.asarray(self.signed, dtype=np.float64)
        sigma = np.broadcast_to(np.asarray(self.sigma, dtype=np.float64), signed.shape)[sel]
        cov = None if self.noise_cov is None else np.broadcast_to(self.noise_cov, signed.shape + (3,))[sel]
        rel = self.relative_weight
        rel = None if rel is None else np.broadcast_to(np.asarray(rel, dtype=np.float64), signed.shape)[sel]
        signed = signed[sel]
        for name, weight in (("rmse", None), ("relmse", rel)):
            m = mse_noise(signed, sigma, None, weight, z, cov=cov, spp=self.spp)
            value = m["mse"] if name == "relmse" else float(np.sqrt(m["mse"]))
            if name == "rmse":
                hi, lo = math.sqrt(m["mse"] + m["stderr"]), math.sqrt(max(m["mse"] - m["stderr"], 0.0))
                extra = {
                    "rmse_stderr": 0.5 * (hi - lo),
                    "rmse_noise_floor": math.sqrt(m["noise_floor"]),
                    "rmse_debiased": math.sqrt(m["debiased"]),
                }
            else:
                extra = {
                    "relmse_stderr": m["stderr"],
                    "relmse_noise_floor": m["noise_floor"],
                    "relmse_debiased": m["debiased"],
                }
            out.update({name: value, **extra, f"{name}_below_noise": m["below_noise"]})
        if self.relative_weight is None:  # relMSE without its weight: the map's mean, no noise split
            out["relmse"] = float(np.mean(self.relative_squared[sel]))
        me = mean_noise(signed, sigma, None, z, cov=cov)
        out.update(
            {
                "mean_error": me["mean"],
                "mean_error_stderr": me["stderr"],
                "mean_error_below_noise": me["below_noise"],
                "mean_abs_error": float(np.mean(self.absolute[sel])),
                "mean_abs_error_noise_floor": float(math.sqrt(2.0 / math.pi) * np.mean(self.sigma[sel])),
                "max_abs_error": float(np.max(self.absolute[sel])),
            }
        )
        if self.delta_e2000 is not None:
            out["delta_e2000_mean"] = float(np.mean(self.delta_e2000[sel]))
            out["delta_e2000_p95"] = float(np.percentile(self.delta_e2000[sel], 95))
        if self.flip is not None:
            out["flip_mean"] = float(np.mean(self.flip[sel]))
        if self.delta_e2000_noise is not None:
            out["delta_e2000_mean_noise_floor"] = float(np.mean(self.delta_e2000_noise[sel]))
        if self.flip_noise is not None:
            out["flip_mean_noise_floor"] = float(np.mean(self.flip_noise[sel]))
        return out


def error_maps(
    reference,
    test,
    *,
    white: float | None = None,
    eps: float = RELMSE_EPS,
    ppd: float = FLIP_PPD,
    sigma=None,
    valid=None,
    noise_cov=None,
    spp: int = 0,
    perceptual: bool = True,
) -> ErrorMaps:
    """All per-pixel errors of ``test`` against ``reference`` (both ``(H, W, 3)``).

    Parameters
    ----------
    reference : array_like, ``(H, W, 3)``
        Finite linear RGB (ValueError otherwise).
    test : array_like, ``(H, W, 3)``
        The model; non-finite pixels are marked invalid and counted, never averaged.
    white : float, optional
        ΔE exposure white (default :func:`exposure_white` of the reference; pass 1
        for transmittance, whose white is T = 1).
    eps : float
        relMSE stabiliser (> 0) [image units²].
    ppd : float
        FLIP pixels per degree (> 0).
    sigma : array_like, broadcastable to ``(H, W, 3)``, optional
        Standard error of ``test - reference`` from the reference's Monte Carlo
        noise [image units]; default 0 (noise-free).
    valid : array_like of bool, ``(H, W)``, optional
        Pixels where the comparison is defined (default all).
    noise_cov : array_like, ``(H, W, 3, 3)``, optional
        The noise's covariance [image units²]; when given, ``sigma`` is its diagonal's
        root and the noise draw is correlated as it says.
    spp : int
        The truth's samples per pixel (the noise of its estimated variance), 0: exact.
    perceptual : bool
        False: no ΔE2000 or FLIP map (nor their noise floors, nor the noise draw they need):
        the other maps and every other summary are the same, at a fraction of the cost
        (FLIP is most of a comparison's work).

    Returns
    -------
    ErrorMaps

    Examples
    --------
    >>> r = np.full((2, 2, 3), 0.5)
    >>> x = r.copy(); x[0, 0] = np.nan
    >>> e = error_maps(r, x, white=1.0)
    >>> s = e.summary()
    >>> s["pixels"], s["excluded_pixels"], s["model_nonfinite_pixels"], s["rmse"]
    (3, 1, 1, 0.0)
    """
    r, x = check_pair(reference, test)
    if r.ndim != 3:
        raise ValueError(f"error_maps needs (H, W, 3) images, got shape {r.shape}")
    if not eps > 0:
        raise ValueError(f"relMSE eps must be > 0, got {eps}")
    nonfinite = ~finite_pixels(x)
    ok = ~nonfinite if valid is None else (np.asarray(valid, dtype=bool) & ~nonfinite)
    x = np.where(ok[..., None], x, r)  # excluded pixels: error 0 in the maps, left out of every summary
    C = None if noise_cov is None else np.asarray(noise_cov, dtype=np.float64)
    if C is not None:
        C = np.where(ok[..., None, None], C, 0.0)
        sigma = np.sqrt(np.maximum(noise.diagonal(C), 0.0))
    s = np.zeros(r.shape) if sigma is None else np.broadcast_to(np.asarray(sigma, dtype=np.float64), r.shape)
    if count_nonfinite(s) or np.any(s < 0):
        raise ValueError("sigma must be finite and >= 0")
    s = np.where(ok[..., None], s, 0.0)
    de = flip = de_noise = flip_noise = None
    flip_params: dict = {}
    if perceptual:
        if white is None:
            white = exposure_white(r)
        flip, flip_params = flip_map(r, x, ppd)
        if np.any(s > 0):  # the ΔE2000/FLIP noise floors, from one seeded draw (0 where sigma is)
            draw = np.random.default_rng(0).standard_normal(r.shape)
            if C is None:
                noisy = r + s * draw
            else:  # correlated as the noise is
                noisy = r + np.einsum("...ij,...j->...i", noise.sqrt_psd(C), draw)
            de, de_noise = delta_e2000_maps(r, [x, noisy], white)  # the reference in CIELAB once
            flip_noise, _ = flip_map(r, noisy, ppd)
        else:
            (de,) = delta_e2000_maps(r, [x], white)
    return ErrorMaps(
        signed=x - r,
        absolute=abs_error_map(r, x),
        squared=squared_error_map(r, x),
        relative_squared=relative_squared_error_map(r, x, eps),
        delta_e2000=de,
        flip=flip,
        white=None if white is None else float(white),
        flip_params=flip_params,
        valid=ok,
        nonfinite=nonfinite,
        sigma=s,
        relative_weight=1.0 / (r * r + eps),
        delta_e2000_noise=de_noise,
        flip_noise=flip_noise,
        noise_cov=C,
        spp=int(spp),
    )
