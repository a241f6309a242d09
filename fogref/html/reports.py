"""``report.html`` of ``fogref compare``, ``fogref study``, ``fogref sweep`` and of a batch of images.

Each is one self-contained page (:mod:`fogref.html.page`) written next to the command's
Markdown: the compare page has the viewer (:mod:`fogref.html.viewer`), the check's rows with
their intervals and verdicts, the descriptive metrics with their standard errors and noise
floors, and the report's figures; the study page adds the fit and the error budget; the
sweep page the table and its plots.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from fogref.gbuffer import Truth, part_attribute
from fogref.html.inline import check_rows_html, esc, fmt, fmt_noise, table_html
from fogref.html.page import figure, verdict_badge, write_page
from fogref.html.viewer import viewer_data
from fogref.models.terms import note, unreal_field
from fogref.study.budget.report import port_vs_engine_line, validation_paragraphs
from fogref.study.plot_units import HEADLINE_METRICS

#: Columns of the descriptive metric table: (metrics.json key, heading, with its ± stderr).
METRIC_COLUMNS = (
    ("pixels", "pixels", False),
    ("rmse", "RMSE", True),
    ("rmse_noise_floor", "RMSE noise floor", False),
    ("relmse", "relMSE", True),
    ("mean_error", "mean error", True),
    ("mean_abs_error", "mean |error|", False),
    ("delta_e2000_mean", "ΔE2000 mean", False),
    ("flip_mean", "FLIP mean", False),
    ("rmse_below_noise", "below the noise", False),
)


def _pm(s: dict, key: str, with_err: bool) -> str:
    v = s.get(key)
    e = s.get(f"{key}_stderr") if with_err else None
    return fmt(v) if e is None or v is None else f"{fmt(v)} ± {fmt(e, 2)}"


def metrics_table_html(metrics: dict, units: dict) -> str:
    """The descriptive metrics of a compare report (``metrics.json``'s ``metrics``) as a table."""
    rows = []
    for part, regions in metrics.items():
        for region, s in regions.items():
            rows.append([part, units.get(part, ""), region, *(_pm(s, k, e) for k, _, e in METRIC_COLUMNS)])
    header = ["part", "units", "region", *(h for _, h, _ in METRIC_COLUMNS)]
    return '<div class="fr-wide">' + table_html(header, rows) + "</div>"


def _figures(folder: Path, names) -> list[str]:
    out = []
    for rel, caption in names:
        p = folder / rel
        if p.is_file():
            out.append(figure(p, caption))
    return out


def compare_sections(report: dict, folder: Path) -> list[str]:
    """The sections of a compare page below the viewer."""
    cand = report.get("candidate", {})
    check = report.get("check")
    s = [
        f"<p>candidate: <b>{esc(cand.get('name', ''))}</b> ({esc(cand.get('kind', ''))}); truth "
        f"<code>{esc(report.get('exr', ''))}</code>, {esc(report.get('truth', {}).get('spp'))} spp, "
        f"{report['image']['width']}×{report['image']['height']} px.</p>"
    ]
    s += [f'<p class="fr-note">warning: {esc(w)}</p>' for w in report.get("warnings", [])]
    params = (report.get("model") or {}).get("parameters")
    if isinstance(params, dict):
        name = report["model"]["name"]
        s += [
            "<h2>Model parameters</h2>",
            table_html(
                ["parameter", "value", "unit or colour space"],
                [
                    [k, json.dumps(v) if isinstance(v, (list, dict)) else v, note(name, k, v)]
                    for k, v in params.items()
                ],
            ),
        ]
    if check:
        s += [
            "<h2>Check</h2>",
            f"<p>verdict: {verdict_badge(check['verdict'])} at "
            f"{check['confidence']:.0%} confidence; intervals from the truth's per-pixel noise. A row "
            "passes when its interval lies within the tolerance, fails when wholly outside, else is "
            "inconclusive.</p>",
            '<div class="fr-wide">' + check_rows_html(check["rows"], check["confidence"]) + "</div>",
        ]
    s += [
        "<h2>Metrics</h2>",
        '<p class="fr-note">± one standard error from the truth\'s noise; the noise '
        "floor is what a perfect candidate scores against this truth.</p>",
        metrics_table_html(report.get("metrics", {}), report.get("units", {})),
    ]
    parts = list(report.get("metrics", {}))
    figs = _figures(
        folder,
        [(f"heatmaps/{p}.png", f"{p}: error heatmaps") for p in parts]
        + [
            ("error_vs_distance.png", "error vs distance"),
            ("error_vs_sun_angle.png", "error vs angle to the sun"),
        ],
    )
    if figs:
        s += ["<h2>Figures</h2>", *figs]
    return s


def write_compare_html(out_dir, truth=None, title: str | None = None) -> Path:
    """``out_dir/report.html`` from a compare report folder (``metrics.json``, ``errors.exr``, the PNGs)
    and, when given, its truth (:class:`fogref.gbuffer.Truth`: every part and its standard error in the
    viewer).  Returns the path."""
    folder = Path(out_dir)
    report = json.loads((folder / "metrics.json").read_text())
    name = report.get("candidate", {}).get("name", "candidate")
    title = title or f"fogref compare: {name} vs {Path(report.get('exr', 'truth')).name}"
    data = viewer_data(truth, folder, title=title)
    return write_page(folder / "report.html", title, compare_sections(report, folder), data)


def _csv_table(path: Path, columns=None, limit: int = 400) -> str:
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    if not rows:
        return "<p>(empty table)</p>"
    cols = [c for c in (columns or rows[0].keys()) if c in rows[0]]

    def num(v):
        try:
            return float(v) if v not in ("", None) else None
        except ValueError:
            return v

    body = [[num(r[c]) for c in cols] for r in rows[:limit]]
    more = (
        f"<p class='fr-note'>first {limit} of {len(rows)} rows; all in {esc(path.name)}</p>"
        if len(rows) > limit
        else ""
    )
    return '<div class="fr-wide">' + table_html(cols, body) + "</div>" + more


def write_sweep_html(sweep_dir, table: str = "results") -> Path:
    """``sweep_dir/report.html``: the sweep's table (its main columns) and every plot of ``plots/``."""
    folder = Path(sweep_dir)
    info = json.loads((folder / "sweep.json").read_text()) if (folder / "sweep.json").is_file() else {}
    name = (info.get("spec") or {}).get("name") or info.get("name") or folder.name
    params = list((info.get("spec") or {}).get("parameters") or info.get("parameters") or {})
    csv_path = folder / f"{table}.csv"
    rmse, *rest = HEADLINE_METRICS  # final.all.rmse, then its standard error beside it
    cols = ["config_id", *params, "model", "status", rmse, f"{rmse}_stderr", *rest]
    s = [
        f"<p>sweep <b>{esc(name)}</b>: one row per configuration × model "
        f"(<code>{esc(csv_path.name)}</code>; the Parquet file has every column).</p>"
    ]
    plots = sorted((folder / "plots").glob("*.png")) if (folder / "plots").is_dir() else []
    if plots:
        s += ["<h2>Plots</h2>", *(figure(p, p.stem.replace("_vs_", " vs ")) for p in plots)]
    if csv_path.is_file():
        s += ["<h2>Table</h2>", _csv_table(csv_path, cols)]
    return write_page(folder / "report.html", f"fogref sweep: {name}", s)


def write_study_html(study_dir, truth=None) -> Path:
    """``study_dir/report.html``: the fit, the error budget (table and plot), the comparison's
    verdicts and metrics with the viewer (from ``compare/``; the truth's every part when given)."""
    folder = Path(study_dir)
    s = []
    summary = json.loads((folder / "summary.json").read_text()) if (folder / "summary.json").is_file() else {}
    prov = summary.get("provenance", {})
    if prov:
        s += [
            f"<p>truth <code>{esc(prov.get('truth'))}</code> of <code>{esc(prov.get('scene'))}</code>, "
            f"{esc(prov.get('spp'))} spp, seed {esc(prov.get('seed'))}.</p>"
        ]
    fit = summary.get("fit", {}).get("unreal_editor") or {}
    if fit:
        s += [
            "<h2>Fit (Unreal's fog parameters)</h2>",
            table_html(
                ["property", "value", "unit or colour space"],
                [
                    [k, json.dumps(v) if isinstance(v, (list, dict)) else v, note("ue4", unreal_field(k), v)]
                    for k, v in fit.items()
                ],
            ),
        ]
    budget = folder / "budget.json"
    if budget.is_file():
        s += ["<h2>Error budget</h2>", _budget_html(json.loads(budget.read_text()))]
        s += _figures(folder, [("budget.png", "error budget")])
    data = None
    comp = folder / "compare"
    if (comp / "metrics.json").is_file():
        report = json.loads((comp / "metrics.json").read_text())
        data = viewer_data(truth, comp, title="study")
        s += compare_sections(report, comp)
    return write_page(folder / "report.html", "fogref study: Unreal's fog against the ground truth", s, data)


#: How to read a Shapley share, for the study page.
SHARES_EXPLAINED = (
    "<p>Each effect's <b>share</b> is the part of the squared error (RMSE²) it is responsible for. "
    "The model is evaluated with every combination of the effects switched to the engine's side, "
    "and an effect's share is its average contribution over all of them (its Shapley value), so "
    "no order of the effects is privileged; the shares add up to 100 %.</p>"
    "<ul><li>A <b>positive</b> share: the effect adds error. Fixing it in the engine removes about "
    "that part of the squared error.</li>"
    "<li>A <b>negative</b> share: the effect cancels part of the other effects' error. On its own "
    "it would make the image worse, but here it compensates: fixing the effects with positive "
    "shares without it leaves a larger error than fixing them together with it.</li>"
    "<li>Because effects cancel, one share can exceed 100 % or fall below −100 %: "
    "+102 %, +86 % and −115 % mean that two effects each cost about the whole error, and a third "
    "hides more than the whole error.</li></ul>"
    "<p>± is the share's Monte Carlo noise (bootstrap over pixel blocks); every value is rounded "
    "to it. A share within twice its noise of 0 is no measurable effect.</p>"
)


def _reading(share: float, noise: float) -> str:
    if abs(share) < 5e-4:
        return "none (below 0.05 %)"
    if share - 2 * noise > 0:
        return "adds error"
    if share + 2 * noise < 0:
        return "cancels part of the others"
    return "no measurable effect"


def _shapley_table(sh: dict) -> str:
    rows = sorted(sh["effects"], key=lambda r: -r["share"])
    return table_html(
        ["effect", "share of the squared error", "reading"],
        [
            [
                f"[{r['effect']}] {r['label']}",
                "0 %"
                if abs(r["share"]) < 5e-4
                else fmt_noise(100 * r["share"], 100 * r["share_noise"], " %", 1),
                _reading(r["share"], r["share_noise"]),
            ]
            for r in rows
        ],
    )


def _budget_html(budget: dict) -> str:
    """The error budget (``budget.json``) for a reader: the total error, the Shapley shares and
    how to read them, the telescoping chain and the what-if variants, each number rounded to its
    noise (``budget.md`` has the same, with every digit)."""
    t = budget.get("total", {})
    rmse = t.get("rmse", {})
    out = [
        f"<p>Total error of Unreal's fog against the truth (linear radiance): <b>RMSE "
        f"{fmt_noise(rmse.get('all'), t.get('rmse_stderr'))}</b>, {fmt(rmse.get('surface'), 3)} on "
        f"surface pixels and {fmt(rmse.get('sky'), 3)} on sky pixels; the truth's RMS is "
        f"{fmt(t.get('truth_rms'), 3)}, and the truth's own noise alone would give an RMSE of "
        f"{fmt(t.get('rmse_noise_floor'), 2)}.</p>"
    ]
    sh = budget.get("shapley")
    if sh:
        top = next((r for r in sh["effects"] if r["key"] == sh.get("largest")), None)
        out += ["<h3>What each effect costs (Shapley shares)</h3>"]
        if top is not None:
            out.append(
                f"<p>Largest: <b>[{esc(top['effect'])}] {esc(top['label'])}</b>, "
                f"{esc(fmt_noise(100 * top['share'], 100 * top['share_noise'], ' %', 1))} of the squared "
                "error.</p>"
            )
        out += [SHARES_EXPLAINED, '<div class="fr-wide">' + _shapley_table(sh) + "</div>"]
        out.append(f"<p>{esc(port_vs_engine_line('ue4'))}</p>")
    folded = budget.get("shapley_colours_in_lobe")
    if folded:
        out += [
            "<h3>The same, with the colour re-fit counted as part of the lobe</h3>",
            '<div class="fr-wide">' + _shapley_table(folded) + "</div>",
        ]
    steps = budget.get("steps") or []
    if steps:
        out += [
            "<h3>One effect at a time (telescoping chain)</h3>",
            "<p>Going from the truth to Unreal's fog, one effect switched at each step: the RMSE of "
            "the step's change to the image and its share of the squared error (in this order; the "
            "Shapley shares above do not depend on one).</p>",
            '<div class="fr-wide">'
            + table_html(
                ["effect", "RMSE of the step", "share of the squared error", "RMSE after the step"],
                [
                    [
                        f"[{st['effect']}] {st['label']}",
                        fmt_noise(st["rmse"]["all"], st.get("rmse_stderr")),
                        fmt_noise(100 * st["share"], 100 * (st.get("noise") or {}).get("share", 0.0), " %", 1)
                        if (st.get("noise") or {}).get("share")
                        else f"{100 * st['share']:+.1f} %",
                        fmt(st.get("rmse_vs_truth_after"), 4),
                    ]
                    for st in steps
                ],
            )
            + "</div>",
        ]
    checks = validation_paragraphs(budget)
    if checks:
        out += ["<h3>How the budget was checked</h3>", *(f"<p>{esc(t)}</p>" for t in checks)]
    what_if = budget.get("what_if") or []
    if what_if:
        out += [
            "<h3>What if (one engine setting changed)</h3>",
            table_html(
                ["variant", "RMSE", "change of the RMSE"],
                [
                    [w["variant"], fmt_noise(w["rmse"], w.get("rmse_stderr")), f"{w['delta_rmse']:+.2g}"]
                    for w in what_if
                ],
            ),
        ]
    return "\n".join(out)


def write_batch_html(out_dir, rows: list[dict], truth_path: str, columns) -> Path:
    """``out_dir/report.html`` of a batch: one row per image, the verdict, each check row over all
    pixels as ``estimate [low, high]`` (every region's rows are in ``batch.csv``), the descriptive
    metrics of ``final``, and links to each image's own report."""
    folder = Path(out_dir)
    keys = [c for c in columns if "/all:" in c and "." not in c.split(":")[1]]
    desc = [c for c in columns if c.startswith("final.all.")]
    body = []
    for r in rows:
        cells = [r["image"], r.get("verdict")]
        for k in keys:
            e, lo, hi = r.get(k), r.get(k + ".low"), r.get(k + ".high")
            cells.append("—" if e is None else f"{fmt(e)} [{fmt(lo)}, {fmt(hi)}] {r.get(k + '.verdict')}")
        body.append(cells + [r.get(c) for c in desc])
    cls = ["v-" + str(r.get("verdict", "")) for r in rows]
    s = [
        f"<p>{len(rows)} image(s) against <code>{esc(truth_path)}</code>; each image's full report "
        "(viewer, figures) is in its own folder:</p><ul>"
        + "".join(
            f'<li><a href="{esc(r["report"])}/report.html">{esc(r["image"])}</a>: '
            f"{verdict_badge(str(r.get('verdict')))}</li>"
            if r.get("report")
            else f"<li>{esc(r['image'])}: {verdict_badge('error')} {esc(str(r.get('error')))}</li>"
            for r in rows
        )
        + "</ul>",
        "<h2>Table</h2>",
        "<p class='fr-note'>estimate [interval] verdict per part over all pixels; "
        "batch.csv has every region.</p>",
        '<div class="fr-wide">' + table_html(["image", "verdict", *keys, *desc], body, cls) + "</div>",
    ]
    return write_page(folder / "report.html", "fogref compare: a batch of images", s)


def write_diff_html(out_dir, result, a, b) -> Path:
    """``out_dir/report.html`` of :func:`fogref.compare.diff.diff`: the viewer (A as the truth, B as
    the candidate: its error is B - A) and the rows tested."""
    folder = Path(out_dir)
    truth = a if isinstance(a, Truth) else b if isinstance(b, Truth) else None
    ch: dict = {}
    for part, e in result.errors.items():
        name = part_attribute(part)
        for i, c in enumerate("RGB"):
            ch[f"{name}.error.{c}"] = e[..., i]
        valid = truth.surface_valid if (truth is not None and part == "final") else np.ones(e.shape[:2], bool)
        ch[f"{name}.valid"] = valid.astype(np.float32)
        ch[f"{name}.noise"] = np.zeros(e.shape[:2])
        if truth is None:
            for i, c in enumerate("RGB"):
                ch[f"{name}.reference.{c}"] = a[..., i]
    if truth is None:
        ch["hit"] = np.ones(a.shape[:2])
        ch["distance"] = np.ones(a.shape[:2])
    title = f"fogref diff: {result.verdict}"
    data = viewer_data(truth, None, title=title, channels=ch, stderr=truth is not None)
    s = [
        f"<p>B = <code>{esc(result.b)}</code> ({esc(result.kinds[1])}) against A = <code>{esc(result.a)}"
        f"</code> ({esc(result.kinds[0])}): {verdict_badge(result.verdict)}</p>",
        "<pre>" + esc("\n".join(result.lines())) + "</pre>",
    ]
    if result.rows:
        s += ["<h2>Rows tested</h2>", check_rows_html(result.rows, result.row_confidence)]
    return write_page(folder / "report.html", title, s, data)
