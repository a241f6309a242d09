"""How many times does plain ``mi.render`` compile fogpath's path kernel?

Writes reports/benchmarks/mirender_compiles.md (and .json).

A fresh process with an empty Dr.Jit kernel cache (``HOME`` is a new folder) loads the
valley scene (32x18) six times, as a user's loop over seeds and configurations does, and
renders each with ``mi.render(scene, spp=16, seed=...)``; Dr.Jit's kernel history says per
call whether the path kernel (the largest) was compiled and how long codegen + LLVM took.

Two loading patterns, each in its own fresh process:

* ``reassign``: ``scene = mi.load_file(...)``: the previous scene is still alive while the
  next one loads;
* ``free_first``: ``scene = None`` (and ``gc.collect()``) before ``mi.load_file``.

Dr.Jit's virtual-call tables are indexed by the instance registry ids of the scene's
emitters, shapes and BSDFs.  A scene loaded while the previous one is alive gets new ids, so
the kernel differs; the ids of a freed scene are reused, and so is the kernel.

    .venv/bin/python benchmarks/mirender_compiles.py
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: (what changes, seed, overrides) per call: a repeat, new seeds and two new configurations
CALLS = [
    ("first call", 0, {}),
    ("same scene, same seed", 0, {}),
    ("new seed", 1, {}),
    ("g = 0.6", 2, {"g": "0.6"}),
    ("new seed", 3, {}),
    ("g = 0.7", 4, {"g": "0.7"}),
]


def _child(pattern: str) -> list:
    import gc

    import mitsuba as mi
    from _common import kernel_profile  # sets the variant ($FOGREF_VARIANT, else llvm_ad_rgb)

    rows, scene = [], None
    for what, seed, over in CALLS:
        if pattern == "free_first":
            scene = None
            gc.collect()
        scene = mi.load_file(str(ROOT / "scenes" / "valley.xml"), parallel=False, res="32", resy="18", **over)
        prof = kernel_profile(scene, 16, seed)
        rows.append(
            {
                "call": what,
                "seed": seed,
                "wall_s": prof["wall_s"],
                "path_kernel_compiled": prof["largest_kernel_compiled"],
                "compile_s": prof["largest_kernel_compile_s"],
            }
        )
    return rows


def main() -> None:
    if len(sys.argv) == 3 and sys.argv[1] == "--child":
        print(json.dumps(_child(sys.argv[2])))
        return
    runs = {}
    for pattern in ("reassign", "free_first"):
        with tempfile.TemporaryDirectory() as home:
            out = subprocess.run(
                [sys.executable, __file__, "--child", pattern],
                env=dict(os.environ, HOME=home),
                capture_output=True,
                text=True,
                check=True,
            )
        runs[pattern] = json.loads(out.stdout.strip().splitlines()[-1])
    dest = ROOT / "reports" / "benchmarks" / "mirender_compiles.md"
    dest.with_suffix(".json").write_text(json.dumps(runs, indent=1) + "\n")
    lines = [
        "# Kernel compiles through plain `mi.render`",
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores; `llvm_ad_rgb`, valley 32x18, 16 spp, each "
        "pattern in a fresh process with an empty Dr.Jit cache.  "
        "Command: `.venv/bin/python benchmarks/mirender_compiles.py`.",
        "",
        "| call | seed | reassign: compiled | compile [s] | free first: compiled | compile [s] |",
        "|---|---|---|---|---|---|",
    ]
    for a, b in zip(runs["reassign"], runs["free_first"]):
        lines.append(
            f"| {a['call']} | {a['seed']} | {'yes' if a['path_kernel_compiled'] else 'no'} | "
            f"{a['compile_s']:.2f} | {'yes' if b['path_kernel_compiled'] else 'no'} | {b['compile_s']:.2f} |"
        )
    n_re = sum(r["path_kernel_compiled"] for r in runs["reassign"])
    n_ff = sum(r["path_kernel_compiled"] for r in runs["free_first"])
    lines += [
        "",
        f"The path kernel compiled {n_re} times with `scene = mi.load_file(...)` and {n_ff} times when "
        "the previous scene is freed first.  Dr.Jit indexes its virtual-call tables by the registry ids "
        "of the scene's objects: a scene loaded while the previous one is alive gets new ids and a new "
        "kernel, until two sets of ids alternate.  `fogref render` loads one scene per process, and a "
        "`fogref sweep` worker renders each configuration in a call whose scene is freed when it returns "
        "(`reports/sweeps/kernel_reuse.md`).",
        "",
    ]
    dest.write_text("\n".join(lines))
    print(dest.read_text())


if __name__ == "__main__":
    main()
