"""Colour metrics of physical radiances: CIEDE2000 and HDR-FLIP.

Conventions as in :mod:`fogref.compare.metrics` (``(reference, test)``, linear
Rec.709 RGB ``(..., 3)``, finite reference).  Both treat pixels as physical,
non-negative radiances: they clip negative values to 0 (:func:`to_display_radiance`);
FLIP also clips to a multiple of the reference's largest value (:func:`flip_map`).
Neither imports colour-science: its 0.4.7 takes 0.8-1.4 s to import (its plotting package with
matplotlib's pyplot and pandas), a third of a small ``fogref compare``.  ΔE2000 transcribes its
operations in their order, and the tests hold them to colour-science's, bit for bit.

===============  =============================================================
ΔE2000           CIEDE2000 of CIELAB colours, after the exposure normalisation
                 of :func:`linear_rgb_to_lab`; unitless (1 ≈ just noticeable);
                 colour-science's values bit for bit (:func:`delta_e_cie2000`)
FLIP             HDR-FLIP (Andersson et al. 2021) via ``flip_evaluator``,
                 in [0, 1]; 67 pixels per degree unless told otherwise
===============  =============================================================
"""

from __future__ import annotations

import math
import os

import numpy as np

from fogref.compare.metrics import check_pair, count_nonfinite, require_finite
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


#: Linear sRGB (Rec. 709 primaries) to CIE XYZ, the matrix of IEC 61966-2-1 as colour-science 0.4.7
#: holds it (``colour.RGB_COLOURSPACES["sRGB"].matrix_RGB_to_XYZ``).
SRGB_TO_XYZ = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
#: CAT02 from D65 to D65 as colour-science computes it (``matrix_chromatic_adaptation_VonKries``):
#: the identity up to 3e-17, which ``colour.RGB_to_XYZ(x, "sRGB")`` applies after
#: :data:`SRGB_TO_XYZ`; kept, so that :func:`linear_rgb_to_lab` gives its values bit for bit.
CAT02_D65_TO_D65 = np.array(
    [
        [1.0, -2.925337592710602e-17, -2.0424934209769367e-17],
        [1.865516512262643e-17, 1.0, -6.012863655103287e-19],
        [-1.1925326645651568e-18, -6.805220268068795e-19, 1.0],
    ]
)
#: CIE 1931 2-degree chromaticity (x, y) of D65, sRGB's white and CIELAB's here.
D65_XY = (0.3127, 0.3290)


def _planes(a: np.ndarray) -> np.ndarray:
    """``a``'s last axis first, each plane contiguous (colour-science's ``tsplit``: numpy's
    transcendental functions may round differently on strided views)."""
    return np.array([a[..., i] for i in range(a.shape[-1])])


def _vecmul(m: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``m @ v`` over ``v``'s last axis, as colour-science's ``vecmul`` computes it."""
    return np.matmul(m, v[..., None]).squeeze(-1)


def _lab_f(t: np.ndarray) -> np.ndarray:
    """CIE 1976's ``f(t)`` of ``t = Y / Y_n``: the cube root above ``(24/116)^3``, the line below
    (colour-science's ``intermediate_lightness_function_CIE1976``, its signed power included, on
    arrays: a single colour's power of a 0-d array and of a numpy scalar can differ by an ulp)."""
    t = np.asarray(t, dtype=np.float64)
    cube_root = np.sign(t) * np.abs(t) ** np.asarray(1 / 3)
    return np.where(t > (24 / 116) ** 3, cube_root, (841 / 108) * t + 16 / 116)


def linear_rgb_to_lab(rgb, white: float) -> np.ndarray:
    """CIELAB (D65) of linear sRGB/Rec.709 ``rgb`` after exposure normalisation, ``(..., 3)``.

    Steps: ``rgb / white`` (so that luminance ``white`` becomes ``Y = 1``, i.e.
    L* = 100; brighter pixels get L* > 100, which CIEDE2000 handles), negatives
    clipped to 0, then linear sRGB -> XYZ (no CCTF decoding) and XYZ -> Lab with the D65
    white point.  ``white`` must be finite and > 0.  The values are colour-science's
    ``XYZ_to_Lab(RGB_to_XYZ(x, "sRGB"), D65)``, bit for bit, without importing colour-science
    (0.8-1.4 s: version 0.4.7 imports its plotting package, and with it matplotlib's pyplot
    and pandas):

    >>> import colour
    >>> x = np.random.default_rng(0).random((1000, 3)) ** 3 * 4
    >>> d65 = colour.RGB_COLOURSPACES["sRGB"].whitepoint
    >>> want = colour.XYZ_to_Lab(colour.RGB_to_XYZ(x, "sRGB"), d65)
    >>> bool(np.array_equal(linear_rgb_to_lab(x, 1.0), want))
    True
    >>> [round(float(v), 6) for v in linear_rgb_to_lab(np.ones(3), 1.0)]
    [100.0, 0.0, 0.0]
    """
    if not (np.isfinite(white) and white > 0):
        raise ValueError(f"white must be finite and > 0, got {white}")
    x = to_display_radiance(rgb) / white
    X, Y, Z = _planes(_vecmul(CAT02_D65_TO_D65, _vecmul(SRGB_TO_XYZ, x)))
    xw, yw = D65_XY
    scale = 1.0 / yw  # the white's XYZ at Y = 1, as colour's xyY_to_XYZ computes it
    f_x, f_y, f_z = _lab_f(X / (xw * scale)), _lab_f(Y / 1.0), _lab_f(Z / ((1 - (xw + yw)) * scale))
    return np.stack([116 * f_y - 16, 500 * (f_x - f_y), 200 * (f_y - f_z)], axis=-1)


def delta_e_cie2000(lab_1, lab_2) -> np.ndarray:
    """CIEDE2000 colour difference of CIELAB colours ``(..., 3)`` -> ``(...)``; unitless (1 is about a
    just noticeable difference), ``k_L = k_C = k_H = 1``.

    Sharma, Wu and Dalal, "The CIEDE2000 color-difference formula: implementation notes,
    supplementary test data, and mathematical observations", Color Research & Application 30(1),
    2005.  The operations are colour-science 0.4.7's ``delta_E_CIE2000``, in its order, so the
    values are its own bit for bit; the first pair of Sharma's test data gives 2.0425:

    >>> import colour
    >>> pair = np.array([50.0, 2.6772, -79.7751]), np.array([50.0, 0.0, -82.7485])
    >>> round(float(delta_e_cie2000(*pair)), 4)
    2.0425
    >>> rng = np.random.default_rng(1)
    >>> a, b = rng.uniform(-120, 120, (2, 1000, 3)) + [60, 0, 0]
    >>> a[:9, 1:] = 0.0  # greys: hue undefined
    >>> bool(np.array_equal(delta_e_cie2000(a, b), colour.difference.delta_E_CIE2000(a, b)))
    True
    >>> delta_e_cie2000([50.0, np.nan, 0.0], [50.0, 0.0, 0.0])
    Traceback (most recent call last):
    ...
    ValueError: delta_e_cie2000: CIELAB values must be finite; 1 are NaN or infinite
    """
    lab_1, lab_2 = np.asarray(lab_1, dtype=np.float64), np.asarray(lab_2, dtype=np.float64)
    bad = count_nonfinite(lab_1) + count_nonfinite(lab_2)
    if bad:
        raise ValueError(f"delta_e_cie2000: CIELAB values must be finite; {bad} are NaN or infinite")
    L_1, a_1, b_1 = _planes(lab_1)
    L_2, a_2, b_2 = _planes(lab_2)
    C_bar_7 = ((np.hypot(a_1, b_1) + np.hypot(a_2, b_2)) / 2) ** 7
    G = 0.5 * (1 - np.sqrt(C_bar_7 / (C_bar_7 + 25**7)))
    a_p_1, a_p_2 = (1 + G) * a_1, (1 + G) * a_2
    C_p_1, C_p_2 = np.hypot(a_p_1, b_1), np.hypot(a_p_2, b_2)
    h_p_1 = np.where((b_1 == 0) & (a_p_1 == 0), 0, np.degrees(np.arctan2(b_1, a_p_1)) % 360)
    h_p_2 = np.where((b_2 == 0) & (a_p_2 == 0), 0, np.degrees(np.arctan2(b_2, a_p_2)) % 360)
    dh, C_p_12 = h_p_2 - h_p_1, C_p_1 * C_p_2
    delta_h_p = np.select([C_p_12 == 0, np.fabs(dh) <= 180, dh > 180, dh < -180], [0, dh, dh - 360, dh + 360])
    delta_L_p, delta_C_p = L_2 - L_1, C_p_2 - C_p_1
    delta_H_p = 2 * np.sqrt(C_p_12) * np.sin(np.deg2rad(delta_h_p / 2))
    L_bar_p, C_bar_p = (L_1 + L_2) / 2, (C_p_1 + C_p_2) / 2
    apart, h_sum = np.fabs(h_p_1 - h_p_2), h_p_1 + h_p_2
    h_bar_p = np.select(
        [C_p_12 == 0, apart <= 180, (apart > 180) & (h_sum < 360), (apart > 180) & (h_sum >= 360)],
        [h_sum, h_sum / 2, (h_sum + 360) / 2, (h_sum - 360) / 2],
    )
    T = (
        1
        - 0.17 * np.cos(np.deg2rad(h_bar_p - 30))
        + 0.24 * np.cos(np.deg2rad(2 * h_bar_p))
        + 0.32 * np.cos(np.deg2rad(3 * h_bar_p + 6))
        - 0.20 * np.cos(np.deg2rad(4 * h_bar_p - 63))
    )
    delta_theta = 30 * np.exp(-(((h_bar_p - 275) / 25) ** 2))
    C_bar_p_7 = C_bar_p**7
    R_C = 2 * np.sqrt(C_bar_p_7 / (C_bar_p_7 + 25**7))
    L_bar_p_2 = (L_bar_p - 50) ** 2
    S_L = 1 + ((0.015 * L_bar_p_2) / np.sqrt(20 + L_bar_p_2))
    S_C = 1 + 0.045 * C_bar_p
    S_H = 1 + 0.015 * C_bar_p * T
    R_T = -np.sin(np.deg2rad(2 * delta_theta)) * R_C
    return np.sqrt(
        (delta_L_p / (1 * S_L)) ** 2
        + (delta_C_p / (1 * S_C)) ** 2
        + (delta_H_p / (1 * S_H)) ** 2
        + R_T * (delta_C_p / (1 * S_C)) * (delta_H_p / (1 * S_H))
    )


def delta_e2000_maps(reference, tests, white: float | None = None) -> list[np.ndarray]:
    """CIEDE2000 per pixel (:func:`delta_e_cie2000`), ``(...)`` each, of every image of ``tests``
    against ``reference`` (converted to CIELAB once); unitless.

    All images are exposure-normalised by the **same** ``white`` (default:
    :func:`exposure_white` of the reference), see :func:`linear_rgb_to_lab`.

    >>> r = np.full((2, 3), 0.5)
    >>> [m.tolist() for m in delta_e2000_maps(r, [r, r])]
    [[0.0, 0.0], [0.0, 0.0]]
    """
    r = np.asarray(reference, dtype=np.float64)
    xs = [check_pair(r, x)[1] for x in tests]
    if white is None:
        white = exposure_white(r)
    for x in xs:
        require_finite(x, "ΔE2000")
    lab_r = linear_rgb_to_lab(r, white)
    return [delta_e_cie2000(lab_r, linear_rgb_to_lab(x, white)) for x in xs]


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
