"""Which light the variance that is left comes from: fogpath's per-sample variance of each part
with the sun and the sky, the sun alone and the sky alone -> reports/benchmarks/variance_by_light.{md,json}.

The four ladder scenes (``benchmarks/_scenes.py``) at 96x54, max_depth 8, fogpath's defaults; each
(scene, light) rendered ``--seeds`` times at ``--spp`` samples with seeds of its own.  A value is the
per-pixel variance of one sample, summed over the pixels and RGB (linear Rec.709, the scene's
radiance unit squared), as the mean over the seeds with the standard error from their spread.
The parts are correlated, so neither the parts nor the two lights need add up to the whole.

    .venv/bin/python benchmarks/variance_by_light.py [--spp 64] [--seeds 4]
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

from _checkouts import kept_reading, write_report
from _common import ROOT, machine_info, mi, np, part_variances
from _scenes import SCENES, build

LIGHTS = {"sun and sky": (True, True), "sun only": (True, False), "sky only": (False, True)}
PARTS = ("final", "attenuated_surface", "single", "multiple")


def measure(spp: int, n_seeds: int) -> dict:
    """scene -> light -> part -> {"mean", "stderr", "values"}."""
    out: dict = {}
    for i, name in enumerate(SCENES):
        for j, (light, (sun, sky)) in enumerate(LIGHTS.items()):
            scene = build(mi, name, "fogpath", sun=sun, sky=sky)
            part_variances(scene, 1, [0])  # compiles (or loads the kernel cache); not counted
            seeds = [100_000 * (i + 1) + 1_000 * j + k for k in range(n_seeds)]  # each its own
            v = part_variances(scene, spp, seeds)
            out.setdefault(name, {})[light] = {
                p: {
                    "mean": float(np.mean(v[p])),
                    "stderr": float(np.std(v[p], ddof=1) / np.sqrt(len(v[p]))),
                    "values": v[p],
                }
                for p in PARTS
            }
            print(name, light, {p: round(out[name][light][p]["mean"], 3) for p in PARTS}, flush=True)
    return out


def report(res: dict) -> str:
    a = res["args"]
    L = [
        "# Which light the variance that is left comes from",
        "",
        f"`python benchmarks/variance_by_light.py --spp {a['spp']} --seeds {a['seeds']}` "
        f"({res['seconds']:.0f} s).  Machine: {res['machine']}; load average (1 min) "
        f"{res['load_average'][0]:.1f} -> {res['load_average'][1]:.1f}.",
        "",
        "fogpath with its defaults, max_depth 8, 96x54, on the four ladder scenes "
        f"(`benchmarks/_scenes.py`); each (scene, light) {a['seeds']} renders of {a['spp']} spp with "
        "seeds of their own.  Per-pixel variance of one sample, summed over pixels and RGB (linear "
        "Rec.709, the scene's radiance unit squared); mean over the renders +- the standard error "
        "from their spread.  The parts are correlated, so they need not add up to `final`, nor the "
        "lights to `sun and sky`.",
        "",
        "| scene | light | " + " | ".join(PARTS) + " |",
        "|---|---|" + "---:|" * len(PARTS),
    ]
    for name, by_light in res["variance"].items():
        for light, parts in by_light.items():
            cells = [f"{parts[p]['mean']:.4g} +- {parts[p]['stderr']:.2g}" for p in PARTS]
            L.append(f"| {name} | {light} | " + " | ".join(cells) + " |")
    L += [
        "",
        "**Single scattering of the sky alone, against the whole image's variance with both lights** "
        "(sky only `single` / sun and sky `final`):",
        "",
    ]
    for name, by_light in res["variance"].items():
        share = by_light["sky only"]["single"]["mean"] / by_light["sun and sky"]["final"]["mean"]
        L.append(f"* {name}: {share:.2f}")
    L += ["", *res.get("reading", [])]
    return "\n".join(L) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--out", default=str(ROOT / "reports" / "benchmarks" / "variance_by_light"))
    a = ap.parse_args(argv)
    t0, load0 = time.perf_counter(), os.getloadavg()[0]
    res = {
        "args": {"spp": a.spp, "seeds": a.seeds},
        "machine": ", ".join(f"{k} {v}" for k, v in machine_info().items()),
        "variance": measure(a.spp, a.seeds),
        "seconds": time.perf_counter() - t0,
        "load_average": [load0, os.getloadavg()[0]],
    }
    out = Path(a.out)
    reading = kept_reading(out.with_suffix(".md"))  # the hand-written reading is kept across reruns
    if reading:
        res["reading"] = reading
    write_report(out.parent, out.name, res, report(res))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
