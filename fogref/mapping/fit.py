"""A fit of any fog model to the physical fog: the free parameters of :mod:`fogref.mapping.free`.

:func:`fit_model` generalises :func:`fogref.mapping.unreal.fit_unreal` to every model (the
built-in ones and a user's ``module:Class``, resolved by :func:`fogref.models.resolve_model`).
The target needs no rendering: the closed-form single scattering of the physical fog
(sun + uniform sky, :func:`~fogref.mapping.unreal.physical_single_scattering`) and its
transmittance, over the views of :func:`~fogref.mapping.unreal.sample_views` (Fibonacci
directions with ``d_y >= -0.5`` at 12 distances from 10 m to 20 km, plus the sky), for each
sun elevation asked for (the sun keeps the scene's azimuth).  One parameter set is fitted
over all the elevations together; the model's light follows the sun
(:attr:`~fogref.mapping.free.FitSpec.sun`).

Loss (least squares, :func:`scipy.optimize.least_squares`, trust-region reflective within
the bounds): the residuals are the inscatter errors ``L_model - L_phys`` (all RGB channels,
radiance) and ``w s (T_model - T_phys)`` with ``s`` the RMS of the physical inscatter and
``w = transmittance_weight`` (default 1): a transmittance error of 1 costs as much as the
whole inscatter.  The model is evaluated in float64.  Parameters flagged ``log`` are fitted
as log10.

Uncertainty of each fitted parameter, two numbers:

* ``uncertainty``: from the Jacobian ``J`` at the optimum, ``cov = s^2 (J^T J)^-1`` with
  ``s^2 = SSE / (m - p)`` (m residuals, p parameters; through the SVD of ``J`` with unit
  columns, so a direction the views barely constrain gets the large uncertainty it has;
  :attr:`ModelFit.ill_posed` lists the parameters whose uncertainty exceeds their value),
  mapped through ``d value / d log10 value = ln(10) value`` for log parameters.  It treats
  the model's misfit as noise: it measures how sharply the views pin the parameter, and
  shrinks as ``1/sqrt(views)``.
* ``spread``: ``|value(2N) - value(N)|`` between the last two direction counts of the
  convergence check (the quadrature's own error); with a fixed direction count, the largest
  ``|value(N turned) - value(N)|`` over two refits on the same directions turned about the
  vertical (:data:`RESAMPLE_TURNS`, :func:`~fogref.mapping.views.rotated_views`): the error of
  sampling the sphere with few directions, which the Jacobian does not see.

Direction count: without ``views``, ``FIT_DIRECTIONS_START`` (128) directions, doubled until
every parameter changes by at most ``max(rtol |value|, uncertainty)`` (default ``rtol``
5e-3), at most :data:`FIT_DIRECTIONS_MAX_GENERIC`.

Examples
--------
>>> from fogref.media import ExpLayer, FogMedium
>>> from fogref.mapping.physical import PhysicalScene
>>> ps = PhysicalScene(FogMedium(sigma_t=0.01, albedo=0.5, layers=(ExpLayer(1.0, 0.0, 0.0),)),
...                    sky_radiance=(1.0, 1.0, 1.0))
>>> from fogref.mapping.views import sample_views
>>> meshes = sample_views(ps.camera, n_dirs=64, sky_min_dy=1.0)  # Unity's skybox has no fog
>>> r = fit_model("unity", ps, views=meshes)
>>> round(r.values["fogDensity"], 6), r.rel_rmse < 1e-6
(0.01, True)
"""

from __future__ import annotations

import dataclasses
import inspect
import math
import time
from dataclasses import dataclass, field, replace
from typing import Any, Iterable, Sequence

import numpy as np
import numpy.typing as npt
from threadpoolctl import threadpool_limits

from fogref.errors import FogrefError, ParameterError, did_you_mean
from fogref.mapping.build import model_label, param_dict
from fogref.mapping.free import FitSpec, Free, fit_spec
from fogref.mapping.physical import PhysicalScene
from fogref.mapping.registry import from_physical, has_mapping
from fogref.mapping.unreal import FIT_DIRECTIONS_START, FIT_RTOL
from fogref.mapping.views import Views, physical_single_scattering, rotated_views, sample_views
from fogref.media import NP
from fogref.models.base import SKY_DISTANCE
from fogref.models.resolve import resolve_model
from fogref.models.terms import annotate
from fogref.params import number

__all__ = [
    "FIT_DIRECTIONS_MAX_GENERIC",
    "ModelFit",
    "Target",
    "fit_model",
    "evaluate_on_views",
    "fit_to_targets",
    "jsonable",
    "model_class",
    "physical_targets",
    "start_params",
    "sun_elevation",
    "with_sun_elevation",
]

#: The most directions :func:`fit_model` doubles to (each fit has up to ~15 parameters).
FIT_DIRECTIONS_MAX_GENERIC = 4096
#: With a fixed direction count, the refits that give the spread turn the directions about the vertical
#: by a third and two thirds of the golden angle [rad] (between the Fibonacci spiral's azimuths).
RESAMPLE_TURNS = tuple(k / 3 * math.pi * (3.0 - math.sqrt(5.0)) for k in (1, 2))


def sun_elevation(pf: PhysicalScene) -> float:
    """The scene's sun elevation above the horizon [degrees], in [-90, 90].

    Examples
    --------
    >>> from fogref.media import FogMedium
    >>> round(sun_elevation(PhysicalScene(FogMedium(), (1.0, 1.0, 0.0), 1.0)), 6)
    45.0
    """
    return math.degrees(math.asin(max(-1.0, min(1.0, pf.sun_direction[1]))))


def with_sun_elevation(pf: PhysicalScene, elevation_deg: float) -> PhysicalScene:
    """``pf`` with the sun at ``elevation_deg`` [degrees, -90..90], same azimuth (north +z if
    the scene's sun is at the zenith).  ParameterError naming 'sun_elevation' outside the range.

    Examples
    --------
    >>> from fogref.media import ExpLayer, FogMedium
    >>> ps = PhysicalScene(FogMedium(sigma_t=0.01, layers=(ExpLayer(1.0, 0.0, 0.0),)), (1.0, 1.0, 0.0), 1.0)
    >>> round(sun_elevation(with_sun_elevation(ps, 30.0)), 6)
    30.0
    """
    e = number(elevation_deg, "sun_elevation", source=pf.source, lo=-90.0, hi=90.0, unit="deg")
    w = np.asarray(pf.sun_direction, dtype=float)
    h = math.hypot(w[0], w[2])
    ax, az = (w[0] / h, w[2] / h) if h > 1e-12 else (0.0, 1.0)
    c, s = math.cos(math.radians(e)), math.sin(math.radians(e))
    return replace(pf, sun_direction=(c * ax, s, c * az))


@dataclass
class Target:
    """The physical fog on a set of views: inscatter ``L`` and transmittance ``T`` (N, 3)."""

    scene: PhysicalScene
    views: Views
    L: np.ndarray
    T: np.ndarray


def physical_targets(
    pf: PhysicalScene, views: Views, elevations: Iterable[float] | None = None
) -> list[Target]:
    """One :class:`Target` per sun elevation (default: the scene's own sun): what a fit aims at,
    the physical fog's closed-form inscatter and transmittance on ``views`` (the targets of
    :func:`fit_model` and :func:`fogref.mapping.translate.translate`)."""
    scenes = [pf] if elevations is None else [with_sun_elevation(pf, e) for e in elevations]
    out = []
    for ps in scenes:
        L = physical_single_scattering(ps, views)
        T = np.stack(ps.medium.transmittance(NP, *views.rays()), axis=-1)
        out.append(Target(ps, views, np.asarray(L, float), np.asarray(T, float)))
    return out


def model_class(model: str | type) -> type:
    """The model class a name (or class) stands for (:func:`fogref.models.resolve.resolve_model`)."""
    cls = resolve_model(model) if isinstance(model, str) else model
    if not inspect.isclass(cls):
        raise FogrefError(f"model '{model}' names an instance, not a class: the fit builds its own instances")
    return cls


def start_params(
    cls: type,
    pf: PhysicalScene,
    spec: FitSpec | None = None,
    overrides: dict[str, Any] | None = None,
    use_mapping: bool = True,
) -> tuple[Any, str]:
    """The parameters the fit starts from: the physical mapping of ``pf`` where the model has
    one for it (and ``use_mapping``), else the model's defaults; then ``spec.start`` and
    ``overrides``.

    Returns ``(params, source)`` with source "mapping" or "defaults".
    """
    spec = spec or fit_spec(cls)
    params: Any = None  # the model's Params dataclass
    source = "defaults"
    if spec.initial is not None and use_mapping:
        params = spec.initial(pf)
        source = "mapping" if params is not None else source
    if params is None and use_mapping and has_mapping(cls):
        try:
            model: Any = from_physical(cls, pf)  # a model instance; its settings are .params
            params, source = model.params, "mapping"
        except (ParameterError, FogrefError):
            params = None
    if params is None:
        pc = getattr(cls, "Params", None)
        if not (isinstance(pc, type) and dataclasses.is_dataclass(pc)):
            raise FogrefError(f"model '{model_label(cls)}': the fit needs a parameter dataclass 'Params'")
        params = pc()
    kw = {k: v for k, v in spec.start.items() if source == "defaults" or k not in _MAPPED_KEEP}
    kw.update(overrides or {})
    names = {f.name for f in dataclasses.fields(params)}
    bad = [k for k in kw if k not in names]
    if bad:
        raise FogrefError(f"model '{model_label(cls)}': no parameter '{bad[0]}'{did_you_mean(bad[0], names)}")
    try:
        return replace(params, **kw), source
    except ParameterError:  # names the parameter, its value and its range already
        raise
    except (TypeError, ValueError) as e:
        raise FogrefError(f"model '{model_label(cls)}': cannot set {sorted(kw)}: {e}") from e


#: Start settings the physical mapping chooses better than a generic start (the lobe it fitted).
_MAPPED_KEEP = ("lightColorIntensity", "inScatteringSize")


def _get(params: Any, f: Free) -> float:
    v = getattr(params, f.field)
    return float(v if f.index is None else v[f.index])


def _set(params: Any, free: Sequence[Free], values: Iterable[float]) -> Any:
    upd: dict[str, Any] = {}
    for f, v in zip(free, values):
        if f.index is None:
            upd[f.field] = float(v)
        else:
            cur = list(upd.get(f.field, getattr(params, f.field)))
            cur[f.index] = float(v)
            upd[f.field] = tuple(cur)
    return replace(params, **upd)


def _to_internal(f: Free, v: float) -> float:
    return math.log10(max(v, f.lo if f.lo > 0 else 1e-300)) if f.log else v


def _to_value(f: Free, x: float) -> float:
    return 10.0**x if f.log else x


def _bounds(free: Sequence[Free]) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    lo = [math.log10(f.lo) if f.log else f.lo for f in free]
    hi = [math.log10(f.hi) if f.log else f.hi for f in free]
    return np.array(lo, float), np.array(hi, float)


def evaluate_on_views(
    cls: type, params: Any, view_sets: Iterable[Views]
) -> list[tuple[np.ndarray, np.ndarray]]:
    """The model ``cls(params)`` in float64 on each set of views: ``(L, T)`` per set, its inscatter
    (radiance) and transmittance ([0, 1]), each (N, 3) for the N views (the sky at
    :data:`~fogref.models.base.SKY_DISTANCE`)."""
    out = []
    for views in view_sets:
        r = cls(params).evaluate(views.camera, views.world_positions(SKY_DISTANCE), "float64")
        L = np.broadcast_to(np.asarray(r.inscatter, float), (len(views.D), 3))
        T = np.broadcast_to(np.asarray(r.transmittance, float), (len(views.D), 3))
        out.append((L, T))
    return out


def _jacobian_sigma(J: np.ndarray, s2: float) -> np.ndarray:
    """Standard errors ``sqrt(diag(s2 (J^T J)^-1))`` of the parameters, through the SVD of ``J`` with its
    columns scaled to unit norm: a parameter the views barely constrain (a near-zero column, or a
    combination of parameters with a near-zero singular value) gets the large error it has, not the 0
    of a truncated pseudo-inverse.  Singular values and column norms are floored at float64's epsilon
    of the largest, so the errors stay finite."""
    if J.size == 0:
        return np.zeros(J.shape[1])
    eps = np.finfo(float).eps
    norms = np.linalg.norm(J, axis=0)
    norms = np.maximum(norms, eps * max(float(norms.max()), eps))
    _, S, Vt = np.linalg.svd(J / norms, full_matrices=False)
    S = np.maximum(S, eps * max(float(S[0]), eps))
    return np.sqrt(s2 * np.sum((Vt.T / S) ** 2, axis=1)) / norms


def fit_to_targets(
    cls: type,
    targets: list[Target],
    params0: Any,
    spec: FitSpec | None = None,
    transmittance_weight: float = 1.0,
    x0: npt.ArrayLike | None = None,
) -> dict[str, Any]:
    """Least squares of the free parameters of ``cls`` (starting at ``params0``) to ``targets``.

    Returns ``{"params" (dataclass, the scene's own sun), "x" (internal), "values", "uncertainty",
    "at_bound", "rank", "rmse", "rel_rmse", "rmse_T", "target_rms", "n_views", "nfev", "free"}``.
    """
    from scipy.optimize import least_squares

    spec = spec or fit_spec(cls)
    free = spec.free
    lo, hi = _bounds(free)
    if x0 is None:
        x0 = np.array([_to_internal(f, _get(params0, f)) for f in free])
    span = np.where(np.isfinite(hi - lo), hi - lo, 1.0)
    x0 = np.clip(np.asarray(x0, float), lo + 1e-9 * span, hi - 1e-9 * span)
    L_t = np.concatenate([t.L for t in targets])
    T_t = np.concatenate([t.T for t in targets])
    s = float(np.sqrt(np.mean(L_t**2))) or 1.0
    wT = float(transmittance_weight) * s
    suns = [t.scene.sun_direction for t in targets]

    def params_at(x: Iterable[float], w: Any = None) -> Any:
        p = _set(params0, free, [_to_value(f, xi) for f, xi in zip(free, x)])
        return spec.sun(p, w) if (spec.sun is not None and w is not None) else p

    def predict(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        Ls, Ts = [], []
        for t, w in zip(targets, suns):
            ((L, T),) = evaluate_on_views(cls, params_at(x, w), [t.views])
            Ls.append(L)
            Ts.append(T)
        return np.concatenate(Ls), np.concatenate(Ts)

    bad = np.full(2 * L_t.size, 1.0e3 * max(s, 1.0))

    def resid(x: np.ndarray) -> np.ndarray:
        try:
            L, T = predict(x)
        except (ParameterError, ValueError, FloatingPointError):
            return bad
        r = np.concatenate([(L - L_t).ravel(), wT * (T - T_t).ravel()])
        return r if np.all(np.isfinite(r)) else bad

    with threadpool_limits(limits=1, user_api="blas"):  # the same last digits with any BLAS thread count
        res = least_squares(
            resid,
            x0,
            bounds=(lo, hi),
            method="trf",
            x_scale="jac",
            ftol=1e-12,
            xtol=1e-12,
            gtol=1e-12,
            max_nfev=200 * (len(free) + 1),
        )
        x = res.x
        r = res.fun
        J = np.asarray(res.jac, float)
        m, p = r.size, len(free)
        s2 = float(r @ r) / max(m - p, 1)
        sig_int = _jacobian_sigma(J, s2)
    values = {f.name: float(_to_value(f, xi)) for f, xi in zip(free, x)}
    unc = {
        f.name: float(math.log(10.0) * values[f.name] * si) if f.log else float(si)
        for f, si in zip(free, sig_int)
    }
    at_bound = {
        f.name: bool(np.isclose(xi, a, atol=1e-7 * sp) or np.isclose(xi, b, atol=1e-7 * sp))
        for f, xi, a, b, sp in zip(free, x, lo, hi, span)
    }
    L, T = predict(x)
    rmse = float(np.sqrt(np.mean((L - L_t) ** 2)))
    return {
        "params": params_at(x, suns[0]),
        "x": x,
        "values": values,
        "uncertainty": unc,
        "at_bound": at_bound,
        "rank": int(np.linalg.matrix_rank(J)) if J.size else 0,
        "rmse": rmse,
        "rel_rmse": rmse / s if s > 0 else 0.0,
        "rmse_T": float(np.sqrt(np.mean((T - T_t) ** 2))),
        "target_rms": s,
        "n_views": int(len(L_t)),
        "nfev": int(res.nfev),
        "free": [f.name for f in free],
    }


@dataclass
class ModelFit:
    """The best parameters of one model for a physical fog, with uncertainties (see the module doc)."""

    model: str
    params: object
    values: dict
    uncertainty: dict
    spread: dict | None
    at_bound: dict
    rmse: float  #: RMSE of the inscatter over the views (radiance)
    rel_rmse: float  #: rmse / RMS of the physical inscatter
    rmse_T: float  #: RMSE of the transmittance
    target_rms: float
    n_views: int
    n_dirs: int
    sun_elevations: list
    start: str  #: "mapping" or "defaults"
    note: str = ""
    history: dict = field(default_factory=dict)

    @property
    def ill_posed(self) -> list[str]:
        """The parameters the views do not determine: uncertainty (or spread) larger than the value."""
        spread = self.spread or {}
        return [k for k, v in self.values.items() if max(self.uncertainty[k], spread.get(k, 0.0)) > abs(v)]

    def to_dict(self) -> dict:
        return {
            "model": self.model,
            "parameters": {
                k: {
                    "value": v,
                    **annotate(self.model, k, v),
                    "uncertainty": self.uncertainty[k],
                    **({"spread": self.spread[k]} if self.spread else {}),
                    **({"at_bound": True} if self.at_bound.get(k) else {}),
                }
                for k, v in self.values.items()
            },
            "settings": jsonable(param_dict(self.params)),
            "settings_units": {
                k: a for k, v in param_dict(self.params).items() if (a := annotate(self.model, k, v))
            },
            "error": {
                "rmse": self.rmse,
                "rel_rmse": self.rel_rmse,
                "rmse_transmittance": self.rmse_T,
                "target_rms": self.target_rms,
                "n_views": self.n_views,
            },
            "fit": {
                "n_dirs": self.n_dirs,
                "sun_elevations_deg": self.sun_elevations,
                "start": self.start,
                "uncertainty": "Jacobian at the optimum, cov = s^2 (J^T J)^-1, s^2 = SSE/(m - p)",
                "ill_posed": self.ill_posed,
                "spread": "|value(2N) - value(N)| between the last two direction counts, or with a "
                "fixed count |value(N turned about the vertical) - value(N)|",
                "loss": "sum of squared inscatter errors (RGB) + (w s)^2 sum of squared "
                "transmittance "
                "errors, s = RMS physical inscatter; model float64",
                "cannot_represent": self.note,
                **self.history,
            },
        }


def jsonable(d: dict[str, Any]) -> dict[str, Any]:
    """``d`` (model settings) ready for :func:`json.dumps`: nested parameter dataclasses as dicts,
    tuples as lists, infinities and NaN as strings; other values unchanged.

    Examples
    --------
    >>> jsonable({"cutOffDistance": math.inf, "color": (0.5, 0.5, 0.5)})
    {'cutOffDistance': 'inf', 'color': [0.5, 0.5, 0.5]}
    """
    out = {}
    for k, v in d.items():
        if dataclasses.is_dataclass(v):
            v = jsonable(param_dict(v))
        elif isinstance(v, float) and not math.isfinite(v):
            v = str(v)
        elif isinstance(v, tuple):
            v = list(v)
        out[k] = v
    return out


def fit_model(
    model: str | type,
    scene: PhysicalScene | dict[str, Any],
    views: int | Views | None = None,
    sun_elevations: Iterable[float] | None = None,
    *,
    params: dict[str, Any] | None = None,
    transmittance_weight: float = 1.0,
    rtol: float = FIT_RTOL,
    max_dirs: int = FIT_DIRECTIONS_MAX_GENERIC,
) -> ModelFit:
    """Fit ``model``'s free parameters to the physical fog of ``scene``.

    Parameters
    ----------
    model : str or type
        A registry name ("ue4", "unity", "hdrp", "filament", "altitude", "box", "godot", "bevy",
        "threejs", "babylon", "playcanvas"), ``module.path:Class`` or a model class.
    scene : PhysicalScene or dict
        The physical fog (an EXR's ``fogref.params`` dict or a scene; :func:`fogref.fit_model`
        also reads a scene XML path).
    views : int or Views, optional
        A fixed number of Fibonacci directions, or the views themselves; default: doubled from
        128 until converged (module doc).
    sun_elevations : sequence of float, optional
        Sun elevations [degrees] fitted together; default the scene's sun.
    params : dict, optional
        Fixed settings (the model's names) that override the start (e.g. a mode).
    transmittance_weight : float
        Weight ``w`` of the transmittance residuals, >= 0.
    rtol : float
        Convergence tolerance of the direction count, in (0, 1).

    Raises
    ------
    FogrefError
        Unknown model (with a "did you mean"), a model without parameter dataclass.
    fogref.errors.ParameterError
        A sun elevation outside [-90, 90], a bad weight or tolerance.
    """
    t0 = time.perf_counter()
    cls = model_class(model)
    pf = _scene(scene)
    if not (0.0 <= float(transmittance_weight) < math.inf):
        raise ParameterError("fit_model", "transmittance_weight", f"{transmittance_weight} outside [0, inf)")
    if not 0.0 < float(rtol) < 1.0:
        raise ParameterError("fit_model", "rtol", f"{rtol} outside (0, 1)")
    elevations = None if sun_elevations is None else [float(e) for e in sun_elevations]
    spec = fit_spec(cls)
    p0, source = start_params(cls, pf, spec, params)

    def one(v: Views, x0: np.ndarray | None = None) -> dict[str, Any]:
        return fit_to_targets(cls, physical_targets(pf, v, elevations), p0, spec, transmittance_weight, x0)

    spread: dict[str, float] | None = None
    history: dict[str, Any] = {}
    if isinstance(views, Views):
        r, n = one(views), len(views.D)
    elif views is not None:
        n = int(views)
        if not 8 <= n <= 100_000:
            raise ParameterError("fit_model", "views", f"{views} directions outside [8, 100000]")
        r = one(sample_views(pf.camera, n_dirs=n))
        turned = [one(rotated_views(sample_views(pf.camera, n_dirs=n), a), r["x"]) for a in RESAMPLE_TURNS]
        spread = {k: max(abs(t["values"][k] - v) for t in turned) for k, v in r["values"].items()}
    else:
        n = FIT_DIRECTIONS_START
        prev = one(sample_views(pf.camera, n_dirs=n))
        conv: list[dict[str, Any]] = []
        converged = False
        while True:
            conv.append({"n_dirs": n, "rel_rmse": prev["rel_rmse"], **prev["values"]})
            if 2 * n > max_dirs:
                r = prev
                break
            r = one(sample_views(pf.camera, n_dirs=2 * n), prev["x"])
            n *= 2
            spread = {k: abs(r["values"][k] - prev["values"][k]) for k in r["values"]}
            if all(spread[k] <= max(rtol * abs(r["values"][k]), r["uncertainty"][k]) for k in spread):
                converged = True
                conv.append({"n_dirs": n, "rel_rmse": r["rel_rmse"], **r["values"]})
                break
            prev = r
        history = {"directions_converged": converged, "convergence": conv}
    history["fit_seconds"] = time.perf_counter() - t0
    name = getattr(cls, "name", None) or f"{cls.__module__}:{cls.__qualname__}"
    fitted = "params values uncertainty at_bound rmse rel_rmse rmse_T target_rms n_views".split()
    return ModelFit(
        model=name,
        **{k: r[k] for k in fitted},
        spread=spread,
        n_dirs=n,
        sun_elevations=elevations if elevations is not None else [sun_elevation(pf)],
        start=source,
        note=spec.note,
        history=history,
    )


def _scene(scene: object) -> PhysicalScene:
    if isinstance(scene, PhysicalScene):
        return scene
    if isinstance(scene, dict):
        return PhysicalScene.from_params(scene)
    raise FogrefError(
        f"fit_model: scene {scene!r} is not a PhysicalScene or a fogref.params dict "
        "(fogref.fit_model reads a scene XML path)"
    )
