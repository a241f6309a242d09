"""The render checkpoint: one atomic record of a render's running sums.

The per-pixel float64 sums, squares and channel-pair products, the number of passes they
hold and the render's key are written together in one ``.npz`` with a SHA-256 over all of
them (:func:`write_checkpoint`, through :func:`fogref.atomic.savez_atomic`).  :func:`resume`
reads one back only when every check passes (:func:`checkpoint_problem`: fields, key, pass
count, dtype, shape, checksum, finite values, the sums of the [0, 1]-bounded channels within
the sample count); a checkpoint of other inputs or settings is left to be replaced, and one
that is damaged is renamed ``<name>.damaged[N]`` with a one-line warning (:func:`set_aside_checkpoint`).
The driver (:mod:`fogref.render.render`) defers SIGINT/SIGTERM across the write.
"""

from __future__ import annotations

import functools
import hashlib
import sys
from pathlib import Path

import numpy as np

from fogref import gbuffer
from fogref.atomic import savez_atomic, set_aside

__all__ = [
    "checkpoint_problem",
    "checkpoint_record",
    "record_sha256",
    "resume",
    "set_aside_checkpoint",
    "write_checkpoint",
]


def record_sha256(key: str, done: int, sums: np.ndarray, squares: np.ndarray) -> str:
    """SHA-256 binding a checkpoint's parts: its key, its pass count and its sums' bytes and shapes.

    The arrays are hashed in place as little-endian float64 in C order, with no copy of their
    bytes (a 1920x1080 render's sums and squares are 1.2 GB, and copying them took more time
    than hashing them).

    >>> a, b = np.arange(6.0).reshape(2, 3), np.ones((2, 1), dtype=np.float32)
    >>> same = f"k\\0{7}\\0{a.shape}\\0{b.shape}\\0".encode() + a.tobytes() + b.astype("<f8").tobytes()
    >>> record_sha256("k", 7, a, b) == hashlib.sha256(same).hexdigest()
    True
    """
    h = hashlib.sha256(f"{key}\0{done}\0{sums.shape}\0{squares.shape}\0".encode())
    for a in (sums, squares):
        h.update(memoryview(np.ascontiguousarray(a, dtype="<f8")).cast("B"))
    return h.hexdigest()


def checkpoint_record(state, key: str) -> dict:
    """The arrays of one checkpoint record, for ``np.savez``: the running state ``(sums, squares,
    passes done)`` (copied from the device) with its key and a SHA-256 over them all."""
    sums, squares, done = state
    sums, squares = np.asarray(sums, dtype=np.float64), np.asarray(squares, dtype=np.float64)
    return {
        "sums": sums,
        "squares": squares,
        "done": np.array(done),
        "key": np.array(key),
        "sha256": np.array(record_sha256(key, done, sums, squares)),
    }


def write_checkpoint(ckpt: Path, state, key: str) -> None:
    """Write the running state ``(sums, squares, passes done)`` atomically to ``ckpt`` as one
    record (:func:`checkpoint_record`)."""
    savez_atomic(ckpt, **checkpoint_record(state, key))


#: Per-sample channels bounded by [0, 1]: per pixel, their sums can't exceed the sample count.
_BOUNDED = ("T", "surface_coverage", "hit")


def sum_channels(group: str) -> slice:
    """Where ``group``'s channels sit in the last axis of the sums (``final`` first, then
    :data:`fogref.gbuffer.SAMPLE_GROUPS`); KeyError for another name.

    >>> sum_channels("final")
    slice(0, 3, None)
    """
    return _sum_slices()[group]


@functools.cache
def _sum_slices() -> dict[str, slice]:
    """Group -> its slice of the sums' last axis (built once: the driver asks for every group
    at the end of every render)."""
    slices, i = {}, 0
    for g in ("final",) + tuple(gbuffer.SAMPLE_GROUPS):
        k = len(gbuffer.channel_names(g))
        slices[g], i = slice(i, i + k), i + k
    return slices


def _sum_widths() -> tuple[int, int]:
    """Channels of the sums and of the squares (each squared group: 3 squares, 3 channel-pair products)."""
    n = sum(len(gbuffer.channel_names(g)) for g in ("final",) + tuple(gbuffer.SAMPLE_GROUPS))
    return n, 6 * len(gbuffer.SQUARED_GROUPS)


def checkpoint_problem(z, key: str, shape: tuple, passes: list):
    """Why the loaded checkpoint ``z`` can't be resumed (a phrase), else None.  'stale' when it
    belongs to other inputs or settings."""
    names = set(z.files)
    if not {"sums", "squares", "done", "key", "sha256"} <= names:
        missing = sorted({"sums", "squares", "done", "key", "sha256"} - names)
        return f"not a checkpoint of this fogref (no {', '.join(missing)})"
    if str(z["key"]) != key:
        return "stale"
    sums, squares, done = z["sums"], z["squares"], z["done"]
    if done.shape != () or done.dtype.kind not in "iu" or not 1 <= int(done) <= len(passes):
        return f"pass count {done.tolist()!r} outside [1, {len(passes)}]"
    done = int(done)
    ns, nq = _sum_widths()
    if sums.dtype != np.float64 or squares.dtype != np.float64:
        return f"sums of type {sums.dtype}/{squares.dtype}, not float64"
    if sums.shape != (*shape, ns) or squares.shape != (*shape, nq):
        return f"sums of shape {sums.shape}/{squares.shape}, expected {(*shape, ns)}/{(*shape, nq)}"
    if str(z["sha256"]) != record_sha256(key, done, sums, squares):
        return "its SHA-256 does not match its content"
    if not (np.isfinite(sums).all() and np.isfinite(squares).all()):
        return "non-finite sums"
    n = sum(passes[:done])
    for g in _BOUNDED:
        part = sums[..., sum_channels(g)]
        if part.min() < 0 or part.max() > n * (1 + 1e-9):
            return f"the sums of '{g}' leave [0, {n}] (the samples of {done} pass(es))"
    return None


def set_aside_checkpoint(ckpt: Path, reason: str) -> None:
    """Rename a checkpoint that can't be resumed to an unused ``<ckpt>.damaged[N]``
    (:func:`fogref.atomic.set_aside`), with a one-line warning."""
    try:
        where = f"set aside as {set_aside(ckpt, '.damaged')}"
    except OSError as e:
        where = f"could not be set aside ({e.strerror}); it will be replaced"
    print(
        f"fogref render: warning: checkpoint {ckpt}: {reason}; {where}; rendering from the start",
        file=sys.stderr,
    )


def resume(ckpt: Path, key: str, shape: tuple, passes: list):
    """``(sums, squares, passes done)`` from a checkpoint of this render, else None.

    A checkpoint of other inputs or settings is left to be replaced; one that can't be
    read or fails a check (:func:`checkpoint_problem`) is set aside (:func:`set_aside_checkpoint`).
    """
    if not ckpt.exists():
        return None
    try:
        with np.load(ckpt, allow_pickle=False) as z:
            problem = checkpoint_problem(z, key, shape, passes)
            if problem is None:
                return z["sums"], z["squares"], int(z["done"])
    except Exception as e:  # any way a damaged file fails to read: zip, npy header, CRC, pickle refused
        detail = (str(e).splitlines() or ["no detail"])[0]
        problem = f"unreadable ({type(e).__name__}: {detail[:80]}{'...' if len(detail) > 80 else ''})"
    if problem != "stale":
        set_aside_checkpoint(ckpt, problem)
    return None
