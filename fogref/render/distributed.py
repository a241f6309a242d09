"""One truth's passes on Dask workers (``fogref render --scheduler ADDRESS`` / ``--workers N``).

A render is a sum of independent passes (:mod:`fogref_plugins.passes`): pass ``k`` draws
``passes[k]`` samples per pixel with the seed :func:`~fogref_plugins.passes.pass_seed`
``(seed, k)``.  Here each pass is one Dask task, :func:`render_pass`, which returns the
pass's float64 per-pixel sums and squares; :func:`passes_in_order` hands them to the render
driver (:func:`fogref.render.render.render`) in pass order, whatever order they arrive in, and
the driver adds them exactly as it adds its own passes.  Float64 addition is not associative,
so the fixed order is what makes the truth bitwise equal to a one-process render of the same
``(scene, overrides, spp, seed, pixel filter, variant)`` on any number of workers (on workers
of the same instruction set: the LLVM back end compiles for the host CPU).

* **A killed worker's passes are redone**: the scheduler reruns the tasks of a worker that
  dies (Dask's ``distributed.scheduler.allowed-failures``), and a task that raises is retried
  ``retries`` times; a pass is a pure function of its key, so a rerun gives the same sums.
* **Workers keep their compiled kernels**: a worker process loads the scene once (kept by
  the digest of its inputs, the variant, the overrides and the thread count,
  :func:`fogref.render.load.loaded_scene`) and keeps it for every later pass of that render and
  later renders of the same scene, until it loads another; the seed and spp are opaque to the
  kernels, so every pass after a worker's first reuses its compiled kernels; fogpath records a
  worker's second pass of a size and replays it from the third on (:mod:`fogref_plugins.fogpath`).
* **Same inputs everywhere**: a worker renders only if the digest of the scene and of every
  file it loads (:func:`fogref.scene.inputs.inputs_digest`), read on the worker, is the
  driver's; workers on other machines need the scene at the same path (a shared file system).
  A worker reads the scene and digests its inputs once per render (the job's ``render``
  token), on its first pass of it; each of its passes then compares every input's SHA-256
  with the one it checked (:func:`fogref.scene.inputs.file_sha256`, memoised on the file's
  size, times and inode: a ``stat`` per file, the bytes read again only when they changed), after
  the pass, so a pass whose inputs were edited before it ended is refused, not returned.
* **A lost worker is named**: each pass that the scheduler reruns because its worker died
  (running there, or its result lost with it) is reported in one line (:func:`redone_passes`,
  from the scheduler's ``remove-worker`` events).
* **Too small to share is said**: a render of fewer passes than workers leaves workers idle
  (:func:`split_note`); the passes are never split by the worker count, which would change
  the pixels (:mod:`fogref_plugins.passes`).
* **Bounded memory**: at most ``window`` passes are submitted ahead of the next pass to merge,
  so the driver holds at most that many passes' sums that arrived early.

The cluster itself (a LocalCluster or a running scheduler, the workers' log, closing it) is
:mod:`fogref.cluster`, shared with ``fogref sweep``.  Importing this module does no work.
"""

from __future__ import annotations

import os
import secrets
import time
from pathlib import Path

import numpy as np
from fogref_plugins.passes import pass_seed

from fogref.errors import FogrefError
from fogref.render.load import loaded_scene
from fogref.render.variant import set_variant
from fogref.scene.inputs import file_sha256
from fogref.scene.parsed import read_scene

__all__ = [
    "PassFailed",
    "job",
    "render_pass",
    "passes_in_order",
    "redone_passes",
    "split_note",
    "transfer_bytes",
]


class PassFailed(FogrefError):
    """A pass failed on the cluster after its retries (one line: the pass and the error)."""


def job(scene_path, overrides, digest: str, variant: str, seed: int, pixel_filter: str, threads) -> dict:
    """What every pass of one render needs on a worker: a small dict, sent with each task; ``render``
    is a token of this render, new on each call (a worker checks the inputs once per render).

    >>> sorted(job("a.xml", {}, "0" * 64, "llvm_ad_rgb", 0, "centre", 1))  # doctest: +NORMALIZE_WHITESPACE
    ['digest', 'overrides', 'pixel_filter', 'render', 'scene', 'seed', 'threads', 'variant']
    """
    return {
        "render": secrets.token_hex(8),
        "scene": os.path.abspath(scene_path),
        "overrides": dict(overrides or {}),
        "digest": digest,
        "variant": variant,
        "seed": int(seed),
        "pixel_filter": pixel_filter,
        "threads": threads,
    }


#: The renders this worker process checked: ``render`` token -> ``(the read scene, {input path:
#: SHA-256 as checked})``; the last :data:`KEEP_CHECKED` only, oldest dropped first.
_CHECKED: dict = {}
#: How many renders' checks a worker keeps.
KEEP_CHECKED = 4


def _input_sha256(path) -> str:
    """:func:`fogref.scene.inputs.file_sha256` of ``path``, ``"missing"`` when it can't be read."""
    try:
        return file_sha256(path)
    except OSError:
        return "missing"


def _worker_scene(j: dict):
    """``(scene, integrator, the inputs' hashes as checked)`` of ``j`` in this process.  On this
    worker's first pass of the render: the scene read, its inputs hashed (before the digest and the
    load, so an edit after that is seen by :func:`_check_unchanged`) and their digest compared with
    the driver's; the scene loaded on the first pass and then reused
    (:func:`fogref.render.load.loaded_scene`)."""
    set_variant(j["variant"])
    hit = _CHECKED.pop(j["render"], None)
    if hit is None:
        parsed = read_scene(Path(j["scene"]), j["overrides"] or None)
        hashes = {i.path: _input_sha256(i.path) for i in parsed.inputs}
        digest = parsed.digest
        if digest != j["digest"]:
            raise FogrefError(
                f"{j['scene']}: this worker (pid {os.getpid()}) reads other inputs than the driver "
                f"(inputs SHA-256 {digest[:12]}..., not {j['digest'][:12]}...); the workers need the "
                f"scene and the files it loads at the same path"
            )
        hit = (parsed, hashes)
        while len(_CHECKED) >= KEEP_CHECKED:
            _CHECKED.pop(next(iter(_CHECKED)))
    _CHECKED[j["render"]] = hit  # the most recently used last
    parsed, hashes = hit
    scene, _ = loaded_scene(parsed, j["threads"])
    integrator = scene.integrator()
    integrator.aovs = True
    return scene, integrator, hashes


def _check_unchanged(j: dict, hashes: dict) -> None:
    """A FogrefError naming the inputs of ``j`` whose SHA-256 is no longer the one checked."""
    changed = [str(p) for p, sha in hashes.items() if _input_sha256(p) != sha]
    if changed:
        raise FogrefError(
            f"{j['scene']}: {', '.join(changed)} changed during the render (seen by the worker with "
            f"pid {os.getpid()}); render again"
        )


def render_pass(j: dict, k: int, spp: int) -> dict:
    """Pass ``k`` (``spp`` samples per pixel, seed ``pass_seed(j["seed"], k)``) on this process.

    Returns ``{"k", "sums", "squares", "seconds", "cpu_seconds", "pid"}``: the float64 per-pixel
    sums and squares of :meth:`FogPathIntegrator.render_moments` as numpy arrays ``(H, W, 30)``
    and ``(H, W, 42)``, the wall and CPU seconds the pass took in this process (its first pass
    on this process includes loading the scene and compiling the kernels) and the process id.
    Raises :class:`~fogref.errors.FogrefError` when the inputs read here are not the driver's,
    or when one of them changed since this worker checked them (the pass is not returned).
    """
    t0, c0 = time.perf_counter(), time.process_time()
    scene, integrator, hashes = _worker_scene(j)
    s, q = integrator.render_moments(
        scene, 0, pass_seed(j["seed"], k), int(spp), pixel_exact=j["pixel_filter"] == "centre"
    )
    sums, squares = np.asarray(s, dtype=np.float64), np.asarray(q, dtype=np.float64)
    _check_unchanged(j, hashes)
    return {
        "k": k,
        "sums": sums,
        "squares": squares,
        "seconds": time.perf_counter() - t0,
        "cpu_seconds": time.process_time() - c0,
        "pid": os.getpid(),
    }


def transfer_bytes(width: int, height: int) -> int:
    """Bytes of float64 moments one pass sends back: 30 sums and 42 squares per pixel.

    >>> transfer_bytes(160, 90)
    8294400
    """
    return width * height * (30 + 42) * 8


def split_note(
    samples: int, passes: int, workers: int, lanes: int, source: str = "fogref render"
) -> str | None:
    """The line saying that a render of ``samples`` samples (pixels x spp) in ``passes`` passes of
    at most ``lanes`` samples is too small to gain from ``workers`` workers (fewer passes than
    workers: one worker renders a pass); None when every worker has a pass.

    >>> print(split_note(41472, 1, 2, 1 << 18))  # doctest: +NORMALIZE_WHITESPACE
    fogref render: 41472 samples make 1 pass (up to 262144 samples each) for 2 workers:
    1 worker idle, too small to gain from more than 1
    >>> split_note(4147200, 16, 2, 1 << 18) is None
    True
    """
    if passes >= workers:
        return None
    idle = workers - passes
    return (
        f"{source}: {samples} samples make {passes} pass{'es' if passes > 1 else ''} (up to {lanes} "
        f"samples each) for {workers} workers: {idle} worker{'s' if idle > 1 else ''} idle, too small "
        f"to gain from more than {passes}"
    )


def redone_passes(events, tag: str, n_passes: int, seen: set) -> list[str]:
    """One line per pass of the render ``tag`` that a lost worker makes the scheduler redo, from
    the scheduler's ``"all"`` events (``client.get_events("all")``: ``(time, msg)`` pairs); events
    in ``seen`` (updated) are skipped.

    >>> ev = [(1.0, {"action": "remove-worker", "worker": "tcp://h:1", "expected": False,
    ...        "processing-tasks": {"fogref-render-ab-3"}, "lost-computed-tasks": {"fogref-render-ab-1"}})]
    >>> for line in redone_passes(ev, "ab", 8, set()): print(line)
    worker tcp://h:1 lost: pass 1 of 8 redone (its result was lost with the worker)
    worker tcp://h:1 lost: pass 3 of 8 redone (it was running there)
    """
    lines = []
    prefix = f"fogref-render-{tag}-"
    for t, msg in events:
        event = (t, msg.get("worker")) if isinstance(msg, dict) else None
        if event is None or msg.get("action") != "remove-worker" or event in seen:
            continue
        seen.add(event)
        why = {
            **{k: "its result was lost with the worker" for k in msg.get("lost-computed-tasks") or ()},
            **{k: "it was running there" for k in msg.get("processing-tasks") or ()},
        }
        ours = sorted((int(k[len(prefix) :]), w) for k, w in why.items() if str(k).startswith(prefix))
        lines += [f"worker {msg.get('worker')} lost: pass {k} of {n_passes} redone ({w})" for k, w in ours]
    return lines


def passes_in_order(
    client,
    j: dict,
    passes: list[int],
    start: int,
    retries: int = 2,
    window: int | None = None,
    stop=None,
    redone=None,
):
    """Run passes ``start..len(passes)-1`` on ``client``'s workers; yield their results in pass order.

    Each yielded item is :func:`render_pass`'s dict.  At most ``window`` passes (default:
    4 per worker, at least 4) are submitted beyond the next one to yield.  A pass whose
    task still fails after ``retries`` reruns raises :class:`PassFailed`.  ``stop`` (a
    callable, e.g. "Ctrl-C was pressed") is polled every 50 ms while waiting: when true,
    KeyboardInterrupt is raised (a terminal's Ctrl-C also stops a LocalCluster's workers, so
    no more passes would come).  Closing the generator (an interruption) cancels the passes
    still queued or running.  ``redone`` (a callable) is given each line of
    :func:`redone_passes`, checked as each pass arrives (a redone pass arrives after its event).
    """
    from dask.distributed import as_completed

    if window is None:
        window = max(4, 4 * len(client.scheduler_info().get("workers", {})))
    tag = secrets.token_hex(6)
    running = as_completed()
    futures = {}
    arrived: dict[int, dict] = {}
    nxt, merge = start, start
    seen: set = set()

    def report_redone():
        if redone is None:
            return
        try:
            events = client.get_events("all")
        except Exception:  # noqa: BLE001 - a scheduler that keeps no events: nothing to report
            return
        for line in redone_passes(events, tag, len(passes), seen):
            redone(line)

    try:
        while merge < len(passes):
            while nxt < len(passes) and nxt - merge < window:
                f = client.submit(
                    render_pass,
                    j,
                    nxt,
                    passes[nxt],
                    key=f"fogref-render-{tag}-{nxt}",
                    retries=retries,
                    pure=False,
                )
                futures[f.key] = (nxt, f)
                running.add(f)
                nxt += 1
            while stop is not None and not running.has_ready():
                if stop():
                    raise KeyboardInterrupt
                time.sleep(0.05)
            f = next(running)
            k, _ = futures.pop(f.key)
            try:
                arrived[k] = f.result()
            except FogrefError:
                raise
            except Exception as e:  # the task's own error, after Dask's retries; KilledWorker
                detail = (str(e).splitlines() or [""])[0][:200]
                raise PassFailed(
                    f"pass {k} of {len(passes)} failed on the cluster: {type(e).__name__}: {detail}"
                ) from None
            report_redone()
            while merge in arrived:
                yield arrived.pop(merge)
                merge += 1
    finally:
        left = [f for _, f in futures.values()]
        if left:
            try:
                client.cancel(left)
            except Exception:  # noqa: BLE001 - a closed client: nothing left to cancel
                pass
