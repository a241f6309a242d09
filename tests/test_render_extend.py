"""``fogref render --spp N`` on an existing truth adds samples to it (fogref.render.render, "Extensible").

16 spp extended to 32 must equal, bitwise in every channel, the direct render whose passes are the
same (16 then 16, seeds of passes 0 and 1): the float64 sums merge exactly, as the passes on Dask
do.  A different seed, a changed file of the scene, or missing sums are refused with the reason;
fewer samples than the truth holds is a new render.
"""

import numpy as np
import pytest
import tiny_inputs_scene as tiny

from fogref.errors import FogrefError
from fogref.exrio import read_exr

pytestmark = pytest.mark.render


def sixteen_spp_passes(monkeypatch):
    """Passes of 16 spp at the tiny scene's 8x6 pixels."""
    import fogref_plugins.passes as passes

    monkeypatch.setattr(passes, "MAX_LANES", {"llvm": 16 * 48, "cuda": 16 * 48})


@pytest.mark.parametrize("threaded", [True, False], ids=["sums in a thread", "sums after"])
def test_extending_16_to_32_spp_equals_the_direct_render_bitwise(
    tmp_path, mitsuba, monkeypatch, capsys, threaded
):
    """Also with the sums written in a thread beside the EXR (a large truth's way): the sums it
    wrote are read back, checksum and all, and extend the truth bit for bit."""
    import fogref.render.render as R
    from fogref.render.render import moments_path, render

    monkeypatch.setattr(R, "SUMS_THREAD_MIN_PIXELS", 0 if threaded else 10**9)
    sixteen_spp_passes(monkeypatch)
    scene = tiny.make(mitsuba, tmp_path / "scene")
    kw = dict(seed=7, progress=False, png=False)
    direct = render(scene, tmp_path / "direct.exr", spp=32, **kw)
    out = render(scene, tmp_path / "x.exr", spp=16, **kw)
    assert moments_path(out).is_file() and "adding" not in capsys.readouterr().err
    render(scene, out, spp=32, **kw)
    err = capsys.readouterr().err
    assert "adding 16 spp to the 16 spp of" in err and "-> 32 spp" in err
    (a, attrs), (b, attrs_direct) = read_exr(out), read_exr(direct)
    assert attrs["fogref.spp"] == 32 and attrs["fogref.passes"] == attrs_direct["fogref.passes"] == [16, 16]
    assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)
    # fewer samples than it holds: a new render (its own passes), not an extension
    render(scene, out, spp=8, **kw)
    assert read_exr(out)[1]["fogref.spp"] == 8 and "adding" not in capsys.readouterr().err


def test_another_seed_changed_files_or_missing_sums_are_refused(tmp_path, mitsuba, monkeypatch):
    from fogref.render.render import moments_path, render

    sixteen_spp_passes(monkeypatch)
    scene = tiny.make(mitsuba, tmp_path / "scene")
    kw = dict(progress=False, png=False)
    out = render(scene, tmp_path / "x.exr", spp=16, seed=1, **kw)
    before = out.read_bytes()
    with pytest.raises(FogrefError, match=r"cannot add samples .*its seed is 1, this render's 2"):
        render(scene, out, spp=32, seed=2, **kw)
    tiny.write_texture(mitsuba, scene.parent / "tex.png", grey=120)
    with pytest.raises(FogrefError, match=r"the scene's files changed since it was rendered \(tex.png\)"):
        render(scene, out, spp=32, seed=1, **kw)
    assert out.read_bytes() == before  # refused: nothing written
    tiny.write_texture(mitsuba, scene.parent / "tex.png")  # as it was
    moments_path(out).unlink()
    with pytest.raises(FogrefError, match=r"float64 sums \(x.exr.moments.npz\) are missing"):
        render(scene, out, spp=32, seed=1, **kw)
    render(scene, out, spp=32, seed=2, resume=False, **kw)  # afresh over it
    assert read_exr(out)[1]["fogref.seed"] == 2


@pytest.mark.parametrize("failure", [KeyboardInterrupt, OSError])
@pytest.mark.parametrize("threaded", [True, False], ids=["sums in a thread", "sums after"])
def test_sums_never_land_without_their_truth(tmp_path, mitsuba, monkeypatch, failure, threaded):
    """The sums land only after the EXR, also when a large truth writes them in a thread beside
    it: when the EXR's write fails or is interrupted, the earlier truth and its sums are both
    kept, bitwise, and no temporary file is left.  (Sums that landed regardless would hold the
    new seed's values.)"""
    import re

    import fogref.render.render as R
    from fogref.atomic import temporary_names

    monkeypatch.setattr(R, "SUMS_THREAD_MIN_PIXELS", 0 if threaded else 10**9)
    sixteen_spp_passes(monkeypatch)
    scene = tiny.make(mitsuba, tmp_path / "scene")
    out = R.render(scene, tmp_path / "x.exr", spp=16, seed=7, progress=False, png=False)
    before = {p: p.read_bytes() for p in (out, R.moments_path(out))}
    real = R.write_exr

    def write_then_fail(path, *a, **kw):
        real(tmp_path / "elsewhere.exr", *a, **kw)  # the EXR's time, without replacing the truth
        raise failure("the disk went away")

    monkeypatch.setattr(R, "write_exr", write_then_fail)
    with pytest.raises(failure):
        R.render(scene, out, spp=16, seed=8, progress=False, png=False, resume=False)
    assert {p: p.read_bytes() for p in before} == before
    left = [p.name for p in tmp_path.iterdir() if re.fullmatch(temporary_names(R.moments_path(out)), p.name)]
    assert left == []
