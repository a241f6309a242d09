"""A `fogref compare` report's figures, and a study's, before and after: what their drawing costs.
-> reports/benchmarks/report_figures.{json,md}

``fogref compare TRUTH --model ue4 --from-scene`` on truths of ``scenes/valley.xml`` rendered here
(64x36 and 320x180, 16 spp, seed 0), the figures drawn the command's way (worker processes, one per
core) and with ``--processes 1`` (in the command's process, where their cost is the figures' alone);
and ``fogref study TRUTH`` at 64x36 (its extra renders made once per checkout before the rounds).
Each run is a fresh process; rounds alternate ``before`` (the checkout ``--base``, its ``fogref``
package first on ``PYTHONPATH`` with this ``.venv``) and ``after`` (this checkout).  ``wall`` is
``fogref.cli.main``'s time in the child; ``figures`` is ``fogref.compare.report``'s ``run_jobs``
(the comparison's ten figures drawn or waited for; not the study's budget figure).  Identity:
every run's ``metrics.json`` equal but for paths, and every figure's PNG bytes equal.

    .venv/bin/python benchmarks/report_figures.py --base /tmp/base [--rounds 5]

(``git worktree add /tmp/base <commit>`` or a clone makes the base.)
"""

from __future__ import annotations

import statistics
import tempfile
from pathlib import Path

from _checkouts import (
    ROOT,
    before_after,
    before_after_arguments,
    identity_lines,
    kept_reading,
    metrics_without_paths,
    timed_command,
    timing_rows,
    valley_truth,
    write_report,
)

FIGURES = "fogref.compare.report:run_jobs"  # the report's figures, as write_report calls them
SIZES = ((64, 36), (320, 180))
#: (label, truth size, the command's arguments after the truth; "{out}", "{renders}" filled in)
COMPARE = ["compare", "{truth}", "--model", "ue4", "--from-scene", "--out", "{out}"]
COMMANDS = tuple(
    (f"compare, {w}x{h}{label}", (w, h), COMPARE + extra)
    for w, h in SIZES
    for label, extra in (("", []), (", --processes 1", ["--processes", "1"]))
) + (("study, 64x36", (64, 36), ["study", "{truth}", "--out", "{out}", "--renders", "{renders}"]),)


def _pngs(folder: Path) -> dict:
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*.png"))}


def main() -> None:
    a = before_after_arguments(__doc__)
    work = Path(tempfile.mkdtemp(prefix="report-figures-"))
    truths = {size: valley_truth(work, *size, 16) for size in SIZES}

    def run_all(checkout: Path, out: Path) -> dict:
        rows = {}
        for i, (label, size, args) in enumerate(COMMANDS):
            fill = {"truth": truths[size], "out": out / str(i), "renders": work / f"renders-{checkout.name}"}
            argv = [a.format(**{k: str(v) for k, v in fill.items()}) for a in args]
            rows[label] = timed_command(checkout, FIGURES, argv, codes=(0, 1, 3))
        return rows

    for mode, checkout in (("before", Path(a.base).resolve()), ("after", ROOT)):
        run_all(checkout, work / f"warm-{mode}")  # the fits cached

    def identical() -> dict:
        same = {}
        for i, (label, _, _) in enumerate(COMMANDS):
            before, after = work / "before" / str(i), work / "after" / str(i)
            same[f"{label}: metrics.json"] = metrics_without_paths(before) == metrics_without_paths(after)
            b, f = _pngs(before), _pngs(after)
            same[f"{label}: its {len(f)} figures"] = bool(f) and b == f
        return same

    def run(mode: str, checkout: Path) -> dict:
        rows = run_all(checkout, work / mode)
        return {f"{label}|{k}": v for label, row in rows.items() for k, v in row.items()}

    result = before_after(Path(a.base), a.rounds, run, identical)
    md_path = Path(a.out) / "report_figures.md"
    write_report(Path(a.out), "report_figures", result, report(result, kept_reading(md_path)))


def report(r: dict, reading: list[str] | None) -> str:
    """The Markdown page of a run (``reading``: the hand-written section kept from the last one)."""
    runs = r["runs"]
    labels = [c[0] for c in COMMANDS]
    md = [
        "# A comparison report's figures, before and after",
        "",
        "`benchmarks/report_figures.py`: `fogref compare TRUTH --model ue4 --from-scene` and "
        "`fogref study TRUTH` on truths of `scenes/valley.xml` (16 spp), each run a fresh process, "
        f"{len(runs['after'])} rounds alternating the two checkouts; {r['cores']} cores, load average "
        "(1 min) "
        + " -> ".join(f"{x:.1f}" for x in r["load_average"])
        + f".  `before`: {r['base']}; `after`: {r['after']}.  `wall`: `fogref.cli.main` in the child; "
        "`figures`: `run_jobs`, the report's ten figures drawn (`--processes 1`) or waited for (workers, "
        "one per core); not the study's budget figure.  Ratio: `before` / `after` per round, "
        "median [smallest, largest].",
        "",
    ]
    md += timing_rows(runs, [(f"{label}|wall_s", f"{label}: wall") for label in labels])
    md += timing_rows(runs, [(f"{label}|part_s", f"{label}: figures") for label in labels])[2:]

    def calls(label: str, mode: str) -> str:
        return str(int(statistics.median(x[f"{label}|calls"] for x in runs[mode])))

    per_command = [f"{label} {calls(label, 'before')} and {calls(label, 'after')}" for label in labels]
    md += [f"\n`run_jobs` calls per run, before and after: {'; '.join(per_command)}."]
    md += identity_lines(r["identical"], " (PNG bytes; metrics.json but for paths)")
    return "\n".join(md + (reading or [])) + "\n"


if __name__ == "__main__":
    main()
