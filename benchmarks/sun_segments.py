"""fogpath's ``sun_sampling_rays``: the sun's scattering sampled from its integrand along every
segment (``-1``, fogpath's default) against the camera ray and the segment after it (``2``): bias
and equal-time error on the ladder's scenes and the open valley's changes of
``benchmarks/sky_residual.py``.

    .venv/bin/python benchmarks/sun_segments.py --renders 32    # 96x54, 16 spp x 32 renders each, ~2 min

On each segment it covers, the sampler draws one point from the sun's single-scattering integrand
along the segment (exact in unbounded exponential fog, a closed-form mixture with the exact weight
in bounded fog) with one shadow ray, and the medium vertex on the segment skips the sun's next-event
sample: the segment's estimate replaces whether it scatters at all.  Same measurements as
``benchmarks/sun_guiding.py``, written to ``reports/benchmarks/sun_segments.{json,md}``.
"""

from __future__ import annotations

import _scenes as S
import sun_guiding
from sky_residual import CONDITIONS, auto_takes

SUN_SEGMENTS = {
    "label": "fogpath_sun_every_segment",
    "short": "every",
    "title": "The sun sampled along every segment against the two first",
    "describe": lambda args: (
        "`fogpath` here is fogpath with `sun_sampling_rays = 2` (the camera ray and the segment after "
        "its first vertex).",
        "`fogpath_sun_every_segment`: fogpath's defaults, `sun_sampling_rays = -1`: the sun sampled "
        "from its integrand along every segment (`plugins/fogpath.py`, `_sun_single_scatter`).",
    ),
    "baseline": {"sun_sampling_rays": 2},
    "knobs": lambda args: {},
    "note": auto_takes,
}

if __name__ == "__main__":
    sun_guiding.main(
        method=SUN_SEGMENTS,
        script="sun_segments.py",
        name="sun_segments",
        doc=__doc__,
        scenes=(*S.SCENES, *CONDITIONS),
    )
