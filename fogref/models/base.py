"""The fog-model protocol, what every model returns, and the model registry.

Conventions: inputs are in fogref's world frame, **y-up, metres** (a model that
works in engine units, e.g. Unreal's z-up centimetres, converts internally).
``camera``: shape (3,); ``positions``: shape (..., 3), the shaded point of each
pixel (for pixels that see the sky, ``camera + view_dir * SKY_DISTANCE``).
Colours are linear RGB in the scene's radiance units.  A model composites as the
engine does: ``final = scene * transmittance + inscatter``.

A model is a port of an engine's shader: it depends on numpy and
:mod:`fogref.media` only.  Which model parameters stand for a physical scene is
the business of :mod:`fogref.mapping`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, ClassVar, Generic, Protocol, TypeVar, runtime_checkable

import numpy as np

__all__ = ["BUILTIN_MODELS", "SKY_DISTANCE", "FogModel", "FogResult", "ParamModel", "as_points", "register"]

#: Where a model fogs the pixels that see the sky [m] (compare, the fits and the
#: study all use it): far enough that every fog of the scenes is saturated.
SKY_DISTANCE = 1.0e5


@dataclass
class FogResult:
    """What a fog model returns for each pixel.

    Attributes
    ----------
    inscatter : ndarray, shape (..., 3)
        RGB radiance added by the fog (scene radiance units, >= 0).
    transmittance : ndarray, shape (..., 3)
        RGB transmittance from the camera to the point, in [0, 1].

    Examples
    --------
    >>> r = FogResult(inscatter=np.full((1, 3), 0.2), transmittance=np.full((1, 3), 0.5))
    >>> r.composite(np.ones((1, 3)))
    array([[0.7, 0.7, 0.7]])
    """

    inscatter: np.ndarray
    transmittance: np.ndarray

    def composite(self, scene_rgb: np.ndarray) -> np.ndarray:
        """The engine's compositing rule: ``scene * T + inscatter`` (RGB radiance)."""
        return scene_rgb * self.transmittance + self.inscatter


@runtime_checkable
class FogModel(Protocol):
    """The protocol every fog model follows (built-in or user-supplied).

    Attributes
    ----------
    name : str
        The registry name (``fogref.models.get(name)`` finds the class).
    params : dataclass
        The model's parameters in the engine's own names and units; the model is
        built as ``Model(params)`` (``Model.Params`` is the dataclass).

    Methods
    -------
    evaluate(camera, positions, precision="float32") -> FogResult
        ``camera``: (3,) camera position [m]; ``positions``: (..., 3) shaded
        points [m], y-up.  ``precision``: "float32" mirrors the GPU shader
        (every intermediate rounded to float32), "float64" the same model in
        double precision.  Returns (..., 3) ``inscatter`` and ``transmittance``
        in the precision's dtype.

    Examples
    --------
    >>> from fogref.models import get
    >>> isinstance(get("ue4")(), FogModel)
    True
    """

    name: ClassVar[str]

    def evaluate(self, camera: Any, positions: Any, precision: str = "float32") -> FogResult: ...


P = TypeVar("P")


class ParamModel(Generic[P]):
    """What the built-in models share: ``Model(params)`` keeps ``params``, an instance of the
    class attribute ``Params`` (the engine's settings dataclass); None builds ``Params()``.

    >>> from fogref.models import get
    >>> get("unity")().params.fogMode
    'exp2'
    """

    Params: type[P]

    def __init__(self, params: P | None = None) -> None:
        self.params: P = params or self.Params()


#: The built-in models by name (filled by :func:`register`), read by :mod:`fogref.models.resolve`.
BUILTIN_MODELS: dict[str, type] = {}


def register(name: str) -> Callable[[type], type]:
    """Class decorator: make a model a built-in one, found by name by
    :func:`fogref.models.resolve.resolve_model`.

    Examples
    --------
    >>> @register("doc_fog")
    ... class DocFog:
    ...     def evaluate(self, camera, positions, precision="float32"): ...
    >>> BUILTIN_MODELS["doc_fog"].name
    'doc_fog'
    >>> del BUILTIN_MODELS["doc_fog"]
    """

    def deco(cls: Any) -> Any:
        cls.name = name
        BUILTIN_MODELS[name] = cls
        return cls

    return deco


def as_points(x: Any) -> np.ndarray:
    """``x`` as a float64 array of points, shape (..., 3); ValueError otherwise.

    Examples
    --------
    >>> as_points([1, 2, 3]).dtype
    dtype('float64')
    """
    x = np.asarray(x, dtype=np.float64)
    if x.shape[-1] != 3:
        raise ValueError(f"expected (..., 3) positions, got shape {x.shape}")
    return x
