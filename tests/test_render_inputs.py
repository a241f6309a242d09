"""Every file a scene loads is in its keys, and no output replaces one.

The tiny scene (tests/tiny_inputs_scene.py) loads an OBJ mesh, an envmap EXR and a bitmap
texture, two of them through ``$default``s.  An edit of any of them between an interruption
and the rerun, or before a cached truth is reused, means a fresh render.
"""

import os
import shutil

import numpy as np
import pytest
import tiny_inputs_scene as tiny

import fogref.render.checkpoint as C
from fogref.errors import FogrefError
from fogref.exrio import read_exr

pytestmark = pytest.mark.render


def _same_pixels(a, b) -> bool:
    ca, cb = read_exr(a)[0], read_exr(b)[0]
    return sorted(ca) == sorted(cb) and all(np.array_equal(ca[k], cb[k]) for k in ca)


# ------------------------------------------------------------------ the list of inputs


def test_scene_inputs_follow_mitsubas_resolution(tmp_path, mitsuba, monkeypatch):
    """Relative to the scene's folder, `$default`s and overrides applied, includes followed (a
    `filename` in an included file resolved against the top scene, as Mitsuba does), `<path>`
    folders searched first; each file once, the scene first."""
    from fogref.scene.inputs import scene_inputs

    scene = tiny.make(mitsuba, tmp_path / "proj")
    (tmp_path / "proj" / "meshes").mkdir()
    tiny.write_obj(tmp_path / "proj" / "meshes" / "rock.obj")
    (tmp_path / "proj" / "other.obj").write_text("v 0 0 0\n")
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "rock.xml").write_text(
        '<scene version="3.0.0"><shape type="obj"><string name="filename" value="rock.obj"/></shape></scene>'
    )
    scene.write_text(
        scene.read_text().replace(
            "</scene>", '<path value="meshes"/><include filename="../parts/rock.xml"/></scene>'
        )
    )
    monkeypatch.chdir(tmp_path)  # relative names are not looked up from the working directory first
    got = [(i.kind, os.path.relpath(i.path, tmp_path)) for i in scene_inputs(scene)]
    assert got == [
        ("scene", "proj/s.xml"),
        ("include", "parts/rock.xml"),
        ("emitter", "proj/sky.exr"),
        ("texture", "proj/tex.png"),
        ("shape", "proj/box.obj"),
        ("shape", "proj/meshes/rock.obj"),
    ]
    assert all(i.exists for i in scene_inputs(scene))
    over = [i.path.name for i in scene_inputs(scene, {"mesh": "other.obj", "sky": "sky.exr"})]
    assert "other.obj" in over and "box.obj" not in over
    # the same files as Mitsuba loads: the scene renders, and without the mesh it does not
    mitsuba.load_file(str(scene), parallel=False)
    (tmp_path / "proj" / "meshes" / "rock.obj").unlink()
    assert not [i for i in scene_inputs(scene) if i.path.name == "rock.obj"][0].exists
    with pytest.raises(Exception, match="rock.obj"):
        mitsuba.load_file(str(scene), parallel=False)


def test_digest_changes_with_every_input_and_only_with_them(tmp_path, mitsuba):
    from fogref.render.cache import truth_key
    from fogref.scene.inputs import inputs_digest

    scene = tiny.make(mitsuba, tmp_path)
    tiny.write_obj(tmp_path / "unused.obj", dx=3)
    key = lambda: truth_key(scene, 4, 0, tiny.RES)  # noqa: E731
    d0, k0 = inputs_digest(scene), key()
    (tmp_path / "unused.obj").write_text("v 1 1 1\n")  # a file the scene does not load
    assert (inputs_digest(scene), key()) == (d0, k0)
    seen = {k0}
    for edit in (
        lambda: tiny.write_obj(tmp_path / "box.obj", dx=8),
        lambda: tiny.write_envmap(mitsuba, tmp_path / "sky.exr", level=0.6),
        lambda: tiny.write_texture(mitsuba, tmp_path / "tex.png", grey=30),
    ):
        edit()
        assert key() not in seen
        seen.add(key())
    # a $default that selects a file: the override's file is hashed, not the default's
    assert key() != truth_key(scene, 4, 0, {**tiny.RES, "mesh": "unused.obj"})
    k_unused = truth_key(scene, 4, 0, {**tiny.RES, "mesh": "unused.obj"})
    tiny.write_obj(tmp_path / "box.obj", dx=-8)
    assert truth_key(scene, 4, 0, {**tiny.RES, "mesh": "unused.obj"}) == k_unused


# ------------------------------------------------------------------ resume after an edit


def _interrupt_after_first_checkpoint(R, monkeypatch):
    real = C.savez_atomic

    def savez_then_interrupt(path, **kw):
        real(path, **kw)
        raise KeyboardInterrupt

    monkeypatch.setattr(C, "savez_atomic", savez_then_interrupt)
    return lambda: monkeypatch.setattr(C, "savez_atomic", real)


EDITS = {
    "mesh moved 8 m": lambda mi, d: tiny.write_obj(d / "box.obj", dx=8),
    "envmap edited": lambda mi, d: tiny.write_envmap(mi, d / "sky.exr", level=0.9),
    "texture edited": lambda mi, d: tiny.write_texture(mi, d / "tex.png", grey=220),
}


@pytest.mark.parametrize("edit", list(EDITS))
def test_an_edited_input_between_interruption_and_rerun_means_a_fresh_render(
    tmp_path, mitsuba, monkeypatch, edit
):
    import fogref.render.render as R

    tiny.one_spp_passes(monkeypatch)
    scene = tiny.make(mitsuba, tmp_path / "scene")
    out = tmp_path / "x.exr"
    before = R.render(scene, tmp_path / "before.exr", spp=4, seed=2, progress=False, png=False)
    restore = _interrupt_after_first_checkpoint(R, monkeypatch)
    with pytest.raises(KeyboardInterrupt):
        R.render(scene, out, spp=4, seed=2, progress=False, png=False, checkpoint_seconds=0)
    assert (tmp_path / "x.exr.partial.npz").exists()
    restore()
    EDITS[edit](mitsuba, tmp_path / "scene")
    R.render(scene, out, spp=4, seed=2, progress=False, png=False)
    fresh = R.render(scene, tmp_path / "fresh.exr", spp=4, seed=2, progress=False, png=False)
    assert not _same_pixels(before, fresh), f"{edit}: the edit must change the pixels (else the test is void)"
    assert _same_pixels(out, fresh), f"{edit}: the rerun resumed from sums of the old {edit.split()[0]}"
    if edit.startswith("mesh"):
        assert set(np.unique(read_exr(out)[0]["hit"])) <= {0.0, 1.0}  # no fractional hit: one geometry


# ------------------------------------------------------------------ the cache


def test_cached_truth_after_a_mesh_edit_is_rendered_again(tmp_path, mitsuba, monkeypatch, request):
    from fogref.render.cache import cached_truth, render_cached
    from fogref.render.render import render

    monkeypatch.setenv("FOGREF_CACHE", str(tmp_path / "cache"))
    scene = tiny.make(mitsuba, tmp_path / "scene")
    first = cached_truth(scene, res=(8, 6), spp=4, cache_dir=tmp_path / "cache")
    assert render_cached(scene, 4, 0, tiny.RES, tmp_path / "cache")[1]  # unchanged: from the cache
    tiny.write_obj(tmp_path / "scene" / "box.obj", dx=8)
    truth, was_cached = render_cached(scene, 4, 0, tiny.RES, tmp_path / "cache")
    path = truth.path
    assert not was_cached and path != first.path
    fresh = render(scene, tmp_path / "fresh.exr", spp=4, seed=0, progress=False, png=False)
    assert _same_pixels(path, fresh)
    # the pytest fixture goes through the same cache, with the same key
    fixture_truth = request.getfixturevalue("fogref_truth")(scene, res=(8, 6), spp=4)
    assert _same_pixels(fixture_truth.path, fresh)
    tiny.write_texture(mitsuba, tmp_path / "scene" / "tex.png", grey=200)
    assert not render_cached(scene, 4, 0, tiny.RES, tmp_path / "cache")[1]


# ------------------------------------------------------------------ no output over an input


def test_out_equal_to_the_scenes_envmap_is_refused(tmp_path, mitsuba):
    from fogref.render.render import render

    scene = tiny.make(mitsuba, tmp_path)
    sky = (tmp_path / "sky.exr").read_bytes()
    with pytest.raises(FogrefError, match=r"sky\.exr would overwrite the envmap .*sky\.exr") as e:
        render(scene, tmp_path / "sky.exr", spp=1, progress=False)
    assert "\n" not in str(e.value)
    os.symlink(tmp_path / "sky.exr", tmp_path / "link.exr")  # a symlink to it: the same file
    with pytest.raises(FogrefError, match=r"link\.exr would overwrite the envmap .*sky\.exr"):
        render(scene, tmp_path / "link.exr", spp=1, progress=False)
    (tmp_path / "sub").mkdir()
    os.symlink(tmp_path, tmp_path / "sub" / "up")  # through a symlinked folder
    with pytest.raises(FogrefError, match="would overwrite the envmap"):
        render(scene, tmp_path / "sub" / "up" / "sky.exr", spp=1, progress=False)
    assert (tmp_path / "sky.exr").read_bytes() == sky


def test_out_whose_png_preview_is_a_texture_is_refused(tmp_path, mitsuba):
    from fogref.render.render import render

    scene = tiny.make(mitsuba, tmp_path)
    tex = (tmp_path / "tex.png").read_bytes()
    with pytest.raises(
        FogrefError,
        match=r"--out .*tex\.exr: the PNG preview .*tex\.png would overwrite the "
        r"texture .*tex\.png",
    ):
        render(scene, tmp_path / "tex.exr", spp=1, progress=False)
    assert (tmp_path / "tex.png").read_bytes() == tex and not (tmp_path / "tex.exr").exists()
    render(scene, tmp_path / "tex.exr", spp=1, progress=False, png=False)  # no preview: no clash
    assert (tmp_path / "tex.png").read_bytes() == tex


def test_out_over_a_mesh_selected_by_an_override_and_over_an_include_is_refused(tmp_path, mitsuba):
    from fogref.render.render import render

    scene = tiny.make(mitsuba, tmp_path)
    shutil.copy(tmp_path / "sky.exr", tmp_path / "night.exr")
    with pytest.raises(FogrefError, match="night.exr"):
        render(scene, tmp_path / "night.exr", spp=1, overrides={"sky": "night.exr"}, progress=False)
    # an include named like a checkpoint
    (tmp_path / "inc.exr.partial.npz").write_text('<scene version="3.0.0"/>')
    include = '<include filename="inc.exr.partial.npz"/></scene>'
    scene.write_text(scene.read_text().replace("</scene>", include))
    with pytest.raises(
        FogrefError,
        match=r"checkpoint .*inc\.exr\.partial\.npz "
        r"would overwrite the included XML",
    ):
        render(scene, tmp_path / "inc.exr", spp=1, progress=False)


def test_the_cli_refuses_in_one_line(tmp_path, mitsuba, capsys):
    from fogref.cli import main

    scene = tiny.make(mitsuba, tmp_path)
    rc = main(["render", str(scene), "--spp", "1", "--quiet", "--out", str(tmp_path / "sky.exr")])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1 and "sky.exr" in err and "Traceback" not in err


def test_refuse_overwriting_inputs_for_other_commands(tmp_path):
    """The reusable check (compare, sweep, study): paths, labelled pairs, hard links."""
    from fogref.atomic import refuse_overwriting_inputs

    a = tmp_path / "truth.exr"
    a.write_bytes(b"x")
    os.link(a, tmp_path / "hard.exr")
    refuse_overwriting_inputs([tmp_path / "errors.exr"], [a], "--out")
    for out in (a, tmp_path / "hard.exr", tmp_path / "." / "truth.exr"):
        with pytest.raises(FogrefError, match="truth.exr, which is an input"):
            refuse_overwriting_inputs([(out, "error map")], [(a, "truth")], "compare --out")
