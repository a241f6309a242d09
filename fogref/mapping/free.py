"""Which parameters of each fog model the generic fit may change, with their bounds: one place.

:func:`fogref.mapping.fit.fit_model` fits a model's **free** parameters to the physical fog;
every other setting keeps the value of the model's physical mapping
(:func:`fogref.mapping.from_physical`) or, where the scene has none, the model's defaults
plus :attr:`FitSpec.start`.  A :class:`FitSpec` per registry name (:data:`FIT_SPECS`) says

* ``free``: the free parameters (:class:`Free`: a field of the model's ``Params`` dataclass,
  or one channel of an RGB field), each with its bounds in the engine's units;
* ``start``: fixed settings the fit needs (a mode, the sun lobe switched on);
* ``sun``: ``(params, direction) -> params``, pointing the model's light at the sun
  (fogref frame, toward the sun) for each sun elevation; None for models without a sun;
* ``sun_off``: ``params -> params`` without the sun lobe (the error budget's sky/sun split);
* ``initial``: ``scene -> params`` or None, a cheaper start than the mapping where it has one;
* ``exact_medium``: ``params -> FogMedium`` when these settings have an exact physical
  extinction (:mod:`fogref.mapping.translate`), else None;
* ``note``: what the model cannot represent.

A user model (``module:Class``) declares its own with a class attribute
``FIT_PARAMETERS = {"density": (0.0, 1.0), "color[0]": (0.0, inf), ...}`` (bounds in its
units); without one, every float field and every float channel of a tuple field of its
``Params`` is free, in ``[0, inf)`` where the default is >= 0, else unbounded
(:func:`fit_spec`).

Examples
--------
>>> [f.name for f in FIT_SPECS["unity"].free]
['fogDensity', 'fogColor[0]', 'fogColor[1]', 'fogColor[2]']
>>> FIT_SPECS["ue4"].free[-1].name, FIT_SPECS["ue4"].free[-1].log
('DirectionalInscatteringExponent', True)
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Mapping, TypeVar

from fogref.errors import FogrefError, ParameterError
from fogref.mapping.engines import (
    babylon_to_medium,
    bevy_to_medium,
    box_to_medium,
    filament_to_medium,
    godot_to_medium,
    hdrp_to_medium,
    unity_to_medium,
)
from fogref.mapping.physical import PhysicalScene
from fogref.mapping.unreal import base_params
from fogref.media import FogMedium
from fogref.models.babylon import BabylonFogParams
from fogref.models.bevy import BevyFogParams
from fogref.models.box import BoxFogParams
from fogref.models.filament import FilamentFogParams
from fogref.models.ue4 import UE4FogParams, ue4_to_medium
from fogref.models.unity_builtin import UnityFogParams

__all__ = ["FIT_SPECS", "FitSpec", "Free", "fit_spec", "rgb_free"]

INF = math.inf

_P = TypeVar("_P")
_R = TypeVar("_R")


@dataclass(frozen=True)
class Free:
    """One free parameter: ``field`` of the model's ``Params`` (``index``: one element of a
    tuple field), bounds ``[lo, hi]`` in the engine's units; ``log``: fitted as log10 (a
    positive parameter spanning decades; ``lo`` must then be > 0)."""

    field: str
    lo: float = 0.0
    hi: float = INF
    index: int | None = None
    log: bool = False

    @property
    def name(self) -> str:
        return self.field if self.index is None else f"{self.field}[{self.index}]"


def rgb_free(name: str, lo: float = 0.0, hi: float = INF, n: int = 3) -> tuple[Free, ...]:
    """The ``n`` channels of an RGB(A) field as free parameters."""
    return tuple(Free(name, lo, hi, index=i) for i in range(n))


@dataclass(frozen=True)
class FitSpec:
    """What the generic fit changes in one model (see the module doc)."""

    free: tuple[Free, ...]
    start: dict[str, Any] = field(default_factory=dict)
    #: ``(params, direction toward the sun) -> params`` (params: the model's ``Params`` dataclass)
    sun: Callable[[Any, Any], Any] | None = None
    sun_off: Callable[[Any], Any] | None = None
    initial: Callable[[PhysicalScene], Any] | None = None
    exact_medium: Callable[[Any], FogMedium | None] | None = None
    note: str = ""


def _try(fn: Callable[[_P], _R]) -> Callable[[_P], _R | None]:
    """``fn``, None where these settings have no exact medium; an extinction outside the truth's range
    (``FogMedium``'s ``sigma_t`` in [0, 1e2] 1/m) stays an error: no fit stands in for it."""

    def wrapped(p: _P) -> _R | None:
        try:
            return fn(p)
        except ParameterError as e:
            if e.name == "sigma_t":
                raise
            return None
        except ValueError:
            return None

    return wrapped


def _ue4_exact(p: UE4FogParams) -> FogMedium | None:
    plain = p.StartDistance == 0 and p.FogCutoffDistance == 0 and p.FogMaxOpacity == 1 and p.EndDistance == 0
    return ue4_to_medium(p) if plain else None


def _ue4_initial(ps: PhysicalScene) -> UE4FogParams | None:
    """Without a sun above the horizon, Unreal's mapping (its lobe fit) has nothing to fit: start from
    the exact extinction and the sky colour instead."""
    if ps.has_sun and ps.sun_direction[1] > 0:
        return None
    return base_params(ps, FogInscatteringColor=ps.sky_colour(), DirectionalInscatteringColor=(0.0, 0.0, 0.0))


def _unity_exact(p: UnityFogParams) -> FogMedium | None:
    return unity_to_medium(p) if p.fogMode == "exp" and p.fog_coordinate == "distance" else None


def _bevy_exact(p: BevyFogParams) -> FogMedium | None:
    if p.falloff not in ("Exponential", "Atmospheric"):
        return None
    if p.falloff == "Atmospheric" and tuple(p.extinction) != tuple(p.inscattering):
        return None
    return bevy_to_medium(p)


def _filament_exact(p: FilamentFogParams) -> FogMedium | None:
    plain = p.distance == 0 and math.isinf(p.cutOffDistance) and p.maximumOpacity == 1
    return filament_to_medium(p) if plain else None


def _babylon_exact(p: BabylonFogParams) -> FogMedium | None:
    return babylon_to_medium(p) if p.fogMode == "EXP" else None


def _box_exact(p: BoxFogParams) -> FogMedium | None:
    return box_to_medium(p) if p.mode == "beer" else None


def _builtin_specs() -> dict[str, FitSpec]:
    return {
        "ue4": FitSpec(
            free=(
                Free("FogDensity", 1e-8, 10.0, log=True),
                Free("FogHeightFalloff", 0.0, 10.0),
                *rgb_free("FogInscatteringColor"),
                *rgb_free("DirectionalInscatteringColor"),
                Free("DirectionalInscatteringStartDistance", 0.0, 1.0e5),
                Free("DirectionalInscatteringExponent", 1e-2, 1e3, log=True),
            ),
            start={"StartDistance": 0.0, "FogMaxOpacity": 1.0, "FogCutoffDistance": 0.0},
            sun=lambda p, w: p.with_sun(w, p.SunLuminance),
            sun_off=lambda p: replace(p, DirectionalInscatteringColor=(0.0, 0.0, 0.0)),
            initial=_try(_ue4_initial),
            exact_medium=_try(_ue4_exact),
            note="cosine lobe max(cos,0)^n instead of HG; no sun attenuation along the view ray",
        ),
        "unity": FitSpec(
            free=(Free("fogDensity", 1e-8, 10.0, log=True), *rgb_free("fogColor")),
            start={"fogMode": "exp", "fog_coordinate": "distance"},
            exact_medium=_try(_unity_exact),
            note="no height term, no sun",
        ),
        "hdrp": FitSpec(
            free=(
                Free("meanFreePath", 1e-2, 1e7, log=True),
                Free("baseHeight", -1e4, 1e4),
                Free("maximumHeight", -1e4, 1e4),
                *rgb_free("color"),
            ),
            exact_medium=_try(hdrp_to_medium),
            note="constant below baseHeight; no sun",
        ),
        "filament": FitSpec(
            free=(
                Free("density", 1e-8, 10.0, log=True),
                Free("heightFalloff", 0.0, 10.0),
                *rgb_free("color"),
                *rgb_free("lightColorIntensity"),
                Free("inScatteringStart", 0.0, 1e4),
                Free("inScatteringSize", 1e-2, 1e3, log=True),
            ),
            start={
                "distance": 0.0,
                "cutOffDistance": INF,
                "maximumOpacity": 1.0,
                "lightColorIntensity": (0.1, 0.1, 0.1, 1.0),
                "inScatteringSize": 8.0,
            },
            sun=lambda p, w: replace(p, lightDirection=tuple(float(x) for x in w)),
            sun_off=lambda p: replace(p, inScatteringSize=-1.0),
            exact_medium=_try(_filament_exact),
            note="cosine lobe instead of HG; lobe not attenuated",
        ),
        "altitude": FitSpec(
            free=(
                Free("_FogEnd", 1.0, 1e5, log=True),
                Free("_FogPower", 0.05, 50.0, log=True),
                *rgb_free("_FogColor", n=3),
                Free("_FogColor", 1e-8, 10.0, index=3, log=True),
            ),
            start={"_FogStart": 0.0},
            note="blend 1 - saturate(tau) instead of exp(-tau); power-law density; no sun",
        ),
        "box": FitSpec(
            free=(
                Free("density", 1e-8, 10.0, log=True),
                Free("box_max", 1.0, 1e5, index=1, log=True),
                *rgb_free("fog_color"),
            ),
            start={"mode": "beer", "box_min": (-1.0e6, -1.0e4, -1.0e6), "box_max": (1.0e6, 100.0, 1.0e6)},
            exact_medium=_try(_box_exact),
            note="homogeneous inside a box (a slab here); no sun",
        ),
        "godot": FitSpec(
            free=(
                Free("fog_density", 1e-8, 10.0, log=True),
                *rgb_free("fog_light_color"),
                *rgb_free("sun_color"),
                Free("fog_sky_affect", 0.0, 1.0),
            ),
            start={
                "fog_mode": "exponential",
                "fog_height_density": 0.0,
                "fog_sun_scatter": 1.0,
                "fog_aerial_perspective": 0.0,
                "fog_light_energy": 1.0,
            },
            sun=lambda p, w: replace(p, sun_direction=tuple(float(x) for x in w)),
            sun_off=lambda p: replace(p, fog_sun_scatter=0.0),
            exact_medium=_try(godot_to_medium),
            note="no height term in the optical depth; fixed lobe exponent 8; lobe not attenuated",
        ),
        "bevy": FitSpec(
            free=(
                *rgb_free("extinction", 1e-8, 10.0),
                *rgb_free("inscattering", 1e-8, 10.0),
                *rgb_free("color"),
                *rgb_free("directional_light_color"),
                Free("directional_light_exponent", 1e-2, 1e3, log=True),
            ),
            start={"falloff": "Atmospheric", "light_color": (1.0, 1.0, 1.0)},
            sun=lambda p, w: replace(p, light_direction=tuple(float(x) for x in w)),
            sun_off=lambda p: replace(p, directional_light_color=(0.0, 0.0, 0.0, 0.0)),
            exact_medium=_try(_bevy_exact),
            note="no height term; cosine lobe instead of HG",
        ),
        "threejs": FitSpec(
            free=(Free("density", 1e-8, 10.0, log=True), *rgb_free("color")),
            start={"mode": "FogExp2"},
            note="exp(-(density depth)^2) instead of exp(-tau); eye depth, not distance; no sun",
        ),
        "babylon": FitSpec(
            free=(Free("fogDensity", 1e-8, 10.0, log=True), *rgb_free("fogColor")),
            start={"fogMode": "EXP"},
            exact_medium=_try(_babylon_exact),
            note="no height term; no sun",
        ),
        "playcanvas": FitSpec(
            free=(Free("density", 1e-8, 10.0, log=True), *rgb_free("color")),
            start={"type": "exp"},
            note="remapped eye depth far (z - near)/(far - near), not distance; no height term; no sun",
        ),
    }


#: registry name -> :class:`FitSpec` of the built-in models.
FIT_SPECS: dict[str, FitSpec] = _builtin_specs()


def _default_free(cls: type) -> tuple[Free, ...]:
    params_cls = getattr(cls, "Params", None)
    if not (isinstance(params_cls, type) and dataclasses.is_dataclass(params_cls)):
        raise FogrefError(
            f"model '{getattr(cls, 'name', cls)}': the fit needs a parameter dataclass "
            "'Params' (see docs/byo.md) or a FIT_PARAMETERS attribute"
        )
    try:
        p = params_cls()
    except TypeError as e:
        raise FogrefError(
            f"model '{getattr(cls, 'name', cls)}': {params_cls.__name__}() needs arguments "
            f"({e}); declare FIT_PARAMETERS"
        ) from None
    out = []
    for f in dataclasses.fields(p):
        v = getattr(p, f.name)
        if isinstance(v, bool) or not f.init:
            continue
        if isinstance(v, float) and math.isfinite(v):
            out.append(Free(f.name, 0.0 if v >= 0 else -INF, INF))
        elif isinstance(v, tuple) and v and all(isinstance(x, float) and math.isfinite(x) for x in v):
            out += [Free(f.name, 0.0 if x >= 0 else -INF, INF, index=i) for i, x in enumerate(v)]
    return tuple(out)


def _parse_declared(cls: type, declared: Mapping[str, tuple[float, float]]) -> tuple[Free, ...]:
    out = []
    for key, bounds in declared.items():
        name, _, rest = str(key).partition("[")
        index = int(rest.rstrip("]")) if rest else None
        lo, hi = (float(b) for b in bounds)
        out.append(Free(name, lo, hi, index=index))
    return tuple(out)


def fit_spec(cls: type) -> FitSpec:
    """The :class:`FitSpec` of a model class: the built-in one for its registry name, else
    from its ``FIT_PARAMETERS`` (and optional ``FIT_START``), else every float of its ``Params``.

    Raises FogrefError when no parameter is free.

    Examples
    --------
    >>> from fogref.models.resolve import resolve_model
    >>> len(fit_spec(resolve_model("threejs")).free)
    4
    """
    name = getattr(cls, "name", None)
    if name in FIT_SPECS:
        return FIT_SPECS[name]
    declared = getattr(cls, "FIT_PARAMETERS", None)
    free = _parse_declared(cls, declared) if declared else _default_free(cls)
    if not free:
        raise FogrefError(f"model '{name or cls}': no free float parameter to fit (declare FIT_PARAMETERS)")
    return FitSpec(
        free=free,
        start=dict(getattr(cls, "FIT_START", {}) or {}),
        note="user model: free parameters " + ", ".join(f.name for f in free),
    )
