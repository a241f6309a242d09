"""Fit Unreal's fog colours and cosine lobe to the physical single scattering.

Unreal's Exponential Height Fog adds, per pixel (start distances 0, see
:mod:`fogref.models.ue4`)::

    inscatter = FogInscatteringColor (1 - T) + DirectionalInscatteringColor max(cos, 0)^n (1 - T_dir)

where ``T_dir`` is the transmittance of the part of the ray beyond
DirectionalInscatteringStartDistance.  The physical single scattering of a sun
(irradiance E, toward ``w``) and a uniform sky ``L_sky`` in the same medium is
(closed forms of :mod:`fogref.media.single_scatter`)::

    L = alpha E p_HG(cos) T_sun(o) tau phi(m tau)  +  alpha L_sky (1 - T)

Given the exponent ``n`` and the start distance, the model is **linear** in the
two colours, so each colour channel is a 2-parameter non-negative least-squares
problem on two basis images (the model evaluated with unit colours); ``n`` and
the start distance are then found by scipy (a grid, then Nelder–Mead on
``(log10 n, start)``).  Density, falloff and height come from the exact mapping
:func:`fogref.models.ue4.medium_to_ue4`; the model is evaluated in float64.

The loss is the mean squared error of the inscattered radiance over a set of
views (:func:`sample_views`): directions on a Fibonacci sphere from the scene's
camera, at log-spaced distances, plus the sky (an infinite distance, fogged by
the model at ``sky_distance``) for upward views.

:func:`lobe_fit` is the same question for the phase function alone: the best
``a + c max(mu, 0)^n`` for Henyey–Greenstein ``p_g(mu)``, with relative L2 error
over the sphere of directions (uniform in ``mu``).  With no sun attenuation and
start distance 0 the scene fit reduces exactly to it (both terms carry ``1 - T``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from fogref.errors import FogrefError
from fogref.media import NP, FogMedium, hg_phase, single_scatter_sun
from fogref.media.single_scatter import single_scatter_sky
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams, medium_to_ue4

#: Unreal clamps DirectionalInscatteringExponent to this range.
EXPONENT_RANGE = (1e-6, 1000.0)
#: Search range of log10(exponent) in the fits.
LOG_N_RANGE = (-2.0, 3.0)
#: Where sky views are fogged by the model [m] (same as fogref.compare's default).
SKY_DISTANCE = 1.0e5
#: Upper bound of the fitted DirectionalInscatteringStartDistance [cm] (1 km).
MAX_START_CM = 1.0e5


@dataclass(frozen=True)
class PhysicalFog:
    """The physical scene a fit represents: fog, sun, sky, camera (y-up, metres).

    sun_direction: unit vector toward the sun; sun_irradiance: RGB E;
    sky_radiance: RGB uniform sky radiance; camera: (3,) camera position [m].
    """

    medium: FogMedium
    sun_direction: tuple = (0.0, 1.0, 0.0)
    sun_irradiance: tuple = (1.0, 1.0, 1.0)
    sky_radiance: tuple = (0.0, 0.0, 0.0)
    camera: tuple = (0.0, 2.0, 0.0)

    def __post_init__(self):
        w = np.asarray(self.sun_direction, dtype=float)
        n = float(np.linalg.norm(w))
        if not np.isfinite(n) or n == 0:
            raise FogrefError(f"sun direction {self.sun_direction} is not a direction")
        object.__setattr__(self, "sun_direction", tuple(float(x) for x in w / n))
        for name in ("sun_irradiance", "sky_radiance", "camera"):
            object.__setattr__(self, name, tuple(float(x) for x in np.broadcast_to(getattr(self, name), 3)))

    @classmethod
    def from_params(cls, params: dict, camera=None) -> PhysicalFog:
        """From ``describe_scene``'s dict or an EXR's ``fogref.params``."""
        from fogref.render.params import medium_from_params

        med = medium_from_params(params["medium"], f"{params.get('scene', '<scene>')}: medium")
        sun = params.get("sun") or {"direction": [0.0, 1.0, 0.0], "irradiance": [0.0, 0.0, 0.0]}
        sky = params.get("sky") or {}
        L = sky.get("radiance", [0.0, 0.0, 0.0])
        L = [float(L)] * 3 if isinstance(L, (int, float)) else [float(x) for x in L]
        if camera is None:
            camera = (params.get("camera") or {}).get("origin", (0.0, 2.0, 0.0))
        return cls(med, tuple(sun["direction"]), tuple(sun["irradiance"]), tuple(L), tuple(camera))

    @classmethod
    def from_scene(cls, path, camera=None) -> PhysicalFog:
        """From a fogref XML scene (no Mitsuba needed): fog, sun, sky and the sensor's origin."""
        from fogref.render.scene import describe_scene

        desc = describe_scene(path)
        if desc["medium"] is None:
            raise FogrefError(f"{path}: no <medium type=\"heightfog\"> in the scene")
        return cls.from_params(desc, camera if camera is not None else _lookat_origin(path))


def _lookat_origin(path):
    import xml.etree.ElementTree as ET

    root = ET.parse(path).getroot()
    for s in root.iter("sensor"):
        la = s.find(".//lookat")
        if la is not None and la.get("origin"):
            return tuple(float(x) for x in la.get("origin").replace(",", " ").split())
    return None


@dataclass
class Views:
    """Sample views: unit directions ``d`` (N, 3), distances ``D`` (N,) [m] (inf: sky)."""

    camera: np.ndarray
    d: np.ndarray
    D: np.ndarray

    @property
    def sky(self) -> np.ndarray:
        return ~np.isfinite(self.D)

    def world_positions(self, sky_distance: float = SKY_DISTANCE) -> np.ndarray:
        D = np.where(self.sky, sky_distance, self.D)
        return self.camera + self.d * D[:, None]


def fibonacci_directions(n: int) -> np.ndarray:
    """``n`` nearly uniform unit directions on the sphere (y-up), (n, 3)."""
    i = np.arange(n) + 0.5
    y = 1.0 - 2.0 * i / n
    r = np.sqrt(np.maximum(0.0, 1.0 - y * y))
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    return np.stack([r * np.cos(phi), y, r * np.sin(phi)], axis=-1)


def sample_views(camera, n_dirs: int = 400, distances=None, min_dy: float = -0.5,
                 sky_min_dy: float = 0.0) -> Views:
    """Views from ``camera``: Fibonacci directions with ``d_y >= min_dy`` at each of
    ``distances`` [m] (default 12 log-spaced from 10 m to 20 km), plus the sky
    (infinite distance) for directions with ``d_y > sky_min_dy``."""
    if distances is None:
        distances = np.geomspace(10.0, 2.0e4, 12)
    dirs = fibonacci_directions(n_dirs)
    dirs = dirs[dirs[:, 1] >= min_dy]
    D = np.asarray(distances, dtype=float)
    d_all = np.repeat(dirs, len(D), axis=0)
    D_all = np.tile(D, len(dirs))
    up = dirs[dirs[:, 1] > sky_min_dy]
    d_all = np.concatenate([d_all, up])
    D_all = np.concatenate([D_all, np.full(len(up), np.inf)])
    return Views(np.asarray(camera, dtype=float), d_all, D_all)


def physical_single_scattering(pf: PhysicalFog, views: Views, sun_attenuation: bool = True,
                               sky: bool = True, sun: bool = True) -> np.ndarray:
    """Closed-form single scattering (sun + sky, no occluders) of each view, (N, 3).

    ``sun_attenuation=False``: the sun term without its attenuation in the fog,
    ``alpha E p (1 - T)``.  The sky term is ``alpha L_sky (1 - T)`` (unoccluded,
    unattenuated: what FogInscatteringColor stands for).
    """
    m = pf.medium
    o = tuple(np.full(len(views.D), c) for c in views.camera)
    d = tuple(views.d[:, i] for i in range(3))
    D = np.where(views.sky, NP.largest, views.D)
    out = np.zeros((len(D), 3))
    if sun and max(pf.sun_irradiance) > 0:
        w = pf.sun_direction
        if sun_attenuation:
            out += np.stack(single_scatter_sun(NP, m, o, d, D, w, pf.sun_irradiance), axis=-1)
        elif w[1] > 0:
            cos = d[0] * w[0] + d[1] * w[1] + d[2] * w[2]
            p = hg_phase(NP, cos, m.g)
            T = np.stack(m.transmittance(NP, o, d, D), axis=-1)
            out += (np.asarray(m.albedo) * np.asarray(pf.sun_irradiance)) * p[:, None] * (1.0 - T)
    if sky and max(pf.sky_radiance) > 0:
        out += np.stack(single_scatter_sky(NP, m, o, d, D, pf.sky_radiance), axis=-1)
    return out


def base_params(pf: PhysicalFog, **kw) -> UE4FogParams:
    """Unreal parameters with the exact density/falloff/height of ``pf.medium``, the
    sun direction, and ``kw`` (other fields; start distances default to 0)."""
    defaults = dict(DirectionalInscatteringStartDistance=0.0, StartDistance=0.0, FogMaxOpacity=1.0,
                    FogCutoffDistance=0.0, SunLuminance=1.0)
    defaults.update(kw)
    p = medium_to_ue4(pf.medium, replace(UE4FogParams(), **defaults))
    return p.with_sun(pf.sun_direction, p.SunLuminance)


def unreal_inscatter(params: UE4FogParams, camera, world_pos, precision: str = "float64") -> np.ndarray:
    """Unreal's inscatter (N, 3) for the given parameters."""
    return np.asarray(UE4ExponentialHeightFog(params).evaluate(camera, world_pos, precision).inscatter, dtype=float)


@dataclass
class Basis:
    """The two basis images of Unreal's inscatter at fixed exponent and start distance."""

    iso: np.ndarray   # (N,) 1 - T
    lobe: np.ndarray  # (N,) max(cos,0)^n (1 - T_dir)


def unreal_basis(pf: PhysicalFog, views: Views, exponent: float, start_cm: float,
                 sky_distance: float = SKY_DISTANCE) -> Basis:
    """Unreal (float64) evaluated with unit colours: the isotropic and lobe images."""
    wp = views.world_positions(sky_distance)
    p = base_params(pf, DirectionalInscatteringExponent=exponent, DirectionalInscatteringStartDistance=start_cm,
                    FogInscatteringColor=(1.0, 0.0, 0.0), DirectionalInscatteringColor=(0.0, 1.0, 0.0))
    ins = unreal_inscatter(p, np.asarray(pf.camera), wp)
    return Basis(iso=ins[:, 0], lobe=ins[:, 1])


def solve_colours(basis: Basis, target: np.ndarray, weights=None) -> tuple[np.ndarray, np.ndarray, float]:
    """Non-negative least squares per channel: ``target ≈ C_fog iso + C_dir lobe``.

    Returns ``(C_fog (3,), C_dir (3,), sse)`` with ``sse`` the weighted sum of
    squared residuals over all channels.
    """
    from scipy.optimize import nnls

    A = np.stack([basis.iso, basis.lobe], axis=-1)
    sw = np.ones(len(A)) if weights is None else np.sqrt(np.asarray(weights, dtype=float))
    Aw = A * sw[:, None]
    cf, cd, sse = np.zeros(3), np.zeros(3), 0.0
    for c in range(3):
        x, r = nnls(Aw, target[:, c] * sw)
        cf[c], cd[c] = x
        sse += r * r
    return cf, cd, float(sse)


@dataclass
class FitResult:
    """Best Unreal parameters for a physical fog, and how well they do on the views."""

    params: UE4FogParams
    rmse: float                  #: RMSE of the inscatter over the views (radiance)
    rel_rmse: float              #: rmse / RMS of the physical inscatter
    target_rms: float
    n_views: int
    sun_attenuation: bool
    fit_start: bool
    history: dict = field(default_factory=dict)

    def editor_properties(self) -> dict:
        """The fitted values under the names of Unreal's details panel."""
        p = self.params
        return {
            "Fog Density": p.FogDensity,
            "Fog Height Falloff": p.FogHeightFalloff,
            "Fog Height Offset": p.FogHeight,
            "Fog Inscattering Color": list(p.FogInscatteringColor),
            "Directional Inscattering Color": list(p.DirectionalInscatteringColor),
            "Directional Inscattering Exponent": p.DirectionalInscatteringExponent,
            "Directional Inscattering Start Distance": p.DirectionalInscatteringStartDistance,
            "Start Distance": p.StartDistance,
            "Fog Max Opacity": p.FogMaxOpacity,
            "Fog Cutoff Distance": p.FogCutoffDistance,
        }

    def to_dict(self) -> dict:
        p = self.params
        return {
            "unreal": {
                "FogDensity": p.FogDensity, "FogHeightFalloff": p.FogHeightFalloff,
                "FogHeight_cm": p.FogHeight,
                "FogInscatteringColor": list(p.FogInscatteringColor),
                "DirectionalInscatteringColor": list(p.DirectionalInscatteringColor),
                "DirectionalInscatteringExponent": p.DirectionalInscatteringExponent,
                "DirectionalInscatteringStartDistance_cm": p.DirectionalInscatteringStartDistance,
                "InscatteringLightDirection_unreal": list(p.InscatteringLightDirection or ()),
                "SunLuminance": p.SunLuminance,
                "SecondFogData": {"FogDensity": p.SecondFogData.FogDensity,
                                  "FogHeightFalloff": p.SecondFogData.FogHeightFalloff,
                                  "FogHeightOffset_cm": p.SecondFogData.FogHeightOffset},
            },
            "unreal_editor": self.editor_properties(),
            "error": {"rmse": self.rmse, "rel_rmse": self.rel_rmse, "target_rms": self.target_rms,
                      "n_views": self.n_views},
            "fit": {"sun_attenuation_in_target": self.sun_attenuation, "start_distance_fitted": self.fit_start,
                    "loss": "mean squared inscatter error over views (all RGB channels), model float64",
                    **self.history},
        }


def fit_unreal(pf: PhysicalFog, views: Views | None = None, *, sun_attenuation: bool = True,
               fit_start: bool = True, target: np.ndarray | None = None,
               sky_distance: float = SKY_DISTANCE, exponent: float | None = None) -> FitResult:
    """Best FogInscatteringColor, DirectionalInscatteringColor, exponent and (if
    ``fit_start``) DirectionalInscatteringStartDistance for ``pf``.

    ``target``: the (N, 3) inscatter to match (default: the closed-form physical
    single scattering of sun and sky, :func:`physical_single_scattering`).
    ``exponent``: keep the exponent fixed (only colours, and start, are fitted).
    """
    from scipy.optimize import minimize

    if views is None:
        views = sample_views(pf.camera)
    if target is None:
        target = physical_single_scattering(pf, views, sun_attenuation=sun_attenuation)
    target = np.asarray(target, dtype=float)
    N = len(views.D)
    cache: dict = {}

    def sse(log_n: float, start_cm: float):
        log_n = float(np.clip(log_n, *LOG_N_RANGE))
        start_cm = float(np.clip(start_cm, 0.0, MAX_START_CM)) if fit_start else 0.0
        key = (round(log_n, 12), round(start_cm, 9))
        if key not in cache:
            b = unreal_basis(pf, views, 10.0 ** log_n, start_cm, sky_distance)
            cache[key] = solve_colours(b, target)
        return cache[key]

    # coarse grid, then Nelder–Mead (or 1-D bounded search) from the best point
    log_ns = [math.log10(exponent)] if exponent is not None else np.linspace(*LOG_N_RANGE, 21)
    starts = [0.0, 2e3, 1e4, 3e4] if fit_start else [0.0]
    grid = [(ln, s, sse(ln, s)[2]) for ln in log_ns for s in starts]
    ln0, s0, _ = min(grid, key=lambda r: r[2])
    if exponent is None or fit_start:
        x0 = []
        if exponent is None:
            x0.append(ln0)
        if fit_start:
            x0.append(s0 / 1e4)

        def f(x):
            i = 0
            ln = ln0
            if exponent is None:
                ln = x[0]
                i = 1
            s = x[i] * 1e4 if fit_start else 0.0
            pen = 0.0
            if fit_start and s < 0:
                pen = s * s
            return sse(ln, max(s, 0.0))[2] * (1.0 + pen)

        res = minimize(f, np.asarray(x0), method="Nelder-Mead",
                       options={"xatol": 1e-4, "fatol": 1e-12 * max(1.0, float(np.sum(target ** 2))),
                                "maxiter": 400, "initial_simplex": None})
        x = res.x
        i = 0
        if exponent is None:
            ln0 = float(np.clip(x[0], *LOG_N_RANGE))
            i = 1
        if fit_start:
            s0 = float(np.clip(x[i] * 1e4, 0.0, MAX_START_CM))
    cf, cd, best = sse(ln0, s0)
    params = base_params(pf, FogInscatteringColor=tuple(cf), DirectionalInscatteringColor=tuple(cd),
                         DirectionalInscatteringExponent=10.0 ** ln0,
                         DirectionalInscatteringStartDistance=s0 if fit_start else 0.0)
    rmse = math.sqrt(best / (3 * N))
    trms = math.sqrt(float(np.mean(target ** 2)))
    return FitResult(params=params, rmse=rmse, rel_rmse=rmse / trms if trms > 0 else 0.0, target_rms=trms,
                     n_views=N, sun_attenuation=sun_attenuation, fit_start=fit_start,
                     history={"evaluations": len(cache)})


# ----------------------------------------------------------------- phase lobe alone

def _mu_quadrature(n: int = 256):
    """Gauss–Legendre nodes/weights on [-1, 0] and [0, 1] (the lobe has a kink at 0)."""
    x, w = np.polynomial.legendre.leggauss(n)
    mu = np.concatenate([0.5 * (x - 1.0), 0.5 * (x + 1.0)])
    return mu, np.concatenate([0.5 * w, 0.5 * w])


def lobe_fit(g: float, isotropic: bool = True, n_quad: int = 256) -> dict:
    """Best ``a + c max(mu, 0)^n`` (``a`` = 0 when not ``isotropic``) for HG ``p_g(mu)``.

    Least squares over the sphere (uniform in ``mu``), ``a, c >= 0``.  Returns
    ``{"g", "exponent", "lobe" (c * 4 pi), "iso" (a * 4 pi), "rel_error"}``:
    coefficients relative to the isotropic phase 1/(4 pi) (so DirectionalInscatteringColor
    = alpha E c and FogInscatteringColor = alpha (L_sky + E a) when sun attenuation
    is ignored), rel_error = ||fit - p|| / ||p||.  ``exponent`` is None when the
    best lobe is 0 (the fit is flat).
    """
    from scipy.optimize import minimize_scalar, nnls

    mu, w = _mu_quadrature(n_quad)
    p = hg_phase(NP, mu, float(g))
    sw = np.sqrt(w)
    norm = math.sqrt(float(np.sum(w * p * p)))

    def solve(log_n):
        lobe = np.maximum(mu, 0.0) ** (10.0 ** log_n)
        A = np.stack([np.ones_like(mu), lobe], -1) if isotropic else lobe[:, None]
        x, r = nnls(A * sw[:, None], p * sw)
        return x, r

    grid = np.linspace(*LOG_N_RANGE, 51)
    rs = [solve(ln)[1] for ln in grid]
    k = int(np.argmin(rs))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    res = minimize_scalar(lambda ln: solve(ln)[1], bounds=(lo, hi), method="bounded", options={"xatol": 1e-6})
    ln = float(res.x) if res.fun <= rs[k] else float(grid[k])
    x, r = solve(ln)
    a, c = (x[0], x[1]) if isotropic else (0.0, x[0])
    flat = c * 4 * math.pi < 1e-9
    return {"g": float(g), "exponent": None if flat else 10.0 ** ln, "lobe": float(c * 4 * math.pi),
            "iso": float(a * 4 * math.pi), "rel_error": float(r / norm) if norm > 0 else 0.0}


def lobe_table(gs=None, pf: PhysicalFog | None = None, views: Views | None = None) -> list[dict]:
    """:func:`lobe_fit` for each g (default -0.9 to 0.9 step 0.1), with and without
    the isotropic term; with ``pf`` also the full scene fit (sun attenuation on,
    start distance fitted) for that g: its exponent and relative RMSE."""
    if gs is None:
        gs = np.round(np.arange(-0.9, 0.9001, 0.1), 10)
    rows = []
    for g in gs:
        g = float(round(float(g), 10)) + 0.0  # no "-0.0"
        row = lobe_fit(g)
        only = lobe_fit(g, isotropic=False)
        row["lobe_only_exponent"] = only["exponent"]
        row["lobe_only_rel_error"] = only["rel_error"]
        if pf is not None:
            m = replace(pf.medium, g=float(g))
            r = fit_unreal(replace(pf, medium=m), views)
            p = r.params
            lobe_on = max(p.DirectionalInscatteringColor) > 1e-6 * max(max(p.FogInscatteringColor), 1e-300)
            row["scene_exponent"] = p.DirectionalInscatteringExponent if lobe_on else None
            row["scene_start_distance_cm"] = p.DirectionalInscatteringStartDistance if lobe_on else 0.0
            row["scene_fog_colour"] = list(r.params.FogInscatteringColor)
            row["scene_dir_colour"] = list(r.params.DirectionalInscatteringColor)
            row["scene_rel_rmse"] = r.rel_rmse
        rows.append(row)
    return rows


def write_lobe_table(rows: list[dict], out_dir, scene_name: str | None = None) -> dict:
    """``lobe_table.json``, ``lobe_table.md`` and ``lobe_table.png`` in ``out_dir``."""
    import json
    from pathlib import Path

    from fogref.atomic import save_figure_atomic as save_figure
    from fogref.atomic import write_text_atomic as write_text

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    doc = {"description": "Best Unreal cosine lobe a + c max(mu,0)^n for Henyey-Greenstein p_g(mu); "
                          "coefficients relative to 1/(4 pi); rel_error = L2 over the sphere / ||p||. "
                          "scene_*: full fit (sun + sky, sun attenuation, start distance) on "
                          f"{scene_name or 'the scene'}'s fog with that g.",
           "rows": rows}
    write_text(out / "lobe_table.json", json.dumps(doc, indent=2) + "\n")
    has_scene = any("scene_rel_rmse" in r for r in rows)

    def f(x, fmt="{:.3g}"):
        return "—" if x is None else fmt.format(x)

    head = "| g | exponent n | lobe c·4π | iso a·4π | rel. error | lobe only: n | lobe only: rel. error |"
    sep = "|---|---|---|---|---|---|---|"
    if has_scene:
        head += " scene fit: n | scene fit: start [m] | scene fit: rel. RMSE |"
        sep += "---|---|---|"
    lines = ["# Cosine lobe vs Henyey–Greenstein", "",
             "Best `a + c·max(cosθ, 0)^n` (Unreal: FogInscatteringColor carries `a`, "
             "DirectionalInscatteringColor carries `c`, DirectionalInscatteringExponent is `n`) for the HG phase "
             "function of asymmetry g; least squares over the sphere of directions.  `c·4π`, `a·4π` are relative to "
             "the isotropic phase 1/(4π) (multiply by albedo × sun irradiance for the colours).  "
             "`rel. error` = ‖fit − p‖/‖p‖.  *Lobe only*: without the isotropic term.  — : the best lobe is 0 "
             "(flat: the isotropic term does everything); for g ≤ 0 the cosine lobe cannot help (it only adds light "
             "forward), and n = 0.01 is the search bound (the lobe degenerates to a half-sphere step).", ""]
    if has_scene:
        lines += [f"*Scene fit*: the full fit of `fogref fit` (sun + sky single scattering with sun attenuation, "
                  f"views from the camera) on {scene_name or 'the scene'}'s fog with that g; relative RMSE of the "
                  "inscatter over the views.", ""]
    lines += [head, sep]
    for r in rows:
        s = (f"| {r['g']:+.1f} | {f(r['exponent'])} | {r['lobe']:.3g} | {r['iso']:.3g} | {r['rel_error']:.3f} | "
             f"{f(r['lobe_only_exponent'])} | {r['lobe_only_rel_error']:.3f} |")
        if has_scene:
            s += (f" {f(r.get('scene_exponent'))} | {r.get('scene_start_distance_cm', 0) / 100:.1f} | "
                  f"{f(r.get('scene_rel_rmse'), '{:.3f}')} |")
        lines.append(s)
    lines += ["", "![lobe table](lobe_table.png)", ""]
    write_text(out / "lobe_table.md", "\n".join(lines))

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    g = np.array([r["g"] for r in rows])
    fig, ax = plt.subplots(1, 3, figsize=(13, 3.6))
    n = np.array([np.nan if r["exponent"] is None else r["exponent"] for r in rows])
    n_only = np.array([np.nan if r["lobe_only_exponent"] is None else r["lobe_only_exponent"] for r in rows])
    ax[0].semilogy(g, n, "o-", label="lobe + iso")
    ax[0].semilogy(g, n_only, "s--", label="lobe only")
    if has_scene:
        ax[0].semilogy(g, [np.nan if r.get("scene_exponent") is None else r["scene_exponent"] for r in rows], "^:",
                       label="scene fit")
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
        line, = ax[2].semilogy(mu, p, label=f"HG g={gg}")
        ax[2].semilogy(mu, np.maximum(fit, 1e-3), "--", color=line.get_color())
    ax[2].set_xlabel("cos θ (view · sun)"), ax[2].set_ylabel("phase × 4π (solid: HG, dashed: fit)")
    ax[2].legend(fontsize=8), ax[2].grid(alpha=0.3)
    fig.tight_layout()
    save_figure(fig, out / "lobe_table.png")
    plt.close(fig)
    return doc
