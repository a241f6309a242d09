"""Filament (npm ``filament``, WebAssembly, pinned in ``package.json``) in the loop: page, fog, canvas.

The npm build's ``Engine.createMaterial`` takes only materials compiled ahead of time by
Filament's ``matc``, which it does not ship; its only materials are gltfio's ubershaders.  So the
page (``filament.js``) builds the scene as a glTF of **unlit** triangles (``KHR_materials_unlit``)
whose vertex colours are fogref's Lambert shading of each vertex (reflectance / pi times the sun's
``E cos`` and the sky's ``pi L (1 + n_y) / 2``, the lighting the three.js page gets from its
lights), interpolated across each triangle: Filament's own (PBR) lighting is not exercised, its
fog is.  Fog: ``View.setFogOptions`` from fogref's Filament model (:mod:`fogref.models.filament`,
mapped by ``fogref.mapping.engines.filament_from_physical``), its sun term from a directional
light; exposure 1 and an indirect light of intensity 1 (the shader scales the fog colour by
their product); the sky is the clear colour (not fogged).  Its fog reads the distance to the
interpolated world position.

Float pixels: the view draws into a ``RenderTarget`` with an ``RGBA32F`` texture, read back from
Filament's WebGL 2 context (its JS API has no ``readPixels``).  Depth: a pass whose vertex
colours are the positions relative to the camera.

The canvas: what a Filament ``View`` shows by default (post-processing on: the default
``ColorGrading``, ACES-legacy tone mapping and the sRGB output encoding of ``ColorGrading.h`` /
``ToneMapper.cpp``), but with FXAA (an edge filter across neighbouring pixels) and temporal
dithering (noise under one 8-bit step, which no per-pixel port reproduces) turned off: FXAA by
``View.setAntiAliasing``, the dithering by ``withoutDithering`` of ``page_helpers.js`` (the JS
API has no ``View.setDithering``: the page compiles the colour-grading shader with its noise
term 0).  The port's canvas is its ``output="canvas"``
(:class:`fogref.models.filament.CanvasGrade`): :func:`port` returns it.

Examples
--------
>>> from fogref.models.filament import FilamentFog, FilamentFogParams
>>> s = settings(FilamentFog(FilamentFogParams(density=0.01, heightFalloff=0.1)))
>>> s["density"], s["heightFalloff"], s["inScatteringSize"], "cutOffDistance" in s
(0.01, 0.1, -1.0, False)
>>> port(FilamentFog(FilamentFogParams()), {}).params.output
'canvas'
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

__all__ = [
    "FOG_COORDINATE",
    "IMPORTS",
    "LINEAR_LEVEL",
    "NOTES",
    "MODEL",
    "PACKAGE",
    "PAGE",
    "port",
    "settings",
]

MODEL = "filament"
PACKAGE = "filament"
PAGE = Path(__file__).with_name("filament.js")
IMPORTS = {"filament": "filament/filament.js"}
FOG_COORDINATE = "distance"
#: The linear image's quantisation level for Filament's fog, relative (``fogref.engines.port``):
#: its line integral ``(A - density exp(y - h)) / h`` cancels for small ``h = heightFalloff
#: view.y`` (down to 0.00125, where it switches to ``A``), which multiplies float32 ``exp``'s
#: rounding (a few ulps, about 2e-7; SwiftShader's and numpy's differ) by up to 1 / 0.00125 in the
#: optical depth ``tau``, and ``T tau`` is at most 1/e: 2e-7 / 0.00125 / e = 6e-5.  Measured on
#: the valley: 8.3e-7 at 32x18, 2.9e-6 at 96x54, at pixels with ``h`` from 0.0016 to 0.025.
LINEAR_LEVEL = 6e-5
#: What this engine's images are, said in ``engine.json``'s notes.
NOTES = (
    "filament: unlit glTF (KHR_materials_unlit) whose vertex colours are fogref's Lambert shading of "
    "each vertex (sun and sky), interpolated across each triangle: Filament's own lighting is not used",
    "filament: the linear target is drawn with post-processing off; the canvas with Filament's defaults "
    "(post-processing on: the default ColorGrading, ACES-legacy tone mapping, sRGB output encoding) but "
    "FXAA (an edge filter across pixels) and temporal dithering (noise under one 8-bit step; the JS API "
    "has no View.setDithering, so the page compiles the colour-grading shader with its noise term 0), "
    "turned off: neither is reproduced by the per-pixel port",
)


def settings(model: Any) -> dict:
    """``View.FogOptions`` for the page from a :class:`fogref.models.filament.FilamentFog`, plus the
    sun term's directional light (``lightDirection`` toward the sun, ``lightColor``,
    ``lightIntensity``); ``cutOffDistance`` only when finite (JSON has no infinity)."""
    p = model.params
    out = {
        k: float(getattr(p, k))
        for k in (
            "distance",
            "maximumOpacity",
            "height",
            "heightFalloff",
            "density",
            "inScatteringStart",
            "inScatteringSize",
        )
    }
    if math.isfinite(p.cutOffDistance):
        out["cutOffDistance"] = float(p.cutOffDistance)
    return {
        **out,
        "color": [float(c) for c in p.color],
        "lightDirection": [float(c) for c in p.lightDirection],
        "lightColor": [float(c) for c in p.lightColorIntensity[:3]],
        "lightIntensity": float(p.lightColorIntensity[3]),
    }


def port(model: Any, camera: dict) -> Any:
    """The port with its canvas output (Filament's fog reads the world position, whatever the
    camera's axis): its ``transmittance`` and ``inscatter`` are the linear target's, its
    ``display`` the default canvas."""
    return type(model)(dataclasses.replace(model.params, output="canvas"))
