"""fogpath's frozen passes (``dr.freeze``) give the traced pixels, bitwise, and never stale ones.

``FogPathIntegrator.render_moments`` traces its pass on the first call of a fingerprint (every
Python value the trace reads), records it with ``dr.freeze`` on the
:data:`~fogref_plugins.fogpath.RECORD_FROM_CALL`-th call and replays the recording after.
Every comparison here is bitwise (float64 per-pixel sums and squares, 8x6 px, 4 spp of
``scenes/valley.xml``), so each test fails on any pixel that differs in any bit:

* replays of one loaded scene with new seeds equal the traced passes; the Python pass body runs
  only for the traced calls and the recording (fails if replays were not happening);
* a value changed on the loaded scene (the sky's radiance, a Dr.Jit input: replayed with the new
  value; the sun's irradiance, read in Python too; the fog object's extinction) gives the traced
  pixels of the changed scene, and differs from before (fails on a stale replay);
* a recording Dr.Jit refuses falls back to tracing, with one warning naming Dr.Jit's reason, and
  the JIT state stays usable (the fallback's pixels are the traced ones);
* ``freeze`` off (XML ``<boolean name="freeze" value="false"/>`` or the attribute) traces every
  pass;
* the render driver (:func:`fogref.render.render.render`) repeated in one process reuses the
  loaded scene, and an edited input file does not (:func:`fogref.render.load.loaded_scene`); what
  the driver sets on the integrator does not outlive the call.
"""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

VALLEY = Path(__file__).resolve().parents[1] / "scenes" / "valley.xml"
TINY = {"res": "8", "resy": "6"}
SPP = 4


def _sums(scene, seed, freeze=True):
    fp = scene.integrator()
    fp.freeze = freeze
    sums, squares = fp.render_moments(scene, seed=seed, spp=SPP, pixel_exact=True)
    return np.concatenate([np.array(sums).ravel(), np.array(squares).ravel()])


@pytest.fixture
def counted(mitsuba, monkeypatch):
    """The number of times the Python pass body ran (traced or recorded, never replayed)."""
    import fogref_plugins.fogpath as fpm

    calls = [0]
    body = fpm.FogPathIntegrator._pass

    def counting(self, *args):
        calls[0] += 1
        return body(self, *args)

    monkeypatch.setattr(fpm.FogPathIntegrator, "_pass", counting)
    return calls


@pytest.mark.render
def test_replays_of_one_scene_give_the_traced_pixels_bitwise(mitsuba, counted):
    import fogref_plugins.fogpath as fpm

    scene = mitsuba.load_file(str(VALLEY), **TINY, parallel=False)
    seeds = range(1, fpm.RECORD_FROM_CALL + 4)  # traced, recorded, 3 replays
    frozen = []
    for seed in seeds:
        frozen.append(_sums(scene, seed))
    assert counted[0] == fpm.RECORD_FROM_CALL, "the pass body ran on a replay (or never recorded)"
    assert scene.integrator().n_recordings == 1
    traced = [_sums(scene, seed, freeze=False) for seed in seeds]
    assert scene.integrator().n_recordings == 1
    for seed, a, b in zip(seeds, frozen, traced):
        assert np.array_equal(a, b), f"seed {seed}: frozen and traced pixels differ"
    assert not np.array_equal(frozen[-1], frozen[-2]), "a new seed did not change the pixels"


def _replaying(scene):
    """Frozen calls until ``scene``'s pass replays (a recording exists for its fingerprint)."""
    import fogref_plugins.fogpath as fpm

    for seed in range(fpm.RECORD_FROM_CALL + 1):
        _sums(scene, 10 + seed)


@pytest.mark.render
def test_a_changed_scene_value_gives_the_changed_scenes_traced_pixels(mitsuba, counted):
    scene = mitsuba.load_file(str(VALLEY), **TINY, parallel=False)
    fp = scene.integrator()
    _replaying(scene)
    before, recordings = _sums(scene, 7), fp.n_recordings
    params = mitsuba.traverse(scene)

    # the sky's radiance enters only as a Dr.Jit input: replayed, with the new value
    params["sky.radiance.value"] = mitsuba.Color3f(0.5, 0.2, 0.1)
    params.update()
    n = counted[0]
    sky = _sums(scene, 7)
    assert counted[0] == n and fp.n_recordings == recordings, "a new input value was not replayed"
    assert np.array_equal(sky, _sums(scene, 7, freeze=False)), "the sky's new radiance was not used"
    assert not np.array_equal(sky, before)

    # the sun's irradiance is also read in Python (the sun's sampler): a new recording
    params["sun.irradiance.value"] = mitsuba.Color3f(1.0, 4.0, 2.0)
    params.update()
    sun = _sums(scene, 7)
    assert np.array_equal(sun, _sums(scene, 7, freeze=False)), "a stale sun was replayed"
    assert not np.array_equal(sun, sky)

    # a fog value of the medium object (Python numbers of a Python plugin)
    medium = scene.sensors()[0].get_medium()
    medium.fog = dataclasses.replace(medium.fog, sigma_t=(0.003, 0.002, 0.001))
    for seed in (7, 8, 9):  # traced, recorded, replayed: each the changed scene's pixels
        fog = _sums(scene, seed)
        assert np.array_equal(fog, _sums(scene, seed, freeze=False)), f"seed {seed}: stale fog replayed"
    assert not np.array_equal(_sums(scene, 7), sun)


@pytest.mark.render
def test_a_refused_recording_falls_back_to_tracing_with_one_warning(mitsuba, monkeypatch, capfd):
    import fogref_plugins.fogpath as fpm

    scene = mitsuba.load_file(str(VALLEY), **TINY, parallel=False)
    fp = scene.integrator()
    capfd.readouterr()
    # reading the scene while tracing (a wait on an evaluated variable) is what Dr.Jit refuses to record
    monkeypatch.setattr(fpm.FogPathIntegrator, "_read_once", lambda self, scene, name, read: read())
    got = [_sums(scene, seed) for seed in (1, 2, 3, 4)]
    out = capfd.readouterr()
    err = out.err + out.out  # Mitsuba's log goes to stdout or stderr
    warnings = [line for line in err.splitlines() if "dr.freeze refused" in line]
    assert len(warnings) == 1, err
    assert fp.freeze_refused and fp.freeze_refused in warnings[0]
    assert "evaluated variables" in fp.freeze_refused, fp.freeze_refused
    monkeypatch.undo()
    for seed, a in zip((1, 2, 3, 4), got):
        assert np.array_equal(a, _sums(scene, seed, freeze=False)), (
            f"seed {seed}: the fallback's pixels differ"
        )
    # the JIT state is usable: a new scene records and replays
    other = mitsuba.load_file(str(VALLEY), **TINY, parallel=False)
    for seed in (1, 2, 3, 4):
        _sums(other, seed)
    assert other.integrator().n_recordings == 1 and other.integrator().freeze_refused is None


@pytest.mark.render
def test_freeze_off_traces_every_pass(mitsuba, counted, tmp_path):
    xml = VALLEY.read_text().replace(
        '<integrator type="fogpath">',
        '<integrator type="fogpath">\n        <boolean name="freeze" value="false"/>',
    )
    path = tmp_path / "valley_traced.xml"
    path.write_text(xml)
    scene = mitsuba.load_file(str(path), **TINY, parallel=False)
    fp = scene.integrator()
    assert fp.freeze is False
    for seed in (1, 2, 3, 4):
        sums, _ = fp.render_moments(scene, seed=seed, spp=SPP)
    assert counted[0] == 4 and fp.n_recordings == 0
    on = mitsuba.load_file(str(VALLEY), **TINY, parallel=False)
    assert on.integrator().freeze is True
    _replaying(on)
    n = counted[0]
    on.integrator().freeze = False  # the attribute: traced from the next pass on
    _sums(on, 1, freeze=False)
    assert counted[0] == n + 1


def _exr_pixels(path):
    from fogref.exrio import read_exr

    channels, _ = read_exr(path)
    return np.stack([channels[k] for k in sorted(channels)])


@pytest.mark.render
def test_repeated_renders_reuse_the_loaded_scene_and_an_edited_file_does_not(mitsuba, tmp_path):
    from fogref.render.load import held_scenes
    from fogref.render.render import render

    path = tmp_path / "valley.xml"
    path.write_text(VALLEY.read_text())
    kw = dict(spp=SPP, overrides={"res": 8, "resy": 6, "max_depth": 3}, progress=False, png=False)
    render(path, tmp_path / "a.exr", seed=1, **kw)
    scene = held_scenes()[-1]
    for seed in (2, 3):
        render(path, tmp_path / f"seed{seed}.exr", seed=seed, **kw)
        assert held_scenes()[-1] is scene, "the render loaded the scene again"
    assert scene.integrator().n_recordings == 1, "the repeated renders did not replay"
    # the replayed render's pixels: those of a render that traces (freeze off, another file)
    traced = tmp_path / "traced.xml"
    traced.write_text(
        VALLEY.read_text().replace(
            '<integrator type="fogpath">',
            '<integrator type="fogpath">\n        <boolean name="freeze" value="false"/>',
        )
    )
    render(traced, tmp_path / "traced.exr", seed=3, **kw)
    assert held_scenes()[-1].integrator().n_recordings == 0
    assert np.array_equal(_exr_pixels(tmp_path / "seed3.exr"), _exr_pixels(tmp_path / "traced.exr"))
    # an edited input file: loaded again
    path.write_text(VALLEY.read_text().replace("</scene>", "<!-- edited -->\n</scene>"))
    render(path, tmp_path / "edited.exr", seed=3, **kw)
    assert held_scenes()[-1] is not scene


def test_what_a_caller_sets_on_a_loaded_integrator_does_not_outlive_the_call(mitsuba):
    from fogref.render.load import loaded_scene
    from fogref.scene.parsed import read_scene

    parsed = read_scene(VALLEY, {"res": 8, "resy": 6})
    scene, desc = loaded_scene(parsed)
    fp = scene.integrator()
    aovs, depth = fp.aovs, fp.max_depth
    fp.aovs, fp.max_depth, fp.freeze = not aovs, 1, False
    desc["camera"] = None
    again, desc2 = loaded_scene(read_scene(VALLEY, {"res": 8, "resy": 6}))
    assert again is scene
    assert (fp.aovs, fp.max_depth, fp.freeze) == (aovs, depth, True)
    assert desc2["camera"] is not None
    other, _ = loaded_scene(read_scene(VALLEY, {"res": 8, "resy": 7}))
    assert other is not scene


@pytest.mark.render
def test_mi_render_replays_too(mitsuba):
    """``mi.render`` (fogpath's ``render``: passes of ``render_moments``) goes through the same path."""
    scene = mitsuba.load_file(str(VALLEY), **TINY, parallel=False)
    fp = scene.integrator()
    frozen = [np.array(mitsuba.render(scene, spp=SPP, seed=s)) for s in (1, 2, 3, 4)]
    assert fp.n_recordings == 1
    fp.freeze = False
    for s, a in zip((1, 2, 3, 4), frozen):
        assert np.array_equal(a, np.array(mitsuba.render(scene, spp=SPP, seed=s))), f"seed {s}"


@pytest.mark.render
def test_an_error_of_the_pass_while_recording_is_raised_as_itself(mitsuba, monkeypatch):
    """Not taken for a refusal: the pass's own exception reaches the caller and freezing stays on."""
    import fogref_plugins.fogpath as fpm

    scene = mitsuba.load_file(str(VALLEY), **TINY, parallel=False)
    body = fpm.FogPathIntegrator._pass
    calls = [0]

    def failing_when_recorded(self, *args):
        calls[0] += 1
        if calls[0] == fpm.RECORD_FROM_CALL:
            raise ValueError("the pass failed")
        return body(self, *args)

    monkeypatch.setattr(fpm.FogPathIntegrator, "_pass", failing_when_recorded)
    for seed in range(1, fpm.RECORD_FROM_CALL):
        _sums(scene, seed)
    with pytest.raises(ValueError, match="the pass failed"):
        _sums(scene, 99)
    assert scene.integrator().freeze_refused is None


def _assert_recorded_and_replayed_the_traced_pixels(scene, seeds, frozen, counted):
    """``frozen`` (``_sums`` of ``scene`` at ``seeds``, freeze on) was recorded without a refusal,
    at least one call replayed (Dr.Jit records again when the registry it walks has changed, e.g.
    when a collection freed another test's objects between two calls), and every call's pixels
    are bitwise the traced ones."""
    fp = scene.integrator()
    assert fp.freeze_refused is None, f"the recording was refused: {fp.freeze_refused}"
    assert fp.n_recordings >= 1 and counted[0] < len(seeds), "no pass was replayed"
    for seed, a in zip(seeds, frozen):
        assert np.array_equal(a, _sums(scene, seed, freeze=False)), f"seed {seed}: frozen and traced differ"


@pytest.mark.render
def test_a_stock_volpath_render_with_heightfog_does_not_stop_later_recordings(mitsuba, counted):
    """``dr.freeze`` takes every registered Mitsuba object's variables as inputs of a recording,
    those of other scenes too.  A stock ``volpath`` render through the ``heightfog`` medium must
    leave none of its symbolic loop's variables on the medium, or every later recording in the
    process is refused (``jit_var_schedule(...): not permitted``) and fogpath traces every pass.
    Fails if the recording is refused or if the replays differ from the traced pixels in any bit."""
    import fogref_plugins.fogpath as fpm
    from render_scenes import base_scene, heightfog

    stock = mitsuba.load_dict(
        base_scene(mitsuba, {"type": "volpath", "max_depth": 4}, heightfog(mitsuba), res=(8, 6)),
        parallel=False,
    )
    scene = mitsuba.load_file(str(VALLEY), **TINY, parallel=False)
    seeds = range(1, fpm.RECORD_FROM_CALL + 4)
    frozen = []
    for seed in seeds:
        mitsuba.render(stock, spp=2, seed=seed)  # a stock render between every pass of fogpath
        frozen.append(_sums(scene, seed))
    _assert_recorded_and_replayed_the_traced_pixels(scene, seeds, frozen, counted)


@pytest.mark.render
def test_a_droplet_fogs_tabulated_phase_is_recorded_and_replays_the_traced_pixels(mitsuba, counted):
    """A droplet fog's Mie phase is a table that fogpath interpolates (``DrJitOps.interp``).  An
    array made from host data inside a recording is one Dr.Jit refuses, so the tables are made
    before it and passed in as inputs.  Fails if the recording is refused, if the pass body runs on
    a replay, or if a replay differs from the traced pixels in any bit."""
    import fogref_plugins.fogpath as fpm
    from render_scenes import base_scene, heightfog

    from fogref.mapping.droplet_fog import droplet_fog

    table = droplet_fog(None, "radiation").phase
    fog = heightfog(mitsuba, phase=table.as_params(), g=table.mean_cosine)
    scene = mitsuba.load_dict(
        base_scene(mitsuba, {"type": "fogpath", "max_depth": 4}, fog, res=(8, 6)), parallel=False
    )
    seeds = range(1, fpm.RECORD_FROM_CALL + 4)
    frozen = [_sums(scene, seed) for seed in seeds]
    _assert_recorded_and_replayed_the_traced_pixels(scene, seeds, frozen, counted)
    assert not np.array_equal(frozen[-1], frozen[-2]), "a new seed did not change the pixels"
