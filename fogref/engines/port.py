"""The engine against fogref's port of it, on the same inputs: the engine's depth and surface.

The port (:mod:`fogref.models`) is evaluated at the points whose fog coordinate is the one the
engine's fog saw, interpolated by the rasteriser: the eye depth (``fog_depth``), or the distance
(``fog_distance``) for an engine module whose ``FOG_COORDINATE`` is ``"distance"``, or the point
itself where the page returns it (``fog_position``: Filament, whose fog reads it); composited
over the engine's own unfogged surface (``surface * T + inscatter``) and compared with the
engine's linear image, and -- through the engine's canvas transform (its module's
``canvas_port``, or the port's own canvas output, its result's ``display``: Filament's) -- with
the 8-bit canvas.  Only the pixels the engine drew a surface on are compared (three.js and
Babylon.js draw their background without fog; ``sky_pixels`` counts the others).

The verdict ``at_quantisation`` is True when the linear difference is within
:data:`LINEAR_LEVEL` (relative to ``max(1, |value|)``: float32 storage and float32 shader
arithmetic on eye depths of up to a few km; an engine module's own ``LINEAR_LEVEL`` where its
shader's arithmetic loses more: Filament's) and the canvas within one 8-bit code value
(:data:`CANVAS_LEVEL`: the rounding of the last step).

Examples
--------
>>> line = summary({"linear_max": 3e-7, "linear_rms": 1e-7, "canvas_max": 1, "canvas_rms": 0.2, "pixels": 10,
...                 "linear_blend_canvas_max": 12, "at_quantisation": True, "sky_pixels": 2})
>>> line.split(": ")[1]
'linear max |Δ| 3e-07, RMS 1e-07 (linear RGB); canvas max 1, RMS 0.2 code values (8-bit sRGB)'
>>> line.split(": ")[2]
'at the quantisation level (a linear fog blend would differ by up to 12 code values)'
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fogref.display import srgb_encode
from fogref.engines import engine_module
from fogref.engines.view import pixel_directions

__all__ = ["CANVAS_LEVEL", "LINEAR_LEVEL", "port_vs_engine", "summary"]

#: The linear image's quantisation level, relative to ``max(1, |value|)``: float32 (2^-24) storage
#: and float32 shader arithmetic (``exp``, ``mix``); 1e-6 is about 17 float32 ulps.
LINEAR_LEVEL = 1e-6
#: The canvas's quantisation level [8-bit code values].
CANVAS_LEVEL = 1


def port_vs_engine(r: Any, model: Any, view_dirs: np.ndarray | None = None) -> dict:
    """The port of ``r.engine`` (``model``, fog settings as given to the engine) against ``r``
    (a :class:`fogref.engines.render.EngineRender`).

    ``view_dirs``: ``(H, W, 3)`` unit pixel directions (default: the camera's pixel centres,
    :func:`~fogref.engines.view.pixel_directions`).  Returns a dict: ``pixels``, ``sky_pixels``;
    ``linear_max``, ``linear_rms`` (final, linear RGB), ``T_max`` (transmittance);
    ``canvas_max``, ``canvas_rms`` [code values]; ``linear_blend_canvas_max`` (the canvas a
    linear blend would give, against the engine's); ``at_quantisation`` (bool); ``summary``.
    """
    mod = engine_module(r.engine)
    port = mod.port(model, r.camera)
    dirs = pixel_directions(r.camera) if view_dirs is None else np.asarray(view_dirs, dtype=np.float64)
    cam = np.asarray(r.camera["origin"], dtype=np.float64)
    hit = r.hit
    if r.fog_position is not None:  # the position the engine's fog read, relative to the camera
        pos = cam + r.fog_position
    elif getattr(mod, "FOG_COORDINATE", "depth") == "distance":
        pos = cam + dirs * r.fog_distance[..., None]
    else:
        along = dirs @ np.asarray(r.camera["forward"], dtype=np.float64)
        pos = cam + dirs * (r.fog_depth / np.where(hit, along, 1.0))[..., None]
    res = port.evaluate(cam, pos[hit], "float32")
    T = np.broadcast_to(np.asarray(res.transmittance, dtype=np.float64), (int(hit.sum()), 3))
    L = np.broadcast_to(np.asarray(res.inscatter, dtype=np.float64), (int(hit.sum()), 3))
    final = r.surface[hit] * T + L
    d = r.final[hit] - final
    scale = np.maximum(1.0, np.abs(final))
    f = np.zeros(r.hit.shape)
    f[hit] = 1.0 - T[:, 0]
    if hasattr(res, "display"):  # the port's own canvas output (Filament's)
        canvas = np.rint(np.asarray(res.display(r.surface[hit]), dtype=np.float64) * 255).astype(np.int64)
    else:
        canvas = mod.canvas_port(r.surface, port, f)[hit].astype(np.int64)
    dc = r.canvas[hit].astype(np.int64) - canvas
    linear_blend = np.rint(srgb_encode(final) * 255).astype(np.int64)
    out = {
        "pixels": int(hit.sum()),
        "sky_pixels": int((~hit).sum()),
        "linear_max": float(np.abs(d).max(initial=0.0)),
        "linear_rms": float(np.sqrt(np.mean(d**2))) if d.size else 0.0,
        "linear_max_relative": float((np.abs(d) / scale).max(initial=0.0)),
        "T_max": float(np.abs(r.transmittance[hit] - T).max(initial=0.0))
        if r.transmittance is not None
        else None,
        "canvas_max": int(np.abs(dc).max(initial=0)),
        "canvas_rms": float(np.sqrt(np.mean(dc.astype(np.float64) ** 2))) if dc.size else 0.0,
        "linear_blend_canvas_max": int(np.abs(r.canvas[hit].astype(np.int64) - linear_blend).max(initial=0)),
    }
    out["at_quantisation"] = bool(
        out["linear_max_relative"] <= getattr(mod, "LINEAR_LEVEL", LINEAR_LEVEL)
        and out["canvas_max"] <= CANVAS_LEVEL
    )
    out["summary"] = summary(out)
    return out


def summary(d: dict) -> str:
    """One line for a report: the differences with their units and the verdict."""
    verdict = "at the quantisation level" if d["at_quantisation"] else "ABOVE the quantisation level"
    return (
        f"port vs engine on {d['pixels']} surface pixels: linear max |Δ| {d['linear_max']:.3g}, "
        f"RMS {d['linear_rms']:.3g} (linear RGB); canvas max {d['canvas_max']}, RMS {d['canvas_rms']:.3g} "
        f"code values (8-bit sRGB): {verdict} (a linear fog blend would differ by up to "
        f"{d['linear_blend_canvas_max']} code values)"
    )
