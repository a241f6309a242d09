"""One engine's fog settings carried to another's through the physical truth.

:func:`translate` goes source settings -> physical fog -> target settings:

1. The source model is built from the user's settings; every setting not given comes either from
   the reference scene's physical mapping (``fill="mapping"``: :func:`fogref.mapping.fit.start_params`,
   the fit of that scene) or from the engine's own defaults (``fill="defaults"``: the model's
   ``Params()``, :data:`fogref.models.terms.DEFAULTS_FROM` cites each engine's source), and is
   reported with where it came from (:attr:`Translation.filled`).  The model is evaluated on the
   views; its light follows each sun.
2. Its physical fog: the scene's albedo, camera and sun direction, with

   * the extinction of the **exact mapping** where the source's settings have one
     (:attr:`fogref.mapping.free.FitSpec.exact_medium`: Unreal's ``ue4_to_medium``, Unity's exp
     fog on distance, Godot's exponential mode, Bevy's Exponential/Atmospheric, HDRP, Filament, box
     "beer"), else a fit of ``sigma_t`` and the falloff of one exponential layer at the scene's
     layer height (three.js, the altitude fog's blend, the depth modes);
   * the phase asymmetry ``g`` and the sun irradiance (RGB; only when the scene has a sun) and the
     sky radiance (RGB) fitted to the source's inscatter (the engines' colours stand for
     ``albedo E`` and ``albedo L_sky``, so the albedo is kept and the light is fitted).

   The fit is :func:`fogref.mapping.fit.fit_to_targets` on :class:`PhysicalFog`, the closed forms
   as a model.
3. The target model fitted to that physical fog (:func:`fogref.mapping.fit.fit_model`).

Reported: the error no target setting can remove, the relative RMSE of the best target fit
against the physical truth (``residual_vs_truth``) and against the source model
(``residual_vs_source``), and how well the physical fog reproduces the source
(``source_vs_physical``).

Examples
--------
>>> from fogref.media import ExpLayer, FogMedium
>>> ps = PhysicalScene(FogMedium(sigma_t=0.01, albedo=0.5, layers=(ExpLayer(1.0, 0.0, 0.0),)),
...                    sky_radiance=(1.0, 1.0, 1.0))
>>> t = translate("unity", "godot", {"fogDensity": 0.02}, ps, views=32)
>>> round(t.target.values["fog_density"], 5), t.physical["extinction"]
(0.02, 'exact')
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Iterable, Sequence

import numpy as np
import numpy.typing as npt

from fogref.errors import FogrefError, ParameterError
from fogref.mapping.build import model_label, param_dict
from fogref.mapping.fit import (
    FIT_DIRECTIONS_MAX_GENERIC,
    ModelFit,
    Target,
    evaluate_on_views,
    fit_model,
    fit_to_targets,
    jsonable,
    model_class,
    start_params,
    with_sun_elevation,
)
from fogref.mapping.free import FitSpec, Free, fit_spec, rgb_free
from fogref.mapping.physical import PhysicalScene
from fogref.mapping.views import Views, physical_single_scattering, sample_views
from fogref.media import NP, ExpLayer, FogMedium
from fogref.models.base import SKY_DISTANCE, FogResult, ParamModel
from fogref.models.terms import DEFAULTS_FROM, annotate

__all__ = ["PhysicalFog", "PhysicalFogParams", "Translation", "physical_of_model", "translate"]

#: Directions of :func:`translate` without ``views`` (a fixed count: three fits in a row).
TRANSLATE_DIRECTIONS = 512


@dataclass(frozen=True)
class PhysicalFogParams:
    """A physical fog as model parameters.  ``medium``: fixed extinction (an exact mapping); else
    ``sigma_t`` [1/m] at ``height`` [m] with ``falloff`` [1/m].  ``g``: HG asymmetry;
    ``sun_irradiance``, ``sky_radiance``: RGB; ``sun_direction``: toward the sun; ``albedo``: RGB."""

    sigma_t: float = 0.001
    falloff: float = 0.01
    height: float = 0.0
    albedo: tuple = (0.9, 0.9, 0.9)
    g: float = 0.0
    sun_irradiance: tuple = (1.0, 1.0, 1.0)
    sky_radiance: tuple = (0.2, 0.3, 0.5)
    sun_direction: tuple = (0.0, 1.0, 0.0)
    medium: FogMedium | None = None

    def scene(self, camera: Iterable[float]) -> PhysicalScene:
        if self.medium is not None:
            m = replace(self.medium, albedo=self.albedo, g=self.g)
        else:
            m = FogMedium(
                sigma_t=self.sigma_t,
                albedo=self.albedo,
                g=self.g,
                layers=(ExpLayer(1.0, self.falloff, self.height),),
                source="<translate>",
            )
        return PhysicalScene(
            m, self.sun_direction, self.sun_irradiance, self.sky_radiance, tuple(camera), source="<translate>"
        )


class PhysicalFog(ParamModel[PhysicalFogParams]):
    """The closed-form single scattering and transmittance of a physical fog, as a fog model
    (sky pixels, at :data:`~fogref.models.base.SKY_DISTANCE` or farther, see an infinite distance)."""

    name = "physical"
    Params = PhysicalFogParams

    def evaluate(
        self, camera: npt.ArrayLike, positions: npt.ArrayLike, precision: str = "float64"
    ) -> FogResult:
        cam = np.asarray(camera, float)
        rel = np.asarray(positions, float).reshape(-1, 3) - cam
        D = np.linalg.norm(rel, axis=-1)
        d = rel / np.maximum(D, 1e-30)[:, None]
        D = np.where(D >= SKY_DISTANCE * (1.0 - 1e-9), np.inf, D)
        ps = self.params.scene(cam)
        v = Views(cam, d, D)
        L = physical_single_scattering(ps, v)
        T = np.stack(ps.medium.transmittance(NP, *v.rays()), axis=-1)
        shape = np.shape(positions)
        return FogResult(inscatter=L.reshape(shape), transmittance=T.reshape(shape))


def _physical_spec(exact: bool, sun: bool = True) -> FitSpec:
    light = (Free("g", -0.95, 0.95), *rgb_free("sun_irradiance", 0.0, 1e4)) if sun else ()
    light += rgb_free("sky_radiance", 0.0, 1e4)
    ext = () if exact else (Free("sigma_t", 1e-8, 10.0, log=True), Free("falloff", 0.0, 1.0))
    return FitSpec(
        free=ext + light,
        sun=lambda p, w: replace(p, sun_direction=tuple(float(x) for x in w)),
        note="single scattering, HG phase, unoccluded sky",
    )


def _source_targets(
    cls: type,
    spec: FitSpec,
    params: Any,
    pf: PhysicalScene,
    views: Views,
    elevations: Sequence[float] | None,
) -> list[Target]:
    scenes = [pf] if elevations is None else [with_sun_elevation(pf, e) for e in elevations]
    out = []
    for ps in scenes:
        p = spec.sun(params, ps.sun_direction) if spec.sun is not None else params
        ((L, T),) = evaluate_on_views(cls, p, [views])
        out.append(Target(ps, views, np.array(L), np.array(T)))
    return out


#: A source fog whose transmittance is below this on every view of a surface is opaque: nothing
#: to translate.
OPAQUE = 1e-9


def physical_of_model(
    cls: type, params: Any, pf: PhysicalScene, views: Views, elevations: Sequence[float] | None = None
) -> tuple[dict[str, Any], dict[str, str]]:
    """The physical fog of a model's settings (module doc, step 2).

    Returns ``(fit, info)``: :func:`~fogref.mapping.fit.fit_to_targets`'s dict for
    :class:`PhysicalFog` and ``{"extinction": "exact" | "fitted", ...}``.
    """
    spec = fit_spec(cls)
    targets = _source_targets(cls, spec, params, pf, views, elevations)
    # on the views of surfaces: engines that draw the background unfogged (three.js, Bevy, ...)
    # show T = 1 on the sky whatever the fog
    surface_T = [np.asarray(t.T)[~t.views.sky] if (~t.views.sky).any() else np.asarray(t.T) for t in targets]
    if all(float(np.max(T)) < OPAQUE for T in surface_T):
        raise ParameterError(
            f"translate: {getattr(cls, 'name', cls.__name__)}",
            "settings",
            f"the fog is opaque (transmittance < {OPAQUE:g}) on every view: no extinction can be "
            "recovered from it; give a thinner fog",
        )
    medium = spec.exact_medium(params) if spec.exact_medium is not None else None
    if medium is not None and max(medium.sigma_t) <= 0:
        medium = None
    m = pf.medium
    L0 = m.layers[0]
    p0 = PhysicalFogParams(
        sigma_t=float(np.mean(m.sigma_t)),
        falloff=float(getattr(L0, "falloff", 0.0)),
        height=float(getattr(L0, "height", 0.0)),
        albedo=tuple(m.albedo),
        g=float(m.g),
        sun_irradiance=tuple(pf.sun_irradiance),
        sky_radiance=tuple(pf.sky_radiance),
        sun_direction=pf.sun_direction,
        medium=medium,
    )
    fit = fit_to_targets(PhysicalFog, targets, p0, _physical_spec(medium is not None, pf.has_sun))
    info = {"extinction": "exact" if medium is not None else "fitted"}
    return fit, info


#: ``fill`` of :func:`translate`: where the source's settings that were not given come from.
FILLS = ("mapping", "defaults")


def source_settings(
    cls: type, pf: PhysicalScene, spec: FitSpec, params: dict[str, Any] | None, fill: str, scene_label: str
) -> tuple[Any, dict[str, dict[str, Any]]]:
    """The source's settings and, for each setting not in ``params``, ``{"value", "from"}``.

    ``fill="mapping"``: the physical mapping of the reference scene (its fit); ``"defaults"``: the
    model's ``Params()`` defaults, which are the engine's (cited by
    :data:`fogref.models.terms.DEFAULTS_FROM`).  A setting the sun sets (its direction) says so.
    """
    given = dict(params or {})
    name = model_label(cls)
    if fill == "mapping":
        p, how = start_params(cls, pf, spec, given)
        origin = (
            f"the fit of {scene_label} (fogref.mapping's physical mapping)"
            if how == "mapping"
            else f"{_defaults_from(name)}, then the fit's start settings"
        )
    elif fill == "defaults":
        p, _ = start_params(cls, pf, FitSpec(free=spec.free), given, use_mapping=False)
        origin = _defaults_from(name)
    else:
        raise ParameterError("translate", "fill", f"{fill!r} is not one of {', '.join(FILLS)}")
    sunlit = param_dict(spec.sun(p, pf.sun_direction)) if spec.sun is not None else {}
    filled = {}
    for k, v in param_dict(p).items():
        if k in given:
            continue
        moved = k in sunlit and sunlit[k] != v
        filled[k] = {
            "value": sunlit[k] if moved else v,
            "from": f"the sun of {scene_label}" if moved else origin,
        }
    return p, filled


def _defaults_from(name: str) -> str:
    where = DEFAULTS_FROM.get(name)
    return f"the default of {where}" if where else f"the default of {name}'s Params"


@dataclass
class Translation:
    """Result of :func:`translate`.  ``filled``: each source setting that was not given, with its
    value and where it came from (:func:`source_settings`); ``reference``: the reference scene."""

    source: str
    source_settings: dict
    physical: dict
    target: ModelFit
    residual_vs_truth: float  #: relative RMSE of the best target fit vs the physical fog's inscatter
    residual_vs_source: float  #: relative RMSE of the best target fit vs the source model's inscatter
    source_vs_physical: float  #: relative RMSE of the physical fog vs the source model's inscatter
    filled: dict = field(default_factory=dict)
    reference: str = ""

    def to_dict(self) -> dict:
        return {
            "source": {
                "model": self.source,
                "settings": jsonable(self.source_settings),
                "units": {
                    k: a for k, v in self.source_settings.items() if (a := annotate(self.source, k, v))
                },
                "not_given": {
                    k: {"value": jsonable({"v": d["value"]})["v"], "from": d["from"]}
                    for k, d in self.filled.items()
                },
                "reference_scene": self.reference,
            },
            "physical": self.physical,
            "target": self.target.to_dict(),
            "residual": {
                "target_vs_truth_rel_rmse": self.residual_vs_truth,
                "target_vs_source_rel_rmse": self.residual_vs_source,
                "physical_vs_source_rel_rmse": self.source_vs_physical,
                "target_vs_truth_rmse_transmittance": self.target.rmse_T,
                "cannot_represent": self.target.note,
            },
        }


def translate(
    source: str | type,
    target: str | type,
    params: dict[str, Any] | None = None,
    scene: PhysicalScene | dict[str, Any] | None = None,
    views: int | Views | None = None,
    sun_elevations: Iterable[float] | None = None,
    target_params: dict[str, Any] | None = None,
    fill: str = "mapping",
    scene_label: str = "the reference scene",
) -> Translation:
    """Carry ``source``'s settings (``params``, its own names) to ``target`` through the physical fog.

    Parameters
    ----------
    source, target : str or type
        Model names (:func:`fogref.models.resolve_model`) or classes.
    params : dict, optional
        The source's settings; the rest come from the reference scene's mapping (or the
        source's defaults where it has none).
    scene : PhysicalScene or dict
        The reference scene (camera, albedo, sun azimuth, layer height; a default light).
    views : int or Views, optional
        Fibonacci directions (default :data:`TRANSLATE_DIRECTIONS`).
    sun_elevations : sequence of float, optional
        Sun elevations [degrees] fitted together (default the scene's sun).
    target_params : dict, optional
        Fixed settings of the target (e.g. a mode).
    fill : {"mapping", "defaults"}
        Where the source's settings not in ``params`` come from: the reference scene's physical
        mapping (its fit) or the engine's defaults (:func:`source_settings`).
    scene_label : str
        The reference scene's name in :attr:`Translation.filled`.
    """
    if scene is None:
        raise FogrefError("translate: a reference scene is needed (fogref.translate defaults to the valley)")
    pf = scene if isinstance(scene, PhysicalScene) else PhysicalScene.from_params(scene)
    src_cls = model_class(source)
    tgt_cls = model_class(target)
    src_spec = fit_spec(src_cls)
    src_params, filled = source_settings(src_cls, pf, src_spec, params, fill, scene_label)
    if views is None:
        views = TRANSLATE_DIRECTIONS
    if not isinstance(views, Views):
        n = int(views)
        if not 8 <= n <= 100_000:
            raise ParameterError("translate", "views", f"{views} directions outside [8, 100000]")
        views = sample_views(pf.camera, n_dirs=n)
    elev = None if sun_elevations is None else [float(e) for e in sun_elevations]
    phys, info = physical_of_model(src_cls, src_params, pf, views, elev)
    pp = phys["params"]
    ps = pp.scene(pf.camera)
    tfit = fit_model(
        tgt_cls,
        ps,
        views=views,
        sun_elevations=elev,
        params=target_params,
        max_dirs=FIT_DIRECTIONS_MAX_GENERIC,
    )
    # the best target against the source model, on the same views and suns
    src_targets = _source_targets(src_cls, src_spec, src_params, pf, views, elev)
    tspec = fit_spec(tgt_cls)
    errs, ref = [], []
    for t in src_targets:
        p = tspec.sun(tfit.params, t.scene.sun_direction) if tspec.sun is not None else tfit.params
        ((L, _),) = evaluate_on_views(tgt_cls, p, [views])
        errs.append(L - t.L)
        ref.append(t.L)
    e, r = np.concatenate(errs), np.concatenate(ref)
    rms = float(np.sqrt(np.mean(r**2)))
    vs_source = float(np.sqrt(np.mean(e**2))) / rms if rms > 0 else 0.0
    m = ps.medium
    physical = {
        **info,
        "sigma_t": [float(x) for x in m.sigma_t],
        "layers": [repr(L) for L in m.layers],
        "albedo": list(ps.medium.albedo),
        "g": pp.g,
        "sun_irradiance": list(pp.sun_irradiance),
        "sky_radiance": list(pp.sky_radiance),
        "uncertainty": {k: v for k, v in phys["uncertainty"].items()},
        "rel_rmse_vs_source": phys["rel_rmse"],
    }
    return Translation(
        source=getattr(src_cls, "name", str(source)),
        source_settings=param_dict(src_params),
        physical=physical,
        target=tfit,
        residual_vs_truth=tfit.rel_rmse,
        residual_vs_source=vs_source,
        source_vs_physical=phys["rel_rmse"],
        filled=filled,
        reference=scene_label,
    )
