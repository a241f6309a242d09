"""The display tone map used for every side-by-side picture of a report.

``display = sRGB_OETF(clip(exposure * linear_rgb, 0, 1))``: a plain exposure scale,
a hard clip to [0, 1] (no highlight roll-off, so that what is shown is linear up to
white and differences are not hidden by a curve), then the IEC 61966-2-1 sRGB
transfer function.  Reference, model and |error| of one part share one exposure,
``1 / white`` where ``white`` is the 99th percentile of the reference's Rec.709
luminance (:func:`fogref.compare.metrics.exposure_white`); transmittance uses
exposure 1 (T = 1 is white).
"""

from __future__ import annotations

import numpy as np

from fogref.compare.metrics import exposure_white


def srgb_oetf(linear) -> np.ndarray:
    """IEC 61966-2-1 sRGB encoding of linear values in [0, 1] (clipped first).

    Display only: a non-finite value (which no metric ever sees) is shown black.
    """
    x = np.asarray(linear, dtype=np.float64)
    x = np.clip(np.where(np.isfinite(x), x, 0.0), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def exposure_for(reference) -> float:
    """The shared exposure of a part: ``1 / exposure_white(reference)`` [1/image units]."""
    return 1.0 / exposure_white(reference)


def tone_map(linear_rgb, exposure: float) -> np.ndarray:
    """Display-referred sRGB in [0, 1], ``(..., 3)``: exposure, clip, sRGB OETF."""
    return srgb_oetf(np.asarray(linear_rgb, dtype=np.float64) * float(exposure))
