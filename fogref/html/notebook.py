"""A sweep's table in a notebook: :func:`sweep_table` gives a :class:`SweepTable` that Jupyter shows
as HTML (the main columns, the plots as thumbnails, the row count and the failed configurations).

``%load_ext fogref.html.notebook`` (:func:`load_ipython_extension`) shows a
:class:`~fogref.gbuffer.Truth` and a :class:`~fogref.compare.results.CheckResult` as HTML
(:func:`fogref.html.inline.truth_html`, :func:`~fogref.html.inline.check_html`): the truth and the
check hold data, this floor draws them.

Examples
--------
>>> root = Path(__file__).resolve().parents[2]
>>> t = sweep_table(root / "reports/sweeps/unreal_sun_falloff_g")
>>> len(t.frame), bool(t.frame["status"].eq("ok").all())
(48, True)
>>> "<table" in t._repr_html_()
True
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from fogref.compare.results import CheckResult
from fogref.errors import FogrefError
from fogref.gbuffer import Truth
from fogref.html.inline import NOTEBOOK_CSS, check_html, esc, png_data_uri, table_html, truth_html
from fogref.study.plot_units import HEADLINE_METRICS

#: Columns shown first (when present), after the swept parameters.
MAIN_COLUMNS = ("model", "status", *HEADLINE_METRICS)


def load_ipython_extension(ipython) -> None:
    """``%load_ext fogref.html.notebook``: IPython shows a :class:`~fogref.gbuffer.Truth` with
    :func:`~fogref.html.inline.truth_html` (part thumbnails, provenance) and a
    :class:`~fogref.compare.results.CheckResult` with :func:`~fogref.html.inline.check_html`
    (verdict, error thumbnails, rows)."""
    formatter = ipython.display_formatter.formatters["text/html"]
    formatter.for_type(Truth, truth_html)
    formatter.for_type(CheckResult, check_html)


@dataclass
class SweepTable:
    """A sweep's table: ``frame`` (pandas DataFrame of ``results.csv``), ``parameters`` (the swept
    ones), ``plots`` (the PNGs of ``plots/``) and ``folder``."""

    frame: object
    parameters: list
    plots: list
    folder: Path

    def _repr_html_(self, max_rows: int = 60) -> str:
        df = self.frame
        cols = [c for c in ("config_id", *self.parameters, *MAIN_COLUMNS) if c in df.columns]
        shown = df[cols].head(max_rows)
        failed = int((df["status"] != "ok").sum()) if "status" in df.columns else 0
        thumbs = "".join(
            f'<img title="{esc(p.stem)}" src="{png_data_uri(p)}" style="width:220px;margin:2px">'
            for p in self.plots[:12]
        )
        return (
            NOTEBOOK_CSS + f"<div><b>fogref sweep</b> {esc(self.folder.name)}: {len(df)} rows, "
            f"{failed} failed; swept {esc(', '.join(self.parameters))}<div>{thumbs}</div>"
            + table_html(cols, shown.values.tolist())
            + (f"<p>first {max_rows} rows of {len(df)}</p>" if len(df) > max_rows else "")
            + "</div>"
        )


def sweep_table(folder, table: str = "results") -> SweepTable:
    """The :class:`SweepTable` of a sweep's output folder (``results.csv``, ``sweep.json``, ``plots/``).

    A missing folder or table, or a ``sweep.json`` that is not a JSON object, is a one-line
    :class:`~fogref.errors.FogrefError` naming the file.

    >>> sweep_table("no/such/sweep")
    Traceback (most recent call last):
    ...
    fogref.errors.FogrefError: no/such/sweep/results.csv: no such file (a sweep's output folder ...
    """
    import pandas as pd

    folder = Path(folder)
    csv = folder / f"{table}.csv"
    if not csv.is_file():
        raise FogrefError(
            f"{csv}: no such file (a sweep's output folder holds {table}.csv; run fogref sweep)"
        )
    info = {}
    if (folder / "sweep.json").is_file():
        try:
            info = json.loads((folder / "sweep.json").read_text(encoding="utf-8"))
        except (ValueError, OSError) as e:
            raise FogrefError(f"{folder / 'sweep.json'}: not readable JSON ({e})") from None
        if not isinstance(info, dict):
            raise FogrefError(
                f"{folder / 'sweep.json'}: holds a {type(info).__name__}, not the sweep's JSON object"
            )
    params = list(info.get("parameters") or {})
    plots = sorted((folder / "plots").glob("*.png")) if (folder / "plots").is_dir() else []
    try:
        frame = pd.read_csv(csv)
    except (ValueError, OSError) as e:  # pandas' EmptyDataError and ParserError are ValueErrors
        raise FogrefError(
            f"{csv}: not a readable table ({str(e).splitlines()[0] if str(e) else e})"
        ) from None
    return SweepTable(frame, params, plots, folder)
