"""Report figures: error heatmaps, side-by-side pictures, errors binned by distance/angle.

Uses matplotlib's object API with the Agg canvas (no pyplot, no global backend
change, no display needed).  Every figure is written atomically.
Image row 0 is the top of the picture, as in the EXR.
Drawing a figure is matplotlib laying it out in Python, on one core: about 0.2-0.3 s for a heatmap
figure and 0.3-0.4 s for a binned one, whatever the image size (:mod:`fogref.compare.workers` draws
a report's figures side by side).  Every panel title is placed at ``y=1.0``: where matplotlib is
left to place it, it measures the axes' decorations to clear them, in each of the two layouts of a
tight bounding box, and the panels here have none above them, so it lands there anyway (the same
pixels, ``reports/benchmarks/report_figures.md``).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from fogref.atomic import save_figure_atomic
from fogref.compare.error_maps import ErrorMaps
from fogref.display import tone_map


def heatmap_maps(errors: ErrorMaps) -> ErrorMaps:
    """``errors`` without what :func:`plot_error_heatmaps` does not draw: the noise model's
    ``(H, W, 3, 3)`` covariance, the relMSE weights and the noise floors' maps (less to send to a
    worker)."""
    return replace(errors, noise_cov=None, relative_weight=None, delta_e2000_noise=None, flip_noise=None)


def agg_figure(width_in: float, height_in: float):
    """A matplotlib ``Figure`` of ``width_in`` x ``height_in`` inches on its own Agg canvas (no
    pyplot: nothing global changes, and nothing to close)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width_in, height_in))
    FigureCanvasAgg(fig)
    return fig


def _panel_size(shape: tuple[int, int]) -> tuple[float, float]:
    h, w = shape
    aspect = h / max(w, 1)
    return 4.0, max(1.5, 4.0 * aspect)


def _robust_max(m: np.ndarray) -> float:
    """Upper colour limit: the 99.5th percentile of finite values (> 0), else 1."""
    v = m[np.isfinite(m)]
    if v.size == 0:
        return 1.0
    hi = float(np.percentile(v, 99.5))
    if not hi > 0:
        hi = float(v.max())
    return hi if hi > 0 else 1.0


def plot_error_heatmaps(errors: ErrorMaps, part: str, units: str, path) -> Path:
    """Five heatmaps of one part (three without the perceptual maps), each with a colour bar and its units.

    The signed error ``model − reference`` (mean over RGB) [``units``] on the
    diverging ``RdBu_r`` map centred at 0 with symmetric limits (red: the model is
    too bright, blue: too dark); |error| (mean over RGB) [``units``], relative
    squared error [1], ΔE2000 [1] and HDR-FLIP [0..1].  Colour limits: the 99.5th
    percentile (FLIP: 0 to 1), so a few outliers do not flatten the map.  Excluded
    pixels (``errors.valid`` False) are grey.
    """
    signed = errors.signed.mean(-1)
    lim = _robust_max(np.abs(signed[errors.valid])) if errors.valid.any() else 1.0  # symmetric limits
    panels = [
        (signed, "candidate − truth (signed)", f"[{units}]", "RdBu_r", -lim, lim),
        (errors.absolute, "|candidate − truth|", f"[{units}]", "viridis", 0.0, _robust_max(errors.absolute)),
        (
            errors.relative_squared,
            "relative squared error",
            "[1]",
            "viridis",
            0.0,
            _robust_max(errors.relative_squared),
        ),
    ]
    if errors.delta_e2000 is not None:  # the perceptual maps, unless the comparison left them out
        panels.append((errors.delta_e2000, "ΔE2000", "[1]", "viridis", 0.0, _robust_max(errors.delta_e2000)))
    if errors.flip is not None:
        panels.append((errors.flip, "HDR-FLIP", "[0..1]", "magma", 0.0, 1.0))
    pw, ph = _panel_size(errors.absolute.shape)
    fig = agg_figure(pw * len(panels) + 1.0, ph + 0.8)
    axes = fig.subplots(1, len(panels))
    fig.subplots_adjust(wspace=0.3)
    import matplotlib

    for ax, (m, title, unit, cmap, vmin, vmax) in zip(axes, panels):
        cm = matplotlib.colormaps[cmap].with_extremes(bad="0.6")
        im = ax.imshow(
            np.ma.masked_array(m, ~errors.valid), cmap=cm, vmin=vmin, vmax=vmax, interpolation="nearest"
        )
        ax.set_title(f"{title} {unit}", fontsize=9, y=1.0)
        ax.set_axis_off()
        fig.colorbar(im, ax=ax, fraction=0.046, pad=0.04).set_label(unit, fontsize=8)
    excluded = int(np.count_nonzero(~errors.valid))
    fig.suptitle(
        f"{part}: per-pixel error of the candidate (model or engine image)"
        + (f" (grey: {excluded} excluded pixels)" if excluded else ""),
        fontsize=10,
    )
    return save_figure_atomic(fig, path)


def plot_side_by_side(reference, model, exposure: float, part: str, units: str, path, valid=None) -> Path:
    """Reference | model | |model − reference|, all through one tone map.

    Tone map: :func:`fogref.display.tone_map` with the shared ``exposure``
    [1/``units``] (exposure, clip to [0, 1], sRGB OETF).  ``valid``: ``(H, W)`` bool;
    pixels outside it (excluded from the metrics) are drawn magenta in the model and
    error panels.
    """
    reference, model = np.asarray(reference, dtype=np.float64), np.asarray(model, dtype=np.float64)
    valid = np.ones(reference.shape[:2], dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    magenta = np.array([1.0, 0.0, 1.0])
    model_img = tone_map(model, exposure)
    error_img = tone_map(np.abs(model - reference), exposure)
    model_img[~valid], error_img[~valid] = magenta, magenta
    images = [
        (tone_map(reference, exposure), "truth"),
        (model_img, "candidate"),
        (error_img, "|candidate − truth|"),
    ]
    pw, ph = _panel_size(reference.shape[:2])
    fig = agg_figure(pw * 3, ph + 0.8)
    axes = fig.subplots(1, 3)
    for ax, (img, title) in zip(axes, images):
        ax.imshow(img, interpolation="nearest")
        ax.set_title(title, fontsize=9, y=1.0)
        ax.set_axis_off()
    note = "" if valid.all() else "; magenta: excluded"
    fig.suptitle(
        f"{part} — shared tone map: ×{exposure:.4g} [1/{units}], clip to [0, 1], sRGB OETF{note}", fontsize=10
    )
    return save_figure_atomic(fig, path)


def _floats(values) -> np.ndarray:
    """A binned list (None for a bin empty for that part) as floats with NaN gaps (plotting only)."""
    return np.array([np.nan if v is None else v for v in values], dtype=np.float64)


def plot_binned_errors(
    binned: dict, part_units: dict[str, str], xlabel: str, title: str, path, log_x: bool
) -> Path:
    """Errors per bin of a coordinate, one line per part, in a 2×2 grid.

    Panels: RMSE of the radiance parts [their units], RMSE of dimensionless parts
    [1] (each with its noise floor dashed), mean ΔE2000 [1], mean HDR-FLIP [0..1].  ``binned``: the output of
    :func:`fogref.compare.binning.binned_errors`; ``part_units``: part -> units
    ("1" marks a dimensionless part).  Markers sit at the bin centres.
    """
    fig = agg_figure(10.0, 7.0)
    axes = fig.subplots(2, 2, sharex=True).ravel()
    x = np.asarray(binned.get("center", []), dtype=np.float64)
    radiance_units = sorted({u for u in part_units.values() if u != "1"}) or ["radiance"]
    labels = [
        f"RMSE [{', '.join(radiance_units)}]",
        "RMSE, dimensionless parts [1]",
        "mean ΔE2000 [1]",
        "mean HDR-FLIP [0..1]",
    ]
    for i, (part, stats) in enumerate(binned.get("parts", {}).items()):
        style = {"marker": "o", "ms": 3, "label": part, "color": f"C{i}"}  # one colour per part
        dimensionless = part_units.get(part) == "1"
        ax = axes[1 if dimensionless else 0]
        ax.plot(x, _floats(stats["rmse"]), **style)
        if "rmse_noise_floor" in stats:
            ax.plot(
                x,
                _floats(stats["rmse_noise_floor"]),
                ls="--",
                lw=1,
                color=style["color"],
                label=f"{part} noise floor",
            )
        for ax, key in ((axes[2], "delta_e2000_mean"), (axes[3], "flip_mean")):
            if key in stats:  # not when the comparison left the perceptual metrics out
                ax.plot(x, _floats(stats[key]), **style)
    stats_of = binned.get("parts", {}).values()
    left_out = bool(stats_of) and not any("flip_mean" in stats for stats in stats_of)  # perceptual off
    for k, (ax, label) in enumerate(zip(axes, labels)):
        ax.set_ylabel(label, fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        if log_x:
            ax.set_xscale("log")
        if ax.lines:
            ax.legend(fontsize=8)
        else:
            empty = "not computed (no perceptual metrics)" if k >= 2 and left_out else "no data"
            ax.text(0.5, 0.5, empty, transform=ax.transAxes, ha="center", va="center")
    for ax in axes[2:]:
        ax.set_xlabel(xlabel, fontsize=9)
    fig.suptitle(title, fontsize=10)
    return save_figure_atomic(fig, path)
