"""Statistical comparison of Monte Carlo images, used by the render tests.

Images are compared on blocks of pixels.  For each block, the block mean of each
independent run (different seeds) is one observation; two estimators agree when
Welch's t-test does not reject equal means at level ``alpha / n_blocks``
(Bonferroni), so the whole image comparison has family-wise confidence
``1 - alpha``.
"""

from __future__ import annotations

import numpy as np
from scipy import stats


def block_means(img: np.ndarray, block: int) -> np.ndarray:
    """(H, W, C) -> (H//block * W//block * C,) block means."""
    H, W = img.shape[:2]
    h, w = H // block, W // block
    x = img[: h * block, : w * block].reshape(h, block, w, block, -1).mean(axis=(1, 3))
    return x.reshape(-1)


def welch_blocks(runs_a, runs_b, block: int = 4, alpha: float = 1e-3, floor: float = 0.0):
    """Welch t-test per block between two lists of independent images.

    ``floor``: an absolute tolerance added to the standard error, for known
    deterministic differences (e.g. float32 round-off); 0 by default.
    Returns (p_min, alpha_per_block, worst_index, details).
    """
    a = np.stack([block_means(r, block) for r in runs_a])
    b = np.stack([block_means(r, block) for r in runs_b])
    ma, mb = a.mean(0), b.mean(0)
    va, vb = a.var(0, ddof=1) / len(a), b.var(0, ddof=1) / len(b)
    se = np.sqrt(va + vb) + floor
    t = np.where(se > 0, np.abs(ma - mb) / np.where(se > 0, se, 1.0), np.where(ma == mb, 0.0, np.inf))
    num = (va + vb) ** 2
    den = va**2 / max(len(a) - 1, 1) + vb**2 / max(len(b) - 1, 1)
    df = np.where(den > 0, num / np.where(den > 0, den, 1.0), 1e9)
    p = 2 * stats.t.sf(t, df)
    per = alpha / len(p)
    i = int(np.argmin(p))
    return float(p[i]), per, i, {"mean_a": ma[i], "mean_b": mb[i], "se": se[i]}


def assert_agree(runs_a, runs_b, block=4, alpha=1e-3, floor=0.0, what=""):
    p, per, i, d = welch_blocks(runs_a, runs_b, block, alpha, floor)
    assert p >= per, (
        f"{what}: block {i} differs (p={p:.2e} < {per:.2e}, family-wise alpha={alpha}): "
        f"{d['mean_a']:.6g} vs {d['mean_b']:.6g} (se {d['se']:.3g})"
    )


def one_sample_blocks(runs, reference, block=4, alpha=1e-3, floor=0.0, what=""):
    """t-test of Monte Carlo runs against a noise-free reference image, per block (Bonferroni)."""
    a = np.stack([block_means(r, block) for r in runs])
    ref = block_means(reference, block)
    m = a.mean(0)
    se = a.std(0, ddof=1) / np.sqrt(len(a)) + floor
    t = np.where(
        se > 0, np.abs(m - ref) / np.where(se > 0, se, 1.0), np.where(np.isclose(m, ref), 0.0, np.inf)
    )
    p = 2 * stats.t.sf(t, len(a) - 1)
    per = alpha / len(p)
    i = int(np.argmin(p))
    assert p[i] >= per, (
        f"{what}: block {i} differs from the reference (p={p[i]:.2e} < {per:.2e}, "
        f"family-wise alpha={alpha}): {m[i]:.6g} vs {ref[i]:.6g} (se {se[i]:.3g})"
    )
    return float(p[i])


#: z for a two-sided test at alpha = 1e-3 and for 95 % power (one-sided 5 %).
Z_ALPHA, Z_POWER = 3.29, 1.645


def image_means_rgb(mi, scene, n_runs, spp, seed0):
    """(n_runs, 3): the R, G, B means over pixels of ``n_runs`` independent renders (seeds
    seed0, seed0+1, ...), float64."""
    return np.array(
        [
            np.array(mi.render(scene, spp=spp, seed=seed0 + k), dtype=np.float64)[..., :3].mean((0, 1))
            for k in range(n_runs)
        ]
    )


def image_means(mi, scene, n_runs, spp, seed0):
    """Mean over pixels and RGB of ``n_runs`` independent renders (seeds seed0, seed0+1, ...)."""
    return image_means_rgb(mi, scene, n_runs, spp, seed0).mean(1)


def assert_mean_equals(means, expected, max_detectable=1e-3, what=""):
    """One-sample test of the relative image-mean bias against an exact ``expected``.

    The standard error is the spread of the independent renders' means over sqrt(n).
    Asserts the test's own power first: the smallest relative bias it detects with
    95 % power at alpha = 1e-3, ``(Z_ALPHA + Z_POWER) * se / expected``, must be at
    most ``max_detectable``.  Returns ``(bias, se, smallest detectable bias)``, relative.
    """
    bias = means.mean() / expected - 1.0
    se = means.std(ddof=1) / np.sqrt(len(means)) / expected
    mde = (Z_ALPHA + Z_POWER) * se
    assert mde <= max_detectable, (
        f"{what}: underpowered, detects only {mde:.2%} (wanted {max_detectable:.2%})"
    )
    assert abs(bias) <= Z_ALPHA * se, (
        f"{what}: image mean biased by {bias:+.4%} +- {se:.4%} (z = {bias / se:+.1f}; detects {mde:.3%})"
    )
    return bias, se, mde


def assert_means_agree(means_a, means_b, max_detectable=1e-3, what=""):
    """Welch test on the relative difference of two estimators' image means (independent seeds)."""
    ma, mb = means_a.mean(), means_b.mean()
    se = np.sqrt(means_a.var(ddof=1) / len(means_a) + means_b.var(ddof=1) / len(means_b)) / mb
    diff = ma / mb - 1.0
    mde = (Z_ALPHA + Z_POWER) * se
    assert mde <= max_detectable, (
        f"{what}: underpowered, detects only {mde:.2%} (wanted {max_detectable:.2%})"
    )
    assert abs(diff) <= Z_ALPHA * se, (
        f"{what}: image means differ by {diff:+.4%} +- {se:.4%} (z = {diff / se:+.1f})"
    )
    return diff, se, mde
