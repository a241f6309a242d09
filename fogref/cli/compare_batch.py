"""``fogref compare TRUTH --image a.exr b.exr ...`` (or a glob): several engine images, one table.

Each image is checked (:func:`fogref.compare.check.check`) and reported on its own, as a single
``--image`` run would (``<out>/<image stem>/``: ``index.md``, ``report.html``, ``metrics.json``,
...), and the batch gathers one row per image, with every check row's estimate, interval
and verdict and the descriptive metrics of ``final``/``all``, into ``<out>/batch.csv``,
``<out>/batch.json`` and ``<out>/report.html``.  An image that cannot be checked (unreadable, the
wrong resolution) is a row with its error (verdict ``error``), and the batch goes on with the
others.  Exit code: the worst image's (2 if any is in error, else 1 if any fails, else 3 if any
is inconclusive, mapped by ``--inconclusive``, else 0).
"""

from __future__ import annotations

import csv
import glob
import io
import json
import sys
from pathlib import Path

from fogref import params
from fogref.atomic import write_text_atomic
from fogref.cli.checks import Check
from fogref.cli.spec import UsageError
from fogref.compare.check import check
from fogref.compare.foreign import IMAGE_SUFFIXES, load_engine_images
from fogref.compare.gate import exit_code
from fogref.compare.report import compare_images
from fogref.errors import FogrefError
from fogref.gbuffer import load_truth
from fogref.html.reports import write_batch_html, write_compare_html

#: Descriptive metrics of the ``final`` part over all pixels added to each row (metrics.json keys).
DESCRIPTIVE = (
    "rmse",
    "rmse_stderr",
    "rmse_noise_floor",
    "relmse",
    "relmse_stderr",
    "mean_error",
    "mean_error_stderr",
    "delta_e2000_mean",
    "flip_mean",
)


class ImageList(Check):
    """``--image FILE [FILE ...]``: one or more images, a pattern (``'renders/*.exr'``) expanded
    in sorted order to the image files it matches (suffix of
    :data:`fogref.compare.foreign.IMAGE_SUFFIXES`: not the folders, tables and pages of an earlier
    batch); one image gives its path (the single-image mode), several a tuple.

    >>> ImageList().parse(["a.exr"], "--image", "demo")
    'a.exr'
    >>> ImageList().parse(["a.exr", "b.png"], "--image", "demo")
    ('a.exr', 'b.png')
    """

    metavar = "FILE"
    role = "input"  # the files a command reads (fogref.cli.spec.check_paths)

    def parse(self, raw, name, source):
        raw = [raw] if isinstance(raw, str) else list(raw)
        out: list[str] = []
        for r in raw:
            if any(c in r for c in "*?["):
                hits = sorted(
                    h for h in glob.glob(r) if Path(h).is_file() and Path(h).suffix.lower() in IMAGE_SUFFIXES
                )
                if not hits:
                    raise FogrefError(
                        f"{source}: parameter '{name}': the pattern '{r}' matches no file "
                        f"of an image type ({', '.join(IMAGE_SUFFIXES)})"
                    )
                out.extend(hits)
            else:
                out.append(r)
        out = [str(params.path(p, name, source=source)) for p in out]
        if len(set(out)) != len(out):
            raise FogrefError(f"{source}: parameter '{name}': an image is given twice")
        return out[0] if len(out) == 1 else tuple(out)


def _stem_names(paths) -> list[str]:
    """Report folder names of the images: their stems, made unique with their parent folders.

    >>> _stem_names(["x/a.exr", "y/a.exr", "b.png"])
    ['x_a', 'y_a', 'b']
    """
    stems = [Path(p).stem for p in paths]
    return [f"{Path(p).parent.name}_{s}" if stems.count(s) > 1 else s for p, s in zip(paths, stems)]


def batch_rows(results) -> tuple[list[dict], list[str]]:
    """Table rows (one per image) and columns from ``(image, folder name, CheckResult, report)``
    tuples: the verdict, each check row's ``estimate``/``low``/``high``/``verdict`` under
    ``part/region:metric``, and :data:`DESCRIPTIVE` of ``final``/``all``."""
    rows, cols = [], ["image", "report", "verdict", "error"]
    for image, name, result, report in results:
        if isinstance(result, Exception):
            rows.append({"image": image, "report": "", "verdict": "error", "error": str(result)})
            continue
        row = {"image": image, "report": name, "verdict": result.verdict, "error": ""}
        for r in result.rows:
            key = f"{r.part}/{r.region}:{r.metric}"
            for k, v in (("", r.estimate), (".low", r.low), (".high", r.high), (".verdict", r.verdict)):
                row[key + k] = v
        final = report.get("metrics", {}).get("final") or report.get("metrics", {}).get("composite") or {}
        for k in DESCRIPTIVE:
            row[f"final.all.{k}"] = (final.get("all") or {}).get(k)
        rows.append(row)
        cols += [c for c in row if c not in cols]
    return rows, cols


def run_batch(o, given, default_out, options: dict) -> int:
    """Check and report every image of ``o.image`` (a tuple) against the truth with ``options`` (of
    :func:`fogref.compare.check.check`); write the table into ``o.out``, else ``default_out``."""
    for opt in ("transmittance", "inscatter", "fog_colour", "json", "junit"):
        if opt in given:
            flag = "--" + opt.replace("_", "-")
            raise UsageError(
                f"fogref compare: {flag} does not apply to several --image files "
                "(the batch writes batch.json and batch.csv)"
            )
    truth = load_truth(o.exr)
    out = Path(o.out) if o.out else Path(default_out)
    results = []
    for image, name in zip(o.image, _stem_names(o.image)):
        try:
            imgs = load_engine_images(
                image, encoding=o.encoding, exposure=o.exposure, shape=truth.shape, truth_name=str(o.exr)
            )
        except (FogrefError, OSError) as e:  # this image only: the others are still checked
            print(
                f"fogref compare: error: {'' if str(image) in str(e) else f'{image}: '}{e}", file=sys.stderr
            )
            results.append((image, name, e, {}))
            continue
        result = check(truth, imgs, **options)
        report = compare_images(
            truth,
            imgs,
            out / name,
            figures=not o.no_figures,
            perceptual=not o.no_perceptual,
            processes=o.processes,
            check=result,
        )
        write_compare_html(out / name, truth)
        for w in report["warnings"]:
            print(f"fogref compare: warning: {image}: {w}", file=sys.stderr)
        print(f"{image}: {result.verdict}")
        results.append((image, name, result, report))
    rows, cols = batch_rows(results)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=cols, lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    write_text_atomic(out / "batch.csv", buf.getvalue())
    codes = [
        2 if isinstance(r, Exception) else exit_code(r.verdict, o.inconclusive) for _, _, r, _ in results
    ]
    code = next((c for c in (2, 1, 3) if c in codes), 0)
    write_text_atomic(
        out / "batch.json",
        json.dumps(
            {"truth": str(o.exr), "exit_code": code, "columns": cols, "rows": rows}, indent=2, allow_nan=False
        )
        + "\n",
    )
    write_batch_html(out, rows, str(o.exr), cols)
    print(f"table: {out / 'batch.csv'}; report: {out / 'report.html'}")
    print(f"exit code {code}")
    return code
