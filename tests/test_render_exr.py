"""Ground-truth EXR: the schema's parts add up, same seed -> same pixels, header,
atomic writes, resume only from matching state, and clear errors for bad input."""

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from terminal_signals import sigint_default

import fogref.render.checkpoint as C
from conftest import ROOT, SCENES
from fogref import gbuffer
from fogref.errors import FogrefError, ParameterError
from fogref.exrio import read_exr

pytestmark = pytest.mark.render
SMALL = {"res": 12, "resy": 8}


@pytest.fixture(scope="module")
def rendered(tmp_path_factory, mitsuba):
    from fogref.render.render import render

    d = tmp_path_factory.mktemp("exr")
    a = render(SCENES / "valley.xml", d / "a.exr", spp=8, seed=3, overrides=SMALL, progress=False)
    b = render(SCENES / "valley.xml", d / "b.exr", spp=8, seed=3, overrides=SMALL, progress=False)
    return d, read_exr(a), read_exr(b)


def test_every_schema_channel_and_the_parts_add_up(rendered):
    _, (c, _), _ = rendered
    assert sorted(c) == sorted(gbuffer.exr_channel_names())
    for ch in "RGB":
        assert np.allclose(c[ch], c[f"attenuated_surface.{ch}"] + c[f"inscatter.{ch}"], rtol=1e-6, atol=1e-7)
        assert np.allclose(
            c[f"inscatter.{ch}"], c[f"single.{ch}"] + c[f"multiple.{ch}"], rtol=1e-6, atol=1e-7
        )
        valid = c["surface_coverage"] > 0
        # T * surface estimates attenuated_surface (both consistent; equal in expectation)
        assert np.all(c[f"surface.{ch}"][~valid] == 0)
        assert np.all(c[f"stderr.{ch}"] >= 0)
    assert all(np.isfinite(v).all() for v in c.values())
    assert ((c["T.R"] > 0) & (c["T.R"] <= 1)).all()
    assert set(np.unique(c["hit"])) == {0.0, 1.0}  # pixel-exact: a pixel hits or misses, never a mix


def test_same_seed_same_pixels(rendered):
    _, (a, _), (b, _) = rendered
    for k in a:
        assert np.array_equal(a[k], b[k]), k


def test_every_compression_stores_the_same_values(rendered, mitsuba, tmp_path):
    """``exr_compression`` changes the file, never a value: the render of ``a`` written with each
    other lossless compression reads back bitwise equal (smallest error detected: one bit of one
    float32 value of one channel); a lossy or unknown one is refused in one line before any work."""
    import OpenEXR

    from fogref.render.render import render

    d, (a, _), _ = rendered
    sizes = {}
    for c in ("none", "rle"):
        out = render(
            SCENES / "valley.xml",
            tmp_path / f"{c}.exr",
            spp=8,
            seed=3,
            overrides=SMALL,
            progress=False,
            png=False,
            exr_compression=c,
        )
        got, attrs = read_exr(out)
        assert attrs["compression"] == getattr(
            OpenEXR, "NO_COMPRESSION" if c == "none" else "RLE_COMPRESSION"
        )
        assert sorted(got) == sorted(a) and all(
            np.array_equal(got[k].view(np.uint32), a[k].view(np.uint32)) for k in a
        )
        sizes[c] = out.stat().st_size
    assert sizes["none"] > (d / "a.exr").stat().st_size  # zip, the default, compresses
    with pytest.raises(FogrefError, match="--exr-compression: 'b44' is not one of"):
        render(
            SCENES / "valley.xml",
            tmp_path / "lossy.exr",
            spp=8,
            overrides=SMALL,
            progress=False,
            exr_compression="b44",
        )
    assert not (tmp_path / "lossy.exr").exists()


@pytest.mark.parametrize("spp, exact", [(1, True), (2, True), (8, True), (3, True), (16, True), (4, False)])
def test_the_channels_on_the_host_and_on_the_device_are_bitwise_equal(mitsuba, spp, exact):
    """The driver computes the EXR's channels with numpy on the host copy of the sums up to
    ``HOST_CHANNELS_MAX_PIXELS`` pixels and with one Dr.Jit kernel above: the same sums give the
    same float64 values, and so the same float32 ones, either way.  Smallest error detected: one
    bit of one float64 value of one channel (a fused multiply-add, a division where Dr.Jit
    multiplies by the reciprocal: spp 3 and 16 divide by 3 and 15, another order of the
    operations)."""
    import drjit as dr

    import fogref.render.render as R
    from fogref.render.load import loaded_scene
    from fogref.scene.parsed import read_scene

    scene, _ = loaded_scene(read_scene(SCENES / "valley.xml", {"res": 24, "resy": 14}))
    integrator = scene.integrator()
    integrator.aovs = True
    s, q = integrator.render_moments(scene, 0, 7, spp, pixel_exact=exact)
    dr.eval(s, q)
    host64, device64 = R._channels(np.asarray(s), np.asarray(q), spp), R._channels(s, q, spp)
    differ = [k for k in host64 if np.asarray(device64[k]).tobytes() != host64[k].tobytes()]
    assert not differ, differ
    host, _ = R._float32_planes(host64)
    device, _ = R._device_float32(device64)
    assert sorted(host) == sorted(device) == sorted(gbuffer.exr_channel_names())
    differ = [k for k in host if not np.array_equal(host[k].view(np.uint32), device[k].view(np.uint32))]
    assert not differ, differ
    assert 24 * 14 <= R.HOST_CHANNELS_MAX_PIXELS < 320 * 180


def test_header_records_everything(rendered):
    _, (_, attrs), _ = rendered
    for k in (
        "fogref.params",
        "fogref.spp",
        "fogref.seed",
        "fogref.variant",
        "fogref.version",
        "fogref.mitsuba",
        "fogref.schema",
        "fogref.pixel_filter",
        "fogref.scene_sha256",
        "fogref.overrides",
    ):
        assert k in attrs, k
    p = attrs["fogref.params"]
    assert p["medium"]["falloff"] == pytest.approx(0.0138629)
    assert p["sun"]["direction"][1] > 0 and p["sky"]["radiance"] == [0.2, 0.3, 0.5]
    assert attrs["fogref.spp"] == 8 and attrs["fogref.seed"] == 3  # JSON-decoded by read_exr
    assert attrs["fogref.pixel_filter"] == "centre" and str(attrs["fogref.schema"]) == str(
        gbuffer.SCHEMA_VERSION
    )


def test_no_temporary_files_left_and_plain_file_mode(rendered):
    d, _, _ = rendered
    # each truth, its preview and its float64 sums (kept so that more samples can be added)
    want = ["a.exr", "a.exr.moments.npz", "a.png", "b.exr", "b.exr.moments.npz", "b.png"]
    assert sorted(p.name for p in d.iterdir()) == want
    umask = os.umask(0)
    os.umask(umask)
    assert (d / "a.exr").stat().st_mode & 0o777 == 0o666 & ~umask  # not mkstemp's 0600


def test_stderr_matches_the_spread_of_independent_renders(tmp_path, mitsuba):
    """Per-pixel standard errors from second moments vs the spread of 12 renders.

    The ratio of the mean stderr^2 to the variance across renders is 1 within
    ~0.15 (12 runs x 96 pixels); a factor-of-1.5 mistake in the stderr fails."""
    from fogref.render.render import render

    runs = [
        read_exr(
            render(
                SCENES / "valley.xml",
                tmp_path / f"r{s}.exr",
                spp=16,
                seed=s,
                overrides=SMALL,
                progress=False,
                png=False,
            )
        )[0]
        for s in range(12)
    ]
    for part in ("", "inscatter.", "single."):
        vals = np.stack([r[f"{part}G"] for r in runs])
        se2 = np.stack([r[f"stderr.{part}G"] for r in runs]) ** 2
        spread = vals.var(axis=0, ddof=1)
        ok = spread > 0
        ratio = se2.mean(axis=0)[ok].mean() / spread[ok].mean()
        assert 0.7 < ratio < 1.4, f"{part or 'final'}: mean stderr^2 / spread = {ratio:.3f}"


def _interrupting_savez(R, monkeypatch):
    real = C.savez_atomic

    def savez_then_interrupt(path, **kw):
        real(path, **kw)
        raise KeyboardInterrupt

    monkeypatch.setattr(C, "savez_atomic", savez_then_interrupt)
    return real


def test_resume_after_interruption_gives_identical_pixels(tmp_path, mitsuba, monkeypatch):
    """Interrupt after the first checkpoint; the rerun resumes and gives the same pixels."""
    import fogref_plugins.passes as passes

    import fogref.render.checkpoint as C
    import fogref.render.render as R

    monkeypatch.setattr(passes, "MAX_LANES", {"llvm": 96 * 4, "cuda": 96 * 4})  # 4 spp per pass at 12x8
    ref = R.render(
        SCENES / "valley.xml", tmp_path / "ref.exr", spp=8, seed=1, overrides=SMALL, progress=False
    )
    real = _interrupting_savez(R, monkeypatch)
    out = tmp_path / "x.exr"
    with pytest.raises(KeyboardInterrupt):
        R.render(
            SCENES / "valley.xml", out, spp=8, seed=1, overrides=SMALL, progress=False, checkpoint_seconds=0
        )
    assert not out.exists() and (tmp_path / "x.exr.partial.npz").exists()
    monkeypatch.setattr(C, "savez_atomic", real)
    R.render(SCENES / "valley.xml", out, spp=8, seed=1, overrides=SMALL, progress=False)
    a, b = read_exr(ref)[0], read_exr(out)[0]
    assert all(np.array_equal(a[k], b[k]) for k in a) and not (tmp_path / "x.exr.partial.npz").exists()


def test_checkpoint_of_an_edited_scene_is_not_resumed(tmp_path, mitsuba, monkeypatch):
    """The checkpoint key is the scene's content: edit the scene between the
    interruption and the rerun, and the rerun starts over (no mixed image)."""
    import fogref_plugins.passes as passes

    import fogref.render.checkpoint as C
    import fogref.render.render as R

    monkeypatch.setattr(passes, "MAX_LANES", {"llvm": 96 * 4, "cuda": 96 * 4})
    scene = tmp_path / "s.xml"
    scene.write_text((SCENES / "valley.xml").read_text())
    real = _interrupting_savez(R, monkeypatch)
    out = tmp_path / "x.exr"
    with pytest.raises(KeyboardInterrupt):
        R.render(scene, out, spp=8, seed=1, overrides=SMALL, progress=False, checkpoint_seconds=0)
    monkeypatch.setattr(C, "savez_atomic", real)
    scene.write_text(scene.read_text().replace('name="albedo" value="0.9"', 'name="albedo" value="0.5"'))
    R.render(scene, out, spp=8, seed=1, overrides=SMALL, progress=False)
    fresh = R.render(scene, tmp_path / "fresh.exr", spp=8, seed=1, overrides=SMALL, progress=False)
    a, b = read_exr(out)[0], read_exr(fresh)[0]
    assert all(np.array_equal(a[k], b[k]) for k in a)


@pytest.mark.parametrize("stale", ["x.exr.partial.npz.abc123.tmp.npz", "x.exr.moments.npz.k3_x9.tmp.npz"])
def test_leftover_temporary_checkpoint_is_removed(tmp_path, mitsuba, stale):
    """A writer killed mid-write (SIGKILL) leaves '<out>.partial.npz.XXXX.tmp.npz' (a checkpoint)
    or '<out>.moments.npz.XXXX.tmp.npz' (the sums, staged while the EXR was written); the next run
    removes it."""
    from fogref.render.render import render

    (tmp_path / stale).write_bytes(b"partial")
    render(SCENES / "valley.xml", tmp_path / "x.exr", spp=1, overrides=SMALL, progress=False, png=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.exr", "x.exr.moments.npz"]


#: wall-clock limit [s] of a wait, for a hang only: generous on a loaded machine
HANG_S = 900


def test_ctrl_c_stops_cleanly_and_the_rerun_resumes(tmp_path, mitsuba):
    """SIGINT to `fogref render`: exit 130, a one-line message (no traceback), a
    checkpoint; the same command then finishes from it."""
    out = tmp_path / "x.exr"
    cmd = [
        sys.executable,
        "-m",
        "fogref.cli",
        "render",
        str(SCENES / "valley.xml"),
        "--spp",
        "4096",
        "--quiet",
        "--no-png",
        "--checkpoint-seconds",
        "0",
        "--out",
        str(out),
    ]  # 320x180: ~36 spp per pass, a second or two each; a checkpoint after every pass
    # stderr to a file: a pipe nobody reads while we wait could fill and block the render
    with open(tmp_path / "err.txt", "w+") as log:
        p = subprocess.Popen(cmd, cwd=ROOT, stderr=log, text=True, preexec_fn=sigint_default)
        # the event: the first checkpoint, so the pass loop runs; the clock only catches a hang
        deadline = time.monotonic() + HANG_S
        while p.poll() is None and not (tmp_path / "x.exr.partial.npz").exists():
            assert time.monotonic() < deadline, f"no pass finished in {HANG_S} s: a hang"
            time.sleep(0.1)
        p.send_signal(signal.SIGINT)
        p.wait(timeout=HANG_S)  # a hang only
        log.seek(0)
        err = log.read()
    assert p.returncode == 130, err
    assert "Traceback" not in err and "interrupted" in err
    assert (tmp_path / "x.exr.partial.npz").exists() and not out.exists()


def test_outputs_never_overwrite_inputs(tmp_path, mitsuba):
    from fogref.render.render import render

    scene = tmp_path / "s.xml"
    scene.write_text((SCENES / "valley.xml").read_text())
    with pytest.raises(FogrefError, match=r"ending in \.exr"):
        render(scene, tmp_path / "x.png", spp=1, overrides=SMALL, progress=False)
    with pytest.raises(FogrefError, match="ending in .exr"):
        render(scene, scene, spp=1, overrides=SMALL, progress=False)
    (tmp_path / "dir.exr").mkdir()
    with pytest.raises(FogrefError, match="is a directory"):
        render(scene, tmp_path / "dir.exr", spp=1, overrides=SMALL, progress=False)
    notexr = tmp_path / "notes.exr"
    notexr.write_text("my notes")
    with pytest.raises(FogrefError, match="not an EXR"):
        render(scene, notexr, spp=1, overrides=SMALL, progress=False)
    assert notexr.read_text() == "my notes" and "fogpath" in scene.read_text()


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_read_only_folder_is_refused_before_rendering(tmp_path, mitsuba):
    from fogref.render.render import render

    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    with pytest.raises(FogrefError, match="not writable"):
        render(SCENES / "valley.xml", ro / "x.exr", spp=1, overrides=SMALL, progress=False)


def test_folder_check_happens_before_rendering(tmp_path, mitsuba, monkeypatch):
    """The folder is checked before any pass runs (the old driver failed after rendering)."""
    import fogref.render.render as R

    def no_write(path, write):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(R, "atomic_write", no_write)
    t = time.perf_counter()
    with pytest.raises(FogrefError, match="not writable"):
        R.render(
            SCENES / "valley.xml",
            tmp_path / "x.exr",
            spp=64,
            overrides={"res": 320, "resy": 180},
            progress=False,
        )
    assert time.perf_counter() - t < 5


def test_out_of_range_parameter_is_named(tmp_path, mitsuba):
    from fogref.render.render import render

    bad = tmp_path / "bad.xml"
    bad.write_text(
        (SCENES / "valley.xml")
        .read_text()
        .replace('<default name="g" value="0.6"/>', '<default name="g" value="1.5"/>')
    )
    with pytest.raises(ParameterError, match=r"bad.xml.*'g'.*1.5.*outside \[-0.999, 0.999\]"):
        render(bad, tmp_path / "o.exr", spp=1, overrides=SMALL, progress=False)
    with pytest.raises(ParameterError, match=r"'falloff'.*outside"):
        render(
            SCENES / "valley.xml",
            tmp_path / "o.exr",
            spp=1,
            overrides={**SMALL, "falloff": -1},
            progress=False,
        )


@pytest.mark.parametrize(
    "override, message",
    [
        ({"sigma_t": "abc"}, r"sigma_t=abc: 'abc' does not parse as a number"),
        ({"res": "0"}, r"res=0: 0 is outside \[1, 65536\] pixels"),
        ({"res": "12.5"}, r"res=12.5: 12.5 is not an integer"),
        ({"sigmat": "0.01"}, r"no \$default 'sigmat' \(did you mean 'sigma_t'\?\)"),
        ({"sky_radiance": "-0.18, 0.3, 0.5"}, r"sky_radiance.*outside.*\[0, inf\)"),
        ({"max_depth": "-5"}, r"max_depth.*-5"),
    ],
)
def test_bad_overrides_get_clear_errors(tmp_path, mitsuba, override, message):
    from fogref.render.render import render

    with pytest.raises(FogrefError, match=message):
        render(
            SCENES / "valley.xml", tmp_path / "o.exr", spp=1, overrides={**SMALL, **override}, progress=False
        )


def test_huge_resolution_is_refused_with_the_memory_figure(tmp_path, mitsuba):
    from fogref.render.render import render

    with pytest.raises(FogrefError, match=r"20000x20000 pixels need about .* GiB"):
        render(
            SCENES / "valley.xml",
            tmp_path / "o.exr",
            spp=1,
            overrides={"res": 20000, "resy": 20000},
            progress=False,
        )


def test_non_finite_render_is_refused_and_located(tmp_path, mitsuba, monkeypatch):
    from fogref_plugins.fogpath import FogPathIntegrator as cls

    real = cls.render_moments

    def poisoned(self, *a, **kw):
        s, q = real(self, *a, **kw)
        s = np.array(s)
        s[2, 5, 0] = np.nan
        return s, q

    monkeypatch.setattr(cls, "render_moments", poisoned)
    from fogref.render.render import render

    with pytest.raises(FogrefError, match=r"non-finite values in 'R': 1 pixel\(s\), first at \(x=5, y=2\)"):
        render(SCENES / "valley.xml", tmp_path / "o.exr", spp=1, overrides=SMALL, progress=False)
    assert not (tmp_path / "o.exr").exists()


def test_unsupported_emitters_and_media_are_refused(tmp_path, mitsuba):
    from fogref.render.render import render

    text = (SCENES / "valley.xml").read_text()
    sunsky = tmp_path / "sunsky.xml"
    sunsky.write_text(text.replace("</scene>", '<emitter type="sunsky"/></scene>'))
    with pytest.raises(FogrefError, match="a sunsky brings its own sun"):  # a 2nd sun and a 2nd sky
        render(sunsky, tmp_path / "o.exr", spp=1, overrides=SMALL, progress=False)
    point = tmp_path / "point.xml"
    point.write_text(
        text.replace(
            "</scene>", '<emitter type="point"><point name="position" value="0,5,0"/></emitter></scene>'
        )
    )
    with pytest.raises(FogrefError, match="emitter 'point' is not supported"):
        render(point, tmp_path / "o.exr", spp=1, overrides=SMALL, progress=False)


def test_malformed_xml_and_cli_message(tmp_path, mitsuba):
    bad = tmp_path / "broken.xml"
    bad.write_text("<scene version='3.0.0'><integrator type='fogpath'>")
    from fogref.render.render import render

    with pytest.raises(FogrefError, match="broken.xml: malformed XML"):
        render(bad, tmp_path / "o.exr", spp=1, progress=False)
    r = subprocess.run(
        [sys.executable, "-m", "fogref.cli", "render", str(bad), "--out", str(tmp_path / "o.exr")],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert r.returncode == 2 and "broken.xml: malformed XML" in r.stderr and "Traceback" not in r.stderr
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "fogref.cli",
            "render",
            str(SCENES / "valley.xml"),
            "--spp",
            "0",
            "--out",
            str(tmp_path / "o.exr"),
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert r.returncode == 2 and "--spp" in r.stderr


def test_heightfog_floor_nan_is_refused(tmp_path, mitsuba):
    from fogref.render.render import render

    bad = tmp_path / "floor.xml"
    bad.write_text(
        (SCENES / "valley.xml")
        .read_text()
        .replace(
            '<float name="height" value="$fog_height"/>',
            '<float name="height" value="$fog_height"/><float name="floor" value="nan"/>',
        )
    )
    with pytest.raises(FogrefError, match=r"'floor'.*nan"):
        render(bad, tmp_path / "o.exr", spp=1, overrides=SMALL, progress=False)


def test_full_disk_is_an_error_not_a_traceback(tmp_path, mitsuba, monkeypatch, capsys):
    """ENOSPC while writing the EXR: exit 2, the file and the reason, no partial output."""
    import errno

    import fogref.render.render as R
    from fogref.cli import main

    def full(path, channels, attrs=None, compression="zip"):
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(R, "write_exr", full)
    rc = main(
        [
            "render",
            str(SCENES / "valley.xml"),
            "--set",
            "res=12",
            "--set",
            "resy=8",
            "--spp",
            "1",
            "--quiet",
            "--out",
            str(tmp_path / "o.exr"),
        ]
    )
    err = capsys.readouterr().err
    assert rc == 2 and "o.exr: No space left on device" in err and not (tmp_path / "o.exr").exists()


def test_write_exr_refuses_non_finite_channels(tmp_path):
    from fogref.exrio import write_exr

    with pytest.raises(FogrefError, match=r"non-finite values in channel\(s\) b, c"):
        write_exr(
            tmp_path / "x.exr",
            {"a": np.zeros((2, 2)), "b": np.full((2, 2), np.nan), "c": np.full((2, 2), 1e39)},
        )
    assert not (tmp_path / "x.exr").exists()
