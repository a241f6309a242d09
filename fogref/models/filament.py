"""Google Filament height fog (``View::FogOptions``).

Follows Filament 1.53.4 (tag ``v1.53.4``): ``shaders/src/surface_fog.fs`` (the "Real-time
Atmospheric Effects in Games (Carsten Wenzel)" version, ``exp`` based) and
``PerViewUniforms::prepareFog`` (CPU: ``fogDensity = (density, -heightFalloff (camera.y -
height), density exp(-heightFalloff (camera.y - height)))``); the same GLSL is in the
1.53.4 web build's ``filament.wasm`` (gltfio's ubershaders).  Held to that web build (npm
``filament`` 1.53.4) in headless Chromium by ``tests/test_web_filament.py``: unlit quads,
post-processing off, sun term on, the 8-bit canvas within 1/255.  The shader scales the fog colour by
``iblLuminance`` (the indirect light's intensity times the camera's exposure): ``color`` here
is ``FogOptions.color`` times that (the test sets both to 1).

Units: Filament is y-up **metres** (same as fogref) and uses **exp** (not exp2):
density [1/m], heightFalloff [1/m], so the medium is exactly
``sigma_t(y) = density * exp(-heightFalloff * (y - height))`` [1/m] (one
:class:`~fogref.media.ExpLayer`).  Shader: ``h = falloff * view.y`` (view =
world - camera, unnormalised), line integral ``(A - density exp(y - h))/h = A (1 - exp(-h))/h``
(``A = density exp(y)``, ``y = -heightFalloff (camera.y - height)``) if ``|h| > 0.00125``
else ``A`` (zeroth-order branch: up to 0.06 % low; releases before ``surface_fog.fs`` had
``A (1 - exp(-h))/h`` with 0.01, up to 0.5 %), times
``max(d - distance, 0)``; note that the start distance only shortens the ray, the
density is still averaged from the camera (unlike Unreal).

Compositing: ``opacity = min(1 - exp(-integral), maximumOpacity)``,
``final = scene * (1 - opacity) + color * opacity + sun term``, with the sun term
``sunColor * pow(max(dot(view, l)/d, 0), inScatteringSize) * (1 - exp(-insc))``
when ``inScatteringSize > 0`` (``insc`` uses ``inScatteringStart``).  So
``transmittance = 1 - opacity`` (grey).  ``cutOffDistance`` (newer versions):
pixels farther than it get no fog.  Robustness (deviations): ``d`` is floored at
1e-30 in the sun term (the shader divides 0/0 at the camera), the density at the
camera is capped at the largest float, and where the shader's line integral is
not finite (``0 * inf`` far above the fog looking down) the log-form closed
form is used; float64 always uses that closed form (no 0.00125 branch).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fogref import params as valid
from fogref.errors import ParameterError
from fogref.media import NP
from fogref.media.closed_form import phi
from fogref.models._num import dtype_of, grey, split
from fogref.models.base import FogResult, register


@dataclass(frozen=True)
class FilamentFogParams:
    """View::FogOptions (metres) plus the sun (``lightDirection``: toward the sun)."""

    distance: float = 0.0
    cutOffDistance: float = math.inf
    maximumOpacity: float = 1.0
    height: float = 0.0
    heightFalloff: float = 1.0
    color: tuple = (1.0, 1.0, 1.0)
    density: float = 0.1
    inScatteringStart: float = 0.0
    inScatteringSize: float = -1.0
    lightDirection: tuple = (0.0, 1.0, 0.0)
    lightColorIntensity: tuple = (1.0, 1.0, 1.0, 1.0)

    def __post_init__(self) -> None:
        src = "<FilamentFogParams>"
        for name in ("distance", "density", "heightFalloff"):
            object.__setattr__(self, name, valid.number(getattr(self, name), name, source=src, lo=0.0))
        object.__setattr__(
            self,
            "maximumOpacity",
            valid.number(self.maximumOpacity, "maximumOpacity", source=src, lo=0.0, hi=1.0),
        )
        object.__setattr__(self, "height", valid.number(self.height, "height", source=src, unit="m"))
        if not (isinstance(self.cutOffDistance, float) and self.cutOffDistance == math.inf):  # inf: none
            cut = valid.number(self.cutOffDistance, "cutOffDistance", source=src, lo=0.0, unit="m")
            object.__setattr__(self, "cutOffDistance", cut)
        for name in ("inScatteringStart", "inScatteringSize"):  # Filament: size < 0 turns it off
            object.__setattr__(self, name, valid.number(getattr(self, name), name, source=src))
        object.__setattr__(self, "color", valid.rgb(self.color, "color", source=src, lo=0.0))
        w = np.asarray(valid.vector(self.lightDirection, "lightDirection", source=src), dtype=np.float64)
        if not np.linalg.norm(w) > 0:
            raise ParameterError(src, "lightDirection", "(0, 0, 0) has no direction")
        object.__setattr__(self, "lightDirection", tuple(float(x) for x in w / np.linalg.norm(w)))
        lci = valid.vector(self.lightColorIntensity, "lightColorIntensity", source=src, n=4, lo=0.0)
        object.__setattr__(self, "lightColorIntensity", lci)


@register("filament")
class FilamentFog:
    """Filament height fog (see module doc)."""

    Params = FilamentFogParams

    def __init__(self, params: FilamentFogParams | None = None) -> None:
        self.params = params or FilamentFogParams()

    def evaluate(self, camera: Any, world_pos: Any, precision: str = "float32") -> FogResult:
        """Fog of each pixel: camera (3,), world_pos (..., 3) in metres."""
        dt = dtype_of(precision)
        q = self.params
        cam, wp = split(camera, world_pos)
        # CPU: density at the viewer's height
        with np.errstate(all="ignore"):
            y = dt(-q.heightFalloff) * (dt(cam[1]) - dt(q.height))
            A = dt(q.density) * np.exp(y)
            A = min(A, dt(np.finfo(dt).max))  # robustness: no inf density
        falloff = dt(q.heightFalloff)
        with np.errstate(all="ignore"):
            view = (wp - cam).astype(dt)
            h = falloff * view[..., 1]

            # robust line integral in log form (no 0 * inf when the camera is far above)
            def robust(hh: Any) -> Any:
                log_a = (math.log(q.density) if q.density > 0 else -1e4) - q.heightFalloff * (
                    cam[1] - q.height
                )
                h64 = hh.astype(np.float64)
                return np.where(
                    h64 > -1.0,
                    np.exp(min(log_a, 700.0)) * phi(NP, np.maximum(h64, -1.0)),
                    np.exp(np.minimum(log_a - h64, 700.0))
                    * (-np.expm1(np.minimum(h64, 0.0)))
                    / np.where(h64 < 0, -h64, 1.0),
                )

            if dt is np.float64:
                fi = robust(h)
            else:
                fi = np.where(np.abs(h) > dt(0.00125), (A - dt(q.density) * np.exp(y - h)) / h, A)
                bad = ~np.isfinite(fi)
                if np.any(bad):
                    fi[bad] = np.minimum(robust(h[bad]), np.finfo(dt).max).astype(dt)
            d = np.sqrt(np.sum(view * view, axis=-1))
            run = np.maximum(d - dt(q.distance), dt(0.0))
            integral = np.where(run > 0, fi * run, dt(0.0))
            if dt is np.float64:  # same value, without the cancellation of 1 - (1 - T)
                trans = np.maximum(np.exp(-integral), dt(1.0) - dt(q.maximumOpacity))
                opacity = dt(1.0) - trans
            else:
                opacity = np.minimum(dt(1.0) - np.exp(-integral), dt(q.maximumOpacity))
                trans = dt(1.0) - opacity
            fog_color = np.asarray(q.color, dtype=dt) * opacity[..., None]
            if q.inScatteringSize > 0:
                run_i = np.maximum(d - dt(q.inScatteringStart), dt(0.0))
                insc = np.where(run_i > 0, fi * run_i, dt(0.0))
                insc_opacity = dt(1.0) - np.exp(-insc)
                lc = q.lightColorIntensity
                sun = np.asarray(lc[:3], dtype=dt) * dt(lc[3])
                l = np.asarray(q.lightDirection, dtype=dt)
                amount = np.maximum(
                    (view[..., 0] * l[0] + view[..., 1] * l[1] + view[..., 2] * l[2])
                    / np.maximum(d, dt(1e-30)),
                    dt(0.0),
                )
                fog_color = (
                    fog_color + sun * (np.power(amount, dt(q.inScatteringSize)) * insc_opacity)[..., None]
                )
            if math.isfinite(q.cutOffDistance):
                cut = d > dt(q.cutOffDistance)
                trans = np.where(cut, dt(1.0), trans)
                fog_color = np.where(cut[..., None], dt(0.0), fog_color)
        return FogResult(inscatter=fog_color.astype(dt), transmittance=grey(trans, dt))
