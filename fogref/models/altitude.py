"""Unity altitude fog with a power-law density ("积分解 Unity 高度雾", 2018).

Source: the blog post "积分解 Unity 高度雾" ("Integrating Unity height fog in
closed form", 2018-12-17), a Unity image-effect shader (``integral``,
``integralZeroK``, ``GetAltitudeFog`` and the
final ``lerp(color, _FogColor, saturate(fog * _FogColor.a))``); a blog post has no version or
commit: its text and shader were checked against a copy in the public code index (a Jekyll post
of that title and date; its final line calls the integral ``GetVerticalFog``).  Reproduces the
colour the image effect writes: linear in a Linear colour-space project.

Units: Unity, y-up **metres** (same as fogref; no conversion).  Density profile
(dimensionless): ``T(y) = 1`` below ``_FogStart = S``, ``0`` above ``_FogEnd = E``
and ``((E - y)/(E - S))^p`` between (``p = _FogPower``).  ``GetAltitudeFog``
returns the path integral ``I = int T ds`` [m] in closed form via the
antiderivative ``F(x)`` along the horizontal coordinate x (``y = k x + b``, times
``sqrt(1 + k^2)``), with a separate branch for ``k = 0``.  No exp/exp2 appears.

Compositing: the fog blends **linearly in optical depth**:
``opacity = saturate(I * _FogColor.a)``, ``final = lerp(scene, _FogColor.rgb,
opacity)``, i.e. ``transmittance = 1 - opacity`` and ``inscatter =
_FogColor.rgb * opacity``.  The physical counterpart (:func:`fogref.mapping.engines.altitude_to_medium`)
is the medium ``sigma_t(y) = _FogColor.a * T(y)`` [1/m] (a :class:`fogref.media.PowerLawLayer`),
whose optical depth is exactly ``_FogColor.a * I``; only the blend differs
(``1 - saturate(tau)`` instead of Beer–Lambert ``exp(-tau)``).

Robustness (deviation): a vertical ray (``hDist = 0``) gives ``k = inf`` and NaN
in the shader; where the post's formula is not finite the float32 mode falls back
to the float64 integral below (rounded to float32).

float64 mode (:func:`path_integral_exact`): the same integral, computed by the
physical counterpart's :meth:`fogref.media.PowerLawLayer.depth` (no second copy
of the math), which forms the power piece
``H/(p+1) (u0^(p+1) - u1^(p+1))`` as ``u0^(p+1) * -expm1((p+1) log1p(-delta))``
-- free of the cancellation of ``G(y1) - G(y0)`` near ``_FogEnd`` and exact for
horizontal and near-horizontal rays (no midpoint rule).  The ray is always
integrated **upwards from its lower end** (the integral is symmetric): the lower
end's height is an input, so ``E - y_lo`` is exact, whereas descending from a
camera far above ``_FogEnd`` would rebuild it as ``(E - y_cam) + t |dy|`` and
lose it to cancellation.  Relative error against mpmath (tests/test_models_stress.py):
at most ``16 eps kappa``, ``kappa = 2 + (p+1) (1 + |ln u_lo|)``, ``u_lo`` the
relative depth below ``_FogEnd`` where the ray enters the power piece.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from fogref import params as valid
from fogref.media import NP, PowerLawLayer
from fogref.models._num import dtype_of, grey, saturate, split
from fogref.models.base import FogResult, ParamModel, register


@dataclass(frozen=True)
class AltitudeFogParams:
    """Material properties of the altitude-fog shader (metres).  ``_FogColor``: RGB + a [1/m]."""

    _FogStart: float = 0.0
    _FogEnd: float = 50.0
    _FogPower: float = 2.0
    _FogColor: tuple = (0.6, 0.65, 0.7, 0.01)

    def __post_init__(self) -> None:
        src = "<AltitudeFogParams>"
        start = valid.number(self._FogStart, "_FogStart", source=src, unit="m")
        end = valid.number(self._FogEnd, "_FogEnd", source=src, lo=start, lo_open=True, unit="m")
        power = valid.number(self._FogPower, "_FogPower", source=src, lo=0.0)
        c = valid.vector(self._FogColor, "_FogColor", source=src, n=4, lo=0.0)
        for name, v in (("_FogStart", start), ("_FogEnd", end), ("_FogPower", power), ("_FogColor", c)):
            object.__setattr__(self, name, v)


def _integral(x: Any, k: Any, b: Any, s: Any, e: Any, p: Any, dt: Any) -> Any:
    """The shader's ``integral(x, k, b)`` (vectorised; branches as np.where)."""
    s_bk = (s - b) / k
    y = k * x + b
    below = x - s_bk
    above = (e - s) / ((p + dt(1.0)) * k)
    mid = (np.power(e - s, p + dt(1.0)) - np.power(np.maximum(e - y, dt(0.0)), p + dt(1.0))) / (
        k * (p + dt(1.0)) * np.power(e - s, p)
    )
    return np.where(y <= s, below, np.where(y >= e, above, mid))


def _integral_zero_k(x: Any, b: Any, s: Any, e: Any, p: Any, dt: Any) -> Any:
    """The shader's ``integralZeroK(x, b)``."""
    mid = x * np.power(np.maximum((e - b) / (e - s), dt(0.0)), p)
    return np.where(b >= e, dt(0.0), np.where(b <= s, x, mid))


def density(y: Any, s: Any, e: Any, p: Any) -> Any:
    """Relative density ``T(y)`` (dimensionless)."""
    u = np.clip((e - y) / (e - s), 0.0, 1.0)
    return np.power(u, p)


def path_integral_exact(cam: Any, wp: Any, s: Any, e: Any, p: Any) -> np.ndarray:
    """``I = int T ds`` [m] in float64: :meth:`PowerLawLayer.depth` from the ray's lower end.

    Stable at all slopes (horizontal rays included) and near ``_FogEnd``; see the module doc.
    """
    d = np.asarray(wp, np.float64) - np.asarray(cam, np.float64)
    dist = np.sqrt(np.sum(d * d, axis=-1))
    y_lo = np.minimum(np.broadcast_to(np.float64(cam[1]), dist.shape), wp[..., 1])
    with np.errstate(all="ignore"):
        dy = np.where(dist > 0, np.abs(d[..., 1]) / np.where(dist > 0, dist, 1.0), 0.0)
    layer = PowerLawLayer(density=1.0, start=float(s), end=float(e), power=float(p))
    return np.asarray(layer.depth(NP, y_lo, dy, dist), np.float64)


@register("altitude")
class AltitudeFog(ParamModel[AltitudeFogParams]):
    """The altitude fog of "积分解 Unity 高度雾" (see module doc)."""

    Params = AltitudeFogParams

    def path_integral(self, camera: Any, world_pos: Any, precision: str = "float32") -> np.ndarray:
        """``GetAltitudeFog``: the density path integral I [m] of each pixel."""
        dt = dtype_of(precision)
        q = self.params
        cam, wp = split(camera, world_pos)
        s, e, p = dt(q._FogStart), dt(q._FogEnd), dt(q._FogPower)
        if dt is np.float64:
            return path_integral_exact(cam, wp, float(s), float(e), float(p))
        with np.errstate(all="ignore"):
            dist_dir = (wp - cam).astype(dt)
            h = np.sqrt(dist_dir[..., 0] * dist_dir[..., 0] + dist_dir[..., 2] * dist_dir[..., 2])
            v = dist_dir[..., 1]
            k = v / h
            b = dt(cam[1])
            stretch = np.sqrt(dt(1.0) + k * k)
            nz = k != 0
            k_safe = np.where(nz, k, dt(1.0))
            i_k = stretch * (
                _integral(h, k_safe, b, s, e, p, dt) - _integral(dt(0.0), k_safe, b, s, e, p, dt)
            )
            i_0 = stretch * _integral_zero_k(h, b, s, e, p, dt)
            out = np.where(nz, i_k, i_0)
            bad = ~np.isfinite(out)
            if np.any(bad):
                exact = path_integral_exact(cam, wp[bad] if wp.ndim > 1 else wp, float(s), float(e), float(p))
                out = out.copy() if out.ndim else np.asarray(out)
                out[bad] = exact.astype(dt)
        return out.astype(dt, copy=False)

    def evaluate(self, camera: Any, world_pos: Any, precision: str = "float32") -> FogResult:
        """Fog of each pixel: camera (3,), world_pos (..., 3) in metres."""
        dt = dtype_of(precision)
        I = self.path_integral(camera, world_pos, precision)
        opacity = saturate(I * dt(self.params._FogColor[3])).astype(dt)
        color = np.asarray(self.params._FogColor[:3], dtype=dt)
        return FogResult(inscatter=color * opacity[..., None], transmittance=grey(dt(1.0) - opacity, dt))
