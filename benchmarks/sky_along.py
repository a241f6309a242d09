"""fogpath's residual for a constant sky at medium vertices (``sky_at_media = "residual"``) with the
closed form taken as its mean along each segment after the camera ray (fogpath) against the same
closed form added at the segments' vertices (as before): bias and equal-time error on the ladder's
scenes and the open valley's changes of ``benchmarks/sky_residual.py``.

    .venv/bin/python benchmarks/sky_along.py --renders 32    # 96x54, 16 spp x 32 renders each, ~2 min

A segment's vertex, drawn by free flight, carries weight ``w_ff`` with ``E[w_ff 1{vertex before D}] =
albedo (1 - T(D))`` per channel, and the closed form ``L H(d_y) + B (1 - H(d_y))`` depends only on the
segment's direction ``d``, so its mean along the segment is exact: ``albedo (1 - T(D)) (L H + B (1 -
H))`` times the throughput at the segment's start (``plugins/fogpath.py``, ``_sky_on_segment``).  Both
columns force the residual on every scene (also where ``sky_at_media = "auto"`` takes next-event
estimation; each row notes what it takes).  Same measurements as ``benchmarks/sun_guiding.py``,
written to ``reports/benchmarks/sky_along.{json,md}``.
"""

from __future__ import annotations

import _scenes as S
import sun_guiding
from sky_residual import CONDITIONS, auto_takes

SKY_ALONG = {
    "label": "fogpath_sky_along",
    "short": "along",
    "title": "The sky's closed form at medium vertices: its mean along each segment, against the vertex's",
    "describe": lambda args: (
        '`fogpath` here is fogpath with `sky_at_media = "residual"` and the closed form added at the '
        "vertices of segments after the camera ray (`sky_along_segments = false`, "
        "`benchmarks/_fogpath_knobs.py`).",
        '`fogpath_sky_along`: fogpath with `sky_at_media = "residual"` (its default otherwise): on each '
        "segment after the camera ray the closed form `L H(d_y) + B (1 - H(d_y))` is added as its mean "
        "along the segment, `albedo (1 - T(D)) (L H + B (1 - H))`, and the segment's vertex adds the "
        "residual alone (`plugins/fogpath.py`, `_sky_on_segment`).",
    ),
    "baseline": {"sky_at_media": "residual", "sky_along_segments": False},
    "knobs": lambda args: {"sky_at_media": "residual"},
    "note": auto_takes,
}

if __name__ == "__main__":
    sun_guiding.main(
        method=SKY_ALONG,
        script="sky_along.py",
        name="sky_along",
        doc=__doc__,
        scenes=(*S.SCENES, *CONDITIONS),
    )
