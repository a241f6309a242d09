"""Coverage of ``check``'s 99 % intervals on real renders, before and after the channel covariance.

Pairs of independent truths of ``scenes/valley.xml`` are checked against each other
(true error 0; see ``tests/coverage_harness.py``).  "before" is the same renders with
the channels' noise correlation set to 0, the noise model of fogref 0.2's ``check``;
"after" uses the measured ``corr.*`` channels.  Writes
``reports/check_coverage/coverage.{md,json}``.

    .venv/bin/python benchmarks/check_coverage.py [--pairs 32]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import coverage_harness as H  # noqa: E402

CASES = (((32, 18), 16), ((64, 36), 64))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=32)
    ap.add_argument("--out", default=str(ROOT / "reports" / "check_coverage"))
    a = ap.parse_args(argv)
    import fogref
    from fogref.atomic import write_text_atomic

    fogref.set_variant()
    results = {}
    for res, spp in CASES:
        with tempfile.TemporaryDirectory() as tmp:
            truths = H.render_truths(ROOT / "scenes" / "valley.xml", Path(tmp), 2 * a.pairs, res=res, spp=spp)
            for mode in ("independent", "measured"):
                results[f"{res[0]}x{res[1]} {spp} spp, {mode}"] = H.summary(
                    H.coverage_rows(truths, channel_correlation=mode)
                )
    lines = [
        "# Coverage of `check`'s 99 % intervals on real renders",
        "",
        f"`benchmarks/check_coverage.py`: {a.pairs} pairs of independent truths of `scenes/valley.xml` "
        "checked against each other (true error 0). *independent*: the channels' noise correlation set "
        "to 0 (fogref 0.2's `check`); *measured*: the `corr.*` channels (schema 3).",
        "",
        "Distinct statistics: `bias` and `rmse` of inscatter and final over surface and sky, 8 per pair; "
        "expected miss rate 0.75 % (the RMSEs miss one-sided). Binomial limit at alpha = 1 %.",
        "",
        "| case | distinct misses | binomial limit | p | signed rows: miss rate, z sd | RMSE rows: z sd |",
        "|---|---|---|---|---|---|",
    ]
    for name, s in results.items():
        rm = [v["z_sd"] for k, v in s["table"].items() if k.endswith("/rmse")]
        lines.append(
            f"| {name} | {s['distinct']['misses']} / {s['distinct']['n']} | {s['binomial_limit']} | "
            f"{s['binomial_p']:.3g} | {s['signed']['miss_rate']:.1%}, {s['signed']['z_sd']:.2f} | "
            f"{min(rm):.2f}-{max(rm):.2f} |"
        )
    lines += ["", "Per part, region and metric (misses / rows, z sd):", ""]
    for name, s in results.items():
        lines += [f"### {name}", "", "| row | misses | z sd | z mean |", "|---|---|---|---|"]
        lines += [
            f"| {k} | {v['misses']} / {v['n']} | {v['z_sd']:.2f} | {v['z_mean']:.2f} |"
            for k, v in s["table"].items()
        ]
        lines.append("")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out / "coverage.md", "\n".join(lines) + "\n")
    write_text_atomic(out / "coverage.json", json.dumps(results, indent=2, allow_nan=False) + "\n")
    print("\n".join(lines[: 12 + len(results)]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
