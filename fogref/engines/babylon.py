"""Babylon.js (npm ``@babylonjs/core``, pinned in ``package.json``) in the loop: page, fog settings, canvas.

The page (``babylon.js``) draws the scene in a right-handed scene with ``StandardMaterial``
(diffuse ``max(n.l, 0) * light colour * albedo``, no 1/pi: ``Shaders/ShadersInclude/
lightsFragmentFunctions.fx``, ``computeLighting``), the sun as a ``DirectionalLight`` of colour
``E / pi``, the uniform sky as a ``HemisphericLight`` (``mix(ground, sky, n.up * 0.5 + 0.5)``,
``computeHemisphericLighting``) of colour ``L`` and ground colour 0 (radiance ``albedo L (1 +
n_y) / 2``) and as ``scene.clearColor`` (not fogged), no shadows; ``default.fragment.fx``
clamps the shaded colour to [0, 1] before the fog.  ``scene.fogMode`` and its settings come
from fogref's Babylon.js model (:mod:`fogref.models.babylon`, mapped by
``fogref.mapping.engines.babylon_from_physical``): its fog is on the distance.

The canvas: Babylon's ``StandardMaterial`` with the default image processing (no tone mapping,
exposure and contrast 1) writes the blended values unconverted, so the canvas holds the linear
result rounded to 8 bits (and the browser shows it as sRGB): :func:`canvas_port`.

Examples
--------
>>> from fogref.models.babylon import BabylonFog, BabylonFogParams
>>> settings(BabylonFog(BabylonFogParams(fogMode="EXP", fogDensity=0.01, fogColor=(0.2, 0.3, 0.5))))
{'mode': 'EXP', 'color': [0.2, 0.3, 0.5], 'density': 0.01, 'start': 0.0, 'end': 1000.0}
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["FOG_COORDINATE", "IMPORTS", "MODEL", "PACKAGE", "PAGE", "canvas_port", "port", "settings"]

MODEL = "babylon"
PACKAGE = "@babylonjs/core"
PAGE = Path(__file__).with_name("babylon.js")
#: the page imports the modules it uses from the package's folder (``@babylonjs/core/scene.js``, ...),
#: not its index (3,400 modules, 3 s of loading in Chromium from file://)
IMPORTS = {"@babylonjs/core/": "@babylonjs/core"}
#: Babylon's fog reads ``length(vFogDistance)``, the interpolated view position's length
FOG_COORDINATE = "distance"


def settings(model: Any) -> dict:
    """``scene.fogMode`` and its settings for the page from a :class:`fogref.models.babylon.BabylonFog`."""
    p = model.params
    return {
        "mode": p.fogMode,
        "color": [float(c) for c in p.fogColor],
        "density": float(p.fogDensity),
        "start": float(p.fogStart),
        "end": float(p.fogEnd),
    }


def port(model: Any, camera: dict) -> Any:
    """The port as it is: Babylon fogs the distance, which does not depend on the view direction."""
    return model


def canvas_port(surface: np.ndarray, model: Any, fog_factor: np.ndarray) -> np.ndarray:
    """The 8-bit canvas Babylon draws: ``mix(surface, fog colour, f)`` clamped, rounded, unconverted.

    ``surface`` (H, W, 3) linear, ``fog_factor`` (H, W) in [0, 1]; returns uint8 (H, W, 3).
    """
    colour = np.asarray(model.params.fogColor, dtype=np.float64)
    f = np.asarray(fog_factor, dtype=np.float64)[..., None]
    out = np.asarray(surface, dtype=np.float64) * (1 - f) + colour * f
    return np.rint(np.clip(out, 0.0, 1.0) * 255).astype(np.uint8)
