"""Render a view with a real engine and write its images in the forms ``fogref compare`` reads.

:func:`render_engine` builds the page's ``spec`` (:mod:`fogref.engines`) from an
:class:`~fogref.engines.view.EngineView` and the engine's fog settings, runs the page in
headless Chromium (:class:`~fogref.engines.browser.Browser`) and decodes what it returns;
:func:`write_engine_render` writes it, atomically, refusing to replace an input:

=================  ===========================================================================
file               what (linear RGB unless said)
=================  ===========================================================================
``final.exr``      the engine's image on a linear float32 render target (``R,G,B``), with the
                   engine's view distance ``distance`` [m] (0 on sky, as the truth's G-buffer)
                   and ``hit`` (1 where a surface was drawn): ``compare --image``
``T.exr``          the engine's fog transmittance ``1 - f`` (grey): ``--transmittance``
``inscatter.exr``  what its fog adds, ``C f``: ``--inscatter``
``surface.exr``    the engine's image without fog (its own surface shading)
``canvas.png``     the canvas as the engine ships it (8 bits): ``--image`` (read as sRGB)
``engine.json``    engine and version, browser, fog settings, camera, notes, the port's difference
=================  ===========================================================================

The camera's clip planes are :meth:`~fogref.engines.view.EngineView.clip_planes`: the far plane
twice the farthest vertex, the near plane half the nearest vertex (at least the scene's
``near_clip``), so that nothing drawn is clipped (``fogref.engines.view`` keeps every triangle
edge within 0.5 of its distance, so no surface is nearer than half its nearest vertex).  An
engine whose fog reads its clip planes (PlayCanvas) takes them from its fog settings, which
``fogref engine`` sets to these unless ``--param`` gives them.
"""

from __future__ import annotations

import base64
import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from fogref.atomic import atomic_write, refuse_overwriting_inputs, write_text_atomic
from fogref.engines import engine_module
from fogref.engines.browser import Browser, node_modules_dir, package_version
from fogref.engines.port import port_vs_engine
from fogref.engines.view import EngineView
from fogref.errors import FogrefError
from fogref.exrio import write_exr
from fogref.mapping import PhysicalScene

__all__ = ["EngineRender", "FILES", "output_paths", "render_engine", "write_engine_render"]

#: The files :func:`write_engine_render` writes, by role.
FILES = {
    "final": "final.exr",
    "transmittance": "T.exr",
    "inscatter": "inscatter.exr",
    "surface": "surface.exr",
    "canvas": "canvas.png",
    "record": "engine.json",
}


@dataclass
class EngineRender:
    """What an engine drew.  Arrays ``(H, W, 3)`` float64 linear (from float32) unless said.

    final, surface: with and without fog.  transmittance: ``1 - f``; inscatter: ``C f``
    (both None without fog).
    canvas: ``(H, W, 3)`` uint8 sRGB as shipped.  settings: the fog settings given to the engine.
    fog_position: ``(H, W, 3)`` the point the engine's fog read minus the camera [m] (0 on sky),
    where the page returns it (Filament), else None.
    """

    engine: str
    version: str
    final: np.ndarray
    surface: np.ndarray
    transmittance: np.ndarray | None
    inscatter: np.ndarray | None
    distance: np.ndarray
    fog_depth: np.ndarray
    fog_distance: np.ndarray
    hit: np.ndarray
    canvas: np.ndarray
    settings: dict | None
    camera: dict
    browser: str = ""
    renderer: str = ""
    target: str = ""
    output_colour_space: str = ""
    tone_mapping: str = ""
    seconds: float = 0.0
    notes: list[str] = field(default_factory=list)
    fog_position: np.ndarray | None = None

    def record(self) -> dict:
        """The JSON-able description written to ``engine.json`` (no pixels)."""
        return {
            "engine": self.engine,
            "version": self.version,
            "browser": f"Chromium {self.browser}",
            "webgl_renderer": self.renderer,
            "render_target": self.target,
            "canvas_colour_space": self.output_colour_space,
            "canvas_tone_mapping": self.tone_mapping,
            "fog_settings": self.settings,
            "camera": {k: self.camera.get(k) for k in ("origin", "forward", "up", "fov_deg", "resolution")},
            "seconds": round(self.seconds, 3),
            "notes": self.notes,
        }


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a).tobytes()).decode("ascii")


def _pixels(text: str, shape: tuple[int, int], dtype: Any) -> np.ndarray:
    H, W = shape
    a = np.frombuffer(base64.b64decode(text), dtype=dtype)
    if a.size != H * W * 4:
        raise FogrefError(f"the engine returned {a.size} values, expected {H}x{W}x4")
    return a.reshape(H, W, 4)[::-1]  # GL rows are bottom-up


def spec_of(view: EngineView, fog: dict | None) -> dict:
    """The page's ``spec`` (see :mod:`fogref.engines`) for ``view`` and the fog settings ``fog``."""
    ps = PhysicalScene.from_params(view.params)
    H, W = view.shape
    c = view.camera
    near, far = view.clip_planes()
    return {
        "width": W,
        "height": H,
        "camera": {
            "origin": list(c["origin"]),
            "forward": list(c["forward"]),
            "up": list(c["up"]),
            "right": list(c["right"]),
            "fov_y_deg": float(c["fov_y_deg"]),
            "near": near,
            "far": far,
        },
        "shapes": [
            {
                "positions": _b64(s.positions),
                "normals": None if s.normals is None else _b64(s.normals),
                "indices": _b64(s.indices),
                "reflectance": list(s.reflectance),
            }
            for s in view.shapes
        ],
        "sun": {"direction": list(ps.sun_direction), "irradiance": list(ps.sun_irradiance)}
        if ps.has_sun
        else None,
        "sky": list(ps.sky_radiance) if max(ps.sky_radiance) > 0 else None,
        "fog": fog,
    }


def render_engine(
    view: EngineView, model: Any, engine: str = "threejs", timeout: float = 300.0
) -> EngineRender:
    """Render ``view`` with ``engine``, its fog set from ``model`` (the engine's fogref model, e.g. from
    :func:`fogref.mapping.build.build_model`; None: no fog).

    EngineUnavailable (a FogrefError) without Chromium, its driver or the engine's npm package;
    ``timeout`` [s] bounds a hung page.
    """
    mod = engine_module(engine)
    nm = node_modules_dir()
    imports = {k: nm / v for k, v in mod.IMPORTS.items()}
    fog = mod.settings(model) if model is not None else None
    spec = spec_of(view, fog)
    t0 = time.perf_counter()
    with Browser(timeout=timeout) as browser:
        out = browser.run_page(mod.PAGE, imports, spec)
        browser_version = browser.version
    seconds = time.perf_counter() - t0
    shape = view.shape
    final, surface = (
        _pixels(out[k], shape, np.float32)[..., :3].astype(np.float64) for k in ("final", "surface")
    )
    depth = _pixels(out["depth"], shape, np.float32).astype(np.float64)
    T = inscatter = None
    if fog is not None:
        T = 1.0 - _pixels(out["fog_factor"], shape, np.float32)[..., :3].astype(np.float64)
        inscatter = _pixels(out["inscatter"], shape, np.float32)[..., :3].astype(np.float64)
    hit = depth[..., 3] > 0.5
    for name, a in (
        ("final", final),
        ("surface", surface),
        ("depth", depth),
        ("T", T),
        ("inscatter", inscatter),
    ):
        if a is not None and not np.all(np.isfinite(a)):
            raise FogrefError(f"{engine}: the engine's {name} image has NaN or infinite pixels")
    return EngineRender(
        engine=engine,
        version=package_version(nm, mod.PACKAGE),
        final=final,
        surface=surface,
        transmittance=T,
        inscatter=inscatter,
        distance=np.where(hit, depth[..., 0], 0.0),
        fog_depth=np.where(hit, depth[..., 1], 0.0),
        fog_distance=np.where(hit, depth[..., 2], 0.0),
        hit=hit,
        canvas=_pixels(out["canvas"], shape, np.uint8)[..., :3].copy(),
        settings=fog,
        camera=view.camera,
        browser=browser_version,
        renderer=str(out.get("renderer", "")),
        target=str(out.get("target_type", "")),
        output_colour_space=str(out.get("output_colour_space", "")),
        tone_mapping=str(out.get("tone_mapping", "")),
        seconds=seconds,
        notes=[*view.notes, *getattr(mod, "NOTES", ())],
        fog_position=np.where(hit[..., None], _pixels(out["position"], shape, np.float32)[..., :3], 0.0)
        if "position" in out
        else None,
    )


def output_paths(out_dir) -> dict[str, Path]:
    """Role -> the file :func:`write_engine_render` writes in ``out_dir`` (:data:`FILES`)."""
    return {k: Path(out_dir) / v for k, v in FILES.items()}


def _rgb(a: np.ndarray) -> dict:
    return {c: a[..., i] for i, c in enumerate("RGB")}


def write_engine_render(r: EngineRender, out_dir, inputs=(), extra: dict | None = None) -> dict[str, Path]:
    """Write ``r`` into ``out_dir`` (the files of :data:`FILES`; without fog no ``T.exr`` and
    ``inscatter.exr``), each atomically; ``inputs`` (paths or ``(path, label)``) are refused as
    outputs before anything is written.  ``extra``: more keys for ``engine.json``.  Returns role -> path.
    """
    paths = output_paths(out_dir)
    if r.transmittance is None:
        paths.pop("transmittance")
        paths.pop("inscatter")
    refuse_overwriting_inputs([(p, f"engine {k} image") for k, p in paths.items()], inputs, "--out")
    attrs = {"fogref.engine": r.record()}
    write_exr(
        paths["final"],
        {**_rgb(r.final), "distance": r.distance, "hit": r.hit.astype(np.float32)},
        attrs,
    )
    write_exr(paths["surface"], _rgb(r.surface), attrs)
    if r.transmittance is not None and r.inscatter is not None:
        write_exr(paths["transmittance"], _rgb(r.transmittance), attrs)
        write_exr(paths["inscatter"], _rgb(r.inscatter), attrs)

    def png(tmp: str) -> None:
        Image.fromarray(r.canvas, "RGB").save(tmp, format="PNG")

    atomic_write(paths["canvas"], png)
    write_text_atomic(paths["record"], json.dumps({**r.record(), **(extra or {})}, indent=2) + "\n")
    return paths


def truth_agreement(r: EngineRender, truth: Any) -> dict:
    """The engine's camera against the truth's G-buffer: pixels whose hit differs, and the relative
    difference of the distance [m] where both hit: its median, its maximum and the pixels within
    1e-5 (float32 level where the cameras agree; a silhouette pixel may show another surface, a
    tessellated sphere differs from the truth's by up to 5.4e-4 of its radius)."""
    both = r.hit & truth.hit
    rel = np.abs(r.distance[both] - truth.distance[both]) / np.maximum(truth.distance[both], 1e-30)
    out = {
        "hit_mismatch_pixels": int((r.hit != truth.hit).sum()),
        "pixels": int(r.hit.size),
        "both_hit_pixels": int(both.sum()),
        "distance_within_1e-5": int((rel <= 1e-5).sum()),
        "distance_median_relative": float(np.median(rel)) if rel.size else 0.0,
        "distance_max_relative": float(rel.max(initial=0.0)),
    }
    out["summary"] = (
        f"camera vs the truth's G-buffer: {out['hit_mismatch_pixels']} of {out['pixels']} pixels hit "
        f"differently; where both hit, the distance is within 1e-5 relative on {out['distance_within_1e-5']} "
        f"of {out['both_hit_pixels']} pixels (median {out['distance_median_relative']:.2g}, "
        f"max {out['distance_max_relative']:.2g})"
    )
    return out


def render_and_write(
    view: EngineView,
    model: Any,
    out_dir,
    engine: str = "threejs",
    truth: Any = None,
    inputs=(),
    timeout: float = 300.0,
    sources: dict | None = None,
) -> tuple[EngineRender, dict[str, Path], dict]:
    """Render ``view`` with ``engine`` (fog from ``model``, None: none; ``sources``: where each of
    its settings came from, written as ``fog_settings_source``), compare it with its port
    (:func:`fogref.engines.port.port_vs_engine`) and, given a ``truth``, its camera with the
    truth's (:func:`truth_agreement`); write everything into ``out_dir``.  Outputs that would
    replace one of ``inputs`` are refused before the engine starts.

    Returns ``(render, role -> path, record)``; ``record`` (what ``engine.json`` holds) has
    ``summary``, one line per finding.
    """
    refuse_overwriting_inputs(
        [(p, f"engine {k} file") for k, p in output_paths(out_dir).items()], inputs, "--out"
    )
    r = render_engine(view, model, engine, timeout=timeout)
    extra: dict = {"summary": []}
    if sources is not None:
        extra["fog_settings_source"] = sources
    if model is not None:
        extra["port_vs_engine"] = port_vs_engine(r, model, None if truth is None else truth.view)
        extra["summary"].append(extra["port_vs_engine"]["summary"])
    if truth is not None:
        extra["truth"] = truth_agreement(r, truth)
        extra["summary"].append(extra["truth"]["summary"])
    extra["summary"] += r.notes
    paths = write_engine_render(r, out_dir, inputs, extra)
    return r, paths, {**r.record(), **extra}
