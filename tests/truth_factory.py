"""Synthetic ground truths (the current schema) for compare/study tests (no renders).

``truth_channels`` builds every channel of :func:`fogref.gbuffer.exr_channel_names`
from a few parts, so the file or :class:`~fogref.gbuffer.Truth` is exactly what
``fogref render`` writes (same names, same identities), and tests stay fast.
"""

from __future__ import annotations

import numpy as np

from fogref.exrio import write_exr
from fogref.gbuffer import (
    GROUPS,
    SCHEMA_VERSION,
    channel_names,
    correlation_names,
    stderr_names,
    truth_from_channels,
)


def truth_channels(
    *,
    T,
    surface,
    inscatter,
    distance,
    position,
    view,
    hit,
    coverage=None,
    single=None,
    multiple=None,
    rel_stderr: float = 0.0,
    stderr=None,
    corr: float = 1.0,
) -> dict:
    """Every channel of a truth, ``(H, W)`` float64 each.

    ``T, surface, inscatter``: ``(H, W, 3)``; ``attenuated_surface = T * surface``
    and ``final = attenuated_surface + inscatter`` exactly.  ``coverage``: ``(H, W)``
    (default 1 where ``T > 0``, else 0; ``surface`` is written as 0 where it is 0).
    ``single``/``multiple``: default 0.7/0.3 of ``inscatter``.  ``stderr``: part ->
    array; the others default to ``rel_stderr * |part|`` (``T``: 0, pixel-exact).
    ``corr``: the correlation of every part's channels' noise (``corr.*``), in [-1, 1].
    """
    T, surface, inscatter = (np.asarray(a, dtype=np.float64) for a in (T, surface, inscatter))
    if coverage is None:
        coverage = (T.max(-1) > 0).astype(np.float64)
    surface = np.where(coverage[..., None] > 0, surface, 0.0)
    att = T * surface
    parts = {
        "final": att + inscatter,
        "T": T,
        "attenuated_surface": att,
        "inscatter": inscatter,
        "single": 0.7 * inscatter if single is None else single,
        "multiple": 0.3 * inscatter if multiple is None else multiple,
        "surface": surface,
    }
    ch = {}
    for name, a in parts.items():
        for i, c in enumerate(channel_names(name)):
            ch[c] = a[..., i]
        se = (stderr or {}).get(name)
        if se is None:
            se = np.zeros_like(a) if name == "T" else rel_stderr * np.abs(a)
        se = np.broadcast_to(np.asarray(se, dtype=np.float64), a.shape)
        for i, c in enumerate(stderr_names(name)):
            ch[c] = se[..., i]
        for c in correlation_names(name):
            ch[c] = np.full(a.shape[:-1], float(corr))
    ch["surface_coverage"] = np.asarray(coverage, dtype=np.float64)
    ch["distance"] = np.asarray(distance, dtype=np.float64)
    ch["hit"] = np.asarray(hit, dtype=np.float64)
    for i, c in enumerate(channel_names("P")):
        ch[c] = position[..., i]
    for i, c in enumerate(channel_names("view")):
        ch[c] = view[..., i]
    return ch


def truth_attrs(
    params: dict,
    *,
    spp: int = 16,
    seed: int = 0,
    scene: str = "scenes/synthetic.xml",
    scene_sha256: str = "0" * 64,
    overrides: dict | None = None,
    pixel_filter: str = "centre",
) -> dict:
    """Header attributes of a truth (non-string values are JSON in the file)."""
    return {
        "fogref.schema": str(SCHEMA_VERSION),
        "fogref.params": params,
        "fogref.spp": str(spp),
        "fogref.seed": str(seed),
        "fogref.scene": scene,
        "fogref.scene_sha256": scene_sha256,
        "fogref.overrides": overrides or {},
        "fogref.pixel_filter": pixel_filter,
        "fogref.variant": "llvm_ad_rgb",
        "fogref.version": "test",
        "fogref.mitsuba": "test",
    }


def as_truth(channels: dict, attrs: dict, source: str = "<synthetic>"):
    """The :class:`~fogref.gbuffer.Truth` that ``load_truth`` would return (float32 storage)."""
    f32 = {k: np.asarray(v, dtype=np.float32) for k, v in channels.items()}
    return truth_from_channels(f32, attrs, source)


_FIELDS = {"T": "transmittance", "P": "position", "hit": "hit_fraction"}


def write_truth_exr(truth, path):
    """A Truth as a schema-2 ground-truth EXR (every channel, stderr and header attribute)."""
    ch = {}
    for g in GROUPS:
        a = getattr(truth, _FIELDS.get(g.name, g.name))
        for i, c in enumerate(channel_names(g.name)):
            ch[c] = a[..., i] if a.ndim == 3 else a
        if g.noisy:
            se = truth.stderr["transmittance" if g.name == "T" else g.name]
            for i, c in enumerate(stderr_names(g.name)):
                ch[c] = se[..., i]
    write_exr(path, ch, truth.attrs)
    return path


def write_rgb(path, img):
    """An ``(H, W, 3)`` image as an RGB EXR (an engine's image written outside fogref)."""
    write_exr(path, {c: img[..., i] for i, c in enumerate("RGB")})
    return path


def synthetic_truth_exr(path, model, shape=(36, 64), noise: float = 0.02, seed: int = 7):
    """:func:`fogref.compare.synthetic.synthetic_truth` of ``model`` written to ``path``; returns the
    path and the model's exact ``{"T", "inscatter"}`` on it
    (:func:`~fogref.compare.candidate.evaluate_model`)."""
    from fogref.compare.candidate import evaluate_model
    from fogref.compare.synthetic import synthetic_truth

    truth = synthetic_truth(model, shape=shape, noise=noise, seed=seed)
    return write_truth_exr(truth, path), evaluate_model(truth, model)
