"""The budget's players and their game: the effects, the images they switch and every coalition's image.

:data:`STEPS` names the nine effects (the letters of ``docs/design.md``, "Error budget");
:func:`closed_forms` gives the closed-form single scattering they switch to;
:func:`shapley_parts` caches everything a coalition needs (the renders, the closed forms and
the engine's images for each configuration), and :func:`coalition_image` is the image of any
coalition, from the truth (none) to the engine (all).  The cooperative game and its Shapley
values are in :mod:`fogref.study.budget.shapley`; the engine sides in
:mod:`fogref.study.budget.engines`.
"""

from __future__ import annotations

import itertools

import numpy as np

from fogref.gbuffer import Truth
from fogref.media import NP, hg_phase, single_scatter_sun
from fogref.media.single_scatter import single_scatter_sky

#: Step keys, effect letters (docs/design.md, "Error budget") and labels, in chain order (step k = 1..9).
STEPS: tuple[tuple[str, str, str], ...] = (
    ("multiple", "d", "multiple scattering"),
    ("shadows", "e", "geometric shadows (sun)"),
    ("sky", "c", "sky occlusion by the ground + sky attenuation"),
    ("sun_attenuation", "b", "sun attenuation in the fog"),
    ("lobe", "a", "cosine lobe vs Henyey–Greenstein"),
    ("refit", "a/b", "colours/exponent re-fitted to the attenuated target"),
    ("start_distance", "f", "start distances (directional + fog)"),
    ("opacity_cutoff", "g", "max opacity + cutoff distance"),
    ("float32", "h", "float32 shader arithmetic"),
)

#: The droplets' phase against HG of its mean cosine: a Shapley player of droplet fogs only (a
#: tabulated phase, :func:`applicable <fogref.study.budget.engines.applicable_effects>`), not a
#: step of the chain.  It switches the sun's single scattering from the fog's phase to ``HG(g)``
#: (one factor per camera ray: the sun is a delta); the sky's and multiple scattering keep the
#: fog's phase, their share stays in "lobe" and "multiple".
PHASE: tuple[str, str, str] = ("phase", "p", "droplets' phase vs HG(g) (the sun's single scattering)")

#: Steps whose images come from renders (carry Monte Carlo noise).
RENDERED = ("multiple", "shadows", "sky")

#: The Shapley budget's players: the chain's effects (:data:`STEPS` keys, same order).
EFFECTS: tuple[str, ...] = tuple(s[0] for s in STEPS)

#: The same players with the colour re-fit folded into the lobe (the engine always uses the
#: study's colours): the compensation between "lobe" and "refit" disappears from the table.
EFFECTS_COLOURS_IN_LOBE: tuple[str, ...] = tuple(k for k in EFFECTS if k != "refit")

#: Effects that select the engine's configuration (refit, start distances, opacity/cutoff, float32).
CONFIG_EFFECTS = ("refit", "start_distance", "opacity_cutoff", "float32")


def closed_forms(truth: Truth, pf) -> dict:
    """Closed-form single-scattering images (H, W, 3) of the physical fog ``pf``
    (a :class:`fogref.mapping.PhysicalScene`) at each pixel's distance."""
    m = pf.medium
    o, d, D = truth.rays()
    shape = (*truth.shape, 3)
    w = pf.sun_direction
    E = np.asarray(pf.sun_irradiance)
    alb = np.asarray(m.albedo)
    T = np.stack(m.transmittance(NP, o, d, D), -1)
    sun_att = np.stack(single_scatter_sun(NP, m, o, d, D, w, tuple(E)), -1)
    if w[1] > 0:
        cos = d[0] * w[0] + d[1] * w[1] + d[2] * w[2]
        sun_noatt = alb * E * m.phase_value(NP, cos)[:, None] * (1.0 - T)
    else:
        sun_noatt = np.zeros_like(T)
    sky = np.stack(single_scatter_sky(NP, m, o, d, D, pf.sky_radiance or (0.0, 0.0, 0.0)), -1)
    return {
        "T": T.reshape(shape),
        "sun_att": sun_att.reshape(shape),
        "sun_noatt": sun_noatt.reshape(shape),
        "sky": sky.reshape(shape),
    }


def shapley_parts(truth: Truth, sky_single: np.ndarray, pf, engine, sky_distance: float = 1.0e5) -> dict:
    """Everything :func:`coalition_image` needs, computed once (the cache of the 2^k coalitions).

    The renders (the truth and ``sky_single``, the sun-less render's ``single``), the closed
    forms of :func:`closed_forms`, and the engine's ``(T, L_sun, L_sky)`` for each of the
    2^4 configurations of :data:`CONFIG_EFFECTS` (``engine``: e.g. :func:`unreal_engine`).
    """
    cf = closed_forms(truth, pf)
    ratio = None
    if pf.medium.phase is not None and pf.sun_direction[1] > 0:  # HG(g) / the droplets' phase
        _, d, _ = truth.rays()
        w = pf.sun_direction
        cos = d[0] * w[0] + d[1] * w[1] + d[2] * w[2]
        r = hg_phase(NP, cos, pf.medium.g) / pf.medium.phase_value(NP, cos)
        ratio = r.reshape(*truth.shape, 1)
    eng = {}
    for bits in itertools.product((False, True), repeat=len(CONFIG_EFFECTS)):
        eng[bits] = engine(truth, dict(zip(CONFIG_EFFECTS, bits)), sky_distance)
    return {
        "final": truth.final,
        "att": truth.attenuated_surface,
        "surface": truth.surface,
        "multiple": truth.final - truth.attenuated_surface - truth.single,
        "sun_render": truth.single - sky_single,
        "sky_render": sky_single,
        "sun_att": cf["sun_att"],
        "sun_noatt": cf["sun_noatt"],
        "sky_cf": cf["sky"],
        "phase_ratio": ratio,
        "engine": eng,
    }


def effective_coalition(parts: dict, coalition, fixed=()) -> frozenset:
    """The effects of ``coalition`` (with ``fixed``, as :func:`coalition_image` takes them) that
    change its image: :func:`coalition_image` of this set is the coalition's image, bit for bit.
    Of the 512 coalitions of the nine effects, 212 have distinct images, so the budget's game
    (:func:`~fogref.study.budget.shapley.shapley_budget`) evaluates each of those once.

    With the engine's lobe in, only the configuration and "multiple" remain (the engine's images
    replace the physical sun and sky); without it, the configuration counts only when a start
    distance, the opacity/cutoff or float32 is in (they change the surface's T), the sun's
    attenuation only with the shadows (the closed form), the phase only for a droplet fog.

    >>> parts = {"phase_ratio": None}
    >>> sorted(effective_coalition(parts, {"lobe", "shadows", "sky", "refit"}))
    ['lobe', 'refit']
    >>> sorted(effective_coalition(parts, {"sun_attenuation", "refit", "phase", "multiple"}))
    ['multiple']
    >>> sorted(effective_coalition(parts, {"shadows", "sun_attenuation", "float32"}, ("refit",)))
    ['float32', 'refit', 'shadows', 'sun_attenuation']
    """
    C = set(coalition) | set(fixed)
    keep = C & {"lobe", "multiple"}
    if "lobe" in C or C & set(CONFIG_EFFECTS[1:]):
        keep |= C & set(CONFIG_EFFECTS)
    if "lobe" not in C:
        keep |= C & {"shadows", "sky"}
        if "shadows" in C:
            keep |= C & {"sun_attenuation"}
        if parts.get("phase_ratio") is not None:
            keep |= C & {"phase"}
    return frozenset(keep)


def coalition_image(parts: dict, coalition, fixed=()) -> np.ndarray:
    """The image (H, W, 3) with the effects in ``coalition`` switched to the engine's side.

    ``final = surface part + sun inscatter + sky inscatter + multiple`` where

    * multiple [d]: the truth's ``final - attenuated_surface - single`` unless "multiple" is
      in the coalition (then 0);
    * sun: if "lobe" [a] is in: the engine's directional inscatter; else the rendered sun
      single scattering (``single - sky_single``), or with "shadows" [e] the closed form,
      attenuated unless "sun_attenuation" [b] is in;
    * sky: if "lobe": the engine's other inscatter; else the rendered ``sky_single``, or with
      "sky" [c] the closed form ``alpha L_sky (1 - T)``;
    * phase [p] (droplet fogs, :data:`PHASE`): while the sun is physical, its single
      scattering times ``HG(g) / p`` per pixel;
    * surface: the truth's ``attenuated_surface`` (with "lobe": ``surface T_engine`` of the
      plain configuration), plus ``surface (T_engine(config) - T_engine(plain))`` for the
      configuration effects (start distances, opacity/cutoff, float32);
    * the configuration (refit, start distances, opacity/cutoff, float32) selects the
      engine's images.

    ``fixed``: configuration effects held on the engine's side in every coalition (e.g.
    ``("refit",)``: the engine always uses the study's colours, so the colour choice is part
    of the lobe effect).  The empty coalition is the truth and the full one the engine's image
    ``surface T + L``, exactly, so the Shapley values of the squared error sum to it.
    Effects act where the physics lets them: shadows/sun attenuation matter only while the
    sun is physical (the lobe is out), the refit only once it is in; Shapley splits such
    interactions equally between the effects involved.
    """
    C = set(coalition) | set(fixed)
    cfg = tuple(k in C for k in CONFIG_EFFECTS)
    T, L_sun, L_sky = parts["engine"][cfg]
    T0 = parts["engine"][(False,) * len(CONFIG_EFFECTS)][0]
    surf = parts["surface"] * T0 if "lobe" in C else parts["att"]
    if any(cfg[1:]):
        surf = surf + parts["surface"] * (T - T0)
    if "lobe" in C:
        sun, sky = L_sun, L_sky
    else:
        if "shadows" in C:
            sun = parts["sun_noatt"] if "sun_attenuation" in C else parts["sun_att"]
        else:
            sun = parts["sun_render"]
        sky = parts["sky_cf"] if "sky" in C else parts["sky_render"]
        if "phase" in C and parts.get("phase_ratio") is not None:
            sun = sun * parts["phase_ratio"]
    img = surf + sun + sky
    return img if "multiple" in C else img + parts["multiple"]
