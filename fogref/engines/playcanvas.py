"""PlayCanvas (npm ``playcanvas``, pinned in ``package.json``) in the loop: page, fog settings, canvas.

The page (``playcanvas.js``) draws the scene with ``StandardMaterial`` (``combineColor``: albedo
times the diffuse light, no 1/pi), the sun as a ``directional`` light of linear colour ``E / pi``,
the uniform sky as ``scene.ambientLight`` (uniform: radiance ``albedo L`` whatever the normal,
the sky's only on a horizontal surface; PlayCanvas has no hemisphere light) and as the camera's
clear colour (not fogged), no shadows, no skybox.  ``scene.fog`` comes from fogref's PlayCanvas
model (:mod:`fogref.models.playcanvas`, mapped by ``fogref.mapping.engines.playcanvas_from_physical``),
and so do the camera's clip planes ``nearClip``, ``farClip``: its fog reads
``gl_FragCoord.z / gl_FragCoord.w = far (z - near) / (far - near)`` of the eye depth ``z``.
Colours are handed to PlayCanvas gamma-encoded (``c^(1/2.2)``; it raises them to 2.2).

The canvas: the camera's defaults, ``TONEMAP_LINEAR`` (exposure 1) and ``GAMMA_SRGB``
(``pow(c + 1e-7, 1/2.2)``, :func:`fogref.models.playcanvas.gamma_correct_output`), 8 bits:
:func:`canvas_port`.

Examples
--------
>>> from fogref.models.playcanvas import PlayCanvasFog, PlayCanvasFogParams
>>> s = settings(PlayCanvasFog(PlayCanvasFogParams(type="exp", density=0.01, farClip=5000.0)))
>>> s["type"], s["density"], s["nearClip"], s["farClip"]
('exp', 0.01, 0.1, 5000.0)
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

from fogref.models.playcanvas import gamma_correct_output

__all__ = ["IMPORTS", "MODEL", "PACKAGE", "PAGE", "canvas_port", "port", "settings", "view_settings"]

MODEL = "playcanvas"
PACKAGE = "playcanvas"
PAGE = Path(__file__).with_name("playcanvas.js")
IMPORTS = {"playcanvas": "playcanvas/build/playcanvas.mjs"}


def settings(model: Any) -> dict:
    """``scene.fog`` and the camera's clip planes for the page from a
    :class:`fogref.models.playcanvas.PlayCanvasFog` (``color`` linear: ``color^2.2``)."""
    p = model.params
    return {
        "type": p.type,
        "color": [float(c) ** 2.2 for c in p.color],
        "density": float(p.density),
        "start": float(p.start),
        "end": float(p.end),
        "nearClip": float(p.nearClip),
        "farClip": float(p.farClip),
    }


def view_settings(near: float, far: float) -> dict:
    """The settings a view fixes: the camera's clip planes [m] (so that nothing in view is clipped)."""
    return {"nearClip": float(near), "farClip": float(far)}


def port(model: Any, camera: dict) -> Any:
    """The port looking along the camera's forward axis (PlayCanvas fogs the eye depth along it)."""
    return type(model)(dataclasses.replace(model.params, camera_forward=tuple(camera["forward"])))


def canvas_port(surface: np.ndarray, model: Any, fog_factor: np.ndarray) -> np.ndarray:
    """The 8-bit canvas PlayCanvas draws: ``gamma(mix(surface, color^2.2, f))``, rounded.

    ``surface`` (H, W, 3) linear, ``fog_factor`` (H, W) in [0, 1]; returns uint8 (H, W, 3).
    """
    colour = np.asarray([float(c) ** 2.2 for c in model.params.color], dtype=np.float64)
    f = np.asarray(fog_factor, dtype=np.float64)[..., None]
    out = gamma_correct_output(np.asarray(surface, dtype=np.float64) * (1 - f) + colour * f, np.float64)
    return np.rint(np.clip(out, 0.0, 1.0) * 255).astype(np.uint8)
