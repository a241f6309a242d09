"""Reading a ground truth's physical scene for the models' ``from_physical`` (numpy only).

``params`` is an EXR's ``fogref.params`` object (see
:mod:`fogref.compare.model_factory`): ``{"medium": {heightfog XML parameters},
"sun": {"direction", "irradiance"} | None, "sky": {"type": "constant",
"radiance"} | None, "camera": {"origin"}}``.  The medium is built by
:func:`fogref.render.params.medium_from_params`, so a bad value gets the same
message as in ``fogref render``.

Colour convention shared by every model: the engine's constant fog colour stands
for the single scattering of a uniform, unoccluded sky whose own attenuation is
ignored, ``albedo * L_sky * (1 - T)`` (DESIGN.md), i.e. colour = ``albedo * L_sky``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fogref.errors import ParameterError


@dataclass(frozen=True)
class PhysicalScene:
    """The parts of ``fogref.params`` the fog models need (fogref frame: y-up, metres).

    medium: :class:`~fogref.media.FogMedium`; profile: its XML profile name;
    source: the name used in error messages; sun_direction: unit (3,) toward the
    sun, or None; sun_irradiance: (3,) RGB (zeros without sun); sky_radiance:
    (3,) RGB (zeros without sky); camera: (3,) [m].
    """

    medium: object
    profile: str
    source: str
    sun_direction: np.ndarray | None
    sun_irradiance: np.ndarray
    sky_radiance: np.ndarray
    camera: np.ndarray

    @property
    def albedo(self) -> np.ndarray:
        return np.asarray(self.medium.albedo, dtype=np.float64)

    def sky_colour(self) -> tuple:
        """``albedo * L_sky``: the constant fog colour (see the module doc)."""
        return tuple(float(x) for x in self.albedo * self.sky_radiance)

    def require_profile(self, model: str, allowed: tuple, why: str) -> None:
        """ParameterError naming 'profile' unless the medium's profile is in ``allowed``."""
        if self.profile not in allowed:
            raise ParameterError(self.source, "profile",
                                 f"'{self.profile}' has no {model} counterpart: {why}")

    def require_unbounded(self, model: str) -> None:
        """ParameterError naming 'profile' when the fog is confined to a box."""
        if self.medium.bounds is not None:
            raise ParameterError(self.source, "profile",
                                 f"'{self.profile}' fog confined to bounds_min/bounds_max has no {model} "
                                 f"counterpart: {model} fog is unbounded")

    def grey_sigma_t(self, model: str) -> float:
        """The (grey) extinction scale [1/m]; ParameterError naming 'sigma_t' if the channels differ."""
        s = self.medium.sigma_t
        if max(s) - min(s) > 1e-12 * max(max(s), 1e-300):
            raise ParameterError(self.source, "sigma_t", f"{model}'s fog is grey; got {tuple(s)}")
        return float(s[0])

    def sun_transmittance_at_camera(self) -> np.ndarray:
        """RGB ``T_sun`` from the camera to the sun through the fog (ones without sun)."""
        from fogref.media import NP

        if self.sun_direction is None:
            return np.ones(3)
        o = tuple(np.asarray([c]) for c in self.camera)
        tau = np.asarray(self.medium.sun_optical_depth(NP, o, tuple(float(x) for x in self.sun_direction)),
                         dtype=np.float64).reshape(-1)[0]
        return np.exp(-np.asarray(self.medium.sigma_t, dtype=np.float64) * tau)


def _rgb3(v, source: str, name: str) -> np.ndarray:
    a = np.asarray(v, dtype=np.float64).reshape(-1)
    if a.size == 1:
        a = np.repeat(a, 3)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ParameterError(source, name, f"expected 1 or 3 finite numbers, got {v!r}")
    return a


def physical_scene(params: dict) -> PhysicalScene:
    """Decode ``fogref.params`` (see the module doc).  Raises ParameterError on bad values."""
    from fogref.render.params import medium_from_params

    if not isinstance(params, dict) or not isinstance(params.get("medium"), dict):
        raise ParameterError("<fogref.params>", "medium", "no heightfog medium in the scene parameters")
    scene = params.get("scene", "<scene>")
    src = f"{scene}: medium"
    mp = params["medium"]
    medium = medium_from_params(mp, src)
    sun = params.get("sun") or None
    direction = None
    irradiance = np.zeros(3)
    if sun:
        w = _rgb3(sun.get("direction"), f"{scene}: sun", "direction")
        n = float(np.linalg.norm(w))
        if n == 0:
            raise ParameterError(f"{scene}: sun", "direction", "zero vector")
        direction = w / n
        irradiance = _rgb3(sun.get("irradiance", 0.0), f"{scene}: sun", "irradiance")
    sky = params.get("sky") or {}
    radiance = _rgb3(sky.get("radiance", 0.0), f"{scene}: sky", "radiance") if sky else np.zeros(3)
    camera = _rgb3((params.get("camera") or {}).get("origin", (0.0, 2.0, 0.0)), f"{scene}: camera", "origin")
    return PhysicalScene(medium=medium, profile=str(mp.get("profile", "exponential")), source=src,
                         sun_direction=direction, sun_irradiance=irradiance, sky_radiance=radiance,
                         camera=camera)
