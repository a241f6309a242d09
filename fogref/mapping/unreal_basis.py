"""Unreal's inscatter as a linear model in its two colours, and the colour solve.

Unreal's Exponential Height Fog adds, per pixel (start distances 0, see
:mod:`fogref.models.ue4`)::

    inscatter = FogInscatteringColor (1 - T) + DirectionalInscatteringColor max(cos, 0)^n (1 - T_dir)

where ``T_dir`` is the transmittance of the part of the ray beyond
DirectionalInscatteringStartDistance.  Given the exponent ``n`` and the start
distance, the model is **linear** in the two colours, so each colour channel is a
2-parameter non-negative least-squares problem (:func:`solve_colours`) on two basis
images (:func:`unreal_basis`: the model evaluated with unit colours, in float64).
Density, falloff and height come from the exact mapping
:func:`fogref.models.ue4.medium_to_ue4` (:func:`base_params`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from fogref.mapping.physical import PhysicalScene
from fogref.mapping.views import Views
from fogref.models.base import SKY_DISTANCE
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams, medium_to_ue4

__all__ = ["Basis", "base_params", "solve_colours", "unreal_basis", "unreal_inscatter"]


def base_params(pf: PhysicalScene, **kw: Any) -> UE4FogParams:
    """Unreal parameters with the exact density/falloff/height of ``pf.medium``, the
    sun direction, and ``kw`` (other fields; start distances default to 0)."""
    defaults: dict[str, Any] = dict(
        DirectionalInscatteringStartDistance=0.0,
        StartDistance=0.0,
        FogMaxOpacity=1.0,
        FogCutoffDistance=0.0,
        SunLuminance=1.0,
    )
    defaults.update(kw)
    p = medium_to_ue4(pf.medium, replace(UE4FogParams(), **defaults))
    return p.with_sun(pf.sun_direction, p.SunLuminance)


def unreal_inscatter(
    params: UE4FogParams, camera: Any, world_pos: Any, precision: str = "float64"
) -> np.ndarray:
    """Unreal's inscatter (N, 3) for the given parameters."""
    fog = UE4ExponentialHeightFog(params)
    return np.asarray(fog.evaluate(camera, world_pos, precision).inscatter, dtype=float)


@dataclass
class Basis:
    """The two basis images of Unreal's inscatter at fixed exponent and start distance."""

    iso: np.ndarray  # (N,) 1 - T
    lobe: np.ndarray  # (N,) max(cos,0)^n (1 - T_dir)


def unreal_basis(
    pf: PhysicalScene, views: Views, exponent: float, start_cm: float, sky_distance: float = SKY_DISTANCE
) -> Basis:
    """Unreal (float64) evaluated with unit colours: the isotropic and lobe images."""
    wp = views.world_positions(sky_distance)
    p = base_params(
        pf,
        DirectionalInscatteringExponent=exponent,
        DirectionalInscatteringStartDistance=start_cm,
        FogInscatteringColor=(1.0, 0.0, 0.0),
        DirectionalInscatteringColor=(0.0, 1.0, 0.0),
    )
    ins = unreal_inscatter(p, np.asarray(pf.camera), wp)
    return Basis(iso=ins[:, 0], lobe=ins[:, 1])


def solve_colours(
    basis: Basis, target: np.ndarray, weights: Any = None
) -> tuple[np.ndarray, np.ndarray, float]:
    """Non-negative least squares per channel: ``target ≈ C_fog iso + C_dir lobe``.

    Returns ``(C_fog (3,), C_dir (3,), sse)`` with ``sse`` the weighted sum of
    squared residuals over all channels.
    """
    from scipy.optimize import nnls

    A = np.stack([basis.iso, basis.lobe], axis=-1)
    sw = np.ones(len(A)) if weights is None else np.sqrt(np.asarray(weights, dtype=float))
    Aw = A * sw[:, None]
    cf, cd, sse = np.zeros(3), np.zeros(3), 0.0
    for c in range(3):
        x, r = nnls(Aw, target[:, c] * sw)
        cf[c], cd[c] = x
        sse += r * r
    return cf, cd, float(sse)
