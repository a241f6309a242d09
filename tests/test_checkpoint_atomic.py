"""The render checkpoint is one atomic record.

* An interruption at any line of the pass loop, or of the functions it calls in
  ``fogref/render/render.py``, ``fogref/render/checkpoint.py`` and ``fogref/atomic.py``
  (the checkpoint write included),
  leaves a state that the rerun resumes to a truth bitwise equal to an uninterrupted one.
  The interruption is a KeyboardInterrupt raised at that line (``sys.settrace``: stronger
  than a signal, which the driver may defer) or two real SIGINTs delivered there.
* A damaged or inconsistent checkpoint is set aside (renamed, not deleted) with a one-line
  warning naming it, and the render starts over.
"""

import ctypes
import hashlib
import os
import signal
import sys
from pathlib import Path

import numpy as np
import pytest
import tiny_inputs_scene as tiny
from terminal_signals import sigint_raises

from fogref.exrio import read_exr

pytestmark = pytest.mark.render
ROOT = Path(__file__).resolve().parents[1]
TRACED = {str(ROOT / "fogref" / "render" / f) for f in ("render.py", "checkpoint.py")} | {
    str(ROOT / "fogref" / f) for f in ("atomic.py", "cluster.py")
}
SPP = 3  # three passes of 1 spp (tiny.one_spp_passes)


def _pixels(path) -> dict:
    return read_exr(path)[0]


def _equal(a: dict, b: dict) -> bool:
    return sorted(a) == sorted(b) and all(np.array_equal(a[k], b[k]) for k in a)


def _is_interrupt(frame) -> bool:
    """The frame is a method of the driver's signal handling (``fogref.cluster.Interrupt``)."""
    return type(frame.f_locals.get("self")).__name__ == "Interrupt"


class _InjectAt:
    """A trace function that interrupts the n-th line executed in TRACED files while the pass loop
    runs: from the driver's installing its signal handlers (``Interrupt.__enter__``) to its
    restoring them (``Interrupt.__exit__`` returns)."""

    def __init__(self, n: int, how: str):
        self.n, self.how, self.count, self.armed, self.fired = n, how, 0, None, None

    def __call__(self, frame, event, arg):
        if frame.f_code.co_filename not in TRACED:
            return None
        if frame.f_code.co_name in ("__enter__", "__exit__") and _is_interrupt(frame):
            self.armed = self.armed is None if frame.f_code.co_name == "__enter__" else self.armed
        return self._line

    def _line(self, frame, event, arg):
        if event == "return" and frame.f_code.co_name == "__exit__" and _is_interrupt(frame):
            self.armed = False
        if event == "line" and self.armed and self.fired is None:
            self.count += 1
            if self.count == self.n:
                code = frame.f_code
                self.fired = f"{Path(code.co_filename).name}:{frame.f_lineno} ({code.co_name})"
                if self.how == "exception":
                    raise KeyboardInterrupt
                os.kill(os.getpid(), signal.SIGINT)  # two Ctrl-C, delivered at this line
                os.kill(os.getpid(), signal.SIGINT)
        return self._line


def _forget_the_handled_exception() -> None:
    """Clear what ``sys.exc_info()`` reports.  CPython 3.11 leaves an exception "being handled"
    when a trace function raises at the line event of a ``return`` inside an ``except`` block
    (``fogref.atomic.is_stream``'s ``except OSError: return False``; twelve lines of plain Python
    reproduce it in 3.11.7): every later exception of the process would carry it as its
    ``__context__``, and the tracebacks of later tests would show it.  ``PyErr_SetExcInfo`` with
    NULLs is the C API's way to clear it."""
    set_exc_info = ctypes.pythonapi.PyErr_SetExcInfo
    set_exc_info.argtypes = [ctypes.py_object] * 3
    set_exc_info.restype = None
    null = ctypes.py_object()
    set_exc_info(null, null, null)


@pytest.mark.parametrize("how", ["exception", "two SIGINTs"])
def test_an_interruption_at_every_line_of_the_pass_loop_resumes_bitwise(tmp_path, mitsuba, monkeypatch, how):
    import fogref.render.render as R

    tiny.one_spp_passes(monkeypatch)
    scene = tiny.make(mitsuba, tmp_path / "scene")
    kw = dict(spp=SPP, seed=5, progress=False, png=False)
    ref = _pixels(R.render(scene, tmp_path / "ref.exr", **kw))
    import fogref.render.load as S

    loaded = S.load_scene(scene)
    monkeypatch.setattr(S, "load_scene", lambda *a, **k: loaded)  # the same scene every run: faster
    out, ckpt = tmp_path / "run" / "x.exr", tmp_path / "run" / "x.exr.partial.npz"
    points, interrupted, verified = 0, 0, {}
    with sigint_raises():  # as in a terminal, even when the suite runs in the background
        previous = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
        for n in range(1, 2000):
            inject = _InjectAt(n, how)
            sys.settrace(inject)
            try:
                R.render(scene, out, checkpoint_seconds=0, **kw)
            except KeyboardInterrupt:
                interrupted += 1
            finally:
                sys.settrace(None)
                signal.signal(signal.SIGINT, previous[0])
                signal.signal(signal.SIGTERM, previous[1])
                _forget_the_handled_exception()
            if inject.fired is None:  # ran to the end: every line has had its turn
                break
            points += 1
            left = sorted(p.name for p in out.parent.iterdir())
            assert set(left) <= {"x.exr.partial.npz"}, f"interrupted at {inject.fired}: left {left}"
            state = hashlib.sha256(ckpt.read_bytes()).hexdigest() if ckpt.exists() else None
            if state not in verified:  # the rerun from this state (a checkpoint's bytes, or none)
                R.render(scene, out, checkpoint_seconds=0, **kw)  # resumes, or starts over
                verified[state] = _equal(_pixels(out), ref)
                assert sorted(p.name for p in out.parent.iterdir()) == ["x.exr", "x.exr.moments.npz"]
                out.unlink()
                R.moments_path(out).unlink()  # the finished truth's sums (the next run is a new one)
            why = f"interrupted at {inject.fired} (line event {n}): the resumed truth differs"
            assert verified[state], why
            ckpt.unlink(missing_ok=True)
    assert points > 50 and interrupted > 30 and len(verified) >= 3, (points, interrupted, len(verified))
    assert not ckpt.exists()
    assert sys.exc_info() == (None, None, None)  # nothing left for later tests' tracebacks


def test_a_second_ctrl_c_during_the_checkpoint_write_waits_for_it(tmp_path, mitsuba, monkeypatch):
    """A race: a second Ctrl-C right after a pass is summed.  The checkpoint on disk then
    holds the sums of the passes it says it holds, and the resumed truth is the uninterrupted one."""
    import fogref.render.checkpoint as C
    import fogref.render.render as R

    tiny.one_spp_passes(monkeypatch)
    scene = tiny.make(mitsuba, tmp_path / "scene")
    kw = dict(spp=SPP, seed=5, progress=False, png=False)
    ref = _pixels(R.render(scene, tmp_path / "ref.exr", **kw))
    real = C.savez_atomic
    calls = []

    def ctrl_c_twice_then_write(path, **arrays):
        calls.append(int(arrays["done"]))
        os.kill(os.getpid(), signal.SIGINT)
        os.kill(os.getpid(), signal.SIGINT)
        return real(path, **arrays)

    monkeypatch.setattr(C, "savez_atomic", ctrl_c_twice_then_write)
    out = tmp_path / "x.exr"
    with pytest.raises(KeyboardInterrupt):
        R.render(scene, out, checkpoint_seconds=0, **kw)
    monkeypatch.setattr(C, "savez_atomic", real)
    with np.load(tmp_path / "x.exr.partial.npz") as z:
        assert int(z["done"]) == 1 and calls == [1]
    R.render(scene, out, **kw)
    assert _equal(_pixels(out), ref)


# ------------------------------------------------------------------ damaged checkpoints


def _flip_byte(p: Path, at: float) -> None:
    b = bytearray(p.read_bytes())
    b[int(len(b) * at)] ^= 0x40
    p.write_bytes(bytes(b))


def _rewrite(p: Path, **change) -> None:
    """Rewrite the checkpoint with some fields changed; the SHA-256 is recomputed unless given."""
    import fogref.render.checkpoint as C

    with np.load(p) as z:
        d = {k: z[k] for k in z.files}
    d.update(change)
    if "sha256" not in change and "sha256" in d:
        d["sha256"] = np.array(C.record_sha256(str(d["key"]), int(d["done"]), d["sums"], d["squares"]))
    np.savez(p, **d)


def _nan_in_sums(p: Path) -> None:
    with np.load(p) as z:
        s = z["sums"].copy()
    s[1, 2, 0] = np.nan
    _rewrite(p, sums=s)


def _sums_of_two_passes_counted_as_one(p: Path) -> None:
    """What that race left before: 'done = 1' with the sums of 2 passes (here: the sums doubled)."""
    with np.load(p) as z:
        s, q = z["sums"] * 2, z["squares"] * 2
    _rewrite(p, sums=s, squares=q)


def _drop_field(p: Path) -> None:
    with np.load(p) as z:
        d = {k: z[k] for k in z.files if k != "sha256"}
    np.savez(p, **d)


DAMAGE = {
    "truncated": lambda p: p.write_bytes(p.read_bytes()[: p.stat().st_size // 2]),
    "empty": lambda p: p.write_bytes(b""),
    "one flipped byte in the sums": lambda p: _flip_byte(p, 0.5),
    "one flipped byte in the first header": lambda p: _flip_byte(p, 0.0),
    "not a zip": lambda p: p.write_text("hello"),
    "sums of the wrong shape": lambda p: _rewrite(p, sums=np.zeros((3, 4, 30))),
    "squares of the wrong width": lambda p: _rewrite(p, squares=np.zeros((6, 8, 41))),
    "sums as float32": lambda p: _rewrite(p, sums=np.zeros((6, 8, 30), np.float32)),
    "pass count 0": lambda p: _rewrite(p, done=np.array(0)),
    "pass count past the end": lambda p: _rewrite(p, done=np.array(7)),
    "pass count not an integer": lambda p: _rewrite(p, done=np.array(1.5)),
    "pass count changed, checksum not": lambda p: _rewrite(p, done=np.array(2), sha256=np.load(p)["sha256"]),
    "a NaN in the sums": _nan_in_sums,
    "sums of two passes counted as one": _sums_of_two_passes_counted_as_one,
    "no checksum (an older fogref)": _drop_field,
    "a pickled object": lambda p: np.savez(p, sums=np.array([{"a": 1}], dtype=object)),
}


@pytest.fixture(scope="module")
def interrupted(tmp_path_factory, mitsuba):
    """A checkpoint after 1 of 3 passes, and the uninterrupted truth."""
    import fogref_plugins.passes as passes

    import fogref.render.checkpoint as C
    import fogref.render.render as R

    d = tmp_path_factory.mktemp("ckpt")
    scene = tiny.make(mitsuba, d / "scene")
    kw = dict(spp=SPP, seed=5, progress=False, png=False)
    mp = pytest.MonkeyPatch()
    mp.setattr(passes, "MAX_LANES", {"llvm": 48, "cuda": 48})
    ref = _pixels(R.render(scene, d / "ref.exr", **kw))
    real = C.savez_atomic

    def savez_then_interrupt(path, **kw2):
        real(path, **kw2)
        raise KeyboardInterrupt

    mp.setattr(C, "savez_atomic", savez_then_interrupt)
    with pytest.raises(KeyboardInterrupt):
        R.render(scene, d / "x.exr", checkpoint_seconds=0, **kw)
    mp.undo()
    return scene, (d / "x.exr.partial.npz").read_bytes(), ref, kw


@pytest.mark.parametrize("damage", list(DAMAGE))
def test_a_damaged_checkpoint_is_set_aside_with_a_warning_and_the_render_starts_over(
    tmp_path, interrupted, monkeypatch, capsys, damage
):
    import fogref.render.render as R

    tiny.one_spp_passes(monkeypatch)
    scene, good, ref, kw = interrupted
    ckpt = tmp_path / "x.exr.partial.npz"
    ckpt.write_bytes(good)
    DAMAGE[damage](ckpt)
    damaged = ckpt.read_bytes()
    out = R.render(scene, tmp_path / "x.exr", **kw)
    err = capsys.readouterr().err.strip()
    assert _equal(_pixels(out), ref), damage
    aside = tmp_path / "x.exr.partial.npz.damaged"
    assert aside.read_bytes() == damaged and not ckpt.exists(), damage  # renamed, not deleted
    assert len(err.splitlines()) == 1 and str(ckpt) in err and str(aside) in err, err
    assert "warning" in err and "Traceback" not in err


def test_a_flipped_byte_anywhere_is_set_aside_or_harmless(tmp_path, interrupted, monkeypatch, capsys):
    """A byte flipped at 40 places through the file: the truth is always the uninterrupted one; the
    checkpoint is resumed only when the flip left its record intact (zip metadata), else set aside."""
    import fogref.render.render as R

    tiny.one_spp_passes(monkeypatch)
    scene, good, ref, kw = interrupted
    for i in range(40):
        ckpt = tmp_path / f"{i}.exr.partial.npz"
        ckpt.write_bytes(good)
        _flip_byte(ckpt, i / 40)
        out = R.render(scene, tmp_path / f"{i}.exr", **kw)
        err = capsys.readouterr().err.strip()
        assert _equal(_pixels(out), ref), i
        aside = tmp_path / f"{i}.exr.partial.npz.damaged"
        assert (err == "" and not aside.exists()) or (len(err.splitlines()) == 1 and aside.exists()), (i, err)


def test_the_good_checkpoint_resumes_and_a_second_damaged_one_gets_its_own_name(
    tmp_path, interrupted, monkeypatch, capsys
):
    import fogref.render.checkpoint as C
    import fogref.render.render as R

    tiny.one_spp_passes(monkeypatch)
    scene, good, ref, kw = interrupted
    ckpt = tmp_path / "x.exr.partial.npz"
    ckpt.write_bytes(good)
    resumed = []
    real = C.resume
    monkeypatch.setattr(C, "resume", lambda *a: resumed.append(real(*a)) or resumed[-1])
    R.render(scene, tmp_path / "x.exr", **kw)
    assert resumed[0] is not None and resumed[0][2] == 1  # resumed after pass 1
    assert _equal(_pixels(tmp_path / "x.exr"), ref) and capsys.readouterr().err == ""
    (tmp_path / "x.exr.partial.npz.damaged").write_text("an earlier one")
    ckpt.write_bytes(b"")
    R.render(scene, tmp_path / "x.exr", **kw)
    assert (tmp_path / "x.exr.partial.npz.damaged").read_text() == "an earlier one"
    assert (tmp_path / "x.exr.partial.npz.damaged1").read_bytes() == b""
    assert "damaged1" in capsys.readouterr().err


def test_sigterm_stops_after_the_pass_with_a_checkpoint_like_ctrl_c(tmp_path, mitsuba, monkeypatch):
    """SIGTERM (a job scheduler, `kill`) is handled as Ctrl-C: the pass ends, the checkpoint is
    written, the rerun resumes to the uninterrupted truth."""
    from fogref_plugins.fogpath import FogPathIntegrator as cls

    import fogref.render.render as R

    tiny.one_spp_passes(monkeypatch)
    scene = tiny.make(mitsuba, tmp_path / "scene")
    kw = dict(spp=SPP, seed=5, progress=False, png=False)
    ref = _pixels(R.render(scene, tmp_path / "ref.exr", **kw))
    real = cls.render_moments

    def terminated_during_a_pass(self, *a, **k):
        os.kill(os.getpid(), signal.SIGTERM)
        return real(self, *a, **k)

    def unhandled(signum, frame):
        raise SystemExit("SIGTERM reached the test: the render did not handle it (no checkpoint)")

    previous = signal.signal(signal.SIGTERM, unhandled)
    try:
        monkeypatch.setattr(cls, "render_moments", terminated_during_a_pass)
        with pytest.raises(KeyboardInterrupt):
            R.render(scene, tmp_path / "x.exr", **kw)
        monkeypatch.setattr(cls, "render_moments", real)
        assert signal.getsignal(signal.SIGTERM) is unhandled  # restored
    finally:
        signal.signal(signal.SIGTERM, previous)
    with np.load(tmp_path / "x.exr.partial.npz") as z:
        assert int(z["done"]) == 1
    R.render(scene, tmp_path / "x.exr", **kw)
    assert _equal(_pixels(tmp_path / "x.exr"), ref)
