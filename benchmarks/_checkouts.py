"""What the benchmarks that compare checkouts share: a checkout's commit, the environment that
runs its ``fogref`` package, a command run there with one function timed apart, rounds that
alternate the checkouts, per-round ratios, and the report's two files."""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

from fogref.atomic import write_text_atomic

#: This checkout (the benchmarks' "after").
ROOT = Path(__file__).resolve().parents[1]
#: The committed example sweep (48 configurations), relative to a checkout.
EXAMPLE_SWEEP = Path("reports") / "sweeps" / "unreal_sun_falloff_g" / "SWEEP.toml"
#: ``python -c FOGREF_MAIN ARGS`` runs ``fogref ARGS`` with the package first on ``sys.path``.
FOGREF_MAIN = "import sys; from fogref.cli import main; sys.exit(main())"


def commit_of(tree: Path) -> str:
    """The short commit of the git work tree ``tree``, with " (with uncommitted changes)" when a
    tracked file differs from it."""
    head = subprocess.run(
        ["git", "-C", str(tree), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
    )
    dirty = subprocess.run(
        ["git", "-C", str(tree), "status", "--porcelain", "--untracked-files=no"],
        capture_output=True,
        text=True,
    )
    return head.stdout.strip() + (" (with uncommitted changes)" if dirty.stdout.strip() else "")


def checkout_env(checkout: Path) -> dict:
    """The environment in which this ``.venv``'s Python runs ``checkout``'s ``fogref`` package: the
    checkout first on ``PYTHONPATH`` (the dependencies are this ``.venv``'s), ``$FOGREF_VARIANT``
    unset."""
    env = {**os.environ, "PYTHONPATH": str(checkout)}
    env.pop("FOGREF_VARIANT", None)
    return env


def ratio_range(before: list, after: list) -> str:
    """The per-round ratios ``before / after`` as ``median [smallest, largest]``.

    >>> ratio_range([2.0, 3.0, 4.0], [1.0, 1.0, 1.0])
    '3.00 [2.00, 4.00]'
    """
    r = sorted(b / x for b, x in zip(before, after))
    return f"{statistics.median(r):.2f} [{r[0]:.2f}, {r[-1]:.2f}]"


#: A child process's code: run ``fogref.cli.main(argv)`` with one function timed.  ``argv[1]`` is the
#: function, ``module:name`` (replaced on its module by a wrapper that sums its seconds), the rest the
#: command's arguments.  Its last line is JSON: ``wall_s`` (the command), ``part_s`` (the function's
#: calls together), ``calls``, the exit ``code`` and which of the heavy libraries a small command can do
#: without the process ``imported`` (colour-science, pandas, matplotlib's pyplot).
TIMED_COMMAND = """
import importlib, json, sys, time
module_name, name = sys.argv[1].split(":")
module = importlib.import_module(module_name)
function = getattr(module, name)
seconds = []
def timed(*args, **kwargs):
    t0 = time.perf_counter()
    out = function(*args, **kwargs)
    seconds.append(time.perf_counter() - t0)
    return out
setattr(module, name, timed)
from fogref.cli import main
t0 = time.perf_counter()
code = main(sys.argv[2:])
wall = time.perf_counter() - t0
imported = [m for m in ("colour", "pandas", "matplotlib.pyplot") if m in sys.modules]
print(json.dumps({"wall_s": wall, "part_s": sum(seconds), "calls": len(seconds), "code": code,
                  "imported": imported}))
"""


def timed_command(checkout: Path, part: str, args: list, codes=(0,)) -> dict:
    """Run ``fogref ARGS`` with ``checkout``'s package (:func:`checkout_env`, in a fresh process, its
    working folder the checkout), the function ``part`` (``module:name``) timed apart
    (:data:`TIMED_COMMAND`); SystemExit with the child's stderr unless its exit code is in ``codes``."""
    p = subprocess.run(
        [sys.executable, "-c", TIMED_COMMAND, part, *map(str, args)],
        env=checkout_env(checkout),
        capture_output=True,
        text=True,
        cwd=checkout,
    )
    row = json.loads(p.stdout.strip().splitlines()[-1]) if p.stdout.strip() else {}
    if row.get("code") not in codes:
        raise SystemExit(f"fogref {args[0]} in {checkout} failed:\n{p.stderr[-3000:]}")
    return row


def alternating(checkouts: dict, rounds: int, run) -> dict:
    """``{name: [run(name, checkout) of each round]}``, the checkouts' order rotated every round so
    that a trend in the machine's load falls on all alike."""
    names = list(checkouts)
    runs: dict = {n: [] for n in names}
    for r in range(rounds):
        for n in names[r % len(names) :] + names[: r % len(names)]:
            runs[n].append(run(n, checkouts[n]))
    return runs


def kept_reading(markdown_path: Path) -> list[str] | None:
    """The hand-written ``## Reading`` section of an earlier run's report (its heading and the lines
    after it), to be kept when the report is written again; None when there is none."""
    path = Path(markdown_path)
    text = path.read_text(encoding="utf-8") if path.is_file() else ""
    if "\n## Reading\n" not in text:
        return None
    return ["## Reading", *text.split("\n## Reading\n", 1)[1].rstrip("\n").split("\n")]


def write_report(out: Path, stem: str, result: dict, markdown: str) -> None:
    """``<stem>.json`` and ``<stem>.md`` in ``out`` (made if missing), each written atomically, and
    the Markdown printed."""
    write_text_atomic(Path(out) / f"{stem}.json", json.dumps(result, indent=1) + "\n")
    write_text_atomic(Path(out) / f"{stem}.md", markdown)
    print(markdown)


def metrics_without_paths(folder: Path) -> dict:
    """A comparison's ``metrics.json`` in ``folder`` (a study's ``compare/metrics.json``) without what
    names paths (``inputs``, ``out_dir``, ``exr``, ``truth.path``): what two checkouts' runs share."""
    own = Path(folder) / "metrics.json"
    doc = json.loads((own if own.is_file() else Path(folder) / "compare" / "metrics.json").read_text())
    for k in ("inputs", "out_dir", "exr"):
        doc.pop(k, None)
    if isinstance(doc.get("truth"), dict):
        doc["truth"].pop("path", None)
    return doc


def valley_truth(folder: Path, width: int, height: int, spp: int) -> Path:
    """``folder/valley_<W>x<H>.exr``: ``scenes/valley.xml`` at that size, ``spp`` and seed 0, rendered
    by this checkout's ``fogref render`` (no PNG)."""
    truth = Path(folder) / f"valley_{width}x{height}.exr"
    args = ["render", str(ROOT / "scenes" / "valley.xml"), "--spp", str(spp), "--seed", "0", "--quiet"]
    args += ["--set", f"res={width}", "--set", f"resy={height}", "--out", str(truth), "--no-png"]
    subprocess.run([sys.executable, "-c", FOGREF_MAIN, *args], env=checkout_env(ROOT), check=True, cwd=ROOT)
    return truth


def before_after(base: Path, rounds: int, run, identical) -> dict:
    """Rounds alternating ``before`` (the checkout ``base``) and ``after`` (this one), each run
    ``run(name, checkout)`` (:func:`alternating`); then ``identical()``, the runs' outputs compared.
    Returns what a report needs: the commits, the cores, the load average (1 min) before and after
    the rounds, the runs and the identity."""
    checkouts = {"before": Path(base).resolve(), "after": ROOT}
    load = [os.getloadavg()[0]]
    runs = alternating(checkouts, rounds, run)
    load.append(os.getloadavg()[0])
    return {
        "base": commit_of(checkouts["before"]),
        "after": commit_of(ROOT),
        "cores": len(os.sched_getaffinity(0)),
        "load_average": load,
        "runs": runs,
        "identical": identical(),
    }


def timing_rows(runs: dict, rows) -> list[str]:
    """A Markdown table of ``rows`` (``(key, label)``: a seconds field of every run) from
    :func:`before_after`'s runs: each side's median and the per-round ratio :func:`ratio_range`."""
    md = ["| | before [s], median | after [s], median | before / after |", "|---|---:|---:|---|"]
    for key, label in rows:
        before, after = ([v[key] for v in runs[m]] for m in ("before", "after"))
        ratio = ratio_range(before, after)
        md.append(f"| {label} | {statistics.median(before):.2f} | {statistics.median(after):.2f} | {ratio} |")
    return md


def identity_lines(identical: dict, how: str) -> list[str]:
    """The report's lines on :func:`before_after`'s identity (``{what: equal}``), ``how`` said after
    it (what was left out of the comparison), and a blank line.

    >>> identity_lines({"`fit.json`": True, "`budget.json`": False}, " (but for paths)")
    ['', 'Identity: `fit.json` equal, `budget.json` DIFFERENT (but for paths).', '']
    """
    states = ", ".join(f"{what} {'equal' if ok else 'DIFFERENT'}" for what, ok in identical.items())
    return ["", f"Identity: {states}{how}.", ""]


def before_after_arguments(doc: str) -> argparse.Namespace:
    """The command line of a before/after benchmark (``doc``: its module docstring, whose first
    paragraph describes it): ``--base`` (the checkout to compare with), ``--rounds`` (default 3) and
    ``--out`` (default ``reports/benchmarks``)."""
    ap = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    ap.add_argument("--base", required=True, help="the checkout to compare with (a git worktree)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks"))
    return ap.parse_args()


def example_sweep(tree: Path, work: Path, outputs: dict | None = None) -> Path:
    """``work/SWEEP.toml``: the example sweep of the checkout ``tree`` (:data:`EXAMPLE_SWEEP`) with its
    scene by absolute path, its truth cache and outputs in ``work``, and ``outputs`` (key -> TOML
    value as written) set in its ``[outputs]`` table."""
    text = (Path(tree) / EXAMPLE_SWEEP).read_text()
    text = text.replace('"scenes/valley.xml"', f'"{(Path(tree) / "scenes" / "valley.xml").as_posix()}"')
    text = text.replace('"out/sweep_cache"', f'"{(Path(work) / "cache").as_posix()}"')
    head, table = text.split("[outputs]\n", 1)
    for key, value in (outputs or {}).items():
        lines = [ln for ln in table.splitlines() if not ln.startswith(f"{key} =")]
        table = "\n".join([f"{key} = {value}", *lines]) + "\n"
    Path(work).mkdir(parents=True, exist_ok=True)
    (Path(work) / "SWEEP.toml").write_text(head + "[outputs]\n" + table)
    return Path(work) / "SWEEP.toml"
