"""The engine side of the budget, per model, and the budget of any model.

:func:`unreal_engine` (Unreal's Exponential Height Fog, :mod:`fogref.models.ue4`, in each
configuration of :data:`~fogref.study.budget.effects.CONFIG_EFFECTS`) and :func:`model_engine` (any
fog model, its sun lobe split off with :attr:`fogref.mapping.free.FitSpec.sun_off`) give
``engine(truth, config, sky_distance) -> (T, L_sun, L_sky)``; :func:`applicable_effects` the
effects that apply to a model; :func:`run_budget` plays the Shapley game with them.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from fogref.gbuffer import Truth
from fogref.mapping.free import fit_spec
from fogref.mapping.registry import from_physical
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams
from fogref.study.budget.effects import EFFECTS, shapley_parts
from fogref.study.budget.report import port_vs_engine_line
from fogref.study.budget.shapley import BOOTSTRAP_RESAMPLES, shapley_budget


def unreal_fog(params: UE4FogParams, truth: Truth, precision: str, sky_distance: float):
    """Unreal's fog with ``params`` at the truth's pixels (sky pixels at ``sky_distance`` m, the
    shader in ``precision``): ``(transmittance (H, W) in [0, 1], inscatter (H, W, 3) >= 0)``,
    float64 arrays."""
    r = UE4ExponentialHeightFog(params).evaluate(truth.camera, truth.world_positions(sky_distance), precision)
    return np.asarray(r.transmittance, np.float64), np.asarray(r.inscatter, np.float64)


def _config_params(
    lobe_params: UE4FogParams, model_params: UE4FogParams, refit: bool, start: bool, opacity: bool
) -> UE4FogParams:
    p = model_params if refit else lobe_params
    m = model_params
    dist = m.DirectionalInscatteringStartDistance if start else 0.0
    return replace(
        p,
        DirectionalInscatteringStartDistance=dist,
        StartDistance=m.StartDistance if start else 0.0,
        FogMaxOpacity=model_params.FogMaxOpacity if opacity else 1.0,
        FogCutoffDistance=model_params.FogCutoffDistance if opacity else 0.0,
    )


def unreal_engine(lobe_params: UE4FogParams, model_params: UE4FogParams):
    """The engine side of the Shapley game for Unreal: ``engine(truth, config, sky_distance)``.

    ``config``: a dict of the :data:`CONFIG_EFFECTS` effects (True = the engine's setting):
    ``refit`` (the study's colours/exponent instead of the lobe-only fit), ``start_distance``
    (its StartDistance and DirectionalInscatteringStartDistance, else 0), ``opacity_cutoff``
    (its FogMaxOpacity and FogCutoffDistance, else 1 and 0), ``float32`` (the shader's
    arithmetic, else float64).  Returns ``(T, L_sun, L_sky)``, each (H, W, 3): the
    transmittance, the directional (sun) inscatter and the rest (``L_sky``: the model with
    DirectionalInscatteringColor 0).  Another engine plugs in with the same signature.
    """

    def engine(truth: Truth, config: dict, sky_distance: float):
        p = _config_params(
            lobe_params, model_params, config["refit"], config["start_distance"], config["opacity_cutoff"]
        )
        prec = "float32" if config["float32"] else "float64"
        T, L = unreal_fog(p, truth, prec, sky_distance)
        no_sun = replace(p, DirectionalInscatteringColor=(0.0, 0.0, 0.0))
        _, L_sky = unreal_fog(no_sun, truth, prec, sky_distance)
        return T, L - L_sky, L_sky

    return engine


#: Effects that are Unreal's own settings (the chain's steps 7 and 8); another model has none.
UNREAL_ONLY = ("start_distance", "opacity_cutoff")


def _evaluate(model, truth: Truth, precision: str, sky_distance: float):
    r = model.evaluate(truth.camera, truth.world_positions(sky_distance), precision)
    shape = (*truth.shape, 3)
    return (
        np.broadcast_to(np.asarray(r.transmittance, np.float64), shape),
        np.broadcast_to(np.asarray(r.inscatter, np.float64), shape),
    )


def model_engine(model, lobe_model=None):
    """The engine side of the Shapley game for any fog model instance (the signature of
    :func:`unreal_engine`): ``engine(truth, config, sky_distance) -> (T, L_sun, L_sky)``.

    ``config["refit"]``: ``model`` (else ``lobe_model``, the model fitted to the unattenuated
    target; without one, ``model`` in both); ``config["float32"]``: the shader's arithmetic, else
    float64; the Unreal-only settings (:data:`UNREAL_ONLY`) do not apply and are ignored.
    ``L_sun``: the model's inscatter minus the same model with its sun lobe off
    (:attr:`fogref.mapping.free.FitSpec.sun_off`; a model without a sun: 0).
    """

    def sun_off(m):
        spec = fit_spec(type(m))
        if spec.sun_off is None or not hasattr(m, "params"):
            return None
        return type(m)(spec.sun_off(m.params))

    def engine(truth: Truth, config: dict, sky_distance: float):
        m = model if (config["refit"] or lobe_model is None) else lobe_model
        prec = "float32" if config["float32"] else "float64"
        T, L = _evaluate(m, truth, prec, sky_distance)
        off = sun_off(m)
        L_sky = L if off is None else _evaluate(off, truth, prec, sky_distance)[1]
        return T, L - L_sky, L_sky

    return engine


def applicable_effects(model, lobe_model=None, pf=None) -> tuple[str, ...]:
    """The effects of :data:`EFFECTS` that apply to ``model``: all of them for Unreal; without
    Unreal's start distances and opacity/cutoff for the others; without "refit" when there is
    no separate ``lobe_model``; with "phase" (:data:`~fogref.study.budget.effects.PHASE`) when
    the fog of ``pf`` has a tabulated phase (droplets)."""
    name = getattr(model, "name", None)
    out = [k for k in EFFECTS if name == "ue4" or k not in UNREAL_ONLY]
    if lobe_model is None:
        out.remove("refit")
    return tuple(out) + phase_effect(pf)


def phase_effect(pf) -> tuple[str, ...]:
    """``("phase",)`` when the fog of ``pf`` has a tabulated phase (droplets), else ``()``."""
    return ("phase",) if pf is not None and pf.medium.phase is not None else ()


def run_budget(
    truth: Truth,
    sky_single: np.ndarray,
    pf,
    model,
    lobe_model=None,
    valid=None,
    sky_distance: float = 1.0e5,
    resamples: int = BOOTSTRAP_RESAMPLES,
    seed: int = 0,
    port_vs_engine: dict | None = None,
) -> dict:
    """The Shapley budget of any model (an instance, or a name built by
    :func:`fogref.mapping.from_physical` of ``pf``) against a truth.

    Unreal with a ``lobe_model`` uses :func:`unreal_engine`; every other model
    :func:`model_engine`, over :func:`applicable_effects`.  ``sky_single``: the sun-less
    render's ``single``; ``valid``: pixels (default ``truth.surface_valid``); ``port_vs_engine``:
    the model's port against its real engine where one ran (``engine.json``'s ``port_vs_engine``
    from ``fogref compare TRUTH --engine NAME``).  Returns :func:`shapley_budget`'s dict with
    ``"model"`` and ``"port_vs_engine"`` (:func:`~fogref.study.budget.report.port_vs_engine_line`)
    added.
    """
    if isinstance(model, str):
        model = from_physical(model, pf)
    if isinstance(lobe_model, str):
        raise TypeError("run_budget: lobe_model must be a model instance")
    name = getattr(model, "name", type(model).__name__)
    if name == "ue4" and lobe_model is not None:
        engine = unreal_engine(lobe_model.params, model.params)
    else:
        engine = model_engine(model, lobe_model)
    parts = shapley_parts(truth, sky_single, pf, engine, sky_distance)
    valid = truth.surface_valid if valid is None else valid
    effects = applicable_effects(model, lobe_model, pf)
    out = shapley_budget(parts, valid, effects, resamples=resamples, seed=seed)
    out["model"] = name
    out["port_vs_engine"] = port_vs_engine_line(name, port_vs_engine)
    return out
