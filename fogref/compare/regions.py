"""The regions of a truth's image that :func:`fogref.compare.check.check` scores separately.

``all``, ``surface`` (pixels that see a surface), ``sky``, and distance bands of the
surface pixels: ``d<100m``, ``d100-1000m``, ``d>1000m`` for the default band edges
``(100, 1000)`` [m].
"""

from __future__ import annotations

import math

import numpy as np

from fogref.errors import FogrefError
from fogref.gbuffer import Truth


def _band_name(lo: float, hi: float) -> str:
    if lo <= 0:
        return f"d<{hi:g}m"
    if math.isinf(hi):
        return f"d>{lo:g}m"
    return f"d{lo:g}-{hi:g}m"


def region_masks(truth: Truth, distance_bands=(100.0, 1000.0)) -> dict:
    """Region name -> ``(H, W)`` bool mask: ``all``, ``surface``, ``sky`` and one per distance band.

    ``distance_bands``: increasing band edges [m], each > 0; the bands split the
    surface pixels at them (``(100, 1000)`` gives ``d<100m``, ``d100-1000m``, ``d>1000m``).

    Examples
    --------
    >>> from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams
    >>> from fogref.compare.synthetic import synthetic_truth
    >>> truth = synthetic_truth(UE4ExponentialHeightFog(UE4FogParams()))
    >>> list(region_masks(truth))
    ['all', 'surface', 'sky', 'd<100m', 'd100-1000m', 'd>1000m']
    """
    edges = [float(e) for e in (distance_bands or ())]
    if any(not (math.isfinite(e) and e > 0) for e in edges) or edges != sorted(set(edges)):
        raise FogrefError(f"distance_bands: {list(distance_bands)} must be increasing, finite and > 0 m")
    out = {"all": np.ones(truth.shape, bool), "surface": truth.hit, "sky": truth.sky}
    if edges:
        bounds = [0.0, *edges, math.inf]
        for lo, hi in zip(bounds[:-1], bounds[1:]):
            out[_band_name(lo, hi)] = truth.hit & (truth.distance >= lo) & (truth.distance < hi)
    return out
