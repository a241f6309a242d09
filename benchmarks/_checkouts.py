"""What the benchmarks that compare checkouts share: a checkout's commit, the environment that
runs its ``fogref`` package, and per-round ratios."""

from __future__ import annotations

import os
import statistics
import subprocess
from pathlib import Path


def commit_of(tree: Path) -> str:
    """The short commit of the git work tree ``tree``, with " (with uncommitted changes)" when a
    tracked file differs from it."""
    head = subprocess.run(
        ["git", "-C", str(tree), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
    )
    dirty = subprocess.run(
        ["git", "-C", str(tree), "status", "--porcelain", "--untracked-files=no"],
        capture_output=True,
        text=True,
    )
    return head.stdout.strip() + (" (with uncommitted changes)" if dirty.stdout.strip() else "")


def checkout_env(checkout: Path) -> dict:
    """The environment in which this ``.venv``'s Python runs ``checkout``'s ``fogref`` package: the
    checkout first on ``PYTHONPATH`` (the dependencies are this ``.venv``'s), ``$FOGREF_VARIANT``
    unset."""
    env = {**os.environ, "PYTHONPATH": str(checkout)}
    env.pop("FOGREF_VARIANT", None)
    return env


def ratio_range(before: list, after: list) -> str:
    """The per-round ratios ``before / after`` as ``median [smallest, largest]``.

    >>> ratio_range([2.0, 3.0, 4.0], [1.0, 1.0, 1.0])
    '3.00 [2.00, 4.00]'
    """
    r = sorted(b / x for b, x in zip(before, after))
    return f"{statistics.median(r):.2f} [{r[0]:.2f}, {r[-1]:.2f}]"
