"""The fit cache (:mod:`fogref.mapping.fit_cache`): Unreal's fit is computed once per scene and
settings, read back from disk by later calls (as a later process would), and recomputed whenever
an input differs or the file is damaged.  Exact: the stored values are the fit's own floats."""

import json
from dataclasses import replace

import pytest

from fogref.mapping import PhysicalScene, fit_unreal
from fogref.mapping import unreal as unreal_mod
from fogref.mapping.fit_cache import fit_cache_dir
from fogref.media import ExpLayer, FogMedium


def scene(g=0.6):
    return PhysicalScene(
        FogMedium(sigma_t=0.002, albedo=0.9, g=g, layers=(ExpLayer(1.0, 0.02, 0.0),)),
        (1.0, 0.3, 0.2),
        (3.0, 3.0, 3.0),
        (0.2, 0.3, 0.5),
    )


def no_fit(*a, **k):
    raise AssertionError("the fit ran instead of being read from the cache")


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("FOGREF_CACHE", str(tmp_path / "truths"))
    return tmp_path / "truths" / "fits"


def test_a_fit_is_read_back_and_recomputed_when_an_input_differs(cache, monkeypatch):
    assert fit_cache_dir() == cache
    first = fit_unreal(scene())
    assert "from_cache" not in first.history
    (entry,) = cache.glob("*.json")
    with monkeypatch.context() as m:
        m.setattr(unreal_mod, "ColourLoss", no_fit)
        again = fit_unreal(scene())
        assert again.history["from_cache"] and again is not first
        assert again.params == first.params
        assert (again.rmse, again.rel_rmse, again.n_views) == (first.rmse, first.rel_rmse, first.n_views)
        for changed in (
            lambda: fit_unreal(scene(g=0.5)),  # another scene
            lambda: fit_unreal(scene(), rtol=1e-2),  # other settings
            lambda: fit_unreal(scene(), fit_start=False),
        ):
            with pytest.raises(AssertionError, match="instead of being read"):
                changed()
        # an entry whose stored inputs differ from the key's (a collision, an edit) is a miss
        d = json.loads(entry.read_text())
        d["inputs"]["scene"]["camera"] = [0.0, 3.0, 0.0]
        entry.write_text(json.dumps(d))
        with pytest.raises(AssertionError, match="instead of being read"):
            fit_unreal(scene())
    entry.write_text("{ damaged")
    redo = fit_unreal(scene())
    assert "from_cache" not in redo.history and redo.params == first.params
    assert json.loads(entry.read_text())["result"]["DirectionalInscatteringExponent"] == (
        first.params.DirectionalInscatteringExponent
    )


def test_an_unwritable_cache_warns_and_still_fits(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("FOGREF_CACHE", str(blocker))
    with pytest.warns(UserWarning, match="fit cache .*not written"):
        r = fit_unreal(replace(scene(), camera=(0.0, 5.0, 0.0)))
    assert r.params.DirectionalInscatteringExponent > 0
