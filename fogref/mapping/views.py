"""Sample views from a camera and the physical single scattering on them: the target of the fits.

The loss of :func:`fogref.mapping.unreal.fit_unreal` (and of the lobe table,
:mod:`fogref.mapping.lobe`) is the mean squared error of the inscattered radiance
over a set of views (:func:`sample_views`): directions on a Fibonacci sphere from
the scene's camera, at log-spaced distances, plus the sky (an infinite distance,
fogged by a model at :data:`~fogref.models.base.SKY_DISTANCE`) for upward views.
The physical single scattering of a sun (irradiance E, toward ``w``) and a uniform
sky ``L_sky`` (closed forms of :mod:`fogref.media.single_scatter`)::

    L = alpha E p_HG(cos) T_sun(o) tau phi(m tau)  +  alpha L_sky (1 - T)

A physical sky (``PhysicalScene.sky_model``, a ``sunsky``) replaces ``L_sky`` by its projection
onto the phase function per view direction, ``S(d) = int_{up} L(w) p_HG(w . d) dw``
(:func:`sky_projection`), so the fitted colours come from the real sky.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fogref.mapping.physical import PhysicalScene
from fogref.media import NP, single_scatter_sun
from fogref.media.single_scatter import single_scatter_sky, single_scatter_sky_projected, sky_phase_projection
from fogref.media.sky import sky_radiance
from fogref.models.base import SKY_DISTANCE

__all__ = [
    "Views",
    "fibonacci_directions",
    "physical_single_scattering",
    "rotated_views",
    "sample_views",
    "sky_projection",
]


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

    def rays(self) -> tuple:
        """``(o, d, D)`` as 3-tuples of (N,) arrays and (N,) [m], the sky at ``NP.largest``: the
        closed forms' rays (:mod:`fogref.media`)."""
        o = tuple(np.full(len(self.D), c) for c in self.camera)
        return o, tuple(self.d[:, i] for i in range(3)), np.where(self.sky, NP.largest, self.D)


def fibonacci_directions(n: int) -> np.ndarray:
    """``n`` nearly uniform unit directions on the sphere (y-up), (n, 3)."""
    i = np.arange(n) + 0.5
    y = 1.0 - 2.0 * i / n
    r = np.sqrt(np.maximum(0.0, 1.0 - y * y))
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    return np.stack([r * np.cos(phi), y, r * np.sin(phi)], axis=-1)


def sample_views(
    camera: Any,
    n_dirs: int = 400,
    distances: Any = None,
    min_dy: float = -0.5,
    sky_min_dy: float = 0.0,
    ground: float | None = None,
) -> Views:
    """Views from ``camera``: Fibonacci directions with ``d_y >= min_dy`` at each of
    ``distances`` [m] (default 12 log-spaced from 10 m to 20 km), plus the sky
    (infinite distance) for directions with ``d_y > sky_min_dy``; with ``ground`` [m], every
    downward view stops at the plane ``y = ground`` if that is nearer.

    >>> sample_views((0.0, 2.0, 0.0), 2, [10.0], ground=0.0).D.tolist()
    [10.0, 4.0, inf]
    """
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
    cam = np.asarray(camera, dtype=float)
    if ground is not None:
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(d_all[:, 1] < 0, (float(ground) - cam[1]) / d_all[:, 1], np.inf)
        D_all = np.minimum(D_all, np.where(t > 0, t, np.inf))
    return Views(cam, d_all, D_all)


def rotated_views(views: Views, angle: float) -> Views:
    """``views`` turned by ``angle`` [rad] about the vertical (y) axis through the camera: the same
    directions' pattern, another sampling of the sphere (sky views stay sky views).

    >>> v = rotated_views(Views(np.zeros(3), np.array([[1.0, 0.0, 0.0]]), np.array([10.0])), math.pi / 2)
    >>> np.round(v.d, 12).tolist(), v.D.tolist()
    ([[0.0, 0.0, -1.0]], [10.0])
    """
    c, s = math.cos(angle), math.sin(angle)
    R = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    return Views(views.camera, views.d @ R.T, views.D)


def physical_single_scattering(
    pf: PhysicalScene, views: Views, sun_attenuation: bool = True, sky: bool = True, sun: bool = True
) -> np.ndarray:
    """Closed-form single scattering (sun + sky, no occluders) of each view, (N, 3).

    ``sun_attenuation=False``: the sun term without its attenuation in the fog,
    ``alpha E p (1 - T)``.  The sky term is ``alpha L_sky (1 - T)`` (unoccluded,
    unattenuated: what FogInscatteringColor stands for) for a uniform sky, and
    ``alpha S(d) (1 - T)`` for a physical sky (``pf.sky_model``; :func:`sky_projection`).
    """
    m = pf.medium
    o, d, D = views.rays()
    out = np.zeros((len(D), 3))
    # the shape optical depth of each view, shared by the terms that need it (made once, when first asked)
    tau = functools.cache(lambda: m.optical_depth(NP, o, d, D))
    if sun and max(pf.sun_irradiance) > 0:
        w = pf.sun_direction
        if sun_attenuation:
            sun_tau = tau() if w[1] > 0 else None  # a sun below the horizon needs none
            out += np.stack(single_scatter_sun(NP, m, o, d, D, w, pf.sun_irradiance, sun_tau), axis=-1)
        elif w[1] > 0:
            cos = d[0] * w[0] + d[1] * w[1] + d[2] * w[2]
            p = m.phase_value(NP, cos)
            T = np.stack(m.transmittance(NP, o, d, D), axis=-1)
            out += (np.asarray(m.albedo) * np.asarray(pf.sun_irradiance)) * p[:, None] * (1.0 - T)
    if sky and pf.sky_model is not None:
        S = sky_projection(pf, views.d)
        out += np.stack(single_scatter_sky_projected(NP, m, o, d, D, tuple(S.T), tau()), axis=-1)
    elif sky and max(pf.sky_radiance) > 0:
        out += np.stack(single_scatter_sky(NP, m, o, d, D, pf.sky_radiance, tau()), axis=-1)
    return out


def sky_projection(pf: PhysicalScene, d: np.ndarray, sky: Any = None) -> np.ndarray:
    """The sky of ``pf`` projected onto its phase function per view direction, (N, 3).

    ``S(v) = int_{w_y > 0} L_sky(w) p_HG(w . v; g) dw``
    (:func:`fogref.media.single_scatter.sky_phase_projection`), each distinct direction of ``d``
    ((N, 3) unit, away from the camera) once.  ``sky``: the radiance function ((M, 3) directions
    -> (M, 3) RGB); default the physical sky of ``pf.sky_model`` (Mitsuba's ``sunsky`` without
    its sun, :func:`fogref.media.sky.sky_radiance`), else the uniform ``pf.sky_radiance`` above
    the horizon (then ``S = L H(v_y)``, :func:`fogref.media.single_scatter.hg_upper_fraction`).
    """
    if sky is None:
        if pf.sky_model is not None:
            sky = sky_radiance(pf.sky_model)
        else:
            L = np.asarray(pf.sky_radiance, dtype=np.float64)
            sky = lambda w: np.broadcast_to(L, (len(w), 3))  # noqa: E731
    pf.medium.require_hg("the sky's projection onto the phase function")
    d = np.asarray(d, dtype=np.float64)
    uniq, inv = np.unique(d, axis=0, return_inverse=True)
    return sky_phase_projection(sky, float(pf.medium.g), uniq)[np.asarray(inv).reshape(-1)]
