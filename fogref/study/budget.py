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
reused by all coalitions.  Noise: a block bootstrap over the image and, with a second pair
of renders, the seed-to-seed difference.  **Second, the telescoping chain** below.

**Every model** (:func:`run_budget`): the same Shapley game with another model's engine side
(:func:`model_engine`: its transmittance and inscatter, the sun lobe split off with
:attr:`fogref.mapping.free.FitSpec.sun_off`), over the effects that apply to it
(:func:`applicable_effects`: Unreal's start distances and opacity/cutoff are Unreal's own).

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

from __future__ import annotations

import math

import numpy as np

from fogref.gbuffer import Truth
from fogref.media import NP, hg_phase, single_scatter_sun
from fogref.media.single_scatter import single_scatter_sky
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams

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
#: Steps whose images come from renders (carry Monte Carlo noise).
RENDERED = ("multiple", "shadows", "sky")


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
        sun_noatt = alb * E * hg_phase(NP, cos, m.g)[:, None] * (1.0 - T)
    else:
        sun_noatt = np.zeros_like(T)
    sky = np.stack(single_scatter_sky(NP, m, o, d, D, pf.sky_radiance or (0.0, 0.0, 0.0)), -1)
    return {"T": T.reshape(shape), "sun_att": sun_att.reshape(shape), "sun_noatt": sun_noatt.reshape(shape),
            "sky": sky.reshape(shape)}


def _unreal(params: UE4FogParams, truth: Truth, precision: str, sky_distance: float):
    r = UE4ExponentialHeightFog(params).evaluate(truth.camera, truth.world_positions(sky_distance), precision)
    return np.asarray(r.transmittance, np.float64), np.asarray(r.inscatter, np.float64)


def _model_configs(lobe_params: UE4FogParams, model_params: UE4FogParams) -> list:
    """``(params, precision)`` of steps 5..9."""
    from dataclasses import replace

    plain = dict(DirectionalInscatteringStartDistance=0.0, StartDistance=0.0, FogMaxOpacity=1.0,
                 FogCutoffDistance=0.0)
    return [(replace(lobe_params, **plain), "float64"), (replace(model_params, **plain), "float64"),
            (replace(model_params, FogMaxOpacity=1.0, FogCutoffDistance=0.0), "float64"),
            (model_params, "float64"), (model_params, "float32")]


def chain(truth: Truth, sky_single: np.ndarray, pf, lobe_params: UE4FogParams, model_params: UE4FogParams,
          sky_distance: float = 1.0e5) -> list[np.ndarray]:
    """The images ``S_0 .. S_9`` (see the module doc), each ``(H, W, 3)``.

    ``sky_single``: (H, W, 3) ``single.*`` of a render of the same scene with the sun
    removed.  ``lobe_params``: Unreal fitted to the unattenuated single scattering
    (start distances 0).  ``model_params``: the Unreal parameters under study.
    ``S_5 .. S_9`` hold ``surface * T_model + L_model``; they mean something only
    where ``truth.surface_valid`` (``surface`` is 0 elsewhere).
    """
    cf = closed_forms(truth, pf)
    att = truth.attenuated_surface
    S = [truth.final,
         att + truth.single,
         att + cf["sun_att"] + sky_single,
         att + cf["sun_att"] + cf["sky"],
         att + cf["sun_noatt"] + cf["sky"]]
    for p, precision in _model_configs(lobe_params, model_params):
        Tm, Lm = _unreal(p, truth, precision, sky_distance)
        S.append(truth.surface * Tm + Lm)
    return S


def chain_noise(truth: Truth, sky_single_stderr: np.ndarray, lobe_params: UE4FogParams,
                model_params: UE4FogParams, sky_distance: float = 1.0e5) -> dict:
    """Per-pixel standard errors ``(H, W, 3)`` of each ``Δ_k`` and of the total ``E``.

    From the truth's ``stderr.*`` channels and ``sky_single_stderr`` (the sun-less
    render's ``stderr.single``); see the module doc.  Returns ``{"steps": [σ_1 ..
    σ_9], "total": σ_E}`` [radiance].
    """
    se = truth.stderr
    Tms = [_unreal(p, truth, precision, sky_distance)[0] for p, precision in _model_configs(lobe_params,
                                                                                          model_params)]
    zero = np.zeros(truth.final.shape)
    steps = [se["multiple"], np.hypot(se["single"], sky_single_stderr), sky_single_stderr, zero,
             np.hypot(Tms[0] * se["surface"], se["attenuated_surface"])]
    steps += [np.abs(Tms[k] - Tms[k - 1]) * se["surface"] for k in range(1, len(Tms))]
    return {"steps": steps, "total": np.hypot(se["final"], Tms[-1] * se["surface"])}


def _rmse(x, mask=None):
    if mask is not None:
        x = x[mask]
    return float(np.sqrt(np.mean(x * x))) if x.size else 0.0


def _noise_fields(d: np.ndarray, sigma: np.ndarray, mask: np.ndarray) -> dict:
    from fogref.compare.metrics import mse_noise

    m = mse_noise(d, sigma, mask)
    if m is None:
        return {}
    hi, lo = np.sqrt(m["mse"] + m["stderr"]), np.sqrt(max(m["mse"] - m["stderr"], 0.0))
    return {"rmse_noise_floor": float(np.sqrt(m["noise_floor"])), "rmse_stderr": float(0.5 * (hi - lo)),
            "rmse_debiased": float(np.sqrt(m["debiased"])), "below_noise": m["below_noise"]}


def attribute(S: list[np.ndarray], hit: np.ndarray, valid: np.ndarray | None = None,
              noise: dict | None = None) -> dict:
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
            "key": key, "effect": letter, "label": label,
            "rmse": {r: _rmse(dk, m) for r, m in masks.items()},
            "mean": float(np.mean(dk[valid])) if valid.any() else 0.0,
            "share": float(np.sum((dk * E)[valid]) / e2) if e2 > 0 else 0.0,
            "rmse_vs_truth_after": _rmse(Sk - S[0], valid),
        }
        if noise is not None:
            step.update(_noise_fields(dk, noise["steps"][i], valid))
        steps.append(step)
    total = {"rmse": {r: _rmse(E, m) for r, m in masks.items()},
             "mean": float(np.mean(E[valid])) if valid.any() else 0.0, "truth_rms": _rmse(S[0], valid)}
    if noise is not None:
        total.update(_noise_fields(E, noise["total"], valid))
    return {"total": total, "steps": steps, "telescoping_residual": resid,
            "share_sum": float(sum(s["share"] for s in steps)),
            "pixels": int(valid.sum()), "excluded_pixels": int((~valid).sum())}


def add_noise(result: dict, S_a: list[np.ndarray], S_b: list[np.ndarray], hit: np.ndarray,
              valid: np.ndarray | None = None) -> dict:
    """Add Monte Carlo noise estimates from a second chain ``S_b`` (other seeds) to ``result``
    (computed from ``S_a``), over the pixels valid in both (default all)."""
    valid = np.ones(hit.shape, dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    other = attribute(S_b, hit, valid)
    da = [S_a[k] - S_a[k - 1] for k in range(1, len(S_a))]
    db = [S_b[k] - S_b[k - 1] for k in range(1, len(S_b))]
    r2 = math.sqrt(2.0)
    for s, so, a, b in zip(result["steps"], other["steps"], da, db):
        s["noise"] = {
            "pixel_rms": _rmse(a - b, valid) / r2,     # per-pixel noise of Δ_k
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
    return {"tolerance": tol, "pixel_fraction": float(mixed.mean()), "step": step,
            "share_of_step_sq": float(np.sum(dk[mixed] ** 2) / tot) if tot > 0 else 0.0,
            "max_T_difference": float(np.abs(cf["T"] - truth.transmittance).max())}


def what_if(truth: Truth, model_params: UE4FogParams, variants: dict,
            sky_distance: float = 1.0e5) -> list[dict]:
    """RMSE against the truth of the model with some fields changed (``variants``:
    name -> dict of UE4FogParams fields), float32; and the change vs the model.

    Over the pixels where ``surface`` is defined (the model is composited on it);
    each row also carries ``rmse_noise_floor`` and ``below_noise``.
    """
    from dataclasses import replace

    valid = truth.surface_valid
    se = truth.stderr

    def row(params):
        Tm, Lm = _unreal(params, truth, "float32", sky_distance)
        d = truth.surface * Tm + Lm - truth.final
        return _rmse(d, valid), _noise_fields(d, np.hypot(se["final"], Tm * se["surface"]), valid)

    base, _ = row(model_params)
    rows = []
    for name, kw in variants.items():
        r, noise = row(replace(model_params, **kw))
        rows.append({"variant": name, "fields": kw, "rmse": r, "delta_rmse": r - base, **noise})
    return rows


def _floor(s: dict) -> str:
    if "rmse_noise_floor" not in s:
        return "—"
    return f"{s['rmse_noise_floor']:.2g}" + (" (below the noise)" if s["below_noise"] else "")


def markdown(result: dict, title: str = "Error budget of Unreal's exponential height fog") -> str:
    """The budget table as Markdown."""
    t = result["total"]
    lines = [f"# {title}", "",
             f"Total error of the Unreal model (float32, as compared) against the path-traced truth: "
             f"**RMSE {t['rmse']['all']:.4g}** (surface pixels {t['rmse']['surface']:.4g}, "
             f"sky {t['rmse']['sky']:.4g}; truth RMS {t['truth_rms']:.4g}; Monte Carlo noise of the total "
             f"±{t.get('noise_rmse', float('nan')):.2g}"
             + (f"; noise floor {t['rmse_noise_floor']:.2g} from the truth's stderr, "
                f"{'**below the noise**' if t['below_noise'] else 'above the noise'}"
                if "rmse_noise_floor" in t else "") + ").",
             ""]
    if result.get("shapley"):
        lines += [shapley_markdown(result["shapley"]), ""]
        if result.get("shapley_colours_in_lobe"):
            lines += [shapley_markdown(result["shapley_colours_in_lobe"],
                                       "### Variant: the colour re-fit folded into the lobe"), ""]
        lines += ["## Telescoping chain (second view)", ""]
    lines += [f"Pixels: {result.get('pixels', '?')} used, {result.get('excluded_pixels', 0)} excluded "
              "(the truth's "
             "unattenuated surface is undefined there: no sample reached it, so no model can be composited "
             "on it).",
             "",
             "Each row switches one effect, going from the truth to Unreal; Δ_k = S_k − S_{k−1}. "
             "*Share* = ⟨Δ_k, E⟩/⟨E, E⟩ with E = model − truth: the shares add up to 100 % exactly "
             f"(sum {100 * result['share_sum']:.6f} %, "
             f"largest |ΣΔ_k − E| = {result['telescoping_residual']:.2g}); "
             "a negative share means the step cancels part of the other errors. "
             "*Noise*: per-pixel Monte Carlo noise of Δ_k and the noise of its share, from a second render "
             "with another seed (closed-form steps are noise-free).", "",
             "*Denoised*: √(RMSE² − noise²), the step's size without the Monte Carlo noise.", "",
             "*Noise floor*: the RMSE Δ_k would have from the truths' per-pixel standard errors alone "
             "(`stderr.*` channels); *below the noise*: Δ_k cannot be told from 0 at this sample count.", "",
             "| k | effect | step | RMSE of Δ_k | denoised | (surface / sky) | share of E² | "
             "noise: pixel RMS / share | noise floor (stderr) | RMSE vs truth after step |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for k, s in enumerate(result["steps"], 1):
        n = s.get("noise")
        rendered = n and s["key"] in RENDERED
        ns = f"{n['pixel_rms']:.2g} / ±{100 * n['share']:.2g} %" if rendered else "0 (closed form)"
        dn = f"{n['rmse_denoised']:.4g}" if n and s["key"] in RENDERED else f"{s['rmse']['all']:.4g}"
        lines.append(f"| {k} | [{s['effect']}] | {s['label']} | {s['rmse']['all']:.4g} | {dn} | "
                     f"{s['rmse']['surface']:.3g} / {s['rmse']['sky']:.3g} | {100 * s['share']:+.1f} % | "
                     f"{ns} | "
                     f"{_floor(s)} | {s['rmse_vs_truth_after']:.4g} |")
    by = {s["key"]: s for s in result["steps"]}
    off = [k for k in ("start_distance", "opacity_cutoff") if by.get(k) and by[k]["rmse"]["all"] == 0]
    if off:
        lines += ["", "Steps " + " and ".join(f"[{by[k]['effect']}]" for k in off) + " are exactly 0 "
                  "because the model under study has those settings off (the fitted "
                  "DirectionalInscatteringStartDistance is "
                  "0; StartDistance 0, FogMaxOpacity 1 and FogCutoffDistance 0 are the editor defaults); the "
                  "*What if* table below measures them switched on."]
    fc = result.get("footprint")
    if fc:
        lines += ["", f"Pixel footprint: {100 * fc['pixel_fraction']:.2g} % of the pixels straddle an edge "
                  "(their "
                  f"closed-form T differs from the EXR's by more than {fc['tolerance']}); they hold "
                  f"{100 * fc['share_of_step_sq']:.2g} % of the squared '{fc['step']}' step, so that step is "
                  "not an artefact of per-pixel (G-buffer) evaluation."]
    oc = result.get("open_plane_check")
    if oc:
        lines += ["", f"Closed-form check on `{oc['scene']}` (no occluders, {oc['resolution'][0]}×"
                  f"{oc['resolution'][1]}, {oc['spp']} spp): the 'shadows' step there is RMSE "
                  f"{oc['shadows_rmse']:.3g} against an expected pure-noise level of {oc['noise_rmse']:.3g} "
                  f"(mean {oc['shadows_mean']:+.2g} vs single-scattering RMS {oc['single_rms']:.3g}): "
                  "the closed-form sun "
                  "single scattering matches the path tracer where nothing casts shadows."]
    if result.get("what_if"):
        lines += ["", "## What if (engine settings the study leaves at their defaults)", "",
                  "RMSE of the float32 model against the truth with one setting changed:", "",
                  "| variant | fields | RMSE | Δ RMSE | noise floor |", "|---|---|---|---|---|"]
        for r in result["what_if"]:
            lines.append(f"| {r['variant']} | `{r['fields']}` | {r['rmse']:.4g} | {r['delta_rmse']:+.3g} | "
                         f"{_floor(r)} |")
    lines += ["", "![budget](budget.png)", ""]
    return "\n".join(lines)


def plot(result: dict, path) -> None:
    """Bar charts: the Shapley shares first (with their noise, when ``result["shapley"]``), then
    each chain step's RMSE (with noise bars) and its chain share of the total."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fogref.atomic import save_figure_atomic as save_figure

    steps = result["steps"]
    labels = [f"[{s['effect']}] {s['label']}" for s in steps]
    rm = [s["rmse"]["all"] for s in steps]
    err = [s["noise"]["pixel_rms"] if s.get("noise") and s["key"] in RENDERED else 0.0 for s in steps]
    share = [100 * s["share"] for s in steps]
    y = np.arange(len(steps))[::-1]
    sh = result.get("shapley")
    if sh:
        by = {r["key"]: r for r in sh["effects"]}
        fig, ax3 = plt.subplots(1, 3, figsize=(20, 4.6), sharey=True)
        a0, ax = ax3[0], ax3[1:]
        sv = [100 * by[s["key"]]["share"] if s["key"] in by else 0.0 for s in steps]
        se = [100 * by[s["key"]]["share_noise"] if s["key"] in by else 0.0 for s in steps]
        a0.barh(y, sv, xerr=se, capsize=3, color=["#c0504d" if v > 0 else "#9bbb59" for v in sv])
        a0.axvline(0, color="k", lw=0.8)
        a0.set_yticks(y, labels)
        a0.set_xlabel("Shapley share of the squared error [%]\n"
                      "all coalitions, order-free; bars: bootstrap noise")
        for yy, v in zip(y, sv):
            a0.text(v, yy, f" {v:+.1f}%", va="center", ha="left" if v >= 0 else "right", fontsize=8)
        a0.grid(axis="x", alpha=0.3)
    else:
        fig, ax = plt.subplots(1, 2, figsize=(14, 4.6), sharey=True)
    ax[0].barh(y, rm, xerr=err, color="#4a78b0", capsize=3)
    ax[0].axvline(result["total"]["rmse"]["all"], color="k", ls="--", lw=1, label="total model − truth")
    ax[0].set_yticks(y, labels)
    ax[0].set_xlabel("RMSE of Δ_k (radiance)\nerror bars: Monte Carlo noise per pixel")
    ax[0].legend(loc="lower right", fontsize=8)
    ax[1].barh(y, share, color=["#c0504d" if v > 0 else "#9bbb59" for v in share])
    ax[1].axvline(0, color="k", lw=0.8)
    ax[1].set_xlabel("chain share of the total squared error [%]\n⟨Δ_k, E⟩/⟨E, E⟩, sums to 100")
    for yy, v in zip(y, share):
        ax[1].text(v, yy, f" {v:+.1f}%", va="center", ha="left" if v >= 0 else "right", fontsize=8)
    for a in ax:
        a.grid(axis="x", alpha=0.3)
    fig.suptitle("Unreal exponential height fog: error budget "
                 f"(total RMSE {result['total']['rmse']['all']:.4g})")
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


# ------------------------------------------------------------------------------------------
# Shapley budget: order-independent shares over the same effects
# ------------------------------------------------------------------------------------------

#: The Shapley budget's players: the chain's effects (:data:`STEPS` keys, same order).
EFFECTS: tuple[str, ...] = tuple(s[0] for s in STEPS)
#: The same players with the colour re-fit folded into the lobe (the engine always uses the
#: study's colours): the compensation between "lobe" and "refit" disappears from the table.
EFFECTS_COLOURS_IN_LOBE: tuple[str, ...] = tuple(k for k in EFFECTS if k != "refit")
#: Effects that select the engine's configuration (refit, start distances, opacity/cutoff, float32).
_CONFIG = ("refit", "start_distance", "opacity_cutoff", "float32")
#: Side of the square pixel blocks of the bootstrap [pixels].
BOOTSTRAP_BLOCK = 16
#: Bootstrap resamples of the Shapley shares' noise.
BOOTSTRAP_RESAMPLES = 400


def shapley_weights(n: int) -> np.ndarray:
    """The ``(n, 2^n)`` matrix ``W`` with ``phi = W @ v`` for a game ``v`` over bitmask coalitions.

    ``v[mask]`` is the value of the coalition whose players are the set bits of ``mask``
    (player ``i`` = bit ``i``); ``phi_i = sum_{S not containing i} |S|! (n - |S| - 1)! / n!
    (v(S + i) - v(S))`` (Shapley 1953).  Rows sum to 0; columns of the full and empty
    coalitions make ``sum_i phi_i = v(all) - v(empty)`` (efficiency).

    Examples
    --------
    >>> shapley_weights(2)
    array([[-0.5,  0.5, -0.5,  0.5],
           [-0.5, -0.5,  0.5,  0.5]])
    """
    if not 1 <= n <= 16:
        raise ValueError(f"shapley_weights: n = {n} players outside [1, 16]")
    size = np.array([bin(m).count("1") for m in range(1 << n)])
    wt = np.array([math.factorial(s) * math.factorial(n - s - 1) / math.factorial(n) for s in range(n)])
    W = np.zeros((n, 1 << n))
    for i in range(n):
        bit = 1 << i
        for m in range(1 << n):
            if m & bit:
                continue
            w = wt[size[m]]
            W[i, m | bit] += w
            W[i, m] -= w
    return W


def shapley_values(value, players) -> dict:
    """Exact Shapley values of the game ``value`` over all ``2^k`` coalitions of ``players``.

    Parameters
    ----------
    value : callable
        ``value(frozenset of players) -> float or ndarray`` (arrays: one game per element,
        e.g. per pixel block); called once per coalition.
    players : sequence of hashable
        The k players (k <= 16).

    Returns
    -------
    dict
        player -> Shapley value (float or ndarray); the values sum to ``value(all) -
        value(empty)`` and do not depend on the order of ``players``.

    Examples
    --------
    >>> v = lambda c: float(len(c) ** 2)            # symmetric players share equally
    >>> shapley_values(v, ["a", "b", "c"])
    {'a': 3.0, 'b': 3.0, 'c': 3.0}
    """
    players = list(players)
    n = len(players)
    coalitions = (frozenset(p for i, p in enumerate(players) if m >> i & 1) for m in range(1 << n))
    V = np.stack([np.asarray(value(c), dtype=np.float64) for c in coalitions])
    phi = np.tensordot(shapley_weights(n), V, axes=1)
    return {p: (float(phi[i]) if phi[i].ndim == 0 else phi[i]) for i, p in enumerate(players)}


def _config_params(lobe_params: UE4FogParams, model_params: UE4FogParams, refit: bool, start: bool,
                   opacity: bool) -> UE4FogParams:
    from dataclasses import replace

    p = model_params if refit else lobe_params
    m = model_params
    dist = m.DirectionalInscatteringStartDistance if start else 0.0
    return replace(p, DirectionalInscatteringStartDistance=dist,
                   StartDistance=m.StartDistance if start else 0.0,
                   FogMaxOpacity=model_params.FogMaxOpacity if opacity else 1.0,
                   FogCutoffDistance=model_params.FogCutoffDistance if opacity else 0.0)


def unreal_engine(lobe_params: UE4FogParams, model_params: UE4FogParams):
    """The engine side of the Shapley game for Unreal: ``engine(truth, config, sky_distance)``.

    ``config``: a dict of the :data:`_CONFIG` effects (True = the engine's setting):
    ``refit`` (the study's colours/exponent instead of the lobe-only fit), ``start_distance``
    (its StartDistance and DirectionalInscatteringStartDistance, else 0), ``opacity_cutoff``
    (its FogMaxOpacity and FogCutoffDistance, else 1 and 0), ``float32`` (the shader's
    arithmetic, else float64).  Returns ``(T, L_sun, L_sky)``, each (H, W, 3): the
    transmittance, the directional (sun) inscatter and the rest (``L_sky``: the model with
    DirectionalInscatteringColor 0).  Another engine plugs in with the same signature.
    """
    from dataclasses import replace

    def engine(truth: Truth, config: dict, sky_distance: float):
        p = _config_params(lobe_params, model_params, config["refit"], config["start_distance"],
                           config["opacity_cutoff"])
        prec = "float32" if config["float32"] else "float64"
        T, L = _unreal(p, truth, prec, sky_distance)
        no_sun = replace(p, DirectionalInscatteringColor=(0.0, 0.0, 0.0))
        _, L_sky = _unreal(no_sun, truth, prec, sky_distance)
        return T, L - L_sky, L_sky

    return engine


def shapley_parts(truth: Truth, sky_single: np.ndarray, pf, engine, sky_distance: float = 1.0e5) -> dict:
    """Everything :func:`coalition_image` needs, computed once (the cache of the 2^k coalitions).

    The renders (the truth and ``sky_single``, the sun-less render's ``single``), the closed
    forms of :func:`closed_forms`, and the engine's ``(T, L_sun, L_sky)`` for each of the
    2^4 configurations of :data:`_CONFIG` (``engine``: e.g. :func:`unreal_engine`).
    """
    import itertools

    cf = closed_forms(truth, pf)
    eng = {}
    for bits in itertools.product((False, True), repeat=len(_CONFIG)):
        eng[bits] = engine(truth, dict(zip(_CONFIG, bits)), sky_distance)
    return {"final": truth.final, "att": truth.attenuated_surface, "surface": truth.surface,
            "multiple": truth.final - truth.attenuated_surface - truth.single,
            "sun_render": truth.single - sky_single, "sky_render": sky_single,
            "sun_att": cf["sun_att"], "sun_noatt": cf["sun_noatt"], "sky_cf": cf["sky"], "engine": eng}


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
    cfg = tuple(k in C for k in _CONFIG)
    T, L_sun, L_sky = parts["engine"][cfg]
    T0 = parts["engine"][(False,) * len(_CONFIG)][0]
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
    img = surf + sun + sky
    return img if "multiple" in C else img + parts["multiple"]


def _block_ids(shape: tuple, block: int) -> np.ndarray:
    h, w = shape
    by, bx = np.arange(h)[:, None] // block, np.arange(w)[None, :] // block
    return by * ((w + block - 1) // block) + bx


def shapley_budget(parts: dict, valid: np.ndarray, effects=EFFECTS, block: int = BOOTSTRAP_BLOCK,
                   resamples: int = BOOTSTRAP_RESAMPLES, seed: int = 0) -> dict:
    """Shapley shares of the squared error ``sum |S(all) - S(empty)|^2`` over ``valid`` pixels.

    The game: ``e(C) = sum over valid pixels and channels of |coalition_image(C) - truth|^2``
    (0 for the empty coalition, the model's squared error for the full one).  Each effect's
    Shapley value ``phi_k`` is its share of the squared error, ``share_k = phi_k / e(all)``
    (the shares sum to 1 exactly; no effect's place in an order matters).  A configuration
    effect left out of ``effects`` (e.g. "refit": :data:`EFFECTS_COLOURS_IN_LOBE`) is held on
    the engine's side (see :func:`coalition_image`'s ``fixed``), so the ends stay the truth
    and the model.

    Noise: ``e(C)`` is a sum over pixel blocks (``block`` x ``block``), so the shares are
    re-computed on ``resamples`` bootstrap resamples of the blocks (seeded ``seed``) and
    each share gets their standard deviation, ``share_noise`` (Monte Carlo noise and the
    spread over the image together; Efron & Tibshirani 1993, the block bootstrap).

    Returns ``{"effects": [{key, effect, label, phi, share, share_noise}, ...] (in
    :data:`STEPS` order), "total_sq": e(all), "share_sum", "largest": key, "block",
    "resamples", "coalitions": 2^k}``.
    """
    effects = list(effects)
    fixed = tuple(k for k in _CONFIG if k not in effects)
    valid = np.asarray(valid, dtype=bool)
    ids = _block_ids(valid.shape, block)[valid]
    nb = int(ids.max()) + 1 if ids.size else 1
    truth = parts["final"]

    def per_block(C):
        d = coalition_image(parts, C, fixed) - truth
        e = np.sum(d[valid] ** 2, axis=-1)
        return np.bincount(ids, weights=e, minlength=nb)

    phi_blocks = shapley_values(per_block, effects)                    # key -> (nb,)
    P = np.stack([phi_blocks[k] for k in effects])                     # (k, nb)
    phi = P.sum(1)
    total = float(phi.sum())
    rng = np.random.default_rng(seed)
    shares_b = []
    for _ in range(resamples):
        idx = rng.integers(0, nb, nb)
        pb = P[:, idx].sum(1)
        tb = pb.sum()
        if tb > 0:
            shares_b.append(pb / tb)
    noise = np.std(np.array(shares_b), axis=0) if shares_b else np.zeros(len(effects))
    meta = {s[0]: s for s in STEPS}
    rows = []
    for i, k in enumerate(effects):
        _, letter, label = meta.get(k, (k, "?", k))
        rows.append({"key": k, "effect": letter, "label": label, "phi": float(phi[i]),
                     "share": float(phi[i] / total) if total > 0 else 0.0, "share_noise": float(noise[i])})
    largest = max(rows, key=lambda r: r["share"])["key"] if rows else None
    return {"effects": rows, "total_sq": total, "share_sum": float(sum(r["share"] for r in rows)),
            "largest": largest, "fixed": list(fixed), "block": block, "resamples": resamples,
            "coalitions": 1 << len(effects),
            "pixels": int(valid.sum())}


def add_shapley_seed_noise(result: dict, other: dict) -> dict:
    """Add ``share_noise_seeds = |share(seed a) - share(seed b)| / sqrt(2)`` from a second
    Shapley budget (other renders), and keep the other seed's share."""
    by = {r["key"]: r for r in other["effects"]}
    for r in result["effects"]:
        o = by[r["key"]]
        r["share_other_seed"] = o["share"]
        r["share_noise_seeds"] = abs(r["share"] - o["share"]) / math.sqrt(2.0)
    return result


def shapley_markdown(sh: dict, title: str = "## Shapley budget (order-independent)") -> str:
    """The Shapley table as Markdown (largest share first)."""
    rows = sorted(sh["effects"], key=lambda r: -r["share"])
    top = next(r for r in rows if r["key"] == sh["largest"])
    fixed = ("  Held on the engine's side in every coalition: " + ", ".join(sh["fixed"]) + "."
             if sh.get("fixed") else "")
    lines = [title, "",
             f"Largest term: **[{top['effect']}] {top['label']}**, {100 * top['share']:.1f} % "
             f"± {100 * top['share_noise']:.1f} % of the squared error.", "",
             f"Each effect's share is its Shapley value in the game 'squared error of the image with these "
             f"effects switched to the engine's side', over all {sh['coalitions']} coalitions of the "
             f"{len(rows)} effects, divided by the total: the shares sum to 100 % "
             f"({100 * sh['share_sum']:.6f} %) and no order of the effects is privileged. "
             f"*Noise*: block bootstrap ({sh['block']}×{sh['block']}-pixel blocks, "
             f"{sh['resamples']} resamples)"
             + ("; *seeds*: |share(seed a) − share(seed b)|/√2 from a second render." if "share_noise_seeds"
                in rows[0] else ".") + fixed, "",
             "| effect | Shapley share of E² | noise (bootstrap) | noise (seeds) |", "|---|---|---|---|"]
    for r in rows:
        ns = f"±{100 * r['share_noise_seeds']:.2g} %" if "share_noise_seeds" in r else "—"
        lines.append(f"| [{r['effect']}] {r['label']} | {100 * r['share']:+.1f} % | "
                     f"±{100 * r['share_noise']:.2g} % | {ns} |")
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------
# The same Shapley budget for every model
# ------------------------------------------------------------------------------------------

#: Effects that are Unreal's own settings (the chain's steps 7 and 8); another model has none.
UNREAL_ONLY = ("start_distance", "opacity_cutoff")


def _evaluate(model, truth: Truth, precision: str, sky_distance: float):
    r = model.evaluate(truth.camera, truth.world_positions(sky_distance), precision)
    shape = (*truth.shape, 3)
    return (np.broadcast_to(np.asarray(r.transmittance, np.float64), shape),
            np.broadcast_to(np.asarray(r.inscatter, np.float64), shape))


def model_engine(model, lobe_model=None):
    """The engine side of the Shapley game for any fog model instance (the signature of
    :func:`unreal_engine`): ``engine(truth, config, sky_distance) -> (T, L_sun, L_sky)``.

    ``config["refit"]``: ``model`` (else ``lobe_model``, the model fitted to the unattenuated
    target; without one, ``model`` in both); ``config["float32"]``: the shader's arithmetic, else
    float64; the Unreal-only settings (:data:`UNREAL_ONLY`) do not apply and are ignored.
    ``L_sun``: the model's inscatter minus the same model with its sun lobe off
    (:attr:`fogref.mapping.free.FitSpec.sun_off`; a model without a sun: 0).
    """
    from fogref.mapping.free import fit_spec

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


def applicable_effects(model, lobe_model=None) -> tuple[str, ...]:
    """The effects of :data:`EFFECTS` that apply to ``model``: all of them for Unreal; without
    Unreal's start distances and opacity/cutoff for the others; without "refit" when there is
    no separate ``lobe_model``."""
    name = getattr(model, "name", None)
    out = [k for k in EFFECTS if name == "ue4" or k not in UNREAL_ONLY]
    if lobe_model is None:
        out.remove("refit")
    return tuple(out)


def run_budget(truth: Truth, sky_single: np.ndarray, pf, model, lobe_model=None, valid=None,
               sky_distance: float = 1.0e5, resamples: int = BOOTSTRAP_RESAMPLES, seed: int = 0) -> dict:
    """The Shapley budget of any model (an instance, or a name built by
    :func:`fogref.mapping.from_physical` of ``pf``) against a truth.

    Unreal with a ``lobe_model`` uses :func:`unreal_engine`; every other model
    :func:`model_engine`, over :func:`applicable_effects`.  ``sky_single``: the sun-less
    render's ``single``; ``valid``: pixels (default ``truth.surface_valid``).  Returns
    :func:`shapley_budget`'s dict with ``"model"`` added.
    """
    if isinstance(model, str):
        from fogref.mapping.registry import from_physical

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
    out = shapley_budget(parts, valid, applicable_effects(model, lobe_model), resamples=resamples, seed=seed)
    out["model"] = name
    return out
