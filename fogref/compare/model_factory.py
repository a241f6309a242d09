"""Build a game fog model for a comparison: by name, from ``KEY=VALUE`` settings or
from the ground truth's physical fog.

Model classes come from the registry (``fogref.models.get``).  Contract used here:

* ``cls.from_physical(params: dict)`` (classmethod, optional): the model whose
  parameters best represent the physical scene; ``params`` is the EXR's whole
  ``fogref.params`` object (camera, medium, sun, sky).
* ``cls.from_dict(d: dict)`` (classmethod, optional); else, when the class names its
  parameter dataclass as ``cls.Params``, ``cls(cls.Params(**d))``; else ``cls(**d)``:
  the model with parameters set by name.
* ``model.to_dict()`` (optional), else the fields of a dataclass model, else the
  fields of its ``model.params`` dataclass, else ``vars(model)``: the current
  parameters, used to apply ``KEY=VALUE`` on top of ``from_physical``.
"""

from __future__ import annotations

import dataclasses
import importlib
import json

from fogref.errors import FogrefError


def model_class(name: str) -> type:
    """The registered model class called ``name`` (e.g. ``"ue4"``); FogrefError if unknown."""
    pkg = importlib.import_module("fogref.models")
    get = getattr(pkg, "get", None) or importlib.import_module("fogref.models.base").get
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


def current_parameters(model) -> dict:
    """The parameters of a model instance as a dict (``to_dict``, dataclass or ``vars``)."""
    if callable(getattr(model, "to_dict", None)):
        return dict(model.to_dict())
    for obj in (model, getattr(model, "params", None)):
        if obj is not None and dataclasses.is_dataclass(obj) and not isinstance(obj, type):
            return {f.name: getattr(obj, f.name) for f in dataclasses.fields(obj) if f.init}
    return {k: v for k, v in vars(model).items() if not k.startswith("_")}


def _construct(cls: type, params: dict):
    name = getattr(cls, "name", cls.__name__)
    try:
        if callable(getattr(cls, "from_dict", None)):
            return cls.from_dict(dict(params))
        params_class = getattr(cls, "Params", None)
        if isinstance(params_class, type) and dataclasses.is_dataclass(params_class):
            return cls(params_class(**params))
        return cls(**params)
    except (TypeError, ValueError, KeyError) as e:
        raise FogrefError(f"model '{name}': cannot set parameters {sorted(params)}: {e}") from e


def build_model(cls: type, params: dict | None = None, scene_params: dict | None = None):
    """An instance of ``cls``.

    ``scene_params`` (the EXR's ``fogref.params``) given: ``cls.from_physical(scene_params)``,
    then ``params`` override its parameters by name.  Otherwise the model built from
    ``params`` alone (``from_dict`` or the constructor; ``{}`` gives the defaults).
    """
    params = dict(params or {})
    name = getattr(cls, "name", cls.__name__)
    if scene_params is None:
        return _construct(cls, params)
    from_physical = getattr(cls, "from_physical", None)
    if not callable(from_physical):
        raise FogrefError(
            f"model '{name}' has no from_physical(params) classmethod, so --from-scene cannot derive its "
            f"parameters; set them with --param KEY=VALUE instead"
        )
    model = from_physical(scene_params)
    if not params:
        return model
    merged = current_parameters(model)
    merged.update(params)
    return _construct(cls, merged)
