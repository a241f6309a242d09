"""Fits kept on disk, so ``compare``, ``study`` and sweeps reuse them across processes.

A fit is stored as one JSON file in the ``fits`` folder of the render cache
(:func:`fogref.cache_dir.default_cache_dir`: ``$FOGREF_CACHE/fits``, else
``~/.cache/fogref/truths/fits``), named by its key: the SHA-256 of

* the physical scene the fit reads (every field of :class:`~fogref.mapping.PhysicalScene` that
  takes part in its equality: the fog, sun, sky, camera, the physical sky's parameters; that is
  the part of a truth's ``fogref.params`` a fit depends on),
* the fit's settings (which fit, its options and tolerance),
* fogref's version and the digest of the source of ``fogref/media``, ``fogref/models`` and
  ``fogref/mapping`` (:func:`fogref.cache_dir.sources_digest`).

The file repeats those inputs, and :func:`load_fit` returns an entry only when every one of
them still matches; a file that does not read (damaged, another format) is a miss.  Writes are
atomic (:func:`fogref.atomic.write_text_atomic`): parallel workers may race, the last one wins
with the same content.  A cache that cannot be written is reported by a warning, and the fit is
returned all the same.

Examples
--------
>>> import tempfile
>>> from fogref.media import FogMedium
>>> ps = PhysicalScene(FogMedium(), (1.0, 1.0, 0.0), 1.0)
>>> folder = Path(tempfile.mkdtemp())
>>> store_fit(ps, {"fit": "demo"}, {"value": 0.5}, folder)
>>> load_fit(ps, {"fit": "demo"}, folder)
{'value': 0.5}
>>> load_fit(ps, {"fit": "demo", "rtol": 0.01}, folder) is None
True
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import warnings
from pathlib import Path
from typing import Any

from fogref._version import __version__
from fogref.atomic import write_text_atomic
from fogref.cache_dir import default_cache_dir, sources_digest
from fogref.mapping.physical import PhysicalScene

__all__ = ["fit_cache_dir", "load_fit", "store_fit"]


def fit_cache_dir() -> Path:
    """The folder of the fit cache: ``fits`` in :func:`fogref.cache_dir.default_cache_dir`."""
    return default_cache_dir() / "fits"


def _plain(v: Any) -> Any:
    """``v`` as JSON values: dataclasses by their compared fields, tuples and arrays as lists."""
    if dataclasses.is_dataclass(v) and not isinstance(v, type):
        return {
            "type": type(v).__name__,
            **{f.name: _plain(getattr(v, f.name)) for f in dataclasses.fields(v) if f.compare},
        }
    if isinstance(v, dict):
        return {str(k): _plain(x) for k, x in sorted(v.items(), key=lambda kv: str(kv[0]))}
    if isinstance(v, (tuple, list)):
        return [_plain(x) for x in v]
    if hasattr(v, "tolist"):
        return _plain(v.tolist())
    if v is None or isinstance(v, (bool, int, float, str)):
        return v
    return repr(v)


def _inputs(pf: PhysicalScene, settings: dict) -> dict:
    root = Path(__file__).resolve().parents[1]
    return {
        "scene": _plain(pf),
        "settings": _plain(settings),
        "version": __version__,
        "source": sources_digest([root / "media", root / "models", root / "mapping"]),
    }


def _path(inputs: dict, folder: Path | None) -> Path:
    key = hashlib.sha256(json.dumps(inputs, sort_keys=True).encode()).hexdigest()[:32]
    return (Path(folder) if folder is not None else fit_cache_dir()) / f"{key}.json"


def load_fit(pf: PhysicalScene, settings: dict, folder: Path | None = None) -> dict | None:
    """The stored result of the fit ``settings`` of ``pf``, or None (no entry, a damaged one,
    or one whose inputs differ)."""
    inputs = _inputs(pf, settings)
    try:
        entry = json.loads(_path(inputs, folder).read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(entry, dict) or entry.get("inputs") != json.loads(json.dumps(inputs)):
        return None
    result = entry.get("result")
    return result if isinstance(result, dict) else None


def store_fit(pf: PhysicalScene, settings: dict, result: dict, folder: Path | None = None) -> None:
    """Store ``result`` (JSON values) as the fit ``settings`` of ``pf``, atomically."""
    inputs = _inputs(pf, settings)
    path = _path(inputs, folder)
    try:
        write_text_atomic(path, json.dumps({"inputs": inputs, "result": result}, indent=1))
    except OSError as e:
        warnings.warn(f"fit cache {path.parent}: not written ({e}); the fit is not kept", stacklevel=2)
