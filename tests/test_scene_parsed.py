"""A scene is read once: one parse of its XML per render before Mitsuba's own, and per
description of its fog and camera (:class:`fogref.scene.parsed.ParsedScene`)."""

import xml.etree.ElementTree as ET

import pytest

from fogref.shipped_scenes import scene_path


@pytest.fixture
def parses(monkeypatch):
    """Every XML parse of the Python standard library in the test: (function, argument)."""
    seen = []
    for name in ("parse", "fromstring", "XML", "iterparse"):
        real = getattr(ET, name)

        def counting(*a, _real=real, _name=name, **k):
            seen.append((_name, a[0] if a else None))
            return _real(*a, **k)

        monkeypatch.setattr(ET, name, counting)
    return seen


@pytest.mark.render
def test_a_render_parses_the_scene_once(tmp_path, mitsuba, parses):
    from fogref.render.render import render

    render(scene_path("valley"), tmp_path / "t.exr", spp=1, overrides={"res": 8, "resy": 4}, progress=False)
    assert [n for n, _ in parses] == ["parse"], parses  # Mitsuba parses the file itself (C++)


@pytest.mark.render
def test_a_cached_truth_parses_the_scene_once(tmp_path, mitsuba, parses):
    from fogref.render.cache import render_cached

    _, cached = render_cached(scene_path("valley"), 1, 0, {"res": 8, "resy": 4}, cache_dir=tmp_path)
    assert not cached and len(parses) == 1, parses  # the key and the render share the parse


def test_the_physical_scene_and_its_camera_parse_the_scene_once(parses):
    from fogref.study.fit import physical_from_scene

    pf = physical_from_scene(scene_path("valley"))
    assert list(pf.camera) == [0.0, 2.0, 0.0] and pf.camera_forward is not None and len(parses) == 1, parses


def test_parsed_scene_resolves_overrides_and_lists_inputs_from_the_same_tree(tmp_path, parses):
    from fogref.scene.parsed import read_scene

    s = read_scene(scene_path("valley"), {"sun_elevation": 12})
    assert s.defaults["sun_elevation"] == "12" and s.overrides == {"sun_elevation": 12}
    assert [i.kind for i in s.inputs] == ["scene"] and len(s.digest) == 64
    assert len(parses) == 1, parses
    assert s.root.find("default[@name='sun_elevation']").get("value") != "12"  # the tree is not edited


def test_a_read_scene_with_other_overrides_is_refused(tmp_path):
    from fogref.errors import FogrefError
    from fogref.render.render import render
    from fogref.scene.parsed import read_scene

    with pytest.raises(FogrefError, match="carries its overrides"):
        render(read_scene(scene_path("valley")), tmp_path / "t.exr", overrides={"res": 8})
    assert not (tmp_path / "t.exr").exists()
