"""Colour metrics of physical radiances: CIEDE2000 and HDR-FLIP.

Conventions as in :mod:`fogref.compare.metrics` (``(reference, test)``, linear
Rec.709 RGB ``(..., 3)``, finite reference).  Both treat pixels as physical,
non-negative radiances: they clip negative values to 0 (:func:`to_display_radiance`);
FLIP also clips to a multiple of the reference's largest value (:func:`flip_map`).

===============  =============================================================
ΔE2000           CIEDE2000 of CIELAB colours, after the exposure normalisation
                 of :func:`linear_rgb_to_lab`; unitless (1 ≈ just noticeable)
FLIP             HDR-FLIP (Andersson et al. 2021) via ``flip_evaluator``,
                 in [0, 1]; 67 pixels per degree unless told otherwise
===============  =============================================================
"""

from __future__ import annotations

import math
import os

import numpy as np

from fogref.compare.metrics import check_pair, require_finite
from fogref.display import exposure_white, luminance

#: FLIP's default viewing condition: pixels per degree of visual angle.
FLIP_PPD = 67.0
#: FLIP inputs are clipped to this many times the reference's largest finite value.
FLIP_CEILING_FACTOR = 1e4
#: Widest HDR-FLIP exposure range [stops] before it is narrowed (see :func:`flip_map`).
FLIP_MAX_STOPS = 20
#: A reference whose largest luminance is outside [FLIP_DIMMEST, FLIP_BRIGHTEST] is scaled by a power of
#: two before FLIP (see :func:`flip_map`): FLIP exits the process below float32's epsilon.
FLIP_DIMMEST, FLIP_BRIGHTEST = 2.0**-16, 2.0**32

_FLT_MAX = float(np.finfo(np.float32).max)


# ---------------------------------------------------------------- ΔE2000


def to_display_radiance(image, ceiling: float | None = None) -> np.ndarray:
    """``image`` (finite) with negatives clipped to 0 and values clipped to ``ceiling``.

    Colour metrics (ΔE2000, FLIP) treat pixels as physical, non-negative radiances.
    ``ceiling``: default FLT_MAX.  ValueError for a non-finite value.
    """
    x = np.asarray(image, dtype=np.float64)
    require_finite(x, "colour metric")
    return np.clip(x, 0.0, _FLT_MAX if ceiling is None else ceiling)


def linear_rgb_to_lab(rgb, white: float) -> np.ndarray:
    """CIELAB (D65) of linear sRGB/Rec.709 ``rgb`` after exposure normalisation, ``(..., 3)``.

    Steps: ``rgb / white`` (so that luminance ``white`` becomes ``Y = 1``, i.e.
    L* = 100; brighter pixels get L* > 100, which CIEDE2000 handles), negatives
    clipped to 0, then colour-science's linear sRGB -> XYZ (no CCTF decoding) and
    XYZ -> Lab with the D65 white point.  ``white`` must be finite and > 0.

    >>> [round(float(v), 6) for v in linear_rgb_to_lab(np.ones(3), 1.0)]
    [100.0, 0.0, 0.0]
    """
    import colour

    if not (np.isfinite(white) and white > 0):
        raise ValueError(f"white must be finite and > 0, got {white}")
    x = to_display_radiance(rgb) / white
    xyz = colour.RGB_to_XYZ(x, "sRGB", apply_cctf_decoding=False)
    return colour.XYZ_to_Lab(xyz, colour.RGB_COLOURSPACES["sRGB"].whitepoint)


def delta_e2000_maps(reference, tests, white: float | None = None) -> list[np.ndarray]:
    """CIEDE2000 per pixel (colour-science's ``delta_E_CIE2000``), ``(...)`` each, of every image
    of ``tests`` against ``reference`` (converted to CIELAB once); unitless.

    All images are exposure-normalised by the **same** ``white`` (default:
    :func:`exposure_white` of the reference), see :func:`linear_rgb_to_lab`.

    >>> r = np.full((2, 3), 0.5)
    >>> [m.tolist() for m in delta_e2000_maps(r, [r, r])]
    [[0.0, 0.0], [0.0, 0.0]]
    """
    import colour

    r = np.asarray(reference, dtype=np.float64)
    xs = [check_pair(r, x)[1] for x in tests]
    if white is None:
        white = exposure_white(r)
    for x in xs:
        require_finite(x, "ΔE2000")
    lab_r = linear_rgb_to_lab(r, white)
    de = colour.difference.delta_E_CIE2000
    return [np.asarray(de(lab_r, linear_rgb_to_lab(x, white)), dtype=np.float64) for x in xs]


def delta_e2000_map(reference, test, white: float | None = None) -> np.ndarray:
    """CIEDE2000 per pixel, ``(...)``; unitless (:func:`delta_e2000_maps` of one image)."""
    return delta_e2000_maps(reference, [test], white)[0]


# ---------------------------------------------------------------- FLIP


def _import_flip_evaluator():
    """Import ``flip_evaluator`` with OpenMP's passive wait policy unless the user chose one.

    ``flip_evaluator`` bundles its own libgomp.  With the default (spinning) wait
    policy and other thread pools in the process, its threads spin against the others
    and a small FLIP runs orders of magnitude slower.  libgomp reads the variable when
    it loads, so this must run before the first import; it changes nothing if set already.
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
      luminance)``, or the map is all zero when the test is black too;
    * the reference's largest luminance is below ``FLIP_DIMMEST`` (FLIP floors the median
      at float32's epsilon, so its start exposure would pass its stop and it *exits the
      process*) or above ``FLIP_BRIGHTEST`` (near float32's range): both images are first
      multiplied by the power of two (``prescale`` in the parameters returned) that brings
      that luminance to [1, 2); FLIP's exposures are relative to the image, so its map is
      what it is for the unscaled images.

    ``ppd`` must be > 0 (``flip_evaluator`` exits the process otherwise).
    """
    flip_evaluator = _import_flip_evaluator()
    if not (np.isfinite(ppd) and ppd > 0):
        raise ValueError(f"FLIP pixels per degree must be finite and > 0, got {ppd}")
    r, x = check_pair(reference, test)
    if r.ndim != 3:
        raise ValueError(f"FLIP needs (H, W, 3) images, got shape {r.shape}")
    r, x = to_display_radiance(r), to_display_radiance(x)
    r_max = float(r[r < _FLT_MAX].max(initial=0.0))
    ceiling = FLIP_CEILING_FACTOR * r_max if r_max > 0 else 1e30
    r, x = np.minimum(r, ceiling), np.minimum(x, ceiling)
    params: dict = {"ppd": float(ppd)}
    y_max = float(luminance(r).max(initial=0.0))
    outside = 0.0 < y_max < FLIP_DIMMEST or y_max > FLIP_BRIGHTEST
    prescale = 2.0 ** -math.floor(math.log2(y_max)) if outside else 1.0
    if prescale != 1.0:  # FLIP floors the median at float32's epsilon: its start would pass its stop
        r, x = r * prescale, x * prescale
    span = flip_exposure_range(r)
    if span is None:
        y_test = float(luminance(x).max(initial=0.0))
        if not y_test > 0:
            return np.zeros(r.shape[:2]), {"ppd": float(ppd), "note": "reference and test are black"}
        e = float(np.log2(1.0 / y_test))
        params.update(startExposure=e, stopExposure=e, numExposures=2)
    elif span[1] - span[0] > FLIP_MAX_STOPS:
        params.update(
            startExposure=span[1] - FLIP_MAX_STOPS, stopExposure=span[1], numExposures=FLIP_MAX_STOPS + 1
        )
    err, _, used = flip_evaluator.evaluate(
        r.astype(np.float32), x.astype(np.float32), "HDR", applyMagma=False, parameters=params
    )
    err = np.asarray(err, dtype=np.float64).reshape(r.shape[:2])
    used = {k: (float(v) if isinstance(v, (int, float)) else v) for k, v in used.items()}
    if prescale != 1.0:
        used["prescale"] = prescale
    return np.clip(err, 0.0, 1.0), used
