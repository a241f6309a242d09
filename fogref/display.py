"""The one display transform of fogref: exposure, clip, IEC 61966-2-1 sRGB encoding.

Every picture fogref writes (the render preview, the report's side-by-side images)
goes through :func:`tone_map`, which uses colour-science's sRGB encoding
(``colour.cctf_encoding(..., function="sRGB")``).  Only the choice of exposure
differs: the render preview maps the mean luminance to 0.18
(:func:`preview_exposure`); reports map a percentile to white.

Examples
--------
>>> import numpy as np
>>> tone_map(np.array([[0.0, 0.5, 2.0]]), 1.0).round(3).tolist()
[[0.0, 0.735, 1.0]]
"""

from __future__ import annotations

import numpy as np

from fogref.atomic import atomic_write

#: Rec. 709 / sRGB luminance weights of linear R, G, B.
LUMINANCE_WEIGHTS = np.array([0.2126, 0.7152, 0.0722])


def srgb_encode(linear) -> np.ndarray:
    """sRGB-encode linear values, clipped to [0, 1] first; non-finite values show black.

    Domain: any real array.  Range: [0, 1].
    """
    import colour

    x = np.asarray(linear, dtype=np.float64)
    x = np.clip(np.where(np.isfinite(x), x, 0.0), 0.0, 1.0)
    return np.asarray(colour.cctf_encoding(x, function="sRGB"), dtype=np.float64)


def tone_map(linear_rgb, exposure: float) -> np.ndarray:
    """Display-referred sRGB in [0, 1]: ``srgb_encode(exposure * linear_rgb)``."""
    return srgb_encode(np.asarray(linear_rgb, dtype=np.float64) * float(exposure))


def preview_exposure(linear_rgb) -> float:
    """Exposure that maps the mean Rec. 709 luminance to 0.18 (1 for a black image).

    >>> preview_exposure(np.full((2, 2, 3), 0.36))
    0.5
    """
    lum = float(np.mean(np.asarray(linear_rgb, dtype=np.float64) @ LUMINANCE_WEIGHTS))
    return 0.18 / lum if np.isfinite(lum) and lum > 0 else 1.0


def write_png(display_rgb, path) -> None:
    """Write display-referred RGB in [0, 1] as an 8-bit PNG, atomically."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    img = np.clip(np.asarray(display_rgb, dtype=np.float64), 0.0, 1.0)
    atomic_write(path, lambda tmp: plt.imsave(tmp, img, format="png"))


def write_preview(linear_rgb, path, exposure: float | None = None) -> float:
    """The render's PNG preview: :func:`preview_exposure` (unless given), :func:`tone_map`.

    Returns the exposure used.
    """
    exposure = preview_exposure(linear_rgb) if exposure is None else float(exposure)
    write_png(tone_map(linear_rgb, exposure), path)
    return exposure
