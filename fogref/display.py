"""The one display transform of fogref: exposure, clip, IEC 61966-2-1 sRGB encoding.

Every picture fogref writes (the render preview, the report's side-by-side images)
goes through :func:`tone_map`, which computes colour-science's sRGB encoding
(``colour.cctf_encoding(..., function="sRGB")``, bit for bit; see :func:`srgb_encode`).  Only the choice
of exposure differs: the render preview maps the mean luminance to 0.18
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

    Domain: any real array.  Range: [0, 1].  IEC 61966-2-1 computed as colour-science's
    ``colour.cctf_encoding(x, function="sRGB")`` computes it (``12.92 x`` up to 0.0031308,
    ``1.055 x^(1/2.4) - 0.055`` above), bit for bit, without importing colour (about 1.5 s):

    >>> import colour
    >>> x = np.concatenate([np.linspace(0, 1, 100_001), [0.0031308, np.nextafter(0.0031308, 1)]])
    >>> bool(np.array_equal(srgb_encode(x), colour.cctf_encoding(x, function="sRGB")))
    True
    """
    x = np.asarray(linear, dtype=np.float64)
    x = np.clip(np.where(np.isfinite(x), x, 0.0), 0.0, 1.0)
    return np.where(x <= 0.0031308, x * 12.92, 1.055 * np.power(x, 1 / 2.4) - 0.055)


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
    """Write display-referred RGB in [0, 1] as an 8-bit PNG, atomically.

    8-bit values are ``floor(255 x)`` (what ``matplotlib.pyplot.imsave`` writes), saved
    with Pillow directly (matplotlib's import alone takes about 0.5 s).
    """
    from PIL import Image

    img = np.clip(np.asarray(display_rgb, dtype=np.float64), 0.0, 1.0)
    px = (img * 255).astype(np.uint8)
    atomic_write(path, lambda tmp: Image.fromarray(px).save(tmp, format="PNG"))


def write_preview(linear_rgb, path, exposure: float | None = None) -> float:
    """The render's PNG preview: :func:`preview_exposure` (unless given), :func:`tone_map`.

    Returns the exposure used.
    """
    exposure = preview_exposure(linear_rgb) if exposure is None else float(exposure)
    write_png(tone_map(linear_rgb, exposure), path)
    return exposure
