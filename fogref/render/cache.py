"""Render a ground truth once and reuse it: a cache keyed on everything that changes its pixels.

The key holds the digest of the scene file and of every file it loads (meshes,
environment maps, textures, included XML, and the files that ``$default``s and
overrides select: :func:`fogref.scene.inputs.inputs_digest`), the overrides
(``res``, ``resy`` and any ``--set``), the
sample count, the seed, the pixel filter, fogref's version and a hash of the
renderer's source (``fogref/media``, ``fogref/render``, ``fogref/gbuffer.py``, the
plugins), so an edited scene, mesh, envmap or texture, or a changed renderer, never returns a
stale truth.
This is fogref's one render cache: the pytest plugin, ``fogref study`` and
``fogref sweep`` all go through it.

Cache folder: ``cache_dir``, else ``$FOGREF_CACHE``, else ``~/.cache/fogref/truths``.
Each truth is one EXR named by its key; writes are atomic, so parallel test workers
may race, and the last one wins with identical pixels.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import fogref_plugins

import fogref
from fogref import params
from fogref._version import __version__
from fogref.cache_dir import default_cache_dir, sources_digest
from fogref.errors import FogrefError, ParameterError
from fogref.gbuffer import Truth, load_truth
from fogref.render.render import render
from fogref.scene.parsed import ParsedScene, read_scene
from fogref.shipped_scenes import resolve_scene


def _renderer_hash() -> str:
    root = Path(fogref.__file__).resolve().parent
    plugins = Path(fogref_plugins.__file__).resolve().parent  # the plugins this process renders with
    return sources_digest([root / "media", root / "scene", root / "render", root / "gbuffer.py", plugins])


def truth_key(scene, spp: int, seed: int, overrides: dict | None = None, pixel_filter: str = "centre") -> str:
    """The cache key (hex, 24 characters) of a truth; FogrefError if the scene is missing.

    ``scene``: a path (with ``overrides``) or a :class:`~fogref.scene.parsed.ParsedScene`
    (which carries its overrides).

    Examples
    --------
    >>> k = truth_key("scenes/valley.xml", 16, 0, {"res": 32, "resy": 18})
    >>> len(k), k == truth_key("scenes/valley.xml", 16, 1, {"res": 32, "resy": 18})
    (24, False)
    """
    parsed = scene if isinstance(scene, ParsedScene) else read_scene(scene, overrides)
    spec = {
        "inputs": parsed.digest,
        "spp": int(spp),
        "seed": int(seed),
        "pixel_filter": pixel_filter,
        "overrides": {str(k): str(v) for k, v in sorted(parsed.overrides.items())},
        "version": __version__,
        "renderer": _renderer_hash(),
    }
    return hashlib.sha256(json.dumps(spec, sort_keys=True).encode()).hexdigest()[:24]


def truth_path(
    scene, spp: int, seed: int, overrides: dict | None = None, cache_dir=None, pixel_filter: str = "centre"
) -> Path:
    """Where the cache keeps the truth of these inputs: ``<cache>/<scene stem>-<key>.exr``."""
    folder = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    stem = (scene.path if isinstance(scene, ParsedScene) else Path(scene)).stem
    return folder / f"{stem}-{truth_key(scene, spp, seed, overrides, pixel_filter)}.exr"


def render_cached(
    scene,
    spp: int = 16,
    seed: int = 0,
    overrides: dict | None = None,
    cache_dir=None,
    variant: str | None = None,
    pixel_filter: str = "centre",
) -> tuple[Truth, bool]:
    """The cached truth, rendered first if needed, read once: ``(truth, was_cached)``;
    ``truth.path`` is the cached EXR.

    Parameters as :func:`cached_truth` (``overrides`` holds ``res``/``resy`` if wanted).
    A cached file that no longer reads as a truth (older schema, damaged) is rendered again.
    """
    if int(spp) < 1 or int(seed) < 0:
        raise FogrefError(f"spp {spp} must be >= 1 and seed {seed} >= 0")
    parsed = read_scene(scene, overrides)  # once, for the key and the render
    path = truth_path(parsed, spp, seed, None, cache_dir, pixel_filter)
    folder = path.parent
    if path.is_file():
        try:
            return load_truth(path), True
        except FogrefError:
            path.unlink(missing_ok=True)
    folder.mkdir(parents=True, exist_ok=True)
    render(
        parsed,
        path,
        spp=int(spp),
        seed=int(seed),
        variant=variant,
        progress=False,
        resume=False,
        png=False,
        pixel_filter=pixel_filter,
        keep_moments=False,
    )
    return load_truth(path), False


def cached_truth(
    scene,
    res=(32, 18),
    spp: int = 16,
    seed: int = 0,
    overrides: dict | None = None,
    cache_dir=None,
    variant: str | None = None,
    pixel_filter: str = "centre",
):
    """A ground truth of ``scene``, rendered on first use and read from the cache after.

    Parameters
    ----------
    scene : path or str
        A fogref XML scene, or the name of a shipped one (``"valley"``,
        :func:`fogref.shipped_scenes.resolve_scene`).
    res : (int, int) or None
        ``(width, height)`` [px], set as the overrides ``res`` and ``resy``; None keeps the
        scene's own.
    spp : int
        Samples per pixel, >= 1.
    seed : int
        Render seed, >= 0.
    overrides : dict, optional
        More XML ``$name`` defaults (as ``fogref render --set``).
    cache_dir : path, optional
        See the module docstring.
    variant, pixel_filter :
        Passed to :func:`fogref.render.render.render` (the variant is not part of the
        key: it changes only float rounding).

    Returns
    -------
    Truth
        From :func:`fogref.gbuffer.load_truth`; ``truth.path`` is the cached EXR.
    """
    over = dict(overrides or {})
    if res is not None:
        if isinstance(res, (str, bytes)) or not hasattr(res, "__len__") or len(res) != 2:
            raise ParameterError("cached_truth", "res", f"{res!r}: expected (width, height) [px]")
        w, h = (params.integer(x, "res", source="cached_truth", lo=1, hi=1 << 16, unit="px") for x in res)
        over.update({"res": w, "resy": h})
    return render_cached(resolve_scene(scene), spp, seed, over, cache_dir, variant, pixel_filter)[0]
