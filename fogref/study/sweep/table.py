"""The sweep's table and plots: per-configuration result files gathered into CSV + Parquet, metric plots.

One row per configuration x model (a failed configuration: one row per model
with ``status = "error"`` and its error); ``plots/<metric>_vs_<parameter>.png``
shows each plotted metric against each swept parameter.
"""

from __future__ import annotations

import io
import json
import sys
from pathlib import Path

from fogref.atomic import atomic_write, figure_save_options, set_aside, write_text_atomic
from fogref.compare.plots import agg_figure
from fogref.study.plot_units import HEADLINE_METRICS, is_perceptual, metric_label, parameter_label
from fogref.study.sweep.spec import SweepSpec

__all__ = [
    "DEFAULT_PLOT_METRICS",
    "figure_png",
    "plot_files",
    "plot_table",
    "plotted_metrics",
    "read_result",
    "set_aside_result",
    "write_table",
]

#: Metrics plotted when the sweep's ``[outputs] plot_metrics`` is not given.
DEFAULT_PLOT_METRICS = HEADLINE_METRICS


def _problem(cfg: dict, result) -> str:
    """Why ``result`` is not a configuration result of ``cfg`` (``""``: it is one)."""
    if not isinstance(result, dict):
        return f"holds a {type(result).__name__}, not a result object"
    if result.get("id") != cfg["id"]:
        return f"its id {result.get('id')!r} is not {cfg['id']!r}"
    status = result.get("status")
    if status == "error":
        return "" if isinstance(result.get("error"), str) else "an error result without its 'error' text"
    if status != "ok":
        return f"status {status!r} is neither 'ok' nor 'error'"
    rows = result.get("rows")
    if not isinstance(result.get("provenance"), dict):
        return "no 'provenance' object"
    if not isinstance(rows, list) or not all(isinstance(r, dict) and "model" in r for r in rows):
        return "'rows' is not a list of model rows"
    return ""


def read_result(path, cfg: dict):
    """The result file of one configuration, or ``(None, why)`` when it is missing, unreadable or malformed
    (not JSON, ``[]``, missing fields, another configuration's id); else ``(result, "")``."""
    path = Path(path)
    if not path.is_file():
        return None, "missing"
    try:
        result = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as e:
        return None, f"not readable as JSON ({str(e).splitlines()[0]})"
    why = _problem(cfg, result)
    return (None, why) if why else (result, "")


def set_aside_result(path, why: str) -> Path:
    """Rename a malformed result file to an unused ``<name>.bad[N]`` (:func:`fogref.atomic.set_aside`)
    and warn in one line."""
    aside = set_aside(path, ".bad")
    print(
        f"fogref sweep: warning: {path}: {why}; set aside as {aside.name}, the configuration runs again",
        file=sys.stderr,
    )
    return aside


def _rows_of(cfg: dict, result: dict) -> list[dict]:
    """Table rows of one configuration's result file."""
    if "scene" not in cfg:  # a closed-form configuration
        base = {"config_id": cfg["id"], **cfg["values"]}
    else:
        base = {
            "config_id": cfg["id"],
            "scene": Path(cfg["scene"]).name,
            "scene_path": cfg["scene"],
            "scene_sha256": cfg["scene_sha256"],
            **{k: v for k, v in cfg["values"].items()},
            "overrides": json.dumps(cfg["overrides"], sort_keys=True),
            "spp": cfg["spp"],
            "seed": cfg["seed"],
        }
    for k, v in list(base.items()):
        if isinstance(v, (list, dict)):
            base[k] = json.dumps(v)
    if result.get("status") == "error":
        return [
            {
                **base,
                "model": m["label"],
                "model_name": m["name"],
                "status": "error",
                "error": result["error"],
                "truth_path": cfg.get("truth", ""),
            }
            for m in cfg["models"]
        ]
    return [{**base, **result["provenance"], "status": "ok", "error": "", **row} for row in result["rows"]]


def write_table(spec: SweepSpec, configs: list[dict], run=None) -> dict:
    """Gather the per-configuration result files into the CSV + Parquet table and the plots
    (``run``: how :func:`plot_table` draws them)."""
    import pandas as pd

    out = Path(spec.out)
    rows = []
    for cfg in configs:
        f = out / "configs" / f"{cfg['id']}.json"
        result, why = read_result(f, cfg)
        if result is not None:
            rows.extend(_rows_of(cfg, result))
        elif why != "missing":
            set_aside_result(f, why)
    df = pd.DataFrame(rows)
    csv, pq = out / f"{spec.table}.csv", out / f"{spec.table}.parquet"
    write_text_atomic(csv, df.to_csv(index=False))
    atomic_write(pq, lambda tmp: df.to_parquet(tmp, index=False))
    plots = plot_table(df, spec, out / "plots", run) if spec.plots and len(df) else []
    return {"table": csv, "parquet": pq, "rows": len(df), "plots": plots}


def plot_files(spec: SweepSpec, plot_dir: Path) -> list[Path]:
    """Every figure :func:`plot_table` may write: ``<metric>_vs_<parameter>.png``."""
    if not spec.plots:
        return []
    return [plot_dir / f"{m}_vs_{p}.png" for m in plotted_metrics(spec) for p in spec.parameters]


def plotted_metrics(spec: SweepSpec) -> list[str]:
    """The metrics a sweep plots: ``[outputs] plot_metrics``, else :data:`DEFAULT_PLOT_METRICS` (less
    the perceptual ones when the sweep leaves them out)."""
    if spec.plot_metrics:
        return list(spec.plot_metrics)
    return [m for m in DEFAULT_PLOT_METRICS if getattr(spec, "perceptual", True) or not is_perceptual(m)]


def _noise_column(df, metric: str) -> str | None:
    for suffix in ("_noise", "_stderr", ".noise", ".stderr", "_mc_noise"):
        if metric + suffix in df.columns:
            return metric + suffix
    return None


def plot_table(df, spec: SweepSpec, plot_dir: Path, run=None) -> list[Path]:
    """One figure per (metric, swept parameter): every configuration as a point, the
    mean over the other parameters as a line, one colour per model; error bars from
    the metric's Monte Carlo noise column when the table has one.  Returns the paths.

    ``run(figure_png, jobs)``: how the figures are drawn, a list of PNGs (bytes) in the order of
    ``jobs`` (each a tuple of :func:`figure_png`'s arguments: plain lists, so a worker drawing
    them needs matplotlib alone); default: one after the other here.  :func:`run_sweep` passes its
    cluster's ``map``, so the figures are drawn on its workers, side by side, and written here.
    """
    ok = df[df["status"] == "ok"] if "status" in df.columns else df
    if ok.empty:
        return []
    metrics = [m for m in plotted_metrics(spec) if m in ok.columns]
    jobs = [
        (_series(ok, param, metric), spec.name, param, metric, _log_scale(ok[metric]))
        for param in spec.parameters
        if param in ok.columns
        for metric in metrics
    ]
    pngs = run(figure_png, jobs) if run is not None else [figure_png(*job) for job in jobs]
    paths = []
    for (_, _, param, metric, _), png in zip(jobs, pngs, strict=True):
        paths.append(
            atomic_write(plot_dir / f"{metric}_vs_{param}.png", lambda tmp, b=png: Path(tmp).write_bytes(b))
        )
    return paths


def _log_scale(values) -> bool:
    """A log axis for ``values`` (a column): all positive and spanning more than a factor of 20."""
    return bool((values > 0).all() and values.max() > 20 * values.min())


def _series(ok, param: str, metric: str) -> list[dict]:
    """Per model (in name order): its configurations' ``x`` (the parameter; text when any value is
    not a number), ``y`` (the metric), ``err`` (two standard errors, None without a noise column)
    and the mean of ``y`` per value of ``x`` (``mean_x``, ``mean_y``, in the parameter's order)."""
    numeric = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in ok[param])
    noise = _noise_column(ok, metric)
    out = []
    for model, g in ok.groupby("model"):
        mean = g.groupby(param)[metric].mean()
        out.append(
            {
                "model": str(model),
                "x": (g[param] if numeric else g[param].astype(str)).tolist(),
                "y": g[metric].tolist(),
                "err": (2 * g[noise]).tolist() if noise else None,
                "mean_x": (mean.index if numeric else mean.index.astype(str)).tolist(),
                "mean_y": mean.tolist(),
            }
        )
    return out


def figure_png(series: list[dict], name: str, param: str, metric: str, log: bool) -> bytes:
    """The PNG of :func:`plot_table`'s figure of ``metric`` against ``param`` (``series``: per model,
    as :func:`_series` gives them; ``name``: the sweep's, in the title; ``log``: a log y axis),
    saved as :func:`fogref.atomic.save_figure_atomic` saves.  Drawn with matplotlib's object API;
    the title's place and the log axis's tick labels are fixed (plain numbers, not mathtext), which
    spares the layout a third of its work."""
    from matplotlib.ticker import LogFormatter

    class PlainLogFormatter(LogFormatter):
        """matplotlib's log-axis labels (which ticks get one) as plain numbers: ``0.06``, ``2e-05``."""

        def _num_to_string(self, x, vmin, vmax):  # the hook matplotlib's own subclasses override
            return f"{x:g}"

    fig = agg_figure(5.2, 3.6)
    ax = fig.subplots()
    for i, s in enumerate(series):
        colour = f"C{i}"  # one colour per model: its points, error bars and mean line
        label = f"{s['model']}: each configuration"
        if s["err"] is not None:
            ax.errorbar(
                s["x"],
                s["y"],
                yerr=s["err"],
                fmt="o",
                ms=3,
                alpha=0.4,
                capsize=2,
                color=colour,
                label=f"{label} (±2 standard errors)",
            )
        else:
            ax.plot(s["x"], s["y"], "o", ms=3, alpha=0.4, color=colour, label=label)
        ax.plot(
            s["mean_x"],
            s["mean_y"],
            "-",
            lw=1.8,
            color=colour,
            label=f"{s['model']}: mean over the other parameters",
        )
    ax.set_xlabel(parameter_label(param), fontsize=8)
    ax.set_ylabel(metric_label(metric), fontsize=8)
    if log:
        ax.set_yscale("log")
        ax.yaxis.set_major_formatter(PlainLogFormatter())
        ax.yaxis.set_minor_formatter(PlainLogFormatter())
    ax.legend(fontsize=7)
    ax.set_title(f"{name}: {metric} vs {param}", fontsize=9, y=1.0, pad=6.0)
    buf = io.BytesIO()
    fig.savefig(buf, **figure_save_options("png"))
    return buf.getvalue()
