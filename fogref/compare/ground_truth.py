"""The ground-truth EXR as the comparison sees it: parts, geometry and scene parameters.

Reads the layout documented in :mod:`fogref.exrio`, plus the per-pixel unit camera
ray direction ``view.X, view.Y, view.Z`` (world frame, y-up) and the header
attribute ``fogref.params`` (JSON) with at least ``camera.origin`` [m] and, when
present, ``sun.direction`` (unit, pointing toward the sun) and ``sky.radiance``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fogref.errors import FogrefError
from fogref.exrio import read_exr, rgb

#: Channels ``compare`` needs, in the order they are reported when missing.
REQUIRED_CHANNELS: tuple[str, ...] = (
    *("R", "G", "B"),
    *(f"T.{c}" for c in "RGB"),
    *(f"inscatter.{c}" for c in "RGB"),
    *(f"surface.{c}" for c in "RGB"),
    "distance",
    *(f"P.{c}" for c in "XYZ"),
    "hit",
    *(f"view.{c}" for c in "XYZ"),
)
PARAMS_ATTRIBUTE = "fogref.params"


@dataclass
class GroundTruth:
    """One ground-truth image.  Arrays are ``(H, W, 3)`` float64 unless noted.

    ``final``: total radiance R,G,B; ``transmittance``: T (camera -> first surface, or
    -> infinity for sky pixels); ``inscatter``: radiance added by the medium;
    ``surface``: unfogged radiance of what the pixel sees (for sky pixels the sky as
    seen without fog, as the renderer writes it); ``distance``: ``(H, W)`` [m], 0 for
    sky pixels; ``position``: first-surface world position [m]; ``hit``: ``(H, W)``
    bool; ``view``: unit ray direction (world, y-up); ``camera``: ``(3,)`` [m];
    ``sun_direction``: ``(3,)`` unit toward the sun, or None; ``params``: the decoded
    ``fogref.params``; ``attrs``: all header attributes.
    """

    path: Path
    final: np.ndarray
    transmittance: np.ndarray
    inscatter: np.ndarray
    surface: np.ndarray
    distance: np.ndarray
    position: np.ndarray
    hit: np.ndarray
    view: np.ndarray
    camera: np.ndarray
    sun_direction: np.ndarray | None
    params: dict
    attrs: dict = field(default_factory=dict)

    @property
    def shape(self) -> tuple[int, int]:
        """``(height, width)`` in pixels."""
        return self.hit.shape

    @property
    def sky(self) -> np.ndarray:
        """``(H, W)`` bool: pixels whose ray escapes (``hit == 0``)."""
        return ~self.hit

    def world_positions(self, sky_distance: float) -> np.ndarray:
        """The point each pixel shades, ``(H, W, 3)`` [m], as an engine would see it.

        ``P`` for pixels that hit a surface; ``camera + view * sky_distance`` [m] for
        sky pixels (engines fog the sky as a surface at a finite distance).
        """
        if not (np.isfinite(sky_distance) and sky_distance > 0):
            raise ValueError(f"sky_distance must be finite and > 0 m, got {sky_distance}")
        far = self.camera + self.view * float(sky_distance)
        return np.where(self.hit[..., None], self.position, far)

    def sun_angle_deg(self) -> np.ndarray | None:
        """``(H, W)`` angle between the view ray and the direction to the sun [degrees].

        0 means looking straight at the sun; None when the scene has no sun.
        """
        if self.sun_direction is None:
            return None
        cos = np.clip(self.view @ self.sun_direction, -1.0, 1.0)
        return np.degrees(np.arccos(cos))

    def identity_residual(self) -> float:
        """Largest ``|final - (T * surface + inscatter)|`` [radiance]: the EXR's own
        consistency (ideally float32 rounding only)."""
        d = self.final - (self.transmittance * self.surface + self.inscatter)
        d = np.nan_to_num(np.abs(d), nan=0.0, posinf=np.finfo(np.float32).max)
        return float(d.max(initial=0.0))


def _unit_rows(v: np.ndarray) -> np.ndarray:
    """Normalise direction vectors along the last axis; zero/NaN vectors become (0, 0, 0)."""
    v = np.nan_to_num(v, nan=0.0, posinf=0.0, neginf=0.0)
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.divide(v, n, out=np.zeros_like(v), where=n > 0)


def _vector(source: str, params: dict, keys: tuple[str, ...]) -> np.ndarray:
    node = params
    for k in keys:
        if not isinstance(node, dict) or k not in node:
            raise FogrefError(f"{source}: header attribute '{PARAMS_ATTRIBUTE}' lacks '{'.'.join(keys)}'")
        node = node[k]
    v = np.asarray(node, dtype=np.float64)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise FogrefError(f"{source}: '{PARAMS_ATTRIBUTE}' {'.'.join(keys)} must be 3 finite numbers, got {node!r}")
    return v


def ground_truth_from_channels(channels: dict, attrs: dict, source: str = "<memory>") -> GroundTruth:
    """Build a :class:`GroundTruth` from decoded EXR ``channels`` and header ``attrs``.

    Raises :class:`FogrefError` naming ``source`` and every missing channel, or the
    missing/malformed ``fogref.params`` entry.
    """
    missing = [c for c in REQUIRED_CHANNELS if c not in channels]
    if missing:
        raise FogrefError(
            f"{source}: missing channel(s) {', '.join(repr(c) for c in missing)} "
            f"(fogref compare needs {', '.join(REQUIRED_CHANNELS)})"
        )
    params = attrs.get(PARAMS_ATTRIBUTE)
    if not isinstance(params, dict):
        raise FogrefError(f"{source}: header attribute '{PARAMS_ATTRIBUTE}' missing or not a JSON object")
    camera = _vector(source, params, ("camera", "origin"))
    sun = params.get("sun")
    sun_direction = _unit_rows(_vector(source, params, ("sun", "direction"))) if sun else None

    def group(g: str) -> np.ndarray:
        return rgb(channels, g).astype(np.float64)

    def xyz(g: str) -> np.ndarray:
        return np.stack([channels[f"{g}.{c}"] for c in "XYZ"], axis=-1).astype(np.float64)

    return GroundTruth(
        path=Path(source),
        final=group(""),
        transmittance=group("T."),
        inscatter=group("inscatter."),
        surface=group("surface."),
        distance=np.asarray(channels["distance"], dtype=np.float64),
        position=xyz("P"),
        hit=np.asarray(channels["hit"]) > 0.5,
        view=_unit_rows(xyz("view")),
        camera=camera,
        sun_direction=sun_direction,
        params=params,
        attrs=attrs,
    )


def load_ground_truth(path) -> GroundTruth:
    """Read and check a ground-truth EXR (see the module docstring for what it needs)."""
    channels, attrs = read_exr(path)
    return ground_truth_from_channels(channels, attrs, str(path))
