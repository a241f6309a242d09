"""The one model builder: a model instance from a name (or class), ``--param`` values and the truth's scene.

``fogref compare --model/--param/--from-scene``, the sweep's ``[[models]]`` tables,
``fogref.build_model`` and the Python API all call :func:`build_model`.  The class
comes from the one resolver, :func:`fogref.models.resolve.resolve_model`; with a
scene, the starting parameters come from :func:`fogref.mapping.from_physical` (the
mapping registry, or the class's own ``from_physical(physical)`` classmethod) and
``params`` override them by name.  A model's parameters are a dataclass
``cls.Params``; it is built as ``cls(cls.Params(**values))`` and keeps them as
``model.params``.
"""

from __future__ import annotations

import dataclasses
import inspect
import json
from typing import Any

from fogref.errors import FogrefError, ParameterError, did_you_mean
from fogref.mapping.physical import PhysicalScene
from fogref.mapping.registry import from_physical, has_mapping
from fogref.models.resolve import resolve_model

__all__ = ["build_model", "current_parameters", "parse_param_assignments"]


def parse_param_assignments(assignments: Any) -> dict:
    """``["density=0.02", "color=[1, 0.9, 0.8]", "mode=exp2"]`` -> dict.

    A value is read as JSON when it parses (numbers, lists, booleans, null), else kept
    as a string.  Raises FogrefError for an item without ``=`` or with an empty name.

    Examples
    --------
    >>> parse_param_assignments(["FogDensity=0.02", "mode=exp2"])
    {'FogDensity': 0.02, 'mode': 'exp2'}
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


def model_label(cls: Any) -> str:
    """The name a model class or instance goes by in messages and reports: its registry ``name``,
    else its class name.

    Examples
    --------
    >>> from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams
    >>> model_label(UE4ExponentialHeightFog), model_label(dict)
    ('ue4', 'dict')
    >>> model_label(UE4ExponentialHeightFog(UE4FogParams())), model_label(object())
    ('ue4', 'object')
    """
    return str(getattr(cls, "name", None) or getattr(cls, "__name__", type(cls).__name__))


def param_dict(params: Any) -> dict[str, Any]:
    """A model's parameter dataclass as a dict of its constructor fields (name -> value, unchanged).

    Examples
    --------
    >>> from fogref.models.unity_builtin import UnityFogParams
    >>> param_dict(UnityFogParams(fogDensity=0.5))["fogDensity"]
    0.5
    """
    return {f.name: getattr(params, f.name) for f in dataclasses.fields(params) if f.init}


def current_parameters(model: Any) -> dict:
    """The parameters of a model instance as a dict: the fields of its ``params`` dataclass."""
    params = getattr(model, "params", None)
    if params is None or not dataclasses.is_dataclass(params) or isinstance(params, type):
        raise FogrefError(f"model '{model_label(type(model))}' keeps no parameter dataclass in 'params'")
    return param_dict(params)


def _params_class(cls: type, params: dict) -> type:
    params_class = getattr(cls, "Params", None)
    if not (isinstance(params_class, type) and dataclasses.is_dataclass(params_class)):
        raise FogrefError(
            f"model '{model_label(cls)}': cannot set parameters {sorted(params)}: "
            f"it has no parameter dataclass 'Params'"
        )
    names = [f.name for f in dataclasses.fields(params_class) if f.init]
    for key in params:
        if key not in names:
            hint, listing = did_you_mean(key, names), ", ".join(names)
            raise FogrefError(
                f"model '{model_label(cls)}': no parameter '{key}'{hint} (parameters: {listing})"
            )
    return params_class


def _construct(cls: type, params: dict) -> Any:
    params_class = _params_class(cls, params)
    try:
        return cls(params_class(**params))
    except ParameterError:  # names the parameter, its value and its range already
        raise
    except (TypeError, ValueError, KeyError) as e:
        raise FogrefError(f"model '{model_label(cls)}': cannot set parameters {sorted(params)}: {e}") from e


def build_model(model: Any, params: dict | None = None, scene_params: dict | None = None) -> Any:
    """A model instance, set up as ``compare`` does.

    Parameters
    ----------
    model : str, type or object
        A name for :func:`~fogref.models.resolve.resolve_model` (``"ue4"``,
        ``"my_pkg.fog:MyFog"``, an entry point), a model class, or an instance
        (returned as is; ``params`` and ``scene_params`` must then be empty).
    params : dict, optional
        Parameters by name, in the model's own names and units (needs ``cls.Params``;
        an unknown name gets a "did you mean").
    scene_params : dict, optional
        The truth's ``fogref.params``: the model starts from
        :func:`fogref.mapping.from_physical` of that scene, then ``params`` override.

    Without ``params`` and ``scene_params``: ``cls()``.

    Raises
    ------
    FogrefError
        Unknown model, unknown or invalid parameter, no physical mapping for
        ``scene_params``, a class that cannot be built without arguments.

    Examples
    --------
    >>> build_model("ue4", {"FogDensity": 0.02}).params.FogDensity
    0.02
    >>> build_model("ue4", {"FogDensty": 0.02})
    Traceback (most recent call last):
    ...
    fogref.errors.FogrefError: model 'ue4': no parameter 'FogDensty'; did you mean 'FogDensity'? ...
    """
    cls = resolve_model(model) if isinstance(model, str) else model
    params = dict(params or {})
    if not inspect.isclass(cls):
        if params or scene_params is not None:
            raise FogrefError(
                f"model '{model}' names an instance, not a class: it cannot take parameters or --from-scene"
            )
        return cls
    if scene_params is None:
        if params:
            return _construct(cls, params)
        try:
            return cls()
        except TypeError as e:
            raise FogrefError(
                f"model '{model_label(cls)}': {cls.__name__}() needs arguments ({e}); give --param "
                "KEY=VALUE (with a Params dataclass) or --from-scene (with from_physical)"
            ) from e
    if not has_mapping(cls):
        raise FogrefError(
            f"model '{model_label(cls)}' has no physical mapping (fogref.mapping) and no "
            f"from_physical(physical) classmethod, so --from-scene cannot derive its parameters; "
            f"set them with --param KEY=VALUE instead"
        )
    built = from_physical(cls, PhysicalScene.from_params(scene_params))
    if not params:
        return built
    if dataclasses.is_dataclass(getattr(cls, "Params", None)):
        _params_class(cls, params)  # an unknown name: "did you mean" before the merge
    merged = current_parameters(built)
    merged.update(params)
    return _construct(cls, merged)
