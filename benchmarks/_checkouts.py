"""What the benchmarks that compare checkouts say about one: its commit."""

from __future__ import annotations

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
