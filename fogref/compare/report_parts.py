"""What a ``compare`` report measures: the parts of a model or an engine's images, with their
references, noise and valid pixels, from the one comparison core (:mod:`fogref.compare.candidate`).

Parts are ``(H, W, 3)`` linear RGB: ``final``, ``transmittance``, ``inscatter``,
``attenuated_surface`` and, for an engine's images with both T and inscatter, ``composite``
(see :mod:`fogref.compare.report` for what each compares).  A report on a run of
:func:`fogref.compare.check.check` takes the model's images from the
:class:`~fogref.compare.results.CheckResult` (:func:`parts_from_check`): the model is
evaluated once.  A model's NaN, infinite or huge (> 1e30) value is refused, in ``check`` and in
the report alike (:func:`fogref.compare.candidate.evaluate_model`), with the count and the
first pixel.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from fogref.compare import noise
from fogref.compare.candidate import candidate_parts, evaluate_model, fog_parts
from fogref.errors import FogrefError
from fogref.gbuffer import COMPARED_PARTS, Truth, part_attribute
from fogref.mapping.build import current_parameters, model_label
from fogref.models.terms import annotate
from fogref.params import number as valid_number

#: A model run's parts (:data:`fogref.gbuffer.COMPARED_PARTS`).
PARTS: tuple[str, ...] = COMPARED_PARTS
#: Units of each part's values ("1": dimensionless; radiance is in the scene's units).
PART_UNITS: dict[str, str] = {
    "final": "radiance",
    "transmittance": "1",
    "inscatter": "radiance",
    "attenuated_surface": "radiance",
    "composite": "radiance",
}
REGIONS: tuple[str, ...] = ("all", "surface", "sky")
#: Every part a report may hold (model runs: PARTS; engine images add ``composite``).
ALL_PARTS: tuple[str, ...] = (*PARTS, "composite")


def model_description(model) -> dict | str:
    """JSON-ready parameters of ``model`` (see :func:`~fogref.mapping.build.current_parameters`)."""
    try:
        return json_safe(current_parameters(model))
    except (TypeError, AttributeError, ValueError, FogrefError):
        return repr(model)


def model_units(model) -> dict:
    """Each parameter's unit and colour space (:func:`fogref.models.terms.annotate`), where fogref
    knows them."""
    params = model_description(model)
    if not isinstance(params, dict):
        return {}
    name = model_label(model)
    return {k: a for k, v in params.items() if (a := annotate(name, k, v))}


def check_sky_distance(value, option: str = "sky_distance") -> float:
    """``value`` as a float if finite and > 0 [m]; ParameterError naming ``option`` otherwise
    (:func:`fogref.params.number`).

    >>> check_sky_distance(0, "sky_distance")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: compare: parameter 'sky_distance': 0 is outside (0, inf) m
    """
    return valid_number(value, option, source="compare", lo=0.0, lo_open=True, unit="m")


def evaluate_parts(truth: Truth, model, precision: str, sky_distance: float) -> dict:
    """Reference, model, noise and valid pixels of every part, from the one comparison core
    (:func:`fogref.compare.check.fog_parts`, which ``check`` uses too).

    Returns ``part -> {"reference", "model", "cov", "valid"}``: ``(H, W, 3)`` float64
    reference and model (a non-finite or huge model value is refused), the ``(H, W,
    3, 3)`` noise covariance of ``model - reference`` (the truth's noise, its channels'
    correlation, and the rounding floor), and the ``(H, W)`` bool pixels where the
    part is defined (``surface_valid`` for the composited parts, every pixel otherwise).
    """
    m = evaluate_model(truth, model, precision, sky_distance)
    out = _from_core(fog_parts(truth, m["T"], m["inscatter"]))
    out["attenuated_surface"] = _attenuated_surface(truth, m["T"])
    return {p: out[p] for p in PARTS}


def parts_from_check(truth: Truth, check, model, precision: str, sky_distance: float) -> dict | None:
    """:func:`evaluate_parts` from a :class:`~fogref.compare.results.CheckResult` of the same truth,
    model, precision and sky distance (the model's images it compared), so the model is evaluated
    once; None when ``check`` is not such a result."""
    cp = getattr(check, "parts", None)
    if (
        cp is None
        or cp.source is not model
        or cp.precision != precision
        or cp.sky_distance != float(sky_distance)
        or check.truth != str(truth.path)
        or "T" not in cp.parts
        or cp.parts["T"].shape != (*truth.shape, 3)
    ):
        return None
    out = _from_core(cp)
    out["attenuated_surface"] = _attenuated_surface(truth, cp.parts["T"])
    return {p: out[p] for p in PARTS}


def image_parts(truth: Truth, images) -> dict:
    """Reference, engine image, noise and valid pixels of every part an engine's images give.

    ``images``: :class:`fogref.compare.foreign.EngineImages` (``final``, ``transmittance``,
    ``inscatter``, any of them None).  Parts, as :func:`evaluate_parts` returns them:
    ``final`` (the engine's own picture against ``R,G,B``: meaningful only if its
    surface lighting matches the truth's), ``transmittance``, ``inscatter``,
    ``attenuated_surface`` (``surface * T_engine``, with a transmittance) and
    ``composite`` (``surface * T_engine + inscatter_engine`` against ``R,G,B``, with both:
    the engine's fog over the truth's own surface, the fair comparison).  The engine's
    images carry no noise; the covariance is the truth's (and the rounding floor).
    """
    out = _from_core(candidate_parts(truth, images))
    if images.transmittance is not None:
        out["attenuated_surface"] = _attenuated_surface(
            truth, np.asarray(images.transmittance, dtype=np.float64)
        )
    return {p: out[p] for p in ALL_PARTS if p in out}


def _from_core(cp) -> dict:
    """The comparison core's parts (:class:`fogref.compare.check.CandidateParts`) as a report's,
    ``T`` named ``transmittance``."""
    return {
        part_attribute(k): {
            "reference": cp.reference[k],
            "model": cp.parts[k],
            "cov": cp.noise_cov[k],
            "valid": cp.valid[k],
        }
        for k in cp.parts
    }


def _attenuated_surface(truth: Truth, T) -> dict:
    """``surface * T`` against the truth's ``attenuated_surface``, where ``surface`` is defined."""
    with np.errstate(
        invalid="ignore", over="ignore"
    ):  # a model's inf/NaN stays non-finite: counted, excluded
        att = truth.surface * T
        cov = truth.noise_cov("attenuated_surface") + noise.scaled(truth.noise_cov("surface"), T)
    return {
        "reference": truth.attenuated_surface,
        "model": att,
        "cov": noise.add_diagonal(cov, noise.rounding_var(truth.attenuated_surface, att)),
        "valid": truth.surface_valid,
    }


def truth_provenance(truth: Truth) -> dict:
    """What a report records about the truth it measured against: path,
    spp, seed, scene (path and SHA-256), overrides, pixel filter, variant, versions."""
    a = truth.attrs
    return {
        "path": str(truth.path),
        "schema": a.get("fogref.schema"),
        "spp": truth.spp,
        "seed": a.get("fogref.seed"),
        "scene": a.get("fogref.scene"),
        "scene_sha256": a.get("fogref.scene_sha256"),
        "overrides": a.get("fogref.overrides") or {},
        "pixel_filter": a.get("fogref.pixel_filter"),
        "pixel_exact": truth.pixel_exact,
        "variant": a.get("fogref.variant"),
        "fogref_version": a.get("fogref.version"),
        "mitsuba_version": a.get("fogref.mitsuba"),
    }


def json_safe(obj):
    """Numpy scalars/arrays -> Python; non-finite floats -> None (never NaN in JSON).

    >>> json_safe({"a": np.array([1.0, np.nan]), 2: (np.float32(0.5), np.bool_(True))})
    {'a': [1.0, None], '2': [0.5, True]}
    """
    if isinstance(obj, dict):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_safe(obj.tolist())
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return json_safe({f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)})
    if isinstance(obj, (np.bool_, bool)):
        return bool(obj)
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        f = float(obj)
        return f if math.isfinite(f) else None
    if obj is None or isinstance(obj, (int, str)):
        return obj
    return str(obj)
