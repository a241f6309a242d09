"""Unreal's fog fitted to the physical single scattering, and its ``from_physical``.

:func:`fit_unreal` matches Unreal's inscatter (:mod:`fogref.mapping.unreal_basis`: linear in
its two colours, solved by non-negative least squares) to the closed-form physical single
scattering of sun and sky over sample views from the camera (:mod:`fogref.mapping.views`).
The exponent ``n`` and the start distance are found by bounded Brent searches, over ``log10 n``
inside one over the start (:class:`~fogref.mapping.unreal_basis.ColourLoss`: one model
evaluation per start distance, the colours in closed form); density, falloff and height come
from the exact mapping :func:`~fogref.mapping.unreal_basis.base_params`.
:func:`ue4_from_physical` registers the result as the ``"ue4"`` mapping;
:func:`fogref.models.ue4.ue4_to_medium` is the other direction (Unreal's settings to the physical
medium of the same extinction).
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field, replace

import numpy as np
from threadpoolctl import threadpool_limits

from fogref.mapping.fit_cache import load_fit, store_fit
from fogref.mapping.physical import PhysicalScene
from fogref.mapping.registry import register_mapping
from fogref.mapping.unreal_basis import (
    LOG_N_RANGE,
    MAX_START_CM,
    Basis,
    ColourLoss,
    base_params,
    solve_colours,
    unreal_basis,
    unreal_inscatter,
)
from fogref.mapping.views import Views, fibonacci_directions, physical_single_scattering, sample_views
from fogref.models.base import SKY_DISTANCE
from fogref.models.terms import annotate, unreal_field
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams

__all__ = [
    "Basis",
    "ColourLoss",
    "EXPONENT_RANGE",
    "FIT_DIRECTIONS_MAX",
    "FIT_DIRECTIONS_START",
    "FIT_RTOL",
    "FitResult",
    "LOG_N_RANGE",
    "MAX_START_CM",
    "Views",
    "base_params",
    "fibonacci_directions",
    "fit_unreal",
    "physical_single_scattering",
    "sample_views",
    "solve_colours",
    "ue4_from_physical",
    "unreal_basis",
    "unreal_inscatter",
]

#: Unreal clamps DirectionalInscatteringExponent to this range.
EXPONENT_RANGE = (1e-6, 1000.0)
#: :func:`fit_unreal` without views: the first number of Fibonacci directions, doubled
#: until the fit converges (:data:`FIT_RTOL`), and the most it doubles to.
FIT_DIRECTIONS_START = 128
FIT_DIRECTIONS_MAX = 16384
#: :func:`fit_unreal`'s convergence tolerance (relative) between two doublings.
FIT_RTOL = 5e-3


@dataclass
class FitResult:
    """Best Unreal parameters for a physical fog, and how well they do on the views."""

    params: UE4FogParams
    rmse: float  #: RMSE of the inscatter over the views (radiance)
    rel_rmse: float  #: rmse / RMS of the physical inscatter
    target_rms: float
    n_views: int
    sun_attenuation: bool
    fit_start: bool
    history: dict = field(default_factory=dict)

    def editor_properties(self) -> dict:
        """The fitted values under the names of Unreal's details panel."""
        p = self.params
        return {
            "Fog Density": p.FogDensity,
            "Fog Height Falloff": p.FogHeightFalloff,
            "Fog Height Offset": p.FogHeight,
            "Fog Inscattering Color": list(p.FogInscatteringColor),
            "Directional Inscattering Color": list(p.DirectionalInscatteringColor),
            "Directional Inscattering Exponent": p.DirectionalInscatteringExponent,
            "Directional Inscattering Start Distance": p.DirectionalInscatteringStartDistance,
            "Start Distance": p.StartDistance,
            "Fog Max Opacity": p.FogMaxOpacity,
            "Fog Cutoff Distance": p.FogCutoffDistance,
        }

    def to_dict(self) -> dict:
        p = self.params
        return {
            "unreal": {
                "FogDensity": p.FogDensity,
                "FogHeightFalloff": p.FogHeightFalloff,
                "FogHeight_cm": p.FogHeight,
                "FogInscatteringColor": list(p.FogInscatteringColor),
                "DirectionalInscatteringColor": list(p.DirectionalInscatteringColor),
                "DirectionalInscatteringExponent": p.DirectionalInscatteringExponent,
                "DirectionalInscatteringStartDistance_cm": p.DirectionalInscatteringStartDistance,
                "InscatteringLightDirection_unreal": list(p.InscatteringLightDirection or ()),
                "SunLuminance": p.SunLuminance,
                "SecondFogData": {
                    "FogDensity": p.SecondFogData.FogDensity,
                    "FogHeightFalloff": p.SecondFogData.FogHeightFalloff,
                    "FogHeightOffset_cm": p.SecondFogData.FogHeightOffset,
                },
            },
            "settings": dataclasses.asdict(p),
            "unreal_editor": self.editor_properties(),
            "unreal_editor_units": {
                k: annotate("ue4", unreal_field(k), v) for k, v in self.editor_properties().items()
            },
            "error": {
                "rmse": self.rmse,
                "rel_rmse": self.rel_rmse,
                "target_rms": self.target_rms,
                "n_views": self.n_views,
            },
            "fit": {
                "sun_attenuation_in_target": self.sun_attenuation,
                "start_distance_fitted": self.fit_start,
                "loss": "mean squared inscatter error over views (all RGB channels), model float64",
                **self.history,
            },
        }


def fit_unreal(
    pf: PhysicalScene,
    views: Views | None = None,
    *,
    sun_attenuation: bool = True,
    fit_start: bool = True,
    target: np.ndarray | None = None,
    sky_distance: float = SKY_DISTANCE,
    exponent: float | None = None,
    rtol: float = FIT_RTOL,
) -> FitResult:
    """Best FogInscatteringColor, DirectionalInscatteringColor, exponent and (if
    ``fit_start``) DirectionalInscatteringStartDistance for ``pf``: Unreal's one fit.

    ``fogref fit``, ``--from-scene`` (:func:`ue4_from_physical`), ``fogref study`` and
    the sweeps all call it without ``views``.

    The loss is the mean squared inscatter error (all RGB channels) over views
    from the camera: Fibonacci directions with ``d_y >= -0.5`` at 12 distances from
    10 m to 20 km, plus the sky for upward directions (:func:`sample_views`); it is a
    quadrature of the integral of the squared error over that part of the sphere.

    **Direction count (``views`` not given).**  The fit runs with
    :data:`FIT_DIRECTIONS_START` (128) directions, then 256, 512, ... until two
    consecutive counts agree within ``rtol`` (default :data:`FIT_RTOL` = 5e-3):
    the exponent relatively, each colour to ``rtol`` of its largest channel, the
    start distance to ``rtol`` of max(start, 100 m); the exponent is not compared
    when the lobe is off (DirectionalInscatteringColor < 1e-6 of FogInscatteringColor).
    The finer fit is returned; it stops at :data:`FIT_DIRECTIONS_MAX` (16384) with
    ``history["directions_converged"] = False``.  ``history`` records each count's
    exponent, colours, start and relative RMSE (``"convergence"``), the count used
    (``"n_dirs"``) and the wall time (``"fit_seconds"``).  Measured on
    scenes/valley.xml (g = 0.6, sun 8° high): exponent 10.84, 15.91, 14.33, 14.23,
    14.187 at 128 ... 2048 directions (stops at 2048; 4096 gives 14.189); relative RMSE
    0.177; about 0.5 s at a load average of 5 on 2 cores, 1.8 s at 15-190
    (``reports/benchmarks/fit.md``).  A Gauss–Legendre product quadrature
    of the same loss agrees within 0.5 % (tests/test_unreal_fit_one.py).  The
    result is kept on disk (:mod:`fogref.mapping.fit_cache`), so every later call with the same
    scene and settings, in any process, reads it (``history["from_cache"]``).

    Parameters
    ----------
    pf : PhysicalScene
    views : Views, optional
        Fit on exactly these views instead (``fogref fit --directions N``, the lobe table).
    sun_attenuation : bool
        Target with the sun's attenuation in the fog (the physics) or without it
        (the lobe-only fit of the error budget).
    fit_start : bool
        Fit DirectionalInscatteringStartDistance [cm], in [0, 1e5]; else 0.
    target : ndarray (N, 3), optional
        The inscatter to match on ``views`` (needs ``views``; default: the closed-form
        physical single scattering of sun and sky, :func:`physical_single_scattering`).
    sky_distance : float
        Where the model fogs sky views [m].
    exponent : float, optional
        Keep the exponent fixed (only colours, and start, are fitted).
    rtol : float
        Convergence tolerance of the direction count, in (0, 1).

    Notes
    -----
    BLAS runs on one thread here (``threadpoolctl``): a threaded BLAS splits a sum of more than
    about 10000 terms over its threads, so the last digits would depend on their number (a Dask
    worker has one, the command line every core; ``--directions 32768`` gave values 1e-10 apart).
    """
    with threadpool_limits(limits=1, user_api="blas"):
        return _fit_unreal(
            pf,
            views,
            sun_attenuation=sun_attenuation,
            fit_start=fit_start,
            target=target,
            sky_distance=sky_distance,
            exponent=exponent,
            rtol=rtol,
        )


def _fit_unreal(
    pf: PhysicalScene,
    views: Views | None,
    *,
    sun_attenuation: bool,
    fit_start: bool,
    target: np.ndarray | None,
    sky_distance: float,
    exponent: float | None,
    rtol: float,
) -> FitResult:
    """:func:`fit_unreal` with BLAS's thread count already set (its arguments)."""
    if views is None:
        if target is not None:
            raise ValueError("fit_unreal: a target needs the views it was computed on")
        n_fixed = None if exponent is None else float(exponent)
        settings = {
            "fit": "fit_unreal",
            "sun_attenuation": bool(sun_attenuation),
            "fit_start": bool(fit_start),
            "sky_distance": float(sky_distance),
            "exponent": n_fixed,
            "rtol": float(rtol),
        }
        stored = load_fit(pf, settings)
        if stored is not None:
            return _from_record(pf, stored)
        r = _fit_converged(pf, sun_attenuation, fit_start, float(sky_distance), n_fixed, float(rtol))
        store_fit(pf, settings, _to_record(r))
        return r
    if target is None:
        target = physical_single_scattering(pf, views, sun_attenuation=sun_attenuation)
    target = np.asarray(target, dtype=float)
    N = len(views.D)
    loss = ColourLoss(pf, views, target, sky_distance)
    ln0, s0 = loss.minimise(None if exponent is None else math.log10(exponent), fit_start)
    cf, cd, best = solve_colours(loss.basis(ln0, s0), target)
    params = base_params(
        pf,
        FogInscatteringColor=tuple(cf),
        DirectionalInscatteringColor=tuple(cd),
        DirectionalInscatteringExponent=10.0**ln0,
        DirectionalInscatteringStartDistance=s0 if fit_start else 0.0,
    )
    rmse = math.sqrt(best / (3 * N))
    trms = math.sqrt(float(np.mean(target**2)))
    return FitResult(
        params=params,
        rmse=rmse,
        rel_rmse=rmse / trms if trms > 0 else 0.0,
        target_rms=trms,
        n_views=N,
        sun_attenuation=sun_attenuation,
        fit_start=fit_start,
        history={"model_evaluations": loss.model_evaluations, "colour_solves": loss.colour_solves},
    )


def _agree(p: UE4FogParams, q: UE4FogParams, rtol: float) -> bool:
    """Whether two fits agree within ``rtol`` (the criterion of :func:`fit_unreal`)."""
    for a, b in (
        (p.FogInscatteringColor, q.FogInscatteringColor),
        (p.DirectionalInscatteringColor, q.DirectionalInscatteringColor),
    ):
        if max(abs(x - y) for x, y in zip(a, b)) > rtol * max(max(b), 1e-300):
            return False
    lobe_on = max(q.DirectionalInscatteringColor) > 1e-6 * max(max(q.FogInscatteringColor), 1e-300)
    n_p, n_q = p.DirectionalInscatteringExponent, q.DirectionalInscatteringExponent
    s_p, s_q = p.DirectionalInscatteringStartDistance, q.DirectionalInscatteringStartDistance
    return (not lobe_on or abs(n_p - n_q) <= rtol * n_q) and abs(s_p - s_q) <= rtol * max(s_q, 1.0e4)


def _to_record(r: FitResult) -> dict:
    """The fitted values of ``r`` as JSON values (the rest of its parameters follow from the scene)."""
    p = r.params
    return {
        "FogInscatteringColor": list(p.FogInscatteringColor),
        "DirectionalInscatteringColor": list(p.DirectionalInscatteringColor),
        "DirectionalInscatteringExponent": p.DirectionalInscatteringExponent,
        "DirectionalInscatteringStartDistance": p.DirectionalInscatteringStartDistance,
        "rmse": r.rmse,
        "rel_rmse": r.rel_rmse,
        "target_rms": r.target_rms,
        "n_views": r.n_views,
        "sun_attenuation": r.sun_attenuation,
        "fit_start": r.fit_start,
        "history": r.history,
    }


def _from_record(pf: PhysicalScene, d: dict) -> FitResult:
    """The :class:`FitResult` of :func:`_to_record`'s ``d`` for the scene ``pf`` it was fitted to."""
    params = base_params(
        pf,
        FogInscatteringColor=tuple(d["FogInscatteringColor"]),
        DirectionalInscatteringColor=tuple(d["DirectionalInscatteringColor"]),
        DirectionalInscatteringExponent=d["DirectionalInscatteringExponent"],
        DirectionalInscatteringStartDistance=d["DirectionalInscatteringStartDistance"],
    )
    fields = ("rmse", "rel_rmse", "target_rms", "n_views", "sun_attenuation", "fit_start")
    return FitResult(params=params, **{k: d[k] for k in fields}, history={**d["history"], "from_cache": True})


def _fit_converged(
    pf: PhysicalScene,
    sun_attenuation: bool,
    fit_start: bool,
    sky_distance: float,
    exponent: float | None,
    rtol: float,
) -> FitResult:
    """:func:`fit_unreal` with the direction count doubled until two fits agree within ``rtol``."""
    if not 0.0 < rtol < 1.0:
        raise ValueError(f"fit_unreal: rtol {rtol!r} must be in (0, 1)")
    t0 = time.perf_counter()
    steps, prev, n = [], None, FIT_DIRECTIONS_START
    while True:
        r = _fit_unreal(
            pf,
            sample_views(pf.camera, n_dirs=n),
            sun_attenuation=sun_attenuation,
            fit_start=fit_start,
            target=None,
            sky_distance=sky_distance,
            exponent=exponent,
            rtol=rtol,
        )
        q = r.params
        steps.append(
            {
                "n_dirs": n,
                "exponent": q.DirectionalInscatteringExponent,
                "FogInscatteringColor": list(q.FogInscatteringColor),
                "DirectionalInscatteringColor": list(q.DirectionalInscatteringColor),
                "DirectionalInscatteringStartDistance": q.DirectionalInscatteringStartDistance,
                "rel_rmse": r.rel_rmse,
            }
        )
        converged = prev is not None and _agree(prev.params, q, rtol)
        if converged or n >= FIT_DIRECTIONS_MAX:
            break
        prev, n = r, 2 * n
    r.history.update(
        n_dirs=n,
        directions_converged=converged,
        rtol=rtol,
        convergence=steps,
        fit_seconds=time.perf_counter() - t0,
    )
    return r


@register_mapping("ue4")
def ue4_from_physical(ps: PhysicalScene) -> UE4ExponentialHeightFog:
    """The Unreal fog that best represents a physical scene.

    Density, falloff, height (and the second layer) are exact
    (:func:`~fogref.mapping.unreal_basis.base_params`, the inverse of :func:`fogref.models.ue4.ue4_to_medium`;
    profiles "exponential" with 1–2 layers and "homogeneous", unbounded, grey ``sigma_t``), so
    the float64 transmittance is the physical one.  With a sun, FogInscatteringColor,
    DirectionalInscatteringColor, DirectionalInscatteringExponent and
    DirectionalInscatteringStartDistance come from :func:`fit_unreal`
    (closed-form sun + sky single scattering, sun attenuation included; the
    direction count chosen by its convergence criterion, about 0.5 s on a lightly loaded core,
    kept on disk per scene, :mod:`fogref.mapping.fit_cache`); the light direction is the scene's sun
    (:meth:`~fogref.models.ue4.UE4FogParams.with_sun`).  Without a sun: no
    directional inscattering and FogInscatteringColor = albedo * sky radiance.
    Other fields: start distances 0, max opacity 1, no cutoff.

    Parameters
    ----------
    ps : PhysicalScene

    Returns
    -------
    UE4ExponentialHeightFog

    Raises
    ------
    fogref.errors.ParameterError
        Naming 'profile' for "hdrp", "powerlaw", "box" or any bounded fog,
        'sigma_t' for a coloured extinction.

    Examples
    --------
    >>> from fogref.media import ExpLayer, FogMedium
    >>> ps = PhysicalScene(FogMedium(sigma_t=0.002, albedo=0.9, layers=(ExpLayer(1.0, 0.02, 0.0),)),
    ...                    sky_radiance=(0.2, 0.3, 0.5))
    >>> p = ue4_from_physical(ps).params
    >>> round(p.FogHeightFalloff, 4), [round(c, 3) for c in p.FogInscatteringColor]
    (0.2885, [0.18, 0.27, 0.45])
    """
    ps.require_profile(
        "Unreal",
        ("exponential", "homogeneous"),
        "Unreal's height fog is 1-2 exponential layers (homogeneous = falloff 0)",
    )
    ps.require_unbounded("Unreal")
    ps.grey_sigma_t("Unreal")
    colours = {"FogInscatteringColor": ps.sky_colour(), "DirectionalInscatteringColor": (0.0, 0.0, 0.0)}
    p = replace(base_params(ps, EndDistance=0.0, **colours), InscatteringLightDirection=None)
    if not ps.has_sun:
        return UE4ExponentialHeightFog(p)
    fit = fit_unreal(ps)
    q = fit.params
    p = replace(
        p,
        FogInscatteringColor=q.FogInscatteringColor,
        DirectionalInscatteringColor=q.DirectionalInscatteringColor,
        DirectionalInscatteringExponent=q.DirectionalInscatteringExponent,
        DirectionalInscatteringStartDistance=q.DirectionalInscatteringStartDistance,
    )
    return UE4ExponentialHeightFog(p.with_sun(ps.sun_direction, 1.0))
