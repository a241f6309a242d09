"""The radiance of a physical sky (Mitsuba 3.9's ``sunsky``, its sun removed), as a numpy function.

``sunsky`` (``src/emitters/sunsky.cpp``; Hosek & Wilkie 2012 sky) is z-up; fogref is y-up, so its
``to_world`` is a rotation of -90 deg about +x.  :func:`sky_radiance` evaluates the sky part
(``sun_scale = 0``) through Mitsuba's own emitter, for :mod:`fogref.render.sunsky` (the scene's
split) and for the closed forms of the fits (:func:`fogref.mapping.views.sky_projection`).
Mitsuba is imported only when a function here is called.
"""

from __future__ import annotations

import functools
import json
from typing import Any, Callable

import numpy as np

from fogref.llvm import DEFAULT_VARIANT, ensure_llvm

__all__ = ["SUNSKY_APERTURE", "SUNSKY_KEYS", "eval_emitter", "sky_radiance", "sunsky_dict"]

#: Mitsuba's default sun aperture (angular diameter) [deg] (``sunsky.cpp``).
SUNSKY_APERTURE = 0.5358
#: The parameters of a fogref sunsky (:func:`sunsky_dict`'s arguments).
SUNSKY_KEYS = ("sun_direction", "turbidity", "albedo", "sun_aperture", "sky_scale", "sun_scale")


def _mitsuba() -> Any:
    """Mitsuba with a variant set (the one already set, else LLVM RGB)."""
    ensure_llvm()
    import mitsuba as mi

    if mi.variant() is None:
        mi.set_variant(DEFAULT_VARIANT)  # the sky needs no fogref plugin
    return mi


def sunsky_dict(
    sun_direction: Any,
    turbidity: float = 3.0,
    albedo: float = 0.3,
    sun_aperture: float = SUNSKY_APERTURE,
    sky_scale: float = 1.0,
    sun_scale: float = 1.0,
) -> dict:
    """A ``mi.load_dict`` description of a y-up ``sunsky`` (``sun_direction``: world, toward the sun)."""
    mi = _mitsuba()
    return {
        "type": "sunsky",
        "sun_direction": [float(x) for x in sun_direction],
        "turbidity": float(turbidity),
        "albedo": float(albedo),
        "sun_aperture": float(sun_aperture),
        "sky_scale": float(sky_scale),
        "sun_scale": float(sun_scale),
        "to_world": mi.ScalarTransform4f().rotate([1, 0, 0], -90.0),
    }


def eval_emitter(emitter: Any, dirs: np.ndarray) -> np.ndarray:
    """The emitter's RGB radiance toward ``dirs`` ((N, 3), unit, toward the sky): (N, 3) float64."""
    import drjit as dr

    mi = _mitsuba()
    d = np.asarray(dirs, dtype=np.float64)
    si = dr.zeros(mi.SurfaceInteraction3f, len(d))
    si.wi = mi.Vector3f(-d[:, 0], -d[:, 1], -d[:, 2])
    return np.asarray(emitter.eval(si), dtype=np.float64).T


@functools.lru_cache(maxsize=16)
def _sky_emitter(variant: str, key: str) -> Any:
    mi = _mitsuba()
    return mi.load_dict({**sunsky_dict(**json.loads(key)), "sun_scale": 0.0}, parallel=False)


def sky_radiance(desc: dict) -> Callable[[np.ndarray], np.ndarray]:
    """The sky part of a sunsky (sun removed), as a numpy function: ``(N, 3)`` unit
    directions toward the sky -> ``(N, 3)`` RGB radiance (0 below the horizon); times
    ``desc["sky_scale"]``.  ``desc``: :func:`sunsky_dict`, or any dict with its parameters
    (:data:`SUNSKY_KEYS`; a scene description's ``"sky"``).  For
    :func:`fogref.media.single_scatter.sky_phase_projection`."""
    mi = _mitsuba()
    args = {k: desc[k] for k in SUNSKY_KEYS if k in desc}
    args["sun_direction"] = [float(x) for x in args["sun_direction"]]
    emitter = _sky_emitter(mi.variant(), json.dumps(args, sort_keys=True))
    return lambda dirs: eval_emitter(emitter, dirs)
