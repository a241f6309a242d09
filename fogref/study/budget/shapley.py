"""Shapley values (Shapley 1953) of the budget's game, and their noise.

:func:`shapley_values` is exact over all ``2^k`` coalitions (weights of
:func:`shapley_weights`); :func:`shapley_budget` plays it with the squared error of
:func:`~fogref.study.budget.effects.coalition_image` and gives each share a block-bootstrap
noise (Efron & Tibshirani 1993); :func:`add_shapley_seed_noise` adds the seed-to-seed noise
from a second pair of renders.
"""

from __future__ import annotations

import math

import numpy as np

from fogref.study.budget.effects import (
    CONFIG_EFFECTS,
    EFFECTS,
    PHASE,
    STEPS,
    coalition_image,
    effective_coalition,
)

#: Side of the square pixel blocks of the bootstrap [pixels].
BOOTSTRAP_BLOCK = 16

#: Bootstrap resamples of the Shapley shares' noise.
BOOTSTRAP_RESAMPLES = 400


def shapley_weights(n: int) -> np.ndarray:
    """The ``(n, 2^n)`` matrix ``W`` with ``phi = W @ v`` for a game ``v`` over bitmask coalitions.

    ``v[mask]`` is the value of the coalition whose players are the set bits of ``mask``
    (player ``i`` = bit ``i``); ``phi_i = sum_{S not containing i} |S|! (n - |S| - 1)! / n!
    (v(S + i) - v(S))`` (Shapley 1953).  Rows sum to 0; columns of the full and empty
    coalitions make ``sum_i phi_i = v(all) - v(empty)`` (efficiency).

    Examples
    --------
    >>> shapley_weights(2)
    array([[-0.5,  0.5, -0.5,  0.5],
           [-0.5, -0.5,  0.5,  0.5]])
    """
    if not 1 <= n <= 16:
        raise ValueError(f"shapley_weights: n = {n} players outside [1, 16]")
    size = np.array([bin(m).count("1") for m in range(1 << n)])
    wt = np.array([math.factorial(s) * math.factorial(n - s - 1) / math.factorial(n) for s in range(n)])
    W = np.zeros((n, 1 << n))
    for i in range(n):
        bit = 1 << i
        for m in range(1 << n):
            if m & bit:
                continue
            w = wt[size[m]]
            W[i, m | bit] += w
            W[i, m] -= w
    return W


def shapley_values(value, players) -> dict:
    """Exact Shapley values of the game ``value`` over all ``2^k`` coalitions of ``players``.

    Parameters
    ----------
    value : callable
        ``value(frozenset of players) -> float or ndarray`` (arrays: one game per element,
        e.g. per pixel block); called once per coalition.
    players : sequence of hashable
        The k players (k <= 16).

    Returns
    -------
    dict
        player -> Shapley value (float or ndarray); the values sum to ``value(all) -
        value(empty)`` and do not depend on the order of ``players``.

    Examples
    --------
    >>> v = lambda c: float(len(c) ** 2)            # symmetric players share equally
    >>> shapley_values(v, ["a", "b", "c"])
    {'a': 3.0, 'b': 3.0, 'c': 3.0}
    """
    players = list(players)
    n = len(players)
    coalitions = (frozenset(p for i, p in enumerate(players) if m >> i & 1) for m in range(1 << n))
    V = np.stack([np.asarray(value(c), dtype=np.float64) for c in coalitions])
    phi = np.tensordot(shapley_weights(n), V, axes=1)
    return {p: (float(phi[i]) if phi[i].ndim == 0 else phi[i]) for i, p in enumerate(players)}


def _block_ids(shape: tuple, block: int) -> np.ndarray:
    h, w = shape
    by, bx = np.arange(h)[:, None] // block, np.arange(w)[None, :] // block
    return by * ((w + block - 1) // block) + bx


def shapley_budget(
    parts: dict,
    valid: np.ndarray,
    effects=EFFECTS,
    block: int = BOOTSTRAP_BLOCK,
    resamples: int = BOOTSTRAP_RESAMPLES,
    seed: int = 0,
) -> dict:
    """Shapley shares of the squared error ``sum |S(all) - S(empty)|^2`` over ``valid`` pixels.

    The game: ``e(C) = sum over valid pixels and channels of |coalition_image(C) - truth|^2``
    (0 for the empty coalition, the model's squared error for the full one).  Each effect's
    Shapley value ``phi_k`` is its share of the squared error, ``share_k = phi_k / e(all)``
    (the shares sum to 1 exactly; no effect's place in an order matters).  A configuration
    effect left out of ``effects`` (e.g. "refit": :data:`EFFECTS_COLOURS_IN_LOBE`) is held on
    the engine's side (see :func:`coalition_image`'s ``fixed``), so the ends stay the truth
    and the model.

    Each distinct image is evaluated once: coalitions with one
    :func:`~fogref.study.budget.effects.effective_coalition` share its value (212 of the 512
    coalitions of the nine effects are distinct).

    Noise: ``e(C)`` is a sum over pixel blocks (``block`` x ``block``), so the shares are
    re-computed on ``resamples`` bootstrap resamples of the blocks (seeded ``seed``) and
    each share gets their standard deviation, ``share_noise`` (Monte Carlo noise and the
    spread over the image together; Efron & Tibshirani 1993, the block bootstrap).

    Returns ``{"effects": [{key, effect, label, phi, share, share_noise}, ...] (in
    :data:`STEPS` order), "total_sq": e(all), "share_sum", "largest": key, "block",
    "resamples", "coalitions": 2^k}``.
    """
    effects = list(effects)
    fixed = tuple(k for k in CONFIG_EFFECTS if k not in effects)
    valid = np.asarray(valid, dtype=bool)
    ids = _block_ids(valid.shape, block)
    nb = int(ids[valid].max()) + 1 if valid.any() else 1
    truth = parts["final"]
    memo: dict[frozenset, np.ndarray] = {}

    def per_block(C):
        key = effective_coalition(parts, C, fixed)
        if key not in memo:  # a coalition with the image of one already played: its value again
            d = coalition_image(parts, key, fixed) - truth
            d *= d
            e = d[..., 0] + d[..., 1]  # np.sum's order over three channels
            e += d[..., 2]
            # every pixel in its block, in the same order, 0 for the invalid ones: the same sums
            weights = np.where(valid, e, 0.0).ravel()
            memo[key] = np.bincount(ids.ravel(), weights=weights, minlength=nb)[:nb]
        return memo[key]

    phi_blocks = shapley_values(per_block, effects)  # key -> (nb,)
    P = np.stack([phi_blocks[k] for k in effects])  # (k, nb)
    phi = P.sum(1)
    total = float(phi.sum())
    rng = np.random.default_rng(seed)
    shares_b = []
    for _ in range(resamples):
        idx = rng.integers(0, nb, nb)
        pb = P[:, idx].sum(1)
        tb = pb.sum()
        if tb > 0:
            shares_b.append(pb / tb)
    noise = np.std(np.array(shares_b), axis=0) if shares_b else np.zeros(len(effects))
    meta = {s[0]: s for s in (*STEPS, PHASE)}
    rows = []
    for i, k in enumerate(effects):
        _, letter, label = meta.get(k, (k, "?", k))
        rows.append(
            {
                "key": k,
                "effect": letter,
                "label": label,
                "phi": float(phi[i]),
                "share": float(phi[i] / total) if total > 0 else 0.0,
                "share_noise": float(noise[i]),
            }
        )
    largest = max(rows, key=lambda r: r["share"])["key"] if rows else None
    return {
        "effects": rows,
        "total_sq": total,
        "share_sum": float(sum(r["share"] for r in rows)),
        "largest": largest,
        "fixed": list(fixed),
        "block": block,
        "resamples": resamples,
        "coalitions": 1 << len(effects),
        "pixels": int(valid.sum()),
    }


def add_shapley_seed_noise(result: dict, other: dict) -> dict:
    """Add ``share_noise_seeds = |share(seed a) - share(seed b)| / sqrt(2)`` from a second
    Shapley budget (other renders), and keep the other seed's share."""
    by = {r["key"]: r for r in other["effects"]}
    for r in result["effects"]:
        o = by[r["key"]]
        r["share_other_seed"] = o["share"]
        r["share_noise_seeds"] = abs(r["share"] - o["share"]) / math.sqrt(2.0)
    return result
