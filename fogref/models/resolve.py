"""The one model resolver: a name -> a fog model class (built-in, ``module:Class`` or an entry point).

Every place that takes a model by name calls :func:`resolve_model` (alias
``fogref.models.get``): ``fogref compare --model``, the sweep TOML's ``[[models]] name``,
:func:`fogref.build_model` and :func:`fogref.mapping.from_physical`.  Building an
instance from ``--param`` values and the truth's physical scene is
:func:`fogref.mapping.build.build_model` (it needs :mod:`fogref.mapping`, a floor above).

The protocol every model follows (the built-in ones too; see ``docs/byo.md``)::

    class MyFog:
        name = "my_fog"                                  # optional, for reports
        def evaluate(self, camera, positions, precision="float32"):
            # camera: (3,) [m]; positions: (H, W, 3) [m], world frame y-up, the point
            # each pixel shades (camera + view * sky_distance on sky pixels)
            return FogResult(transmittance=T, inscatter=L)   # each (H, W, 3) or broadcastable
        @classmethod
        def from_physical(cls, physical):                # optional: used by --from-scene
            return cls(...)                              # physical: fogref.mapping.PhysicalScene

Any object with ``transmittance`` and ``inscatter`` attributes will do as the result
(:class:`fogref.models.base.FogResult` is one).  The model is built with
``cls()``; ``--param KEY=VALUE`` needs a parameter dataclass ``cls.Params`` and
builds ``cls(cls.Params(**values))`` (see :func:`fogref.mapping.build.build_model`).

Where a name is looked up, in order:

1. ``module.path:Attr``: imported with :mod:`importlib` (the module must be importable:
   installed, or on ``sys.path``/``PYTHONPATH``);
2. a built-in model, registered with :func:`fogref.models.register` (``ue4``, ``unity``, ``hdrp``, ...);
3. an installed package's entry point in the group ``fogref.models``, e.g. in its
   ``pyproject.toml``::

       [project.entry-points."fogref.models"]
       my_fog = "my_pkg.fog:MyFog"

Examples
--------
>>> resolve_model("ue4").__name__
'UE4ExponentialHeightFog'
>>> resolve_model("fogref.models.ue4:UE4ExponentialHeightFog").__name__
'UE4ExponentialHeightFog'
>>> resolve_model("eu4")
Traceback (most recent call last):
...
fogref.errors.FogrefError: unknown fog model 'eu4'; did you mean 'ue4'? (built-in: ...)
"""

from __future__ import annotations

import importlib
import inspect
from importlib.metadata import entry_points
from typing import Any

from fogref.errors import FogrefError, did_you_mean
from fogref.models import base

__all__ = [
    "ENTRY_POINT_GROUP",
    "available_models",
    "check_protocol",
    "entry_point_models",
    "get",
    "resolve_model",
]

ENTRY_POINT_GROUP = "fogref.models"


def _builtin_names() -> list[str]:
    # the built-in models registered themselves when fogref.models (which imports this module) imported them
    return sorted(base.BUILTIN_MODELS)


def entry_point_models() -> dict:
    """Name -> entry point of every model registered under the group ``fogref.models``."""
    return {ep.name: ep for ep in entry_points(group=ENTRY_POINT_GROUP)}


def available_models() -> list[str]:
    """Every model name :func:`resolve_model` knows: the built-in ones and the entry points.

    Examples
    --------
    >>> "ue4" in available_models()
    True
    """
    return sorted(set(_builtin_names()) | set(entry_point_models()))


def check_protocol(obj: Any, source: str) -> Any:
    """Return ``obj`` if it is a fog model class (or instance) following the protocol, else FogrefError.

    The protocol: a callable ``evaluate`` whose signature accepts
    ``(camera, positions, precision=...)``; ``from_physical``, if present, callable.

    Examples
    --------
    >>> class NoFog:
    ...     pass
    >>> check_protocol(NoFog, "my_mod:NoFog")
    Traceback (most recent call last):
    ...
    fogref.errors.FogrefError: my_mod:NoFog: NoFog is not a fog model: it has no evaluate(...) method ...
    """
    try:
        label = getattr(obj, "__name__", type(obj).__name__)
        evaluate = getattr(obj, "evaluate", None)
    except Exception as e:  # an object whose attribute lookup raises (a lazy proxy)
        raise FogrefError(
            f"{source}: looking up its evaluate() failed: {type(e).__name__}: {_one_line(e)}"
        ) from e
    if not callable(evaluate):
        raise FogrefError(
            f"{source}: {label} is not a fog model: it has no evaluate(camera, positions, "
            f'precision="float32") method (see docs/byo.md)'
        )
    try:
        sig = inspect.signature(evaluate)
    except (TypeError, ValueError):
        sig = None
    if sig is not None:
        params = list(sig.parameters.values())
        if inspect.isclass(obj) and params and params[0].name == "self":
            params = params[1:]
        try:
            inspect.Signature(params).bind(None, None, precision="float32")
        except TypeError as e:
            raise FogrefError(
                f"{source}: {label}.evaluate{sig} cannot be called as evaluate(camera, positions, "
                f'precision="float32") ({e}); see docs/byo.md'
            ) from None
    fp = inspect.getattr_static(obj, "from_physical", None)
    if fp is not None and not callable(getattr(obj, "from_physical", None)):
        raise FogrefError(
            f"{source}: {label}.from_physical is not callable (a classmethod from_physical(params))"
        )
    return obj


def _load_spec(spec: str) -> Any:
    module_name, _, attr = spec.partition(":")
    if not module_name or not attr:
        raise FogrefError(f"model '{spec}': expected module.path:Class")
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as e:
        if e.name and module_name.startswith(e.name):
            raise FogrefError(
                f"model '{spec}': no module named '{e.name}' (is it installed, or on PYTHONPATH?)"
            ) from None
        raise FogrefError(f"model '{spec}': importing '{module_name}' failed: {e}") from e
    except Exception as e:  # the user's module raised while importing: say so, with its message
        raise FogrefError(f"model '{spec}': importing '{module_name}' failed: {type(e).__name__}: {e}") from e
    obj = module
    for part in attr.split("."):
        try:
            obj = getattr(obj, part)
        except AttributeError:
            try:
                names = [n for n in dir(obj) if not n.startswith("_")]
            except Exception:  # a module whose __dir__ raises: no hint
                names = []
            hint = did_you_mean(part, names)
            raise FogrefError(
                f"model '{spec}': module '{module_name}' has no attribute '{attr}'{hint}"
            ) from None
        except Exception as e:  # a module-level __getattr__ (lazy import) that raised
            raise FogrefError(
                f"model '{spec}': looking up '{attr}' in module '{module_name}' failed: "
                f"{type(e).__name__}: {_one_line(e)}"
            ) from e
    return check_protocol(obj, spec)


def _one_line(e: BaseException) -> str:
    """The first line of an exception's message (an error is one line on the command line)."""
    text = str(e).strip()
    return text.splitlines()[0] if text else "(no message)"


def resolve_model(spec: str) -> Any:
    """The fog model class (or instance) that ``spec`` names.

    Parameters
    ----------
    spec : str
        ``module.path:Class``, a built-in name (``ue4``), or an entry-point name of the
        group ``fogref.models``.

    Returns
    -------
    type or object
        The class (or the object the spec names), checked against the protocol.

    Raises
    ------
    FogrefError
        Unknown name (with a "did you mean"), module or attribute missing, import
        failure, or an object that does not follow the protocol.
    """
    spec = str(spec).strip()
    if ":" in spec:
        return _load_spec(spec)
    if spec in _builtin_names():
        return base.BUILTIN_MODELS[spec]
    eps = entry_point_models()
    if spec in eps:
        try:
            obj = eps[spec].load()
        except Exception as e:
            raise FogrefError(
                f"model '{spec}': entry point '{eps[spec].value}' (group {ENTRY_POINT_GROUP}) "
                f"failed to load: {type(e).__name__}: {e}"
            ) from e
        return check_protocol(obj, f"entry point {spec} = {eps[spec].value}")
    known = available_models()
    hint = did_you_mean(spec, known)
    extra = sorted(eps)
    listing = f"built-in: {', '.join(_builtin_names())}" + (
        f"; installed: {', '.join(extra)}" if extra else ""
    )
    raise FogrefError(f"unknown fog model '{spec}'{hint} ({listing}; or give module.path:Class)")


#: ``fogref.models.get``: the same resolver under the registry's old name.
get = resolve_model
