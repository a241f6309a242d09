"""fogpath's ``sky_at_media``: a constant sky at medium vertices as a closed form plus a residual.

At a medium vertex the sky's light is ``L H(d_y) + B (1 - H(d_y)) + w (L V T - c(w))``, with ``H``
the share of the Henyey-Greenstein lobe above the horizon, ``c(w)`` the sky's radiance ``L``
above the horizon and the control variate ``B`` below it, and ``w`` the continuation's own phase
sample.  Independent references:

* ``H``'s polynomial (:func:`fogref.media.single_scatter.hg_upper_fraction_series`, a truncated
  Legendre series) against the adaptive quadrature of
  :func:`~fogref.media.single_scatter.hg_upper_fraction` (itself checked against HG samples in
  ``tests/test_hg_upper_fraction.py``) and against mpmath's 2-D quadrature over the upper
  hemisphere, and the float32 table fogpath interpolates;
* image means, part by part, against fogpath's next-event estimation (``mis``, checked against
  stock Mitsuba in ``tests/test_render_vs_stock.py``), each with its own seeds; the white furnace
  (exact image mean 1) is in ``tests/test_render_bias.py``;
* the rule ``auto`` follows on scenes made to fall on either side of it.
"""

import math
from pathlib import Path

import numpy as np
import pytest
from numpy.polynomial import legendre
from render_scenes import base_scene, heightfog, render_runs

from fogref.errors import ParameterError
from fogref.media.single_scatter import (
    UPPER_FRACTION_DEGREES,
    hg_upper_fraction,
    hg_upper_fraction_series,
    hg_upper_fraction_table,
)

VALLEY = str(Path(__file__).resolve().parents[1] / "scenes" / "valley.xml")


# scipy's quad asks for 1e-13 and warns of roundoff near the sharp lobes (|g| >= 0.9); it still
# agrees with the series to 3e-9 there, and with mpmath below
@pytest.mark.filterwarnings("ignore::scipy.integrate.IntegrationWarning")
@pytest.mark.parametrize("g", [-0.93, -0.5, 0.2, 0.6, 0.76, 0.85, 0.9, 0.94])
def test_the_share_above_the_horizon_is_within_its_tolerance(g):
    """The polynomial against the adaptive quadrature (within 1e-12) at 401 heights, within the
    1e-7 it promises, at one of the degrees it tries."""
    c = hg_upper_fraction_series(g)
    assert len(c) - 1 in UPPER_FRACTION_DEGREES
    mu = np.linspace(-1.0, 1.0, 401)
    err = np.abs(legendre.legval(mu, c) - hg_upper_fraction(g, mu))
    assert err.max() <= 1e-7, (g, len(c), err.max())


def test_the_share_against_mpmath_on_the_hemisphere():
    """``H`` as a 2-D integral of the HG density over the upper hemisphere (mpmath, polar angle from
    the zenith and azimuth; no azimuthal closed form), within 1e-9 at three heights and two g."""
    mpmath = pytest.importorskip("mpmath")
    mpmath.mp.dps = 20
    for g in (0.5, -0.3):
        c = hg_upper_fraction_series(g, tolerance=1e-12)
        for mu0 in (-0.6, 0.1, 0.8):
            s0 = math.sqrt(1.0 - mu0 * mu0)

            def f(theta, phi, g=g, mu0=mu0, s0=s0):
                cos = mpmath.sin(theta) * mpmath.cos(phi) * s0 + mpmath.cos(theta) * mu0
                return (1 - g * g) / (4 * mpmath.pi * (1 + g * g - 2 * g * cos) ** 1.5) * mpmath.sin(theta)

            H = 2 * mpmath.quad(f, [0, mpmath.pi / 2], [0, mpmath.pi])  # symmetric in the azimuth
            assert abs(float(legendre.legval(mu0, c)) - float(H)) < 1e-9, (g, mu0)


def test_edges_of_the_share():
    """g = 0 is a half exactly (the constant term alone); no polynomial of the largest degree reaches 1e-7 for
    |g| >= 0.95, so fogpath keeps next-event estimation there; the share is 0 straight down and 1
    straight up only in the limit g -> 1, and stays in [0, 1]."""
    assert hg_upper_fraction_series(0.0) == (0.5,)
    assert float(legendre.legval(0.3, (0.5,))) == 0.5
    assert hg_upper_fraction_series(0.95) is None and hg_upper_fraction_series(-0.999) is None
    H = legendre.legval(np.linspace(-1, 1, 2001), hg_upper_fraction_series(0.94))
    assert np.all((H >= -1e-7) & (H <= 1 + 1e-7))


@pytest.mark.filterwarnings("ignore::scipy.integrate.IntegrationWarning")
@pytest.mark.parametrize("g", [-0.94, 0.0, 0.6, 0.85, 0.94])
def test_the_table_fogpath_interpolates_in_float32(mitsuba, g):
    """fogpath reads ``H`` by linear interpolation of a float32 table of 8193 values (one kernel
    for every ``g``): within 7e-7 of the quadrature at 4001 heights, nodes and midpoints."""
    import drjit as dr

    from fogref.media import drjit_ops

    ops, table = drjit_ops(), hg_upper_fraction_table(g)
    mu = np.linspace(-1.0, 1.0, 4001)
    h32 = ops.interp_uniform(mitsuba.Float(mu), -1.0, 1.0, table)
    dr.eval(h32)
    assert np.abs(np.array(h32) - hg_upper_fraction(g, mu)).max() < 7e-7
    assert hg_upper_fraction_table(0.95) is None


def _scene(mi, sky_at_media, res=(16, 9), **fog):
    d = base_scene(
        mi, {"type": "fogpath", "max_depth": 6, "sky_at_media": sky_at_media}, heightfog(mi, **fog), res=res
    )
    return mi.load_dict(d, parallel=False)


def _part_means(mi, scene, n, spp, seed0):
    """Per render: image means of the final image and of ``single`` and ``multiple`` (RGB each)."""
    from fogref_plugins.fogpath import AOV_NAMES

    names = ["R", "G", "B", *AOV_NAMES]
    parts = {"final": [0, 1, 2]} | {
        p: [names.index(f"{p}.{c}") for c in "RGB"] for p in ("single", "multiple")
    }
    runs = np.stack(render_runs(mi, scene, n, spp, aov=True, seed0=seed0))
    return {p: runs[..., i].mean(axis=(1, 2)) for p, i in parts.items()}


@pytest.mark.render
@pytest.mark.parametrize("g", [0.5, 0.85], ids=["g0.5", "g0.85"])
def test_residual_agrees_with_next_event_estimation_part_by_part(mitsuba, g):
    """The base scene (sun, sky, occluder, bounded exponential fog): image means of 48 renders
    each (16x9, 256 spp, independent seeds) of the final image, ``single`` and ``multiple``, per
    channel, within 4 standard errors (from the renders' spread) plus 0.05 %.  The standard errors
    are below 0.3 % of each mean (asserted; ``multiple``'s are the largest), so a bias of about
    1 % fails.  Checked to fail:
    ``H`` of the opposite direction, the control variate's ``B (1 - H)`` left out, ``T`` left
    out of the residual, and in the closed form's mean along a segment the albedo left out, the
    last segment (whose vertex is not lit at ``max_depth``) counted, or ``T(D)`` left out of the
    surface control variate's mean."""
    mi = mitsuba
    a = _part_means(mi, _scene(mi, "residual", g=g), 48, 256, 100)
    b = _part_means(mi, _scene(mi, "mis", g=g), 48, 256, 9000)
    for part in a:
        se = np.sqrt(a[part].var(0, ddof=1) / 48 + b[part].var(0, ddof=1) / 48)
        mean = b[part].mean(0)
        assert np.all(se < 3e-3 * mean), (part, se, mean)  # the power stated above
        diff = a[part].mean(0) - mean
        assert np.all(np.abs(diff) < 4 * se + 5e-4 * mean), (part, diff, se, mean)


def _choice(scene):
    return scene.integrator().sky_at_media_for(scene)


@pytest.mark.render
def test_auto_takes_the_residual_where_it_wins_and_mis_elsewhere(mitsuba):
    """``auto`` on the valley (thin fog above the camera, dark ground) takes the residual; with
    the camera in thick fog (transmittance straight up below 0.25), over a white ground
    (reflectance above 0.7), with g = 0.97 or without a sky it takes next-event estimation."""
    mi = mitsuba
    assert _choice(mi.load_file(VALLEY, res="8", resy="6", parallel=False)) == "residual"
    assert _choice(_scene(mi, "auto")) == "residual"
    assert _choice(_scene(mi, "auto", sigma_t=0.3)) == "mis"  # T up ~0.02
    assert _choice(_scene(mi, "auto", g=0.97)) == "mis"
    d = base_scene(mi, {"type": "fogpath"}, heightfog(mi), res=(8, 6))
    d["ground"]["bsdf"]["reflectance"]["value"] = [0.9, 0.9, 0.9]
    assert _choice(mi.load_dict(d, parallel=False)) == "mis"
    d = base_scene(mi, {"type": "fogpath"}, heightfog(mi), res=(8, 6), sky=False)
    assert _choice(mi.load_dict(d, parallel=False)) == "mis"


@pytest.mark.render
def test_residual_where_it_does_not_apply_says_what_is_missing(mitsuba):
    """``residual`` asked for where it cannot work: one error naming fogpath, ``sky_at_media``
    and what is missing, from the scene's first render (``render_moments``, what ``fogref render``
    calls; ``mi.render`` raises it as the cause of Dr.Jit's error) or from
    ``sky_at_media_for``; an unknown value lists the choices."""
    mi = mitsuba
    cases = {"g": ({"g": 0.97}, "|g| <= 0.94"), "sky": ({}, "a constant sky")}
    for name, (fog, needs) in cases.items():
        d = base_scene(
            mi,
            {"type": "fogpath", "sky_at_media": "residual"},
            heightfog(mi, **fog),
            res=(8, 6),
            sky=name != "sky",
        )
        scene = mi.load_dict(d, parallel=False)
        for call in (scene.integrator().render_moments, scene.integrator().sky_at_media_for):
            with pytest.raises(ParameterError, match="sky_at_media") as e:
                call(scene)
            assert needs in str(e.value) and "fogpath" in str(e.value)
    with pytest.raises(Exception, match="sky_at_media") as e:
        mi.load_dict(
            base_scene(mi, {"type": "fogpath", "sky_at_media": "nee"}, heightfog(mi), res=(8, 6)),
            parallel=False,
        )
    assert "auto" in str(e.value) and "residual" in str(e.value)
