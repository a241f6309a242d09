"""fogpath's ``sky_at_media``: a constant sky at medium vertices as a closed form plus a residual
(``residual``) against next-event estimation (``mis``): bias and equal-time error on the ladder's
scenes.

    .venv/bin/python benchmarks/sky_residual.py --renders 32    # 96x54, 16 spp x 32 renders each, ~2 min

At every medium vertex ``residual`` takes the sky's light as ``L H(d_y) + B (1 - H(d_y)) + w (L V T -
c(w))``: ``H`` the phase lobe's share above the horizon, ``w`` the continuation's own phase sample,
``V T`` its visibility and transmittance to the sky, ``c(w)`` the sky's radiance ``L`` above the
horizon and ``B`` below it (the surface under the camera lit by the sky and the sun); the sun
keeps its next-event estimation, and an escape from a medium vertex adds no sky.  Both columns
are fogpath with every other default; ``residual`` is forced on every scene, also where
``sky_at_media = "auto"`` takes ``mis``.  Same measurements as ``benchmarks/sun_guiding.py`` (bias
with its z-score and chi^2 per pixel, variance per sample, equal-time efficiency with bootstrap
intervals), written to ``reports/benchmarks/sky_residual.{json,md}``.  Besides the ladder's four
scenes, the default scenes include :data:`CONDITIONS`: the open valley with a higher sun, without
the sun, over brighter ground and in denser fog, where ``auto``'s rule is drawn (each row notes
what ``auto`` takes there).
"""

from __future__ import annotations

import _scenes as S
import sun_guiding

#: The open valley changed (``_scenes.scene_spec``): a higher sun, no sun, brighter ground, denser
#: fog (the camera's transmittance straight up about 0.34, 0.12 and 0.014 at 16x, 32x and 64x).
CONDITIONS = (
    "valley_open+sun60",
    "valley_open+nosun",
    "valley_open+ground0.4",
    "valley_open+sun60+ground0.7",
    "valley_open+nosun+ground0.5",
    "valley_open+nosun+ground0.9",
    "valley_open+fog16",
    "valley_open+fog32",
    "valley_open+fog64",
)


def auto_takes(scene) -> str:
    """What ``sky_at_media = "auto"`` takes on ``scene`` (a loaded fogpath scene)."""
    fp = scene.integrator()
    kept, fp.sky_at_media = fp.sky_at_media, "auto"
    try:
        return "auto: " + fp.sky_at_media_for(scene)
    finally:
        fp.sky_at_media = kept


SKY_RESIDUAL = {
    "label": "fogpath_sky_residual",
    "short": "residual",
    "title": "A constant sky at medium vertices: closed form plus residual against next-event estimation",
    "describe": lambda args: (
        '`fogpath` here is fogpath with `sky_at_media = "mis"` (next-event estimation among all emitters '
        "and the phase sample, power heuristic).",
        '`fogpath_sky_residual`: fogpath with `sky_at_media = "residual"`: at every medium vertex the '
        "constant sky's light is `L H(d_y) + B (1 - H(d_y)) + w (L V T - c(w))`, `H` the share of the "
        "Henyey-Greenstein lobe around the ray's direction above the horizon (a truncated Legendre "
        "series, tabulated: `fogref.media.single_scatter.hg_upper_fraction_table`), `w` the "
        "continuation's phase sample, "
        "`V T` its visibility and closed-form transmittance to the sky, `c(w)` the sky's radiance above "
        "the horizon and `B` below it (the surface under the camera lit by the sky and the sun); the sun "
        "keeps its next-event estimation, chosen every time; an escape from a medium vertex adds no sky "
        "(`plugins/fogpath.py`, `_sky_residual_light`).",
    ),
    "baseline": {"sky_at_media": "mis"},
    "knobs": lambda args: {"sky_at_media": "residual"},
    "note": auto_takes,
}

if __name__ == "__main__":
    sun_guiding.main(
        method=SKY_RESIDUAL,
        script="sky_residual.py",
        name="sky_residual",
        doc=__doc__,
        scenes=(*S.SCENES, *CONDITIONS),
    )
