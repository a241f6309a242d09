"""Where fogref keeps what it computes once, and the digest of the source that computed it.

The render cache (:mod:`fogref.render.cache`) keeps truths in :func:`default_cache_dir`; the
fit cache (:mod:`fogref.mapping.fit_cache`) keeps fits in its ``fits`` folder.  Both key an
entry on the digest of the source files that produce it (:func:`sources_digest`), so a changed
renderer or fit never returns a stale entry.

Examples
--------
>>> import fogref
>>> from pathlib import Path
>>> root = Path(fogref.__file__).parent
>>> len(sources_digest([root / "media", root / "gbuffer.py"]))
64
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path
from typing import Iterable

__all__ = ["default_cache_dir", "sources_digest"]


def default_cache_dir() -> Path:
    """``$FOGREF_CACHE``, else ``~/.cache/fogref/truths``."""
    env = os.environ.get("FOGREF_CACHE")
    return Path(env) if env else Path.home() / ".cache" / "fogref" / "truths"


def sources_digest(paths: Iterable[Path]) -> str:
    """SHA-256 (hex) of the names and bytes of the given files and of the ``*.py`` files of the
    given folders (each folder's files sorted by name); a path that does not exist is skipped."""
    h = hashlib.sha256()
    for p in paths:
        files = sorted(Path(p).glob("*.py")) if Path(p).is_dir() else [Path(p)]
        for f in files:
            if f.is_file():
                h.update(f.name.encode())
                h.update(f.read_bytes())
    return h.hexdigest()
