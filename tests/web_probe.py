"""Fog probes of the web engines (three.js, Babylon.js, PlayCanvas) in headless Chromium.

One probe is a 64x64-pixel frame: a perspective camera at the origin looking down -z (y up,
vertical field of view ``FOV_DEG``), and an 8x8 grid of 8x8-pixel tiles.  Each tile holds one
quad facing the camera at a known depth with a known unlit colour, except ``BACKGROUND_TILES``,
which show the clear colour.  A quad covers the inner 6x6 pixels of its tile; the inner 4x4
pixels (``PROBE`` of each tile, 1024 pixels a frame) are compared, away from the quads' edges.

The engine page (``tests/web/<engine>.html``) builds the frame from :func:`layout`'s description
and returns its pixels, bottom row first (``readPixels``), from a float32 render target
(``output="linear"``) or from the default canvas as the engine ships it (``output="canvas"``,
8 bits).  :func:`pixel_points` gives, for the same pixels, the point each one shades [m] (on the
quad's plane along the ray through the pixel centre; ``SKY_DISTANCE`` along it on background
tiles), in the frame of the fogref models (y up, camera at the origin looking down -z).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np
from browser_util import console_errors, find_browser, load, start

from fogref.models import SKY_DISTANCE

ROOT = Path(__file__).resolve().parents[1]
WEB = ROOT / "tests" / "web"
SIZE = 64  # pixels, square
TILE = 8  # pixels
FOV_DEG = 60.0  # vertical
NEAR, FAR = 0.1, 500.0  # the camera's clip planes [m]
BACKGROUND_TILES = (0, 9, 36, 63)  # tile index = row * 8 + column, rows from the bottom
PROBE = slice(2, 6)  # pixels of a tile that are compared (the quad covers 1..6)
DEPTHS = (0.3, 60.0)  # the quads' depths [m], log-uniform
#: Wall-clock limit [s] of a page load or a probe, for hangs only: on the shared 2-core machine a
#: page loads in < 5 s (Babylon's ~2000 ES modules) and a probe renders in < 2 s.
HANG_S = 300.0


def node_modules_missing(*packages: str) -> str:
    """Why the engine pages cannot load (``npm ci`` has not run), or ''."""
    missing = [p for p in packages if not (ROOT / "node_modules" / p / "package.json").is_file()]
    return f"node_modules lacks {', '.join(missing)} (bash scripts/setup.sh runs npm ci)" if missing else ""


def npm_version(package: str) -> str:
    """The installed version of an npm package (``node_modules/<package>/package.json``)."""
    return json.loads((ROOT / "node_modules" / package / "package.json").read_text())["version"]


def layout(seed: int) -> dict:
    """The quads of one frame: depths [m], linear colours in [0, 1], and their view-space corners.

    Returns ``{"depth": (64,), "color": (64, 3), "quads": [...]}``; ``depth`` and ``color`` are NaN
    on background tiles; ``quads`` is what the pages take (``corners``: 4 view-space points [m],
    ``color``).
    """
    rng = np.random.default_rng(seed)
    n = (SIZE // TILE) ** 2
    depth = np.exp(rng.uniform(math.log(DEPTHS[0]), math.log(DEPTHS[1]), n))
    color = rng.uniform(0.0, 1.0, (n, 3))
    depth[list(BACKGROUND_TILES)] = np.nan
    color[list(BACKGROUND_TILES)] = np.nan
    t = math.tan(math.radians(FOV_DEG) / 2)
    quads = []
    for k in range(n):
        if k in BACKGROUND_TILES:
            continue
        row, col = divmod(k, SIZE // TILE)
        x0, x1 = ((2.0 * (col * TILE + e) / SIZE - 1.0) * t for e in (1, TILE - 1))
        y0, y1 = ((2.0 * (row * TILE + e) / SIZE - 1.0) * t for e in (1, TILE - 1))
        d = float(depth[k])
        corners = [[x * d, y * d, -d] for x, y in ((x0, y0), (x1, y0), (x1, y1), (x0, y1))]
        quads.append({"corners": corners, "color": [float(c) for c in color[k]]})
    return {"depth": depth, "color": color, "quads": quads}


def probe_mask() -> np.ndarray:
    """(SIZE, SIZE) bool, rows from the bottom: the compared pixels."""
    m = np.zeros((TILE, TILE), bool)
    m[PROBE, PROBE] = True
    return np.tile(m, (SIZE // TILE, SIZE // TILE))


def tile_index() -> np.ndarray:
    """(SIZE, SIZE) int, rows from the bottom: the tile of each pixel."""
    r, c = np.mgrid[0:SIZE, 0:SIZE] // TILE
    return r * (SIZE // TILE) + c


def pixel_points(lay: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(points (SIZE, SIZE, 3) [m], colour (SIZE, SIZE, 3), background (SIZE, SIZE) bool)``.

    ``points``: the point each pixel centre shades (``SKY_DISTANCE`` along the ray on background
    tiles); ``colour``: the quad's colour there (NaN on background tiles).
    """
    t = math.tan(math.radians(FOV_DEG) / 2)
    c = (np.arange(SIZE) + 0.5) * 2.0 / SIZE - 1.0
    ray = np.stack(
        [np.broadcast_to(c[None, :] * t, (SIZE, SIZE)), np.broadcast_to(c[:, None] * t, (SIZE, SIZE))]
        + [-np.ones((SIZE, SIZE))],
        axis=-1,
    )
    k = tile_index()
    bg = np.isnan(lay["depth"][k])
    d = np.where(bg, 0.0, lay["depth"][k])
    sky = ray / np.linalg.norm(ray, axis=-1, keepdims=True) * SKY_DISTANCE
    points = np.where(bg[..., None], sky, ray * d[..., None])
    return points, lay["color"][k], bg


def render(drv, engine: str, cfg: dict) -> tuple[np.ndarray, dict]:
    """Run ``tests/web/<engine>.html``'s ``probe(cfg)``: (SIZE, SIZE, 4) pixels (rows from the
    bottom; float32 for ``output="linear"``, uint8 for ``"canvas"``) and the page's ``info``."""
    page = WEB / f"{engine}.html"
    if drv.current_url != page.as_uri():
        load(drv, page, timeout=HANG_S)
    cfg = {"width": SIZE, "height": SIZE, "fov_deg": FOV_DEG, "near": NEAR, "far": FAR, **cfg}
    res = drv.execute_async_script(
        "const done = arguments[arguments.length - 1];"
        "Promise.resolve().then(() => window.probe(arguments[0]))"
        ".then(r => done(r), e => done({error: String(e && e.stack || e)}));",
        cfg,
    )
    errors = console_errors(drv)
    if "error" in res or errors:
        raise RuntimeError(f"{engine} page: {res.get('error')} {errors}")
    dt = np.float32 if cfg["output"] == "linear" else np.uint8
    return np.asarray(res["pixels"], dtype=dt).reshape(SIZE, SIZE, 4), res["info"]


@dataclass(frozen=True)
class Engine:
    """One web engine's probe: its page, its fog set-ups and the fogref port that stands for it.

    ``setups()``: the fog set-ups (each a dict the page takes as ``cfg["fog"]``); ``model(fog,
    output)``: the fogref model of one set-up for ``output`` "linear" or "canvas";
    ``canvas(result, scene)``: the canvas value in [0, 1] (before the 8-bit rounding) that the
    port predicts, from the model's result and the linear scene colour.  ``outputs``: the
    read-backs the page offers; ``background``: whether the background tiles are compared.
    """

    name: str
    package: str
    setups: Callable[[], list[dict]]
    model: Callable[[dict, str], Any]
    canvas: Callable[[Any, np.ndarray], np.ndarray]
    outputs: tuple[str, ...] = ("linear", "canvas")
    background: bool = True


def measure(drv, engine: Engine) -> dict:
    """Render every set-up of ``engine`` to both outputs; the port's worst differences.

    Returns ``{"version", "pixels", "linear", "canvas", "linear_at", "canvas_at", "info"}``:
    ``linear`` the largest |engine - port| over all probe pixels and channels of the float32
    target (linear RGB, the scene's units), ``canvas`` the largest |engine - round(255 port)| in
    8-bit steps of the canvas (the engine's output encoding), and where each happened (-1: not
    read back).
    """
    worst = {"linear": (-1.0, None), "canvas": (-1.0, None)}
    pixels, info = 0, {}
    for i, fog in enumerate(engine.setups()):
        lay = layout(i)
        background = np.random.default_rng(1000 + i).uniform(0.0, 1.0, 3)
        pts, col, bg = pixel_points(lay)
        mask = probe_mask() & (engine.background | ~bg)
        scene = np.where(bg[..., None], background, col)[mask]
        cfg = {"fog": fog, "background": [float(b) for b in background], "quads": lay["quads"]}
        for out in engine.outputs:
            px, info = render(drv, engine.name, {**cfg, "output": out})
            res = engine.model(fog, out).evaluate(np.zeros(3), pts[mask], "float32")
            got = px[mask][:, :3].astype(np.float64)
            if out == "linear":
                want = np.asarray(res.composite(scene.astype(np.float32)), np.float64)
            else:
                want = np.round(255.0 * np.asarray(engine.canvas(res, scene), np.float64))
            diff = np.where(np.isnan(got - want), np.inf, np.abs(got - want))  # NaN: fail, loudly
            k = int(np.argmax(diff.max(axis=-1)))
            if diff[k].max() > worst[out][0]:
                where = {
                    "fog": fog,
                    "distance_m": float(np.linalg.norm(pts[mask][k])),
                    "depth_m": float(-pts[mask][k][2]),
                    "scene_linear": scene[k].round(4).tolist(),
                    "engine": got[k].tolist(),
                    "port": want[k].tolist(),
                }
                worst[out] = (float(diff[k].max()), where)
        pixels += int(mask.sum())
    return {
        "version": info.get("version"),
        "pixels": pixels,
        "linear": worst["linear"][0],
        "canvas": worst["canvas"][0],
        "linear_at": worst["linear"][1],
        "canvas_at": worst["canvas"][1],
        "info": info,
    }


def _fog_colours(seed: int, n: int) -> list[list[float]]:
    return np.random.default_rng(seed).uniform(0.0, 1.0, (n, 3)).tolist()


def _log_uniform(rng, lo: float, hi: float) -> float:
    return float(np.exp(rng.uniform(math.log(lo), math.log(hi))))


def threejs_setups() -> list[dict]:
    """8 ``Fog`` (near in [0, 5] m, far - near in [1, 60] m) and 8 ``FogExp2`` (density in
    [0.01, 1] 1/m), alternating, with random linear fog colours."""
    rng = np.random.default_rng(7)
    out = []
    for i, color in enumerate(_fog_colours(8, 16)):
        if i % 2:
            out.append({"mode": "FogExp2", "color": color, "density": _log_uniform(rng, 0.01, 1.0)})
        else:
            near = float(rng.uniform(0.0, 5.0))
            out.append({"mode": "Fog", "color": color, "near": near, "far": near + _log_uniform(rng, 1, 60)})
    return out


def threejs_model(fog: dict, output: str) -> Any:
    from fogref.models.threejs import ThreeFogParams, ThreeJSFog

    return ThreeJSFog(ThreeFogParams(**{**fog, "color": tuple(fog["color"])}, output=output))


THREEJS = Engine("threejs", "three", threejs_setups, threejs_model, lambda res, scene: res.display(scene))


def driver_or_skip(*packages: str):
    """A WebGL headless Chromium for the engine pages, or ``pytest.skip`` saying why not."""
    import pytest

    _, _, why = find_browser()
    why = why or node_modules_missing(*packages)
    if why:
        pytest.skip(why)
    try:
        drv = start(200, 200, webgl=True)
    except Exception as e:  # selenium's SessionNotCreatedException, a missing library
        pytest.skip(f"Chromium cannot start: {type(e).__name__}: {(str(e).splitlines() or [''])[0]}")
    drv.set_script_timeout(HANG_S)
    return drv


def _three_mode_setups(seed: int, names: tuple[str, str, str]) -> list[dict]:
    """16 set-ups cycling linear (start in [0, 5] m, end - start in [1, 60] m), exp (density in
    [0.005, 1] 1/m) and exp2 (density in [0.01, 1] 1/m), with random fog colours in [0, 1]."""
    rng = np.random.default_rng(seed)
    out = []
    for i, color in enumerate(_fog_colours(seed + 1, 16)):
        mode = names[i % 3]
        if i % 3 == 0:
            start = float(rng.uniform(0.0, 5.0))
            end = start + _log_uniform(rng, 1, 60)
            out.append({"mode": mode, "color": color, "start": start, "end": end})
        else:
            lo = 0.005 if i % 3 == 1 else 0.01
            out.append({"mode": mode, "color": color, "density": _log_uniform(rng, lo, 1.0)})
    return out


def babylon_setups() -> list[dict]:
    return _three_mode_setups(11, ("LINEAR", "EXP", "EXP2"))


def babylon_model(fog: dict, output: str) -> Any:
    from fogref.models.babylon import BabylonFog, BabylonFogParams

    return BabylonFog(
        BabylonFogParams(
            fogMode=fog["mode"],
            fogColor=tuple(fog["color"]),
            fogDensity=fog.get("density", 0.1),
            fogStart=fog.get("start", 0.0),
            fogEnd=fog.get("end", 1000.0),
        )
    )


def playcanvas_setups() -> list[dict]:
    MODES = ("linear", "exp", "exp2")
    return [{("type" if k == "mode" else k): v for k, v in s.items()} for s in _three_mode_setups(21, MODES)]


def playcanvas_model(fog: dict, output: str) -> Any:
    from fogref.models.playcanvas import PlayCanvasFog, PlayCanvasFogParams

    return PlayCanvasFog(
        PlayCanvasFogParams(
            type=fog["type"],
            color=tuple(fog["color"]),
            density=fog.get("density", 0.0),
            start=fog.get("start", 1.0),
            end=fog.get("end", 1000.0),
            nearClip=NEAR,
            farClip=FAR,
        )
    )


def _playcanvas_canvas(res: Any, scene: np.ndarray) -> np.ndarray:
    from fogref.models.playcanvas import gamma_correct_output

    return gamma_correct_output(res.composite(scene.astype(np.float32)))


BABYLON = Engine(
    "babylon",
    "@babylonjs/core",
    babylon_setups,
    babylon_model,
    lambda res, scene: np.clip(res.composite(scene.astype(np.float32)), 0.0, 1.0),
)
PLAYCANVAS = Engine("playcanvas", "playcanvas", playcanvas_setups, playcanvas_model, _playcanvas_canvas)


def filament_setups() -> list[dict]:
    """16 ``View.FogOptions``: density in [0.01, 0.5] 1/m, heightFalloff 0 or in [0.05, 1] 1/m,
    height in [-5, 5] m, distance in [0, 3] m, maximumOpacity 1 or in [0.5, 1], random colours,
    no cut-off; every other one with a sun term (a directional light toward the view, linear
    colour in [0, 1], intensity in [0.2, 1] at exposure 1; inScatteringSize in [2, 30],
    inScatteringStart in [0, 5] m)."""
    rng = np.random.default_rng(31)
    out = []
    for i, color in enumerate(_fog_colours(32, 16)):
        fog = {
            "color": color,
            "density": _log_uniform(rng, 0.01, 0.5),
            "heightFalloff": 0.0 if i % 4 == 0 else _log_uniform(rng, 0.05, 1.0),
            "height": float(rng.uniform(-5.0, 5.0)),
            "distance": float(rng.uniform(0.0, 3.0)),
            "maximumOpacity": 1.0 if i % 2 else float(rng.uniform(0.5, 1.0)),
            "inScatteringSize": -1.0,
        }
        if i % 2:
            toward = np.array([*rng.uniform(-0.5, 0.5, 2), -1.0])
            fog["inScatteringSize"] = float(rng.uniform(2.0, 30.0))
            fog["inScatteringStart"] = float(rng.uniform(0.0, 5.0))
            fog["sun"] = {
                "direction": (-toward / np.linalg.norm(toward)).tolist(),  # where the light travels
                "color": rng.uniform(0.0, 1.0, 3).tolist(),
                "intensity": float(rng.uniform(0.2, 1.0)),
            }
        out.append(fog)
    return out


def filament_model(fog: dict, output: str) -> Any:
    from fogref.models.filament import FilamentFog, FilamentFogParams

    fog = dict(fog)
    sun = fog.pop("sun", None)
    if sun:  # FogParams: lightDirection toward the sun, lightColorIntensity (colour, intensity x exposure)
        fog["lightDirection"] = tuple(-np.asarray(sun["direction"]))
        fog["lightColorIntensity"] = (*sun["color"], sun["intensity"])
    return FilamentFog(FilamentFogParams(**{**fog, "color": tuple(fog["color"])}, output=output))


FILAMENT = Engine(
    "filament",
    "filament",
    filament_setups,
    filament_model,
    lambda res, scene: res.display(scene.astype(np.float32)),
    outputs=("canvas",),
    background=False,
)
