"""``from_physical``: the game fog model that stands for a physical scene.

The registry maps a model name (``fogref.models`` registry names: "ue4",
"unity", ...) to a mapping function ``f(physical: PhysicalScene) -> model``.
A model class that is not registered here may carry its own
``from_physical(physical)`` classmethod (user-supplied models); that is the
fallback.
"""

from __future__ import annotations

from typing import Any, Callable

from fogref.errors import FogrefError
from fogref.mapping.physical import PhysicalScene
from fogref.models.resolve import resolve_model

__all__ = ["MAPPINGS", "from_physical", "has_mapping", "register_mapping"]

#: model name -> ``f(PhysicalScene) -> model instance``.
MAPPINGS: dict[str, Callable] = {}


def register_mapping(name: str) -> Any:
    """Decorator: ``f(physical)`` builds the model registered as ``name`` from a scene.

    Examples
    --------
    >>> @register_mapping("doc_model")
    ... def doc_from_physical(ps):
    ...     return ("doc model", ps.camera)
    >>> MAPPINGS.pop("doc_model") is doc_from_physical
    True
    """

    def deco(fn: Any) -> Any:
        MAPPINGS[name] = fn
        return fn

    return deco


def _name_and_class(model: Any) -> tuple[str | None, type | None]:
    if isinstance(model, str):
        cls = resolve_model(model)
        return getattr(cls, "name", None), cls
    return getattr(model, "name", None), model


def has_mapping(model: Any) -> bool:
    """Whether :func:`from_physical` can build ``model`` (a registry name or class).

    Examples
    --------
    >>> has_mapping("ue4"), has_mapping(object)
    (True, False)
    """
    name, cls = _name_and_class(model)
    return name in MAPPINGS or callable(getattr(cls, "from_physical", None))


def from_physical(model: Any, physical: Any) -> object:
    """The model instance that best represents a physical scene.

    Parameters
    ----------
    model : str or type
        A name for :func:`fogref.models.resolve.resolve_model` (the built-in "ue4",
        "unity", "altitude", "box", "hdrp", "filament", ``module.path:Class``, an
        entry point) or a model class.  A class whose name has no
        registered mapping must have a ``from_physical(physical)`` classmethod.
    physical : PhysicalScene or dict
        The scene; a dict is an EXR's ``fogref.params`` and is parsed with
        :meth:`PhysicalScene.from_params`.

    Returns
    -------
    object
        A model following :class:`fogref.models.base.FogModel`.

    Raises
    ------
    fogref.errors.ParameterError
        The scene has no counterpart in the model (naming 'profile', 'sigma_t', ...).
    fogref.errors.FogrefError
        Unknown model name, or a class with neither a mapping nor ``from_physical``.

    Examples
    --------
    >>> from fogref.media import ExpLayer, FogMedium
    >>> ps = PhysicalScene(FogMedium(sigma_t=0.01, albedo=0.5, layers=(ExpLayer(1.0, 0.0, 0.0),)),
    ...                    sky_radiance=1.0)
    >>> fog = from_physical("unity", ps)
    >>> fog.params.fogDensity, fog.params.fogColor
    (0.01, (0.5, 0.5, 0.5))
    """
    name, cls = _name_and_class(model)
    if isinstance(physical, dict):
        physical = PhysicalScene.from_params(physical)
    fn = MAPPINGS.get(name) if name is not None else None
    if fn is not None:
        return fn(physical)
    own = getattr(cls, "from_physical", None)
    if callable(own):
        return own(physical)
    raise FogrefError(
        f"model '{name or cls}' has no physical mapping (fogref.mapping) and no "
        f"from_physical(physical) classmethod"
    )
