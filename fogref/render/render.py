"""Render a fogref scene to a ground-truth EXR (the layout of :mod:`fogref.gbuffer`).

The driver asks ``fogpath`` for per-pixel sums and sums of squares of every
per-sample part (:meth:`FogPathIntegrator.render_moments`), in as few passes as
the back end's memory allows, and turns them into means and standard errors.

* **Pixel-exact by default**: every sample of a pixel goes through its centre, so
  the G-buffer and ``T`` are exact and a model with exact extinction matches ``T``
  at every pixel, silhouettes included.  ``pixel_filter="box"`` spreads samples
  over the pixel (anti-aliased pictures).
* **Deterministic**: pass ``k`` has its own seed derived from ``seed``; the same
  ``(scene, overrides, spp, seed, pixel_filter, variant)`` gives identical pixels.
* **Cheap**: the running sums stay on the device (Dr.Jit float64, added there after
  every pass; copied to the host only for a checkpoint and once at the end), and the
  passes are as few and as equal as :data:`fogref.render.passes.MAX_LANES` allows (``benchmarks/render_driver.py``
  measures the driver against one ``mi.render`` call).
* **Resumable**: the running sums are checkpointed atomically next to the output
  (``<out>.partial.npz``) every ``checkpoint_seconds`` and on Ctrl-C; a rerun resumes
  only from a checkpoint whose key (the scene file's content hash, overrides,
  resolution, spp, seed, filter, variant, fogref version) matches.
* **Nothing lost**: the output must be a ``.exr`` that is neither the scene nor an
  existing non-EXR file; its folder is checked writable before rendering; a truth
  with a non-finite value is refused, with the pixels named.
"""

from __future__ import annotations

import hashlib
import json
import os
import signal
import time
from pathlib import Path

import numpy as np

from fogref import gbuffer
from fogref._version import __version__
from fogref.atomic import atomic_write, savez_atomic
from fogref.errors import FogrefError
from fogref.exrio import write_exr
from fogref.render.passes import max_lanes, pass_seed, pass_sizes

PIXEL_FILTERS = ("centre", "box")
#: Bytes per pixel the driver holds: float64 sums of 30 channels and 42 squares and
#: channel-pair products, twice (running sum and the pass being added), plus the EXR's
#: float32 channels.
_HOST_BYTES_PER_PIXEL = (30 + 42) * 8 * 2 + len(gbuffer.exr_channel_names()) * 4


def file_sha256(path) -> str:
    """SHA-256 of a file's bytes (hex)."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _physical_memory() -> int:
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return 1 << 40


def check_output(out: Path, scene_path: Path, png: bool) -> None:
    """Refuse outputs that would overwrite an input or cannot be written, before rendering."""
    if out.suffix.lower() != ".exr":
        raise FogrefError(f"--out {out}: the ground truth is an EXR; give a path ending in .exr "
                          f"(the PNG preview is written beside it)")
    outputs = [out] + ([out.with_suffix(".png")] if png else [])
    for o in outputs:
        if o.exists() and o.resolve() == scene_path.resolve():
            raise FogrefError(f"--out {out}: would overwrite the scene file {scene_path}")
        if o.is_dir():
            raise FogrefError(f"--out {out}: {o} is a directory")
    if out.exists() and not _is_exr(out):
        raise FogrefError(f"--out {out}: exists and is not an EXR; refusing to overwrite it")
    folder = out.parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise FogrefError(f"--out {out}: cannot create the folder {folder} ({e.strerror})") from None
    try:
        atomic_write(folder / f".{out.name}.writable", lambda tmp: Path(tmp).write_bytes(b"x"))
        (folder / f".{out.name}.writable").unlink()
    except OSError as e:
        raise FogrefError(f"--out {out}: the folder {folder} is not writable ({e.strerror})") from None


def _is_exr(path: Path) -> bool:
    with open(path, "rb") as f:
        return f.read(4) == b"\x76\x2f\x31\x01"


class _NoBar:
    """The progress bar of a quiet render: counts nothing, shows nothing."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def update(self, n):
        pass


class _Interrupt:
    """First Ctrl-C: stop after the current pass (checkpointed); second: stop now."""

    def __init__(self):
        self.requested = False
        self._previous = None

    def __enter__(self):
        try:
            self._previous = signal.signal(signal.SIGINT, self._handle)
        except ValueError:  # not the main thread: leave Ctrl-C alone
            self._previous = None
        return self

    def _handle(self, signum, frame):
        if self.requested:
            raise KeyboardInterrupt
        self.requested = True

    def __exit__(self, *exc):
        if self._previous is not None:
            signal.signal(signal.SIGINT, self._previous)
        return False


def render(scene_path, out, spp: int = 64, seed: int = 0, variant: str | None = None,
           overrides: dict | None = None, progress: bool = True, resume: bool = True, png: bool = True,
           pixel_filter: str = "centre", checkpoint_seconds: float = 60.0) -> Path:
    """Render ``scene_path`` with ``spp`` samples per pixel into the EXR ``out``.

    Parameters
    ----------
    scene_path:   a fogref XML scene (``fogpath`` integrator, ``heightfog`` medium).
    out:          the output ``.exr``; a PNG preview goes beside it when ``png``.
    spp:          samples per pixel, [1, 2^20].  seed: [0, 2^31).
    variant:      Mitsuba variant (default ``llvm_ad_rgb``; ``cuda_ad_rgb`` on a GPU).
    overrides:    XML ``$name`` defaults to replace, e.g. ``{"res": 64}``.
    pixel_filter: ``"centre"`` (pixel-exact, the default for truths) or ``"box"``.
    checkpoint_seconds: time between checkpoints (and one on Ctrl-C).

    Returns the EXR path.  Raises :class:`FogrefError` (or its ParameterError) for bad input.
    """
    if not isinstance(spp, int) or not 1 <= spp <= 1 << 20:
        raise FogrefError(f"--spp: {spp} outside [1, 1048576]")
    if not isinstance(seed, int) or not 0 <= seed < 1 << 31:
        raise FogrefError(f"--seed: {seed} outside [0, 2^31)")
    if pixel_filter not in PIXEL_FILTERS:
        raise FogrefError(f"--pixel-filter: '{pixel_filter}' is not one of {PIXEL_FILTERS}")
    scene_path, out = Path(scene_path), Path(out)
    check_output(out, scene_path, png)

    from fogref.render.scene import load_scene
    from fogref.render.variant import set_variant

    variant = set_variant(variant)
    import drjit as dr
    import mitsuba as mi

    scene, desc = load_scene(scene_path, overrides)
    integrator = scene.integrator()
    if not hasattr(integrator, "render_moments"):
        raise FogrefError(f"{scene_path}: the scene's integrator must be 'fogpath' to write a ground truth")
    integrator.aovs = True
    W, H = (int(x) for x in scene.sensors()[0].film().crop_size())
    need = W * H * _HOST_BYTES_PER_PIXEL
    if need > 0.5 * _physical_memory():
        raise FogrefError(f"{scene_path}: {W}x{H} pixels need about {need / 2**30:.1f} GiB of memory for the "
                          f"ground truth; this machine has {_physical_memory() / 2**30:.1f} GiB (limit: half)")
    passes = pass_sizes(W * H, spp, max_lanes(variant))
    scene_sha = file_sha256(scene_path)
    key = json.dumps({"scene_sha256": scene_sha, "overrides": {k: str(v) for k, v in (overrides or {}).items()},
                      "size": [W, H], "spp": spp, "seed": seed, "variant": variant, "passes": passes,
                      "pixel_filter": pixel_filter, "version": __version__,
                      "schema": gbuffer.SCHEMA_VERSION}, sort_keys=True)
    ckpt = out.with_name(out.name + ".partial.npz")
    for stale in out.parent.glob(ckpt.name + ".*.tmp*"):  # a writer killed mid-write
        stale.unlink(missing_ok=True)
    sums, squares, done = _resume(ckpt, key) if resume else (None, None, 0)
    if sums is not None:  # the running sums live on the device
        sums, squares = mi.TensorXd(sums), mi.TensorXd(squares)

    if progress:
        from tqdm import tqdm

        bar = tqdm(total=spp, initial=sum(passes[:done]), unit="spp", desc=scene_path.name)
    else:  # no bar, no tqdm import (20 ms of a quiet CLI run's start-up)
        bar = _NoBar()
    t0, last_ckpt, timings = time.perf_counter(), time.perf_counter(), []
    with _Interrupt() as stop, bar:
        try:
            for k in range(done, len(passes)):
                ts = time.perf_counter()
                s, q = integrator.render_moments(scene, 0, pass_seed(seed, k), passes[k],
                                                 pixel_exact=pixel_filter == "centre")
                s, q = _device_f64(s), _device_f64(q)
                sums, squares = (s, q) if sums is None else (sums + s, squares + q)
                dr.eval(sums, squares)
                dr.sync_thread()
                timings.append(time.perf_counter() - ts)
                done = k + 1
                bar.update(passes[k])
                if stop.requested:
                    raise KeyboardInterrupt
                if done < len(passes) and time.perf_counter() - last_ckpt > checkpoint_seconds:
                    _checkpoint(ckpt, sums, squares, done, key)
                    last_ckpt = time.perf_counter()
        except (KeyboardInterrupt, RuntimeError) as e:
            if isinstance(e, RuntimeError) and "KeyboardInterrupt" not in str(e):
                raise
            if sums is not None and done < len(passes):
                _checkpoint(ckpt, sums, squares, done, key)
            raise KeyboardInterrupt from None

    channels = _host_float32(_channels(sums, squares, spp))  # arithmetic on the device, one copy
    bad = gbuffer.nonfinite_report(channels)
    if bad:
        raise FogrefError(f"{scene_path}: the render produced {bad}; no ground truth written "
                          f"(please report this with the scene and the command)")
    attrs = {
        "fogref.schema": str(gbuffer.SCHEMA_VERSION),
        "fogref.params": desc,
        "fogref.spp": str(spp),
        "fogref.seed": str(seed),
        "fogref.pixel_filter": pixel_filter,
        "fogref.passes": passes,
        "fogref.variant": variant,
        "fogref.version": __version__,
        "fogref.mitsuba": mi.__version__,
        "fogref.scene": str(scene_path),
        "fogref.scene_sha256": scene_sha,
        "fogref.overrides": {k: str(v) for k, v in (overrides or {}).items()},
        "fogref.render_seconds": {"total": time.perf_counter() - t0, "passes": timings},
    }
    _exr_threads()
    write_exr(out, channels, attrs)
    if png:
        from fogref.display import write_preview

        write_preview(np.stack([channels[c] for c in "RGB"], axis=-1), out.with_suffix(".png"))
    ckpt.unlink(missing_ok=True)
    return out


def _device_f64(x):
    """A pass's sums as a Dr.Jit float64 tensor (what ``render_moments`` returns; anything
    array-like is converted)."""
    import mitsuba as mi

    if isinstance(x, mi.TensorXd):
        return x
    return mi.TensorXd(np.ascontiguousarray(np.asarray(x, dtype=np.float64)))


def _host_float32(channels: dict) -> dict:
    """The EXR's channels, ``(H, W)`` float64 tensors on the device, as host float32 planes.

    All channels are cast and stacked on the device and copied to the host in one
    contiguous block (each channel a contiguous plane).  At 1920x1080 the channel
    arithmetic in numpy on the host and the per-channel copies took 4.2 s of a 10.3 s
    render (4 spp, CPU); on the device they are part of one kernel.
    """
    import drjit as dr
    import mitsuba as mi

    names = list(channels)
    h, w = (int(x) for x in channels[names[0]].shape)
    flat = dr.concat([mi.Float(channels[k].array) for k in names])
    planes = np.asarray(flat).reshape(len(names), h, w)
    return dict(zip(names, planes))


def _exr_threads() -> None:
    """Let OpenEXR compress with every core (its default is 0 threads: the caller's thread
    only).  ZIP output does not depend on the thread count."""
    import OpenEXR

    if hasattr(OpenEXR, "set_global_thread_count") and OpenEXR.global_thread_count() < (os.cpu_count() or 1):
        OpenEXR.set_global_thread_count(os.cpu_count() or 1)


def _checkpoint(ckpt: Path, sums, squares, done: int, key: str) -> None:
    """Write the running sums (copied from the device) atomically to ``ckpt``."""
    savez_atomic(ckpt, sums=np.asarray(sums, dtype=np.float64), squares=np.asarray(squares, dtype=np.float64),
                 done=np.array(done), key=np.array(key))


def _channels(sums, squares, spp: int) -> dict:
    """EXR channels from the integrator's per-pixel sums, ``(H, W, K)`` Dr.Jit float64
    tensors or numpy arrays (see :func:`gbuffer.moments_to_channels`)."""
    names = ["final"] + list(gbuffer.SAMPLE_GROUPS)
    by_group, i = {}, 0
    for g in names:
        k = len(gbuffer.channel_names(g))
        by_group[g] = sums[..., i:i + k]
        i += k
    k = 3 * len(gbuffer.SQUARED_GROUPS)  # squares first, then the channel-pair products
    sq = {g: squares[..., 3 * i:3 * i + 3] for i, g in enumerate(gbuffer.SQUARED_GROUPS)}
    cross = {g: squares[..., k + 3 * i:k + 3 * i + 3] for i, g in enumerate(gbuffer.SQUARED_GROUPS)}
    return gbuffer.moments_to_channels(by_group, sq, spp, cross)


def _resume(ckpt: Path, key: str):
    """(sums, squares, passes done) from a checkpoint whose key matches, else nothing."""
    if not ckpt.exists():
        return None, None, 0
    try:
        with np.load(ckpt, allow_pickle=False) as z:
            if str(z["key"]) == key:
                return z["sums"], z["squares"], int(z["done"])
    except (OSError, ValueError, KeyError):
        pass
    return None, None, 0
