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
is divided by a transmittance.  A model's NaN, infinite or huge (> 1e30, where squared
errors overflow) value is refused with the count and the first pixel, here as in ``check``
(:func:`fogref.compare.candidate.evaluate_model`); with ``check=`` the report reuses the
check's evaluation of the model instead of evaluating it again.

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

import json
import os
from functools import partial
from pathlib import Path

import numpy as np

from fogref.atomic import write_text_atomic
from fogref.compare import metrics as M
from fogref.compare.binning import angle_edges, binned_errors, log_distance_edges
from fogref.compare.error_maps import error_maps
from fogref.compare.paths import refuse_output_over_input
from fogref.compare.perceptual import FLIP_PPD
from fogref.compare.plots import heatmap_maps, plot_binned_errors, plot_error_heatmaps, plot_side_by_side
from fogref.compare.report_page import ERRORS_EXR_LAYOUT, check_table_markdown, index_markdown, warnings_of
from fogref.compare.report_parts import (
    ALL_PARTS,
    PART_UNITS,
    PARTS,
    REGIONS,
    check_sky_distance,
    evaluate_parts,
    image_parts,
    json_safe,
    model_description,
    model_units,
    parts_from_check,
    truth_provenance,
)
from fogref.compare.workers import check_processes, run_jobs, start_workers
from fogref.display import part_exposures
from fogref.errors import FogrefError
from fogref.exrio import write_exr
from fogref.gbuffer import Truth, load_truth
from fogref.mapping.build import model_label
from fogref.models.base import SKY_DISTANCE as DEFAULT_SKY_DISTANCE

__all__ = [
    "ALL_PARTS",
    "DEFAULT_SKY_DISTANCE",
    "ERRORS_EXR_LAYOUT",
    "PARTS",
    "PART_UNITS",
    "REGIONS",
    "check_sky_distance",
    "check_table_markdown",
    "compare",
    "compare_images",
    "compare_metrics",
    "evaluate_parts",
    "figure_paths",
    "image_parts",
    "refuse_output_over_input",
    "report_paths",
    "truth_provenance",
    "warnings_of",
    "write_report",
]


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
        if e.delta_e2000 is not None:  # the perceptual maps, unless the comparison left them out
            ch[f"{part}.deltaE2000"] = e.delta_e2000
        if e.flip is not None:
            ch[f"{part}.flip"] = e.flip
    ch["distance"] = truth.distance
    ch["hit"] = truth.hit.astype(np.float32)
    if sun_angle is not None:
        ch["sun_angle"] = sun_angle
    # float32 storage: every map is finite (excluded pixels hold 0 error); clamp the range
    big = float(np.finfo(np.float32).max)
    return {k: np.clip(np.asarray(v, dtype=np.float64), -big, big).astype(np.float32) for k, v in ch.items()}


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
    processes: int | None = 1,
    check=None,
    perceptual: bool = True,
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
    processes : int >= 1 or None
        Worker processes that draw the figures side by side (:mod:`fogref.compare.workers`; None:
        one per core this process may use; 1: this process draws them).  Above 1 the workers
        import the main module, as :mod:`multiprocessing`'s do: a script calling this needs its
        ``if __name__ == "__main__":`` guard.  ``fogref compare`` uses every core.
    check : CheckResult, optional
        The verdict of :func:`fogref.compare.check.check` on the same truth and model (and
        precision, sky distance): the model's images are taken from it (the model is evaluated
        once, not again), and its rows go into ``metrics.json`` (``check``), ``check.json`` and a
        table in ``index.md``.
    perceptual : bool
        False leaves out the perceptual metrics, ΔE2000 and HDR-FLIP (their maps, means, noise
        floors, binned curves and heatmaps): every other value is the same, and the comparison
        costs a fraction (FLIP is most of its work: ``fogref compare --no-figures`` 2.2x faster
        at 320x180, 2.5-2.9x at 960x540, ``reports/benchmarks/compare_perceptual.md``).  For a check
        or a sweep that reads only the radiometric errors.

    Returns
    -------
    dict
        What ``metrics.json`` holds.  FogrefError for a bad option or truth.
    """
    refuse_output_over_input([("out_dir", p) for p in report_paths(out_dir)], [("truth", _path_of(truth))])
    truth, parts, header = _model_parts(truth, model, precision, sky_distance, check)
    return write_report(
        truth,
        parts,
        out_dir,
        header,
        {"final": True, "attenuated_surface": True},
        relmse_eps=relmse_eps,
        flip_ppd=flip_ppd,
        distance_bins=distance_bins,
        angle_step_deg=angle_step_deg,
        figures=figures,
        processes=processes,
        check=check,
        perceptual=perceptual,
    )


def _model_parts(truth, model, precision: str, sky_distance: float, check=None) -> tuple:
    """``(truth, parts, header)`` of :func:`compare`: the truth read, the parts of ``model`` (or of
    ``check``'s evaluation) and what the report says about the model; FogrefError for a bad option."""
    if precision not in ("float32", "float64"):
        raise FogrefError(f"precision must be 'float32' or 'float64', got {precision!r}")
    sky_distance = check_sky_distance(sky_distance)
    truth = truth if isinstance(truth, Truth) else load_truth(truth)
    parts = parts_from_check(truth, check, model, precision, sky_distance)
    if parts is None:
        parts = evaluate_parts(truth, model, precision, sky_distance)
    header = {
        "candidate": {"kind": "model", "name": model_label(model)},
        "model": {
            "name": model_label(model),
            "parameters": model_description(model),
            "units": model_units(model),
        },
        "precision": precision,
        "sky_distance_m": float(sky_distance),
    }
    return truth, parts, header


def compare_metrics(
    truth,
    model,
    precision: str = "float32",
    sky_distance: float = DEFAULT_SKY_DISTANCE,
    *,
    relmse_eps: float = M.RELMSE_EPS,
    flip_ppd: float = FLIP_PPD,
    perceptual: bool = True,
) -> dict:
    """The metrics of :func:`compare` without its report (nothing is written, no binned errors):
    ``metrics.json``'s ``candidate``, ``model``, ``precision``, ``sky_distance_m`` and ``metrics``,
    the same values.  What a sweep keeps of each comparison.  Arguments as :func:`compare`'s.

    >>> from fogref.compare.synthetic import synthetic_truth
    >>> from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams
    >>> fog = UE4ExponentialHeightFog(UE4FogParams())
    >>> m = compare_metrics(synthetic_truth(fog, shape=(9, 16)), fog)
    >>> sorted(m), sorted(m["metrics"]["final"])
    (['candidate', 'metrics', 'model', 'precision', 'sky_distance_m'], ['all', 'sky', 'surface'])
    """
    truth, parts, header = _model_parts(truth, model, precision, sky_distance)
    errors = _part_errors(truth, parts, relmse_eps, flip_ppd, perceptual)
    return json_safe({**header, "metrics": _metrics_table(truth, errors)})


def _part_errors(truth: Truth, parts: dict, relmse_eps: float, flip_ppd: float, perceptual: bool) -> dict:
    """The :class:`~fogref.compare.error_maps.ErrorMaps` of every part.

    In this process: FLIP's C++ already runs on every core at large sizes, and the worker processes
    measured no faster here (``reports/benchmarks/compare_speed.md``)."""
    return {
        part: error_maps(
            p["reference"],
            p["model"],
            white=1.0 if PART_UNITS[part] == "1" else None,
            eps=relmse_eps,
            ppd=flip_ppd,
            noise_cov=p["cov"],
            valid=p["valid"],
            spp=truth.spp,
            perceptual=perceptual,
        )
        for part, p in parts.items()
    }


def _metrics_table(truth: Truth, errors: dict) -> dict:
    """part -> region -> the summary of the part's errors over the region's pixels."""
    masks = {"all": None, "surface": truth.hit, "sky": truth.sky}
    return {part: {r: errors[part].summary(masks[r]) for r in REGIONS} for part in errors}


def compare_images(
    truth, images, out_dir, *, figures: bool = True, check=None, engine: dict | None = None, **options
) -> dict:
    """The report of :func:`compare` for an engine's images (:func:`image_parts`) instead of a model.

    ``images``: :class:`fogref.compare.foreign.EngineImages`; ``check``: the
    :class:`~fogref.compare.check.CheckResult` of the same images; ``engine``: the record of a
    real engine that rendered them (``fogref.engines.render.EngineRender.record`` with its
    ``summary`` lines), shown in ``index.md`` and kept in ``metrics.json``; ``options``:
    ``relmse_eps``, ``flip_ppd``, ``distance_bins``, ``angle_step_deg``, ``processes``,
    ``perceptual`` as :func:`compare`.
    Returns what ``metrics.json`` holds.
    """
    inputs = [("truth", _path_of(truth))] + [(k, v) for k, v in getattr(images, "sources", {}).items()]
    refuse_output_over_input([("out_dir", p) for p in report_paths(out_dir)], inputs)
    truth = truth if isinstance(truth, Truth) else load_truth(truth)
    parts = image_parts(truth, images)
    name = getattr(images, "description", "engine images")
    header = {
        "candidate": {"kind": "images", "name": name},
        "images": {
            "sources": dict(images.sources),
            "encodings": dict(getattr(images, "encodings", {})),
            "encoding_option": getattr(images, "encoding_option", None),
            "exposure": float(getattr(images, "exposure", 1.0)),
        },
        **({"engine": engine} if engine else {}),
    }
    return write_report(
        truth,
        parts,
        out_dir,
        header,
        {"attenuated_surface": True, "composite": True},
        figures=figures,
        check=check,
        **options,
    )


def _path_of(truth):
    """The file of a truth given as a path or a Truth read from one (None for a synthetic one)."""
    p = truth.path if isinstance(truth, Truth) else truth
    return p if isinstance(p, (str, os.PathLike)) and not str(p).startswith("<") else None


def write_report(
    truth: Truth,
    parts: dict,
    out_dir,
    header: dict,
    composited: dict,
    *,
    relmse_eps: float = M.RELMSE_EPS,
    flip_ppd: float = FLIP_PPD,
    distance_bins: int = 24,
    angle_step_deg: float = 5.0,
    figures: bool = True,
    processes: int | None = 1,
    check=None,
    perceptual: bool = True,
) -> dict:
    """Metrics, maps, figures and pages of ``parts`` (from :func:`evaluate_parts` or :func:`image_parts`).

    ``header``: what the report says about the candidate (``candidate``: ``{"kind", "name"}``, and
    ``model``/``precision``/``sky_distance_m`` or ``images``); ``composited``: part -> True for the
    parts composited over the truth's surface (their excluded pixels are warned about).  Writes
    ``metrics.json``, ``errors.exr``, ``index.md``, the figures unless ``figures`` is False, and with
    ``check`` (a CheckResult) ``check.json``; ``processes`` and ``perceptual`` as :func:`compare`.
    Returns what ``metrics.json`` holds.
    """
    check_processes(processes)
    if figures:
        start_workers(processes)  # they import matplotlib meanwhile, on another core
    out = Path(out_dir)
    names = list(parts)
    out.mkdir(parents=True, exist_ok=True)

    errors = _part_errors(truth, parts, relmse_eps, flip_ppd, perceptual)
    table = _metrics_table(truth, errors)

    sun_angle = truth.sun_angle_deg()
    by_distance = binned_errors(
        truth.distance, errors, log_distance_edges(truth.distance[truth.hit], distance_bins), mask=truth.hit
    )
    by_sun = binned_errors(sun_angle, errors, angle_edges(angle_step_deg)) if sun_angle is not None else None
    exposures = part_exposures({p: parts[p]["reference"] for p in names})

    h, w = truth.shape
    report = json_safe(
        {
            "exr": str(truth.path),
            "truth": truth_provenance(truth),
            **header,
            "image": {
                "width": w,
                "height": h,
                "surface_pixels": int(truth.hit.sum()),
                "sky_pixels": int(truth.sky.sum()),
            },
            "units": {p: PART_UNITS[p] for p in names},
            "composited": {p: bool(composited.get(p)) for p in names},
            "conventions": {
                "relmse_eps": relmse_eps,
                "relmse": "mean over pixels and RGB of (x - r)^2 / (r^2 + eps)",
                "rmse": "sqrt(mean over pixels and RGB of (x - r)^2), in the part's units",
                "mean_error": "mean over pixels and RGB of (x - r): > 0 candidate too bright",
                "perceptual": bool(perceptual),
                **(
                    {
                        "delta_e2000": (
                            "CIEDE2000; linear sRGB/Rec.709 / white -> XYZ -> CIELAB (D65), negatives clipped"
                        ),
                        "delta_e2000_white": {p: errors[p].white for p in names},
                        "flip_ppd": flip_ppd,
                        "flip_params": {p: errors[p].flip_params for p in names},
                    }
                    if perceptual
                    else {"delta_e2000": "not computed", "flip": "not computed"}
                ),
                "tone_map": "display = sRGB_OETF(clip(exposure * linear, 0, 1)); "
                "exposure = 1 / (99th percentile of the reference part's luminance), transmittance 1",
                "sky": "a model is evaluated at camera + view * sky_distance, composited over the truth's "
                "surface.*",
                "composite": "model: final = surface * T_model + inscatter_model; images: composite = "
                "surface * T_engine + inscatter_engine; attenuated_surface = surface * T; only where "
                "surface_coverage > 0; other pixels excluded and counted",
                "noise": "per-pixel covariance of candidate - truth from the truth's stderr.* and corr.* "
                "channels (fogref.compare.noise, through check's comparison core: final/composite = surface "
                "* T' + L' against surface * T + L) plus a rounding floor (4 ulp of float32 of |truth|); "
                "*_noise_floor: a perfect candidate's score; *_stderr: standard error of the estimate; "
                "*_below_noise: within noise_z standard errors of the noise floor (descriptive; the verdict "
                "is the check's)",
                "noise_correlation": truth.attrs.get("fogref.noise_correlation", "measured"),
                "noise_z": M.NOISE_Z,
                "nonfinite": "a candidate with NaN, inf or |value| > 1e30 is refused (count and first "
                "pixel), as in check; the truth is refused if it holds any non-finite value",
            },
            "metrics": table,
            "diagnostics": {
                "model_nonfinite_values": {
                    p: M.count_nonfinite(parts[p]["model"])
                    for p in ("transmittance", "inscatter")
                    if p in parts
                },
                "surface_undefined_pixels": int(np.count_nonzero(~truth.surface_valid)),
                "reference_identity_max_abs": truth.identity_residual(),
            },
            "binned": {"distance_m": by_distance, "sun_angle_deg": by_sun},
            **({"check": check.to_dict()} if check is not None else {}),
        }
    )
    report["warnings"] = warnings_of(report)

    write_exr(
        out / "errors.exr",
        _errors_exr_channels(truth, parts, errors, sun_angle),
        {
            "fogref.compare": {
                "exr": str(truth.path),
                "candidate": report["candidate"],
                **({"model": report["model"], "precision": report["precision"]} if "model" in report else {}),
            }
        },
    )
    _remove_stale_figures(out)
    if figures:
        run_jobs(_figure_jobs(out, parts, errors, exposures, by_distance, by_sun, angle_step_deg), processes)
    if check is not None:
        write_text_atomic(out / "check.json", json.dumps(report["check"], indent=2, allow_nan=False) + "\n")
    write_text_atomic(out / "metrics.json", json.dumps(report, indent=2, allow_nan=False) + "\n")
    write_text_atomic(out / "index.md", index_markdown(report, by_sun is not None, figures, check))
    return report


#: The files a report writes into its folder, besides the figures.
REPORT_FILES = ("index.md", "metrics.json", "check.json", "errors.exr")


def report_paths(out_dir) -> list[Path]:
    """Every file ``compare`` may write into ``out_dir``: :data:`REPORT_FILES` and :func:`figure_paths`."""
    return [Path(out_dir) / f for f in REPORT_FILES] + figure_paths(out_dir)


def figure_paths(out_dir) -> list[Path]:
    """Every PNG ``compare`` may write into ``out_dir``."""
    out = Path(out_dir)
    return [
        out / "error_vs_distance.png",
        out / "error_vs_sun_angle.png",
        *(out / "side_by_side" / f"{p}.png" for p in ALL_PARTS),
        *(out / "heatmaps" / f"{p}.png" for p in ALL_PARTS),
    ]


def _remove_stale_figures(out: Path) -> None:
    """Delete the PNGs an earlier run wrote into ``out``, so the folder shows this run only."""
    for png in figure_paths(out):
        png.unlink(missing_ok=True)


def _figure_jobs(out: Path, parts, errors, exposures, by_distance, by_sun, angle_step_deg) -> list:
    """The report's figures as :func:`~fogref.compare.workers.run_jobs`' jobs."""
    jobs: list = []
    for part in parts:
        e = errors[part]
        ref = parts[part]["reference"]
        side = (ref, ref + e.signed, exposures[part], part, PART_UNITS[part])
        jobs.append(partial(plot_side_by_side, *side, out / "side_by_side" / f"{part}.png", e.valid))
        jobs.append(
            partial(
                plot_error_heatmaps, heatmap_maps(e), part, PART_UNITS[part], out / "heatmaps" / f"{part}.png"
            )
        )
    units = {p: PART_UNITS[p] for p in parts}
    distance_axis = (
        "distance to the surface [m] (log scale)",
        "error vs distance (surface pixels, log-spaced bins)",
    )
    jobs.append(
        partial(plot_binned_errors, by_distance, units, *distance_axis, out / "error_vs_distance.png", True)
    )
    if by_sun is not None:
        sun_axis = (
            "angle between view ray and sun [degrees]",
            f"error vs angle to the sun ({angle_step_deg:g}° bins, all pixels)",
        )
        jobs.append(
            partial(plot_binned_errors, by_sun, units, *sun_axis, out / "error_vs_sun_angle.png", False)
        )
    return jobs
