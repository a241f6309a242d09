"""Image error metrics between a reference (ground truth) and a test (model) image.

Conventions shared by every function here:

* Argument order is ``(reference, test)``, as in NVIDIA's FLIP.
* Images are **linear** RGB arrays of shape ``(..., 3)`` with Rec.709 / sRGB
  primaries and a D65 white, in the scene's radiance units (or dimensionless, for
  transmittance).  Per-pixel maps have shape ``(...)``: the channel axis is reduced.
* The reference (a ground truth) must be finite: a non-finite reference value is a
  ``ValueError`` (:func:`fogref.gbuffer.load_truth` already refuses such truths).
* A non-finite *test* (model) value is never replaced by a number.  The per-pixel
  maps of :func:`error_maps` mark such pixels invalid (``ErrorMaps.valid``) and every
  summary excludes and counts them; the scalar :func:`rmse` / :func:`relmse` raise
  ``ValueError`` when the pixels they average hold one.
* relMSE divides by ``reference² + eps`` (``eps > 0``), so zero reference pixels
  are fine; ΔE2000 and FLIP are colour metrics of physical radiances: they clip
  negative values to 0 (see :func:`to_display_radiance`); FLIP also clips to a
  multiple of the reference's largest value (see :func:`flip_map`).
* A mean over an empty mask is reported as ``None``, never NaN.

Monte Carlo noise of the reference: given the per-pixel noise covariance of
``test - reference`` (from the truth's ``stderr.*`` and ``corr.*`` channels), :func:`mse_noise`
splits an MSE into the part the truth's noise adds (the *noise floor*, the MSE a
perfect model would get) and the rest, with the standard error of the estimate;
:func:`mean_noise` does the same for the mean signed error.  A metric is *below the
noise* when it is within ``NOISE_Z`` standard errors of what a perfect model would
score.

Metrics (per part: final image, transmittance, inscatter, ...):

===============  =============================================================
RMSE             ``sqrt(mean((x - r)²))`` over pixels *and* channels; units of
                 the image (radiance, or 1 for transmittance)
relMSE           ``mean((x - r)² / (r² + eps))`` over pixels and channels,
                 ``eps = RELMSE_EPS = 1e-2`` (in image units squared); unitless
ΔE2000           CIEDE2000 of CIELAB colours, after the exposure normalisation
                 of :func:`linear_rgb_to_lab`; unitless (1 ≈ just noticeable)
FLIP             HDR-FLIP (Andersson et al. 2021) via ``flip_evaluator``,
                 in [0, 1]; 67 pixels per degree unless told otherwise
===============  =============================================================
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from fogref.compare import noise

#: relMSE's stabiliser, in image units squared: ``(x - r)² / (r² + eps)``.
RELMSE_EPS = 1e-2
#: Percentile of the reference luminance that the ΔE exposure maps to white (Y = 1).
WHITE_PERCENTILE = 99.0
#: FLIP's default viewing condition: pixels per degree of visual angle.
FLIP_PPD = 67.0
#: FLIP inputs are clipped to this many times the reference's largest finite value.
FLIP_CEILING_FACTOR = 1e4
#: Widest HDR-FLIP exposure range [stops] before it is narrowed (see :func:`flip_map`).
FLIP_MAX_STOPS = 20
#: Rec.709 / sRGB luminance weights (linear RGB -> Y).
REC709_LUMINANCE = np.array([0.2126, 0.7152, 0.0722])

_FLT_MAX = float(np.finfo(np.float32).max)
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


def luminance(rgb) -> np.ndarray:
    """Rec.709 relative luminance ``Y`` of linear RGB ``(..., 3)`` -> ``(...)``; same units."""
    return np.asarray(rgb, dtype=np.float64) @ REC709_LUMINANCE


def _check_pair(reference, test) -> tuple[np.ndarray, np.ndarray]:
    r, x = np.asarray(reference, dtype=np.float64), np.asarray(test, dtype=np.float64)
    if r.shape != x.shape:
        raise ValueError(f"reference and test shapes differ: {r.shape} vs {x.shape}")
    if r.ndim == 0 or r.shape[-1] != 3:
        raise ValueError(f"expected (..., 3) RGB images, got shape {r.shape}")
    n = count_nonfinite(r)
    if n:
        raise ValueError(f"the reference holds {n} non-finite value(s); a ground truth must be finite")
    return r, x


def _require_finite_test(x: np.ndarray, what: str) -> None:
    n = count_nonfinite(x)
    if n:
        raise ValueError(f"{what}: the test image holds {n} non-finite value(s); mask those pixels out "
                         "(error_maps does, and counts them)")


def _masked_mean(per_pixel: np.ndarray, mask, what: str = "metric") -> float | None:
    """Mean of a per-pixel map over ``mask`` (all pixels if None); None if empty.

    Raises ValueError when a selected value is not finite (never averaged away)."""
    if mask is not None:
        per_pixel = per_pixel[np.asarray(mask, dtype=bool)]
    if per_pixel.size == 0:
        return None
    _require_finite_test(per_pixel, what)
    return float(np.mean(per_pixel))


# ---------------------------------------------------------------- per-pixel maps


def signed_error(reference, test) -> np.ndarray:
    """``test - reference``, per channel, ``(..., 3)``; image units."""
    r, x = _check_pair(reference, test)
    return x - r


def squared_error_map(reference, test) -> np.ndarray:
    """``mean_c (x_c - r_c)²`` per pixel, ``(...)``; image units squared."""
    r, x = _check_pair(reference, test)
    return np.mean((x - r) ** 2, axis=-1)


def abs_error_map(reference, test) -> np.ndarray:
    """``mean_c |x_c - r_c|`` per pixel, ``(...)``; image units."""
    r, x = _check_pair(reference, test)
    return np.mean(np.abs(x - r), axis=-1)


def relative_squared_error_map(reference, test, eps: float = RELMSE_EPS) -> np.ndarray:
    """``mean_c (x_c - r_c)² / (r_c² + eps)`` per pixel, ``(...)``; unitless.

    ``eps`` (> 0, image units squared) keeps zero-valued reference pixels finite.
    """
    if not eps > 0:
        raise ValueError(f"relMSE eps must be > 0, got {eps}")
    r, x = _check_pair(reference, test)
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
    C = s[..., :, None] * s[..., None, :] if cov is None else np.broadcast_to(
        np.asarray(cov, dtype=np.float64), d.shape + (3,))
    if mask is not None:
        m = np.asarray(mask, dtype=bool)
        d, w, C = d[m], w[m], C[m]
    d, w, C = d.reshape(-1, 3), w.reshape(-1, 3), C.reshape(-1, 3, 3)
    _require_finite_test(d, "noise")
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
    _, var = noise.squared_stat(d, C, spp, w)
    _, null_var = noise.squared_stat(np.zeros_like(d), C, spp, w)
    stderr, null = math.sqrt(var) / n, math.sqrt(null_var) / n
    return {"mse": mse, "noise_floor": floor, "stderr": stderr, "debiased": max(mse - floor, 0.0),
            "null_stderr": null, "below_noise": bool(mse - floor <= z * null)}


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


# ---------------------------------------------------------------- ΔE2000


def exposure_white(reference, percentile: float = WHITE_PERCENTILE) -> float:
    """The radiance that the exposure normalisation maps to white (``Y = 1``).

    It is the ``percentile``-th percentile of the reference's Rec.709 luminance over
    its pixels with positive luminance (falling back to their maximum when the
    percentile is 0, and to 1 when no pixel is positive).  Always finite and > 0.
    Units: those of ``reference``.
    """
    y = luminance(reference).ravel()
    y = y[np.isfinite(y) & (y > 0)]
    if y.size == 0:
        return 1.0
    w = float(np.percentile(y, percentile))
    if not w > 0:
        w = float(y.max())
    return min(w, _FLT_MAX)


def to_display_radiance(image, ceiling: float | None = None) -> np.ndarray:
    """``image`` (finite) with negatives clipped to 0 and values clipped to ``ceiling``.

    Colour metrics (ΔE2000, FLIP) treat pixels as physical, non-negative radiances.
    ``ceiling``: default FLT_MAX.  ValueError for a non-finite value.
    """
    x = np.asarray(image, dtype=np.float64)
    _require_finite_test(x, "colour metric")
    return np.clip(x, 0.0, _FLT_MAX if ceiling is None else ceiling)


def linear_rgb_to_lab(rgb, white: float) -> np.ndarray:
    """CIELAB (D65) of linear sRGB/Rec.709 ``rgb`` after exposure normalisation.

    Steps: ``rgb / white`` (so that luminance ``white`` becomes ``Y = 1``, i.e.
    L* = 100; brighter pixels get L* > 100, which CIEDE2000 handles), negatives
    clipped to 0, then colour-science's linear sRGB -> XYZ (no CCTF decoding) and
    XYZ -> Lab with the D65 white point.  ``white`` must be finite and > 0.
    """
    import colour

    if not (np.isfinite(white) and white > 0):
        raise ValueError(f"white must be finite and > 0, got {white}")
    x = to_display_radiance(rgb) / white
    xyz = colour.RGB_to_XYZ(x, "sRGB", apply_cctf_decoding=False)
    return colour.XYZ_to_Lab(xyz, colour.RGB_COLOURSPACES["sRGB"].whitepoint)


def delta_e2000_map(reference, test, white: float | None = None) -> np.ndarray:
    """CIEDE2000 per pixel, ``(...)``; unitless.

    Both images are exposure-normalised by the **same** ``white`` (default:
    :func:`exposure_white` of the reference), see :func:`linear_rgb_to_lab`.
    """
    import colour

    r, x = _check_pair(reference, test)
    if white is None:
        white = exposure_white(r)
    _require_finite_test(x, "ΔE2000")
    de = colour.delta_E(linear_rgb_to_lab(r, white), linear_rgb_to_lab(x, white), method="CIE 2000")
    return np.asarray(de, dtype=np.float64)


# ---------------------------------------------------------------- FLIP


def _import_flip_evaluator():
    """Import ``flip_evaluator`` with OpenMP's passive wait policy unless the user chose one.

    ``flip_evaluator`` bundles its own libgomp.  With the default (spinning) wait
    policy and other thread pools in the process, a 32×24 FLIP took 0.2–1.7 s here
    instead of 5 ms, on 2 shared cores.  libgomp reads the variable when it loads, so
    this must run before the first import; it changes nothing if set already.
    """
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
    import flip_evaluator

    return flip_evaluator


def flip_exposure_range(reference) -> tuple[float, float] | None:
    """HDR-FLIP's own exposure range ``(start, stop)`` [stops] for ``reference``.

    As in FLIP (ACES tone mapper, t = 0.85): ``start = log2(x / max Y)``, ``stop =
    log2(x / median Y)`` with ``x`` the linear value ACES maps to 0.85 and the median
    floored at float32's epsilon.  None when the reference has no positive luminance.
    """
    k0, k1, k2 = 0.6 * 0.6 * 2.51, 0.6 * 0.03, 0.0
    k3, k4, k5 = 0.6 * 0.6 * 2.43, 0.6 * 0.59, 0.14
    t = 0.85
    c0, c1 = (k1 - k4 * t) / (k0 - k3 * t), (k2 - k5 * t) / (k0 - k3 * t)
    x = -0.5 * c0 + np.sqrt((0.5 * c0) ** 2 - c1)
    y = luminance(reference)
    y_hi = float(y.max(initial=0.0))
    if not y_hi > 0:
        return None
    y_lo = max(float(np.median(y)), float(np.finfo(np.float32).eps))
    return float(np.log2(x / y_hi)), float(np.log2(x / y_lo))


def flip_map(reference, test, ppd: float = FLIP_PPD) -> tuple[np.ndarray, dict]:
    """HDR-FLIP error map ``(H, W)`` in [0, 1] and the parameters FLIP used.

    Inputs are linear sRGB ``(H, W, 3)``, clipped to ``[0, FLIP_CEILING_FACTOR x the
    reference's largest finite value]`` (HDR-FLIP needs non-negative, finite
    radiances; anything that bright is saturated by FLIP's tone mapping anyway).

    FLIP chooses its exposures itself (one per stop from the reference's maximum to
    its median, :func:`flip_exposure_range`), except in two cases that
    ``flip_evaluator`` handles badly:

    * that range is wider than ``FLIP_MAX_STOPS`` (run time grows with it; a single
      extreme pixel can make it 100 stops): the start is raised to
      ``stop - FLIP_MAX_STOPS``, one exposure per stop, so the brightest pixels
      saturate but the bulk of the image is examined as usual;
    * the reference has no positive luminance (``flip_evaluator`` then *exits the
      process*): the range is pinned to ``start = stop = log2(1 / max test
      luminance)``, or the map is all zero when the test is black too.

    ``ppd`` must be > 0 (``flip_evaluator`` exits the process otherwise).
    """
    flip_evaluator = _import_flip_evaluator()
    if not (np.isfinite(ppd) and ppd > 0):
        raise ValueError(f"FLIP pixels per degree must be finite and > 0, got {ppd}")
    r, x = _check_pair(reference, test)
    if r.ndim != 3:
        raise ValueError(f"FLIP needs (H, W, 3) images, got shape {r.shape}")
    r, x = to_display_radiance(r), to_display_radiance(x)
    r_max = float(r[r < _FLT_MAX].max(initial=0.0))
    ceiling = FLIP_CEILING_FACTOR * r_max if r_max > 0 else 1e30
    r, x = np.minimum(r, ceiling), np.minimum(x, ceiling)
    params: dict = {"ppd": float(ppd)}
    span = flip_exposure_range(r)
    if span is None:
        y_test = float(luminance(x).max(initial=0.0))
        if not y_test > 0:
            return np.zeros(r.shape[:2]), {"ppd": float(ppd), "note": "reference and test are black"}
        e = float(np.log2(1.0 / y_test))
        params.update(startExposure=e, stopExposure=e, numExposures=2)
    elif span[1] - span[0] > FLIP_MAX_STOPS:
        params.update(startExposure=span[1] - FLIP_MAX_STOPS, stopExposure=span[1], numExposures=FLIP_MAX_STOPS + 1)
    err, _, used = flip_evaluator.evaluate(
        r.astype(np.float32), x.astype(np.float32), "HDR", applyMagma=False, parameters=params
    )
    err = np.asarray(err, dtype=np.float64).reshape(r.shape[:2])
    return np.clip(err, 0.0, 1.0), {k: (float(v) if isinstance(v, (int, float)) else v) for k, v in used.items()}


# ---------------------------------------------------------------- all at once


@dataclass
class ErrorMaps:
    """Every per-pixel error of one part (e.g. the final image), shape ``(H, W)`` each.

    ``signed``: ``test - reference`` per channel ``(H, W, 3)`` [image units];
    ``absolute``: ``mean_c |x - r|`` [image units]; ``squared``: ``mean_c (x - r)²``
    [units²]; ``relative_squared``: relMSE's per-pixel term [1]; ``delta_e2000`` [1];
    ``flip`` [0..1].  ``white``: the ΔE exposure white [image units];
    ``flip_params``: what FLIP used.

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
    delta_e2000: np.ndarray
    flip: np.ndarray
    white: float
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

    def selection(self, mask=None) -> np.ndarray:
        """``(H, W)`` bool: the valid pixels of ``mask`` (None: all)."""
        sel = np.ones(self.absolute.shape, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
        return sel & self.valid

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
        and their ``*_noise_floor`` where noise maps exist.
        """
        region = np.ones(self.absolute.shape, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
        sel = region & self.valid
        n = int(np.count_nonzero(sel))
        out = {"pixels": n, "excluded_pixels": int(np.count_nonzero(region & ~self.valid)),
               "model_nonfinite_pixels": int(np.count_nonzero(region & self.nonfinite))}
        if n == 0:
            return out
        for name, weight in (("rmse", None), ("relmse", self.relative_weight)):
            m = mse_noise(self.signed, self.sigma, sel, weight, z, cov=self.noise_cov, spp=self.spp)
            value = m["mse"] if name == "relmse" else float(np.sqrt(m["mse"]))
            if name == "rmse":
                hi, lo = math.sqrt(m["mse"] + m["stderr"]), math.sqrt(max(m["mse"] - m["stderr"], 0.0))
                extra = {"rmse_stderr": 0.5 * (hi - lo), "rmse_noise_floor": math.sqrt(m["noise_floor"]),
                         "rmse_debiased": math.sqrt(m["debiased"])}
            else:
                extra = {"relmse_stderr": m["stderr"], "relmse_noise_floor": m["noise_floor"],
                         "relmse_debiased": m["debiased"]}
            out.update({name: value, **extra, f"{name}_below_noise": m["below_noise"]})
        if self.relative_weight is None:  # relMSE without its weight: the map's mean, no noise split
            out["relmse"] = float(np.mean(self.relative_squared[sel]))
        me = mean_noise(self.signed, self.sigma, sel, z, cov=self.noise_cov)
        out.update({
            "mean_error": me["mean"], "mean_error_stderr": me["stderr"], "mean_error_below_noise": me["below_noise"],
            "mean_abs_error": float(np.mean(self.absolute[sel])),
            "mean_abs_error_noise_floor": float(math.sqrt(2.0 / math.pi) * np.mean(self.sigma[sel])),
            "max_abs_error": float(np.max(self.absolute[sel])),
            "delta_e2000_mean": float(np.mean(self.delta_e2000[sel])),
            "delta_e2000_p95": float(np.percentile(self.delta_e2000[sel], 95)),
            "flip_mean": float(np.mean(self.flip[sel])),
        })
        if self.delta_e2000_noise is not None:
            out["delta_e2000_mean_noise_floor"] = float(np.mean(self.delta_e2000_noise[sel]))
        if self.flip_noise is not None:
            out["flip_mean_noise_floor"] = float(np.mean(self.flip_noise[sel]))
        return out


def error_maps(
    reference, test, *, white: float | None = None, eps: float = RELMSE_EPS, ppd: float = FLIP_PPD,
    sigma=None, valid=None, noise_seed: int | None = 0, noise_cov=None, spp: int = 0,
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
    noise_seed : int or None
        Seed of the noise draw for the ΔE2000/FLIP noise floors (None: skip them;
        they are also skipped when ``sigma`` is 0 everywhere, where they are 0).
    noise_cov : array_like, ``(H, W, 3, 3)``, optional
        The noise's covariance [image units²]; when given, ``sigma`` is its diagonal's
        root and the noise draw is correlated as it says.
    spp : int
        The truth's samples per pixel (the noise of its estimated variance), 0: exact.

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
    r, x = _check_pair(reference, test)
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
    if white is None:
        white = exposure_white(r)
    flip, flip_params = flip_map(r, x, ppd)
    de_noise = flip_noise = None
    if noise_seed is not None and np.any(s > 0):
        draw = np.random.default_rng(noise_seed).standard_normal(r.shape)
        if C is None:
            noisy = r + s * draw
        else:  # correlated as the noise is
            noisy = r + np.einsum("...ij,...j->...i", noise.sqrt_psd(C), draw)
        de_noise = delta_e2000_map(r, noisy, white)
        flip_noise, _ = flip_map(r, noisy, ppd)
    return ErrorMaps(
        signed=x - r,
        absolute=abs_error_map(r, x),
        squared=squared_error_map(r, x),
        relative_squared=relative_squared_error_map(r, x, eps),
        delta_e2000=delta_e2000_map(r, x, white),
        flip=flip,
        white=float(white),
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
