"""The physical scene a game fog model stands for, and its one parser.

A ground truth's EXR carries its scene in the header attribute ``fogref.params``
(written by ``fogref.render.load.describe_scene``)::

    {"scene": "valley.xml",
     "medium": {heightfog XML parameters: profile, sigma_t, albedo, g, ...},
     "sun": {"direction": [x, y, z] (toward the sun), "irradiance": [r, g, b]} | None,
     "sky": {"type": "constant", "radiance": [r, g, b]} | None,
            (a ``sunsky``: {"type": "sunsky", "turbidity", "albedo", "sun_direction", ...,
             "radiance": its isotropic projection}, fogref/render/sunsky.py)
     "camera": {"origin": [x, y, z], ...}}

:meth:`PhysicalScene.from_params` decodes it; the medium is built by
:func:`fogref.media.medium_from_params`, so a bad value gets the same message as
in ``fogref render``.

Colour convention shared by every model: the engine's constant fog colour stands
for the single scattering of a uniform, unoccluded sky whose own attenuation is
ignored, ``albedo * L_sky * (1 - T)``, i.e. colour = ``albedo * L_sky``
(:meth:`PhysicalScene.sky_colour`).  For a physical sky (``sunsky``), ``L_sky`` is its
isotropic projection ``(1/4 pi) int_{up} L dw``, the uniform sky whose single scattering is the
same at ``g = 0``; the sky's own parameters are in :attr:`PhysicalScene.sky_model`, and its
exact single scattering for any ``g`` is ``alpha S(d) (1 - T)``
(:func:`fogref.media.single_scatter.sky_phase_projection`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fogref.errors import ParameterError
from fogref.media import NP, FogMedium, HDRPLayer, PowerLawLayer, medium_from_params, rgb

__all__ = ["PhysicalScene"]

#: camera origin [m] when ``fogref.params`` has none.
DEFAULT_CAMERA = (0.0, 2.0, 0.0)


def _infer_profile(medium: FogMedium) -> str:
    kinds = {type(L) for L in medium.layers}
    if kinds == {HDRPLayer}:
        return "hdrp"
    if kinds == {PowerLawLayer}:
        return "powerlaw"
    if medium.is_homogeneous:
        return "box" if medium.bounds is not None else "homogeneous"
    return "exponential"


def _unit(value: Any, name: str, what: str, src: str) -> tuple:
    """``value`` (3 finite numbers, not all 0) as a unit tuple; ParameterError naming ``name``."""
    w = np.asarray(rgb(value, name, src), dtype=np.float64)
    n = float(np.linalg.norm(w))
    if not np.isfinite(n) or n == 0:
        raise ParameterError(src, name, f"{what} {tuple(value)} is not a direction")
    return tuple(float(x) for x in w / n)


class _SkyModel(dict):
    """A physical sky's parameters (a dict) that hash by value, so a scene keeps its hash."""

    def __hash__(self) -> int:  # type: ignore[override]
        return hash(json.dumps(self, sort_keys=True, default=str))


@dataclass(frozen=True)
class PhysicalScene:
    """Fog, sun, sky and camera of a ground truth (fogref frame: y-up, metres).

    Parameters
    ----------
    medium : FogMedium
        The fog.
    sun_direction : 3 floats
        Toward the sun (normalised here).  Meaningful only when
        :attr:`has_sun`; default straight up.
    sun_irradiance : 1 or 3 floats
        RGB sun irradiance E on a plane facing the sun (any radiometric unit,
        e.g. W/m^2), >= 0; all 0 (the default): no sun.
    sky_radiance : 1 or 3 floats, or None
        RGB radiance of a uniform sky (E's unit per sr); None or 0: no sky.
    camera : 3 floats
        Camera origin [m].
    camera_forward : 3 floats, optional
        The camera's unit view direction (fogref frame), normalised here: the depth axis of the
        models that fog the eye depth (three.js, PlayCanvas, Unity's "depth").  None: the scene
        names no view direction (those models keep their default, -z).
    profile : str, optional
        The medium's XML ``profile`` name (named in error messages and checked by
        the mappings); inferred from the layers when not given.
    source : str, optional
        Named in error messages (default: the medium's source).

    Examples
    --------
    >>> from fogref.media import ExpLayer, FogMedium
    >>> ps = PhysicalScene(FogMedium(sigma_t=0.002, albedo=0.9, layers=(ExpLayer(1.0, 0.02, 0.0),)),
    ...                    (0.0, 2.0, 0.0), (3.0, 3.0, 3.0), (0.2, 0.3, 0.5))
    >>> ps.sun_direction, ps.has_sun, ps.profile
    ((0.0, 1.0, 0.0), True, 'exponential')
    >>> [round(c, 3) for c in ps.sky_colour()]
    [0.18, 0.27, 0.45]
    """

    medium: FogMedium
    sun_direction: tuple = (0.0, 1.0, 0.0)
    sun_irradiance: tuple = (0.0, 0.0, 0.0)
    sky_radiance: Any = (0.0, 0.0, 0.0)  # None: no sky; stored as a 3-tuple
    camera: tuple = DEFAULT_CAMERA
    profile: str | None = None
    source: str = field(default=None, compare=False)  # type: ignore[assignment]  # None: the medium's
    #: A physical sky's parameters (``sunsky``: turbidity, albedo, sun_direction, ...), else None;
    #: part of the scene's identity (the fits' closed forms project this sky, fogref.mapping.views).
    sky_model: Any = None
    #: The sun's angular diameter [deg] (0: a delta).
    sun_angular_diameter: float = 0.0
    #: The camera's unit view direction (3 floats), or None where the scene names none.
    camera_forward: Any = None

    def __post_init__(self) -> None:
        src: str = self.source or getattr(self.medium, "source", "<PhysicalScene>")
        object.__setattr__(self, "source", src)
        self.medium.require_height_only("the game-model mappings")
        sun = _unit(self.sun_direction, "direction", "sun direction", src)
        object.__setattr__(self, "sun_direction", sun)
        object.__setattr__(self, "sun_irradiance", rgb(self.sun_irradiance, "irradiance", src, 0.0))
        sky = (0.0, 0.0, 0.0) if self.sky_radiance is None else self.sky_radiance
        object.__setattr__(self, "sky_radiance", rgb(sky, "radiance", src, 0.0))
        object.__setattr__(self, "camera", rgb(self.camera, "origin", src))
        if self.camera_forward is not None:
            forward = _unit(self.camera_forward, "forward", "camera forward", src)
            object.__setattr__(self, "camera_forward", forward)
        if self.profile is None:
            object.__setattr__(self, "profile", _infer_profile(self.medium))
        if self.sky_model is not None:
            object.__setattr__(self, "sky_model", _SkyModel(self.sky_model))

    # -- the one parser ---------------------------------------------------------
    @classmethod
    def from_params(cls, params: dict, camera: Any = None) -> "PhysicalScene":
        """Decode ``fogref.params`` (or ``describe_scene``'s dict; see the module doc).

        Parameters
        ----------
        params : dict
            Needs ``"medium"``; ``"sun"``, ``"sky"``, ``"camera"`` are optional
            (no sun, no sky, camera at (0, 2, 0) m; ``camera["forward"]``: the view direction).
        camera : 3 floats, optional
            Overrides the camera origin [m].

        Raises
        ------
        fogref.errors.ParameterError
            Naming the bad value (its source is ``"<scene>: medium"``,
            ``"<scene>: sun"``, ...).

        Examples
        --------
        >>> ps = PhysicalScene.from_params({"scene": "doc.xml", "medium": {"sigma_t": 0.01, "falloff": 0.02},
        ...                                 "sky": {"type": "constant", "radiance": 0.5}})
        >>> ps.has_sun, ps.sky_radiance, ps.camera, ps.camera_forward, ps.source
        (False, (0.5, 0.5, 0.5), (0.0, 2.0, 0.0), None, 'doc.xml: medium')
        """
        if not isinstance(params, dict) or not isinstance(params.get("medium"), dict):
            raise ParameterError("<fogref.params>", "medium", "no heightfog medium in the scene parameters")
        scene = params.get("scene", "<scene>")
        src = f"{scene}: medium"
        mp = params["medium"]
        medium = medium_from_params(mp, src)
        sun = params.get("sun") or None
        direction, irradiance = (0.0, 1.0, 0.0), (0.0, 0.0, 0.0)
        if sun:
            direction = rgb(sun.get("direction"), "direction", f"{scene}: sun")
            if not any(direction):
                raise ParameterError(f"{scene}: sun", "direction", "zero vector")
            irradiance = rgb(sun.get("irradiance", 0.0), "irradiance", f"{scene}: sun", 0.0)
        sky = params.get("sky") or {}
        radiance = rgb(sky.get("radiance", 0.0), "radiance", f"{scene}: sky", 0.0) if sky else None
        model = dict(sky) if sky.get("type") == "sunsky" else None
        size = float((sun or {}).get("angular_diameter", 0.0) or 0.0)
        view = params.get("camera") or {}
        if camera is None:
            camera = view.get("origin", DEFAULT_CAMERA)
        camera = rgb(camera, "origin", f"{scene}: camera")
        forward = view.get("forward")
        return cls(
            medium,
            direction,
            irradiance,
            radiance,
            camera,
            profile=str(mp.get("profile", "exponential")),
            source=src,
            sky_model=model,
            sun_angular_diameter=size,
            camera_forward=None if forward is None else rgb(forward, "forward", f"{scene}: camera"),
        )

    # -- what the mappings ask --------------------------------------------------
    @property
    def has_sun(self) -> bool:
        """A sun with some irradiance."""
        return max(self.sun_irradiance) > 0

    @property
    def albedo(self) -> np.ndarray:
        """The medium's RGB single-scattering albedo, (3,)."""
        return np.asarray(self.medium.albedo, dtype=np.float64)

    def sky_colour(self) -> tuple:
        """``albedo * L_sky`` (RGB, radiance): the constant fog colour (see the module doc)."""
        return tuple(float(x) for x in self.albedo * np.asarray(self.sky_radiance))

    def require_profile(self, model: str, allowed: tuple, why: str) -> None:
        """ParameterError naming 'profile' unless the medium's profile is in ``allowed``."""
        if self.profile not in allowed:
            raise ParameterError(
                self.source, "profile", f"'{self.profile}' has no {model} counterpart: {why}"
            )

    def require_unbounded(self, model: str) -> None:
        """ParameterError naming 'profile' when the fog is confined to a box."""
        if self.medium.bounds is not None:
            raise ParameterError(
                self.source,
                "profile",
                f"'{self.profile}' fog confined to bounds_min/bounds_max has no {model} "
                f"counterpart: {model} fog is unbounded",
            )

    def grey_sigma_t(self, model: str) -> float:
        """The (grey) extinction scale [1/m]; ParameterError naming 'sigma_t' if the channels differ."""
        return self.medium.grey_sigma_t(model)

    def sun_transmittance_at_camera(self) -> np.ndarray:
        """RGB ``T_sun`` in [0, 1], from the camera to the sun through the fog (ones without sun).

        Toward the disk's centre (a delta).  A 0.53 deg disk's average ``T_sun`` differs by
        ``O((theta_s cot e)^2)`` relative (``e``: the sun's elevation): for an exponential layer,
        -1.4e-4 at ``tau = 1`` and +2e-3 at ``tau = 5`` with the sun 8 deg high, -1.3e-5 and
        +9e-5 at 30 deg (disk quadrature, :func:`fogref.media.single_scatter.sun_disk_directions`).

        Examples
        --------
        >>> from fogref.media import ExpLayer, FogMedium
        >>> ps = PhysicalScene(FogMedium(sigma_t=0.01, layers=(ExpLayer(1.0, 0.1, 0.0),)), (0, 1, 0), 1.0,
        ...                    camera=(0.0, 0.0, 0.0))
        >>> [round(float(t), 4) for t in ps.sun_transmittance_at_camera()]   # exp(-0.01 / 0.1)
        [0.9048, 0.9048, 0.9048]
        """
        if not self.has_sun:
            return np.ones(3)
        o = tuple(np.asarray([c]) for c in self.camera)
        tau = np.asarray(self.medium.sun_optical_depth(NP, o, self.sun_direction), dtype=np.float64).reshape(
            -1
        )[0]
        return np.exp(-np.asarray(self.medium.sigma_t, dtype=np.float64) * tau)
