"""`fogref compare` on a large truth, before and after: the command and its metrics table.
-> reports/benchmarks/compare_large.{json,md}

``fogref compare TRUTH --model ue4 --from-scene --no-figures`` on a truth of
``scenes/valley.xml`` rendered here (960x540, 4 spp, seed 0), each run a fresh process;
rounds alternate ``before`` (the checkout ``--base``, its ``fogref`` package first on
``PYTHONPATH`` with this ``.venv``) and ``after`` (this checkout).  In each run the metrics
table (``fogref.compare.report._metrics_table``: every part's summary over every region) is
timed apart, by a wrapper the child process puts around it.  Identity: ``metrics.json`` and
``check.json`` of both equal but for paths.

    .venv/bin/python benchmarks/compare_large.py --base /tmp/compare-base [--rounds 3]

(``git worktree add /tmp/compare-base <commit>`` makes the base.)
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
    timed_command,
    timing_rows,
    valley_truth,
    write_report,
)

SIZE = (960, 540, 4)  # width, height, spp
TABLE = "fogref.compare.report:_metrics_table"  # timed apart in each run


def _compare(checkout: Path, truth: Path, out: Path) -> dict:
    args = ["compare", truth, "--model", "ue4", "--from-scene", "--no-figures", "--out", out]
    return timed_command(checkout, TABLE, args, codes=(0, 1, 3))  # pass, fail, inconclusive: a verdict


def _without_paths(x):
    if isinstance(x, dict):
        return {k: _without_paths(v) for k, v in x.items() if k not in ("path", "exr", "out_dir")}
    if isinstance(x, list):
        return [_without_paths(v) for v in x]
    return x


def main() -> None:
    a = before_after_arguments(__doc__)
    work = Path(tempfile.mkdtemp(prefix="compare-large-"))
    w, h, spp = SIZE
    truth = valley_truth(work, w, h, spp)
    _compare(ROOT, truth, work / "warm")  # the page cache and Python's bytecode, once

    def identical() -> dict:
        return {
            f: _without_paths(json.loads((work / "before" / f).read_text()))
            == _without_paths(json.loads((work / "after" / f).read_text()))
            for f in ("metrics.json", "check.json")
        }

    run = lambda mode, checkout: _compare(checkout, truth, work / mode)
    result = {"size": f"{w}x{h}, {spp} spp", **before_after(Path(a.base), a.rounds, run, identical)}
    write_report(Path(a.out), "compare_large", result, report(result))


def report(r: dict) -> str:
    """The Markdown page of a run."""
    runs = r["runs"]
    md = [
        "# `fogref compare` on a large truth, before and after",
        "",
        f"`benchmarks/compare_large.py`: `fogref compare TRUTH --model ue4 --from-scene --no-figures` on a "
        f"truth of `scenes/valley.xml` ({r['size']}), each run a fresh process, {len(runs['after'])} rounds "
        f"alternating the two; {r['cores']} cores, load average (1 min) "
        + " -> ".join(f"{x:.1f}" for x in r["load_average"])
        + f".  `before`: {r['base']}; `after`: {r['after']}.  The metrics table (every part's summary over "
        "every region) is timed inside the same runs.  Ratio: `before` / `after` per round, median "
        "[smallest, largest].",
        "",
    ]
    md += timing_rows(runs, (("wall_s", "the command"), ("part_s", "its metrics table")))
    md += identity_lines({f"`{f}`": ok for f, ok in r["identical"].items()}, " (but for paths)")
    return "\n".join(md)


if __name__ == "__main__":
    main()
