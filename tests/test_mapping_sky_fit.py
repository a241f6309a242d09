"""The fits' closed forms with a physical sky: a ``sunsky`` projected onto the phase function.

A uniform sky keeps the closed form it had (``alpha L_sky (1 - T)``, bit for bit); a sunsky's sky
term is ``alpha S(d) (1 - T)`` with ``S`` its projection onto the HG phase function per view
(:func:`fogref.mapping.views.sky_projection`), checked here against a brute-force quadrature of
the sky over the dome, and the fitted FogInscatteringColor follows the real sky.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fogref.mapping import PhysicalScene, fit_unreal
from fogref.mapping.views import physical_single_scattering, sample_views, sky_projection
from fogref.media import NP, ExpLayer, FogMedium, single_scatter_sun
from fogref.media.single_scatter import hg_upper_fraction, single_scatter_sky

W_SUN = np.array([0.4, 0.35, 0.85]) / np.linalg.norm([0.4, 0.35, 0.85])
FOG = FogMedium(sigma_t=0.002, albedo=0.9, g=0.6, layers=(ExpLayer(1.0, 0.02, 0.0),))


@pytest.fixture(scope="module")
def sunsky():
    """A sunsky's parameters (as in a scene description) and its isotropic projection."""
    from fogref.media.single_scatter import sky_phase_projection
    from fogref.media.sky import sky_radiance

    model = {"type": "sunsky", "sun_direction": [float(x) for x in W_SUN], "turbidity": 4.0, "albedo": 0.3}
    model.update(sun_aperture=0.5358, sky_scale=1.0, sun_scale=1.0)
    iso = sky_phase_projection(sky_radiance(model), 0.0, [[0.0, 1.0, 0.0]])[0]
    return model, tuple(float(x) for x in iso)


def test_uniform_sky_keeps_its_closed_form_bit_for_bit():
    ps = PhysicalScene(FOG, tuple(W_SUN), (3.0, 3.0, 3.0), (0.2, 0.3, 0.5))
    v = sample_views(ps.camera, n_dirs=32)
    o = tuple(np.full(len(v.D), c) for c in v.camera)
    d = tuple(v.d[:, i] for i in range(3))
    D = np.where(v.sky, NP.largest, v.D)
    ref = np.stack(single_scatter_sun(NP, FOG, o, d, D, ps.sun_direction, ps.sun_irradiance), -1)
    ref = ref + np.stack(single_scatter_sky(NP, FOG, o, d, D, ps.sky_radiance), -1)
    assert np.array_equal(physical_single_scattering(ps, v), ref)
    # a sun below the horizon adds nothing: the sky's term alone (its optical depth made once, as
    # when the sun's term shares it)
    below = PhysicalScene(FOG, (W_SUN[0], -0.1, W_SUN[2]), (3.0, 3.0, 3.0), (0.2, 0.3, 0.5))
    sky = np.stack(single_scatter_sky(NP, FOG, o, d, D, ps.sky_radiance), -1)
    assert np.array_equal(physical_single_scattering(below, v), np.zeros_like(sky) + sky)
    # the projection of a uniform sky is L times the phase function's upper fraction
    S = sky_projection(ps, v.d[:40])
    H = np.asarray(hg_upper_fraction(0.6, v.d[:40, 1]), dtype=float).reshape(-1)
    assert np.allclose(S, H[:, None] * np.asarray(ps.sky_radiance), rtol=0, atol=1e-9)


def _dome(L, g, views, n_theta=300, n_phi=600):
    """Brute force: S(v) by the midpoint rule over the upper hemisphere in world angles (y up)."""
    th = (np.arange(n_theta) + 0.5) * (math.pi / 2 / n_theta)
    ph = (np.arange(n_phi) + 0.5) * (2 * math.pi / n_phi)
    T, P = np.meshgrid(th, ph, indexing="ij")
    w = np.stack([np.sin(T) * np.sin(P), np.cos(T), np.sin(T) * np.cos(P)], -1).reshape(-1, 3)
    dw = (np.sin(T) * (math.pi / 2 / n_theta) * (2 * math.pi / n_phi)).reshape(-1)
    Lw = L(w)
    out = []
    for v in views:
        mu = w @ v
        p = (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * mu) ** 1.5)
        out.append((Lw * (p * dw)[:, None]).sum(0))
    return np.array(out)


def test_sunsky_fit_uses_the_real_sky(sunsky):
    from fogref.media.sky import sky_radiance

    model, iso = sunsky
    stand_in = PhysicalScene(FOG, tuple(W_SUN), (3.0, 3.0, 3.0), iso)
    ps = PhysicalScene(FOG, tuple(W_SUN), (3.0, 3.0, 3.0), iso, sky_model=model)
    assert ps != stand_in and hash(ps) != hash(stand_in)  # the fit cache keeps them apart
    v = sample_views(ps.camera, n_dirs=24, distances=[30.0, 300.0, 3000.0])
    # brute-force target: the sun's closed form plus the dome quadrature of the sky
    uniq, inv = np.unique(v.d, axis=0, return_inverse=True)
    S = _dome(sky_radiance(model), FOG.g, uniq)[np.asarray(inv).reshape(-1)]
    T = np.exp(
        -FOG.sigma_t[0]
        * FOG.optical_depth(
            NP,
            tuple(np.full(len(v.D), c) for c in v.camera),
            tuple(v.d[:, i] for i in range(3)),
            np.where(v.sky, NP.largest, v.D),
        )
    )
    brute = physical_single_scattering(ps, v, sky=False) + 0.9 * S * (1.0 - T)[:, None]
    ours = physical_single_scattering(ps, v)
    assert np.allclose(ours, brute, rtol=3e-3, atol=1e-7 * brute.max())
    f_ours = fit_unreal(ps, views=v, fit_start=False).params.FogInscatteringColor
    f_brute = fit_unreal(ps, views=v, target=brute, fit_start=False).params.FogInscatteringColor
    f_stand = fit_unreal(stand_in, views=v, fit_start=False).params.FogInscatteringColor
    assert np.allclose(f_ours, f_brute, rtol=3e-3)
    assert np.abs(np.subtract(f_ours, f_stand)).max() > 0.05 * max(f_stand)  # the sky's shape shows
