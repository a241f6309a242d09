"""Real engines in the loop: render the truth's view with an engine itself, in headless Chromium.

fogref's ports (:mod:`fogref.models`) are transcriptions of the engines' shaders; this floor
renders the same view with the engine (three.js, Babylon.js, PlayCanvas, Filament from npm,
``package.json``) and reads its pixels back, so a port can be held to its engine and the engine
to the truth.

================  =====================================================================
module            what
================  =====================================================================
``browser``       start Chromium (selenium, Debian's ``chromium-driver``), run a page
``view``          the truth's camera, geometry, sun and sky from its scene file
``render``        render an engine, read back its images, write them for ``compare``
``port``          the engine against fogref's port of it, on the engine's own depth
``threejs``       three.js: its page (``threejs.js``), its fog settings, its canvas
``babylon``       Babylon.js: its page (``babylon.js``), its fog settings, its canvas
``playcanvas``    PlayCanvas: its page (``playcanvas.js``), its fog settings, its canvas
``filament``      Filament (WebAssembly): its page (``filament.js``), its fog settings, its canvas
================  =====================================================================

**An engine is one page and one mapping.** Its module (registered in :data:`ENGINES`) gives
``MODEL`` (the fogref model whose mapping, ``fogref.mapping``, gives the engine's fog settings and
whose port is compared), ``PAGE`` (an ES module), ``IMPORTS`` (bare import name -> path under
``node_modules``; a name ending in ``/`` maps the modules under a folder), ``PACKAGE`` (its npm
name), ``settings(model)`` (the fog settings the page takes, JSON) and ``canvas_port(surface, model,
fog_factor)`` (the canvas the port predicts, 8-bit; none where the port has a canvas output of its
own, a result with ``display``: Filament), ``port(model, camera)`` (the port for that camera) and
optionally ``FOG_COORDINATE`` (``"depth"``, the default, or ``"distance"``: what the engine's fog
reads, see :mod:`fogref.engines.port`) and ``view_settings(near, far)`` (the settings the view
fixes: PlayCanvas's clip planes, which its fog reads) and ``NOTES`` (said in ``engine.json``). The
page sets ``window.fogrefRender(spec)`` (it may return a promise) and then ``data-ready`` on
``<body>``. ``spec``: ``width``, ``height`` [px]; ``camera`` (``origin`` [m], unit ``forward``,
``up``, ``right``, ``fov_y_deg``, ``near``, ``far`` [m]); ``shapes`` (base64 float32 world
``positions`` and ``normals`` or null, uint32 ``indices``, linear ``reflectance``); ``sun`` (unit
``direction`` toward it, ``irradiance``) or null; ``sky`` (uniform radiance) or null; ``fog``
(``settings``) or null. It returns ``version``; ``final``, ``surface`` (no fog), ``fog_factor``
(black materials, white fog: ``1 - T``), ``inscatter`` (black materials, the fog's colour) and
``depth`` (view distance, eye depth, 0, hit) as base64 float32 RGBA rows bottom-up from a linear
float render target; ``canvas`` (base64 uint8 RGBA) as the engine ships it; optionally ``position``
(the point its fog read, minus the camera, float32 RGBA: the port is evaluated there).

Importing this package does no work; nothing starts until :func:`fogref.engines.render.render_engine`.

Examples
--------
>>> sorted(ENGINES)
['babylon', 'filament', 'playcanvas', 'threejs']
>>> engine_module("threejs").MODEL
'threejs'
>>> engine_module("three")
Traceback (most recent call last):
...
fogref.errors.ParameterError: fogref: parameter 'engine': unknown engine 'three'; did you mean 'threejs'? ...
"""

from __future__ import annotations

import importlib
from types import ModuleType

from fogref.errors import ParameterError, did_you_mean

__all__ = ["ENGINES", "engine_module"]

#: engine name -> the module that holds its page and mapping
ENGINES = {
    "threejs": "fogref.engines.threejs",
    "babylon": "fogref.engines.babylon",
    "playcanvas": "fogref.engines.playcanvas",
    "filament": "fogref.engines.filament",
}


def engine_module(name: str, source: str = "fogref") -> ModuleType:
    """The module of engine ``name``; ParameterError with a did-you-mean for an unknown one."""
    if name not in ENGINES:
        raise ParameterError(
            source,
            "engine",
            f"unknown engine '{name}'{did_you_mean(name, ENGINES)} (engines: {', '.join(ENGINES)})",
        )
    return importlib.import_module(ENGINES[name])
