"""The four metrics of :func:`fogref.compare.check.check`, their estimates and confidence intervals.

With ``e = candidate - truth`` per pixel and RGB channel, ``r`` the truth's part and
``s`` the per-pixel standard error of ``e`` that the truth's noise causes (sums over
a region's pixels and RGB):

=============  =====================================================  ==========
metric         estimate                                               range
=============  =====================================================  ==========
``rel_rmse``   ``sqrt(max(0, Σ(e² - s²)) / Σ(r² - s_r²))``             [0, inf)
``rel_bias``   ``Σ e / Σ r`` (mean signed error relative to the mean)  (-inf, inf)
``rmse``       ``sqrt(max(0, Σ(e² - s²)) / n)`` [the part's units]     [0, inf)
``bias``       ``Σ e / n`` [the part's units]                          (-inf, inf)
=============  =====================================================  ==========

``E[e²] = (true error)² + s²``, so an exact candidate has ``rel_rmse`` near 0 at any
sample count.  Each metric is a ratio of sums over pixels (:func:`block_sums`,
:func:`estimates_from_sums`).  Its standard deviation comes either from the truth's
per-pixel noise, the view fixed (:func:`noise_sd`, the delta method of
:mod:`fogref.compare.noise`), or from a block bootstrap over ``block`` × ``block``
pixel blocks (:func:`block_bootstrap`, :func:`bootstrap_interval`: a Student-t
interval with ``k - 1`` degrees of freedom for ``k`` blocks), which also covers noise
correlated between pixels but counts the spatial variation of the candidate's error
as uncertainty.  The derivation: ``docs/design.md``, "check: statistics".
"""

from __future__ import annotations

import math

import numpy as np

from fogref.compare import noise

#: The check's metrics, in the order of its rows.
METRICS = ("rel_rmse", "rel_bias", "rmse", "bias")
#: The signed metrics (a tolerance bounds their absolute value).
SIGNED = ("rel_bias", "bias")
_Q = ("sq", "power", "err", "ref", "n")  # per-block sums


def block_sums(cand, ref, cov, rcov, mask, block: int) -> np.ndarray:
    """``(n_blocks, 5)`` per-block sums of ``e² - s²``, ``r² - s_r²``, ``e``, ``r`` and the count."""
    e = cand - ref
    var, rvar = noise.diagonal(cov), noise.diagonal(rcov)
    q = (
        np.stack(
            [
                (e * e - var).sum(-1),
                (ref * ref - rvar).sum(-1),
                e.sum(-1),
                ref.sum(-1),
                np.full(mask.shape, 3.0),
            ],
            -1,
        )
        * mask[..., None]
    )
    H, W = mask.shape
    hb, wb = -(-H // block), -(-W // block)
    pad = np.zeros((hb * block, wb * block, len(_Q)))
    pad[:H, :W] = q
    sums = pad.reshape(hb, block, wb, block, len(_Q)).sum(axis=(1, 3)).reshape(-1, len(_Q))
    return sums[sums[:, 4] > 0]


def estimates_from_sums(s: np.ndarray) -> dict:
    """The four near-linear statistics (ratios of sums) from summed quantities ``(..., 5)``.

    ``rel_ms`` and ``ms`` are the noise-corrected squared errors (may be < 0 by noise);
    ``rel_rmse = sqrt(max(rel_ms, 0))`` and ``rmse = sqrt(max(ms, 0))``.

    >>> e = estimates_from_sums(np.array([4.0, 100.0, 6.0, 60.0, 30.0]))
    >>> [round(float(e[m]), 4) for m in METRICS]
    [0.04, 0.1, 0.1333, 0.2]
    """
    sq, power, err, ref, n = (s[..., i] for i in range(5))
    with np.errstate(divide="ignore", invalid="ignore"):
        return {
            "rel_rmse": sq / np.where(power > 0, power, np.nan),
            "rel_bias": err / np.where(ref != 0, ref, np.nan),
            "rmse": sq / n,
            "bias": err / n,
        }


def block_bootstrap(sums: np.ndarray, n_boot: int, seed: int, chunk: int = 256) -> dict:
    """Bootstrap replicates of the near-linear statistics from per-block sums.

    Blocks are drawn with replacement (``n_boot`` replicates of ``len(sums)`` blocks,
    seeded).  Returns metric -> ``(n_boot,)`` replicates of :func:`estimates_from_sums`
    (squared-error scale for ``rel_rmse`` and ``rmse``; NaN where undefined).
    """
    rng = np.random.default_rng(seed)
    k = len(sums)
    reps = {m: [] for m in METRICS}
    for start in range(0, n_boot, chunk):
        m = min(chunk, n_boot - start)
        counts = rng.multinomial(k, np.full(k, 1.0 / k), size=m)
        vals = estimates_from_sums(counts.astype(np.float64) @ sums)
        for name in METRICS:
            reps[name].append(vals[name])
    return {name: np.concatenate(v) for name, v in reps.items()}


def bootstrap_interval(est: float, reps: np.ndarray, k: int, alpha: float) -> tuple[float, float]:
    """Student-t interval ``est ± t(k-1) * sd_boot * sqrt(k / (k-1))`` from ``k`` blocks.

    The bootstrap's spread underestimates the variance by ``(k-1)/k`` and the normal
    quantile is too narrow for few blocks; both are corrected here.
    """
    from scipy.special import stdtrit  # Student's t quantile (scipy.stats.t.ppf's own); slow to import

    sd = float(np.std(reps, ddof=1)) * math.sqrt(k / max(k - 1, 1))
    q = float(stdtrit(max(k - 1, 1), 1.0 - alpha))
    return est - q * sd, est + q * sd


def noise_sd(cand, ref, cov, rcov, mask, spp: int, point: dict, at_spp: int | None = None) -> dict:
    """Standard deviation of each statistic (squared scale for the RMSEs) due to the truth's noise.

    Conditional on the view: the candidate's error pattern is fixed, only the Monte
    Carlo noise is random.  Pixels are independent (each has its own samples); the
    channels of a pixel are not, and their covariance ``cov`` is used whole (see
    :mod:`fogref.compare.noise`, the one delta method).  The reference power in the
    denominator of ``rel_rmse`` is taken as exact (its relative noise is that of a sum
    over the whole region).

    ``at_spp``: the standard deviations a truth of ``at_spp`` samples per pixel would give with
    the same error pattern (the noise variances scale as ``spp / at_spp``; needs ``spp`` >= 1).
    """
    e, C, R = (cand - ref)[mask], cov[mask], rcov[mask]
    _, var_sq = noise.squared_stat(e, C, spp, at_spp=at_spp)
    k = spp / at_spp if (at_spp and spp >= 1) else 1.0
    var_err, var_ref = k * noise.sum_var(C), k * noise.sum_var(R)
    n = 3.0 * float(mask.sum())
    power, err, refsum = (float(point[k]) for k in ("_power", "_err", "_ref"))
    out = {
        "rmse": math.sqrt(var_sq) / n,
        "bias": math.sqrt(var_err) / n,
        "rel_rmse": math.sqrt(var_sq) / power if power > 0 else math.nan,
        "_ref_sd": math.sqrt(var_ref),
    }
    out["rel_bias"] = math.sqrt(noise.ratio_var(err, refsum, var_err, var_ref)) if refsum != 0 else math.nan
    return out


def spp_to_decide(decides, spp: int, most: int = 1 << 40) -> int | None:
    """The smallest sample count above ``spp`` at which ``decides(n)`` (monotone: once true, true
    for every larger ``n``) holds, by doubling then bisection; None if not even at ``most``.

    >>> spp_to_decide(lambda n: n >= 1000, 16), spp_to_decide(lambda n: False, 16, most=1 << 10)
    (1000, None)
    """
    lo, hi = int(spp), 2 * max(int(spp), 1)
    while not decides(hi):
        lo, hi = hi, 2 * hi
        if hi > most:
            return None
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (lo, mid) if decides(mid) else (mid, hi)
    return hi
