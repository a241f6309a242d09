"""The sun's direction from elevation and azimuth, and from a scene's ``to_world``.

fogref's shipped scenes expose the sun as two XML ``$defaults``, ``sun_elevation``
and ``sun_azimuth`` [deg], and orient Mitsuba's ``directional`` emitter with a
``to_world`` made of rotations (the emitter's light travels along the local +z
axis of its ``to_world``)::

    <transform name="to_world">
        <rotate x="1" angle="$sun_elevation"/>
        <rotate y="1" angle="$sun_azimuth"/>
        <rotate y="1" angle="180"/>
    </transform>

Mitsuba applies the listed operations in order, so +z is first tilted down by the
elevation, then turned by azimuth + 180 deg about +y: light travels along
``-w``, where ``w`` (toward the sun) is :func:`sun_direction_from_angles`.

Conventions (world y-up): elevation is the angle of ``w`` above the horizontal
plane; azimuth is measured in the horizontal plane from +z (the shipped cameras'
forward direction) toward +x.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from fogref import params
from fogref.errors import FogrefError

__all__ = ["angles_from_sun_direction", "sun_direction_from_angles", "sun_direction_from_to_world"]


def sun_direction_from_angles(elevation_deg: float, azimuth_deg: float) -> np.ndarray:
    """Unit vector toward the sun from its elevation and azimuth.

    Parameters
    ----------
    elevation_deg : float
        Angle above the horizon [deg], domain [-90, 90].
    azimuth_deg : float
        Angle in the horizontal plane from +z toward +x [deg], any finite value.

    Returns
    -------
    numpy.ndarray
        ``(3,)`` float64 ``w = (cos e sin a, sin e, cos e cos a)``, ``|w| = 1``
        (world y-up).  The XML ``directional`` emitter's travel direction is ``-w``.

    Raises
    ------
    fogref.errors.ParameterError
        For a non-finite angle or an elevation outside [-90, 90] (:func:`fogref.params.angle`).

    Examples
    --------
    >>> sun_direction_from_angles(90, 0).round(12).tolist()
    [0.0, 1.0, 0.0]
    >>> sun_direction_from_angles(0, 90).round(12).tolist()
    [1.0, 0.0, 0.0]
    >>> sun_direction_from_angles(95, 0)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    fogref.errors.ParameterError: ...: parameter 'sun_elevation': 95 is outside [-90, 90] deg
    """
    e = params.angle(elevation_deg, "sun_elevation", source="sun_direction_from_angles", lo=-90.0, hi=90.0)
    a = params.angle(azimuth_deg, "sun_azimuth", source="sun_direction_from_angles")
    er, ar = math.radians(e), math.radians(a)
    return np.array([math.cos(er) * math.sin(ar), math.sin(er), math.cos(er) * math.cos(ar)])


def angles_from_sun_direction(w) -> tuple[float, float]:
    """Elevation and azimuth [deg] of a direction toward the sun (the inverse of
    :func:`sun_direction_from_angles`).

    Parameters
    ----------
    w : array_like, shape (3,)
        Direction toward the sun, any non-zero length (normalised here).

    Returns
    -------
    (float, float)
        Elevation in [-90, 90] and azimuth in (-180, 180] [deg].

    Examples
    --------
    >>> [round(x, 6) for x in angles_from_sun_direction([0.4, 0.139173, 0.906])]
    [7.999168, 23.821511]
    """
    v = np.asarray(w, dtype=np.float64)
    n = float(np.linalg.norm(v))
    if v.shape != (3,) or not math.isfinite(n) or n == 0.0:
        raise FogrefError(f"sun direction {w!r} must be a finite non-zero 3-vector")
    v = v / n
    return math.degrees(math.asin(max(-1.0, min(1.0, v[1])))), math.degrees(math.atan2(v[0], v[2]))


def _floats(text: str, what: str, name: str = "value") -> list[float]:
    """The finite numbers of ``text`` (``"a, b c"``), each through :func:`fogref.params.number`."""
    return [params.number(x, name, source=what) for x in text.replace(",", " ").split()]


def _rotation(axis, angle_deg: float) -> np.ndarray:
    """Right-handed rotation matrix about ``axis`` by ``angle_deg`` (Rodrigues)."""
    k = np.asarray(axis, dtype=np.float64)
    k = k / np.linalg.norm(k)
    t = math.radians(angle_deg)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(t) * K + (1 - math.cos(t)) * (K @ K)


def sun_direction_from_to_world(
    transform, subst: Callable[[str], str] = lambda s: s, source: str = "scene"
) -> list[float]:
    """Unit vector toward the sun of a ``directional`` emitter oriented by ``to_world``.

    Parameters
    ----------
    transform : xml.etree.ElementTree.Element
        The emitter's ``<transform name="to_world">`` element; its children
        ``rotate`` (``x``/``y``/``z`` axis, ``angle`` [deg]), ``scale``, ``matrix``
        and ``lookat`` are composed in document order, as Mitsuba does
        (``translate`` does not change a direction).
    subst : callable
        Replaces ``$name`` references in an attribute value (the scene's defaults).
    source : str
        Named in error messages (the scene file).

    Returns
    -------
    list of float
        ``w = -normalize(M e_z)``, the direction toward the sun (unit, world y-up).

    Raises
    ------
    FogrefError
        Naming ``source`` for an unknown operation or a malformed value.

    Examples
    --------
    >>> import xml.etree.ElementTree as ET
    >>> el = ET.fromstring('<transform name="to_world"><rotate x="1" angle="30"/>'
    ...                    '<rotate y="1" angle="45"/><rotate y="1" angle="180"/></transform>')
    >>> w = sun_direction_from_to_world(el)
    >>> bool(np.allclose(w, sun_direction_from_angles(30, 45)))
    True
    """
    M = np.eye(3)
    for op in transform:
        tag = op.tag
        what = f"{source}: sun to_world <{tag}>"
        if tag == "rotate":
            axis = [params.number(subst(op.get(c, "0")), c, source=what) for c in "xyz"]
            if not any(axis):
                raise FogrefError(f"{what}: needs a non-zero axis (x, y or z)")
            R = _rotation(axis, params.angle(subst(op.get("angle", "0")), "angle", source=what))
        elif tag == "scale":
            if op.get("value") is not None:
                R = np.eye(3) * params.number(subst(op.get("value")), "value", source=what)
            else:
                R = np.diag([params.number(subst(op.get(c, "1")), c, source=what) for c in "xyz"])
        elif tag == "matrix":
            v = _floats(subst(op.get("value", "")), what)
            if len(v) not in (9, 16):
                raise FogrefError(f"{what}: expected 9 or 16 values, got {len(v)}")
            m = np.array(v).reshape(4, 4)[:3, :3] if len(v) == 16 else np.array(v).reshape(3, 3)
            R = m
        elif tag == "lookat":
            o = np.array(_floats(subst(op.get("origin", "0 0 0")), what, "origin"))
            t = np.array(_floats(subst(op.get("target", "0 0 1")), what, "target"))
            up = np.array(_floats(subst(op.get("up", "0 1 0")), what, "up"))
            z = t - o
            x = np.cross(up, z)
            if np.linalg.norm(z) == 0 or np.linalg.norm(x) == 0:
                raise FogrefError(f"{what}: origin, target and up must span a frame")
            z, x = z / np.linalg.norm(z), x / np.linalg.norm(x)
            R = np.stack([x, np.cross(z, x), z], axis=1)  # Mitsuba's look_at basis (left, up, dir)
        elif tag == "translate":
            continue
        else:
            raise FogrefError(
                f"{what}: unsupported operation (allowed: rotate, scale, matrix, lookat, translate)"
            )
        M = R @ M
    d = M[:, 2]
    n = float(np.linalg.norm(d))
    if not math.isfinite(n) or n == 0.0:
        raise FogrefError(f"{source}: sun to_world maps +z to a zero or non-finite vector")
    return [float(-x / n) for x in d]
