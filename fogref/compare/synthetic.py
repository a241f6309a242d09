"""A synthetic truth on which a fog model is exact, with known noise: for testing statistics
(:func:`fogref.compare.check.check`, its intervals and verdicts) without a render."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from fogref.errors import FogrefError, ParameterError
from fogref.gbuffer import Truth
from fogref.models.base import SKY_DISTANCE as DEFAULT_SKY_DISTANCE
from fogref.params import integer


def synthetic_truth(
    model,
    shape=(18, 32),
    noise: float = 0.01,
    seed: int = 0,
    fov_deg: float = 70.0,
    surface_radiance=(0.3, 0.25, 0.2),
    sky_radiance=(0.2, 0.3, 0.5),
    sky_distance: float = DEFAULT_SKY_DISTANCE,
    correlated: bool = False,
    channel_correlation: float = 0.0,
) -> Truth:
    """A pixel-exact :class:`~fogref.gbuffer.Truth` on which ``model`` is exact, plus known noise.

    The camera (at 2 m) looks over a ground plane (y = 0) below the horizon and a
    sky above; ``T`` and ``inscatter`` are the model's own values, ``surface`` is
    constant per region, and Gaussian noise of relative standard deviation ``noise``
    is added to ``inscatter`` and ``surface`` (``stderr.*`` says how much); ``T`` is
    noise-free, as in a pixel-exact render.  For testing statistics without a render.

    Parameters
    ----------
    model : fog model
        Evaluated at float64 on the G-buffer.
    shape : (int, int)
        ``(H, W)`` pixels, each in [1, 16384].
    noise : float
        Relative standard error of the noisy parts, >= 0.
    seed : int
        Seed of the noise.
    correlated : bool
        Make the noise of 2×2 pixel groups identical (to test the block bootstrap
        against spatial correlation); ``stderr`` stays per pixel.
    channel_correlation : float
        Correlation of the noise of a pixel's R, G and B, in [0, 1] (a real render's is
        ~0.9); the truth's ``corr`` says so.

    Examples
    --------
    >>> from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams
    >>> t = synthetic_truth(UE4ExponentialHeightFog(UE4FogParams()), shape=(9, 16))
    >>> t.shape, bool(t.hit.any() and t.sky.any()), t.pixel_exact
    ((9, 16), True, True)
    """
    if not (math.isfinite(noise) and noise >= 0):
        raise FogrefError(f"noise: {noise} must be finite and >= 0")
    try:
        H, W = shape
    except (TypeError, ValueError):
        raise ParameterError("synthetic_truth", "shape", f"expected (H, W), got {shape!r}") from None
    H = integer(H, "shape", source="synthetic_truth", lo=1, hi=1 << 14, unit="pixels (H)")
    W = integer(W, "shape", source="synthetic_truth", lo=1, hi=1 << 14, unit="pixels (W)")
    camera = np.array([0.0, 2.0, 0.0])
    tan = math.tan(math.radians(fov_deg) / 2)
    u = (np.arange(W) + 0.5) / W * 2 - 1
    v = 1 - (np.arange(H) + 0.5) / H * 2
    x = u[None, :] * tan
    y = v[:, None] * tan * H / W + 0.02
    d = np.stack(np.broadcast_arrays(x, y, np.ones((H, W))), -1)
    d = d / np.linalg.norm(d, axis=-1, keepdims=True)
    hit = d[..., 1] < -1e-3
    t = np.where(hit, -camera[1] / np.where(hit, d[..., 1], -1.0), 0.0)
    pos = np.where(hit[..., None], camera + d * t[..., None], 0.0)
    world = np.where(hit[..., None], pos, camera + d * sky_distance)
    res = model.evaluate(camera, world, precision="float64")
    T = np.broadcast_to(np.asarray(res.transmittance, float), (H, W, 3)).copy()
    L = np.broadcast_to(np.asarray(res.inscatter, float), (H, W, 3)).copy()
    surface = np.where(hit[..., None], np.asarray(surface_radiance, float), np.asarray(sky_radiance, float))
    rng = np.random.default_rng(seed)

    if not 0.0 <= channel_correlation <= 1.0:
        raise FogrefError(f"channel_correlation: {channel_correlation} must be in [0, 1]")
    rho = float(channel_correlation)

    k = 3 if rho == 0 else 4  # a shared fourth draw makes the channels correlated

    def gauss():
        if not correlated:
            z = rng.standard_normal((H, W, k))
        else:
            z = rng.standard_normal((-(-H // 2), -(-W // 2), k))
            z = np.repeat(np.repeat(z, 2, 0), 2, 1)[:H, :W]
        return z if rho == 0 else math.sqrt(rho) * z[..., 3:] + math.sqrt(1.0 - rho) * z[..., :3]

    se_L, se_s = noise * np.abs(L), noise * surface
    L_hat = L + se_L * gauss()
    s_hat = surface + se_s * gauss()
    att = T * s_hat
    final = att + L_hat
    zero = np.zeros((H, W, 3))
    stderr = {
        "final": np.sqrt(se_L**2 + (T * se_s) ** 2),
        "transmittance": zero,
        "attenuated_surface": T * se_s,
        "inscatter": se_L,
        "single": se_L,
        "multiple": zero,
        "surface": se_s,
    }
    params = {
        "camera": {"origin": camera.tolist()},
        "sun": None,
        "sky": {"type": "constant", "radiance": list(sky_radiance)},
    }
    attrs = {
        "fogref.schema": "2",
        "fogref.pixel_filter": "centre",
        "fogref.spp": 0,
        "fogref.seed": seed,
        "fogref.params": params,
        "fogref.synthetic": True,
    }
    return Truth(
        path=Path(f"<synthetic truth, seed {seed}>"),
        final=final,
        transmittance=T,
        attenuated_surface=att,
        inscatter=L_hat,
        single=L_hat,
        multiple=zero,
        surface=s_hat,
        stderr=stderr,
        surface_coverage=np.ones((H, W)),
        distance=t,
        position=pos,
        view=d,
        hit_fraction=hit.astype(float),
        camera=camera,
        sun_direction=None,
        params=params,
        attrs=attrs,
        corr={k: np.full((H, W, 3), rho) for k in stderr},
    )
