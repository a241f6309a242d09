"""fogpath's stratified sun samples per camera ray (``SUN_SAMPLES``): 4 against 2: bias and
equal-time error on the ladder's scenes and the open valley's changes of
``benchmarks/sky_residual.py``.

    .venv/bin/python benchmarks/sun_samples.py --renders 32    # 96x54, 16 spp x 32 renders each, ~2 min

Along the camera ray the sun's single scattering is sampled from its integrand (exact in unbounded
exponential fog, a closed-form mixture in bounded fog) with stratified samples, each with one
shadow ray (``plugins/fogpath.py``, ``_sun_single_scatter``); what is left of its variance is the
terrain's shadows along the ray.  Both columns are ``benchmarks/_fogpath_knobs.py``'s
``sun_samples``.  Same measurements as ``benchmarks/sun_guiding.py``, written to
``reports/benchmarks/sun_samples.{json,md}``.
"""

from __future__ import annotations

import _scenes as S
import sun_guiding
from sky_residual import CONDITIONS, auto_takes

SUN_SAMPLES = {
    "label": "fogpath_sun_samples",
    "short": "samples",
    "title": "Stratified sun samples per camera ray",
    "describe": lambda args: (
        "`fogpath` here is fogpath with 2 stratified sun samples per camera ray.",
        "`fogpath_sun_samples`: fogpath with 4 (`sun_samples`, `benchmarks/_fogpath_knobs.py`).",
    ),
    "baseline": {"sun_samples": 2},
    "knobs": lambda args: {"sun_samples": 4},
    "note": auto_takes,
}

if __name__ == "__main__":
    sun_guiding.main(
        method=SUN_SAMPLES,
        script="sun_samples.py",
        name="sun_samples",
        doc=__doc__,
        scenes=(*S.SCENES, *CONDITIONS),
    )
