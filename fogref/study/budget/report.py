"""The budget's report: its Markdown tables (``budget.md``) and its figure (``budget.png``).

:func:`markdown` writes the Shapley table (:func:`shapley_markdown`), the telescoping chain
and the checks beside it, and the "port vs engine" line (:func:`port_vs_engine_line`);
:func:`plot` draws the shares and the chain's steps (matplotlib, imported when called).
"""

from __future__ import annotations

import numpy as np

from fogref.atomic import save_figure_atomic as save_figure
from fogref.compare.plots import agg_figure
from fogref.engines import ENGINES
from fogref.study.budget.effects import RENDERED


def port_vs_engine_line(model: str, measured: dict | None = None) -> str:
    """The budget's "port vs engine" line for the fogref model ``model``: how far fogref's port is
    from the real engine (:func:`fogref.engines.port.port_vs_engine`'s dict, ``measured``, as
    ``fogref compare TRUTH --engine NAME`` writes it in ``engine.json``), in the budget's units
    (radiance, linear RGB, RMSE over the engine's surface pixels).  It should be at the
    quantisation level (float32, 8 bits); the line says so, or that it is not.  A model with no
    engine that runs here (Unreal, Godot, Bevy, Unity, HDRP) gets "no runnable engine here".

    >>> port_vs_engine_line("ue4")
    'Port vs engine (ue4): no runnable engine here.'
    >>> port_vs_engine_line("filament")
    'Port vs engine (filament): not measured (`fogref compare TRUTH --engine filament` measures it).'
    >>> port_vs_engine_line("filament", {"linear_rms": 2.5e-8, "linear_max": 8.3e-8, "canvas_max": 0,
    ...                                  "at_quantisation": True})[27:]
    'RMSE 2.5e-08 (max 8.3e-08) radiance, canvas max 0 code values: at the quantisation level, as expected.'
    """
    head = f"Port vs engine ({model}): "
    if model not in ENGINES:
        return head + "no runnable engine here."
    if measured is None:
        return head + f"not measured (`fogref compare TRUTH --engine {model}` measures it)."
    verdict = (
        "at the quantisation level, as expected"
        if measured["at_quantisation"]
        else "ABOVE the quantisation level, where it should be at it"
    )
    return (
        head + f"RMSE {measured['linear_rms']:.2g} (max {measured['linear_max']:.2g}) radiance, "
        f"canvas max {measured['canvas_max']} code values: {verdict}."
    )


def _floor(s: dict) -> str:
    if "rmse_noise_floor" not in s:
        return "—"
    return f"{s['rmse_noise_floor']:.2g}" + (" (below the noise)" if s["below_noise"] else "")


def validation_paragraphs(result: dict) -> list[str]:
    """How the budget's 'shadows' step was checked (the pixel footprint, the closed form on an open
    plane), one paragraph each (Markdown: code in backticks); empty when the result has neither."""
    out = []
    fc = result.get("footprint")
    if fc:
        out.append(
            f"Pixel footprint: {100 * fc['pixel_fraction']:.2g} % of the pixels straddle an edge "
            "(their "
            f"closed-form T differs from the EXR's by more than {fc['tolerance']}); they hold "
            f"{100 * fc['share_of_step_sq']:.2g} % of the squared '{fc['step']}' step, so that step is "
            "not an artefact of per-pixel (G-buffer) evaluation."
        )
    oc = result.get("open_plane_check")
    if oc:
        out.append(
            f"Closed-form check on `{oc['scene']}` (no occluders, {oc['resolution'][0]}×"
            f"{oc['resolution'][1]}, {oc['spp']} spp): the 'shadows' step there is RMSE "
            f"{oc['shadows_rmse']:.3g} against an expected pure-noise level of {oc['noise_rmse']:.3g} "
            f"(mean {oc['shadows_mean']:+.2g} vs single-scattering RMS {oc['single_rms']:.3g}): "
            "the closed-form sun "
            "single scattering matches the path tracer where nothing casts shadows."
        )
    return out


def markdown(result: dict, title: str = "Error budget of Unreal's exponential height fog") -> str:
    """The budget table as Markdown."""
    t = result["total"]
    lines = [
        f"# {title}",
        "",
        f"Total error of the Unreal model (float32, as compared) against the path-traced truth: "
        f"**RMSE {t['rmse']['all']:.4g}** (surface pixels {t['rmse']['surface']:.4g}, "
        f"sky {t['rmse']['sky']:.4g}; truth RMS {t['truth_rms']:.4g}; Monte Carlo noise of the total "
        f"±{t.get('noise_rmse', float('nan')):.2g}"
        + (
            f"; noise floor {t['rmse_noise_floor']:.2g} from the truth's stderr, "
            f"{'**below the noise**' if t['below_noise'] else 'above the noise'}"
            if "rmse_noise_floor" in t
            else ""
        )
        + ").",
        "",
    ]
    if result.get("shapley"):
        lines += [shapley_markdown(result["shapley"]), "", port_vs_engine_line("ue4"), ""]
        if result.get("shapley_colours_in_lobe"):
            lines += [
                shapley_markdown(
                    result["shapley_colours_in_lobe"], "### Variant: the colour re-fit folded into the lobe"
                ),
                "",
            ]
        lines += ["## Telescoping chain (second view)", ""]
    lines += [
        f"Pixels: {result.get('pixels', '?')} used, {result.get('excluded_pixels', 0)} excluded "
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
        "with another seed (closed-form steps are noise-free).",
        "",
        "*Denoised*: √(RMSE² − noise²), the step's size without the Monte Carlo noise.",
        "",
        "*Noise floor*: the RMSE Δ_k would have from the truths' per-pixel standard errors alone "
        "(`stderr.*` channels); *below the noise*: Δ_k cannot be told from 0 at this sample count.",
        "",
        "| k | effect | step | RMSE of Δ_k | denoised | (surface / sky) | share of E² | "
        "noise: pixel RMS / share | noise floor (stderr) | RMSE vs truth after step |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for k, s in enumerate(result["steps"], 1):
        n = s.get("noise")
        rendered = n and s["key"] in RENDERED
        ns = f"{n['pixel_rms']:.2g} / ±{100 * n['share']:.2g} %" if rendered else "0 (closed form)"
        dn = f"{n['rmse_denoised']:.4g}" if n and s["key"] in RENDERED else f"{s['rmse']['all']:.4g}"
        lines.append(
            f"| {k} | [{s['effect']}] | {s['label']} | {s['rmse']['all']:.4g} | {dn} | "
            f"{s['rmse']['surface']:.3g} / {s['rmse']['sky']:.3g} | {100 * s['share']:+.1f} % | "
            f"{ns} | "
            f"{_floor(s)} | {s['rmse_vs_truth_after']:.4g} |"
        )
    by = {s["key"]: s for s in result["steps"]}
    off = [k for k in ("start_distance", "opacity_cutoff") if by.get(k) and by[k]["rmse"]["all"] == 0]
    if off:
        lines += [
            "",
            "Steps " + " and ".join(f"[{by[k]['effect']}]" for k in off) + " are exactly 0 "
            "because the model under study has those settings off (the fitted "
            "DirectionalInscatteringStartDistance is "
            "0; StartDistance 0, FogMaxOpacity 1 and FogCutoffDistance 0 are the editor defaults); the "
            "*What if* table below measures them switched on.",
        ]
    for text in validation_paragraphs(result):
        lines += ["", text]
    if result.get("what_if"):
        lines += [
            "",
            "## What if (engine settings the study leaves at their defaults)",
            "",
            "RMSE of the float32 model against the truth with one setting changed:",
            "",
            "| variant | fields | RMSE | Δ RMSE | noise floor |",
            "|---|---|---|---|---|",
        ]
        for r in result["what_if"]:
            lines.append(
                f"| {r['variant']} | `{r['fields']}` | {r['rmse']:.4g} | {r['delta_rmse']:+.3g} | "
                f"{_floor(r)} |"
            )
    lines += ["", "![budget](budget.png)", ""]
    return "\n".join(lines)


def shapley_markdown(sh: dict, title: str = "## Shapley budget (order-independent)") -> str:
    """The Shapley table as Markdown (largest share first)."""
    rows = sorted(sh["effects"], key=lambda r: -r["share"])
    top = next(r for r in rows if r["key"] == sh["largest"])
    fixed = (
        "  Held on the engine's side in every coalition: " + ", ".join(sh["fixed"]) + "."
        if sh.get("fixed")
        else ""
    )
    lines = [
        title,
        "",
        f"Largest term: **[{top['effect']}] {top['label']}**, {100 * top['share']:.1f} % "
        f"± {100 * top['share_noise']:.1f} % of the squared error.",
        "",
        f"Each effect's share is its Shapley value in the game 'squared error of the image with these "
        f"effects switched to the engine's side', over all {sh['coalitions']} coalitions of the "
        f"{len(rows)} effects, divided by the total: the shares sum to 100 % "
        f"({100 * sh['share_sum']:.6f} %) and no order of the effects is privileged. "
        f"*Noise*: block bootstrap ({sh['block']}×{sh['block']}-pixel blocks, "
        f"{sh['resamples']} resamples)"
        + (
            "; *seeds*: |share(seed a) − share(seed b)|/√2 from a second render."
            if "share_noise_seeds" in rows[0]
            else "."
        )
        + fixed,
        "",
        "| effect | Shapley share of E² | noise (bootstrap) | noise (seeds) |",
        "|---|---|---|---|",
    ]
    for r in rows:
        ns = f"±{100 * r['share_noise_seeds']:.2g} %" if "share_noise_seeds" in r else "—"
        lines.append(
            f"| [{r['effect']}] {r['label']} | {100 * r['share']:+.1f} % | "
            f"±{100 * r['share_noise']:.2g} % | {ns} |"
        )
    if sh.get("port_vs_engine"):
        lines += ["", sh["port_vs_engine"]]
    return "\n".join(lines)


def _bar_labels(ax, y, values, errors) -> None:
    """Label horizontal bars with their value in % beyond the end of the bar and its error bar,
    widening the axis so that every label lies inside it (none over the tick labels or another
    axis); a share that rounds to 0.0 % is written "0 %"."""
    values, errors = np.asarray(values, dtype=float), np.asarray(errors, dtype=float)
    lo, hi = min(0.0, float((values - errors).min())), max(0.0, float((values + errors).max()))
    pad = 0.2 * (hi - lo or 1.0)  # room for a label of about 7 characters at this width
    ax.set_xlim(lo - (pad if (values < 0).any() else 0.05 * pad), hi + pad)
    for yy, v, e in zip(y, values, errors):
        right = v >= 0 or abs(v) < 0.05
        ax.annotate(
            "0 %" if abs(v) < 0.05 else f"{v:+.1f} %",
            (v + e if right else v - e, yy),
            xytext=(3 if right else -3, 0),
            textcoords="offset points",
            va="center",
            ha="left" if right else "right",
            fontsize=8,
        )


def plot(result: dict, path) -> None:
    """``budget.png``: :func:`budget_figure` of ``result``."""
    save_figure(budget_figure(result), path)


def budget_figure(result: dict):
    """Bar charts: the Shapley shares first (with their noise, when ``result["shapley"]``), then
    each chain step's RMSE (with noise bars) and its chain share of the total; each share labelled
    beside its bar, inside its axis.  A figure on its own Agg canvas (:func:`agg_figure`: no pyplot,
    no backend changed)."""
    steps = result["steps"]
    labels = [f"[{s['effect']}] {s['label']}" for s in steps]
    rm = [s["rmse"]["all"] for s in steps]
    err = [s["noise"]["pixel_rms"] if s.get("noise") and s["key"] in RENDERED else 0.0 for s in steps]
    share = [100 * s["share"] for s in steps]
    y = np.arange(len(steps))[::-1]
    sh = result.get("shapley")
    if sh:
        by = {r["key"]: r for r in sh["effects"]}
        fig = agg_figure(20, 4.6)
        ax3 = fig.subplots(1, 3, sharey=True)
        a0, ax = ax3[0], ax3[1:]
        sv = [100 * by[s["key"]]["share"] if s["key"] in by else 0.0 for s in steps]
        se = [100 * by[s["key"]]["share_noise"] if s["key"] in by else 0.0 for s in steps]
        a0.barh(y, sv, xerr=se, capsize=3, color=["#c0504d" if v > 0 else "#9bbb59" for v in sv])
        a0.axvline(0, color="k", lw=0.8)
        a0.set_yticks(y, labels)
        a0.set_xlabel(
            "Shapley share of the squared error [%]\nall coalitions, order-free; bars: bootstrap noise"
        )
        _bar_labels(a0, y, sv, se)
        a0.grid(axis="x", alpha=0.3)
    else:
        fig = agg_figure(14, 4.6)
        ax = fig.subplots(1, 2, sharey=True)
    ax[0].barh(y, rm, xerr=err, color="#4a78b0", capsize=3)
    ax[0].axvline(result["total"]["rmse"]["all"], color="k", ls="--", lw=1, label="total model − truth")
    ax[0].set_yticks(y, labels)
    ax[0].set_xlabel("RMSE of Δ_k (radiance)\nerror bars: Monte Carlo noise per pixel")
    ax[0].legend(loc="lower right", fontsize=8)
    ax[1].barh(y, share, color=["#c0504d" if v > 0 else "#9bbb59" for v in share])
    ax[1].axvline(0, color="k", lw=0.8)
    ax[1].set_xlabel("chain share of the total squared error [%]\n⟨Δ_k, E⟩/⟨E, E⟩, sums to 100")
    _bar_labels(ax[1], y, share, [0.0] * len(share))
    for a in ax:
        a.grid(axis="x", alpha=0.3)
    fig.suptitle(
        f"Unreal exponential height fog: error budget (total RMSE {result['total']['rmse']['all']:.4g})"
    )
    fig.tight_layout()
    return fig
