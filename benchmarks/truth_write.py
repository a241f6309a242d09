"""The cost of writing a large truth: this tree's ``render()`` against a base commit's, side by side.

``fogref.render.render.render`` ends by writing two files: the EXR (float32 channels, ZIP)
and, beside it, the float64 sums (``<out>.moments.npz``, with a SHA-256 over them).  At
1920x1080 the sums are 1.2 GB, and on a GPU the two writes took longer than a 64-spp render
(``reports/benchmarks/gpu.md``).  This benchmark renders the default scene at ``--case``
(1 spp by default, so that the writes dominate) in fresh processes, alternating the base
commit's tree (a ``git worktree``) and this one, ``--pairs`` times. Each process reports:

* ``render()``: the call's wall time;
* ``passes``: the time up to the pixels (the truth's ``fogref.render_seconds`` total);
* ``writes``: the difference, that is the EXR, the sums, and the PNG-less rest of the end.

With ``--renders N`` each process renders N seeds and reports the median of those after its
first: a small truth's writes in a warm process, where the thread that writes the sums costs
its start.

    .venv/bin/python benchmarks/truth_write.py --base d03c982 [--case 1920x1080x1] [--pairs 4]
        [--renders 1] [--out reports/benchmarks] [--name truth_write]

Writes reports/benchmarks/NAME.{json,md}.  Only ``fogref/`` comes from the base tree;
the plugins are this checkout's.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from _checkouts import ROOT, alternating, checkout_env, commit_of, ratio_range, write_report

_CHILD = """
import json, statistics, sys, time
from pathlib import Path
import fogref.render.render as R
from fogref.exrio import read_exr_header
w, h, spp, renders, out = *(int(a) for a in sys.argv[1:5]), Path(sys.argv[5])
got = []
for seed in range(renders):  # in one process: the later renders reuse the kept scene
    t0 = time.perf_counter()
    R.render(sys.argv[6], out, spp=spp, seed=seed, overrides={"res": w, "resy": h}, progress=False,
             png=False, resume=False)
    total = time.perf_counter() - t0
    got.append((total, read_exr_header(out)[0]["fogref.render_seconds"]["total"]))
got = got[1:] or got  # the renders after the process's first, when there are several
total, passes = (statistics.median(x) for x in zip(*got))
print(json.dumps({"render_s": total, "passes_s": passes, "writes_s": total - passes,
                  "fogref": R.__file__}))
"""


def run_child(tree: Path, case, out: Path, renders: int) -> dict:
    """``renders`` renders of ``case`` by ``tree``'s ``fogref`` (:func:`_checkouts.checkout_env`) in
    one fresh process: the child's JSON, checked to come from that tree."""
    args = (*case, renders, out, ROOT / "scenes" / "valley.xml")
    r = subprocess.run(
        [sys.executable, "-c", _CHILD, *map(str, args)],
        capture_output=True,
        text=True,
        env=checkout_env(tree),
        cwd=tree,
    )
    if r.returncode != 0:
        raise RuntimeError(f"render in {tree} failed:\n{r.stderr[-3000:]}")
    got = json.loads(r.stdout.strip().splitlines()[-1])
    if not got["fogref"].startswith(str(tree)):
        raise RuntimeError(f"{tree}: imported fogref from {got['fogref']}")
    return got


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", required=True, help="the commit to compare with")
    ap.add_argument("--case", default="1920x1080x1", help="WxHxSPP")
    ap.add_argument("--pairs", type=int, default=4)
    ap.add_argument(
        "--renders",
        type=int,
        default=1,
        help="renders per process; above 1, the median of those after the first (a warm process)",
    )
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks"))
    ap.add_argument("--name", default="truth_write", help="the reports' file name, without suffix")
    args = ap.parse_args(argv)
    case = tuple(int(x) for x in args.case.split("x"))
    tmp = Path(tempfile.mkdtemp())
    base_tree = tmp / "base"
    add = ["git", "worktree", "add", "-q", "--detach", str(base_tree), args.base]
    subprocess.run(add, check=True, cwd=ROOT)
    trees = {f"base {commit_of(base_tree)}": base_tree, f"this tree {commit_of(ROOT)}": ROOT}
    loads = [os.getloadavg()[0]]

    def timed(name, tree):
        got = run_child(tree, case, tmp / "x.exr", args.renders)
        print(f"{name:36s} render() {got['render_s']:7.4f} s, writes {got['writes_s']:7.4f} s")
        loads.append(os.getloadavg()[0])
        return got

    try:
        for tree in trees.values():  # a first call each: kernel cache, page cache
            run_child(tree, case, tmp / "warm.exr", 1)
        rows = alternating(trees, args.pairs, timed)
    finally:
        subprocess.run(["git", "worktree", "remove", "--force", str(base_tree)], cwd=ROOT)

    names = list(trees)
    w, h, spp = case
    lines = [
        f"# Writing a {w}x{h} truth: {names[1]} against {names[0]}",
        "",
        f"Command: `python benchmarks/truth_write.py --base {args.base} --case {args.case} "
        f"--pairs {args.pairs} --renders {args.renders}`.  {os.cpu_count()} cores, 1-min load average "
        f"{min(loads):.1f}-{max(loads):.1f} while measured.  Default scene, `render()` of {args.renders} "
        "seed(s) in a fresh process per tree and pair (`png=False`, `resume=False`, the sums kept; with "
        "several, the median of the renders after the first), the trees alternating; after one "
        "untimed process each.",
        "",
        "| tree | render() [s] median [min, max] | passes [s] | writes [s] median [min, max] |",
        "|---|---|---|---|",
    ]
    for name in names:
        rs, ps, ws = ([r[k] for r in rows[name]] for k in ("render_s", "passes_s", "writes_s"))
        lines.append(
            f"| {name} | {statistics.median(rs):.4f} [{min(rs):.4f}, {max(rs):.4f}] | "
            f"{statistics.median(ps):.4f} | {statistics.median(ws):.4f} [{min(ws):.4f}, {max(ws):.4f}] |"
        )
    ratio = ratio_range(*([r["writes_s"] for r in rows[n]] for n in names))
    lines += ["", f"Writes, base / this tree, median [range] of the pairs: {ratio}x."]
    record = {"case": args.case, "rows": rows, "load": loads}
    write_report(Path(args.out), args.name, record, "\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
