"""The budget's sun-less copy of a scene finds the files the original loads.

The copy is written in the study's renders folder; before it named a relative mesh, envmap or
texture relative to that folder, where none of them is, so a scene with its own files could
not be budgeted (and its cache key missed them).
"""

import tiny_inputs_scene as tiny

from fogref.scene.edit import sunless_scene
from fogref.scene.inputs import inputs_digest, scene_inputs


def test_sunless_copy_loads_the_originals_files(tmp_path, mitsuba):
    scene = tiny.make(mitsuba, tmp_path / "project")
    copy = sunless_scene(scene, tmp_path / "renders")
    assert copy.parent == tmp_path / "renders"
    loaded = {i.path.name: i for i in scene_inputs(copy)[1:]}
    assert {"box.obj", "sky.exr", "tex.png"} <= set(loaded)
    assert all(i.exists and i.path.parent.resolve() == scene.parent.resolve() for i in loaded.values())
    before = inputs_digest(copy)
    (scene.parent / "box.obj").write_text((scene.parent / "box.obj").read_text() + "v 0 0 0\n")
    assert inputs_digest(copy) != before  # the copy's key covers the original's mesh
    s = mitsuba.load_file(str(copy), **tiny.RES, parallel=False)  # Mitsuba finds them; the sun is gone
    assert all("Directional" not in str(e) for e in s.emitters())


def test_overrides_used_by_reads_a_scene_file(tmp_path):
    """A sun-less copy no longer uses the sun's ``$defaults``; only the overrides a scene file uses pass."""
    from fogref.scene.defaults import overrides_used_by

    p = tmp_path / "s.xml"
    p.write_text('<scene><float name="g" value="$g"/><float name="x" value="$sun"/></scene>')
    assert overrides_used_by(p, {"g": 0.5, "sun_elevation": 4, "sun": 1}) == {"g": 0.5, "sun": 1}
