"""What :func:`fogref.compare.check.check` compares: a candidate's parts, their references and noise.

A candidate is a fog model (anything with ``evaluate``), an engine's images
(:class:`fogref.compare.foreign.EngineImages` or a dict of images), or another
:class:`~fogref.gbuffer.Truth`.  :func:`candidate_parts` turns any of them into
:class:`CandidateParts`: per part, the candidate's image, the truth's matching image,
the noise covariance of their difference and the pixels where the part is defined.

Parts (``(H, W, 3)`` linear RGB):

* ``T``: the transmittance; ``inscatter``: the radiance the fog adds.
* ``final``: for a **model**, the model's fog composited over the truth's own
  surface radiance, as the engine composites, ``surface * T_model + inscatter_model``,
  against ``surface * T + inscatter`` (pixels where ``surface`` is defined,
  ``truth.surface_valid``); the surface is common to both, so only the fog's error is
  measured.  For **foreign images**, the engine's own final image against the
  truth's ``R,G,B``: it means something only if the engine's surface lighting
  matches the truth's ``surface`` part.
* ``composite``: foreign images with both T and inscatter: the engine's fog over
  the truth's surface (the fair version of ``final``).
"""

from __future__ import annotations

import inspect
import os
import traceback
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fogref.compare import noise
from fogref.errors import FogrefError, ParameterError
from fogref.gbuffer import Truth, load_truth
from fogref.mapping.build import model_label
from fogref.models.base import SKY_DISTANCE as DEFAULT_SKY_DISTANCE
from fogref.params import number as valid_number
from fogref.params import path as valid_path


@dataclass
class CandidateParts:
    """A candidate's images and the noise of its error, as :func:`~fogref.compare.check.check` compares them.

    parts:     part name -> ``(H, W, 3)`` candidate image.
    reference: part name -> ``(H, W, 3)`` the truth's matching image.
    noise_cov: part name -> ``(H, W, 3, 3)`` covariance of ``candidate - reference`` due to
               Monte Carlo noise (the truth's, plus the candidate's own if it has any) and
               rounding (:func:`fogref.compare.noise.rounding_var`) [units²].
    ref_cov:   part name -> ``(H, W, 3, 3)`` noise covariance of ``reference``.
    valid:     part name -> ``(H, W)`` bool, pixels where the part is defined.
    name:      what the candidate is, for messages.
    source:    the candidate object itself (a model: the report reuses these parts only for it).
    precision, sky_distance: how a model was evaluated (None for images).
    """

    parts: dict
    reference: dict
    noise_cov: dict
    ref_cov: dict
    valid: dict
    name: str = "candidate"
    source: object = None
    precision: str | None = None
    sky_distance: float | None = None


#: The largest magnitude a candidate's value may have.  Far above any fog's radiance or
#: transmittance (and above float32's 3.4e38, so no engine image reaches it), and low enough that
#: every statistic of ``check`` and the report (sums of squared errors, and of their squares for
#: the standard errors) stays finite in float64.  A larger value is refused with this reason
#: instead of turning a metric into null.
LARGEST_VALUE = 1e30


def _first_pixel(mask) -> str:
    ys, xs = np.nonzero(mask)
    return f"(x={xs[0]}, y={ys[0]})"


def _as_image(x, shape, what: str, nonfinite: str = "refuse") -> np.ndarray:
    """``x`` as a float64 ``shape + (3,)`` image; FogrefError for the wrong shape or (``"refuse"``)
    a NaN, an infinity or a value beyond :data:`LARGEST_VALUE`, with the count and the first pixel."""
    try:
        a = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise FogrefError(f"{what}: not an array of numbers ({type(x).__name__}: {e})") from None
    try:
        a = np.broadcast_to(a, (*shape, 3))
    except ValueError:
        raise FogrefError(
            f"{what}: shape {a.shape}, expected {(*shape, 3)} (the truth's H, W, RGB)"
        ) from None
    if nonfinite == "keep":
        return a
    bad = ~np.isfinite(a).all(-1)
    if bad.any():
        raise FogrefError(
            f"{what}: {int(bad.sum())} pixel(s) are non-finite (NaN or inf), first at "
            f"{_first_pixel(bad)}; "
            "a candidate must be finite everywhere (fogref refuses it rather than drop pixels)"
        )
    with np.errstate(invalid="ignore"):
        huge = (np.abs(a) > LARGEST_VALUE).any(-1)
    if huge.any():
        y, x_ = np.argwhere(huge)[0]
        raise FogrefError(
            f"{what}: {int(huge.sum())} pixel(s) beyond ±{LARGEST_VALUE:g}, first at "
            f"{_first_pixel(huge)} ({np.abs(a[y, x_]).max():.3g}): too large to measure (its "
            "squared errors overflow float64); no fog comes near this: check its units"
        )
    return a


def as_truth(truth, what: str = "truth") -> Truth:
    """``truth`` as a :class:`~fogref.gbuffer.Truth`: a Truth as it is, a path (str or os.PathLike)
    read with :func:`fogref.gbuffer.load_truth`; else ParameterError naming ``what``.

    >>> as_truth(3)
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: api: parameter 'truth': expected a Truth or the path of a ... got int
    """
    if isinstance(truth, Truth):
        return truth
    if isinstance(truth, (str, os.PathLike)):
        return load_truth(valid_path(truth, what, source="api", must_exist=True))
    raise ParameterError(
        "api", what, f"expected a Truth or the path of a ground-truth EXR, got {type(truth).__name__}"
    )


def evaluate_model(
    truth: Truth,
    model,
    precision: str = "float32",
    sky_distance: float = DEFAULT_SKY_DISTANCE,
    nonfinite: str = "refuse",
) -> dict:
    """A fog model evaluated on a truth's G-buffer: ``{"T", "inscatter"}`` -> ``(H, W, 3)``.

    The model shades the point each pixel sees, ``truth.world_positions(sky_distance)``
    (surface points; ``camera + view * sky_distance`` for sky pixels), from
    ``truth.camera``, at ``precision`` (``"float32"`` or ``"float64"``).

    Parameters
    ----------
    truth : Truth or path
        The ground truth, or the path of its EXR (read with :func:`fogref.gbuffer.load_truth`).
    model : object
        Anything with ``evaluate(camera (3,), positions (H, W, 3), precision)``
        returning an object with ``transmittance`` and ``inscatter`` (broadcastable to
        ``(H, W, 3)``); world frame y-up, metres.  A model whose ``evaluate`` also takes
        ``hit`` (``(H, W)`` bool, the pixel sees a surface; False: sky) or ``distance``
        (``(H, W)`` [m] to the surface, 0 for sky), or ``**kwargs``, is given them.
    precision : str
        ``"float32"`` or ``"float64"``.
    sky_distance : float
        Distance [m] at which sky pixels are fogged, > 0.
    nonfinite : str
        ``"refuse"`` (default): a non-finite model value is a FogrefError; ``"keep"``:
        returned as it is (``compare`` excludes and counts such pixels).

    Returns
    -------
    dict
        ``{"T": (H, W, 3), "inscatter": (H, W, 3)}`` float64, finite unless ``"keep"``.

    Raises
    ------
    FogrefError
        The model returns the wrong shape or (``"refuse"``) a non-finite value.

    Examples
    --------
    >>> from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams
    >>> from fogref.compare.synthetic import synthetic_truth
    >>> model = UE4ExponentialHeightFog(UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2))
    >>> parts = evaluate_model(synthetic_truth(model), model)
    >>> parts["T"].shape, bool((parts["T"] <= 1).all())
    ((18, 32, 3), True)
    """
    if precision not in ("float32", "float64"):
        raise FogrefError(f"precision must be 'float32' or 'float64', got {precision!r}")
    truth = as_truth(truth)
    sky_distance = valid_number(sky_distance, "sky_distance", source="api", lo=0.0, lo_open=True, unit="m")
    if nonfinite not in ("refuse", "keep"):
        raise ParameterError("api", "nonfinite", f"{nonfinite!r} is not one of refuse, keep")
    if not callable(getattr(model, "evaluate", None)):
        raise FogrefError(f"{model!r} is not a fog model: it has no evaluate(camera, positions, precision)")
    extra = {
        k: v for k, v in (("hit", truth.hit), ("distance", truth.distance)) if _accepts(model.evaluate, k)
    }
    name = model_label(model)
    try:
        positions = truth.world_positions(sky_distance)
        result = model.evaluate(truth.camera, positions, precision=precision, **extra)
    except FogrefError as e:
        raise FogrefError(f"model '{name}': evaluate() refused: {e}") from e
    except Exception as e:  # the user's code failed: one line naming the model, the error and where
        raise FogrefError(
            f"model '{name}': evaluate() raised {type(e).__name__}: {_one_line(e)}{_where(e)}"
        ) from e
    for attr in ("transmittance", "inscatter"):
        if not hasattr(result, attr):
            raise FogrefError(
                f"model '{name}': evaluate() returned {type(result).__name__} without "
                f"'{attr}' (expected an object with transmittance and inscatter)"
            )
    return {
        "T": _as_image(result.transmittance, truth.shape, f"model '{name}' transmittance", nonfinite),
        "inscatter": _as_image(result.inscatter, truth.shape, f"model '{name}' inscatter", nonfinite),
    }


def _one_line(e: BaseException) -> str:
    text = str(e).strip()
    return text.splitlines()[0] if text else "(no message)"


def _where(e: BaseException) -> str:
    """`` (at file.py:12 in evaluate)``: the innermost frame of ``e``'s traceback."""
    tb = traceback.extract_tb(e.__traceback__)
    if not tb:
        return ""
    f = tb[-1]
    return f" (at {Path(f.filename).name}:{f.lineno} in {f.name})"


def _accepts(fn, name: str) -> bool:
    try:
        params = inspect.signature(fn).parameters
    except (TypeError, ValueError):
        return False
    return name in params or any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values())


def _composite_parts(truth: Truth, T, L, cand_cov_T=None, cand_cov_L=None):
    """The fog ``(T, L)`` over the truth's surface vs the truth's own fog over it.

    Returns ``(candidate, reference, noise_cov, ref_cov)``; the noise of the difference
    is ``Cov(L_truth) + s Cov(T_truth) s + (T - T_truth) Cov(surface) (T - T_truth)``
    (channel-wise scaled covariances; plus the candidate's own where given).  The
    covariance between the truth's parts (one path feeds all) is left out: it enters
    only through ``T - T_truth``, and ``T`` of a pixel-exact truth has no noise.
    """
    s = truth.surface
    cand = s * T + L
    ref = s * truth.transmittance + truth.inscatter
    cov = (
        truth.noise_cov("inscatter")
        + noise.scaled(truth.noise_cov("T"), s)
        + noise.scaled(truth.noise_cov("surface"), T - truth.transmittance)
    )
    if cand_cov_T is not None:
        cov = cov + cand_cov_L + noise.scaled(cand_cov_T, s)
    return cand, ref, cov, truth.noise_cov("final")


def fog_parts(truth: Truth, T, L, name: str = "fog") -> CandidateParts:
    """A noise-free fog ``(T, L)`` (a model's, ``(H, W, 3)`` each) as
    :func:`~fogref.compare.check.check` compares it: parts ``T``, ``inscatter`` and ``final`` (the fog
    over the truth's surface, where that is defined), each with its reference and noise covariance.
    Non-finite values stay."""
    every = np.ones(truth.shape, bool)
    with np.errstate(invalid="ignore", over="ignore"):
        final = _composite_parts(truth, T, L)
        parts = {
            "T": (T, truth.transmittance, truth.noise_cov("T"), truth.noise_cov("T"), every),
            "inscatter": (
                L,
                truth.inscatter,
                truth.noise_cov("inscatter"),
                truth.noise_cov("inscatter"),
                every,
            ),
            "final": (*final, truth.surface_valid),
        }
        cov = {k: noise.add_diagonal(v[2], noise.rounding_var(v[1], v[0])) for k, v in parts.items()}
    return CandidateParts(
        {k: v[0] for k, v in parts.items()},
        {k: v[1] for k, v in parts.items()},
        cov,
        {k: v[3] for k, v in parts.items()},
        {k: v[4] for k, v in parts.items()},
        name=name,
    )


def candidate_parts(
    truth: Truth, candidate, precision: str = "float32", sky_distance: float = DEFAULT_SKY_DISTANCE
) -> CandidateParts:
    """What :func:`~fogref.compare.check.check` compares, for any kind of candidate.

    ``candidate`` is one of:

    * a fog model (has ``evaluate``): parts ``T``, ``inscatter``, ``final`` (its fog over
      the truth's surface);
    * :class:`fogref.compare.foreign.EngineImages` (an engine's images): the parts it has,
      ``final`` direct, and ``composite`` when it has both T and inscatter;
    * another :class:`~fogref.gbuffer.Truth` (e.g. an independent render): ``T``,
      ``inscatter``, ``final``, with both truths' noise taken out;
    * a dict with any of ``"T"``, ``"inscatter"``, ``"final"`` -> ``(H, W, 3)`` images
      (taken as noise-free engine images).

    Every part's noise covariance includes the rounding floor of
    :func:`fogref.compare.noise.rounding_var`.

    Examples
    --------
    >>> from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams
    >>> from fogref.compare.synthetic import synthetic_truth
    >>> model = UE4ExponentialHeightFog(UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2))
    >>> sorted(candidate_parts(synthetic_truth(model), model).parts)
    ['T', 'final', 'inscatter']
    """
    truth = as_truth(truth)
    valid_all = np.ones(truth.shape, bool)
    T_ref, L_ref = truth.transmittance, truth.inscatter
    parts, ref, cov, rcov, valid = {}, {}, {}, {}, {}

    def put(name, c, r, v, rv, m):
        parts[name], ref[name], rcov[name], valid[name] = c, r, rv, m
        cov[name] = noise.add_diagonal(v, noise.rounding_var(r, c))

    if isinstance(candidate, Truth):
        if candidate.shape != truth.shape:
            raise FogrefError(
                f"{candidate.path}: {candidate.shape[1]}x{candidate.shape[0]} px, but the truth "
                f"{truth.path} is {truth.shape[1]}x{truth.shape[0]}"
            )
        for part, c, r in (("T", candidate.transmittance, T_ref), ("inscatter", candidate.inscatter, L_ref)):
            put(
                part,
                c,
                r,
                truth.noise_cov(part) + candidate.noise_cov(part),
                truth.noise_cov(part),
                valid_all,
            )
        put(
            "final",
            *_composite_parts(
                truth,
                candidate.transmittance,
                candidate.inscatter,
                candidate.noise_cov("T"),
                candidate.noise_cov("inscatter"),
            ),
            truth.surface_valid,
        )
        return CandidateParts(parts, ref, cov, rcov, valid, name=str(candidate.path))

    if callable(getattr(candidate, "evaluate", None)):
        m = evaluate_model(truth, candidate, precision, sky_distance)
        name = model_label(candidate)
        cp = fog_parts(truth, m["T"], m["inscatter"], name=f"model '{name}'")
        cp.source, cp.precision, cp.sky_distance = candidate, precision, float(sky_distance)
        return cp

    if isinstance(candidate, dict):
        images, name = candidate, "images"
    elif hasattr(candidate, "as_dict"):
        images, name = candidate.as_dict(), str(getattr(candidate, "description", "engine images"))
    else:
        raise FogrefError(
            f"cannot check {type(candidate).__name__}: give a fog model (with evaluate), "
            "EngineImages, a Truth, or a dict of 'T'/'inscatter'/'final' images"
        )
    unknown = sorted(set(images) - {"T", "inscatter", "final"})
    if unknown:
        raise FogrefError(f"unknown image part(s) {unknown}: expected 'T', 'inscatter', 'final'")
    img = {k: _as_image(v, truth.shape, f"{name} {k}") for k, v in images.items() if v is not None}
    if not img:
        raise FogrefError(f"{name}: no image given (need at least one of final, T, inscatter)")
    for part, r in (("T", T_ref), ("inscatter", L_ref), ("final", truth.final)):
        if part in img:
            put(part, img[part], r, truth.noise_cov(part), truth.noise_cov(part), valid_all)
    if "T" in img and "inscatter" in img:
        put("composite", *_composite_parts(truth, img["T"], img["inscatter"]), truth.surface_valid)
    return CandidateParts(parts, ref, cov, rcov, valid, name=name)
