"""The display tone map used for every side-by-side picture of a report.

``display = sRGB_OETF(clip(exposure * linear_rgb, 0, 1))``: a plain exposure scale,
a hard clip to [0, 1] (no highlight roll-off, so that what is shown is linear up to
white and differences are not hidden by a curve), then the IEC 61966-2-1 sRGB
transfer function.  Reference, model and |error| of one part share one exposure,
``1 / white`` where ``white`` is the 99th percentile of the reference's Rec.709
luminance (:func:`fogref.compare.perceptual.exposure_white`); transmittance uses
exposure 1 (T = 1 is white).  The transform itself is :func:`fogref.display.tone_map`,
the one fogref uses for every picture.
"""

from __future__ import annotations

from fogref.compare.perceptual import exposure_white
from fogref.display import srgb_encode as srgb_oetf  # noqa: F401  (the one sRGB transform)
from fogref.display import tone_map  # noqa: F401  (exposure, clip, sRGB: shared with the render preview)


def exposure_for(reference) -> float:
    """The shared exposure of a part: ``1 / exposure_white(reference)`` [1/image units]."""
    return 1.0 / exposure_white(reference)
