"""Phase functions of fog beyond Henyey–Greenstein: tabulated (Mie) and approximate Mie.

Every phase function here is a function of ``cos_theta = dot(d, w)`` (``d`` the
direction of the ray that sees the light, away from the viewer; ``w`` toward the
light: 1 is forward scattering), in 1/sr, normalised to 1 over the sphere, the
convention of :func:`fogref.media.closed_form.hg_phase`.

* :class:`TabulatedPhase`: values at irregular cosines, linear in ``cos_theta``
  between them (a droplet distribution's Mie phase, :mod:`fogref.media.mie`). It is
  exactly the density that fogpath's ``fogtabphase`` plugin evaluates and samples
  (``plugins/tab_phase.py``: Mitsuba's ``IrregularContinuousDistribution``).
* :func:`draine_phase`, :func:`approx_mie_phase`: Draine's phase (Draine 2003) and
  the HG + Draine blend that Jendersie and d'Eon fitted to water droplets.
* :func:`phase_cosines`: the cosine grid that resolves a droplet's diffraction peak.

References: B. T. Draine, "Scattering by interstellar dust grains. I. Optical and
ultraviolet", ApJ 598, 2003, eq. 4; J. Jendersie and E. d'Eon, "An approximate Mie
scattering function for fog and cloud rendering", SIGGRAPH 2023 Talks
(doi:10.1145/3587421.3595409), eqs. 1-4 and the fit for 5 um <= d <= 50 um.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fogref.errors import ParameterError
from fogref.media.closed_form import hg_phase
from fogref.media.ops import Ops, Real

__all__ = [
    "TabulatedPhase",
    "approx_mie_params",
    "approx_mie_phase",
    "draine_phase",
    "phase_cosines",
]


def phase_cosines(forward_deg: float = 0.05, knee_deg: float = 5.0, step_deg: float = 0.25) -> np.ndarray:
    """Increasing cosines from -1 to 1 for a droplet phase table (float64 values that are
    exact in float32).

    Scattering angles: 0, then geometric from ``forward_deg`` to ``knee_deg`` (the
    diffraction peak, 8 nodes per factor 2), then every ``step_deg`` to 180 deg (the
    fogbow and the glory).  Nodes closer than 4 float32 ulps of 1 (2.4e-7 in cosine) to
    the previous one are left out: float32 cosines cannot tell them apart (near the
    forward direction that is about 0.03 deg).

    >>> c = phase_cosines()
    >>> len(c), float(c[0]), float(c[-1])
    (752, -1.0, 1.0)
    """
    n_geo = int(math.ceil(8 * math.log2(knee_deg / forward_deg)))
    fwd = np.geomspace(forward_deg, knee_deg, n_geo + 1)[:-1]
    rest = np.arange(knee_deg, 180.0 + 0.5 * step_deg, step_deg)
    theta = np.concatenate([[0.0], fwd, rest])
    c32 = np.cos(np.radians(theta)).astype(np.float32)
    keep = [0]
    for i in range(1, len(c32)):
        if float(c32[keep[-1]]) - float(c32[i]) >= 4 * 2.0**-24:
            keep.append(i)
    return c32[keep][::-1].astype(np.float64)


def draine_phase(ops: Ops, cos_theta: Real, g: float, alpha: float) -> Real:
    """Draine's phase function [1/sr] (Draine 2003, eq. 4), normalised over the sphere;
    ``alpha = 0`` is Henyey–Greenstein, ``alpha = 1`` Cornette–Shanks.

    >>> from fogref.media import NP
    >>> round(float(draine_phase(NP, 1.0, 0.0, 0.0)) * 4 * math.pi, 12)
    1.0
    """
    shape = (1.0 + alpha * cos_theta * cos_theta) / (1.0 + alpha * (1.0 + 2.0 * g * g) / 3.0)
    return hg_phase(ops, cos_theta, g) * shape


def approx_mie_params(diameter_um: float, src: str = "<approx_mie>") -> tuple[float, float, float, float]:
    """Jendersie and d'Eon's fit ``(g_HG, g_D, alpha, w_D)`` for droplet diameter ``d``
    [um], 5 <= d <= 50 (the fit's range; outside it a ParameterError).

    >>> [round(v, 4) for v in approx_mie_params(10.0)]
    [0.9882, 0.5557, 21.9955, 0.482]
    """
    d = float(diameter_um)
    if not 5.0 <= d <= 50.0:
        raise ParameterError(src, "diameter", f"value {d} um outside [5, 50] (the fit's range)")
    g_hg = math.exp(-0.0990567 / (d - 1.67154))
    g_d = math.exp(-2.20679 / (d + 3.91029) - 0.428934)
    alpha = math.exp(3.62489 - 8.29288 / (d + 5.52825))
    w_d = math.exp(-0.599085 / (d - 0.641583) - 0.665888)
    return g_hg, g_d, alpha, w_d


def approx_mie_phase(ops: Ops, cos_theta: Real, diameter_um: float) -> Real:
    """The approximate Mie phase [1/sr] of water droplets of diameter ``d`` [um]:
    ``(1 - w_D) HG(g_HG) + w_D Draine(g_D, alpha)`` (Jendersie and d'Eon 2023).

    >>> from fogref.media import NP
    >>> round(float(approx_mie_phase(NP, 1.0, 10.0)), 1)   # the forward peak
    586.9
    """
    g_hg, g_d, alpha, w_d = approx_mie_params(diameter_um)
    return (1.0 - w_d) * hg_phase(ops, cos_theta, g_hg) + w_d * draine_phase(ops, cos_theta, g_d, alpha)


@dataclass(frozen=True)
class TabulatedPhase:
    """A phase function [1/sr] given at increasing ``cosines`` (first -1, last 1, at
    least 2), linear in ``cos_theta`` between them, normalised over the sphere by the
    trapezoid rule (the values are scaled; their shape is kept).

    ``label`` names it in reports (e.g. ``"mie radiation"``).

    Examples
    --------
    >>> from fogref.media import NP
    >>> p = TabulatedPhase((-1.0, 1.0), (1.0, 3.0))
    >>> [round(v * 4 * math.pi, 6) for v in p.values]
    [0.5, 1.5]
    >>> round(float(p.eval(NP, 0.0)) * 4 * math.pi, 6), round(p.mean_cosine, 6)
    (1.0, 0.166667)
    """

    cosines: tuple
    values: tuple
    label: str = "tabulated"
    source: str = field(default="<TabulatedPhase>", compare=False, repr=False)

    def __post_init__(self) -> None:
        c = np.asarray(self.cosines, dtype=np.float64)
        v = np.asarray(self.values, dtype=np.float64)
        src = self.source
        if c.ndim != 1 or len(c) < 2 or v.shape != c.shape:
            raise ParameterError(
                src, "cosines", f"need >= 2 cosines, as many values; got {c.shape}, {v.shape}"
            )
        if c[0] != -1.0 or c[-1] != 1.0 or not np.all(np.diff(c) > 0):
            raise ParameterError(src, "cosines", "must increase strictly from -1 to 1")
        if not (np.all(np.isfinite(v)) and np.all(v >= 0)) or not np.any(v > 0):
            raise ParameterError(src, "values", "must be finite, >= 0 and not all 0")
        norm = 2.0 * math.pi * float(np.sum(0.5 * (v[1:] + v[:-1]) * np.diff(c)))
        object.__setattr__(self, "cosines", tuple(float(x) for x in c))
        object.__setattr__(self, "values", tuple(float(x) for x in v / norm))

    @property
    def mean_cosine(self) -> float:
        """The asymmetry parameter ``g = <cos theta>`` of the piecewise-linear table."""
        c, v = np.asarray(self.cosines), np.asarray(self.values)
        a, b, ca, cb = v[:-1], v[1:], c[:-1], c[1:]
        h = cb - ca
        # exact integral of c p(c) on each linear piece
        integral = np.sum(h * (a * (2 * ca + cb) + b * (ca + 2 * cb)) / 6.0)
        return float(2.0 * math.pi * integral)

    def eval(self, ops: Ops, cos_theta: Real) -> Real:
        """The phase function [1/sr] at ``cos_theta`` (clamped to [-1, 1])."""
        return ops.interp(cos_theta, self.cosines, self.values)

    def as_params(self) -> dict:
        """The ``fogtabphase`` plugin's parameters (strings, as in a scene's XML); the values
        keep 9 significant digits, the cosines are exact.

        >>> TabulatedPhase((-1.0, 1.0), (1.0, 1.0), label="iso").as_params()["values"]
        '0.0795774715, 0.0795774715'
        """
        return {
            "type": "fogtabphase",
            "cosines": ", ".join(repr(float(c)) for c in self.cosines),
            "values": ", ".join(f"{v:.9g}" for v in self.values),
            "label": self.label,
        }

    @classmethod
    def from_function(
        cls, fn: Any, cosines: Any = None, label: str = "tabulated", source: str = "<TabulatedPhase>"
    ) -> TabulatedPhase:
        """``fn(cos_theta)`` (numpy, float64) tabulated on ``cosines`` (default
        :func:`phase_cosines`).

        >>> from fogref.media import NP
        >>> p = TabulatedPhase.from_function(lambda c: approx_mie_phase(NP, c, 10.0))
        >>> round(p.mean_cosine, 3)
        0.864
        """
        c = phase_cosines() if cosines is None else np.asarray(cosines, dtype=np.float64)
        return cls(tuple(c), tuple(np.asarray(fn(c), dtype=np.float64)), label=label, source=source)
