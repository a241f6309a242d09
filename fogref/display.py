"""The one display transform of fogref: exposure, clip, IEC 61966-2-1 sRGB encoding.

Every picture fogref writes (the render preview, the report's side-by-side images)
goes through :func:`tone_map`, which computes colour-science's sRGB encoding
(``colour.cctf_encoding(..., function="sRGB")``, bit for bit; see :func:`srgb_encode`), at one
exposure rule, :func:`part_exposures`: the 99th percentile of the luminance maps to white
(:func:`exposure_for`), a transmittance is shown at exposure 1, and single and multiple
scattering at the inscatter's (the render preview, a truth's thumbnails, the report's
side-by-side images and the viewer alike).

Examples
--------
>>> import numpy as np
>>> tone_map(np.array([[0.0, 0.5, 2.0]]), 1.0).round(3).tolist()
[[0.0, 0.735, 1.0]]
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np
from PIL import Image

from fogref.atomic import atomic_write
from fogref.gbuffer import PARTS, part_attribute

#: Rec. 709 / sRGB luminance weights of linear R, G, B.
LUMINANCE_WEIGHTS = np.array([0.2126, 0.7152, 0.0722])
#: Percentile of the luminance that :func:`exposure_for` maps to white (Y = 1).
WHITE_PERCENTILE = 99.0
_FLT_MAX = float(np.finfo(np.float32).max)
#: Parts pictured at another part's exposure so that they compare: single and multiple scattering
#: at the inscatter's.
EXPOSURE_FROM = {"single": "inscatter", "multiple": "inscatter"}
#: The parts a truth's pictures show (the viewer, the notebook thumbnails), in the schema's order
#: (``T`` is the transmittance); ``attenuated_surface`` only beside a report that compares it.
TRUTH_PARTS = tuple(p for p in PARTS if p != "attenuated_surface")


def luminance(rgb) -> np.ndarray:
    """Rec. 709 relative luminance ``Y`` of linear RGB ``(..., 3)`` -> ``(...)``; same units.

    >>> float(luminance([1.0, 1.0, 1.0]))
    1.0
    """
    return np.asarray(rgb, dtype=np.float64) @ LUMINANCE_WEIGHTS


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


def srgb_decode(encoded) -> np.ndarray:
    """Linear values of sRGB-encoded ones (the inverse of :func:`srgb_encode`).

    Domain: finite values >= 0 (an encoded 1 is linear 1; above 1 the curve goes on; a NaN or an
    infinity is a ValueError).  Range: >= 0.
    IEC 61966-2-1 computed as colour-science's ``colour.cctf_decoding(x, function="sRGB")``
    computes it (``x / 12.92`` up to ``12.92 x 0.0031308``, ``((x + 0.055) / 1.055)^2.4`` above),
    bit for bit, without importing colour:

    >>> import colour
    >>> x = np.concatenate([np.linspace(0, 1, 100_001), [0.0031308 * 12.92, 4.0]])
    >>> bool(np.array_equal(srgb_decode(x), colour.cctf_decoding(x, function="sRGB")))
    True
    >>> v = np.arange(256) / 255.0
    >>> bool(np.array_equal(srgb_decode(v), colour.cctf_decoding(v, function="sRGB")))
    True
    >>> srgb_decode([0.5, np.inf])
    Traceback (most recent call last):
    ...
    ValueError: srgb_decode: encoded values must be finite; 1 are NaN or infinite
    """
    x = np.asarray(encoded, dtype=np.float64)
    bad = np.count_nonzero(~np.isfinite(x))
    if bad:
        raise ValueError(f"srgb_decode: encoded values must be finite; {bad} are NaN or infinite")
    curve = np.sign((x + 0.055) / 1.055) * np.abs((x + 0.055) / 1.055) ** np.asarray(2.4)
    return np.where(0.0031308 * 12.92 >= x, x / 12.92, curve)


def tone_map(linear_rgb, exposure: float) -> np.ndarray:
    """Display-referred sRGB in [0, 1]: ``srgb_encode(exposure * linear_rgb)``."""
    return srgb_encode(np.asarray(linear_rgb, dtype=np.float64) * float(exposure))


def exposure_white(reference, percentile: float = WHITE_PERCENTILE) -> float:
    """The radiance that the exposure normalisation maps to white (``Y = 1``).

    It is the ``percentile``-th percentile of the reference's Rec.709 luminance over
    its pixels with positive luminance (falling back to their maximum when the
    percentile is 0, and to 1 when no pixel is positive).  Always finite and > 0.
    Units: those of ``reference``.

    >>> exposure_white(np.full((2, 2, 3), 0.36)), exposure_white(np.zeros((2, 2, 3)))
    (0.36, 1.0)
    """
    y = luminance(reference).ravel()
    y = y[np.isfinite(y) & (y > 0)]
    if y.size == 0:
        return 1.0
    w = float(np.percentile(y, percentile))
    if not w > 0:
        w = float(y.max())
    return min(w, _FLT_MAX)


def exposure_for(linear_rgb) -> float:
    """The exposure of every picture of a radiance: ``1 / exposure_white(linear_rgb)`` [1/image units].

    >>> exposure_for(np.full((2, 2, 3), 0.5))
    2.0
    """
    return 1.0 / exposure_white(linear_rgb)


def part_exposures(images: Mapping[str, Any]) -> dict[str, float]:
    """The exposure of each part's picture [1/part units], the one rule of every preview.

    ``images``: part name -> linear RGB ``(..., 3)``.  A transmittance (``T`` or
    ``transmittance``) is shown at 1; a part of :data:`EXPOSURE_FROM` at the exposure of the part
    it names when ``images`` holds that part; any other part at :func:`exposure_for` of its own
    image.  Each value is finite and > 0.

    >>> ex = part_exposures({"T": np.full((1, 1, 3), 0.2), "inscatter": np.full((1, 1, 3), 0.5),
    ...                      "single": np.full((1, 1, 3), 0.1), "surface": np.full((1, 1, 3), 0.25)})
    >>> ex
    {'T': 1.0, 'inscatter': 2.0, 'single': 2.0, 'surface': 4.0}
    """
    out = {}
    for part, img in images.items():
        src = EXPOSURE_FROM.get(part)
        own = part_attribute(part) == "transmittance"
        out[part] = 1.0 if own else exposure_for(images[src] if src in images else img)
    return out


def write_png(display_rgb, path) -> None:
    """Write display-referred RGB in [0, 1] as an 8-bit PNG, atomically.

    8-bit values are ``floor(255 x)`` (what ``matplotlib.pyplot.imsave`` writes), saved
    with Pillow directly (matplotlib's import alone takes about 0.5 s).
    """
    img = np.clip(np.asarray(display_rgb, dtype=np.float64), 0.0, 1.0)
    px = (img * 255).astype(np.uint8)
    atomic_write(path, lambda tmp: Image.fromarray(px).save(tmp, format="PNG"))


def write_preview(linear_rgb, path, exposure: float | None = None) -> float:
    """The render's PNG preview: :func:`exposure_for` (unless given), :func:`tone_map`.

    Returns the exposure used.
    """
    exposure = exposure_for(linear_rgb) if exposure is None else float(exposure)
    write_png(tone_map(linear_rgb, exposure), path)
    return exposure
