"""`fogref compare` and `fogref study` before and after: what a small comparison's imports cost.
-> reports/benchmarks/compare_imports.{json,md}

Three commands on truths of ``scenes/valley.xml`` rendered here (16 spp, seed 0), each run a fresh
process; rounds alternate ``before`` (the checkout ``--base``, its ``fogref`` package first on
``PYTHONPATH`` with this ``.venv``) and ``after`` (this checkout):

* ``fogref compare TRUTH --model ue4 --from-scene`` at 64x36 and 320x180 (Unreal's fit cached by
  a run of each checkout before the timed rounds);
* ``fogref compare TRUTH --image ENGINE.png`` at 64x36: an 8-bit sRGB picture (the truth's final
  image through :func:`fogref.display.tone_map`, exposure 1), read through the sRGB decoding;
* ``fogref study TRUTH`` at 64x36 (its extra renders made once per checkout before the rounds).

In each run the ΔE2000 maps (``delta_e2000_maps`` as ``fogref.compare.error_maps`` calls it,
which imported colour-science on its first call before) are timed apart, and the run lists which
of colour-science, pandas and matplotlib's pyplot its process imported.  ``wall`` is
``fogref.cli.main``'s time in the child, after the interpreter's start.  Identity: every
command's ``metrics.json`` equal but for paths, between the checkouts.

    .venv/bin/python benchmarks/compare_imports.py --base /tmp/base [--rounds 5]

(``git worktree add /tmp/base <commit>`` or a clone makes the base.)
"""

from __future__ import annotations

import statistics
import tempfile
from pathlib import Path

import numpy as np
from _checkouts import (
    ROOT,
    before_after,
    before_after_arguments,
    identity_lines,
    metrics_without_paths,
    timed_command,
    timing_rows,
    valley_truth,
    write_report,
)
from PIL import Image

DELTA_E = "fogref.compare.error_maps:delta_e2000_maps"  # as error_maps calls it, timed apart in each run
#: (label, truth size, the command's arguments after the truth; "{out}", "{png}", "{renders}" filled in)
COMMANDS = (
    ("compare --from-scene, 64x36", (64, 36), ["--model", "ue4", "--from-scene", "--out", "{out}"]),
    ("compare --from-scene, 320x180", (320, 180), ["--model", "ue4", "--from-scene", "--out", "{out}"]),
    ("compare --image (sRGB PNG), 64x36", (64, 36), ["--image", "{png}", "--out", "{out}"]),
    ("study, 64x36", (64, 36), ["--out", "{out}", "--renders", "{renders}"]),
)
#: compare's exit codes: 0 pass, 1 fail, 3 inconclusive (an engine picture against a truth fails)
CODES = (0, 1, 3)


def _engine_png(truth: Path) -> Path:
    """An engine's 8-bit sRGB picture of ``truth``: its final image tone-mapped at exposure 1."""
    from fogref.display import tone_map
    from fogref.exrio import read_exr

    channels, _ = read_exr(truth)
    rgb = np.stack([channels[c] for c in ("R", "G", "B")], axis=-1)
    png = truth.with_suffix(".png")
    Image.fromarray(np.floor(255 * tone_map(rgb, 1.0)).astype(np.uint8)).save(png)
    return png


def main() -> None:
    a = before_after_arguments(__doc__)
    work = Path(tempfile.mkdtemp(prefix="compare-imports-"))
    truths = {size: valley_truth(work, *size, 16) for size in {c[1] for c in COMMANDS}}
    png = _engine_png(truths[(64, 36)])

    def run_all(mode: str, checkout: Path, out: Path) -> dict:
        rows = {}
        for i, (label, size, args) in enumerate(COMMANDS):
            fill = {"out": out / str(i), "png": png, "renders": work / f"renders-{mode}"}
            argv = ["study" if label.startswith("study") else "compare", truths[size]]
            argv += [str(x).format(**{k: str(v) for k, v in fill.items()}) for x in args]
            rows[label] = timed_command(checkout, DELTA_E, argv, codes=CODES)
        return rows

    for mode, checkout in (("before", Path(a.base).resolve()), ("after", ROOT)):
        run_all(mode, checkout, work / f"warm-{mode}")  # the fits cached, the study's renders made

    def identical() -> dict:
        return {
            label: metrics_without_paths(work / "before" / str(i))
            == metrics_without_paths(work / "after" / str(i))
            for i, (label, _, _) in enumerate(COMMANDS)
        }

    def run(mode: str, checkout: Path) -> dict:
        rows = run_all(mode, checkout, work / mode)
        flat = {f"{label}|{k}": v for label, row in rows.items() for k, v in row.items()}
        return flat

    result = before_after(Path(a.base), a.rounds, run, identical)
    write_report(Path(a.out), "compare_imports", result, report(result))


def report(r: dict) -> str:
    """The Markdown page of a run."""
    runs = r["runs"]
    labels = [c[0] for c in COMMANDS]
    md = [
        "# A small comparison's imports, before and after",
        "",
        f"`benchmarks/compare_imports.py`: `fogref compare` and `fogref study` on truths of "
        f"`scenes/valley.xml` (16 spp), each run a fresh process, {len(runs['after'])} rounds "
        f"alternating the two checkouts; {r['cores']} cores, load average (1 min) "
        + " -> ".join(f"{x:.1f}" for x in r["load_average"])
        + f".  `before`: {r['base']}; `after`: {r['after']}.  The times are `fogref.cli.main`'s "
        "wall time in the child, after the interpreter's start; the ΔE2000 maps' are "
        "`delta_e2000_maps`'s calls in the command's process together, timed inside the same "
        "runs.  Ratio: `before` / `after` per round, median [smallest, largest].",
        "",
    ]
    md += timing_rows(runs, [(f"{label}|wall_s", label) for label in labels])
    md += ["", "| command: its ΔE2000 maps | before [s], median | after [s], median | calls per run |"]
    md += ["|---|---:|---:|---:|"]
    for label in labels:
        before, after = (
            statistics.median(run[f"{label}|part_s"] for run in runs[m]) for m in ("before", "after")
        )
        calls = int(statistics.median(run[f"{label}|calls"] for run in runs["after"]))
        md.append(f"| {label} | {before:.3f} | {after:.3f} | {calls} |")
    md += ["", "Imported by the command's process (every run alike):", ""]
    md += ["| command | before | after |", "|---|---|---|"]
    for label in labels:
        seen = [
            sorted({", ".join(run[f"{label}|imported"]) or "none" for run in runs[m]})
            for m in ("before", "after")
        ]
        md.append(f"| {label} | {' / '.join(seen[0])} | {' / '.join(seen[1])} |")
    md += identity_lines(r["identical"], " (`metrics.json` but for paths)")
    return "\n".join(md)


if __name__ == "__main__":
    main()
