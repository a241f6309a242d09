"""The ``single.*`` channel of fogpath on the open plane against the closed form.

Sky off, so single scattering is the sun's alone, and the open plane casts no
shadow on the fog: ``fogref.media.single_scatter_sun`` is then the exact expected
value of every pixel (box filter: averaged over 8x8 sub-pixel rays).  Test: a
one-sample t-test per 2x2 block over independent runs, Bonferroni-corrected,
family-wise alpha = 1e-3.  The two-layer closed form is itself checked against
mpmath quadrature on rays of the same camera.
"""

import mpmath as mp
import numpy as np
import pytest
from render_scenes import render_runs
from stats import one_sample_blocks

from conftest import SCENES
from fogref.media import NP, hg_phase, single_scatter_sun
from fogref.media.params import medium_from_params

pytestmark = pytest.mark.render
W, H, SUB = 16, 12, 8


def _camera_rays(mi, scene):
    sensor = scene.sensors()[0]
    u = (np.arange(W * SUB) + 0.5) / (W * SUB)
    v = (np.arange(H * SUB) + 0.5) / (H * SUB)
    uu, vv = np.meshgrid(u, v)
    pos = mi.Point2f(uu.ravel().astype(np.float32), vv.ravel().astype(np.float32))
    ray, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
    o = tuple(np.array(ray.o[i], dtype=np.float64) for i in range(3))
    d = np.stack([np.array(ray.d[i], dtype=np.float64) for i in range(3)])
    d /= np.linalg.norm(d, axis=0)
    return o, tuple(d)


def _reference(mi, scene, desc):
    medium = medium_from_params(desc["medium"], "open_plane.xml")
    o, d = _camera_rays(mi, scene)
    D = np.where(d[1] < 0, -o[1] / np.where(d[1] < 0, d[1], -1.0), NP.largest)  # ground at y = 0
    sun = desc["sun"]
    L = single_scatter_sun(NP, medium, o, d, D, sun["direction"], sun["irradiance"])
    img = np.stack(L, axis=-1).reshape(H * SUB, W * SUB, 3)
    return img.reshape(H, SUB, W, SUB, 3).mean(axis=(1, 3)), medium, (o, d, D)


@pytest.mark.parametrize("layers", [{}, {"density2": 0.4}], ids=["one-layer", "two-layer"])
def test_single_channel_matches_closed_form(mitsuba, layers):
    mi = mitsuba
    from fogref.render.load import load_scene

    overrides = {"res": W, "resy": H, "sky_radiance": "0, 0, 0", "max_depth": 2, **layers}
    scene, desc = load_scene(SCENES / "open_plane.xml", overrides)
    names = ["R", "G", "B"] + list(scene.integrator().aov_names())
    i0 = names.index("single.R")
    runs = [r[..., i0 : i0 + 3] for r in render_runs(mi, scene, 8, 64, aov=True)]
    ref, medium, (o, d, D) = _reference(mi, scene, desc)
    assert ref.max() > 0.01  # the test has something to measure
    one_sample_blocks(
        runs, ref, block=2, alpha=1e-3, what=f"single.* vs closed form ({layers or 'one layer'})"
    )

    if layers:  # closed form vs mpmath quadrature on a few of the same rays
        mp.mp.dps = 30
        sun = desc["sun"]
        w = sun["direction"]
        for k in np.linspace(0, len(D) - 1, 5).astype(int):
            ok, dk, Dk = [float(x[k]) for x in o], [float(x[k]) for x in d], float(D[k])
            Dk = min(Dk, 2e4)

            def rho(y):
                return sum(L.density * mp.e ** (-L.falloff * (y - L.height)) for L in medium.layers)

            def tau_sun(y):
                return sum(
                    L.density * mp.e ** (-L.falloff * (y - L.height)) / (L.falloff * w[1])
                    for L in medium.layers
                )

            def tau(t):
                return mp.quad(lambda s: rho(ok[1] + s * dk[1]), [0, t])

            sig, alb, E = medium.sigma_t[0], medium.albedo[0], sun["irradiance"][0]
            p = float(hg_phase(NP, np.dot(dk, w), medium.g))
            ref_k = mp.quad(
                lambda t: (
                    alb
                    * p
                    * E
                    * sig
                    * rho(ok[1] + t * dk[1])
                    * mp.e ** (-sig * tau(t) - sig * tau_sun(ok[1] + t * dk[1]))
                ),
                [0, Dk],
            )
            got = single_scatter_sun(
                NP,
                medium,
                tuple(np.array([x]) for x in ok),
                tuple(np.array([x]) for x in dk),
                np.array([Dk]),
                w,
                sun["irradiance"],
            )[0][0]
            assert abs(got - float(ref_k)) <= 1e-9 * abs(float(ref_k)) + 1e-15
