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

ROOT = Path(__file__).resolve().parents[1]

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
    env = {**os.environ, "PYTHONPATH": str(tree), "PYTHONDONTWRITEBYTECODE": "1"}
    args = (*case, renders, out, ROOT / "scenes" / "valley.xml")
    r = subprocess.run(
        [sys.executable, "-c", _CHILD, *map(str, args)],
        capture_output=True,
        text=True,
        env=env,
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
    base_rev = subprocess.run(
        ["git", "rev-parse", "--short", args.base], capture_output=True, text=True, check=True, cwd=ROOT
    ).stdout.strip()
    head = subprocess.run(
        ["git", "describe", "--always", "--dirty"], capture_output=True, text=True, check=True, cwd=ROOT
    ).stdout.strip()
    tmp = Path(tempfile.mkdtemp())
    base_tree = tmp / "base"
    subprocess.run(
        ["git", "worktree", "add", "-q", "--detach", str(base_tree), base_rev], check=True, cwd=ROOT
    )
    trees = {f"base {base_rev}": base_tree, f"this tree {head}": ROOT}
    rows: dict = {name: [] for name in trees}
    load = [os.getloadavg()[0]]
    try:
        for tree in trees.values():  # a first call each: kernel cache, page cache
            run_child(tree, case, tmp / "warm.exr", 1)
        for k in range(args.pairs):
            order = list(trees) if k % 2 == 0 else list(reversed(trees))
            for name in order:
                got = run_child(trees[name], case, tmp / f"{k}.exr", args.renders)
                rows[name].append(got)
                print(
                    f"pair {k} {name:28s} render() {got['render_s']:6.2f} s, writes {got['writes_s']:6.2f} s"
                )
                load.append(os.getloadavg()[0])
    finally:
        subprocess.run(["git", "worktree", "remove", "--force", str(base_tree)], cwd=ROOT)

    def med(name, field):
        return statistics.median(r[field] for r in rows[name])

    names = list(trees)
    ratio = [a["writes_s"] / b["writes_s"] for a, b in zip(rows[names[0]], rows[names[1]], strict=True)]
    w, h, spp = case
    cpu = os.cpu_count()
    lines = [
        f"# Writing a {w}x{h} truth: {names[1]} against {names[0]}",
        "",
        f"Command: `python benchmarks/truth_write.py --base {args.base} --case {args.case} "
        f"--pairs {args.pairs} --renders {args.renders}`.  {cpu} cores, 1-min load average "
        f"{min(load):.1f}-{max(load):.1f} while measured.  Default scene, `render()` of {args.renders} "
        "seed(s) in a fresh process per tree and pair (`png=False`, `resume=False`, the sums kept; with "
        "several, the median of the renders after the first), the trees alternating; after one "
        "untimed process each.",
        "",
        "| tree | render() [s] median [min, max] | passes [s] | writes [s] median [min, max] |",
        "|---|---|---|---|",
    ]
    for name in names:
        rs, ws = [r["render_s"] for r in rows[name]], [r["writes_s"] for r in rows[name]]
        lines.append(
            f"| {name} | {med(name, 'render_s'):.4f} [{min(rs):.4f}, {max(rs):.4f}] | "
            f"{med(name, 'passes_s'):.4f} | {med(name, 'writes_s'):.4f} [{min(ws):.4f}, {max(ws):.4f}] |"
        )
    lines += [
        "",
        f"Writes, base / this tree: {statistics.median(ratio):.2f}x "
        f"(per pair {min(ratio):.2f}-{max(ratio):.2f}).",
    ]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{args.name}.md").write_text("\n".join(lines) + "\n")
    (out / f"{args.name}.json").write_text(
        json.dumps({"case": args.case, "rows": rows, "load": load}, indent=1)
    )
    print("\n".join(lines))


if __name__ == "__main__":
    main()
