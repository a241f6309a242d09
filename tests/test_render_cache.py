"""fogref's one render cache: its key changes with everything that sets a truth's pixels."""

import pytest

from conftest import SCENES
from fogref.render.cache import truth_key, truth_path


def test_key_depends_on_everything_that_sets_pixels(tmp_path):
    scene = tmp_path / "s.xml"
    mesh = tmp_path / "m.obj"
    mesh.write_text("v 0 0 0\n")
    text = (
        (SCENES / "valley.xml")
        .read_text()
        .replace("</scene>", '<shape type="obj"><string name="filename" value="m.obj"/></shape></scene>')
    )
    scene.write_text(text)
    k = truth_key(scene, 4, 0, {"g": "0.5"})
    assert k == truth_key(scene, 4, 0, {"g": "0.5"})
    others = [
        truth_key(scene, 4, 0, {"g": "0.6"}),
        truth_key(scene, 8, 0, {"g": "0.5"}),
        truth_key(scene, 4, 1, {"g": "0.5"}),
        truth_key(scene, 4, 0, {"g": "0.5"}, pixel_filter="box"),
    ]
    mesh.write_text("v 0 0 1\n")  # a file the scene names
    others.append(truth_key(scene, 4, 0, {"g": "0.5"}))
    scene.write_text(text.replace('value="0.6"', 'value="0.61"'))  # the scene itself
    others.append(truth_key(scene, 4, 0, {"g": "0.5"}))
    assert len(set(others + [k])) == len(others) + 1
    assert truth_path(scene, 4, 0, {"g": "0.5"}, cache_dir=tmp_path).parent == tmp_path


def test_missing_scene_is_a_clear_error(tmp_path):
    from fogref.errors import FogrefError

    with pytest.raises(FogrefError, match="no such scene file"):
        truth_key(tmp_path / "nope.xml", 4, 0)
