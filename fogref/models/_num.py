"""Small numeric helpers shared by the game fog models (numpy only).

``precision="float32"`` mirrors a GPU shader: every intermediate is rounded to
float32 (numpy keeps float32 when mixing float32 arrays with Python floats).
``precision="float64"`` evaluates the same model in double precision and, where
the shader uses a numerical shortcut (a Taylor branch), its exact closed form.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from fogref.errors import ParameterError
from fogref.models.base import as_points

LN2 = 0.6931471805599453
#: Relative tolerance of :func:`background`: ``camera + view * SKY_DISTANCE`` lands a few ulps short.
SKY_TOLERANCE = 1e-9


def dtype_of(precision: str) -> Any:
    """numpy dtype for ``precision`` ("float32" or "float64")."""
    if precision == "float32":
        return np.float32
    if precision == "float64":
        return np.float64
    raise ParameterError("<model>", "precision", f"expected 'float32' or 'float64', got {precision!r}")


def saturate(x: Any) -> Any:
    """HLSL ``saturate``: clamp to [0, 1] (NaN-free for finite or inf input)."""
    return np.minimum(np.maximum(x, 0), 1)


def split(camera: Any, world_pos: Any) -> Any:
    """camera (3,) and world positions (..., 3) as float64 arrays, checked."""
    cam = as_points(camera)
    if cam.shape != (3,):
        raise ValueError(f"camera must have shape (3,), got {cam.shape}")
    return cam, as_points(world_pos)


def glsl_smoothstep(e0: Any, e1: Any, x: Any, dt: Any) -> Any:
    """GLSL ``smoothstep(e0, e1, x)`` in ``dt`` (e1 > e0): ``t = clamp((x - e0)/(e1 - e0), 0, 1)``,
    ``t^2 (3 - 2 t)``; the edges are rounded to ``dt`` first, as a shader's uniforms are.

    >>> float(glsl_smoothstep(0.0, 2.0, np.float32(0.5), np.float32))
    0.15625
    """
    t = np.minimum(np.maximum((x - dt(e0)) / (dt(e1) - dt(e0)), dt(0.0)), dt(1.0))
    return t * t * (dt(3.0) - dt(2.0) * t)


def grey(x: Any, dt: Any) -> Any:
    """Broadcast a (...,) scalar field to (..., 3) RGB."""
    x = np.asarray(x, dtype=dt)
    return np.repeat(x[..., None], 3, axis=-1)


def view_ray(cam: Any, wp: Any, dt: Any) -> Any:
    """Camera-to-point vectors ``v`` (..., 3) [m] and their lengths ``d`` (...,) [m], in ``dt``.

    ``cam`` (3,) and ``wp`` (..., 3) as :func:`split` returns them; ``v = wp - cam`` rounded to
    ``dt`` and ``d = sqrt(v . v)`` as a shader computes ``length(v)`` (overflow gives inf, no warning).

    >>> v, d = view_ray(np.zeros(3), np.array([[3.0, 4.0, 0.0]]), np.float32)
    >>> float(d[0]), v.dtype
    (5.0, dtype('float32'))
    """
    with np.errstate(all="ignore"):
        v = (wp - cam).astype(dt)
        d = np.sqrt(np.sum(v * v, axis=-1))
    return v, d


def unit_direction(value: Any, name: str, source: str) -> tuple:
    """``value`` (a non-zero finite 3-vector, any length) normalised to a unit tuple of floats.

    Raises :class:`~fogref.errors.ParameterError` naming ``source`` and ``name`` otherwise.

    >>> unit_direction((0.0, 2.0, 0.0), "sun_direction", "<P>")
    (0.0, 1.0, 0.0)
    >>> unit_direction((0.0, 0.0, 0.0), "sun_direction", "<P>")
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: <P>: parameter 'sun_direction': expected a non-zero finite 3-vector
    """
    w = np.asarray(value, dtype=np.float64)
    n = float(np.linalg.norm(w))
    if w.shape != (3,) or not (math.isfinite(n) and n > 0):
        raise ParameterError(source, name, "expected a non-zero finite 3-vector")
    return tuple(float(x) for x in w / n)


def sky_pixels(cam: Any, wp: Any, hit: Any, sky_distance: float) -> Any:
    """(...,) bool: the pixels that see the sky (the background), which engines shade apart.

    ``hit``: the truth's own mask ((...,) bool, True where the pixel sees a surface, as
    :func:`fogref.compare.candidate.evaluate_model` passes it); it decides when given.
    ``hit=None``: a pixel is sky where its float64 distance ``|wp - cam|`` [m] is at least
    ``sky_distance (1 - SKY_TOLERANCE)`` (points built as ``camera + view * sky_distance`` in float64,
    never a distance rounded to float32).

    >>> cam = np.zeros(3)
    >>> wp = np.array([[0.0, 0.0, 5.0], [1e5 / 17**0.5, 0.0, 4e5 / 17**0.5]])
    >>> sky_pixels(cam, wp, None, 1e5).tolist()
    [False, True]
    >>> sky_pixels(cam, wp, np.array([True, False]), 1e5).tolist()
    [False, True]
    """
    if hit is not None:
        h = np.asarray(hit)
        if h.dtype != bool or h.shape != wp.shape[:-1]:
            raise ParameterError(
                "<model>", "hit", f"expected a bool mask of shape {wp.shape[:-1]}, got {h.dtype} {h.shape}"
            )
        return ~h
    with np.errstate(all="ignore"):
        d = np.sqrt(np.sum((wp - cam) ** 2, axis=-1))
    return d >= sky_distance * (1.0 - SKY_TOLERANCE)
