"""three.js (npm ``three``, pinned in ``package.json``) in the loop: its page, fog settings and canvas.

The page (``threejs.js``) draws the scene with ``MeshLambertMaterial`` (per-fragment
``BRDF_Lambert``: radiance ``albedo / pi * E cos``), the sun as a ``DirectionalLight`` of colour
``E`` (irradiance on a plane facing it), the uniform sky as ``scene.background`` (drawn without
fog) and as a ``HemisphereLight`` of sky colour ``pi L`` and ground colour 0 (irradiance
``pi L (1 + n_y) / 2``: the unoccluded sky above the horizon), no shadows, and
``scene.fog`` = ``FogExp2``/``Fog`` from the settings of fogref's three.js model
(:mod:`fogref.models.threejs`, mapped by ``fogref.mapping.engines.threejs_from_physical``).
Without fog, on the open plane, this lighting gives the truth's image to 2.1e-7 relative
(``tests/test_engines.py``).

The canvas: three.js r187's material shaders run ``colorspace_fragment`` (linear -> sRGB,
``sRGBTransferOETF`` in ``src/renderers/shaders/ShaderChunk/colorspace_pars_fragment.glsl.js``,
exponent 0.41666) *before* ``fog_fragment``, with the fog colour converted to sRGB on the CPU
(``src/math/ColorManagement.js``, the same curve): the fog is blended in sRGB, then the
canvas keeps 8 bits.  :func:`canvas_port` is that, from the port's fog factor.

Examples
--------
>>> from fogref.models.threejs import ThreeFogParams, ThreeJSFog
>>> settings(ThreeJSFog(ThreeFogParams(mode="FogExp2", density=0.01, color=(0.2, 0.3, 0.5))))
{'type': 'FogExp2', 'color': [0.2, 0.3, 0.5], 'density': 0.01, 'near': 1.0, 'far': 1000.0}
>>> srgb_oetf(np.array([0.0, 0.002, 0.5, 1.0])).round(5).tolist()
[0.0, 0.02584, 0.73536, 1.0]
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["IMPORTS", "MODEL", "PACKAGE", "PAGE", "canvas_port", "settings", "srgb_oetf"]

MODEL = "threejs"
PACKAGE = "three"
PAGE = Path(__file__).with_name("threejs.js")
IMPORTS = {"three": "three/build/three.module.js"}


def settings(model: Any) -> dict:
    """``scene.fog`` for the page from a :class:`fogref.models.threejs.ThreeJSFog` (linear colour)."""
    p = model.params
    return {
        "type": p.mode,
        "color": [float(c) for c in p.color],
        "density": float(p.density),
        "near": float(p.near),
        "far": float(p.far),
    }


def port(model: Any, camera: dict) -> Any:
    """The port looking along the camera's forward axis (three.js fogs the eye depth along it)."""
    return type(model)(dataclasses.replace(model.params, camera_forward=tuple(camera["forward"])))


def srgb_oetf(x: np.ndarray) -> np.ndarray:
    """three.js's ``sRGBTransferOETF`` (exponent 0.41666, not clipped), float64."""
    x = np.asarray(x, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        hi = 1.055 * np.power(np.maximum(x, 0.0), 0.41666) - 0.055
    return np.where(x <= 0.0031308, x * 12.92, hi)


def canvas_port(surface: np.ndarray, model: Any, fog_factor: np.ndarray) -> np.ndarray:
    """The 8-bit canvas three.js draws: ``mix(oetf(surface), oetf(fog colour), f)`` clamped, rounded.

    ``surface`` (H, W, 3) linear, ``fog_factor`` (H, W) in [0, 1]; returns uint8 (H, W, 3).
    """
    colour = srgb_oetf(np.asarray(model.params.color, dtype=np.float64))
    f = np.asarray(fog_factor, dtype=np.float64)[..., None]
    out = srgb_oetf(surface) * (1 - f) + colour * f
    return np.rint(np.clip(out, 0.0, 1.0) * 255).astype(np.uint8)
