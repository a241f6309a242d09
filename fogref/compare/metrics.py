"""Pixel error metrics between a reference (ground truth) and a test (model) image.

Conventions shared by the metrics of :mod:`fogref.compare` (this module,
:mod:`~fogref.compare.perceptual`, :mod:`~fogref.compare.error_maps`):

* Argument order is ``(reference, test)``, as in NVIDIA's FLIP.
* Images are **linear** RGB arrays of shape ``(..., 3)`` with Rec.709 / sRGB
  primaries and a D65 white, in the scene's radiance units (or dimensionless, for
  transmittance).  Per-pixel maps have shape ``(...)``: the channel axis is reduced.
* The reference (a ground truth) must be finite: a non-finite reference value is a
  ``ValueError`` (:func:`fogref.gbuffer.load_truth` already refuses such truths).
* A non-finite *test* (model) value is never replaced by a number: the scalar
  :func:`rmse` / :func:`relmse` raise ``ValueError`` when the pixels they average hold
  one (:func:`fogref.compare.error_maps.error_maps` marks such pixels invalid).
* relMSE divides by ``reference² + eps`` (``eps > 0``), so zero reference pixels
  are fine.  A mean over an empty mask is reported as ``None``, never NaN.

Monte Carlo noise of the reference: given the per-pixel noise covariance of
``test - reference`` (from the truth's ``stderr.*`` and ``corr.*`` channels), :func:`mse_noise`
splits an MSE into the part the truth's noise adds (the *noise floor*, the MSE a
perfect model would get) and the rest, with the standard error of the estimate;
:func:`mean_noise` does the same for the mean signed error.  A metric is *below the
noise* when it is within ``NOISE_Z`` standard errors of what a perfect model would
score.

===============  =============================================================
RMSE             ``sqrt(mean((x - r)²))`` over pixels *and* channels; units of
                 the image (radiance, or 1 for transmittance)
relMSE           ``mean((x - r)² / (r² + eps))`` over pixels and channels,
                 ``eps = RELMSE_EPS = 1e-2`` (in image units squared); unitless
===============  =============================================================
"""

from __future__ import annotations

import math

import numpy as np

from fogref.compare import noise

#: relMSE's stabiliser, in image units squared: ``(x - r)² / (r² + eps)``.
RELMSE_EPS = 1e-2
#: A metric is "below the noise" within this many standard errors of a perfect model's.
NOISE_Z = 3.0


def count_nonfinite(image) -> int:
    """Number of NaN or infinite values in ``image`` (all channels counted).

    Examples
    --------
    >>> count_nonfinite(np.array([1.0, np.nan, np.inf, -2.0]))
    2
    """
    return int(np.size(image) - np.count_nonzero(np.isfinite(image)))


def finite_pixels(image) -> np.ndarray:
    """``(...)`` bool: every channel of the pixel of ``image (..., 3)`` is finite.

    Examples
    --------
    >>> finite_pixels(np.array([[1.0, 2.0, 3.0], [0.0, np.nan, 0.0]])).tolist()
    [True, False]
    """
    return np.all(np.isfinite(np.asarray(image, dtype=np.float64)), axis=-1)


def check_pair(reference, test) -> tuple[np.ndarray, np.ndarray]:
    """``(reference, test)`` as float64 arrays after the shared checks: same shape ``(..., 3)``,
    a finite reference (``ValueError`` otherwise).

    >>> check_pair(np.zeros(3), np.ones(2))
    Traceback (most recent call last):
    ...
    ValueError: reference and test shapes differ: (3,) vs (2,)
    """
    r, x = np.asarray(reference, dtype=np.float64), np.asarray(test, dtype=np.float64)
    if r.shape != x.shape:
        raise ValueError(f"reference and test shapes differ: {r.shape} vs {x.shape}")
    if r.ndim == 0 or r.shape[-1] != 3:
        raise ValueError(f"expected (..., 3) RGB images, got shape {r.shape}")
    n = count_nonfinite(r)
    if n:
        raise ValueError(f"the reference holds {n} non-finite value(s); a ground truth must be finite")
    return r, x


def require_finite(x: np.ndarray, what: str) -> None:
    """``ValueError`` naming ``what`` when the test values ``x`` hold a NaN or an infinity.

    >>> require_finite(np.array([1.0, np.inf]), "rmse")
    Traceback (most recent call last):
    ...
    ValueError: rmse: the test image holds 1 non-finite value(s); mask those pixels out ...
    """
    n = count_nonfinite(x)
    if n:
        raise ValueError(
            f"{what}: the test image holds {n} non-finite value(s); mask those pixels out "
            "(error_maps does, and counts them)"
        )


def _masked_mean(per_pixel: np.ndarray, mask, what: str = "metric") -> float | None:
    """Mean of a per-pixel map over ``mask`` (all pixels if None); None if empty.

    Raises ValueError when a selected value is not finite (never averaged away)."""
    if mask is not None:
        per_pixel = per_pixel[np.asarray(mask, dtype=bool)]
    if per_pixel.size == 0:
        return None
    require_finite(per_pixel, what)
    return float(np.mean(per_pixel))


# ---------------------------------------------------------------- per-pixel maps


def signed_error(reference, test) -> np.ndarray:
    """``test - reference``, per channel, ``(..., 3)``; image units."""
    r, x = check_pair(reference, test)
    return x - r


def squared_error_map(reference, test) -> np.ndarray:
    """``mean_c (x_c - r_c)²`` per pixel, ``(...)``; image units squared."""
    r, x = check_pair(reference, test)
    return np.mean((x - r) ** 2, axis=-1)


def abs_error_map(reference, test) -> np.ndarray:
    """``mean_c |x_c - r_c|`` per pixel, ``(...)``; image units."""
    r, x = check_pair(reference, test)
    return np.mean(np.abs(x - r), axis=-1)


def relative_squared_error_map(reference, test, eps: float = RELMSE_EPS) -> np.ndarray:
    """``mean_c (x_c - r_c)² / (r_c² + eps)`` per pixel, ``(...)``; unitless.

    ``eps`` (> 0, image units squared) keeps zero-valued reference pixels finite.
    """
    if not eps > 0:
        raise ValueError(f"relMSE eps must be > 0, got {eps}")
    r, x = check_pair(reference, test)
    return np.mean((x - r) ** 2 / (r * r + eps), axis=-1)


# ---------------------------------------------------------------- scalar metrics


def rmse(reference, test, mask=None) -> float | None:
    """Root mean squared error over pixels (in ``mask``) and channels.

    Parameters
    ----------
    reference, test : array_like, ``(..., 3)``
        Linear RGB images in the same units; ``reference`` finite.
    mask : array_like of bool, ``(...)``, optional
        Pixels to average over (default: all).

    Returns
    -------
    float or None
        RMSE in the images' units, in ``[0, inf)``; None when ``mask`` selects no
        pixel.  ValueError if a selected test value is not finite.

    Examples
    --------
    >>> r = np.zeros((1, 2, 3))
    >>> x = np.array([[[1.0, 1.0, 1.0], [3.0, 3.0, 3.0]]])
    >>> rmse(r, x)
    2.23606797749979
    >>> rmse(r, x, mask=np.array([[True, False]]))
    1.0
    """
    m = _masked_mean(squared_error_map(reference, test), mask, "rmse")
    return None if m is None else float(np.sqrt(m))


def relmse(reference, test, eps: float = RELMSE_EPS, mask=None) -> float | None:
    """Relative MSE ``mean((x - r)² / (r² + eps))`` over pixels and channels.

    Parameters
    ----------
    reference, test : array_like, ``(..., 3)``
        Linear RGB images; ``reference`` finite.
    eps : float
        Stabiliser (> 0) in image units squared.
    mask : array_like of bool, ``(...)``, optional

    Returns
    -------
    float or None
        Unitless, in ``[0, inf)``; None for an empty mask.

    Examples
    --------
    >>> relmse(np.ones((1, 1, 3)), np.full((1, 1, 3), 2.0), eps=1.0)
    0.5
    """
    return _masked_mean(relative_squared_error_map(reference, test, eps), mask, "relmse")


def _noise_inputs(diff, sigma, mask, weight, cov):
    d = np.asarray(diff, dtype=np.float64)
    s = np.broadcast_to(np.asarray(sigma, dtype=np.float64), d.shape)
    w = np.ones_like(d) if weight is None else np.broadcast_to(np.asarray(weight, dtype=np.float64), d.shape)
    if count_nonfinite(s) or np.any(s < 0):
        raise ValueError("standard errors must be finite and >= 0")
    # no covariance given: the channels' noise is taken as fully correlated (an upper bound
    # for sums of positive weights: they come from the same samples)
    C = (
        s[..., :, None] * s[..., None, :]
        if cov is None
        else np.broadcast_to(np.asarray(cov, dtype=np.float64), d.shape + (3,))
    )
    if mask is not None:
        m = np.asarray(mask, dtype=bool)
        d, w, C = d[m], w[m], C[m]
    d, w, C = d.reshape(-1, 3), w.reshape(-1, 3), C.reshape(-1, 3, 3)
    require_finite(d, "noise")
    return d, w, C


def mse_noise(diff, sigma, mask=None, weight=None, z: float = NOISE_Z, cov=None, spp: int = 0) -> dict | None:
    """A (weighted) MSE and the part of it that the reference's Monte Carlo noise explains.

    With ``d = test - reference`` per channel and ``C`` the per-pixel covariance of the
    noise of ``d`` (pixels independent), the estimate ``mean(w d²)`` has expectation
    ``mean(w bias²) + mean(w C_cc)``.  The second term is the *noise floor*: what a
    perfect model would score.  The standard error of the estimate is the one delta
    method of :func:`fogref.compare.noise.squared_stat` (channels' covariance used whole).

    Parameters
    ----------
    diff : array_like, ``(..., 3)``
        ``test - reference`` [image units]; finite.
    sigma : array_like, ``(..., 3)`` or broadcastable
        Standard error of ``diff`` [image units], >= 0.
    mask : array_like of bool, ``(...)``, optional
        Pixels to use (default all).
    weight : array_like, optional
        Per-value weight (e.g. ``1 / (r² + eps)`` for relMSE); default 1.
    z : float
        Standard errors within which a value counts as *below the noise*.
    cov : array_like, ``(..., 3, 3)``, optional
        Covariance of ``diff``'s noise [image units²] (its diagonal is ``sigma²``);
        default: the channels fully correlated, an upper bound.
    spp : int
        Samples per pixel behind ``cov`` (the noise of the estimated variance), 0: exact.

    Returns
    -------
    dict or None
        ``mse`` (>= 0), ``noise_floor`` (>= 0), ``stderr`` of ``mse`` (>= 0),
        ``debiased`` = ``max(mse - noise_floor, 0)``, ``null_stderr`` (the stderr a
        perfect model would have) and ``below_noise``: ``mse - noise_floor <= z *
        null_stderr``.  None for an empty selection.

    Examples
    --------
    A model that is off by exactly the noise level everywhere:

    >>> r = mse_noise(np.full((10, 10, 3), 0.1), 0.1)
    >>> round(r["mse"], 6), round(r["noise_floor"], 6), r["below_noise"]
    (0.01, 0.01, True)
    >>> mse_noise(np.full((10, 10, 3), 0.5), 0.1)["below_noise"]
    False
    """
    d, w, C = _noise_inputs(diff, sigma, mask, weight, cov)
    n = d.size
    if n == 0:
        return None
    mse = float(np.mean(w * d * d))
    floor = float(np.mean(w * noise.diagonal(C)))
    _, var, null_var = noise.squared_stat_and_null(d, C, spp, w)
    stderr, null = math.sqrt(var) / n, math.sqrt(null_var) / n
    return {
        "mse": mse,
        "noise_floor": floor,
        "stderr": stderr,
        "debiased": max(mse - floor, 0.0),
        "null_stderr": null,
        "below_noise": bool(mse - floor <= z * null),
    }


def mean_noise(diff, sigma, mask=None, z: float = NOISE_Z, cov=None) -> dict | None:
    """Mean signed error over pixels and channels, with its standard error from the noise.

    Parameters
    ----------
    diff : array_like, ``(..., 3)``
        ``test - reference`` [image units]; finite.
    sigma : array_like, broadcastable to ``diff``
        Standard error of ``diff`` [image units], >= 0.
    mask : array_like of bool, ``(...)``, optional
    z : float
        Standard errors within which the mean counts as *below the noise*.
    cov : array_like, ``(..., 3, 3)``, optional
        As in :func:`mse_noise` (default: channels fully correlated).

    Returns
    -------
    dict or None
        ``mean`` [image units; > 0: the model is too bright], ``stderr`` (pixels
        independent, :func:`fogref.compare.noise.sum_var`) and ``below_noise``:
        ``|mean| <= z * stderr``.  None for an empty selection.

    Examples
    --------
    >>> m = mean_noise(np.full((4, 4, 3), 0.01), 0.1)
    >>> round(m["mean"], 6), round(m["stderr"], 6), m["below_noise"]
    (0.01, 0.025, True)
    """
    d, _, C = _noise_inputs(diff, sigma, mask, None, cov)
    n = d.size
    if n == 0:
        return None
    mean = float(np.mean(d))
    stderr = math.sqrt(noise.sum_var(C)) / n
    return {"mean": mean, "stderr": stderr, "below_noise": bool(abs(mean) <= z * stderr)}
