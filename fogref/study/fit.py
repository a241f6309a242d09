"""The ``fogref fit`` reports: the scene read from an XML file and the lobe table's pages.

The numbers come from :mod:`fogref.mapping` (the physical scene, Unreal's fit
:func:`fogref.mapping.fit_unreal`, the lobe fit :func:`fogref.mapping.lobe_fit`
and :func:`fogref.mapping.lobe_table`); this module only reads scenes and writes
reports.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from fogref import mapping
from fogref.atomic import save_figure_atomic as save_figure
from fogref.atomic import write_text_atomic as write_text
from fogref.compare.plots import agg_figure
from fogref.errors import FogrefError
from fogref.mapping import PhysicalScene, lobe_fit
from fogref.media import NP, hg_phase
from fogref.render.load import describe_scene
from fogref.scene.describe import lookat_camera
from fogref.scene.parsed import ParsedScene, read_scene
from fogref.shipped_scenes import SCENES_DIR, resolve_scene


def physical_from_scene(path, camera=None) -> PhysicalScene:
    """The physical scene of a fogref XML file (a path or a :class:`~fogref.scene.parsed.ParsedScene`;
    no Mitsuba needed): fog, sun, sky and the sensor's ``lookat`` origin (``camera`` [m] overrides
    it) and view direction."""
    scene = path if isinstance(path, ParsedScene) else read_scene(path)  # once, for fog and camera
    desc = describe_scene(scene)
    if desc["medium"] is None:
        raise FogrefError(f'{path}: no <medium type="heightfog"> in the scene')
    look = lookat_camera(scene)
    if not desc.get("camera") and look is not None:
        forward = np.subtract(look["target"], look["origin"])
        desc = {**desc, "camera": {"origin": look["origin"], "forward": forward.tolist()}}
    if camera is None:
        camera = (desc.get("camera") or {}).get("origin")
    return PhysicalScene.from_params(desc, camera)


def write_lobe_table(rows: list[dict], out_dir, scene_name: str | None = None) -> dict:
    """``lobe_table.json``, ``lobe_table.md`` and ``lobe_table.png`` in ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    doc = {
        "description": "Best Unreal cosine lobe a + c max(mu,0)^n for Henyey-Greenstein p_g(mu); "
        "coefficients relative to 1/(4 pi); rel_error = L2 over the sphere / ||p||. "
        "scene_*: full fit (sun + sky, sun attenuation, start distance) on "
        f"{scene_name or 'the scene'}'s fog with that g.",
        "rows": rows,
    }
    write_text(out / "lobe_table.json", json.dumps(doc, indent=2) + "\n")
    has_scene = any("scene_rel_rmse" in r for r in rows)

    def f(x, fmt="{:.3g}"):
        return "—" if x is None else fmt.format(x)

    head = "| g | exponent n | lobe c·4π | iso a·4π | rel. error | lobe only: n | lobe only: rel. error |"
    sep = "|---|---|---|---|---|---|---|"
    if has_scene:
        head += " scene fit: n | scene fit: start [m] | scene fit: rel. RMSE |"
        sep += "---|---|---|"
    lines = [
        "# Cosine lobe vs Henyey–Greenstein",
        "",
        "Best `a + c·max(cosθ, 0)^n` (Unreal: FogInscatteringColor carries `a`, "
        "DirectionalInscatteringColor carries `c`, DirectionalInscatteringExponent is `n`) "
        "for the HG phase function of asymmetry g; least squares over the sphere of directions.  "
        "`c·4π`, `a·4π` are relative to "
        "the isotropic phase 1/(4π) (multiply by albedo × sun irradiance for the colours).  "
        "`rel. error` = ‖fit − p‖/‖p‖.  *Lobe only*: without the isotropic term.  "
        "— : the best lobe is 0 (flat: the isotropic term does everything); "
        "for g ≤ 0 the cosine lobe cannot help (it only adds light "
        "forward), and n = 0.01 is the search bound (the lobe degenerates to a half-sphere step).",
        "",
    ]
    if has_scene:
        lines += [
            "*Scene fit*: the full fit of `fogref fit` (sun + sky single scattering with sun "
            f"attenuation, views from the camera) on {scene_name or 'the scene'}'s fog with that g; "
            "relative RMSE of the inscatter over the views.",
            "",
        ]
    lines += [head, sep]
    for r in rows:
        s = (
            f"| {r['g']:+.1f} | {f(r['exponent'])} | {r['lobe']:.3g} | {r['iso']:.3g} | "
            f"{r['rel_error']:.3f} | {f(r['lobe_only_exponent'])} | {r['lobe_only_rel_error']:.3f} |"
        )
        if has_scene:
            s += (
                f" {f(r.get('scene_exponent'))} | {r.get('scene_start_distance_cm', 0) / 100:.1f} | "
                f"{f(r.get('scene_rel_rmse'), '{:.3f}')} |"
            )
        lines.append(s)
    lines += ["", "![lobe table](lobe_table.png)", ""]
    write_text(out / "lobe_table.md", "\n".join(lines))

    g = np.array([r["g"] for r in rows])
    fig = agg_figure(13, 3.6)
    ax = fig.subplots(1, 3)
    n = np.array([np.nan if r["exponent"] is None else r["exponent"] for r in rows])
    n_only = np.array([np.nan if r["lobe_only_exponent"] is None else r["lobe_only_exponent"] for r in rows])
    ax[0].semilogy(g, n, "o-", label="lobe + iso")
    ax[0].semilogy(g, n_only, "s--", label="lobe only")
    if has_scene:
        scene_n = [np.nan if r.get("scene_exponent") is None else r["scene_exponent"] for r in rows]
        ax[0].semilogy(g, scene_n, "^:", label="scene fit")
    ax[0].set_xlabel("g"), ax[0].set_ylabel("best exponent n"), ax[0].legend(), ax[0].grid(alpha=0.3)
    ax[1].plot(g, [r["rel_error"] for r in rows], "o-", label="lobe + iso (phase)")
    ax[1].plot(g, [r["lobe_only_rel_error"] for r in rows], "s--", label="lobe only (phase)")
    if has_scene:
        ax[1].plot(g, [r.get("scene_rel_rmse", np.nan) for r in rows], "^:", label="scene fit (inscatter)")
    ax[1].set_xlabel("g"), ax[1].set_ylabel("relative error"), ax[1].legend(), ax[1].grid(alpha=0.3)
    mu = np.linspace(-1, 1, 400)
    for gg in (-0.5, 0.3, 0.6, 0.9):
        r = lobe_fit(gg)
        p = hg_phase(NP, mu, gg) * 4 * math.pi
        fit = r["iso"] + r["lobe"] * np.maximum(mu, 0) ** (r["exponent"] or 1.0)
        (line,) = ax[2].semilogy(mu, p, label=f"HG g={gg}")
        ax[2].semilogy(mu, np.maximum(fit, 1e-3), "--", color=line.get_color())
    ax[2].set_xlabel("cos θ (view · sun)"), ax[2].set_ylabel("phase × 4π (solid: HG, dashed: fit)")
    ax[2].legend(fontsize=8), ax[2].grid(alpha=0.3)
    fig.tight_layout()
    save_figure(fig, out / "lobe_table.png")
    return doc


#: The reference scene of :func:`fit_model` and :func:`translate` without one (shipped with fogref).
DEFAULT_SCENE = SCENES_DIR / "valley.xml"


def reference_scene(scene=None, camera=None) -> PhysicalScene:
    """The physical scene of a scene XML path or shipped name (default :data:`DEFAULT_SCENE`), an
    EXR's ``fogref.params`` dict, or a :class:`~fogref.mapping.PhysicalScene` as it is.

    >>> reference_scene("valley") == reference_scene()
    True
    """
    if scene is None:
        scene = DEFAULT_SCENE
    if isinstance(scene, (str, Path)):
        scene = resolve_scene(scene)
        if not Path(scene).is_file():
            raise FogrefError(f"{scene}: no such scene file")
        return physical_from_scene(scene, camera=camera)
    if isinstance(scene, dict):
        return PhysicalScene.from_params(scene, camera)
    return scene


def fit_model(name, scene=None, views=None, sun_elevations=None, **kw):
    """``fogref.fit_model``: :func:`fogref.mapping.fit.fit_model` of a model for a scene XML path
    (default :data:`DEFAULT_SCENE`), an EXR's ``fogref.params`` dict or a
    :class:`~fogref.mapping.PhysicalScene`.  Returns a :class:`fogref.mapping.fit.ModelFit`."""
    return mapping.fit_model(name, reference_scene(scene), views=views, sun_elevations=sun_elevations, **kw)


def translate(source, target, params: dict | None = None, scene=None, **kw):
    """``fogref.translate``: :func:`fogref.mapping.translate.translate` with a scene XML path, a
    shipped scene's name, dict or scene as the reference.  Returns a
    :class:`fogref.mapping.translate.Translation`.

    Without ``scene`` the source's settings that are not in ``params`` are the engine's defaults
    and :data:`DEFAULT_SCENE` is the reference (camera, albedo, sun); with one, they come from
    that scene's fit (``fill`` overrides either).
    """
    kw.setdefault("fill", "defaults" if scene is None else "mapping")
    if isinstance(scene, (str, Path)):
        label = str(scene)
    else:
        label = f"the default scene {DEFAULT_SCENE.name}" if scene is None else "the reference scene"
    kw.setdefault("scene_label", label)
    return mapping.translate(source, target, params, reference_scene(scene), **kw)
