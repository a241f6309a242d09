"""fogpath's host-side cuts keep the pixels: scene values read once per render, loops traced once.

Reading an evaluated Dr.Jit value from Python (``str`` of an emitter, ``float`` of the sun's
transform) waits on the device; fogpath used to read them at every call site while tracing
(the sky ten times, the sun three times per pass on the valley).  ``render_moments`` now keeps
what it read for the call (``FogPathIntegrator._read_once``).

* the reads happen once each per ``render_moments`` call, and nothing is kept after it (a
  later render of another scene reads its own values): fails if a call site reads past the
  memo, or if the memo outlives the call;
* the pixels are bitwise those of reading at every call site, at two sun elevations: fails on
  any value the memo changes or mixes up between scenes;
* the pixels are bitwise those of Dr.Jit's ``OptimizeLoops`` on (every symbolic loop body traced
  twice, loop-invariant state dropped), which ``render_moments`` turns off while it traces
  (``OPTIMIZE_LOOPS``): fails on any pixel the unoptimised loops change.
"""

from collections import Counter
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.render

VALLEY = str(Path(__file__).resolve().parents[1] / "scenes" / "valley.xml")
TINY = {"res": "8", "resy": "6"}
READS = ("_read_scene_sun", "_read_constant_sky", "_read_sky_selection", "_read_sky_residual")


def _sums(scene, seed=3):
    sums, squares = scene.integrator().render_moments(scene, seed=seed, spp=2)
    return np.concatenate([np.array(sums).ravel(), np.array(squares).ravel()])


def test_scene_values_are_read_once_per_render(mitsuba, monkeypatch):
    import fogref_plugins.fogpath as common

    calls: Counter = Counter()
    for name in READS:
        read = getattr(common.FogPathIntegrator, name)

        def counted(*args, _read=read, _name=name):
            calls[_name] += 1
            return _read(*args)

        static = isinstance(common.FogPathIntegrator.__dict__[name], staticmethod)
        monkeypatch.setattr(common.FogPathIntegrator, name, staticmethod(counted) if static else counted)
    for sun in ("20", "40"):
        calls.clear()
        scene = mitsuba.load_file(VALLEY, **TINY, sun_elevation=sun, parallel=False)
        _sums(scene)
        assert calls == Counter({name: 1 for name in READS}), dict(calls)
        assert scene.integrator()._memo is None, "the values read outlive the render"


def test_reading_once_keeps_the_pixels(mitsuba, monkeypatch):
    import fogref_plugins.fogpath as common

    scenes = {
        sun: mitsuba.load_file(VALLEY, **TINY, sun_elevation=sun, parallel=False) for sun in ("20", "40")
    }
    once = {sun: _sums(s) for sun, s in scenes.items()}
    monkeypatch.setattr(common.FogPathIntegrator, "_read_once", lambda self, scene, name, read: read())
    every = {sun: _sums(s) for sun, s in scenes.items()}
    for sun in scenes:
        assert np.array_equal(once[sun], every[sun]), f"sun elevation {sun}: pixels changed"
    assert not np.array_equal(once["20"], once["40"]), "the sun's elevation did not change the render"


def test_loops_traced_once_keep_the_pixels(mitsuba, monkeypatch):
    import fogref_plugins.fogpath as common

    assert common.OPTIMIZE_LOOPS is False
    scene = mitsuba.load_file(VALLEY, **TINY, sun_elevation="30", parallel=False)
    once = _sums(scene, seed=4)
    monkeypatch.setattr(common, "OPTIMIZE_LOOPS", True)
    twice = _sums(scene, seed=4)
    assert np.array_equal(once, twice), "OptimizeLoops changed the pixels"
