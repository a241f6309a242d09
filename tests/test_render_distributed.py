"""One truth's passes on a real two-worker Dask LocalCluster.

The default scene at 16x9 pixels and 8 spp, in 8 passes of 1 spp (``MAX_LANES`` shrunk as in
``tests/test_render_passes.py``), rendered once in this process: the reference.  On the
cluster (``processes=True``, one thread per worker, not a mock) the same render must give the
same pixels bit for bit: on two workers, after a worker is SIGKILLed mid-render (its passes
are redone), and after an interruption resumed from the checkpoint on another worker count or
in one process.  Smallest error detected: any pass missing, counted twice, mis-seeded or
merged out of order changes some float32 pixel value (the comparison is exact).  The split
itself (how many passes, so how many workers can share a render) is checked at the real
``MAX_LANES``; a render of fewer passes than workers says so, and a lost worker's redone
passes are named on stderr and in ``<out>.workers.log``.
"""

import logging
import os
import signal
from pathlib import Path

import numpy as np
import pytest

from fogref.exrio import read_exr

pytestmark = pytest.mark.render
ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "valley.xml"
RES = {"res": 16, "resy": 9}
SPP, SEED = 8, 5


def _pixels(path) -> dict:
    return read_exr(path)[0]


def _assert_equal(a: dict, b: dict) -> None:
    assert sorted(a) == sorted(b)
    differ = [k for k in a if not np.array_equal(a[k], b[k])]
    assert not differ, f"channels not bitwise equal: {differ[:8]}"


@pytest.fixture
def one_spp_passes(monkeypatch):
    """Passes of 1 spp at 16x9 (8 passes for 8 spp), in this process (the driver)."""
    import fogref_plugins.passes as passes

    lanes = RES["res"] * RES["resy"]
    monkeypatch.setattr(passes, "MAX_LANES", {"llvm": lanes, "cuda": lanes})
    assert passes.pass_sizes(lanes, SPP, passes.max_lanes("llvm_ad_rgb")) == [1] * SPP


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,
        silence_logs=logging.CRITICAL,
    ) as c:
        yield c


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The one-process render (its own pass sizes set here: a module-scoped fixture)."""
    import fogref_plugins.passes as passes

    from fogref.render.render import render

    saved = passes.MAX_LANES
    passes.MAX_LANES = {"llvm": RES["res"] * RES["resy"], "cuda": RES["res"] * RES["resy"]}
    try:
        out = tmp_path_factory.mktemp("reference") / "one.exr"
        render(SCENE, out, spp=SPP, seed=SEED, overrides=RES, progress=False, png=False)
    finally:
        passes.MAX_LANES = saved
    return _pixels(out)


def _render(out, **kw):
    from fogref.render.render import render

    seed = kw.pop("seed", SEED)
    return render(SCENE, out, spp=SPP, seed=seed, overrides=RES, progress=False, png=False, **kw)


def _loaded_scenes() -> dict:
    """On a worker: its pid -> the ids of the scenes it holds (:func:`fogref.render.load.held_scenes`)."""
    from fogref.render.load import held_scenes

    return {os.getpid(): sorted(id(scene) for scene in held_scenes())}


def test_the_split_lets_workers_share_a_render_and_never_depends_on_them():
    """At the CPU's real ``MAX_LANES``: 320x180 at 72 spp is 18 passes of 4 spp, each filling more
    than 3/4 of a pass (up to 18 workers get one each), 48x27 at 32 spp is one pass; the split has
    no worker argument."""
    import inspect

    from fogref_plugins.passes import max_lanes, pass_sizes

    lanes = max_lanes("llvm_ad_rgb")
    big = pass_sizes(320 * 180, 72, lanes)
    assert big == [4] * 18
    assert all(3 * lanes // 4 < 320 * 180 * p <= lanes for p in big), big
    assert pass_sizes(48 * 27, 32, lanes) == [32]
    assert list(inspect.signature(pass_sizes).parameters) == ["n_pixels", "spp", "max_lanes"]


def test_a_render_too_small_for_the_workers_says_so(tmp_path, capsys, cluster):
    """16x9 at 8 spp is one pass at the real ``MAX_LANES``: one line with the samples, passes and workers."""
    _render(tmp_path / "small.exr", scheduler=cluster.scheduler_address)
    err = [line for line in capsys.readouterr().err.splitlines() if "too small" in line]
    assert err == [
        "fogref render: 1152 samples make 1 pass (up to 262144 samples each) for 2 workers: "
        "1 worker idle, too small to gain from more than 1"
    ]


def test_with_the_progress_bar_the_note_is_a_line_of_its_own(tmp_path, capsys, cluster):
    """With the bar shown, the note is written above it (``tqdm.write``), not after the bar's text on
    its line: the last ``\r``-separated part of a stderr line, what a terminal shows, is the note."""
    from fogref.render.render import render

    render(
        SCENE,
        tmp_path / "bar.exr",
        spp=SPP,
        seed=SEED,
        overrides=RES,
        png=False,
        scheduler=cluster.scheduler_address,
    )
    shown = [line.split("\r")[-1] for line in capsys.readouterr().err.splitlines()]
    assert any(line.startswith("fogref render: 1152 samples make 1 pass") for line in shown), shown


def test_two_workers_give_the_one_process_pixels_bitwise(
    tmp_path, capsys, one_spp_passes, cluster, reference
):
    """...and each worker loads the scene once: a second render (another seed) reuses it, with the
    kernels compiled for it."""
    import fogref.render.distributed as D

    seen, held = [], []
    real = D.passes_in_order

    def spy(client, *a, **kw):
        for r in real(client, *a, **kw):
            seen.append((r["k"], r["pid"]))
            yield r
        held.append(client.run(_loaded_scenes))

    from unittest import mock

    with mock.patch.object(D, "passes_in_order", spy):
        _render(tmp_path / "two.exr", scheduler=cluster.scheduler_address)
        _render(tmp_path / "again.exr", scheduler=cluster.scheduler_address, seed=SEED + 1)
    first, second = ({pid: ids for d in h.values() for pid, ids in d.items()} for h in held)
    assert first == second and all(len(ids) == 1 for ids in first.values()), (first, second)
    seen = seen[:SPP]
    _assert_equal(_pixels(tmp_path / "two.exr"), reference)
    assert [k for k, _ in seen] == list(range(SPP)), "passes not merged in pass order"
    assert len({pid for _, pid in seen}) == 2, "the passes did not run on both workers"
    assert os.getpid() not in {pid for _, pid in seen}
    assert not (tmp_path / "two.exr.partial.npz").exists()
    err = capsys.readouterr().err
    assert "too small" not in err and "redone" not in err, err  # 8 passes on 2 workers, none lost


def _arm(marker: str, disarm: bool = False):
    """On a worker: the first worker to start its second pass kills itself with SIGKILL (once across
    the cluster: ``marker`` is created exclusively and holds the pid).  Tasks name ``render_pass`` by
    reference, so the wrapper set here is what they call."""
    import fogref.render.distributed as D

    orig = getattr(D.render_pass, "__wrapped__", D.render_pass)
    if disarm:
        D.render_pass = orig
        return os.getpid()
    done = []

    def kill_on_second_pass(*a, **kw):
        if done:
            try:
                fd = os.open(marker, os.O_WRONLY | os.O_CREAT | os.O_EXCL)
            except FileExistsError:
                pass
            else:
                os.write(fd, f"{os.getpid()} {a[1]}".encode())
                os.close(fd)
                os.kill(os.getpid(), signal.SIGKILL)
        done.append(a[1])
        return orig(*a, **kw)

    kill_on_second_pass.__wrapped__ = orig
    D.render_pass = kill_on_second_pass
    return os.getpid()


def test_a_worker_killed_mid_render_has_its_passes_redone(
    tmp_path, capsys, one_spp_passes, cluster, reference
):
    """A worker SIGKILLs itself as its second pass starts (its first pass done, the second in flight);
    the scheduler reruns its passes on the other worker (or the one the nanny restarts), and the
    render names them: one line each on stderr, the same in ``<out>.workers.log``."""
    from unittest import mock

    import fogref.render.distributed as D

    marker = tmp_path / "killed"
    real = D.passes_in_order

    def armed(client, *a, **kw):
        client.run(_arm, str(marker))
        try:
            yield from real(client, *a, **kw)
        finally:
            client.run(_arm, str(marker), True)

    with mock.patch.object(D, "passes_in_order", armed):
        _render(tmp_path / "killed.exr", scheduler=cluster.scheduler_address)
    assert marker.exists(), "no worker was killed"
    pid, k = (int(x) for x in marker.read_text().split())
    assert 0 < k < SPP
    _assert_equal(_pixels(tmp_path / "killed.exr"), reference)
    with pytest.raises(OSError):
        os.kill(pid, 0)  # the worker is gone: its passes were rendered elsewhere
    said = [line for line in capsys.readouterr().err.splitlines() if " lost: pass " in line]
    assert f"pass {k} of {SPP} redone (it was running there)" in "\n".join(said), said
    assert all(line.startswith("fogref render: worker tcp://") for line in said), said
    logged = (tmp_path / "killed.exr.workers.log").read_text().splitlines()
    assert logged == said


def _interrupt_after(n: int, real):
    """A pass source that raises KeyboardInterrupt (a Ctrl-C) after yielding ``n`` passes."""

    def source(*a, **kw):
        for i, r in enumerate(real(*a, **kw)):
            if i == n:
                raise KeyboardInterrupt
            yield r

    return source


def _checkpoint_done(out) -> int:
    with np.load(Path(str(out) + ".partial.npz")) as z:
        return int(z["done"])


def test_interrupted_on_two_workers_resumes_on_one_worker(tmp_path, one_spp_passes, cluster, reference):
    """The checkpoint of a cluster render resumes on a LocalCluster of one worker (``workers=1``,
    started by fogref, its output in ``<out>.workers.log``), to the same pixels."""
    from unittest import mock

    import fogref.render.distributed as D

    out = tmp_path / "resumed.exr"
    with mock.patch.object(D, "passes_in_order", _interrupt_after(3, D.passes_in_order)):
        with pytest.raises(KeyboardInterrupt):
            _render(out, scheduler=cluster.scheduler_address, checkpoint_seconds=1e9)
    assert _checkpoint_done(out) == 3 and not out.exists()
    resumed = []
    real = D.passes_in_order

    def spy(client, j, passes, start, **kw):
        resumed.append(start)
        yield from real(client, j, passes, start, **kw)

    with mock.patch.object(D, "passes_in_order", spy):
        _render(out, workers=1)
    assert resumed == [3], "the resumed render did not start at the checkpoint's pass"
    assert Path(str(out) + ".workers.log").exists()
    _assert_equal(_pixels(out), reference)


def test_interrupted_in_one_process_resumes_on_the_cluster_and_back(
    tmp_path, one_spp_passes, cluster, reference
):
    from unittest import mock

    import fogref.render.render as R

    out = tmp_path / "mixed.exr"
    with mock.patch.object(R, "_local_passes", _interrupt_after(2, R._local_passes)):
        with pytest.raises(KeyboardInterrupt):
            _render(out, checkpoint_seconds=1e9)
    assert _checkpoint_done(out) == 2
    import fogref.render.distributed as D

    with mock.patch.object(D, "passes_in_order", _interrupt_after(3, D.passes_in_order)):
        with pytest.raises(KeyboardInterrupt):
            _render(out, scheduler=cluster.scheduler_address, checkpoint_seconds=1e9)
    assert _checkpoint_done(out) == 5
    _render(out)  # the last three passes in this process
    _assert_equal(_pixels(out), reference)


@pytest.mark.parametrize(
    "args, says",
    [
        (["--workers", "0"], "--workers"),
        (["--workers", "two"], "--workers"),
        (["--scheduler", "not an address"], "--scheduler"),
        (["--scheduler", "tcp://127.0.0.1:8786", "--workers", "2"], "does not apply"),
    ],
)
def test_bad_workers_or_scheduler_is_refused_in_one_line(tmp_path, capsys, args, says):
    from fogref.cli import main

    out = tmp_path / "x.exr"
    assert main(["render", str(SCENE), "--out", str(out), "--quiet", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and says in err and "Traceback" not in err, err
    assert not out.exists()


def test_the_api_refuses_bad_workers_and_scheduler_before_any_work(tmp_path):
    from fogref.errors import ParameterError
    from fogref.render.render import render

    for kw in ({"workers": 0}, {"workers": 1.5}, {"scheduler": "nowhere"}, {"scheduler": 8786}):
        with pytest.raises(ParameterError, match="fogref render"):
            render(SCENE, tmp_path / "x.exr", **kw)
    assert not list(tmp_path.iterdir())


def test_a_worker_that_reads_other_inputs_refuses_to_render(tmp_path):
    """The digest of the scene and every file it loads, read on the worker, must be the driver's."""
    import fogref.render.distributed as D
    from fogref.errors import FogrefError

    j = D.job(SCENE, RES, "0" * 64, "llvm_ad_rgb", SEED, "centre", None)
    with pytest.raises(FogrefError, match="reads other inputs than the driver"):
        D.render_pass(j, 0, 1)


def test_a_worker_checks_the_inputs_once_per_render_and_refuses_an_edit_mid_render(
    tmp_path, monkeypatch, mitsuba
):
    """A worker reads the scene and digests its inputs on its first pass of a render only (a new
    render checks again); an input edited mid-render, between two passes or while a pass runs, is
    refused and that pass is not returned.  Smallest error detected: one byte appended to the scene
    file (whitespace: the same scene to Mitsuba), its times set back as a file unmodified for a while
    (the memoised hash is trusted until the file's size or times change)."""
    import fogref_plugins.fogpath as fpm

    import fogref.render.distributed as D
    from fogref.errors import FogrefError
    from fogref.scene.parsed import read_scene

    scene = tmp_path / "valley.xml"
    scene.write_bytes(SCENE.read_bytes())

    def age(path):  # unmodified for a minute: its hash is memoised on its size, times and inode
        old = path.stat().st_mtime - 60
        os.utime(path, (old, old))

    def new_job():
        age(scene)
        return D.job(scene, RES, read_scene(scene, RES).digest, "llvm_ad_rgb", SEED, "centre", None)

    reads = []
    real_read = D.read_scene
    monkeypatch.setattr(D, "read_scene", lambda *a: reads.append(a) or real_read(*a))
    j = new_job()
    first = D.render_pass(j, 0, 1)
    D.render_pass(j, 1, 1)
    assert len(reads) == 1  # the second pass: no read of the scene, no digest
    again = D.render_pass(new_job(), 0, 1)
    assert len(reads) == 2 and np.array_equal(again["sums"], first["sums"])  # a new render: checked

    with open(scene, "ab") as f:  # edited between two passes
        f.write(b" ")
    with pytest.raises(FogrefError, match=f"{scene} changed during the render"):
        D.render_pass(j, 2, 1)

    j = new_job()
    real_pass = fpm.FogPathIntegrator.render_moments

    def edited_while_running(self, *args, **kw):
        with open(scene, "ab") as f:
            f.write(b" ")
        return real_pass(self, *args, **kw)

    monkeypatch.setattr(fpm.FogPathIntegrator, "render_moments", edited_while_running)
    with pytest.raises(FogrefError, match="changed during the render"):
        D.render_pass(j, 0, 1)
    monkeypatch.setattr(fpm.FogPathIntegrator, "render_moments", real_pass)
    with pytest.raises(FogrefError, match="reads other inputs than the driver"):  # a worker new to it
        D.render_pass({**j, "render": "another"}, 1, 1)
