"""``mi.render`` with fogpath renders in passes, as the driver does.

Each pass holds every sample's outputs in memory, so ``mi.render`` splits the samples
with :func:`fogref_plugins.passes.pass_sizes` under ``MAX_LANES`` (here shrunk so that a
12x8 image needs two passes).  Smallest error detected: any pass missing, counted twice,
mis-seeded or mis-weighted changes the mean by a whole pass's share (~50 %), far above
float32 rounding (1e-6 relative, the tolerance).
"""

import numpy as np
import pytest
from render_scenes import base_scene, heightfog

RES = (12, 8)


def _scene(mi):
    return mi.load_dict(
        base_scene(mi, {"type": "fogpath", "max_depth": 4}, heightfog(mi), res=RES), parallel=False
    )


@pytest.mark.render
def test_one_pass_is_one_render_moments_call(mitsuba):
    mi = mitsuba
    scene = _scene(mi)
    img = np.array(mi.render(scene, spp=4, seed=3))
    sums, squares = scene.integrator().render_moments(scene, seed=3, spp=4, squares=False)
    assert squares is None
    np.testing.assert_allclose(img, np.array(sums) / 4, rtol=1e-6, atol=1e-7)


@pytest.mark.render
def test_mi_render_splits_into_seeded_passes(mitsuba, monkeypatch):
    import fogref_plugins.passes as passes

    mi = mitsuba
    monkeypatch.setattr(passes, "MAX_LANES", {"llvm": RES[0] * RES[1] * 4, "cuda": RES[0] * RES[1] * 4})
    assert passes.pass_sizes(RES[0] * RES[1], 8, passes.max_lanes(mi.variant())) == [4, 4]
    scene = _scene(mi)
    img = np.array(mi.render(scene, spp=8, seed=3))
    integ = scene.integrator()
    expected = (
        sum(np.array(integ.render_moments(scene, seed=passes.pass_seed(3, k), spp=4)[0]) for k in range(2))
        / 8
    )
    np.testing.assert_allclose(img, expected, rtol=1e-6, atol=1e-7)
    one_pass = np.array(integ.render_moments(scene, seed=3, spp=8)[0]) / 8
    assert not np.allclose(img, one_pass), "the two passes were not seeded apart from one 8-spp call"


@pytest.mark.parametrize("value", ["0", "-4", "lots", "1.5e6", str(2**31)])
def test_a_bad_lanes_override_is_refused_naming_the_variable_and_range(monkeypatch, value):
    from fogref_plugins.passes import max_lanes

    from fogref.errors import FogrefError

    monkeypatch.setenv("FOGREF_MAX_LANES", value)
    with pytest.raises(FogrefError, match=rf"FOGREF_MAX_LANES='{value}': .* from 1 to 2147483647"):
        max_lanes("cuda_ad_rgb")


@pytest.mark.render
def test_the_lanes_override_sets_the_split_of_a_truth(tmp_path, mitsuba, monkeypatch):
    """``FOGREF_MAX_LANES`` (a GPU with less memory) splits the driver's passes as ``mi.render``'s:
    at 8x6 pixels, 96 lanes are passes of 2 spp."""
    import tiny_inputs_scene as tiny
    from fogref_plugins.passes import max_lanes

    from fogref.exrio import read_exr
    from fogref.render.render import render

    monkeypatch.delenv("FOGREF_MAX_LANES", raising=False)
    assert max_lanes("cuda_ad_rgb") == 1 << 25 and max_lanes("llvm_ad_rgb") == 1 << 18  # unset
    monkeypatch.setenv("FOGREF_MAX_LANES", " 96 ")
    scene = tiny.make(mitsuba, tmp_path / "scene")
    out = render(scene, tmp_path / "x.exr", spp=6, seed=1, progress=False, png=False)
    assert read_exr(out)[1]["fogref.passes"] == [2, 2, 2]


@pytest.mark.render
def test_a_pass_out_of_device_memory_says_which_lanes_to_try(tmp_path, mitsuba, monkeypatch):
    """Dr.Jit's allocator failing in a pass (its message, raised from inside a loop as Dr.Jit
    re-raises it) is one line naming the pass's lanes and the override to set, not a traceback;
    the pass before it is checkpointed."""
    import tiny_inputs_scene as tiny
    from fogref_plugins.fogpath import FogPathIntegrator

    from fogref.errors import FogrefError
    from fogref.render.render import render

    monkeypatch.setenv("FOGREF_MAX_LANES", "96")
    real, calls = FogPathIntegrator.render_moments, []

    def second_pass_runs_out(self, *a, **kw):
        calls.append(1)
        if len(calls) < 2:
            return real(self, *a, **kw)
        try:
            raise RuntimeError(
                "jit_malloc(): out of memory! Could not allocate 6710886400 bytes of device memory."
            )
        except RuntimeError as oom:
            raise RuntimeError("dr.while_loop(): encountered an exception.") from oom

    monkeypatch.setattr(FogPathIntegrator, "render_moments", second_pass_runs_out)
    scene = tiny.make(mitsuba, tmp_path / "scene")
    with pytest.raises(FogrefError) as e:
        render(scene, tmp_path / "x.exr", spp=6, seed=1, progress=False, png=False, checkpoint_seconds=1e9)
    msg = str(e.value)
    assert "\n" not in msg and "a pass of 96 lanes (48 pixels x 2 spp" in msg
    assert "Could not allocate 6710886400 bytes of device memory" in msg and "FOGREF_MAX_LANES=24" in msg
    assert (tmp_path / "x.exr.partial.npz").is_file() and not (tmp_path / "x.exr").exists()
