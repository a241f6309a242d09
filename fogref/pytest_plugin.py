"""fogref's pytest plugin: a cached tiny ground truth and an assertion for a fog model.

Installed with fogref (entry point ``pytest11``), so any project that depends on
fogref has it::

    def test_my_fog(fogref_truth):
        truth = fogref_truth("valley", res=(32, 18), spp=64)  # a shipped scene, or a path
        assert_fog_matches(truth, MyFog(...), tolerances={"inscatter": 0.05})

* fixture ``fogref_truth``: a factory ``(scene, res=(32, 18), spp=16, seed=0,
  overrides=None) -> Truth``.  The truth is rendered on first use and cached (see
  :mod:`fogref.render.cache`) under ``$FOGREF_CACHE`` if set, else in
  pytest's cache folder (``.pytest_cache/d/fogref_truths``), else (pytest's cache
  provider off) in ``~/.cache/fogref/truths``.  The cache key covers the
  scene and every file it loads (meshes, envmaps, textures, included XML:
  :func:`fogref.scene.inputs.inputs_digest`), so an edited mesh means a fresh render.
  A relative scene path is looked up in the working directory, then under pytest's
  root directory; a bare name (``"valley"``) is a shipped scene (:func:`fogref.scene_path`).
* :func:`assert_fog_matches` (re-exported from :mod:`fogref.compare.check`): runs
  ``check`` and fails with the part, region, estimate, interval, tolerance,
  confidence and the folder of the error maps.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from fogref.compare.check import assert_fog_matches, check

__all__ = ["assert_fog_matches", "check", "fogref_truth"]


@pytest.fixture(scope="session")
def fogref_truth(request):
    """Factory ``(scene, res=(32, 18), spp=16, seed=0, overrides=None, **render_options) -> Truth``
    (cached)."""
    # here, not at module level: pytest loads this plugin in every session of a project that
    # installs fogref; the renderer is imported only by a test that asks for a truth
    from fogref.render.cache import cached_truth

    env = os.environ.get("FOGREF_CACHE")
    if env:
        cache = Path(env)
    elif getattr(request.config, "cache", None) is not None:
        cache = request.config.cache.mkdir("fogref_truths")
    else:  # pytest's cache provider is off (-p no:cacheprovider): fogref's own cache folder
        from fogref.render.cache import default_cache_dir

        cache = default_cache_dir()
    root = Path(request.config.rootpath)

    def make(scene, res=(32, 18), spp: int = 16, seed: int = 0, overrides=None, **render_options):
        path = Path(scene)
        if not path.is_absolute() and not path.exists() and (root / path).exists():
            path = root / path
        return cached_truth(
            path, res=res, spp=spp, seed=seed, overrides=overrides, cache_dir=cache, **render_options
        )

    return make
