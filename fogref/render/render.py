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
  every pass; copied to the host only for a checkpoint and once at the end, for the moments
  file and, up to :data:`HOST_CHANNELS_MAX_PIXELS`, the channels' numpy arithmetic), and the
  passes are as few and as equal as :data:`fogref_plugins.passes.MAX_LANES` allows
  (``benchmarks/render_driver.py``
  measures the driver against one ``mi.render`` call).  A process keeps the scene it loaded
  last (:func:`fogref.render.load.loaded_scene`: same input files, variant and overrides), so a
  render repeated with another seed skips loading and replays fogpath's frozen passes
  (``benchmarks/frozen_render.py``); that scene is released before another loads, so a new
  configuration of the scene reuses its compiled kernels (``reports/sweeps/kernel_reuse.md``).
* **Resumable**: the running sums are checkpointed atomically next to the output
  (``<out>.partial.npz``) every ``checkpoint_seconds`` and on Ctrl-C or SIGTERM; a rerun
  resumes only from a checkpoint whose key (the digest of the scene and of every file it
  loads, :func:`fogref.scene.inputs.inputs_digest`; overrides, resolution, spp, seed,
  filter, variant, fogref version) matches.  A checkpoint is one record: the sums, their
  squares and the count of passes they hold change together in memory (one assignment)
  and on disk (one file, with a SHA-256 of its content); signals are deferred while it is
  written.  A checkpoint that is damaged or inconsistent (unreadable, wrong checksum,
  shape, count, non-finite values, a bounded channel summing past its sample count) is
  renamed aside with a one-line warning, and the render starts over.
* **Extensible**: the float64 sums of a finished render are kept beside it
  (``<out>.moments.npz``, :func:`moments_path`; ``keep_moments=False`` does not keep them).
  Rendering again to the same ``out`` with more samples adds passes to those sums instead of
  starting over, and says so: passes ``k = len(old passes), ...`` with their own seeds, so the
  result is bitwise the render whose passes are the old ones followed by the new ones (the
  merge of the passes on Dask, :mod:`fogref.render.distributed`).  It is refused, with the
  reason, when the scene or a file it loads changed, or the seed, overrides, resolution, pixel
  filter, variant or fogref version differ, or the sums are missing; ``resume=False`` renders
  afresh.  Not more samples than the truth holds: a new render, as before.
* **Nothing lost**: the output must be a ``.exr`` that is not an existing non-EXR file,
  and no output (the EXR, its PNG preview, the checkpoint) may be the scene or a file
  it loads (:func:`fogref.atomic.refuse_overwriting_inputs`); the folder is checked
  writable before rendering; a truth with a non-finite value is refused, with the pixels
  named.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import functools
import json
import os
import re
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
from fogref_plugins.passes import MAX_LANES_VARIABLE, max_lanes, pass_seed, pass_sizes

from fogref import cluster, gbuffer
from fogref._version import __version__
from fogref.atomic import atomic_write, refuse_overwriting_inputs, staged_write, temporary_names
from fogref.display import write_preview
from fogref.errors import FogrefError
from fogref.exrio import EXR_COMPRESSIONS, read_exr_header, write_exr
from fogref.render import checkpoint, distributed
from fogref.render import load as scene_loader
from fogref.render.variant import set_variant
from fogref.scene.inputs import file_sha256
from fogref.scene.parsed import ParsedScene, read_scene

PIXEL_FILTERS = ("centre", "box")
_SOURCE = "fogref render"
#: Up to this many pixels the EXR's channels are numpy arithmetic on the host copy of the sums (no
#: Dr.Jit kernel traced for them); above, one fused Dr.Jit kernel (numpy's temporaries cost more
#: than the tracing).  Both timed on the same sums in ``reports/benchmarks/frozen_render.md``; the
#: two give the same float64 values, bit for bit (tests/test_render_exr.py).
HOST_CHANNELS_MAX_PIXELS = 1 << 12
#: Bytes per pixel the driver holds: float64 sums of 30 channels and 42 squares and
#: channel-pair products, twice (running sum and the pass being added), plus the EXR's
#: float32 channels.
_HOST_BYTES_PER_PIXEL = (30 + 42) * 8 * 2 + len(gbuffer.exr_channel_names()) * 4


__all__ = ["render", "check_output", "checkpoint_path", "moments_path", "PIXEL_FILTERS"]


def _physical_memory() -> int:
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return 1 << 40


def checkpoint_path(out) -> Path:
    """Where :func:`render` keeps the running sums of ``out``: ``<out>.partial.npz``."""
    return Path(out).with_name(Path(out).name + ".partial.npz")


def moments_path(out) -> Path:
    """Where :func:`render` keeps the float64 sums of the finished ``out``: ``<out>.moments.npz``
    (the checkpoint's format, :mod:`fogref.render.checkpoint`)."""
    return Path(out).with_name(Path(out).name + ".moments.npz")


def workers_log_path(out) -> Path:
    """Where a LocalCluster's workers write their own output while rendering ``out``, and where a
    render on any cluster names the passes redone because a worker was lost: ``<out>.workers.log``."""
    return Path(out).with_name(Path(out).name + ".workers.log")


def check_output(
    out: Path, scene_path: Path, png: bool, inputs: list | None = None, workers_log: bool = False
) -> None:
    """Refuse outputs that would overwrite an input or cannot be written, before rendering.

    The outputs are ``out``, its PNG preview (when ``png``), its checkpoint and, with
    ``workers_log``, the workers' log (:func:`workers_log_path`); the inputs are the scene
    and every file it loads (``inputs``, from :func:`fogref.scene.inputs.scene_inputs`;
    only the scene when None).
    """
    if out.suffix.lower() != ".exr":
        raise FogrefError(
            f"--out {out}: the ground truth is an EXR; give a path ending in .exr "
            f"(the PNG preview is written beside it)"
        )
    outputs = [(out, "EXR")] + ([(out.with_suffix(".png"), "PNG preview")] if png else [])
    outputs += [(checkpoint_path(out), "checkpoint"), (moments_path(out), "moments")]
    if workers_log:
        outputs.append((workers_log_path(out), "workers' log"))
    refuse_overwriting_inputs(
        outputs, inputs if inputs is not None else [(scene_path, "scene file")], f"--out {out}"
    )
    for o, _ in outputs:
        if o.is_dir():
            raise FogrefError(f"--out {out}: {o} is a directory")
    if out.exists() and not _is_exr(out):
        raise FogrefError(f"--out {out}: exists and is not an EXR; refusing to overwrite it")
    folder = out.parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise FogrefError(f"--out {out}: cannot create the folder {folder} ({e.strerror})") from None
    names = (folder / f".{out.name}.writable{n or ''}" for n in range(100))
    probe = next((p for p in names if not (p.exists() or p.is_symlink())), None)  # never a file of the user's
    try:
        if probe is not None:
            atomic_write(probe, lambda tmp: Path(tmp).write_bytes(b"x"))
            probe.unlink()
    except OSError as e:
        raise FogrefError(f"--out {out}: the folder {folder} is not writable ({e.strerror})") from None


def _is_exr(path: Path) -> bool:
    with open(path, "rb") as f:
        return f.read(4) == b"\x76\x2f\x31\x01"


def render(
    scene_path,
    out,
    spp: int = 64,
    seed: int = 0,
    variant: str | None = None,
    overrides: dict | None = None,
    progress: bool = True,
    resume: bool = True,
    png: bool = True,
    pixel_filter: str = "centre",
    checkpoint_seconds: float = 60.0,
    scheduler: str | None = None,
    workers: int | None = None,
    keep_moments: bool = True,
    worker_timeout: float = cluster.WORKER_TIMEOUT,
    exr_compression: str = "zip",
) -> Path:
    """Render ``scene_path`` with ``spp`` samples per pixel into the EXR ``out``.

    Parameters
    ----------
    scene_path:   a fogref XML scene (``fogpath`` integrator, ``heightfog`` medium), or one already
                  read (:class:`~fogref.scene.parsed.ParsedScene`, which carries its overrides).
    out:          the output ``.exr``; a PNG preview goes beside it when ``png``.
    spp:          samples per pixel, [1, 2^20].  seed: [0, 2^31).
    variant:      Mitsuba variant (default ``llvm_ad_rgb``; ``cuda_ad_rgb`` on a GPU).
    overrides:    XML ``$name`` defaults to replace, e.g. ``{"res": 64}``.
    pixel_filter: ``"centre"`` (pixel-exact, the default for truths) or ``"box"``.
    checkpoint_seconds: time between checkpoints (and one on Ctrl-C or SIGTERM).
    scheduler:    a running Dask scheduler's address (``tcp://HOST:8786``): the passes run on its
                  workers (:mod:`fogref.render.distributed`), the same pixels as here.
    workers:      with no ``scheduler``: the passes run on a new LocalCluster of this many
                  single-threaded worker processes [1, 4096] (their output: ``<out>.workers.log``).
    keep_moments: keep the float64 sums beside the EXR (:func:`moments_path`, 576 bytes per
                  pixel), so that a later render with more samples adds to them.
    resume:       resume from a checkpoint, and add samples to an existing truth at ``out``
                  (the module doc); False: render afresh.
    worker_timeout: with ``scheduler``: seconds to wait for its first worker, (0, 1e6] (it says
                  that it waits; then a one-line error).
    exr_compression: the EXR's lossless compression, one of
                  :data:`fogref.exrio.EXR_COMPRESSIONS` (``zip``: the smallest file; ``none``
                  and ``rle`` write faster, the same values in a larger file).

    Returns the EXR path.  Raises :class:`FogrefError` (or its ParameterError) for bad input,
    and before any work when an output (the EXR, the PNG, the checkpoint) is the scene or a
    file it loads.  Raises KeyboardInterrupt after a Ctrl-C or SIGTERM (checkpoint written).
    """
    if not isinstance(spp, int) or not 1 <= spp <= 1 << 20:
        raise FogrefError(f"--spp: {spp} outside [1, 1048576]")
    if not isinstance(seed, int) or not 0 <= seed < 1 << 31:
        raise FogrefError(f"--seed: {seed} outside [0, 2^31)")
    if pixel_filter not in PIXEL_FILTERS:
        raise FogrefError(f"--pixel-filter: '{pixel_filter}' is not one of {PIXEL_FILTERS}")
    if exr_compression not in EXR_COMPRESSIONS:
        raise FogrefError(f"--exr-compression: '{exr_compression}' is not one of {EXR_COMPRESSIONS}")
    scheduler = cluster.check_scheduler(scheduler, _SOURCE)
    workers = cluster.check_workers(workers, _SOURCE)
    worker_timeout = cluster.check_worker_timeout(worker_timeout, _SOURCE)
    on_cluster = scheduler is not None or workers is not None
    if isinstance(scene_path, ParsedScene) and overrides is not None:
        raise FogrefError(f"{scene_path.path}: a read scene carries its overrides; give them to read_scene")
    # the one parse of the XML before Mitsuba's own
    parsed = scene_path if isinstance(scene_path, ParsedScene) else read_scene(scene_path, overrides)
    scene_path, overrides, out = parsed.path, parsed.overrides, Path(out)
    check_output(out, scene_path, png, list(parsed.inputs), workers_log=on_cluster)
    digest, hashes = parsed.digest, parsed.input_hashes  # before the scene is loaded: what its pixels see

    variant = set_variant(variant)
    import drjit as dr
    import mitsuba as mi

    scene, desc = scene_loader.loaded_scene(parsed)  # loaded once per process: kernels and frozen passes kept
    integrator = scene.integrator()
    if not hasattr(integrator, "render_moments"):
        raise FogrefError(f"{scene_path}: the scene's integrator must be 'fogpath' to write a ground truth")
    integrator.aovs = True
    W, H = (int(x) for x in scene.sensors()[0].film().crop_size())
    need = W * H * _HOST_BYTES_PER_PIXEL
    if need > 0.5 * _physical_memory():
        raise FogrefError(
            f"{scene_path}: {W}x{H} pixels need about {need / 2**30:.1f} GiB of memory for the "
            f"ground truth; this machine has {_physical_memory() / 2**30:.1f} GiB "
            f"(limit: half)"
        )
    scene_sha = file_sha256(scene_path)
    fields = {
        "inputs_sha256": digest,
        "overrides": {k: str(v) for k, v in (overrides or {}).items()},
        "size": [W, H],
        "spp": spp,
        "seed": seed,
        "variant": variant,
        "pixel_filter": pixel_filter,
        "version": __version__,
        "schema": gbuffer.SCHEMA_VERSION,
    }
    base = _truth_to_extend(out, fields, hashes, scene_path, scene_sha) if resume else None
    lanes_per_pass = max_lanes(variant)
    passes = pass_sizes(W * H, spp - (sum(base[0]) if base else 0), lanes_per_pass)
    if base is not None:
        passes = base[0] + passes
        print(
            f"fogref render: adding {spp - sum(base[0])} spp to the {sum(base[0])} spp of {out} "
            f"(same scene, files and seed) -> {spp} spp",
            file=sys.stderr,
        )
    key = json.dumps({**fields, "passes": passes}, sort_keys=True)
    ckpt = checkpoint_path(out)
    leftovers = re.compile("|".join(temporary_names(p) for p in (ckpt, out, moments_path(out))))
    for stale in out.parent.glob(f"{out.name}.*.tmp*"):  # a writer killed mid-write (SIGKILL)
        if leftovers.fullmatch(stale.name):
            stale.unlink(missing_ok=True)
    # the running state, one tuple (sums, squares, passes they hold): replaced in one assignment, so
    # an interruption anywhere sees the sums with their own count; the sums live on the device
    state = checkpoint.resume(ckpt, key, (H, W), passes) if resume else None
    if state is None and base is not None:
        state = base[1]
    if state is not None:
        state = (mi.TensorXd(state[0]), mi.TensorXd(state[1]), state[2])
    saved = state[2] if state is not None else 0  # passes in the checkpoint on disk

    if progress:
        from tqdm import tqdm

        bar = tqdm(total=spp, initial=sum(passes[:saved]), unit="spp", desc=scene_path.name)
        say = functools.partial(tqdm.write, file=sys.stderr)  # a line of its own above the bar
    else:  # no bar, no tqdm import (a quiet run's start-up skips it)
        bar = contextlib.nullcontext(SimpleNamespace(update=lambda n: None))
        say = functools.partial(print, file=sys.stderr, flush=True)
    t0, last_ckpt, timings = time.perf_counter(), time.perf_counter(), []
    with cluster.Interrupt() as stop, bar as shown, contextlib.ExitStack() as closing:
        if on_cluster:  # the passes' sums come from Dask workers, in pass order
            j = (scene_path, overrides, digest, variant, seed, pixel_filter)
            source = _cluster_passes(
                closing, (scheduler, workers, worker_timeout), out, j, passes, saved, stop, W * H, say
            )
        else:
            source = _local_passes(integrator, scene, seed, pixel_filter, passes, saved)
        try:
            for k, s, q, seconds in source:
                s, q = device_f64(s), device_f64(q)
                if state is not None:
                    s, q = state[0] + s, state[1] + q
                dr.eval(s, q)
                dr.sync_thread()
                state = (s, q, k + 1)
                timings.append(seconds)
                shown.update(passes[k])
                if stop.requested:
                    raise KeyboardInterrupt
                if state[2] < len(passes) and time.perf_counter() - last_ckpt > checkpoint_seconds:
                    with stop.deferred():
                        checkpoint.write_checkpoint(ckpt, state, key)
                        saved = state[2]
                    last_ckpt = time.perf_counter()
        except (KeyboardInterrupt, RuntimeError, distributed.PassFailed) as e:
            out_of_memory = _out_of_memory(e)
            if isinstance(e, RuntimeError) and "KeyboardInterrupt" not in str(e) and not out_of_memory:
                raise
            done = state  # one read: the sums and their count
            if done is not None and saved < done[2] < len(passes):
                with stop.deferred():
                    checkpoint.write_checkpoint(ckpt, done, key)
            if out_of_memory:
                raise FogrefError(
                    _out_of_memory_message(scene_path, out_of_memory, W * H, passes, variant, lanes_per_pass)
                ) from None
            if (
                isinstance(e, distributed.PassFailed) and not stop.requested
            ):  # (a Ctrl-C also stops a LocalCluster's workers)
                why = f"{scene_path}: {e}; the passes done are checkpointed, run again to resume"
                raise FogrefError(why) from None
            raise KeyboardInterrupt from None
        finally:
            source.close()

    small = W * H <= HOST_CHANNELS_MAX_PIXELS
    # the sums copied to the host once: the moments file and the small render's channels share it
    host = tuple(np.asarray(x, dtype=np.float64) for x in state[:2]) if small or keep_moments else ()
    if small:  # numpy on that copy: no Dr.Jit kernel traced
        channels, block = _float32_planes(_channels(host[0], host[1], spp))
    else:  # one fused kernel on the device, one copy of the float32 block
        channels, block = _device_float32(_channels(state[0], state[1], spp))
    bad = None if np.isfinite(block).all() else gbuffer.nonfinite_report(channels)
    if bad:
        raise FogrefError(
            f"{scene_path}: the render produced {bad}; no ground truth written "
            f"(please report this with the scene and the command)"
        )
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
        "fogref.inputs_sha256": digest,
        "fogref.inputs": hashes,
        "fogref.overrides": {k: str(v) for k, v in (overrides or {}).items()},
        "fogref.render_seconds": {"total": time.perf_counter() - t0, "passes": timings},
    }
    moments = moments_path(out)
    if keep_moments:
        _write_truth_then_sums(out, channels, attrs, exr_compression, moments, (*host, state[2]), key)
    else:
        write_exr(out, channels, attrs, compression=exr_compression)
        moments.unlink(missing_ok=True)  # they would belong to the truth this one replaced
    if png:
        write_preview(np.stack([channels[c] for c in "RGB"], axis=-1), out.with_suffix(".png"))
    ckpt.unlink(missing_ok=True)
    return out


#: What Dr.Jit's allocator says when the device (or the host) has no memory left for an array
#: (``jit_malloc(): out of memory! Could not allocate N bytes of device memory.``: ``jitc_malloc``
#: in drjit-core's ``src/malloc.cpp``).
OUT_OF_MEMORY = "jit_malloc(): out of memory"


def _out_of_memory(error: BaseException) -> str:
    """Dr.Jit's out-of-memory message in ``error`` or the exceptions it was raised from (Dr.Jit
    re-raises a loop's or a frozen function's failure as ``dr.while_loop(): encountered an
    exception`` from it), its first line; ``""`` if none is.

    >>> try:
    ...     try:
    ...         raise RuntimeError(OUT_OF_MEMORY + "! Could not allocate 64 bytes of device memory.")
    ...     except RuntimeError as oom:
    ...         raise RuntimeError("dr.while_loop(): encountered an exception.") from oom
    ... except RuntimeError as e:
    ...     print(_out_of_memory(e))
    jit_malloc(): out of memory! Could not allocate 64 bytes of device memory.
    >>> _out_of_memory(RuntimeError("something else"))
    ''
    """
    seen: set = set()
    e: BaseException | None = error
    while e is not None and id(e) not in seen:
        seen.add(id(e))
        for line in str(e).splitlines():
            if OUT_OF_MEMORY in line:
                return line[line.index(OUT_OF_MEMORY) :].strip()
        e = e.__cause__ or e.__context__
    return ""


def _out_of_memory_message(
    scene_path, what: str, pixels: int, passes: list, variant: str, lanes_per_pass: int
) -> str:
    """The one-line error of a pass that ran out of memory (``what``: Dr.Jit's line): the pass's
    lanes, the render's ``lanes_per_pass`` and the lanes to try (a quarter) through
    :data:`fogref_plugins.passes.MAX_LANES_VARIABLE`."""
    lanes = pixels * max(passes)
    return (
        f"{scene_path}: a pass of {lanes} lanes ({pixels} pixels x {max(passes)} spp, {variant}) ran out of "
        f"memory ({what}); set {MAX_LANES_VARIABLE}={max(lanes // 4, 1)} (lanes per pass, now "
        f"{lanes_per_pass}) and render again: a new split of the samples, so the passes done are "
        "not resumed"
    )


#: From this many pixels on, a truth's sums are written in a thread beside its EXR.  Below, the
#: thread costs more than it saves: at 32x18 and 64x36 the two writes took 1.45x and 1.2x as long
#: as one after the other, at 96x54 the same, at 160x90 and 320x180 1.2x and 1.3x less, at
#: 1920x1080 1.6x less (2 cores; ``reports/benchmarks/truth_write.md``, ``truth_write_small.md``).
SUMS_THREAD_MIN_PIXELS = 10_000


def _write_truth_then_sums(out, channels, attrs, compression, moments, state, key) -> None:
    """Write the truth ``out`` (:func:`~fogref.exrio.write_exr`), then its float64 sums ``moments``
    (one :func:`~fogref.render.checkpoint.checkpoint_record`).  From :data:`SUMS_THREAD_MIN_PIXELS`
    on, the sums are written in a thread at the same time, to a file staged beside ``moments``
    (:func:`~fogref.atomic.staged_write`): their SHA-256 and ``np.savez`` overlap the EXR's
    compression (1.2 GB of sums at 1920x1080).  Either way the sums replace ``moments`` only after
    the truth is in place, and not at all if writing it failed or was interrupted, so sums without
    their truth are never left."""
    if state[0].shape[0] * state[0].shape[1] < SUMS_THREAD_MIN_PIXELS:
        write_exr(out, channels, attrs, compression=compression)
        checkpoint.write_checkpoint(moments, state, key)
        return
    # the block waits for the thread, whatever happens in it: nothing waits on the main thread
    with staged_write(moments) as sums_file:
        with concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="fogref-moments") as pool:
            sums = pool.submit(lambda: np.savez(sums_file, **checkpoint.checkpoint_record(state, key)))
            write_exr(out, channels, attrs, compression=compression)
            sums.result()


#: What a truth must share with a render that adds samples to it (the key's fields), in words.
_SAME = {
    "seed": "seed",
    "overrides": "overrides (--set)",
    "size": "resolution",
    "pixel_filter": "pixel filter",
    "variant": "Mitsuba variant",
    "version": "fogref version",
    "schema": "schema",
}


def _truth_to_extend(out: Path, fields: dict, hashes: dict, scene_path: Path, scene_sha: str):
    """``(passes, (sums, squares, passes done))`` of the truth at ``out`` when this render adds
    samples to it; None when there is none or it holds at least ``fields["spp"]`` samples (a new
    render).  FogrefError naming the reason when it may not be extended.  ``hashes``: the
    SHA-256 of each file the scene loads now, ``scene_sha`` the scene's."""
    if not out.is_file():
        return None
    try:
        attrs, (H0, W0) = read_exr_header(out)
        old = {
            "inputs_sha256": attrs["fogref.inputs_sha256"],
            "overrides": attrs["fogref.overrides"],
            "spp": int(attrs["fogref.spp"]),
            "seed": int(attrs["fogref.seed"]),
            "variant": attrs["fogref.variant"],
            "passes": [int(p) for p in attrs["fogref.passes"]],
            "pixel_filter": attrs["fogref.pixel_filter"],
            "version": attrs["fogref.version"],
            "schema": int(attrs["fogref.schema"]),
            "size": [int(W0), int(H0)],
        }
    except (FogrefError, KeyError, TypeError, ValueError, StopIteration):
        return None  # not a fogref truth: a new render (check_output refused a non-EXR)
    if fields["spp"] <= old["spp"]:
        return None
    why = f"fogref render: cannot add samples to {out} ({old['spp']} spp): "
    fix = "; --no-resume renders it afresh, or give another --out"
    if old["inputs_sha256"] != fields["inputs_sha256"]:
        before = attrs.get("fogref.inputs") or {}
        changed = sorted({*before, *hashes} - {k for k in before if before.get(k) == hashes.get(k)})
        if attrs.get("fogref.scene_sha256") != scene_sha:
            changed.insert(0, scene_path.name)
        files = ", ".join(str(f) for f in changed) or "the list of files it loads"
        raise FogrefError(f"{why}the scene's files changed since it was rendered ({files}){fix}")
    for k, what in _SAME.items():
        if old[k] != fields[k]:
            raise FogrefError(f"{why}its {what} is {old[k]}, this render's {fields[k]}{fix}")
    key = json.dumps(old, sort_keys=True)
    W, H = fields["size"]
    state = checkpoint.resume(moments_path(out), key, (H, W), old["passes"])
    if state is None or state[2] != len(old["passes"]):
        raise FogrefError(
            f"{why}its float64 sums ({moments_path(out).name}) are missing or are not this truth's{fix}"
        )
    return old["passes"], state


def _local_passes(integrator, scene, seed: int, pixel_filter: str, passes: list, start: int):
    """Passes ``start..`` rendered in this process: ``(k, sums, squares, seconds)`` in pass order."""
    for k in range(start, len(passes)):
        ts = time.perf_counter()
        s, q = integrator.render_moments(
            scene, 0, pass_seed(seed, k), passes[k], pixel_exact=pixel_filter == "centre"
        )
        yield k, s, q, time.perf_counter() - ts


def _cluster_passes(
    closing, where: tuple, out, render_args: tuple, passes: list, start: int, stop, pixels: int, say
):
    """Passes ``start..`` rendered on Dask workers (:mod:`fogref.render.distributed`): ``(k, sums,
    squares, seconds)`` in pass order; ``stop`` (a :class:`fogref.cluster.Interrupt`) requested ends
    the wait, and a signal while the cluster starts or while its first worker is awaited ends the
    start at once.  ``where``: the scheduler, the LocalCluster's workers, the seconds to wait for a
    worker.  ``render_args``: the scene, overrides, inputs digest, variant, seed and pixel filter.
    The cluster (a new LocalCluster of ``workers``, or the one of ``scheduler``) is closed when
    ``closing`` (an ExitStack) ends.  Fewer passes than workers is said with ``say`` (a line on
    stderr, above the progress bar if one is shown; :func:`fogref.render.distributed.split_note`,
    ``pixels`` per sample of a pass); each pass redone because its worker was lost, with ``say``
    and in ``<out>.workers.log``."""
    if start >= len(passes):
        return
    log = workers_log_path(out)
    scheduler, workers, worker_timeout = where
    with stop.urgent():
        client, local, threads = cluster.connect(scheduler, workers, log, _SOURCE, worker_timeout)
    closing.callback(cluster.stop, client, local, log)
    n_workers = len(client.scheduler_info().get("workers", {}))
    left = passes[start:]
    lanes = max_lanes(render_args[3])
    note = distributed.split_note(pixels * sum(left), len(left), n_workers, lanes, _SOURCE)
    if note:
        say(note)

    def redone(line: str) -> None:
        say(f"{_SOURCE}: {line}")
        with open(log, "a", encoding="utf-8") as f:
            f.write(f"{_SOURCE}: {line}\n")

    j = distributed.job(*render_args, threads)
    source = distributed.passes_in_order(client, j, passes, start, stop=lambda: stop.requested, redone=redone)
    for r in source:
        yield r["k"], r["sums"], r["squares"], r["seconds"]


def device_f64(x):
    """A pass's sums as a Dr.Jit float64 tensor (what ``render_moments`` returns; anything
    array-like is converted)."""
    import mitsuba as mi

    if isinstance(x, mi.TensorXd):
        return x
    return mi.TensorXd(np.ascontiguousarray(np.asarray(x, dtype=np.float64)))


def _device_float32(channels: dict) -> tuple[dict, np.ndarray]:
    """The EXR's channels, ``(H, W)`` float64 Dr.Jit tensors, cast and stacked on the device and
    copied to the host in one contiguous ``(channels, H, W)`` float32 block: ``(name -> plane,
    block)``.  The channel arithmetic is part of one kernel, not numpy work after per-channel
    copies."""
    import drjit as dr
    import mitsuba as mi

    names = list(channels)
    h, w = (int(x) for x in channels[names[0]].shape)
    block = np.asarray(dr.concat([mi.Float(channels[k].array) for k in names])).reshape(len(names), h, w)
    return dict(zip(names, block)), block


def _float32_planes(channels: dict) -> tuple[dict, np.ndarray]:
    """The EXR's channels, ``(H, W)`` float64 arrays, cast to float32 planes of one contiguous
    ``(channels, H, W)`` block: ``(name -> plane, block)`` (one finiteness check covers them all)."""
    names = list(channels)
    block = np.empty((len(names), *np.shape(channels[names[0]])), dtype=np.float32)
    for plane, name in zip(block, names):
        plane[...] = channels[name]  # round to nearest, as astype
    return dict(zip(names, block)), block


def _channels(sums, squares, spp: int) -> dict:
    """EXR channels (float64) from the integrator's per-pixel sums and squares, ``(H, W, K)``
    numpy arrays or Dr.Jit float64 tensors, the result of the same kind (see
    :func:`gbuffer.moments_to_channels`)."""
    by_group = {g: sums[..., checkpoint.sum_channels(g)] for g in ("final", *gbuffer.SAMPLE_GROUPS)}
    k = 3 * len(gbuffer.SQUARED_GROUPS)  # squares first, then the channel-pair products
    sq = {g: squares[..., 3 * i : 3 * i + 3] for i, g in enumerate(gbuffer.SQUARED_GROUPS)}
    cross = {g: squares[..., k + 3 * i : k + 3 * i + 3] for i, g in enumerate(gbuffer.SQUARED_GROUPS)}
    return gbuffer.moments_to_channels(by_group, sq, spp, cross)
