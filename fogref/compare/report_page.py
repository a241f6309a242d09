"""The page of a ``compare`` report: ``index.md`` (metadata, warnings, the check's verdict table,
the metric table, figures) and the one-line warnings of a report.

A region without pixels is shown as "no pixels", never as a pass; a metric that is null where
the region has pixels is warned about (it never happens silently).
"""

from __future__ import annotations

import json
from pathlib import Path

from fogref.compare.report_parts import REGIONS
from fogref.models.terms import describe

ERRORS_EXR_LAYOUT = """\
<part>.reference.R,G,B   the reference part
<part>.model.R,G,B       the model part
<part>.error.R,G,B       model - reference (signed)
<part>.signed_error      mean over RGB of model - reference (> 0: model too bright)
<part>.noise             mean over RGB of the standard error of model - reference (truth noise)
<part>.valid             1 where the part is compared, 0 where excluded (error channels 0 there)
<part>.abs_error         mean over RGB of |model - reference|
<part>.rel_sq_error      mean over RGB of (model - reference)^2 / (reference^2 + eps)
<part>.deltaE2000        CIEDE2000 after exposure normalisation (not without perceptual metrics)
<part>.flip              HDR-FLIP (not without perceptual metrics)
distance                 distance to the surface [m] (0 for sky)
hit                      1 for surface pixels, 0 for sky
sun_angle                angle between view ray and sun [deg] (only with a sun)"""


def _fmt(v) -> str:
    if v is None:
        return "—"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int):
        return str(v)
    return f"{v:.4g}"


def _pm(s: dict, key: str) -> str:
    v = s.get(key)
    if v is None:
        return "—"
    e = s.get(f"{key}_stderr")
    return _fmt(v) if e is None else f"{_fmt(v)} ± {e:.2g}"


def _with_floor(s: dict, key: str) -> str:
    v = s.get(key)
    f = s.get(f"{key}_noise_floor")
    return _fmt(v) if f is None else f"{_fmt(v)} ({f:.2g})"


def _verdict(s: dict) -> str:
    if not s.get("pixels"):
        return "no pixels"
    if s.get("rmse") is None:
        return "—"
    if s.get("rmse_below_noise"):
        return "**below the noise**"
    bias = (
        "" if s.get("mean_error_below_noise") else (" (too bright)" if s["mean_error"] > 0 else " (too dark)")
    )
    return "above the noise" + bias


#: Metrics of a region with pixels that must not be null without a warning.
NULL_WATCHED = ("rmse", "relmse", "mean_error", "mean_abs_error")


def warnings_of(report: dict) -> list[str]:
    """Loud one-line warnings of a report: model non-finite values, metrics that could not be
    computed over a region that has pixels, excluded pixels."""
    out = []
    for part, m in report["metrics"].items():
        s = m["all"]
        if s.get("model_nonfinite_pixels"):
            out.append(
                f"{part}: the model returned non-finite values at {s['model_nonfinite_pixels']} pixel(s); "
                "they are excluded from every metric"
            )
    for part, m in report["metrics"].items():
        for region, s in m.items():
            nulls = [k for k in NULL_WATCHED if s.get("pixels") and s.get(k) is None]
            if nulls:
                out.append(
                    f"{part}/{region}: {', '.join(nulls)} could not be computed over {s['pixels']} "
                    "pixel(s) (a value beyond float64's range); shown as —"
                )
    composited = [
        p
        for p in ("final", "composite", "attenuated_surface")
        if p in report["metrics"] and report["composited"].get(p)
    ]
    if composited:
        s = report["metrics"][composited[0]]["all"]
        ex = s.get("excluded_pixels", 0) - s.get("model_nonfinite_pixels", 0)
        if ex > 0:
            out.append(
                f"{', '.join(composited)}: {ex} pixel(s) excluded where the truth's unattenuated surface "
                "radiance is undefined (surface_coverage = 0: no sample reached the surface)"
            )
    return out


def check_table_markdown(result) -> list[str]:
    """The rows of a :class:`~fogref.compare.check.CheckResult` as a markdown table (lines)."""
    lines = [
        "| part | region | metric | estimate | interval | tolerance | verdict | pixels |",
        "|---|---|---|---:|---|---:|---|---:|",
    ]
    for r in result.rows:
        tol = "" if r.tolerance is None else f"{r.tolerance:g}"
        est, ci = ("—", "—") if r.estimate is None else (f"{r.estimate:.4g}", f"[{r.low:.4g}, {r.high:.4g}]")
        verdict = "no pixels" if r.verdict == "empty" else r.verdict
        if r.pixels == 0 and r.verdict == "fail":
            verdict = "fail (no pixels)"
        lines.append(
            f"| {r.part} | {r.region} | {r.metric} | {est} | {ci} | {tol} | {verdict} | {r.pixels} |"
        )
    return lines


def _candidate_lines(report: dict) -> list[str]:
    if "model" in report:
        name, params = report["model"]["name"], report["model"]["parameters"]
        shown = (
            "; ".join(f"`{k}` {describe(name, k, v)}" for k, v in params.items())
            if isinstance(params, dict)
            else f"`{json.dumps(params)}`"
        )
        return [
            f"- model: `{name}`, precision `{report['precision']}`, parameters: {shown}",
            f"- sky pixels fogged at {report['sky_distance_m']:.6g} m; composited over the truth's "
            "`surface.*`",
        ]
    im = report["images"]
    lines = [
        "- engine images: "
        + ", ".join(f"{k} `{v}` ({im['encodings'].get(k, '?')})" for k, v in im["sources"].items()),
        f"- exposure {im['exposure']:g} (radiance images divided by it); encoding option "
        f"`{im['encoding_option']}` (auto: PNG is sRGB, EXR/HDR linear; transmittance always linear)",
    ]
    if "final" in report["metrics"]:
        lines.append(
            "- `final` is the engine's own picture against the truth's `R,G,B`: it means something only "
            "if the engine's surface lighting matches the truth's `surface` part; "
            + (
                "`composite` (the engine's fog over the truth's surface) is the fair comparison"
                if "composite" in report["metrics"]
                else "give the engine's transmittance and inscatter for the fair comparison (`composite`)"
            )
        )
    engine = report.get("engine")
    if engine:
        lines.append(
            f"- rendered by {engine['engine']} {engine['version']} in {engine['browser']} "
            f"({engine['webgl_renderer']}), fog settings `{json.dumps(engine['fog_settings'])}`"
        )
        lines += [f"- {line}" for line in engine.get("summary", [])]
    return lines


def index_markdown(report: dict, has_sun: bool, figures: bool, check=None) -> str:
    c = report["conventions"]
    t = report["truth"]
    names = list(report["metrics"])
    overrides = " ".join(f"--set {k}={v}" for k, v in (t["overrides"] or {}).items())
    lines = [
        f"# fogref compare: `{report['candidate']['name']}` vs `{Path(report['exr']).name}`",
        "",
        (
            f"- ground truth: `{report['exr']}` ({report['image']['width']}×{report['image']['height']} px, "
            f"{report['image']['surface_pixels']} surface, {report['image']['sky_pixels']} sky), scene "
            f"`{t['scene']}`{f' `{overrides}`' if overrides else ''}, {t['spp']} spp, seed {t['seed']}, "
            f"pixel filter `{t['pixel_filter']}`"
            + (
                ""
                if t["pixel_exact"]
                else " (anti-aliased: silhouette pixels mix depths, which exact models cannot match)"
            )
        ),
        *_candidate_lines(report),
        (
            f"- pixels excluded from the composited parts (surface undefined): "
            f"{report['diagnostics']['surface_undefined_pixels']}"
        ),
        (
            f"- reference identity |R,G,B − (attenuated_surface + inscatter)| max: "
            f"{_fmt(report['diagnostics']['reference_identity_max_abs'])}"
        ),
        "",
    ]
    for w in report["warnings"]:
        lines.append(f"> **Warning:** {w}")
    if report["warnings"]:
        lines.append("")
    if check is not None:
        lines += [
            "## Verdict",
            "",
            f"**{check.verdict}** ({check.confidence:.0%} two-sided intervals, {check.method_text}; "
            "`fogref.compare.check.check`, the checker of `assert_fog_matches`). A row passes when its "
            "whole interval lies within the tolerance (|x| for the signed metrics), fails when it lies "
            "wholly outside, else is inconclusive.",
            "",
            *check_table_markdown(check),
            "",
        ]
    lines += [
        "## Metrics",
        "",
        (
            "RMSE and |error| are in each part's units (radiance: the scene's radiance units; "
            "transmittance: 1). relMSE = mean((x−r)²/(r²+ε)), "
            f"ε = {c['relmse_eps']}. Mean error = mean(candidate − truth): > 0 too bright, < 0 too dark. "
            + (
                "ΔE2000: linear sRGB ÷ white → XYZ → CIELAB (D65); "
                "white = 99th percentile of the reference part's luminance (transmittance: 1). "
                f"FLIP: HDR-FLIP at {c['flip_ppd']} px/degree."
                if c.get("perceptual", True)
                else "ΔE2000 and FLIP: not computed (the comparison left out its perceptual metrics)."
            )
        ),
        "",
        (
            f"**Noise.** `± x`: one standard error of the estimate, from the truth's per-pixel `stderr.*` "
            f"channels. *Noise floor*: what a perfect candidate would score against this truth (RMSE: "
            f"√mean(σ²); ΔE/FLIP: a perfect candidate plus one draw of the noise). *Below the noise*: within "
            f"{c['noise_z']:g} standard errors of the noise floor, so this truth cannot tell the candidate "
            "from "
            "a perfect one; render more samples to see further. These columns describe; the verdict is the "
            "check's (above)."
        ),
        "",
        "| part | region | pixels | excluded | RMSE | RMSE noise floor | relMSE (floor) | mean error | "
        "mean \\|err\\| (floor) | ΔE2000 mean (floor) | ΔE2000 p95 | FLIP mean (floor) | noise verdict |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for part in names:
        for region in REGIONS:
            s = report["metrics"][part][region]
            lines.append(
                f"| {part} | {region} | {s['pixels']} | {s.get('excluded_pixels', 0)} | {_pm(s, 'rmse')} | "
                f"{_fmt(s.get('rmse_noise_floor'))} | {_with_floor(s, 'relmse')} | {_pm(s, 'mean_error')} | "
                f"{_with_floor(s, 'mean_abs_error')} | {_with_floor(s, 'delta_e2000_mean')} | "
                f"{_fmt(s.get('delta_e2000_p95'))} | {_with_floor(s, 'flip_mean')} | {_verdict(s)} |"
            )
    lines += [
        "",
        (
            "FLIP is a spatial metric: near the horizon its filters spread errors across regions, "
            "so a region without any pixel error can still show a small FLIP mean."
        ),
        "",
    ]
    if figures:
        lines += [
            "## Truth | candidate | |error|",
            "",
            f"Shared tone map per part: {c['tone_map']}",
            "",
            "Heatmaps: the signed error (candidate − truth, mean over RGB) on a diverging map centred at 0 "
            "with symmetric limits (red: too bright, blue: too dark), then |error|, relative "
            + ("squared error, ΔE2000 and FLIP. " if c.get("perceptual", True) else "squared error. ")
            + "Grey: excluded pixels.",
            "",
        ]
        for part in names:
            lines += [
                f"### {part}",
                "",
                f"![{part} side by side](side_by_side/{part}.png)",
                "",
                f"![{part} error heatmaps](heatmaps/{part}.png)",
                "",
            ]
        lines += ["## Error vs distance", "", "![error vs distance](error_vs_distance.png)", ""]
        lines += ["## Error vs angle to the sun", ""]
        lines += ["![error vs sun angle](error_vs_sun_angle.png)" if has_sun else "The scene has no sun.", ""]
    else:
        lines += [
            "Figures were not written (`figures=False`); the binned curves are in `metrics.json`.",
            "" if has_sun else "The scene has no sun.",
            "",
        ]
    lines += [
        "## Files",
        "",
        "- `metrics.json`: everything above, plus the binned curves"
        + (" and the check's rows (`check`)" if check is not None else ""),
        *(["- `check.json`: the check's rows, intervals and verdict"] if check is not None else []),
        "- `errors.exr`:",
        "",
        "```",
        ERRORS_EXR_LAYOUT,
        "```",
        "",
    ]
    return "\n".join(lines)
