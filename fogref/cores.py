"""The cores this process may run on: what fogref sizes its thread and process pools by.

>>> usable_cores() >= 1
True
"""

from __future__ import annotations

import os

__all__ = ["usable_cores"]


def usable_cores() -> int:
    """The number of cores this process may run on: its CPU affinity where the system has one
    (Linux; ``taskset`` and container CPU sets lower it), else ``os.cpu_count()``; at least 1."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
