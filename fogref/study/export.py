"""Engine settings from a fit, a translation, ``params`` or a scene's fit, with the scene's camera
and sun, written by :func:`fogref.mapping.export.export`: ``fogref.export_engine`` and
``fogref export``.

Examples
--------
>>> files = export_engine("threejs", params={"mode": "FogExp2", "density": 0.002})
>>> "scene.fog = new THREE.FogExp2(fogColor, 0.002);" in files[".mjs"]
True
"""

from __future__ import annotations

import json
from pathlib import Path

from fogref.errors import FogrefError, ParameterError
from fogref.mapping.build import build_model
from fogref.mapping.export import ENGINES, Camera, Sun, export
from fogref.mapping.fit import with_sun_elevation
from fogref.scene.describe import lookat_camera
from fogref.scene.parsed import read_scene
from fogref.shipped_scenes import resolve_scene
from fogref.study.fit import fit_model, physical_from_scene

__all__ = ["export_engine", "settings_from_json"]


def _finite(v):
    """JSON's "inf" strings (fogref writes non-finite floats so) back to floats."""
    if isinstance(v, str) and v in ("inf", "-inf"):
        return float(v)
    if isinstance(v, dict):
        return {k: _finite(x) for k, x in v.items()}
    return v


def settings_from_json(path, model: str, elevation: float | None = None) -> tuple[dict, dict, str]:
    """``(settings, physical, what)`` of a fit, translate or fit-table JSON for ``model``."""
    try:
        doc = json.loads(Path(path).read_text())
    except json.JSONDecodeError as e:
        raise FogrefError(f"{path}: not JSON ({e.msg}, line {e.lineno})") from None
    if not isinstance(doc, dict):
        raise FogrefError(f"{path}: expected a JSON object")
    if "fits" in doc:  # a fit table (scripts/fit_table.py)
        rows = [r for r in doc["fits"] if r.get("model") == model]
        if not rows:
            raise FogrefError(f"{path}: no fit of '{model}' in the table")
        els = [r["fit"]["sun_elevations_deg"][0] for r in rows]
        row = rows[0] if elevation is None else next((r for r, e in zip(rows, els) if e == elevation), None)
        if row is None:
            shown = ", ".join(f"{e:g}" for e in els)
            raise FogrefError(f"{path}: no fit of '{model}' at {elevation:g} deg (the table has {shown})")
        e = row["fit"]["sun_elevations_deg"][0]
        return row["settings"], {"sun_elevation": e}, f"the {model} fit at sun elevation {e:g} deg in {path}"
    if "target" in doc:  # fogref translate
        tgt = doc["target"]
        if tgt.get("model") != model:
            raise FogrefError(f"{path}: translates to '{tgt.get('model')}', not '{model}'")
        return (
            tgt["settings"],
            doc.get("physical") or {},
            f"fogref translate from {doc['source']['model']} ({path})",
        )
    if doc.get("model") == model or ("unreal" in doc and model == "ue4"):  # fogref fit
        if "settings" not in doc:
            raise FogrefError(f"{path}: no 'settings' (write it again with this fogref's fit)")
        return doc["settings"], doc.get("physical") or {}, f"fogref fit ({path})"
    raise FogrefError(f"{path}: not a fit, translate or fit-table JSON of '{model}'")


def export_engine(
    engine: str,
    json_path=None,
    params: dict | None = None,
    scene="valley",
    sun_elevation: float | None = None,
) -> dict[str, str]:
    """Paste-ready text for ``engine`` (:data:`fogref.mapping.export.ENGINES`): ``{suffix: text}``.

    Parameters
    ----------
    engine : str
        ``"unreal"``, ``"godot"``, ``"bevy"``, ``"threejs"``, ``"unity"``, ``"hdrp"`` or ``"filament"``.
    json_path : path, optional
        The JSON of ``fogref fit`` (``--model``, or Unreal's own), ``fogref translate`` or a fit table
        (``reports/fit/engines.json``; ``sun_elevation`` [deg] picks its row, default the first).
    params : dict, optional
        Settings in the engine model's names, on top of the JSON's (or of the model's defaults).
    scene : path or str
        The scene whose camera and sun are written (a shipped scene's name or a path); without
        ``json_path`` and ``params`` the model is fitted to it (:func:`fogref.fit_model`).
    """
    if engine not in ENGINES:
        export(engine, None, Camera((0, 0, 0), (0, 0, 1)), Sun((0, 1, 0), (1, 1, 1)))  # names the engines
    model = ENGINES[engine]
    parsed = read_scene(resolve_scene(scene))
    pf = physical_from_scene(parsed)
    cam = lookat_camera(parsed)
    if cam is None:
        raise FogrefError(f"{parsed.path}: no sensor with a <lookat> (the export needs the camera)")
    settings: dict = {}
    sun_dir, sun_E = pf.sun_direction, pf.sun_irradiance
    if json_path is not None:
        raw, phys, what = settings_from_json(json_path, model, sun_elevation)
        settings = _finite(dict(raw))
        if "sun_elevation" in phys:
            sun_dir = with_sun_elevation(pf, phys["sun_elevation"]).sun_direction
        sun_dir = phys.get("sun_direction", sun_dir)
        sun_E = phys.get("sun_irradiance", sun_E)
    elif sun_elevation is not None:
        raise ParameterError("fogref export", "sun_elevation", "picks a row of a fit table: give its JSON")
    elif not params:
        r = fit_model(model, pf)
        settings = dict(vars(r.params))
        what = f"fogref fit --model {model} --scene {scene} (inscatter relative RMSE {r.rel_rmse:.3f})"
    else:
        what = f"{model}'s defaults"
    if params:
        settings.update(params)
        what += " with " + ", ".join(f"{k}={v}" for k, v in params.items())
    fog = build_model(model, settings).params
    camera = Camera(cam["origin"], cam["target"], cam["up"], cam["fov_deg"], cam["resolution"])
    return export(engine, fog, camera, Sun(sun_dir, sun_E), source=what)
