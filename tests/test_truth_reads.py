"""A truth's pixels are read once per use, and not at all where its header decides.

Counted at OpenEXR (every ``OpenEXR.File`` opened on a path, with its pixels or header only):

* a render cache hit (``render_cached``) reads the truth's pixels once and hands that
  :class:`~fogref.gbuffer.Truth` on (it read them twice: once to check the file, once for the
  caller); a miss renders, then reads it once;
* a render whose output exists reads that file's header only to decide whether it may add
  samples to it (it read all its pixels);
* ``fogref diff``'s test of whether a file is a truth reads its header only.

Smallest error detected: one read of a file's pixels more than these.
"""

import numpy as np
import OpenEXR
import pytest

from fogref.shipped_scenes import scene_path

TINY = {"res": 8, "resy": 6}


@pytest.fixture
def opened(monkeypatch):
    """The EXR files opened for reading: ``(file name, "pixels" or "header")``, in order."""
    real, log = OpenEXR.File, []

    def counting(*args, **kwargs):
        if isinstance(args[0], str):
            log.append((args[0].rsplit("/", 1)[-1], "header" if kwargs.get("header_only") else "pixels"))
        return real(*args, **kwargs)

    monkeypatch.setattr(OpenEXR, "File", counting)
    return log


@pytest.mark.render
def test_a_cache_hit_reads_the_truth_once_and_a_miss_after_its_render(mitsuba, tmp_path, opened):
    from fogref.gbuffer import load_truth
    from fogref.render.cache import render_cached

    truth, cached = render_cached(scene_path("valley"), 2, 0, TINY, cache_dir=tmp_path)
    assert not cached and [k for _, k in opened].count("pixels") == 1, opened
    opened.clear()
    again, cached = render_cached(scene_path("valley"), 2, 0, TINY, cache_dir=tmp_path)
    assert cached and opened == [(truth.path.name, "pixels")], opened
    assert np.array_equal(again.final, load_truth(truth.path).final)


@pytest.mark.render
def test_rendering_over_a_truth_reads_its_header_only(mitsuba, tmp_path, opened):
    from fogref.render.render import render

    out = tmp_path / "t.exr"
    render(scene_path("valley"), out, spp=2, overrides=TINY, progress=False, png=False)
    assert opened == []
    render(scene_path("valley"), out, spp=2, seed=1, overrides=TINY, progress=False, png=False)
    assert opened == [("t.exr", "header")], opened


def test_whether_a_file_is_a_truth_is_read_from_its_header(tmp_path, opened):
    from fogref.compare.diff import is_truth
    from fogref.exrio import write_exr

    write_exr(tmp_path / "image.exr", {c: np.ones((2, 3)) for c in "RGB"})
    write_exr(tmp_path / "truth.exr", {c: np.ones((2, 3)) for c in "RGB"}, {"fogref.schema": 3})
    assert not is_truth(tmp_path / "image.exr") and is_truth(tmp_path / "truth.exr")
    assert opened == [("image.exr", "header"), ("truth.exr", "header")], opened
