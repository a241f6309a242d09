"""What every game fog model returns, and the registry.

Conventions: inputs are in fogref's world frame, **y-up, metres** (a model that
works in engine units, e.g. Unreal's z-up centimetres, converts internally).
``camera``: shape (3,); ``world_pos``: shape (..., 3), the shaded point of each
pixel (for pixels that see the sky, ``camera + view_dir * sky_distance``).
Colours are linear RGB in the scene's radiance units.  A model composites as the
engine does: ``final = scene * transmittance + inscatter``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class FogResult:
    """inscatter: (..., 3) RGB radiance added by the fog; transmittance: (..., 3)."""

    inscatter: np.ndarray
    transmittance: np.ndarray

    def composite(self, scene_rgb: np.ndarray) -> np.ndarray:
        """The engine's compositing rule: ``scene * T + inscatter``."""
        return scene_rgb * self.transmittance + self.inscatter


_REGISTRY: dict[str, type] = {}


def register(name: str):
    """Class decorator: make a model available as ``fogref.models.get(name)``."""

    def deco(cls):
        cls.name = name
        _REGISTRY[name] = cls
        return cls

    return deco


def get(name: str):
    """The model class registered under ``name`` (e.g. ``"ue4"``)."""
    try:
        return _REGISTRY[name]
    except KeyError:
        raise KeyError(f"unknown fog model '{name}'; known: {sorted(_REGISTRY)}") from None


def available() -> list[str]:
    return sorted(_REGISTRY)


def as_points(x) -> np.ndarray:
    x = np.asarray(x, dtype=np.float64)
    if x.shape[-1] != 3:
        raise ValueError(f"expected (..., 3) positions, got shape {x.shape}")
    return x
