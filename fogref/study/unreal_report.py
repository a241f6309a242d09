"""The README of ``fogref study``'s report folder (:func:`readme`: the fit, the comparison and the
error budget, from the data) and the commands that rebuild the study (:func:`reproduce_command`)."""

from __future__ import annotations

from pathlib import Path

from fogref.models.terms import note, unreal_field

__all__ = ["readme", "reproduce_command"]


def reproduce_command(provenance: dict) -> str:
    """The shell commands that rebuild the truth and the study, from the truth's own header.

    Examples
    --------
    >>> reproduce_command({"scene": "scenes/lake.xml", "spp": 32, "seed": 1, "overrides": {"res": 64},
    ...                    "truth": "out/lake.exr", "pixel_filter": "centre"})
    'fogref render scenes/lake.xml --spp 32 --seed 1 --set res=64 --out out/lake.exr && fogref study ...'
    """
    sets = "".join(f" --set {k}={v}" for k, v in (provenance.get("overrides") or {}).items())
    return (
        f"fogref render {provenance['scene']} --spp {provenance['spp']} "
        f"--seed {provenance['seed']}{sets} "
        f"--out {provenance['truth']} && fogref study {provenance['truth']}"
    )


def readme(summary: dict, res: dict) -> str:
    """``<out>/README.md`` of the study: ``summary`` (``summary.json``'s dict: provenance, fit,
    comparison) and ``res`` (``budget.json``'s dict: the total, the telescoping steps, the Shapley
    budget and the checks) as Markdown, every number from the data."""
    fit = summary["fit"]
    ed = fit["unreal_editor"]
    t = res["total"]
    steps = sorted(res["steps"], key=lambda s: -s["share"])

    def col(c):
        return "(" + ", ".join(f"{x:.3g}" for x in c) + ")"

    prov = summary.get("provenance") or res["inputs"]
    name = Path(prov["scene"]).stem
    ov = prov.get("overrides") or {}
    lines = [
        "# Unreal Exponential Height Fog vs path-traced truth",
        "",
        f"Scene `{prov['scene']}`"
        + (f" with {', '.join(f'`{k}={v}`' for k, v in ov.items())}" if ov else "")
        + f", ground truth `{summary['exr']}` ({res['inputs']['resolution'][0]}×"
        f"{res['inputs']['resolution'][1]}, {prov['spp']} spp, seed {prov['seed']}, pixel filter "
        f"`{prov.get('pixel_filter')}`). Reproduce with `{reproduce_command(prov)}`.",
        "",
        "## Unreal settings used (derived from the physical fog)",
        "",
        "| property | value | unit or colour space |",
        "|---|---|---|",
    ]
    for k, v in ed.items():
        unit = note("ue4", unreal_field(k), v) or "1"
        lines.append(f"| {k} | {col(v) if isinstance(v, list) else f'{v:.6g}'} | {unit} |")
    lines += [
        "",
        "Density, falloff and height: exact mapping (`fogref.mapping.base_params`).  Colours, exponent and "
        "directional start distance: `fogref fit` (least squares against the closed-form sun + sky "
        f"single scattering with sun attenuation over {fit['error']['n_views']} views from the camera; "
        f"relative RMSE of the fit on those views {fit['error']['rel_rmse']:.3f}).  Sun luminance 1 "
        "(the colour carries it).",
        "",
        "## Headline",
        "",
    ]
    c = summary.get("compare")
    lines.append(
        f"- **Final image RMSE of Unreal (float32) vs truth: {t['rmse']['all']:.4g}** "
        f"(surface pixels {t['rmse']['surface']:.4g}, sky {t['rmse']['sky']:.4g}; "
        f"truth RMS {t['truth_rms']:.4g}, i.e. {100 * t['rmse']['all'] / t['truth_rms']:.1f} % "
        "relative; "
        f"Monte Carlo noise of this number ±{t.get('noise_rmse', 0):.1g}"
        + (
            f"; noise floor {t['rmse_noise_floor']:.2g}, "
            f"{'below the noise' if t['below_noise'] else 'above the noise'}"
            if "rmse_noise_floor" in t
            else ""
        )
        + ")."
    )
    if c:
        f = c["final"]
        lines.append(
            f"- fogref.compare (final image): relMSE {f.get('relmse', float('nan')):.4g}, "
            f"mean ΔE2000 {f.get('delta_e2000_mean', float('nan')):.3g}, "
            f"mean FLIP {f.get('flip_mean', float('nan')):.3g}; inscatter RMSE "
            f"{c['inscatter'].get('rmse', float('nan')):.4g}; transmittance RMSE "
            f"{c['transmittance'].get('rmse', float('nan')):.3g}.  "
            "Full report: [compare/index.md](compare/index.md)."
        )
    fc = res.get("footprint")
    oc = res.get("open_plane_check")
    top = steps[0]
    sh = res.get("shapley")
    if sh:
        rows = sorted(sh["effects"], key=lambda r: -r["share"])
        st = rows[0]
        lines.append(
            f"- Largest Shapley term: **[{st['effect']}] {st['label']}**, {100 * st['share']:.1f} % "
            f"± {100 * st['share_noise']:.1f} % of the squared error (order-independent: "
            f"its Shapley value over all {sh['coalitions']} coalitions of the effects)."
        )
        lines.append(
            "- Shapley budget, by share of the squared error: "
            + "; ".join(f"[{r['effect']}] {r['label']} {100 * r['share']:+.1f} %" for r in rows)
            + "."
        )
    lines.append(
        f"- Largest term of the telescoping chain (second view, depends on the chain's order): "
        f"**[{top['effect']}] {top['label']}**, {100 * top['share']:.1f} % of the "
        f"squared error (step RMSE {top['rmse']['all']:.4g})."
    )
    lines.append(
        "- Chain, by share of the squared error: "
        + "; ".join(f"[{s['effect']}] {s['label']} {100 * s['share']:+.1f} %" for s in steps)
        + "."
    )
    shadows = next((s for s in res["steps"] if s["key"] == "shadows"), None)
    if oc and shadows:
        here = (
            f"on `{name}` the same step is below the noise (RMSE {shadows['rmse']['all']:.3g}, "
            f"noise floor {shadows['rmse_noise_floor']:.3g}): nothing here casts a measurable shadow "
            "into the fog"
            if shadows.get("below_noise")
            else f"on `{name}` it is RMSE {shadows['rmse']['all']:.3g}"
            + (
                f" against a noise floor of {shadows['rmse_noise_floor']:.3g}"
                if "rmse_noise_floor" in shadows
                else ""
            )
            + ": geometric shadows (light shafts) that the engine does not model"
        )
        lines.append(
            f"- Check: on `{oc['scene']}` (no occluders) the shadow step is pure noise (RMSE "
            f"{oc['shadows_rmse']:.3g} vs noise {oc['noise_rmse']:.3g}), so the closed-form single "
            f"scattering agrees with the path tracer; {here}"
            + (
                f" (edge pixels: {100 * fc['pixel_fraction']:.1f} % of pixels, "
                f"{100 * fc['share_of_step_sq']:.1f} % of that step)."
                if fc
                else "."
            )
        )
    if res.get("excluded_pixels"):
        lines.append(
            f"- {res['excluded_pixels']} pixel(s) are excluded from the budget and the comparison's "
            "composited parts: the truth's unattenuated surface radiance is undefined there "
            "(no sample reached the surface through the fog)."
        )
    lines += [
        "",
        "See [budget.md](budget.md) for the table (RMSE, share and noise of each step), "
        "[budget.png](budget.png), [budget.json](budget.json), [fit.json](fit.json).",
        "",
        "## Reading the budget",
        "",
        "The Shapley shares do not depend on any order: each effect's share is its average "
        "contribution to the squared error over every order in which the effects could be switched "
        "from the truth to the engine (all coalitions, closed forms and renders cached).  "
        "The chain below is the second view.  "
        "The steps telescope exactly: truth → no multiple scattering → closed-form sun without "
        "shadows → closed-form sky without ground occlusion/attenuation → no sun attenuation → "
        "Unreal's cosine lobe (colours fitted without attenuation) → colours re-fitted with "
        "attenuation → start distances → max opacity/cutoff → float32.  The shares sum to 100 %; "
        "negative shares are compensations (the re-fit absorbs part of the sun attenuation on average; "
        "removing multiple scattering removes light Unreal also lacks, etc.).  The RMSE column gives "
        "each step's own size; steps 1–3 use renders and carry Monte Carlo noise (given per row) — "
        "compare a term with its noise before reading it.",
        "",
    ]
    return "\n".join(lines)
