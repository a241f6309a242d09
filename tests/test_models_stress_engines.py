"""Stress tests of the Godot, Bevy and three.js models (hypothesis), the domain of
tests/test_models_stress.py: extinction 1e-9..1e2 per metre, heights -1e4..1e6 m for
cameras and points, distances 1e-4..1e7 m plus the pixel at the camera, directions exactly
horizontal, within 1e-7 of horizontal, vertical and random; every variant (mode, falloff,
lobe on/off), float32 and float64.

Asserted everywhere: no NaN/Inf in inscatter or transmittance, transmittance in [0, 1],
inscatter >= 0, the precision's dtype.  Accuracy where a model is exact (Godot's
exponential mode, Bevy's Exponential/Atmospheric) is in each model's own test file.
(A separate file, so that tests/test_models_stress.py's ``make``/``VARIANTS`` stay as they are.)
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fogref.models.bevy import BevyDistanceFog, BevyFogParams
from fogref.models.godot import GodotFog, GodotFogParams
from fogref.models.threejs import ThreeFogParams, ThreeJSFog

SET = settings(max_examples=150, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
sigmas = st.floats(-9, 2).map(lambda e: 10.0**e)
heights = st.one_of(st.floats(-1e4, 1e6), st.sampled_from([-1e4, 0.0, 1e6]))
dists = st.floats(-4, 7).map(lambda e: 10.0**e)
_special = st.sampled_from(
    [(1.0, 0.0, 0.0), (0.0, 0.0, 1.0), (0.0, 1.0, 0.0), (0.0, -1.0, 0.0), (0.6, 0.0, -0.8)]
)
_near_h = st.tuples(st.floats(-1.0, 1.0), st.floats(0, 2 * math.pi)).map(
    lambda a: (math.cos(a[1]), 1e-7 * a[0], math.sin(a[1]))
)
_random = st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)).filter(
    lambda v: sum(x * x for x in v) > 1e-6
)
directions = st.one_of(_special, _near_h, _random)


def make(name: str, variant: str, sigma: float, h: float, sun) -> object:
    """One model of the engine ``name`` with extinction-like parameters ``sigma`` [1/m]."""
    if name == "godot":
        kw = dict(
            fog_density=sigma,
            fog_height=h,
            fog_sun_scatter=1.0,
            sun_direction=sun,
            sun_color=(5.0, 4.0, 3.0),
            fog_aerial_perspective=0.3,
            sky_color=(0.2, 0.3, 0.5),
        )
        if variant == "height":
            kw.update(fog_height_density=sigma * 10.0)
        elif variant == "height_above":
            kw.update(fog_height_density=-sigma)
        elif variant == "depth":
            kw.update(
                fog_mode="depth",
                fog_density=min(sigma * 100.0, 1.0),
                fog_depth_begin=1.0 / sigma**0.5,
                fog_depth_end=0.0,
                z_far=1e4,
                fog_depth_curve=2.0,
            )
        return GodotFog(GodotFogParams(**kw))
    if name == "bevy":
        lobe = dict(
            directional_light_color=(1.0, 0.9, 0.8, 1.0),
            directional_light_exponent=20.0,
            light_direction=sun,
            light_color=(3.0, 3.0, 3.0),
            color=(0.3, 0.4, 0.5, 0.8),
        )
        if variant == "Linear":
            return BevyDistanceFog(BevyFogParams(falloff="Linear", start=h, end=h + 1.0 / sigma, **lobe))
        if variant == "Atmospheric":
            return BevyDistanceFog(
                BevyFogParams(
                    falloff="Atmospheric",
                    extinction=(sigma, 2 * sigma, 3 * sigma),
                    inscattering=(sigma, sigma, 0.5 * sigma),
                    **lobe,
                )
            )
        return BevyDistanceFog(BevyFogParams(falloff=variant, density=sigma, **lobe))
    if variant == "Fog":
        return ThreeJSFog(ThreeFogParams(mode="Fog", near=h, far=h + 1.0 / sigma, color=(0.5, 0.6, 0.7)))
    return ThreeJSFog(ThreeFogParams(mode="FogExp2", density=sigma, color=(0.5, 0.6, 0.7)))


VARIANTS = {
    "godot": ("exponential", "height", "height_above", "depth"),
    "bevy": ("Linear", "Exponential", "ExponentialSquared", "Atmospheric"),
    "threejs": ("Fog", "FogExp2"),
}


@SET
@given(
    st.sampled_from(sorted(VARIANTS)),
    st.data(),
    sigmas,
    heights,
    heights,
    directions,
    st.lists(st.tuples(directions, dists), min_size=1, max_size=12),
)
def test_no_nan_inf_range(name, data, sigma, h, cam_y, sun, rays):
    variant = data.draw(st.sampled_from(VARIANTS[name]))
    cam = np.array([3.0, cam_y, -2.0])
    pts = [cam + np.asarray(d, float) / np.linalg.norm(d) * L for d, L in rays] + [cam]
    fog = make(name, variant, sigma, h, sun)
    for prec in ("float32", "float64"):
        r = fog.evaluate(cam, np.array(pts), prec)
        T, I = np.asarray(r.transmittance), np.asarray(r.inscatter)
        assert np.all(np.isfinite(T)) and np.all(np.isfinite(I)), (name, variant, prec, T, I)
        assert np.all(T >= 0) and np.all(T <= 1), (name, variant, prec, T)
        assert np.all(I >= 0), (name, variant, prec, I)
        assert T.dtype == (np.float32 if prec == "float32" else np.float64)
