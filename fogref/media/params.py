"""Build a :class:`~fogref.media.FogMedium` from flat scene parameters (no Mitsuba).

One parser serves the Mitsuba plugin (its ``Properties``), the XML pre-check of
``fogref render`` and the physical-scene reader of :mod:`fogref.mapping`, so a
bad value gets the same clear message everywhere:
``<file>: parameter '<name>': value ... outside [lo, hi]``.  The ``profile``
names and their own parameters come from the profile registry
(:data:`fogref.media.protocol.PROFILES`).
"""

from __future__ import annotations

from typing import Any

from fogref.errors import ParameterError
from fogref.media.local_fog_volume import LocalFogVolume
from fogref.media.medium import Box, FogMedium
from fogref.media.phase import TabulatedPhase
from fogref.media.protocol import PROFILES, number, profile_entry, rgb

__all__ = ["PROFILES", "medium_from_params", "phase_from_params"]


def medium_from_params(params: dict, src: str = "<params>") -> FogMedium:
    """The fog medium of a flat dict of ``heightfog`` XML parameters.

    Parameters
    ----------
    params : dict
        ``profile`` (a registered name, default "exponential"), ``sigma_t`` (RGB,
        1/m, 0..1e2, default 0.01), ``albedo`` (RGB, 0..1, default 0.9), ``g``
        (-0.999..0.999, default 0), the profile's own parameters (see its
        ``from_params``), optional ``bounds_min``/``bounds_max`` (points, m) and an
        optional ``phase``: a :class:`~fogref.media.phase.TabulatedPhase` or the dict of a
        ``fogtabphase`` (``cosines``, ``values``: comma-separated, ``label``), which
        replaces the HG of ``g``; an optional Local Fog Volume, ``lfv_radius`` (required for
        one) and ``lfv_centre``, ``lfv_density``, ``lfv_falloff``, ``lfv_height``
        (:meth:`~fogref.media.local_fog_volume.LocalFogVolume.from_params`), whose density
        adds to the profile's.
        Numbers may be given as strings, RGB values as one number, 3 numbers or
        an XML string ``"r, g, b"``.
    src : str
        Named in error messages (the file and the medium).

    Returns
    -------
    FogMedium

    Raises
    ------
    fogref.errors.ParameterError
        Naming the offending parameter.

    Examples
    --------
    >>> m = medium_from_params({"profile": "exponential", "sigma_t": 0.002, "falloff": 0.02})
    >>> m.sigma_t, m.layers
    ((0.002, 0.002, 0.002), (ExpLayer(density=1.0, falloff=0.02, height=0.0),))
    >>> medium_from_params({"profile": "box"}, "<doc>")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: <doc>: parameter 'bounds_min': profile 'box' needs bounds_min and bounds_max
    """
    name = str(params.get("profile", "exponential"))
    entry = profile_entry(name, src)
    sigma_t = (
        rgb(params["sigma_t"], "sigma_t", src, 0.0, 1e2) if params.get("sigma_t") is not None else (0.01,) * 3
    )
    albedo = (
        rgb(params["albedo"], "albedo", src, 0.0, 1.0) if params.get("albedo") is not None else (0.9,) * 3
    )
    g = number(params, "g", 0.0, src, -0.999, 0.999)
    phase = params.get("phase")
    if isinstance(phase, dict):
        phase = phase_from_params(phase, src)
    elif phase is not None and not isinstance(phase, TabulatedPhase):
        raise ParameterError(src, "phase", "expected a fogtabphase's cosines and values")
    if phase is not None and params.get("g") is not None and abs(g - phase.mean_cosine) > 1e-3:
        raise ParameterError(
            src,
            "g",
            f"{g} with a tabulated phase, whose mean cosine is {phase.mean_cosine:.6g}: give that or no g",
        )
    layers = entry.parse(params, src)
    lo, hi = (
        rgb(params[k], k, src) if params.get(k) is not None else None for k in ("bounds_min", "bounds_max")
    )
    if entry.needs_bounds and (lo is None or hi is None):
        raise ParameterError(src, "bounds_min", f"profile '{name}' needs bounds_min and bounds_max")
    if (lo is None) != (hi is None):
        raise ParameterError(src, "bounds_max" if hi is None else "bounds_min", "give both bounds or none")
    bounds = Box(lo, hi) if lo is not None and hi is not None else None
    if entry.parse_bounds is not None:
        if bounds is not None:
            raise ParameterError(
                src, "bounds_min", f"profile '{name}' has its own bounds; give no bounds_min/max"
            )
        bounds = entry.parse_bounds(params, src)
    return FogMedium(
        sigma_t=sigma_t,
        albedo=albedo,
        g=g,
        layers=tuple(layers),
        bounds=bounds,
        source=src,
        phase=phase,
        volume=LocalFogVolume.from_params(params, src),
    )


def phase_from_params(params: dict, src: str = "<params>") -> TabulatedPhase:
    """The :class:`~fogref.media.phase.TabulatedPhase` of a ``fogtabphase``'s parameters:
    ``cosines`` and ``values`` (comma-separated strings or sequences of numbers), ``label``.

    >>> phase_from_params({"cosines": "-1, 1", "values": "1, 1"}).values[0] * 4 * 3.141592653589793
    1.0
    >>> phase_from_params({"cosines": "-1, x", "values": "1, 1"}, "<doc>")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: <doc>: parameter 'phase.cosines': must be comma-separated numbers
    """
    out: dict[str, tuple] = {}
    for name in ("cosines", "values"):
        v: Any = params.get(name)
        try:
            out[name] = tuple(float(x) for x in (v.replace(",", " ").split() if isinstance(v, str) else v))
        except (TypeError, ValueError, AttributeError):
            raise ParameterError(src, f"phase.{name}", "must be comma-separated numbers") from None
    return TabulatedPhase(
        out["cosines"], out["values"], label=str(params.get("label", "tabulated")), source=src
    )
