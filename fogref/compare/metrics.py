"""Image error metrics between a reference (ground truth) and a test (model) image.

Conventions shared by every function here:

* Argument order is ``(reference, test)``, as in NVIDIA's FLIP.
* Images are **linear** RGB arrays of shape ``(..., 3)`` with Rec.709 / sRGB
  primaries and a D65 white, in the scene's radiance units (or dimensionless, for
  transmittance).  Per-pixel maps have shape ``(...)``: the channel axis is reduced.
* Nothing returned is NaN or infinite, on purpose:

  - every input is first passed through :func:`sanitize` (``NaN -> 0``,
    ``+inf -> +FLT_MAX``, ``-inf -> -FLT_MAX``) and computed in float64, so a broken
    pixel shows up as a huge, finite error instead of poisoning a mean;
  - relMSE divides by ``reference² + eps`` (``eps > 0``), so zero reference pixels
    are fine;
  - ΔE2000 and FLIP are colour metrics of physical radiances: they clip negative
    values to 0 (see :func:`to_display_radiance`); FLIP also clips to a multiple of
    the reference's largest finite value (see :func:`flip_map`);
  - a mean over an empty mask is reported as ``None`` by the callers, never NaN.

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

import os
from dataclasses import dataclass

import numpy as np

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


def sanitize(image) -> np.ndarray:
    """``image`` as float64 with ``NaN -> 0`` and ``±inf -> ±FLT_MAX`` (float32's max).

    Used on every metric input, so that a non-finite pixel of a model (e.g. a float32
    overflow) counts as a huge but finite error.
    """
    x = np.asarray(image, dtype=np.float64)
    return np.nan_to_num(x, nan=0.0, posinf=_FLT_MAX, neginf=-_FLT_MAX)


def count_nonfinite(image) -> int:
    """Number of NaN or infinite values in ``image`` (all channels counted)."""
    return int(np.size(image) - np.count_nonzero(np.isfinite(image)))


def luminance(rgb) -> np.ndarray:
    """Rec.709 relative luminance ``Y`` of linear RGB ``(..., 3)`` -> ``(...)``; same units."""
    return sanitize(rgb) @ REC709_LUMINANCE


def _check_pair(reference, test) -> tuple[np.ndarray, np.ndarray]:
    r, x = sanitize(reference), sanitize(test)
    if r.shape != x.shape:
        raise ValueError(f"reference and test shapes differ: {r.shape} vs {x.shape}")
    if r.ndim == 0 or r.shape[-1] != 3:
        raise ValueError(f"expected (..., 3) RGB images, got shape {r.shape}")
    return r, x


def _masked_mean(per_pixel: np.ndarray, mask) -> float | None:
    """Mean of a per-pixel map over ``mask`` (all pixels if None); None if empty."""
    if mask is not None:
        per_pixel = per_pixel[np.asarray(mask, dtype=bool)]
    if per_pixel.size == 0:
        return None
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
    """Root mean squared error over pixels (in ``mask``) and channels; image units.

    ``mask``: boolean array of the image's pixel shape ``(...)``, or None for all.
    Returns None when the mask selects no pixel.
    """
    m = _masked_mean(squared_error_map(reference, test), mask)
    return None if m is None else float(np.sqrt(m))


def relmse(reference, test, eps: float = RELMSE_EPS, mask=None) -> float | None:
    """Relative MSE ``mean((x - r)² / (r² + eps))`` over pixels and channels; unitless."""
    return _masked_mean(relative_squared_error_map(reference, test, eps), mask)


# ---------------------------------------------------------------- ΔE2000


def exposure_white(reference, percentile: float = WHITE_PERCENTILE) -> float:
    """The radiance that the exposure normalisation maps to white (``Y = 1``).

    It is the ``percentile``-th percentile of the reference's Rec.709 luminance over
    its pixels with positive luminance (falling back to their maximum when the
    percentile is 0, and to 1 when no pixel is positive).  Always finite and > 0.
    Units: those of ``reference``.
    """
    y = luminance(reference).ravel()
    y = y[y > 0]
    if y.size == 0:
        return 1.0
    w = float(np.percentile(y, percentile))
    if not w > 0:
        w = float(y.max())
    return min(w, _FLT_MAX)


def to_display_radiance(image, ceiling: float | None = None) -> np.ndarray:
    """Sanitised ``image`` with negatives clipped to 0 and values clipped to ``ceiling``.

    Colour metrics (ΔE2000, FLIP) treat pixels as physical, non-negative radiances.
    ``ceiling`` (default FLT_MAX) bounds ``+inf`` replacements.
    """
    x = sanitize(image)
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
    de = colour.delta_E(linear_rgb_to_lab(r, white), linear_rgb_to_lab(x, white), method="CIE 2000")
    return sanitize(de)


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
    err = sanitize(np.asarray(err)).reshape(r.shape[:2])
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
    """

    signed: np.ndarray
    absolute: np.ndarray
    squared: np.ndarray
    relative_squared: np.ndarray
    delta_e2000: np.ndarray
    flip: np.ndarray
    white: float
    flip_params: dict

    def summary(self, mask=None) -> dict:
        """Scalar metrics over ``mask`` (pixel-shaped bool, None = all); None if empty.

        Keys: ``pixels``, ``rmse``, ``relmse``, ``mean_abs_error``, ``max_abs_error``,
        ``delta_e2000_mean``, ``delta_e2000_p95``, ``flip_mean``.
        """
        sel = np.ones(self.absolute.shape, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
        n = int(np.count_nonzero(sel))
        if n == 0:
            return {"pixels": 0}
        mse = float(np.mean(self.squared[sel]))
        return {
            "pixels": n,
            "rmse": float(np.sqrt(mse)),
            "relmse": float(np.mean(self.relative_squared[sel])),
            "mean_abs_error": float(np.mean(self.absolute[sel])),
            "max_abs_error": float(np.max(self.absolute[sel])),
            "delta_e2000_mean": float(np.mean(self.delta_e2000[sel])),
            "delta_e2000_p95": float(np.percentile(self.delta_e2000[sel], 95)),
            "flip_mean": float(np.mean(self.flip[sel])),
        }


def error_maps(
    reference, test, *, white: float | None = None, eps: float = RELMSE_EPS, ppd: float = FLIP_PPD
) -> ErrorMaps:
    """All per-pixel errors of ``test`` against ``reference`` (both ``(H, W, 3)``).

    ``white``: ΔE exposure white (default :func:`exposure_white` of the reference;
    pass 1 for transmittance, whose white is T = 1).  ``eps``: relMSE stabiliser.
    """
    r, x = _check_pair(reference, test)
    if white is None:
        white = exposure_white(r)
    flip, flip_params = flip_map(r, x, ppd)
    return ErrorMaps(
        signed=x - r,
        absolute=abs_error_map(r, x),
        squared=squared_error_map(r, x),
        relative_squared=relative_squared_error_map(r, x, eps),
        delta_e2000=delta_e2000_map(r, x, white),
        flip=flip,
        white=float(white),
        flip_params=flip_params,
    )
