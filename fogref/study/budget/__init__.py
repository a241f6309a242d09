"""Error budget of Unreal's Exponential Height Fog against the path-traced truth.

Two views of the same attribution.  **First, the Shapley budget** (order-independent;
:func:`shapley_budget`): the image :func:`coalition_image` is defined for *every* subset
(coalition) of the nine effects below switched to the engine's side, so the squared error
``e(C) = |S(C) - truth|^2`` is a cooperative game; each effect's share is its Shapley value
(its mean marginal contribution over all orders, computed exactly from all ``2^9 = 512``
coalitions) over ``e(all)``.  The shares sum to 100 % and do not depend on any ordering;
interactions (e.g. shadows only matter while the sun is physical) are split equally between
the effects involved.  Only the truth and the sun-less render are path traced; the closed
forms and the engine's 16 configurations are computed once (:func:`shapley_parts`) and
reused by all coalitions, and coalitions with the same image (:func:`effective_coalition`: 212
of the 512) share one evaluation of the error.  Noise: a block bootstrap over the image and,
with a second pair of renders, the seed-to-seed difference.  **Second, the telescoping chain**
below.

**Every model** (:func:`run_budget`): the same Shapley game with another model's engine side
(:func:`model_engine`: its transmittance and inscatter, the sun lobe split off with
:attr:`fogref.mapping.free.FitSpec.sun_off`), over the effects that apply to it
(:func:`applicable_effects`: Unreal's start distances and opacity/cutoff are Unreal's own; a
droplet fog adds the player "phase" [p], :data:`PHASE`: its phase vs HG(g) in the sun's single
scattering).

A chain of images ``S_0 .. S_K`` goes from the ground truth (``S_0``, the EXR's
``R,G,B``) to what Unreal computes (``S_K``), switching **one** effect at a time.
Every image is final radiance over the truth's surface, so only the fog differs:
steps 0-4 keep the truth's ``attenuated_surface`` (``T surface``, estimated
directly), steps 5-9 composite the model's T over the truth's unattenuated
``surface`` (``surface T_model + L_model``), which is defined only where
``surface_coverage > 0``.  Every statistic is taken over those pixels
(``truth.surface_valid``); the others are excluded and counted
(``excluded_pixels``), never filled in, and nothing is divided by T:

==  ==========================  ====================================================================
k   effect removed / switched   S_k
==  ==========================  ====================================================================
0   (truth)                     R,G,B  = attenuated_surface + single + multiple
1   multiple scattering [d]     T surface + single   (T surface: the truth's attenuated_surface)
2   geometric shadows [e]       T surface + SUN_cf + SKY_render   (SKY_render: ``single`` of a
                                render with the sun removed; SUN_cf: closed-form sun single
                                scattering at the pixel's distance, HG, with sun attenuation)
3   sky occlusion & sky         T surface + SUN_cf + alpha L_sky (1 - T)
    attenuation [c]
4   sun attenuation [b]         T surface + alpha E p_HG(cos) (1 - T) + alpha L_sky (1 - T)
5   HG -> cosine lobe [a]       T surface + Unreal64(lobe fit: colours and exponent fitted to the
                                unattenuated target of step 4, start distances 0, no max opacity,
                                no cutoff); Unreal's T replaces the EXR's T here too
6   colour/exponent re-fit      T surface + Unreal64(the study's colours and exponent, fitted to the
                                attenuated target; start distances 0)
7   start distances [f]         ... + DirectionalInscatteringStartDistance and StartDistance
8   max opacity & cutoff [g]    ... + FogMaxOpacity and FogCutoffDistance
9   float32 [h]                 Unreal as the shader computes it (float32): the compared model
==  ==========================  ====================================================================

Each step's signed image ``Δ_k = S_k - S_{k-1}`` telescopes: ``Σ Δ_k = S_K - S_0``
= model - truth, exactly (float64).  Reported per step: the RMSE of ``Δ_k`` (its
own size), its **share** ``<Δ_k, E> / <E, E>`` of the total squared error
``E = S_K - S_0`` (shares sum to 1 exactly; a negative share means the step
cancels part of the others), and the RMSE of ``S_k`` against the truth.

Monte Carlo noise, two ways.  (1) From the truths' per-pixel ``stderr.*``
channels (:func:`chain_noise`): each ``Δ_k`` is a sum of rendered parts and closed
forms, so its per-pixel standard error follows (``Δ_1 = -multiple``: ``se_multiple``;
``Δ_2``: ``se_single`` and the sun-less render's ``se_single``; ``Δ_5``:
``T_model se_surface`` and ``se_attenuated_surface``; ``Δ_6..9``: ``|ΔT_model|
se_surface``; covariances ignored); every RMSE gets its noise floor, standard error
and a below-the-noise flag (:func:`fogref.compare.metrics.mse_noise`).  (2) With a
second pair of renders (another seed), each statistic is recomputed and its noise
is estimated as ``|x(seed a) - x(seed b)| / sqrt(2)`` (the shares' noise).
"""

# The modules: effects (the players, their images, every coalition's image), shapley (the
# values and their noise), engines (the engine side per model, run_budget), telescoping (the
# telescoping chain and its noise), report (budget.md's tables and budget.png).

from __future__ import annotations

from fogref.study.budget.effects import (
    CONFIG_EFFECTS,
    EFFECTS,
    EFFECTS_COLOURS_IN_LOBE,
    PHASE,
    RENDERED,
    STEPS,
    closed_forms,
    coalition_image,
    effective_coalition,
    shapley_parts,
)
from fogref.study.budget.engines import (
    UNREAL_ONLY,
    applicable_effects,
    model_engine,
    phase_effect,
    run_budget,
    unreal_engine,
)
from fogref.study.budget.report import markdown, plot, port_vs_engine_line, shapley_markdown
from fogref.study.budget.shapley import (
    BOOTSTRAP_BLOCK,
    BOOTSTRAP_RESAMPLES,
    add_shapley_seed_noise,
    shapley_budget,
    shapley_values,
    shapley_weights,
)
from fogref.study.budget.telescoping import add_noise, attribute, chain, chain_noise, footprint_check, what_if

__all__ = [
    "BOOTSTRAP_BLOCK",
    "BOOTSTRAP_RESAMPLES",
    "CONFIG_EFFECTS",
    "EFFECTS",
    "EFFECTS_COLOURS_IN_LOBE",
    "PHASE",
    "RENDERED",
    "STEPS",
    "UNREAL_ONLY",
    "add_noise",
    "add_shapley_seed_noise",
    "applicable_effects",
    "attribute",
    "chain",
    "chain_noise",
    "closed_forms",
    "coalition_image",
    "effective_coalition",
    "footprint_check",
    "markdown",
    "model_engine",
    "phase_effect",
    "plot",
    "port_vs_engine_line",
    "run_budget",
    "shapley_budget",
    "shapley_markdown",
    "shapley_parts",
    "shapley_values",
    "shapley_weights",
    "unreal_engine",
    "what_if",
]
