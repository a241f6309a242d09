"""`fogref study` before and after: the command and its Shapley budgets.
-> reports/benchmarks/study_speed.{json,md}

``fogref study TRUTH --out OUT --renders RENDERS`` on a truth of ``scenes/valley.xml`` rendered
here (320x180, 16 spp, seed 0: the scene's own size), each run a fresh process; rounds alternate
``before`` (the checkout ``--base``, its ``fogref`` package first on ``PYTHONPATH`` with this
``.venv``) and ``after`` (this checkout).  The budget's extra renders (the sun-less truths and a
second seed) are made once per checkout before the timed rounds (``--renders``, a cache), so the
rounds time the study itself.  In each run the four Shapley budgets
(``fogref.study.budget.shapley_budget``: all coalitions, and the colours in the lobe, for two seeds)
are timed apart, by a wrapper the child process puts around it.  Identity: ``budget.json`` (but for
its input paths and the package's docstring), ``fit.json`` and ``compare/metrics.json`` of both
equal.

    .venv/bin/python benchmarks/study_speed.py --base /tmp/study-base [--rounds 3]

(``git worktree add /tmp/study-base <commit>`` makes the base.)
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

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

SIZE = (320, 180, 16)  # width, height, spp
BUDGET = "fogref.study.budget:shapley_budget"  # timed apart in each run


def _study(checkout: Path, truth: Path, out: Path, renders: Path) -> dict:
    return timed_command(checkout, BUDGET, ["study", truth, "--out", out, "--renders", renders])


def _numbers(folder: Path, name: str):
    """A result file of a study without what names its inputs or documents the package."""
    if name == "compare/metrics.json":
        return metrics_without_paths(folder)
    doc = json.loads((folder / name).read_text())
    if name == "budget.json":
        doc.pop("inputs", None), doc.pop("method", None)
    return doc


def main() -> None:
    a = before_after_arguments(__doc__)
    work = Path(tempfile.mkdtemp(prefix="study-speed-"))
    w, h, spp = SIZE
    truth = valley_truth(work, w, h, spp)
    for mode, checkout in (("before", Path(a.base).resolve()), ("after", ROOT)):
        _study(checkout, truth, work / f"warm-{mode}", work / f"renders-{mode}")  # their extra renders

    def identical() -> dict:
        files = ("budget.json", "fit.json", "compare/metrics.json")
        return {f: _numbers(work / "before", f) == _numbers(work / "after", f) for f in files}

    run = lambda mode, checkout: _study(checkout, truth, work / mode, work / f"renders-{mode}")
    result = {"size": f"{w}x{h}, {spp} spp", **before_after(Path(a.base), a.rounds, run, identical)}
    write_report(Path(a.out), "study_speed", result, report(result))


def report(r: dict) -> str:
    """The Markdown page of a run."""
    runs = r["runs"]
    md = [
        "# `fogref study` before and after",
        "",
        f"`benchmarks/study_speed.py`: `fogref study TRUTH` on a truth of `scenes/valley.xml` "
        f"({r['size']}), its extra renders made once before the timed runs, each run a fresh process, "
        f"{len(runs['after'])} rounds alternating the two; {r['cores']} cores, load average (1 min) "
        + " -> ".join(f"{x:.1f}" for x in r["load_average"])
        + f".  `before`: {r['base']}; `after`: {r['after']}.  The {runs['after'][0]['calls']} Shapley "
        "budgets (all coalitions and the colours in the lobe, for each of two seeds) are timed inside "
        "the same runs.  Ratio: `before` / `after` per round, median [smallest, largest].",
        "",
    ]
    md += timing_rows(runs, (("wall_s", "the command"), ("part_s", "its Shapley budgets")))
    how = " (`budget.json` but for its input paths and the package's docstring, `metrics.json` but for paths)"
    md += identity_lines({f"`{f}`": ok for f, ok in r["identical"].items()}, how)
    return "\n".join(md)


if __name__ == "__main__":
    main()
