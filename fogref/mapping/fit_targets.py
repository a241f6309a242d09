"""What a fit aims at: the physical fog's closed-form inscatter and transmittance on a set of
views, for one or several sun elevations (the targets of :func:`fogref.mapping.fit.fit_model`
and :func:`fogref.mapping.translate.translate`).

Examples
--------
>>> from fogref.media import ExpLayer, FogMedium
>>> ps = PhysicalScene(FogMedium(sigma_t=0.01, layers=(ExpLayer(1.0, 0.0, 0.0),)), (1.0, 1.0, 0.0), 1.0)
>>> round(sun_elevation(with_sun_elevation(ps, 30.0)), 6)
30.0
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Iterable

import numpy as np

from fogref.mapping.physical import PhysicalScene
from fogref.mapping.unreal import Views, physical_single_scattering
from fogref.media import NP
from fogref.params import number

__all__ = ["Target", "physical_targets", "sun_elevation", "with_sun_elevation"]


def sun_elevation(pf: PhysicalScene) -> float:
    """The scene's sun elevation above the horizon [degrees], in [-90, 90].

    Examples
    --------
    >>> from fogref.media import FogMedium
    >>> round(sun_elevation(PhysicalScene(FogMedium(), (1.0, 1.0, 0.0), 1.0)), 6)
    45.0
    """
    return math.degrees(math.asin(max(-1.0, min(1.0, pf.sun_direction[1]))))


def with_sun_elevation(pf: PhysicalScene, elevation_deg: float) -> PhysicalScene:
    """``pf`` with the sun at ``elevation_deg`` [degrees, -90..90], same azimuth (north +z if
    the scene's sun is at the zenith).  ParameterError naming 'sun_elevation' outside the range."""
    e = number(elevation_deg, "sun_elevation", source=pf.source, lo=-90.0, hi=90.0, unit="deg")
    w = np.asarray(pf.sun_direction, dtype=float)
    h = math.hypot(w[0], w[2])
    ax, az = (w[0] / h, w[2] / h) if h > 1e-12 else (0.0, 1.0)
    c, s = math.cos(math.radians(e)), math.sin(math.radians(e))
    return replace(pf, sun_direction=(c * ax, s, c * az))


@dataclass
class Target:
    """The physical fog on a set of views: inscatter ``L`` and transmittance ``T`` (N, 3)."""

    scene: PhysicalScene
    views: Views
    L: np.ndarray
    T: np.ndarray


def physical_targets(
    pf: PhysicalScene, views: Views, elevations: Iterable[float] | None = None
) -> list[Target]:
    """One :class:`Target` per sun elevation (default: the scene's own sun)."""
    scenes = [pf] if elevations is None else [with_sun_elevation(pf, e) for e in elevations]
    out = []
    for ps in scenes:
        L = physical_single_scattering(ps, views)
        o = tuple(np.full(len(views.D), c) for c in views.camera)
        d = tuple(views.d[:, i] for i in range(3))
        D = np.where(views.sky, NP.largest, views.D)
        T = np.stack(ps.medium.transmittance(NP, o, d, D), axis=-1)
        out.append(Target(ps, views, np.asarray(L, float), np.asarray(T, float)))
    return out
