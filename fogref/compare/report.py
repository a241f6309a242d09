"""``compare``: measure one game fog model against one ground-truth EXR and write a report.

What is compared (each a *part*, all ``(H, W, 3)`` linear RGB), read through the one
ground-truth reader :func:`fogref.gbuffer.load_truth`:

======================  ==============================  ===============================  ==========
part                    reference (truth)               model                            pixels
======================  ==============================  ===============================  ==========
``final``               ``surface * T + inscatter``     ``surface * T_model + L_model``  valid
``transmittance``       ``T.*``                         ``T_model``                      all
``inscatter``           ``inscatter.*``                 ``L_model``                      all
``attenuated_surface``  ``attenuated_surface.*``        ``surface * T_model``            valid
======================  ==============================  ===============================  ==========

``final`` is the model *composited* as the engine does (``FogResult.composite``) on
the truth's unattenuated ``surface.*`` radiance, so that only the fog differs.  That
radiance is undefined where no sample reached the surface (``surface_coverage ==
0``, e.g. opaque fog at the horizon): those pixels are *excluded* from ``final`` and
``attenuated_surface`` and counted (``excluded_pixels``), never filled in.  Nothing
is divided by a transmittance.  A model's non-finite values are excluded the same
way and counted (``model_nonfinite_pixels``, and a warning at the top of the page).

Sky pixels (``hit == 0``): the model shades the point ``camera + view * sky_distance``
(engines fog the sky as a surface at a finite distance; the default 100 km stands in
for infinity).  Every metric is reported over all pixels and, separately, over
``surface`` (hit) and ``sky`` pixels, so the sky convention never hides the rest.

Monte Carlo noise: each part's per-pixel noise covariance of ``model - truth`` comes
from the one comparison core, :func:`fogref.compare.check.fog_parts` (the truth's
``stderr.*`` and ``corr.*`` channels, the channels' covariance used whole; ``final``
is ``surface * T_model + L_model`` against ``surface * T + L``, as ``check`` has it),
plus a rounding floor of 4 float32 ulp.  Each metric is reported with its
noise floor (what a perfect model would score), its standard error and whether it is
*below the noise* (:func:`fogref.compare.metrics.mse_noise`).

Report folder (``out_dir``)::

    index.md                   the page: pictures side by side, metric table, plots
    metrics.json               every metric per part and region, binned curves, conventions
    errors.exr                 per-pixel maps (see ERRORS_EXR_LAYOUT)
    side_by_side/<part>.png    reference | model | |error|, one shared tone map
    heatmaps/<part>.png        signed error (diverging, centred at 0), |error|, relative squared
                               error, ΔE2000, FLIP, with colour bars
    error_vs_distance.png      errors binned by log distance (surface pixels)
    error_vs_sun_angle.png     errors binned by view–sun angle (only if the scene has a sun)

Every file is written atomically; no output holds NaN or infinity.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np

from fogref.atomic import write_text_atomic
from fogref.compare import metrics as M
from fogref.compare import noise
from fogref.compare.binning import angle_edges, binned_errors, log_distance_edges
from fogref.compare.candidate import candidate_parts, evaluate_model, fog_parts
from fogref.compare.error_maps import error_maps
from fogref.compare.perceptual import FLIP_PPD
from fogref.compare.plots import plot_binned_errors, plot_error_heatmaps, plot_side_by_side
from fogref.compare.tonemap import exposure_for
from fogref.errors import FogrefError
from fogref.exrio import write_exr
from fogref.gbuffer import Truth, load_truth
from fogref.mapping.build import current_parameters
from fogref.params import number as valid_number

#: Distance [m] at which the model fogs sky pixels (a stand-in for infinity).
DEFAULT_SKY_DISTANCE = 1.0e5
PARTS: tuple[str, ...] = ("final", "transmittance", "inscatter", "attenuated_surface")
#: Units of each part's values ("1": dimensionless; radiance is in the scene's units).
PART_UNITS: dict[str, str] = {
    "final": "radiance",
    "transmittance": "1",
    "inscatter": "radiance",
    "attenuated_surface": "radiance",
    "composite": "radiance",
}
REGIONS: tuple[str, ...] = ("all", "surface", "sky")
ERRORS_EXR_LAYOUT = """\
<part>.reference.R,G,B   the reference part
<part>.model.R,G,B       the model part
<part>.error.R,G,B       model - reference (signed)
<part>.signed_error      mean over RGB of model - reference (> 0: model too bright)
<part>.noise             mean over RGB of the standard error of model - reference (truth noise)
<part>.valid             1 where the part is compared, 0 where excluded (error channels 0 there)
<part>.abs_error         mean over RGB of |model - reference|
<part>.rel_sq_error      mean over RGB of (model - reference)^2 / (reference^2 + eps)
<part>.deltaE2000        CIEDE2000 after exposure normalisation
<part>.flip              HDR-FLIP
distance                 distance to the surface [m] (0 for sky)
hit                      1 for surface pixels, 0 for sky
sun_angle                angle between view ray and sun [deg] (only with a sun)"""


# ---------------------------------------------------------------- evaluation


def _model_name(model) -> str:
    return str(getattr(model, "name", None) or type(model).__name__)


def _model_description(model) -> dict | str:
    """JSON-ready parameters of ``model`` (see :func:`~fogref.mapping.build.current_parameters`)."""
    try:
        return _json_safe(current_parameters(model))
    except (TypeError, AttributeError, ValueError, FogrefError):
        return repr(model)


def check_sky_distance(value, option: str = "sky_distance") -> float:
    """``value`` as a float if finite and > 0 [m]; ParameterError naming ``option`` otherwise
    (:func:`fogref.params.number`).

    >>> check_sky_distance(0, "sky_distance")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: compare: parameter 'sky_distance': 0 is outside (0, inf) m
    """
    return valid_number(value, option, source="compare", lo=0.0, lo_open=True, unit="m")


def evaluate_parts(truth: Truth, model, precision: str, sky_distance: float) -> dict:
    """Reference, model, noise and valid pixels of every part, from the one comparison core
    (:func:`fogref.compare.check.fog_parts`, which ``check`` uses too).

    Returns ``part -> {"reference", "model", "cov", "valid"}``: ``(H, W, 3)`` float64
    reference and model (the model as returned, non-finite values kept), the ``(H, W,
    3, 3)`` noise covariance of ``model - reference`` (the truth's noise, its channels'
    correlation, and the rounding floor), and the ``(H, W)`` bool pixels where the
    part is defined (``surface_valid`` for the composited parts, every pixel otherwise).
    """
    m = evaluate_model(truth, model, precision, sky_distance, nonfinite="keep")
    out = _from_core(fog_parts(truth, m["T"], m["inscatter"]))
    out["attenuated_surface"] = _attenuated_surface(truth, m["T"])
    return {p: out[p] for p in PARTS}


def image_parts(truth: Truth, images) -> dict:
    """Reference, engine image, noise and valid pixels of every part an engine's images give.

    ``images``: :class:`fogref.compare.foreign.EngineImages` (``final``, ``transmittance``,
    ``inscatter``, any of them None).  Parts, as :func:`evaluate_parts` returns them:
    ``final`` (the engine's own picture against ``R,G,B``: meaningful only if its
    surface lighting matches the truth's), ``transmittance``, ``inscatter``,
    ``attenuated_surface`` (``surface * T_engine``, with a transmittance) and
    ``composite`` (``surface * T_engine + inscatter_engine`` against ``R,G,B``, with both:
    the engine's fog over the truth's own surface, the fair comparison).  The engine's
    images carry no noise; the covariance is the truth's (and the rounding floor).
    """
    out = _from_core(candidate_parts(truth, images))
    if images.transmittance is not None:
        out["attenuated_surface"] = _attenuated_surface(truth, np.asarray(images.transmittance, dtype=np.float64))
    order = ("final", "transmittance", "inscatter", "attenuated_surface", "composite")
    return {p: out[p] for p in order if p in out}


def _from_core(cp) -> dict:
    """The comparison core's parts (:class:`fogref.compare.check.CandidateParts`) as a report's,
    ``T`` named ``transmittance``."""
    return {("transmittance" if k == "T" else k): {"reference": cp.reference[k], "model": cp.parts[k],
                                                   "cov": cp.noise_cov[k], "valid": cp.valid[k]}
            for k in cp.parts}


def _attenuated_surface(truth: Truth, T) -> dict:
    """``surface * T`` against the truth's ``attenuated_surface``, where ``surface`` is defined."""
    with np.errstate(invalid="ignore", over="ignore"):  # a model's inf/NaN stays non-finite: counted, excluded
        att = truth.surface * T
        cov = truth.noise_cov("attenuated_surface") + noise.scaled(truth.noise_cov("surface"), T)
    return {"reference": truth.attenuated_surface, "model": att,
            "cov": noise.add_diagonal(cov, noise.rounding_var(truth.attenuated_surface, att)),
            "valid": truth.surface_valid}


def truth_provenance(truth: Truth) -> dict:
    """What a report records about the truth it measured against: path,
    spp, seed, scene (path and SHA-256), overrides, pixel filter, variant, versions."""
    a = truth.attrs
    return {
        "path": str(truth.path), "schema": a.get("fogref.schema"), "spp": truth.spp, "seed": a.get("fogref.seed"),
        "scene": a.get("fogref.scene"), "scene_sha256": a.get("fogref.scene_sha256"),
        "overrides": a.get("fogref.overrides") or {}, "pixel_filter": a.get("fogref.pixel_filter"),
        "pixel_exact": truth.pixel_exact, "variant": a.get("fogref.variant"), "fogref_version": a.get("fogref.version"),
        "mitsuba_version": a.get("fogref.mitsuba"),
    }


# ---------------------------------------------------------------- outputs


def _json_safe(obj):
    """Numpy scalars/arrays -> Python; non-finite floats -> None (never NaN in JSON)."""
    if isinstance(obj, dict):
        return {str(k): _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_json_safe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _json_safe(obj.tolist())
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return _json_safe({f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)})
    if isinstance(obj, (np.bool_, bool)):
        return bool(obj)
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        f = float(obj)
        return f if math.isfinite(f) else None
    if obj is None or isinstance(obj, (int, str)):
        return obj
    return str(obj)


def _errors_exr_channels(truth, parts, errors, sun_angle) -> dict:
    ch: dict[str, np.ndarray] = {}
    for part in parts:
        e = errors[part]
        ref = parts[part]["reference"]
        for i, c in enumerate("RGB"):
            ch[f"{part}.reference.{c}"] = ref[..., i]
            ch[f"{part}.model.{c}"] = ref[..., i] + e.signed[..., i]  # = the model where valid
            ch[f"{part}.error.{c}"] = e.signed[..., i]
        ch[f"{part}.signed_error"] = e.signed.mean(-1)
        ch[f"{part}.noise"] = e.sigma.mean(-1)
        ch[f"{part}.valid"] = e.valid.astype(np.float32)
        ch[f"{part}.abs_error"] = e.absolute
        ch[f"{part}.rel_sq_error"] = e.relative_squared
        ch[f"{part}.deltaE2000"] = e.delta_e2000
        ch[f"{part}.flip"] = e.flip
    ch["distance"] = truth.distance
    ch["hit"] = truth.hit.astype(np.float32)
    if sun_angle is not None:
        ch["sun_angle"] = sun_angle
    # float32 storage: every map is finite (excluded pixels hold 0 error); clamp the range
    big = float(np.finfo(np.float32).max)
    return {k: np.clip(np.asarray(v, dtype=np.float64), -big, big).astype(np.float32) for k, v in ch.items()}


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
    if s.get("rmse") is None:
        return "—"
    if s.get("rmse_below_noise"):
        return "**below the noise**"
    bias = "" if s.get("mean_error_below_noise") else (" (too bright)" if s["mean_error"] > 0 else " (too dark)")
    return "above the noise" + bias


def warnings_of(report: dict) -> list[str]:
    """Loud one-line warnings of a report: model non-finite values, excluded pixels."""
    out = []
    for part, m in report["metrics"].items():
        s = m["all"]
        if s.get("model_nonfinite_pixels"):
            out.append(f"{part}: the model returned non-finite values at {s['model_nonfinite_pixels']} pixel(s); "
                       "they are excluded from every metric")
    composited = [p for p in ("final", "composite", "attenuated_surface") if p in report["metrics"]
                  and report["composited"].get(p)]
    if composited:
        s = report["metrics"][composited[0]]["all"]
        ex = s.get("excluded_pixels", 0) - s.get("model_nonfinite_pixels", 0)
        if ex > 0:
            out.append(f"{', '.join(composited)}: {ex} pixel(s) excluded where the truth's unattenuated surface "
                       "radiance is undefined (surface_coverage = 0: no sample reached the surface)")
    return out


def check_table_markdown(result) -> list[str]:
    """The rows of a :class:`~fogref.compare.check.CheckResult` as a markdown table (lines)."""
    lines = ["| part | region | metric | estimate | interval | tolerance | verdict | pixels |",
             "|---|---|---|---:|---|---:|---|---:|"]
    for r in result.rows:
        tol = "" if r.tolerance is None else f"{r.tolerance:g}"
        est, ci = ("—", "—") if r.estimate is None else (f"{r.estimate:.4g}", f"[{r.low:.4g}, {r.high:.4g}]")
        lines.append(f"| {r.part} | {r.region} | {r.metric} | {est} | {ci} | {tol} | {r.verdict} | {r.pixels} |")
    return lines


def _candidate_lines(report: dict) -> list[str]:
    if "model" in report:
        return [(f"- model: `{report['model']['name']}`, precision `{report['precision']}`, "
                 f"parameters `{json.dumps(report['model']['parameters'])}`"),
                f"- sky pixels fogged at {report['sky_distance_m']:.6g} m; composited over the truth's `surface.*`"]
    im = report["images"]
    lines = ["- engine images: " + ", ".join(f"{k} `{v}` ({im['encodings'].get(k, '?')})"
                                              for k, v in im["sources"].items()),
             f"- exposure {im['exposure']:g} (radiance images divided by it); encoding option "
             f"`{im['encoding_option']}` (auto: PNG is sRGB, EXR/HDR linear; transmittance always linear)"]
    if "final" in report["metrics"]:
        lines.append("- `final` is the engine's own picture against the truth's `R,G,B`: it means something only "
                     "if the engine's surface lighting matches the truth's `surface` part; "
                     + ("`composite` (the engine's fog over the truth's surface) is the fair comparison"
                        if "composite" in report["metrics"] else
                        "give the engine's transmittance and inscatter for the fair comparison (`composite`)"))
    return lines


def _index_markdown(report: dict, has_sun: bool, figures: bool, check=None) -> str:
    c = report["conventions"]
    t = report["truth"]
    names = list(report["metrics"])
    overrides = " ".join(f"--set {k}={v}" for k, v in (t["overrides"] or {}).items())
    lines = [
        f"# fogref compare: `{report['candidate']['name']}` vs `{Path(report['exr']).name}`",
        "",
        (f"- ground truth: `{report['exr']}` ({report['image']['width']}×{report['image']['height']} px, "
         f"{report['image']['surface_pixels']} surface, {report['image']['sky_pixels']} sky), scene "
         f"`{t['scene']}`{f' `{overrides}`' if overrides else ''}, {t['spp']} spp, seed {t['seed']}, "
         f"pixel filter `{t['pixel_filter']}`"
         + ("" if t["pixel_exact"] else " (anti-aliased: silhouette pixels mix depths, which exact models "
            "cannot match)")),
        *_candidate_lines(report),
        (f"- pixels excluded from the composited parts (surface undefined): "
         f"{report['diagnostics']['surface_undefined_pixels']}"),
        (f"- reference identity |R,G,B − (attenuated_surface + inscatter)| max: "
         f"{_fmt(report['diagnostics']['reference_identity_max_abs'])}"),
        "",
    ]
    for w in report["warnings"]:
        lines.append(f"> **Warning:** {w}")
    if report["warnings"]:
        lines.append("")
    if check is not None:
        lines += ["## Verdict", "",
                  f"**{check.verdict}** ({check.confidence:.0%} two-sided intervals, {check.method_text}; "
                  "`fogref.compare.check.check`, the checker of `assert_fog_matches`). A row passes when its "
                  "whole interval lies within the tolerance (|x| for the signed metrics), fails when it lies "
                  "wholly outside, else is inconclusive.", "", *check_table_markdown(check), ""]
    lines += [
        "## Metrics",
        "",
        ("RMSE and |error| are in each part's units (radiance: the scene's radiance units; "
         "transmittance: 1). relMSE = mean((x−r)²/(r²+ε)), "
         f"ε = {c['relmse_eps']}. Mean error = mean(candidate − truth): > 0 too bright, < 0 too dark. "
         "ΔE2000: linear sRGB ÷ white → XYZ → CIELAB (D65); "
         "white = 99th percentile of the reference part's luminance (transmittance: 1). "
         f"FLIP: HDR-FLIP at {c['flip_ppd']} px/degree."),
        "",
        (f"**Noise.** `± x`: one standard error of the estimate, from the truth's per-pixel `stderr.*` "
         f"channels. *Noise floor*: what a perfect candidate would score against this truth (RMSE: "
         f"√mean(σ²); ΔE/FLIP: a perfect candidate plus one draw of the noise). *Below the noise*: within "
         f"{c['noise_z']:g} standard errors of the noise floor, so this truth cannot tell the candidate from "
         "a perfect one; render more samples to see further. These columns describe; the verdict is the "
         "check's (above)."),
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
        ("FLIP is a spatial metric: near the horizon its filters spread errors across regions, "
         "so a region without any pixel error can still show a small FLIP mean."),
        "",
    ]
    if figures:
        lines += ["## Truth | candidate | |error|", "", f"Shared tone map per part: {c['tone_map']}", "",
                  "Heatmaps: the signed error (candidate − truth, mean over RGB) on a diverging map centred at 0 "
                  "with symmetric limits (red: too bright, blue: too dark), then |error|, relative "
                  "squared error, ΔE2000 and FLIP. Grey: excluded pixels.", ""]
        for part in names:
            lines += [f"### {part}", "", f"![{part} side by side](side_by_side/{part}.png)", "",
                      f"![{part} error heatmaps](heatmaps/{part}.png)", ""]
        lines += ["## Error vs distance", "", "![error vs distance](error_vs_distance.png)", ""]
        lines += ["## Error vs angle to the sun", ""]
        lines += ["![error vs sun angle](error_vs_sun_angle.png)" if has_sun else "The scene has no sun.", ""]
    else:
        lines += ["Figures were not written (`figures=False`); the binned curves are in `metrics.json`.",
                  "" if has_sun else "The scene has no sun.", ""]
    lines += ["## Files", "", "- `metrics.json`: everything above, plus the binned curves"
              + (" and the check's rows (`check`)" if check is not None else ""),
              *(["- `check.json`: the check's rows, intervals and verdict"] if check is not None else []),
              "- `errors.exr`:", "", "```", ERRORS_EXR_LAYOUT, "```", ""]
    return "\n".join(lines)


# ---------------------------------------------------------------- entry point


def compare(
    truth,
    model,
    out_dir,
    precision: str = "float32",
    sky_distance: float = DEFAULT_SKY_DISTANCE,
    *,
    relmse_eps: float = M.RELMSE_EPS,
    flip_ppd: float = FLIP_PPD,
    distance_bins: int = 24,
    angle_step_deg: float = 5.0,
    figures: bool = True,
    check=None,
) -> dict:
    """Compare ``model`` with a ground truth; write a report to ``out_dir``.

    Parameters
    ----------
    truth : path or :class:`fogref.gbuffer.Truth`
        A schema-2 ground-truth EXR (read with :func:`fogref.gbuffer.load_truth`,
        which refuses a foreign, old or non-finite file) or an already-read truth.
    model
        Any object with ``evaluate(camera (3,), world_pos (..., 3), precision=...)
        -> FogResult`` (world frame y-up, metres).
    precision : {"float32", "float64"}
        Passed to the model.
    sky_distance : float
        Where sky pixels are fogged [m], finite and > 0.
    relmse_eps : float
        relMSE's ε [image units²], > 0.
    flip_ppd : float
        FLIP pixels per degree, > 0.
    distance_bins : int
        Number of log-distance bins.
    angle_step_deg : float
        Sun-angle bin width [deg].
    figures : bool
        False writes only ``metrics.json``, ``errors.exr`` and ``index.md`` (no PNGs:
        for CI, where matplotlib dominates the run time).
    check : CheckResult, optional
        The verdict of :func:`fogref.compare.check.check` on the same truth and model:
        its rows go into ``metrics.json`` (``check``), ``check.json`` and a table in ``index.md``.

    Returns
    -------
    dict
        What ``metrics.json`` holds.  FogrefError for a bad option or truth.
    """
    if precision not in ("float32", "float64"):
        raise FogrefError(f"precision must be 'float32' or 'float64', got {precision!r}")
    sky_distance = check_sky_distance(sky_distance)
    truth = truth if isinstance(truth, Truth) else load_truth(truth)
    parts = evaluate_parts(truth, model, precision, sky_distance)
    header = {"candidate": {"kind": "model", "name": _model_name(model)},
              "model": {"name": _model_name(model), "parameters": _model_description(model)},
              "precision": precision, "sky_distance_m": float(sky_distance)}
    return write_report(truth, parts, out_dir, header, {"final": True, "attenuated_surface": True},
                        relmse_eps=relmse_eps, flip_ppd=flip_ppd, distance_bins=distance_bins,
                        angle_step_deg=angle_step_deg, figures=figures, check=check)


def compare_images(truth, images, out_dir, *, figures: bool = True, check=None, **options) -> dict:
    """The report of :func:`compare` for an engine's images (:func:`image_parts`) instead of a model.

    ``images``: :class:`fogref.compare.foreign.EngineImages`; ``check``: the
    :class:`~fogref.compare.check.CheckResult` of the same images; ``options``:
    ``relmse_eps``, ``flip_ppd``, ``distance_bins``, ``angle_step_deg`` as :func:`compare`.
    Returns what ``metrics.json`` holds.
    """
    truth = truth if isinstance(truth, Truth) else load_truth(truth)
    parts = image_parts(truth, images)
    name = getattr(images, "description", "engine images")
    header = {"candidate": {"kind": "images", "name": name},
              "images": {"sources": dict(images.sources), "encodings": dict(getattr(images, "encodings", {})),
                         "encoding_option": getattr(images, "encoding_option", None),
                         "exposure": float(getattr(images, "exposure", 1.0))}}
    return write_report(truth, parts, out_dir, header, {"attenuated_surface": True, "composite": True},
                        figures=figures, check=check, **options)


def write_report(truth: Truth, parts: dict, out_dir, header: dict, composited: dict, *,
                 relmse_eps: float = M.RELMSE_EPS, flip_ppd: float = FLIP_PPD, distance_bins: int = 24,
                 angle_step_deg: float = 5.0, figures: bool = True, check=None) -> dict:
    """Metrics, maps, figures and pages of ``parts`` (from :func:`evaluate_parts` or :func:`image_parts`).

    ``header``: what the report says about the candidate (``candidate``: ``{"kind", "name"}``, and
    ``model``/``precision``/``sky_distance_m`` or ``images``); ``composited``: part -> True for the
    parts composited over the truth's surface (their excluded pixels are warned about).  Writes
    ``metrics.json``, ``errors.exr``, ``index.md``, the figures unless ``figures`` is False, and with
    ``check`` (a CheckResult) ``check.json``.  Returns what ``metrics.json`` holds.
    """
    out = Path(out_dir)
    names = list(parts)
    out.mkdir(parents=True, exist_ok=True)

    errors = {
        part: error_maps(p["reference"], p["model"], white=1.0 if PART_UNITS[part] == "1" else None,
                           eps=relmse_eps, ppd=flip_ppd, noise_cov=p["cov"], valid=p["valid"], spp=truth.spp)
        for part, p in parts.items()
    }
    masks = {"all": None, "surface": truth.hit, "sky": truth.sky}
    table = {part: {r: errors[part].summary(masks[r]) for r in REGIONS} for part in names}

    sun_angle = truth.sun_angle_deg()
    by_distance = binned_errors(truth.distance, errors,
                                log_distance_edges(truth.distance[truth.hit], distance_bins), mask=truth.hit)
    by_sun = binned_errors(sun_angle, errors, angle_edges(angle_step_deg)) if sun_angle is not None else None
    exposures = {p: (1.0 if PART_UNITS[p] == "1" else exposure_for(parts[p]["reference"])) for p in names}

    h, w = truth.shape
    report = _json_safe({
        "exr": str(truth.path),
        "truth": truth_provenance(truth),
        **header,
        "image": {"width": w, "height": h, "surface_pixels": int(truth.hit.sum()),
                  "sky_pixels": int(truth.sky.sum())},
        "units": {p: PART_UNITS[p] for p in names},
        "composited": {p: bool(composited.get(p)) for p in names},
        "conventions": {
            "relmse_eps": relmse_eps,
            "relmse": "mean over pixels and RGB of (x - r)^2 / (r^2 + eps)",
            "rmse": "sqrt(mean over pixels and RGB of (x - r)^2), in the part's units",
            "mean_error": "mean over pixels and RGB of (x - r): > 0 candidate too bright",
            "delta_e2000": "CIEDE2000; linear sRGB/Rec.709 / white -> XYZ -> CIELAB (D65), negatives clipped",
            "delta_e2000_white": {p: errors[p].white for p in names},
            "flip_ppd": flip_ppd,
            "flip_params": {p: errors[p].flip_params for p in names},
            "tone_map": "display = sRGB_OETF(clip(exposure * linear, 0, 1)); "
                        "exposure = 1 / (99th percentile of the reference part's luminance), transmittance 1",
            "sky": "a model is evaluated at camera + view * sky_distance, composited over the truth's surface.*",
            "composite": "model: final = surface * T_model + inscatter_model; images: composite = surface * "
                         "T_engine + inscatter_engine; attenuated_surface = surface * T; only where "
                         "surface_coverage > 0; other pixels excluded and counted",
            "noise": "per-pixel covariance of candidate - truth from the truth's stderr.* and corr.* channels "
                     "(fogref.compare.noise, through check's comparison core: final/composite = surface * T' + "
                     "L' against surface * T + L) plus a rounding floor (4 ulp of float32 of |truth|); "
                     "*_noise_floor: a perfect candidate's score; *_stderr: standard error of the estimate; "
                     "*_below_noise: within noise_z standard errors of the noise floor (descriptive; the "
                     "verdict is the check's)",
            "noise_correlation": truth.attrs.get("fogref.noise_correlation", "measured"),
            "noise_z": M.NOISE_Z,
            "nonfinite": "model NaN/inf pixels are excluded from every metric and counted "
                         "(model_nonfinite_pixels); the truth is refused if it holds any",
        },
        "metrics": table,
        "diagnostics": {
            "model_nonfinite_values": {p: M.count_nonfinite(parts[p]["model"])
                                       for p in ("transmittance", "inscatter") if p in parts},
            "surface_undefined_pixels": int(np.count_nonzero(~truth.surface_valid)),
            "reference_identity_max_abs": truth.identity_residual(),
        },
        "binned": {"distance_m": by_distance, "sun_angle_deg": by_sun},
        **({"check": check.to_dict()} if check is not None else {}),
    })
    report["warnings"] = warnings_of(report)

    write_exr(out / "errors.exr", _errors_exr_channels(truth, parts, errors, sun_angle),
              {"fogref.compare": {"exr": str(truth.path), "candidate": report["candidate"],
                                  **({"model": report["model"], "precision": report["precision"]}
                                     if "model" in report else {})}})
    _remove_stale_figures(out)
    if figures:
        _write_figures(out, parts, errors, exposures, by_distance, by_sun, angle_step_deg)
    if check is not None:
        write_text_atomic(out / "check.json", json.dumps(report["check"], indent=2, allow_nan=False) + "\n")
    write_text_atomic(out / "metrics.json", json.dumps(report, indent=2, allow_nan=False) + "\n")
    write_text_atomic(out / "index.md", _index_markdown(report, by_sun is not None, figures, check))
    return report


#: Every part a report may hold (model runs: PARTS; engine images add ``composite``).
ALL_PARTS: tuple[str, ...] = (*PARTS, "composite")


def figure_paths(out_dir) -> list[Path]:
    """Every PNG ``compare`` may write into ``out_dir``."""
    out = Path(out_dir)
    return [out / "error_vs_distance.png", out / "error_vs_sun_angle.png",
            *(out / "side_by_side" / f"{p}.png" for p in ALL_PARTS),
            *(out / "heatmaps" / f"{p}.png" for p in ALL_PARTS)]


def _remove_stale_figures(out: Path) -> None:
    """Delete the PNGs an earlier run wrote into ``out``, so the folder shows this run only."""
    for png in figure_paths(out):
        png.unlink(missing_ok=True)


def _write_figures(out: Path, parts, errors, exposures, by_distance, by_sun, angle_step_deg) -> None:
    for part in parts:
        e = errors[part]
        ref = parts[part]["reference"]
        plot_side_by_side(ref, ref + e.signed, exposures[part], part, PART_UNITS[part],
                          out / "side_by_side" / f"{part}.png", valid=e.valid)
        plot_error_heatmaps(e, part, PART_UNITS[part], out / "heatmaps" / f"{part}.png")
    units = {p: PART_UNITS[p] for p in parts}
    plot_binned_errors(by_distance, units, "distance to the surface [m] (log scale)",
                       "error vs distance (surface pixels, log-spaced bins)", out / "error_vs_distance.png", True)
    if by_sun is not None:
        plot_binned_errors(by_sun, units, "angle between view ray and sun [degrees]",
                           f"error vs angle to the sun ({angle_step_deg:g}° bins, all pixels)",
                           out / "error_vs_sun_angle.png", False)
