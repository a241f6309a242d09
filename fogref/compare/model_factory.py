"""Build a game fog model for a comparison: by name, from ``KEY=VALUE`` settings or
from the ground truth's physical fog.

Model classes come from the registry (``fogref.models.get``) and follow
:class:`fogref.models.base.FogModel`.  One way to construct a model:
``cls(cls.Params(**values))`` (a model's parameters are a dataclass, ``cls.Params``;
its instances keep them as ``model.params``).  ``--from-scene`` asks
:func:`fogref.mapping.from_physical` (the mapping registry, or the class's own
``from_physical(physical)`` classmethod for a model without a registered mapping)
and applies ``KEY=VALUE`` on top of the parameters it chose.
"""

from __future__ import annotations

import dataclasses
import json

from fogref.errors import FogrefError


def model_class(name: str) -> type:
    """The registered model class called ``name`` (e.g. ``"ue4"``); FogrefError if unknown."""
    from fogref.models import get

    try:
        return get(name)
    except KeyError as e:
        raise FogrefError(str(e.args[0]) if e.args else f"unknown fog model '{name}'") from None


def parse_param_assignments(assignments) -> dict:
    """``["density=0.02", "color=[1, 0.9, 0.8]", "mode=exp2"]`` -> dict.

    A value is read as JSON when it parses (numbers, lists, booleans, null), else kept
    as a string.  Raises FogrefError for an item without ``=`` or with an empty name.
    """
    out: dict = {}
    for item in assignments or ():
        key, sep, value = str(item).partition("=")
        key = key.strip()
        if not sep or not key:
            raise FogrefError(f"--param expects KEY=VALUE, got '{item}'")
        try:
            out[key] = json.loads(value)
        except ValueError:
            out[key] = value
    return out


def _params_class(cls: type, params: dict) -> type:
    params_class = getattr(cls, "Params", None)
    if not (isinstance(params_class, type) and dataclasses.is_dataclass(params_class)):
        raise FogrefError(f"model '{getattr(cls, 'name', cls.__name__)}': cannot set parameters {sorted(params)}: "
                          f"it has no parameter dataclass 'Params'")
    return params_class


def current_parameters(model) -> dict:
    """The parameters of a model instance as a dict: the fields of its ``params`` dataclass."""
    params = getattr(model, "params", None)
    if params is None or not dataclasses.is_dataclass(params) or isinstance(params, type):
        raise FogrefError(f"model '{getattr(model, 'name', type(model).__name__)}' keeps no parameter "
                          f"dataclass in 'params'")
    return {f.name: getattr(params, f.name) for f in dataclasses.fields(params) if f.init}


def _construct(cls: type, params: dict):
    name = getattr(cls, "name", cls.__name__)
    params_class = _params_class(cls, params)
    try:
        return cls(params_class(**params))
    except (TypeError, ValueError, KeyError) as e:
        raise FogrefError(f"model '{name}': cannot set parameters {sorted(params)}: {e}") from e


def build_model(cls: type, params: dict | None = None, scene_params: dict | None = None):
    """An instance of ``cls``.

    ``scene_params`` (the EXR's ``fogref.params``) given: the model that stands for
    its physical scene (:func:`fogref.mapping.from_physical`), then ``params``
    override its parameters by name.  Otherwise ``cls(cls.Params(**params))``
    (``{}`` gives the defaults).
    """
    params = dict(params or {})
    if scene_params is None:
        return _construct(cls, params)
    from fogref.mapping import PhysicalScene, from_physical, has_mapping

    if not has_mapping(cls):
        raise FogrefError(
            f"model '{getattr(cls, 'name', cls.__name__)}' has no physical mapping (fogref.mapping) and no "
            f"from_physical(physical) classmethod, so --from-scene cannot derive its parameters; "
            f"set them with --param KEY=VALUE instead")
    model = from_physical(cls, PhysicalScene.from_params(scene_params))
    if not params:
        return model
    merged = current_parameters(model)
    merged.update(params)
    return _construct(cls, merged)
