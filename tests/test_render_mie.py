"""fogpath with a droplet fog's phase function: single scattering against float64 quadrature.

An unbounded exponential fog (no ground, no sky; camera rays all rise) lit by a low sun,
seen toward the sun so that the pixels (2 to 27 deg from the sun) span the flank of the
diffraction peak and the forward lobe, where the phase falls by a factor of 300.  Each
pixel's single scattering (fogpath ``max_depth = 2``, ``pixel_exact``: one ray per pixel)
is compared with scipy's adaptive quadrature of

    alpha E p(d.w) int_0^inf sigma rho(t) exp(-sigma tau(t) - sigma tau_sun(p(t))) dt

in float64 per channel, the phase interpolated from the table by numpy (independent of the
renderer's Dr.Jit lookup and of the closed form).  Two estimators: the exact sun sampler
(``sun_sampling``: zero variance here, so it must agree to float32 rounding: 1.1e-4
measured, 3e-4 allowed) and next-event estimation through the phase plugin's ``eval``
(``sun_sampling = false``: 16 runs of 64 spp, a t-test per pixel, Bonferroni, family-wise
alpha = 1e-3, and a t-test at alpha = 1e-3 of the mean relative error over the pixels, whose
standard error is 7.7e-4 (asserted < 1.5e-3): with 95 % power it detects a bias of 0.44 %
(0.86 % at the bound).  Pixels within 2 deg of the sun are left out: there float32 cosines
(ulp 6e-8) move the phase of the peak by more than 3e-4.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from render_scenes import render_runs
from scipy.integrate import quad
from stats import one_sample_blocks

from fogref.media import NP
from fogref.media.droplets import DROPLET_PRESETS
from fogref.media.mie import droplet_optics
from fogref.media.phase import TabulatedPhase, approx_mie_phase

pytestmark = pytest.mark.render
W, H = 12, 8
RUNS = 16
T_CRIT = 4.07  # two-sided t, 15 degrees of freedom, alpha = 1e-3
SIGMA, FALLOFF, ALBEDO = 0.01, 0.05, 0.95
SUN_ELEV, E = 12.0, (2.0, 1.9, 1.7)


def _phase(kind):
    if kind == "mie":
        return droplet_optics(DROPLET_PRESETS["radiation"]).grey_phase("mie radiation")
    return TabulatedPhase.from_function(lambda c: approx_mie_phase(NP, c, 6.0), label="approx-mie 6 um")


def _scene(mi, phase, sun_sampling):
    T = mi.ScalarTransform4f()
    el = math.radians(SUN_ELEV)
    w = (0.0, math.sin(el), math.cos(el))  # toward the sun
    return mi.load_dict(
        {
            "type": "scene",
            "integrator": {
                "type": "fogpath",
                "max_depth": 2,
                "pixel_exact": True,
                "sun_sampling": sun_sampling,
            },
            "sensor": {
                "type": "perspective",
                "fov": 40,
                "fov_axis": "x",
                "to_world": T.look_at(
                    origin=[0, 2, 0], target=[0, 2 + math.tan(math.radians(20)), 1], up=[0, 1, 0]
                ),
                "film": {"type": "hdrfilm", "width": W, "height": H, "rfilter": {"type": "box"}},
                "medium": {
                    "type": "heightfog",
                    "sigma_t": SIGMA,
                    "albedo": ALBEDO,
                    "falloff": FALLOFF,
                    "height": 0.0,
                    "phase": phase.as_params(),
                },
            },
            "sun": {
                "type": "directional",
                "direction": [-x for x in w],
                "irradiance": {"type": "rgb", "value": E},
            },
        },
        parallel=False,
    ), w


def _rays(mi, scene):
    sensor = scene.sensors()[0]
    u = (np.arange(W) + 0.5) / W
    v = (np.arange(H) + 0.5) / H
    uu, vv = np.meshgrid(u, v)
    pos = mi.Point2f(uu.ravel().astype(np.float32), vv.ravel().astype(np.float32))
    ray, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
    o = np.array([float(ray.o[i][0]) for i in range(3)])
    d = np.stack([np.array(ray.d[i], dtype=np.float64) for i in range(3)], axis=1)
    return o, d / np.linalg.norm(d, axis=1, keepdims=True)


def _reference(o, d, w, phase):
    c, v = np.asarray(phase.cosines), np.asarray(phase.values)
    out = np.zeros((len(d), 3))
    for k, dk in enumerate(d):
        assert dk[1] > 0
        y = lambda t: o[1] + t * dk[1]  # noqa: E731
        rho = lambda t: math.exp(-FALLOFF * y(t))  # noqa: E731
        tau = lambda t: (math.exp(-FALLOFF * o[1]) - rho(t)) / (FALLOFF * dk[1])  # noqa: E731
        tau_sun = lambda t: rho(t) / (FALLOFF * w[1])  # noqa: E731
        f = lambda t: SIGMA * rho(t) * math.exp(-SIGMA * (tau(t) + tau_sun(t)))  # noqa: E731
        integral = quad(f, 0, np.inf, epsabs=0, epsrel=1e-10, limit=200)[0]
        p = np.interp(float(dk @ np.asarray(w)), c, v)
        out[k] = ALBEDO * np.asarray(E) * p * integral
    return out.reshape(H, W, 3)


@pytest.mark.parametrize("kind", ["mie", "approx-mie"])
def test_single_scattering_vs_quadrature(mitsuba, kind):
    mi = mitsuba
    phase = _phase(kind)
    scene, w = _scene(mi, phase, True)
    o, d = _rays(mi, scene)
    ref = _reference(o, d, w, phase)
    far = (np.degrees(np.arccos(np.clip(d @ np.asarray(w), -1, 1))) > 2.0).reshape(H, W)
    assert far.sum() >= W * H - 4 and ref.max() / ref.min() > 3  # the image spans the lobe
    names = ["R", "G", "B"] + list(scene.integrator().aov_names())
    i0 = names.index("single.R")
    img = render_runs(mi, scene, 1, 4, aov=True)[0][..., i0 : i0 + 3]
    rel = np.abs(img / ref - 1)[far]
    assert rel.max() < 3e-4, f"{kind}: sun sampler off by {rel.max():.2e} (relative)"

    scene_nee, _ = _scene(mi, phase, False)
    runs = [r[..., i0 : i0 + 3] for r in render_runs(mi, scene_nee, RUNS, 64, aov=True)]
    runs = [np.where(far[..., None], r, ref) for r in runs]  # pixels near the sun: not tested
    one_sample_blocks(runs, ref, block=1, alpha=1e-3, what=f"single.* with NEE vs quadrature ({kind})")
    # the mean relative error over the pixels, per run: a t-test of its mean against 0
    bias = np.array([(r / ref - 1)[far].mean() for r in runs])
    se = bias.std(ddof=1) / math.sqrt(RUNS)
    assert abs(bias.mean()) < T_CRIT * se, f"{kind}: NEE biased by {bias.mean():.2e} (se {se:.1e})"
    assert se < 1.5e-3  # the test's power (see module)
