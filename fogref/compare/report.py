"""``compare``: measure one game fog model against one ground-truth EXR and write a report.

What is compared (each a *part*, all ``(H, W, 3)`` linear RGB):

======================  ==============================  ===============================
part                    reference (EXR)                 model
======================  ==============================  ===============================
``final``               ``R,G,B``                       ``surface * T_model + inscatter_model``
``transmittance``       ``T.*``                         ``T_model``
``inscatter``           ``inscatter.*``                 ``inscatter_model``
``attenuated_surface``  ``surface * T``                 ``surface * T_model``
======================  ==============================  ===============================

``final`` is the model *composited* as the engine does (``FogResult.composite``) on
the EXR's unfogged ``surface.*`` radiance, so that only the fog differs.
``final = attenuated_surface + inscatter`` on both sides.

Sky pixels (``hit == 0``): the model shades the point ``camera + view * sky_distance``
(engines fog the sky as a surface at a finite distance; the default 100 km stands in
for infinity), and composites over the EXR's ``surface.*``, which for sky pixels is
the sky radiance seen without fog.  The reference's ``T`` and ``inscatter`` there are
those of the whole escaping ray.  We keep the EXR's ``surface.*`` rather than
``fogref.params``' sky radiance because it is exactly what the reference's ``R,G,B``
was composited from (``R,G,B = T * surface + inscatter``), so the difference is the
fog model's alone.  Every metric is reported over all pixels and, separately, over
``surface`` (hit) and ``sky`` pixels, so the sky convention never hides the rest.

Report folder (``out_dir``)::

    index.md                   the page: pictures side by side, metric table, plots
    metrics.json               every metric per part and region, binned curves, conventions
    errors.exr                 per-pixel maps (see ERRORS_EXR_LAYOUT)
    side_by_side/<part>.png    reference | model | |error|, one shared tone map
    heatmaps/<part>.png        |error|, relative squared error, ΔE2000, FLIP, with colour bars
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
from fogref.compare.binning import angle_edges, binned_errors, log_distance_edges
from fogref.compare.ground_truth import GroundTruth, load_ground_truth
from fogref.compare.model_factory import current_parameters
from fogref.compare.plots import plot_binned_errors, plot_error_heatmaps, plot_side_by_side
from fogref.compare.tonemap import exposure_for
from fogref.errors import FogrefError
from fogref.exrio import write_exr

#: Distance [m] at which the model fogs sky pixels (a stand-in for infinity).
DEFAULT_SKY_DISTANCE = 1.0e5
PARTS: tuple[str, ...] = ("final", "transmittance", "inscatter", "attenuated_surface")
#: Units of each part's values ("1": dimensionless; radiance is in the scene's units).
PART_UNITS: dict[str, str] = {
    "final": "radiance",
    "transmittance": "1",
    "inscatter": "radiance",
    "attenuated_surface": "radiance",
}
REGIONS: tuple[str, ...] = ("all", "surface", "sky")
ERRORS_EXR_LAYOUT = """\
<part>.reference.R,G,B   the reference part
<part>.model.R,G,B       the model part
<part>.error.R,G,B       model - reference (signed)
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
    """JSON-ready parameters of ``model`` (see :func:`~fogref.compare.model_factory.current_parameters`)."""
    try:
        return _json_safe(current_parameters(model))
    except (TypeError, AttributeError, ValueError):
        return repr(model)


def _as_image(x, shape: tuple[int, int], what: str) -> np.ndarray:
    a = np.asarray(x)
    try:
        return np.broadcast_to(a, (*shape, 3))
    except ValueError:
        raise FogrefError(f"model returned {what} of shape {a.shape}, expected {(*shape, 3)}") from None


def evaluate_parts(gt: GroundTruth, model, precision: str, sky_distance: float):
    """Reference and model images of every part, and the model's non-finite counts.

    Returns ``(reference_parts, model_parts, nonfinite)``: dicts part -> ``(H, W, 3)``
    float64 (model values sanitised by :func:`fogref.compare.metrics.sanitize`) and
    ``{"transmittance": n, "inscatter": n}`` non-finite values the model returned.
    """
    result = model.evaluate(gt.camera, gt.world_positions(sky_distance), precision=precision)
    t_raw = _as_image(result.transmittance, gt.shape, "transmittance")
    l_raw = _as_image(result.inscatter, gt.shape, "inscatter")
    nonfinite = {"transmittance": M.count_nonfinite(t_raw), "inscatter": M.count_nonfinite(l_raw)}
    t_model, l_model = M.sanitize(t_raw), M.sanitize(l_raw)
    composite = gt.surface * t_model + l_model  # FogResult.composite: the engine's rule
    model_parts = {
        "final": M.sanitize(composite),
        "transmittance": t_model,
        "inscatter": l_model,
        "attenuated_surface": M.sanitize(gt.surface * t_model),
    }
    reference_parts = {
        "final": M.sanitize(gt.final),
        "transmittance": M.sanitize(gt.transmittance),
        "inscatter": M.sanitize(gt.inscatter),
        "attenuated_surface": M.sanitize(gt.surface * gt.transmittance),
    }
    return reference_parts, model_parts, nonfinite


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


def _errors_exr_channels(gt, refs, models, errors, sun_angle) -> dict:
    ch: dict[str, np.ndarray] = {}
    for part in PARTS:
        e = errors[part]
        for i, c in enumerate("RGB"):
            ch[f"{part}.reference.{c}"] = refs[part][..., i]
            ch[f"{part}.model.{c}"] = models[part][..., i]
            ch[f"{part}.error.{c}"] = e.signed[..., i]
        ch[f"{part}.abs_error"] = e.absolute
        ch[f"{part}.rel_sq_error"] = e.relative_squared
        ch[f"{part}.deltaE2000"] = e.delta_e2000
        ch[f"{part}.flip"] = e.flip
    ch["distance"] = M.sanitize(gt.distance)
    ch["hit"] = gt.hit.astype(np.float32)
    if sun_angle is not None:
        ch["sun_angle"] = sun_angle
    # float32 storage: clamp so nothing overflows to inf (write_exr also maps NaN to 0)
    big = float(np.finfo(np.float32).max)
    return {k: np.clip(M.sanitize(v), -big, big).astype(np.float32) for k, v in ch.items()}


def _fmt(v) -> str:
    if v is None:
        return "—"
    if isinstance(v, int):
        return str(v)
    return f"{v:.4g}"


def _index_markdown(report: dict, has_sun: bool, figures: bool) -> str:
    c = report["conventions"]
    lines = [
        f"# fogref compare: `{report['model']['name']}` vs `{Path(report['exr']).name}`",
        "",
        (f"- ground truth: `{report['exr']}` ({report['image']['width']}×{report['image']['height']} px, "
         f"{report['image']['surface_pixels']} surface, {report['image']['sky_pixels']} sky)"),
        (f"- model: `{report['model']['name']}`, precision `{report['precision']}`, "
         f"parameters `{json.dumps(report['model']['parameters'])}`"),
        f"- sky pixels fogged at {report['sky_distance_m']:.6g} m; composited over the EXR's `surface.*`",
        (f"- model non-finite values (replaced: NaN→0, ±inf→±FLT_MAX): "
         f"{report['diagnostics']['model_nonfinite_values']}"),
        (f"- reference identity |R,G,B − (T·surface + inscatter)| max: "
         f"{_fmt(report['diagnostics']['reference_identity_max_abs'])}"),
        "",
        "## Metrics",
        "",
        ("RMSE and |error| are in each part's units (radiance: the scene's radiance units; "
         "transmittance: 1). relMSE = mean((x−r)²/(r²+ε)), "
         f"ε = {c['relmse_eps']}. ΔE2000: linear sRGB ÷ white → XYZ → CIELAB (D65); "
         "white = 99th percentile of the reference part's luminance (transmittance: 1). "
         f"FLIP: HDR-FLIP at {c['flip_ppd']} px/degree."),
        "",
        "| part | region | pixels | RMSE | relMSE | mean \\|err\\| | ΔE2000 mean | ΔE2000 p95 | FLIP mean |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for part in PARTS:
        for region in REGIONS:
            s = report["metrics"][part][region]
            lines.append(
                f"| {part} | {region} | {s['pixels']} | {_fmt(s.get('rmse'))} | {_fmt(s.get('relmse'))} | "
                f"{_fmt(s.get('mean_abs_error'))} | {_fmt(s.get('delta_e2000_mean'))} | "
                f"{_fmt(s.get('delta_e2000_p95'))} | {_fmt(s.get('flip_mean'))} |"
            )
    lines += [
        "",
        ("FLIP is a spatial metric: near the horizon its filters spread errors across regions, "
         "so a region without any pixel error can still show a small FLIP mean."),
        "",
    ]
    if figures:
        lines += ["## Reference | model | |error|", "", f"Shared tone map per part: {c['tone_map']}", ""]
        for part in PARTS:
            lines += [f"### {part}", "", f"![{part} side by side](side_by_side/{part}.png)", "",
                      f"![{part} error heatmaps](heatmaps/{part}.png)", ""]
        lines += ["## Error vs distance", "", "![error vs distance](error_vs_distance.png)", ""]
        lines += ["## Error vs angle to the sun", ""]
        lines += ["![error vs sun angle](error_vs_sun_angle.png)" if has_sun else "The scene has no sun.", ""]
    else:
        lines += ["Figures were not written (`figures=False`); the binned curves are in `metrics.json`.",
                  "" if has_sun else "The scene has no sun.", ""]
    lines += ["## Files", "", "- `metrics.json`: everything above, plus the binned curves", "- `errors.exr`:", "",
              "```", ERRORS_EXR_LAYOUT, "```", ""]
    return "\n".join(lines)


# ---------------------------------------------------------------- entry point


def compare(
    exr_path,
    model,
    out_dir,
    precision: str = "float32",
    sky_distance: float = DEFAULT_SKY_DISTANCE,
    *,
    relmse_eps: float = M.RELMSE_EPS,
    flip_ppd: float = M.FLIP_PPD,
    distance_bins: int = 24,
    angle_step_deg: float = 5.0,
    figures: bool = True,
) -> dict:
    """Compare ``model`` with the ground-truth EXR at ``exr_path``; write a report to ``out_dir``.

    ``model``: any object with ``evaluate(camera (3,), world_pos (..., 3),
    precision=...) -> FogResult`` (world frame y-up, metres).  ``precision``:
    ``"float32"`` or ``"float64"``, passed to the model.  ``sky_distance`` [m]: where
    sky pixels are fogged (see the module docstring).  ``relmse_eps``: relMSE's ε
    [image units²]; ``flip_ppd``: FLIP pixels per degree; ``distance_bins``: number
    of log-distance bins; ``angle_step_deg``: sun-angle bin width [deg];
    ``figures``: False writes only ``metrics.json``, ``errors.exr`` and ``index.md``
    (no PNGs: for CI, where matplotlib dominates the run time).

    Returns the dict written to ``metrics.json``.  Raises :class:`FogrefError` naming
    the file and the missing channel(s) if the EXR lacks any.
    """
    if precision not in ("float32", "float64"):
        raise FogrefError(f"precision must be 'float32' or 'float64', got {precision!r}")
    gt = load_ground_truth(exr_path)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    refs, models, nonfinite = evaluate_parts(gt, model, precision, sky_distance)

    errors = {
        part: M.error_maps(refs[part], models[part], white=1.0 if PART_UNITS[part] == "1" else None,
                           eps=relmse_eps, ppd=flip_ppd)
        for part in PARTS
    }
    masks = {"all": None, "surface": gt.hit, "sky": gt.sky}
    table = {part: {r: errors[part].summary(masks[r]) for r in REGIONS} for part in PARTS}

    sun_angle = gt.sun_angle_deg()
    by_distance = binned_errors(gt.distance, errors, log_distance_edges(gt.distance[gt.hit], distance_bins),
                                mask=gt.hit)
    by_sun = binned_errors(sun_angle, errors, angle_edges(angle_step_deg)) if sun_angle is not None else None
    exposures = {p: (1.0 if PART_UNITS[p] == "1" else exposure_for(refs[p])) for p in PARTS}

    h, w = gt.shape
    report = _json_safe({
        "exr": str(exr_path),
        "model": {"name": _model_name(model), "parameters": _model_description(model)},
        "precision": precision,
        "sky_distance_m": float(sky_distance),
        "image": {"width": w, "height": h, "surface_pixels": int(gt.hit.sum()), "sky_pixels": int(gt.sky.sum())},
        "units": PART_UNITS,
        "conventions": {
            "relmse_eps": relmse_eps,
            "relmse": "mean over pixels and RGB of (x - r)^2 / (r^2 + eps)",
            "rmse": "sqrt(mean over pixels and RGB of (x - r)^2), in the part's units",
            "delta_e2000": "CIEDE2000; linear sRGB/Rec.709 / white -> XYZ -> CIELAB (D65), negatives clipped",
            "delta_e2000_white": {p: errors[p].white for p in PARTS},
            "flip_ppd": flip_ppd,
            "flip_params": {p: errors[p].flip_params for p in PARTS},
            "tone_map": "display = sRGB_OETF(clip(exposure * linear, 0, 1)); "
                        "exposure = 1 / (99th percentile of the reference part's luminance), transmittance 1",
            "tone_map_exposure": exposures,
            "sky": "model evaluated at camera + view * sky_distance, composited over the EXR's surface.*",
            "nonfinite": "model NaN -> 0, +-inf -> +-FLT_MAX before any metric",
        },
        "metrics": table,
        "diagnostics": {
            "model_nonfinite_values": nonfinite,
            "reference_nonfinite_values": {
                "final": M.count_nonfinite(gt.final), "transmittance": M.count_nonfinite(gt.transmittance),
                "inscatter": M.count_nonfinite(gt.inscatter), "surface": M.count_nonfinite(gt.surface),
            },
            "reference_identity_max_abs": gt.identity_residual(),
        },
        "binned": {"distance_m": by_distance, "sun_angle_deg": by_sun},
    })

    write_exr(out / "errors.exr", _errors_exr_channels(gt, refs, models, errors, sun_angle),
              {"fogref.compare": {"exr": str(exr_path), "model": report["model"], "precision": precision}})
    _remove_stale_figures(out)
    if figures:
        _write_figures(out, refs, models, errors, exposures, by_distance, by_sun, angle_step_deg)
    write_text_atomic(out / "metrics.json", json.dumps(report, indent=2, allow_nan=False) + "\n")
    write_text_atomic(out / "index.md", _index_markdown(report, by_sun is not None, figures))
    return report


def figure_paths(out_dir) -> list[Path]:
    """Every PNG ``compare`` may write into ``out_dir``."""
    out = Path(out_dir)
    return [out / "error_vs_distance.png", out / "error_vs_sun_angle.png",
            *(out / "side_by_side" / f"{p}.png" for p in PARTS), *(out / "heatmaps" / f"{p}.png" for p in PARTS)]


def _remove_stale_figures(out: Path) -> None:
    """Delete the PNGs an earlier run wrote into ``out``, so the folder shows this run only."""
    for png in figure_paths(out):
        png.unlink(missing_ok=True)


def _write_figures(out: Path, refs, models, errors, exposures, by_distance, by_sun, angle_step_deg) -> None:
    for part in PARTS:
        plot_side_by_side(refs[part], models[part], exposures[part], part, PART_UNITS[part],
                          out / "side_by_side" / f"{part}.png")
        plot_error_heatmaps(errors[part], part, PART_UNITS[part], out / "heatmaps" / f"{part}.png")
    plot_binned_errors(by_distance, PART_UNITS, "distance to the surface [m] (log scale)",
                       "error vs distance (surface pixels, log-spaced bins)", out / "error_vs_distance.png", True)
    if by_sun is not None:
        plot_binned_errors(by_sun, PART_UNITS, "angle between view ray and sun [degrees]",
                           f"error vs angle to the sun ({angle_step_deg:g}° bins, all pixels)",
                           out / "error_vs_sun_angle.png", False)
