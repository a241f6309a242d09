"""Coverage of ``check``'s intervals on real renders (shared by the test and its report).

Pairs of independent truths of one scene (same view, own seeds) are checked against
each other (:func:`fogref.compare.check.check` with a :class:`~fogref.gbuffer.Truth`
as the candidate, both truths' noise taken out): the true error of every statistic
is exactly 0, so every interval should cover 0 at its nominal rate and every ``z``
(the statistic over its standard error) should be standard normal.

Rows used: parts ``inscatter`` and ``final`` (``T`` of a pixel-exact truth has no
noise), regions ``all``, ``surface``, ``sky``, metrics ``rel_bias``, ``bias``,
``rel_rmse``, ``rmse``.  Within one pair the rows are not independent (``rmse`` and
``rel_rmse`` are one statistic scaled, and ``all`` holds ``surface`` and ``sky``);
the binomial test therefore counts only the *distinct* statistics (:data:`DISTINCT`:
``bias`` and ``rmse`` of both parts over ``surface`` and ``sky``, 8 per pair), and the
full table is reported beside it.

``channel_correlation="independent"`` replaces each truth's measured ``corr.*`` by 0:
the noise model of fogref 0.2 (``check`` then treated R, G and B as independent).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

PARTS = ("inscatter", "final")
REGIONS = ("all", "surface", "sky")
METRICS = ("rel_bias", "bias", "rel_rmse", "rmse")
DISTINCT = [(p, r, m) for p in PARTS for r in ("surface", "sky") for m in ("bias", "rmse")]


def render_truths(
    scene: Path, out_dir: Path, n: int, res=(32, 18), spp: int = 16, first_seed: int = 1000, overrides=None
) -> list:
    """``n`` truths of ``scene`` with seeds ``first_seed ...`` (EXRs under ``out_dir``), loaded."""
    from fogref.gbuffer import load_truth
    from fogref.render.render import render

    ov = {"res": res[0], "resy": res[1], **(overrides or {})}
    truths = []
    for k in range(n):
        path = render(
            scene,
            Path(out_dir) / f"truth_{k}.exr",
            spp=spp,
            seed=first_seed + k,
            overrides=ov,
            progress=False,
            png=False,
            resume=False,
        )
        truths.append(load_truth(path))
    return truths


def coverage_rows(truths: list, confidence: float = 0.99, channel_correlation: str = "measured") -> list:
    """Rows ``(pair, part, region, metric, covered, z)`` of every pair ``(2k, 2k+1)``."""
    from fogref.compare.check import check

    if channel_correlation == "independent":
        truths = [
            dataclasses.replace(t, corr={k: np.zeros_like(v) for k, v in t.corr.items()}) for t in truths
        ]
    no_tol = {p: {m: None for m in METRICS} for p in ("T", "inscatter", "final")}
    out = []
    for k in range(len(truths) // 2):
        res = check(truths[2 * k], truths[2 * k + 1], no_tol, distance_bands=(), confidence=confidence)
        for r in res.rows:
            if r.part in PARTS and r.region in REGIONS and r.metric in METRICS and r.estimate is not None:
                covered = (r.low <= 0.0 <= r.high) if r.metric in ("rel_bias", "bias") else r.low <= 0.0
                out.append((k, r.part, r.region, r.metric, bool(covered), r.z))
    return out


def binomial_upper(n: int, p: float, alpha: float) -> int:
    """Smallest ``k`` with ``P(X >= k) <= alpha`` for ``X ~ Binomial(n, p)``."""
    from scipy.stats import binom

    k = 0
    while binom.sf(k - 1, n, p) > alpha:
        k += 1
    return k


def summary(rows: list, confidence: float = 0.99, alpha: float = 0.01) -> dict:
    """Miss rates and z spreads, overall and per part/region/metric, and the binomial test.

    ``miss_expected``: 1 - confidence for the two-sided signed metrics, half of it for
    the RMSEs (their true value 0 is the end of their range: only the low side can
    miss).  The test rejects when the distinct statistics' misses reach
    ``binomial_limit`` (``P <= alpha`` under the nominal rate); ``power_at_10pct``:
    the chance it rejects a miss rate of 10 % (what fogref 0.2 showed).
    """
    from scipy.stats import binom

    def stats(sel):
        zs = np.array([r[5] for r in sel if r[5] is not None])
        return {
            "n": len(sel),
            "misses": sum(not r[4] for r in sel),
            "miss_rate": sum(not r[4] for r in sel) / max(len(sel), 1),
            "z_sd": float(np.std(zs, ddof=1)) if zs.size > 1 else math.nan,
            "z_mean": float(np.mean(zs)) if zs.size else math.nan,
        }

    table = {
        f"{p}/{r}/{m}": stats([x for x in rows if x[1:4] == (p, r, m)])
        for p in PARTS
        for r in REGIONS
        for m in METRICS
    }
    distinct = [x for x in rows if x[1:4] in DISTINCT]
    # the signed metrics miss two-sided, the RMSEs one-sided: the expected rate per row
    p_miss = float(np.mean([(1 - confidence) * (1.0 if x[3] == "bias" else 0.5) for x in distinct]))
    n = len(distinct)
    limit = binomial_upper(n, p_miss, alpha)
    signed = [x for x in rows if x[3] in ("rel_bias", "bias")]
    return {
        "table": table,
        "all": stats(rows),
        "signed": stats(signed),
        "distinct": stats(distinct),
        "distinct_expected_miss_rate": p_miss,
        "binomial_limit": limit,
        "binomial_p": float(binom.sf(stats(distinct)["misses"] - 1, n, p_miss)),
        "power_at_10pct": float(binom.sf(limit - 1, n, 0.10)),
        "confidence": confidence,
    }
