"""Multi-channel EXR files with the official OpenEXR bindings, written atomically.

This module only reads and writes files: the ground-truth layout (which channels,
what they mean) is :mod:`fogref.gbuffer`.  Header attributes are strings; values
that are not strings are stored as JSON and ``fogref.*`` attributes that hold
JSON are decoded on reading.
"""

from __future__ import annotations

import errno
import json
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import OpenEXR

from fogref.atomic import atomic_write
from fogref.cores import usable_cores
from fogref.errors import FogrefError

#: The lossless compressions :func:`write_exr` offers (OpenEXR's names, lower case), every one
#: readable by OpenEXR 2 and later: ``zip`` (zlib, 16 scan lines a block: the default; the
#: smallest files but the slowest to write), ``zips`` (zlib, one scan line a block), ``rle``
#: (run lengths: fast, larger), ``piz`` (wavelet and Huffman) and ``none``.  The lossy ones
#: (``pxr24``, ``b44``, ``dwaa``) would change a truth's float32 values and are not offered.
EXR_COMPRESSIONS = ("zip", "zips", "rle", "piz", "none")


def use_every_core() -> int:
    """Give OpenEXR's thread pool one thread per core this process may run on, unless it has as
    many already; returns the pool's size.  The setting is OpenEXR's, for the whole process and
    for good (its default is no thread: compression and decompression on the caller's thread).

    :func:`write_exr` and :func:`read_exr` call it: OpenEXR then compresses and decompresses a
    file's blocks of scan lines in parallel (ZIP blocks hold 16 lines), and the bytes written do
    not depend on the thread count.  On 2 cores a 72-channel truth's ZIP write takes 1.45x less
    time at 160x90 and 1.7x less at 320x180 and 960x540, its read 1.5-1.8x less (medians of 7
    pairs; each pair's ratio within about 0.3 of it); at 32x18 (two blocks) no gain beyond the
    pairs' spread (``reports/benchmarks/exr_threads.md``).

    >>> use_every_core() >= 1
    True
    """
    cores = usable_cores()
    if OpenEXR.global_thread_count() < cores:
        OpenEXR.set_global_thread_count(cores)
    return OpenEXR.global_thread_count()


def write_exr(path, channels: dict, attrs: dict | None = None, compression: str = "zip") -> None:
    """Write ``channels`` atomically to the EXR ``path`` (scan lines, ``compression``).

    Parameters
    ----------
    path
        Destination; its folder is created. The file appears only when complete
        (:func:`fogref.atomic.atomic_write`).
    channels
        Channel name -> ``(H, W)`` array, stored as float32. A channel with NaN or
        infinity (also after the cast: values beyond float32's range) is refused
        with :class:`~fogref.errors.FogrefError`; nothing is silently replaced.
    attrs
        Header attributes; values that are not strings are stored as JSON strings.
    compression
        One of :data:`EXR_COMPRESSIONS` (all lossless: the values read back are the same);
        another is a :class:`~fogref.errors.FogrefError`.

    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "a.exr"
    >>> ramp = {"R": np.linspace(0, 1, 6, dtype=np.float32).reshape(2, 3) / 3}
    >>> for c in EXR_COMPRESSIONS:
    ...     write_exr(p, ramp, compression=c)
    ...     assert np.array_equal(read_exr(p)[0]["R"], ramp["R"]), c
    >>> write_exr(p, ramp, compression="b44")
    Traceback (most recent call last):
    ...
    fogref.errors.FogrefError: ...: EXR compression 'b44' is not one of zip, zips, rle, piz, none ...
    """
    path = Path(path)
    if compression not in EXR_COMPRESSIONS:
        raise FogrefError(
            f"{path}: EXR compression {compression!r} is not one of {', '.join(EXR_COMPRESSIONS)} "
            "(the lossless ones)"
        )
    path.parent.mkdir(parents=True, exist_ok=True)
    kind = getattr(OpenEXR, f"{'NO' if compression == 'none' else compression.upper()}_COMPRESSION")
    header = {"compression": kind, "type": OpenEXR.scanlineimage}
    for k, v in (attrs or {}).items():
        header[k] = v if isinstance(v, str) else json.dumps(v)
    with np.errstate(over="ignore", invalid="ignore"):  # beyond float32: inf, refused just below
        chans = {k: np.ascontiguousarray(np.asarray(v, dtype=np.float32)) for k, v in channels.items()}
    bad = [k for k, v in chans.items() if not np.all(np.isfinite(v))]
    if bad:
        raise FogrefError(f"{path}: refusing to write non-finite values in channel(s) {', '.join(bad)}")

    def write(tmp):
        use_every_core()
        try:
            with OpenEXR.File(header, chans) as f:
                f.write(tmp)
        except RuntimeError as e:  # OpenEXR reports I/O failures (a full disk) as RuntimeError
            code = errno.ENOSPC if "No space left" in str(e) else errno.EIO
            raise OSError(
                code, f"{os.strerror(code)}; {path} was not written (an older file there is kept)", str(path)
            ) from e

    atomic_write(path, write)


def read_exr(path) -> tuple[dict, dict]:
    """Read an EXR: ``(channels, attrs)``, channels as ``(H, W)`` float32 arrays.

    ``fogref.*`` attributes that hold JSON are decoded; other attributes are
    returned as the bindings give them.

    Raises
    ------
    fogref.errors.FogrefError
        The file is missing or not a readable EXR (the message names it).
    """
    path = Path(path)
    with _opened(path, separate_channels=True) as f:
        chans = {k: np.array(v.pixels, dtype=np.float32) for k, v in f.channels().items()}
        return chans, _decoded(f.header())


def read_exr_header(path) -> tuple[dict, tuple[int, int]]:
    """The attributes of the EXR ``path`` (decoded as :func:`read_exr` decodes them) and its size
    ``(H, W)`` [pixels], without reading its pixels: what deciding about a file needs (is it a
    truth, may a render extend it), at the cost of its header whatever the image's size.

    Raises
    ------
    fogref.errors.FogrefError
        The file is missing or not a readable EXR (the message names it).

    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "a.exr"
    >>> write_exr(p, {"R": np.zeros((2, 3))}, {"fogref.spp": 4})
    >>> attrs, size = read_exr_header(p)
    >>> attrs["fogref.spp"], size
    (4, (2, 3))
    """
    path = Path(path)
    with _opened(path, header_only=True) as f:
        header = f.header()
        (x0, y0), (x1, y1) = (np.asarray(c).tolist() for c in header["dataWindow"])
        return _decoded(header), (int(y1 - y0 + 1), int(x1 - x0 + 1))


@contextmanager
def _opened(path: Path, **options) -> Iterator:
    """``OpenEXR.File(path, **options)``; FogrefError naming ``path`` when it is missing or not a
    readable EXR (also when reading its header or pixels in the ``with`` block fails)."""
    if not path.is_file():
        raise FogrefError(f"{path}: no such EXR file")
    use_every_core()
    try:
        with OpenEXR.File(str(path), **options) as f:
            yield f
    except Exception as e:
        raise FogrefError(f"{path}: not a readable EXR file ({e})") from e


def _decoded(header) -> dict:
    """The header's attributes, ``fogref.*`` ones that hold JSON decoded."""
    attrs = {}
    for k, v in dict(header).items():
        if isinstance(v, str) and k.startswith("fogref."):
            try:
                v = json.loads(v)
            except ValueError:
                pass
        attrs[k] = v
    return attrs


def rgb(channels: dict, group: str = "") -> np.ndarray:
    """Stack ``group + "R"``, ``"G"``, ``"B"`` into an ``(H, W, 3)`` array.

    ``group`` is a channel prefix such as ``"inscatter."``; ``""`` (the default)
    is the total radiance ``R,G,B``.
    """
    return np.stack([channels[group + c] for c in "RGB"], axis=-1)
