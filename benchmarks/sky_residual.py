"""A constant sky's light at medium vertices as a closed form plus a residual, against fogpath's
defaults: bias and equal-time error on the ladder's scenes.

    .venv/bin/python benchmarks/sky_residual.py --renders 32    # 96x54, 16 spp x 32 renders each

``fogpath_sky_residual`` is ``fogpath_knobs`` (``benchmarks/_fogpath_knobs.py``) with
``sky_residual``: at every medium vertex the sky's light is ``L H(d_y) + w L (V T - 1{w_y > 0})``
(``H`` the phase lobe's share above the horizon, ``w`` the continuation's own phase sample, ``V T``
its visibility and transmittance to the sky), the sun keeps its next-event estimation, and an
escape from a medium vertex adds no sky.  Same measurements as ``benchmarks/sun_guiding.py``
(bias with its z-score and chi^2 per pixel, variance per sample, equal-time efficiency with
bootstrap intervals), written to ``reports/benchmarks/sky_residual.{json,md}``.
"""

from __future__ import annotations

import sun_guiding

SKY_RESIDUAL = {
    "label": "fogpath_sky_residual",
    "short": "residual",
    "title": "A constant sky at medium vertices: closed form plus residual (benchmark only)",
    "describe": lambda args: (
        "`sky_residual` on.",
        "`fogpath_sky_residual`: at every medium vertex the constant sky's light is `L H(d_y) + w L (V T - "
        "1{w_y > 0})`, `H` the share of the Henyey-Greenstein lobe around the ray's direction above the "
        "horizon (a Chebyshev interpolant of `fogref.media.single_scatter.hg_upper_fraction`), `w` the "
        "continuation's phase sample, `V T` its visibility and closed-form transmittance to the sky; the "
        "sun keeps its next-event estimation, chosen every time; an escape from a medium vertex adds no "
        "sky (the continuation's pdf is 0 in the MIS weights) (`benchmarks/_fogpath_knobs.py`, "
        "`_sky_residual_vertex`).",
    ),
    "knobs": lambda args: {"sky_residual": True},
}

if __name__ == "__main__":
    sun_guiding.main(method=SKY_RESIDUAL, script="sky_residual.py", name="sky_residual", doc=__doc__)
