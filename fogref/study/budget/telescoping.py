"""The telescoping chain ``S_0 .. S_9`` from the truth to Unreal, one effect at a time, and its noise.

:func:`chain` builds the images (the table in :mod:`fogref.study.budget`'s docstring),
:func:`chain_noise` their per-pixel standard errors from the truths' ``stderr.*`` channels,
:func:`attribute` each step's RMSE and share of the squared error, :func:`add_noise` the
seed-to-seed noise; :func:`footprint_check` and :func:`what_if` are checks beside it.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from fogref.compare.metrics import mse_noise
from fogref.gbuffer import Truth
from fogref.models.ue4 import UE4FogParams
from fogref.study.budget.effects import STEPS, closed_forms
from fogref.study.budget.engines import unreal_fog


def _model_configs(lobe_params: UE4FogParams, model_params: UE4FogParams) -> list:
    """``(params, precision)`` of steps 5..9."""
    plain = dict(
        DirectionalInscatteringStartDistance=0.0, StartDistance=0.0, FogMaxOpacity=1.0, FogCutoffDistance=0.0
    )
    return [
        (replace(lobe_params, **plain), "float64"),
        (replace(model_params, **plain), "float64"),
        (replace(model_params, FogMaxOpacity=1.0, FogCutoffDistance=0.0), "float64"),
        (model_params, "float64"),
        (model_params, "float32"),
    ]


def chain(
    truth: Truth,
    sky_single: np.ndarray,
    pf,
    lobe_params: UE4FogParams,
    model_params: UE4FogParams,
    sky_distance: float = 1.0e5,
) -> list[np.ndarray]:
    """The images ``S_0 .. S_9`` (see the module doc), each ``(H, W, 3)``.

    ``sky_single``: (H, W, 3) ``single.*`` of a render of the same scene with the sun
    removed.  ``lobe_params``: Unreal fitted to the unattenuated single scattering
    (start distances 0).  ``model_params``: the Unreal parameters under study.
    ``S_5 .. S_9`` hold ``surface * T_model + L_model``; they mean something only
    where ``truth.surface_valid`` (``surface`` is 0 elsewhere).
    """
    cf = closed_forms(truth, pf)
    att = truth.attenuated_surface
    S = [
        truth.final,
        att + truth.single,
        att + cf["sun_att"] + sky_single,
        att + cf["sun_att"] + cf["sky"],
        att + cf["sun_noatt"] + cf["sky"],
    ]
    for p, precision in _model_configs(lobe_params, model_params):
        Tm, Lm = unreal_fog(p, truth, precision, sky_distance)
        S.append(truth.surface * Tm + Lm)
    return S


def chain_noise(
    truth: Truth,
    sky_single_stderr: np.ndarray,
    lobe_params: UE4FogParams,
    model_params: UE4FogParams,
    sky_distance: float = 1.0e5,
) -> dict:
    """Per-pixel standard errors ``(H, W, 3)`` of each ``Δ_k`` and of the total ``E``.

    From the truth's ``stderr.*`` channels and ``sky_single_stderr`` (the sun-less
    render's ``stderr.single``); see the module doc.  Returns ``{"steps": [σ_1 ..
    σ_9], "total": σ_E}`` [radiance].
    """
    se = truth.stderr
    Tms = [
        unreal_fog(p, truth, precision, sky_distance)[0]
        for p, precision in _model_configs(lobe_params, model_params)
    ]
    zero = np.zeros(truth.final.shape)
    steps = [
        se["multiple"],
        np.hypot(se["single"], sky_single_stderr),
        sky_single_stderr,
        zero,
        np.hypot(Tms[0] * se["surface"], se["attenuated_surface"]),
    ]
    steps += [np.abs(Tms[k] - Tms[k - 1]) * se["surface"] for k in range(1, len(Tms))]
    return {"steps": steps, "total": np.hypot(se["final"], Tms[-1] * se["surface"])}


def _rmse(x, mask=None):
    if mask is not None:
        x = x[mask]
    return float(np.sqrt(np.mean(x * x))) if x.size else 0.0


def _noise_fields(d: np.ndarray, sigma: np.ndarray, mask: np.ndarray) -> dict:
    m = mse_noise(d, sigma, mask)
    if m is None:
        return {}
    hi, lo = np.sqrt(m["mse"] + m["stderr"]), np.sqrt(max(m["mse"] - m["stderr"], 0.0))
    return {
        "rmse_noise_floor": float(np.sqrt(m["noise_floor"])),
        "rmse_stderr": float(0.5 * (hi - lo)),
        "rmse_debiased": float(np.sqrt(m["debiased"])),
        "below_noise": m["below_noise"],
    }


def attribute(
    S: list[np.ndarray], hit: np.ndarray, valid: np.ndarray | None = None, noise: dict | None = None
) -> dict:
    """Per-step statistics of a chain over the ``valid`` pixels (default all).

    ``noise``: :func:`chain_noise`'s per-pixel standard errors; with it every RMSE
    (step and total) gets ``rmse_noise_floor``, ``rmse_stderr``, ``rmse_debiased``
    and ``below_noise``.  ``telescoping_residual`` is the largest ``|Σ Δ_k - (S_K -
    S_0)|`` (0 up to float64 rounding); ``excluded_pixels`` counts the pixels left
    out (``surface`` undefined).
    """
    valid = np.ones(hit.shape, dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    E = S[-1] - S[0]
    e2 = float(np.sum(E[valid] ** 2))
    deltas = [S[k] - S[k - 1] for k in range(1, len(S))]
    resid = float(np.max(np.abs(sum(deltas) - E)[valid], initial=0.0))
    masks = {"all": valid, "surface": hit & valid, "sky": ~hit & valid}
    steps = []
    for i, ((key, letter, label), dk, Sk) in enumerate(zip(STEPS, deltas, S[1:])):
        step = {
            "key": key,
            "effect": letter,
            "label": label,
            "rmse": {r: _rmse(dk, m) for r, m in masks.items()},
            "mean": float(np.mean(dk[valid])) if valid.any() else 0.0,
            "share": float(np.sum((dk * E)[valid]) / e2) if e2 > 0 else 0.0,
            "rmse_vs_truth_after": _rmse(Sk - S[0], valid),
        }
        if noise is not None:
            step.update(_noise_fields(dk, noise["steps"][i], valid))
        steps.append(step)
    total = {
        "rmse": {r: _rmse(E, m) for r, m in masks.items()},
        "mean": float(np.mean(E[valid])) if valid.any() else 0.0,
        "truth_rms": _rmse(S[0], valid),
    }
    if noise is not None:
        total.update(_noise_fields(E, noise["total"], valid))
    return {
        "total": total,
        "steps": steps,
        "telescoping_residual": resid,
        "share_sum": float(sum(s["share"] for s in steps)),
        "pixels": int(valid.sum()),
        "excluded_pixels": int((~valid).sum()),
    }


def add_noise(
    result: dict,
    S_a: list[np.ndarray],
    S_b: list[np.ndarray],
    hit: np.ndarray,
    valid: np.ndarray | None = None,
) -> dict:
    """Add Monte Carlo noise estimates from a second chain ``S_b`` (other seeds) to ``result``
    (computed from ``S_a``), over the pixels valid in both (default all)."""
    valid = np.ones(hit.shape, dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    other = attribute(S_b, hit, valid)
    da = [S_a[k] - S_a[k - 1] for k in range(1, len(S_a))]
    db = [S_b[k] - S_b[k - 1] for k in range(1, len(S_b))]
    r2 = math.sqrt(2.0)
    for s, so, a, b in zip(result["steps"], other["steps"], da, db):
        s["noise"] = {
            "pixel_rms": _rmse(a - b, valid) / r2,  # per-pixel noise of Δ_k
            # RMSE of Δ_k with the noise removed in quadrature (noise adds variance)
            "rmse_denoised": math.sqrt(max(s["rmse"]["all"] ** 2 - (_rmse(a - b, valid) / r2) ** 2, 0.0)),
            "rmse": abs(s["rmse"]["all"] - so["rmse"]["all"]) / r2,
            "share": abs(s["share"] - so["share"]) / r2,
        }
        s["rmse_other_seed"] = so["rmse"]["all"]
        s["share_other_seed"] = so["share"]
    result["total"]["noise_rmse"] = abs(result["total"]["rmse"]["all"] - other["total"]["rmse"]["all"]) / r2
    result["total"]["rmse_other_seed"] = other["total"]["rmse"]["all"]
    return result


def footprint_check(truth: Truth, pf, S: list[np.ndarray], step: str = "shadows", tol: float = 0.01) -> dict:
    """Pixels straddling an edge (rays of one pixel hitting different depths) are
    evaluated at their mean distance by the closed forms and by the model.  They
    show up as ``|T_closed_form - T_exr| > tol``; returns their fraction and their
    part of the squared norm of ``step``'s Δ."""
    k = [s[0] for s in STEPS].index(step) + 1
    cf = closed_forms(truth, pf)
    mixed = np.abs(cf["T"] - truth.transmittance).max(-1) > tol
    dk = S[k] - S[k - 1]
    tot = float(np.sum(dk * dk))
    return {
        "tolerance": tol,
        "pixel_fraction": float(mixed.mean()),
        "step": step,
        "share_of_step_sq": float(np.sum(dk[mixed] ** 2) / tot) if tot > 0 else 0.0,
        "max_T_difference": float(np.abs(cf["T"] - truth.transmittance).max()),
    }


def what_if(
    truth: Truth, model_params: UE4FogParams, variants: dict, sky_distance: float = 1.0e5
) -> list[dict]:
    """RMSE against the truth of the model with some fields changed (``variants``:
    name -> dict of UE4FogParams fields), float32; and the change vs the model.

    Over the pixels where ``surface`` is defined (the model is composited on it);
    each row also carries ``rmse_noise_floor`` and ``below_noise``.
    """
    valid = truth.surface_valid
    se = truth.stderr

    def row(params):
        Tm, Lm = unreal_fog(params, truth, "float32", sky_distance)
        d = truth.surface * Tm + Lm - truth.final
        return _rmse(d, valid), _noise_fields(d, np.hypot(se["final"], Tm * se["surface"]), valid)

    base, _ = row(model_params)
    rows = []
    for name, kw in variants.items():
        r, noise = row(replace(model_params, **kw))
        rows.append({"variant": name, "fields": kw, "rmse": r, "delta_rmse": r - base, **noise})
    return rows
