"""The fog a user gives ``fogref scene``: in physical units, or as Unreal's Exponential Height Fog
editor values, as the physical ``heightfog`` of a fogref scene.

:func:`fog_from_physical` validates extinction, falloff, heights, a second layer
and box bounds (y-up, metres) plus albedo and the Henyey-Greenstein ``g`` against
:data:`fogref.scene.vocabulary.PHYSICAL` and ``SCATTERING``, and returns the ``heightfog`` XML
parameters.  :func:`fog_from_unreal` maps FogDensity, FogHeightFalloff, FogHeight and
SecondFogData exactly (:func:`fogref.models.ue4.ue4_to_medium`: Unreal is z-up,
centimetres; ``sigma_t = 100 (ln 2)^2 FogDensity/1000`` per metre at
``FogHeight/100`` m, ``falloff = 100 ln 2 FogHeightFalloff/1000`` per metre; see
``docs/design.md`` section 3.1).  The editor values with no physical counterpart
(:data:`UNREAL_IGNORED`: FogInscatteringColor, DirectionalInscattering*,
StartDistance, FogMaxOpacity, FogCutoffDistance, EndDistance) are checked and
reported as notes, never silently dropped.
"""

from __future__ import annotations

import difflib
from typing import Any

from fogref.errors import ParameterError
from fogref.media import local_fog_volume as lfv
from fogref.media.params import medium_from_params
from fogref.models.ue4 import (
    CM_PER_M,
    SecondFogData,
    UE4FogParams,
    sigma_to_unreal,
    ue4_to_medium,
    unreal_to_sigma,
)
from fogref.scene.vocabulary import PHYSICAL, SCATTERING, SOURCE, Range, check_option, value_text

__all__ = [
    "UNREAL_IGNORED",
    "UNREAL_IGNORED_RANGES",
    "UNREAL_MAPPED",
    "flat_unreal",
    "fog_from_physical",
    "fog_from_unreal",
]

#: Unreal editor values that map exactly onto the physical fog: name -> command-line option.
UNREAL_MAPPED = {
    "FogDensity": "--ue-fog-density",
    "FogHeightFalloff": "--ue-fog-height-falloff",
    "FogHeight": "--ue-fog-height",
    "SecondFogData.FogDensity": "--ue-second-fog-density",
    "SecondFogData.FogHeightFalloff": "--ue-second-fog-height-falloff",
    "SecondFogData.FogHeightOffset": "--ue-second-fog-height-offset",
}
#: Unreal editor values with no physical counterpart: name -> (option, kind, why it is ignored).
UNREAL_IGNORED = {
    "FogInscatteringColor": (
        "--ue-fog-inscattering-color",
        "rgb",
        "it stands for albedo x sky radiance (a fit output, fogref fit); "
        "the truth's sky is sky_radiance and its albedo is albedo",
    ),
    "DirectionalInscatteringExponent": (
        "--ue-directional-inscattering-exponent",
        "number",
        "a cosine lobe is not a phase function; the truth scatters with Henyey-Greenstein g",
    ),
    "DirectionalInscatteringColor": (
        "--ue-directional-inscattering-color",
        "rgb",
        "it stands for albedo x sun irradiance x phase; the truth's sun is sun_irradiance",
    ),
    "DirectionalInscatteringStartDistance": (
        "--ue-directional-inscattering-start-distance",
        "number",
        "physical fog scatters sunlight from the camera on",
    ),
    "StartDistance": ("--ue-start-distance", "number", "physical fog starts at the camera"),
    "FogMaxOpacity": ("--ue-fog-max-opacity", "number", "physical transmittance has no clamp"),
    "FogCutoffDistance": ("--ue-fog-cutoff-distance", "number", "physical fog has no cutoff distance"),
    "EndDistance": ("--ue-end-distance", "number", "physical fog does not end at a distance"),
}
#: The range of each ignored value (checked although it is ignored: a value Unreal could not
#: mean is a mistake).  Unreal's ``ExponentialHeightFogComponent.h`` (Engine/Classes/Components;
#: UE 4.19 and 5.3) gives these UPROPERTYs slider limits only, no ClampMin/ClampMax:
#: FogMaxOpacity ``UIMin = "0", UIMax = "1"`` (an opacity: [0, 1] here);
#: DirectionalInscatteringExponent ``UIMin = "2", UIMax = "64"`` (the exponent of
#: ``pow(saturate(cos), e)``: any e >= 0 is a lobe, a negative one is not); StartDistance
#: ``UIMin = "0", UIMax = "5000"``; FogCutoffDistance ``UIMin = "100000", UIMax = "20000000"``
#: (0: no cutoff); DirectionalInscatteringStartDistance none (a distance).  Colours are linear
#: RGB >= 0 (FLinearColor).  Distances in cm.
UNREAL_IGNORED_RANGES = {
    "FogInscatteringColor": Range("--ue-fog-inscattering-color", "rgb", 0.0),
    "DirectionalInscatteringExponent": Range("--ue-directional-inscattering-exponent", "number", 0.0),
    "DirectionalInscatteringColor": Range("--ue-directional-inscattering-color", "rgb", 0.0),
    "DirectionalInscatteringStartDistance": Range(
        "--ue-directional-inscattering-start-distance", "number", 0.0, unit="cm"
    ),
    "StartDistance": Range("--ue-start-distance", "number", 0.0, unit="cm"),
    "FogMaxOpacity": Range("--ue-fog-max-opacity", "number", 0.0, 1.0),
    "FogCutoffDistance": Range("--ue-fog-cutoff-distance", "number", 0.0, unit="cm"),
    "EndDistance": Range("--ue-end-distance", "number", 0.0, unit="cm"),
}


def _unreal_value(unreal: dict, key: str) -> Any:
    if key.startswith("SecondFogData."):
        sfd = unreal.get("SecondFogData") or {}
        if not isinstance(sfd, dict):
            raise ParameterError(
                SOURCE, "SecondFogData", "expected a dict of FogDensity, FogHeightFalloff, FogHeightOffset"
            )
        return sfd.get(key.split(".", 1)[1])
    return unreal.get(key)


def fog_from_unreal(unreal: dict, *, albedo: Any = 0.9, g: float = 0.6) -> tuple[dict, list[str]]:
    """The ``heightfog`` parameters of Unreal editor values, through the exact mapping.

    Parameters
    ----------
    unreal : dict
        Unreal's Exponential Height Fog component, in the editor's names and units:
        ``FogDensity`` (default 0.02), ``FogHeightFalloff`` (default 0.2),
        ``FogHeight`` [cm, Unreal z-up world Z; default 0] and ``SecondFogData``, a
        dict of ``FogDensity`` (default 0: no second layer), ``FogHeightFalloff``
        (default 0.2) and ``FogHeightOffset`` [cm, relative to FogHeight]. These map
        exactly (:func:`fogref.models.ue4.ue4_to_medium`). The values of
        :data:`UNREAL_IGNORED` (FogInscatteringColor, DirectionalInscatteringExponent,
        ...) have no physical counterpart: they are checked, kept out of the fog
        and reported in the notes.
    albedo : float or 3 floats
        Single-scattering albedo in [0, 1] (Unreal has none).
    g : float
        Henyey-Greenstein asymmetry in [-0.999, 0.999] (Unreal has none).

    Returns
    -------
    (dict, list of str)
        The fog as :func:`fog_from_physical` returns it, and one note per ignored
        Unreal value (what it was and why it is ignored).

    Raises
    ------
    fogref.errors.ParameterError
        Naming the Unreal value, its command-line option and the allowed range.

    Examples
    --------
    >>> from fogref.models.ue4 import unreal_to_sigma
    >>> fog, notes = fog_from_unreal({"FogDensity": 0.02, "FogHeightFalloff": 0.2, "FogHeight": 150.0,
    ...                               "DirectionalInscatteringExponent": 4.0})
    >>> (fog["sigma_t"], fog["falloff"]) == unreal_to_sigma(0.02, 0.2), fog["fog_height"]
    (True, 1.5)
    >>> print(notes[0].replace("; ", ";\\n"))
    Unreal DirectionalInscatteringExponent = 4.0 is ignored: a cosine lobe is not a phase function;
    the truth scatters with Henyey-Greenstein g
    """
    if not isinstance(unreal, dict):
        raise ParameterError(SOURCE, "unreal", f"expected a dict of Unreal editor values, got {unreal!r}")
    known = {k.split(".")[0] for k in UNREAL_MAPPED} | set(UNREAL_IGNORED)
    unknown = sorted(set(unreal) - known)
    if unknown:
        close = difflib.get_close_matches(unknown[0], sorted(known), n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        raise ParameterError(
            SOURCE,
            unknown[0],
            f"not an Unreal Exponential Height Fog value{hint}; known: {', '.join(sorted(known))}",
        )
    # the editor ranges that keep the physical fog inside what fogref renders (sigma_t <= 1e2, falloff <= 1e3)
    d_max, f_max = sigma_to_unreal(PHYSICAL["sigma_t"].hi, PHYSICAL["falloff"].hi)
    h_max = PHYSICAL["height"].hi * CM_PER_M
    limits = {
        "FogDensity": (0.0, d_max, "", 0.02),
        "FogHeightFalloff": (0.0, f_max, "", 0.2),
        "FogHeight": (-h_max, h_max, "cm", 0.0),
        "SecondFogData.FogDensity": (0.0, d_max, "", 0.0),
        "SecondFogData.FogHeightFalloff": (0.0, f_max, "", 0.2),
        "SecondFogData.FogHeightOffset": (-h_max, h_max, "cm", 0.0),
    }
    v = {}
    for key, opt in UNREAL_MAPPED.items():
        lo, hi, unit, default = limits[key]
        raw = _unreal_value(unreal, key)
        v[key] = check_option(default if raw is None else raw, key, Range(opt, "number", lo, hi, unit))
    sfd = unreal.get("SecondFogData") or {}
    extra = sorted(set(sfd) - {"FogDensity", "FogHeightFalloff", "FogHeightOffset"})
    if extra:
        raise ParameterError(
            SOURCE,
            f"SecondFogData.{extra[0]}",
            "SecondFogData has FogDensity, FogHeightFalloff and FogHeightOffset",
        )
    notes = []
    for key, (_, _, why) in UNREAL_IGNORED.items():
        if unreal.get(key) is None:
            continue
        val = check_option(unreal[key], key, UNREAL_IGNORED_RANGES[key])
        notes.append(f"Unreal {key} = {value_text(val)} is ignored: {why}")
    params = UE4FogParams(
        FogDensity=v["FogDensity"],
        FogHeightFalloff=v["FogHeightFalloff"],
        FogHeight=v["FogHeight"],
        SecondFogData=SecondFogData(
            v["SecondFogData.FogDensity"],
            v["SecondFogData.FogHeightFalloff"],
            v["SecondFogData.FogHeightOffset"],
        ),
    )
    medium = ue4_to_medium(params)
    layers = medium.layers
    if params.FogDensity == 0 and params.SecondFogData.FogDensity == 0:  # no fog: keep layer 1's shape
        _, b = unreal_to_sigma(0.0, params.FogHeightFalloff)
        fog = {"sigma_t": 0.0, "density": 1.0, "falloff": b, "height": params.FogHeight / CM_PER_M}
    else:
        fog = {
            "sigma_t": medium.sigma_t[0],
            "density": layers[0].density,
            "falloff": layers[0].falloff,
            "height": layers[0].height,
        }
    if len(layers) > 1:
        fog.update(density2=layers[1].density, falloff2=layers[1].falloff, height2=layers[1].height)
    else:  # no second layer (density2 = 0), but its shape stays settable with --set
        _, b2 = unreal_to_sigma(0.0, params.SecondFogData.FogHeightFalloff)
        fog.update(
            density2=0.0,
            falloff2=b2,
            height2=(params.FogHeight + params.SecondFogData.FogHeightOffset) / CM_PER_M,
        )
    return fog_from_physical(fog, albedo=albedo, g=g), notes


def flat_unreal(unreal: dict) -> dict:
    """Unreal values with ``SecondFogData`` flattened to ``SecondFogData.FogDensity`` etc.

    >>> flat_unreal({"FogDensity": 0.02, "SecondFogData": {"FogDensity": 0.01}})
    {'FogDensity': 0.02, 'SecondFogData.FogDensity': 0.01}
    """
    flat = {}
    for k, v in unreal.items():
        if isinstance(v, dict):
            flat.update({f"{k}.{kk}": vv for kk, vv in v.items()})
        else:
            flat[k] = v
    return flat


def fog_from_physical(fog: dict | None = None, *, albedo: Any = 0.9, g: float = 0.6) -> dict:
    """The ``heightfog`` parameters of a fog given in physical units, validated.

    Parameters
    ----------
    fog : dict, optional
        ``sigma_t`` [1/m] (1 grey or 3 RGB values, 0..1e2; extinction at ``height``),
        ``falloff`` [1/m] (0..1e3), ``height`` [m], ``density`` (relative, default 1),
        an optional second layer ``density2`` (relative to ``sigma_t``; 0 = none),
        ``falloff2`` [1/m], ``height2`` [m], and optional box bounds ``bounds_min``,
        ``bounds_max`` (3 values each [m], both or none), and an optional Local Fog Volume:
        ``lfv_radius`` [m] with ``lfv_centre`` [m], ``lfv_density``, ``lfv_falloff`` [1/m],
        ``lfv_height`` [m] (:class:`~fogref.media.local_fog_volume.LocalFogVolume`; those not
        given take its defaults). Missing values take the shipped valley's fog (Unreal's
        FogDensity 0.02, FogHeightFalloff 0.2 at 0 m).
    albedo : float or 3 floats
        Single-scattering albedo in [0, 1].
    g : float
        Henyey-Greenstein asymmetry in [-0.999, 0.999].

    Returns
    -------
    dict
        XML parameter name -> value (floats, lists of floats): ``sigma_t``, ``albedo``,
        ``g``, ``density``, ``falloff``, ``fog_height``, ``density2``, ``falloff2``,
        ``height2`` and, when given, ``bounds_min``, ``bounds_max``.

    Raises
    ------
    fogref.errors.ParameterError
        Naming the parameter, its command-line option and the allowed range.

    Examples
    --------
    >>> p = fog_from_physical({"sigma_t": [0.001, 0.002, 0.003], "falloff": 0.05, "height": 10})
    >>> p["sigma_t"], p["falloff"], p["fog_height"], p["density2"]
    ([0.001, 0.002, 0.003], 0.05, 10.0, 0.0)
    >>> fog_from_physical({"falloff": -1})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: fogref scene: parameter 'falloff (--falloff)': -1 is outside [0, 1000] 1/m
    """
    if fog is not None and not isinstance(fog, dict):
        raise ParameterError(SOURCE, "fog", f"expected a dict of physical fog values, got {fog!r}")
    fog = dict(fog or {})
    unknown = sorted(set(fog) - set(PHYSICAL) - set(SCATTERING))
    if unknown:
        raise ParameterError(
            SOURCE, unknown[0], f"not a physical fog parameter; known: {', '.join(PHYSICAL)}"
        )
    albedo = fog.pop("albedo", albedo)
    g = fog.pop("g", g)
    sigma0, falloff0 = unreal_to_sigma(0.02, 0.2)  # the shipped valley's fog
    defaults = {
        "sigma_t": sigma0,
        "density": 1.0,
        "falloff": falloff0,
        "height": 0.0,
        "density2": 0.0,
        "falloff2": 0.002,
        "height2": 100.0,
    }
    out = {}
    for name, rng in PHYSICAL.items():
        v = fog.get(name, defaults.get(name))
        if v is not None:
            out[name] = check_option(v, name, rng)
    out["albedo"] = check_option(albedo, "albedo", SCATTERING["albedo"])
    out["g"] = check_option(g, "g", SCATTERING["g"])
    if ("bounds_min" in out) != ("bounds_max" in out):
        missing = "bounds_max" if "bounds_min" in out else "bounds_min"
        raise ParameterError(SOURCE, PHYSICAL[missing].label(missing), "give both bounds or none")
    if "bounds_min" in out and not all(a < b for a, b in zip(out["bounds_min"], out["bounds_max"])):
        raise ParameterError(
            SOURCE,
            PHYSICAL["bounds_max"].label("bounds_max"),
            f"{out['bounds_max']} must exceed bounds_min {out['bounds_min']} on every axis",
        )
    if "lfv_radius" in out:  # a volume is written whole (its scene $defaults are one group)
        whole = lfv.LocalFogVolume(radius=out["lfv_radius"])
        for name in lfv.PARAMS:
            out.setdefault(name, check_option(getattr(whole, name[4:]), name, PHYSICAL[name]))
    out["fog_height"] = out.pop("height")
    _check_medium(out)
    return out


def _medium_params(fog: dict) -> dict:
    """``heightfog`` XML parameter names (``height`` for ``fog_height``)."""
    p = {k: v for k, v in fog.items() if k != "fog_height"}
    p["height"] = fog["fog_height"]
    return p


def _check_medium(fog: dict) -> None:
    """The medium parser that ``fogref render`` uses must accept the values too."""
    medium_from_params(_medium_params(fog), f"{SOURCE}: fog")
