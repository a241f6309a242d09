"""Per-sample variance of each part, this version beside a previous one.

Reads the ``variance_shares`` that ``benchmarks/time_vs_error.py`` stores in
``reports/benchmarks/time_vs_error.json`` (per scene and fogpath method: the per-pixel
variance of one sample of the final image, summed over pixels and RGB, and each part's
share of it) from the working tree and from a previous commit, and writes
``reports/benchmarks/variance_parts.md``: each part's variance per sample (share x final),
before and after, and their ratio.  Same scenes, 96x54, 64 spp x 2 seeds in both.

    .venv/bin/python benchmarks/variance_parts.py --previous af011fa
"""

from __future__ import annotations

import argparse
import json
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
JSON = "reports/benchmarks/time_vs_error.json"
PARTS = ("attenuated_surface", "single", "multiple")


def _parts(shares: dict) -> dict:
    total = shares["final_variance_per_sample"]
    return {"final": total, **{p: shares[p] * total for p in PARTS}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--previous", required=True, help="the commit whose time_vs_error.json is 'before'")
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks" / "variance_parts.md"))
    a = ap.parse_args()
    before = json.loads(
        subprocess.run(
            ["git", "show", f"{a.previous}:{JSON}"], cwd=ROOT, capture_output=True, text=True, check=True
        ).stdout
    )
    after = json.loads((ROOT / JSON).read_text())
    lines = [
        "# Per-sample variance of each part: before and after",
        "",
        f"Before: `{JSON}` at commit `{a.previous}` ({before['config']['command']}); "
        "after: the same file now "
        f"({after['config']['command']}).  Variance of one sample, summed over the pixels and RGB of the "
        "96x54 image (64 spp x 2 seeds); the parts are correlated, so they need not add up to `final`.  "
        "Command: `.venv/bin/python benchmarks/variance_parts.py --previous " + a.previous + "`.",
        "",
        "| scene | method | part | before | after | after / before |",
        "|---|---|---|---|---|---|",
    ]
    for scene, sc in after["scenes"].items():
        prev = before["scenes"].get(scene, {}).get("variance_shares", {})
        for method, shares in sc.get("variance_shares", {}).items():
            now = _parts(shares)
            old = _parts(prev[method]) if method in prev else None
            for part in ("final", *PARTS):
                b = f"{old[part]:.4g}" if old else "(new)"
                r = f"{now[part] / old[part]:.2f}" if old and old[part] > 0 else ""
                lines.append(f"| {scene} | {method} | {part} | {b} | {now[part]:.4g} | {r} |")
    Path(a.out).write_text("\n".join(lines) + "\n")
    print(Path(a.out).read_text())


if __name__ == "__main__":
    main()
