"""Camera rays and the G-buffer of a pixel-exact truth, against float64 formulas
written here independently of fogref's closed forms and of Mitsuba's camera.

* every sample of a pixel goes through its centre: ``view`` is the pinhole
  direction of the pixel centre (1e-6), ``T`` has zero standard error;
* ``T`` starts at the camera itself (Mitsuba's near clip would drop the first
  centimetre: 1e-4 relative here, 50x the float32 tolerance);
* a model whose extinction maps exactly (Unreal's) matches ``T`` at every pixel,
  silhouettes included;
* surfaces beyond Mitsuba's 10 km far clip are hit;
* where the fog is opaque toward the horizon, ``surface`` stays bounded and is
  marked undefined instead of exploding (it was Tsurface / T: up to 7e22).
"""

import numpy as np
import pytest

from conftest import SCENES
from fogref.gbuffer import load_truth

pytestmark = pytest.mark.render


def pinhole(origin, target, up, fov_x_deg, W, H):
    """Unit world directions through the pixel centres of a y-up pinhole camera
    (Mitsuba's ``perspective`` with ``fov_axis = x``, film y down), float64."""
    o, t, up = (np.asarray(v, float) for v in (origin, target, up))
    f = (t - o) / np.linalg.norm(t - o)
    left = np.cross(up, f)
    left /= np.linalg.norm(left)
    up2 = np.cross(f, left)
    tx = np.tan(np.radians(fov_x_deg) / 2)
    ty = tx * H / W
    x, y = (np.arange(W) + 0.5) / W, (np.arange(H) + 0.5) / H
    d = f + ((1 - 2 * x)[None, :, None] * tx) * left + ((1 - 2 * y)[:, None, None] * ty) * up2
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def exp_layer_depth(oy, dy, t, b, h):
    """Optical depth of exp(-b (y - h)) along y = oy + s dy, s in [0, t] (float64, t may be inf)."""
    c = np.exp(-b * (oy - h))
    k = b * dy
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        kt = k * t
        finite = np.where(np.abs(kt) > 1e-12, -np.expm1(-kt) / np.where(kt == 0, 1, kt), 1 - kt / 2)
        depth = np.where(np.isinf(t), np.where(k > 0, c / np.where(k > 0, k, 1), np.inf), c * t * finite)
    return depth


def render_truth(tmp_path, scene, overrides, spp=4, name="t.exr"):
    from fogref.render.render import render

    out = render(SCENES / scene, tmp_path / name, spp=spp, overrides=overrides, progress=False, png=False)
    return load_truth(out)


@pytest.fixture(scope="module")
def valley(tmp_path_factory, mitsuba):
    """The default valley, 48x27, denser fog so that the first centimetre shows."""
    return render_truth(
        tmp_path_factory.mktemp("valley"),
        "valley.xml",
        {"res": 48, "resy": 27, "sigma_t": 0.01, "falloff": 0.0138629},
    )


def test_view_is_the_pixel_centre_and_T_is_exact(valley):
    W, H = 48, 27
    expected = pinhole([0, 2, 0], [0.15, 2.35, 1], [0, 1, 0], 70, W, H)
    assert np.abs(valley.view - expected).max() < 1e-6
    assert valley.stderr["transmittance"].max() == 0.0  # every sample traced the same ray
    assert set(np.unique(valley.hit_fraction)) <= {0.0, 1.0}


#: float32's unit roundoff
U = 2.0**-24
#: the error of Dr.Jit's float32 exp and log, taken as 4 ulp (its polynomial approximations are
#: within 1-2 ulp; the margin covers a fused or unfused multiply-add in them)
E_EXP = 4 * U


def t_error_bound(s, log_c, x):
    """First-order bound on the relative error of ``T = exp(-s)`` computed in float32 as fogref
    does (``s = sigma c t phi(x)``, ``c = exp(log_c)``, ``x = k t``; ``fogref.media.closed_form``),
    against float64 from the same stored view and distance.

    The relative error of ``s`` is the sum of: sigma and b rounded to float32 (u each; b's
    reaches ``s`` through ``log_c`` and ``x``, times |log_c| and |x|), the products ``b (o_y - h)``,
    ``b d_y``, ``k t``, ``t phi``, ``c (t phi)``, ``sigma tau`` (u each; the first two times
    |log_c| and |x|), ``exp(log_c)`` (E_EXP) and ``phi`` (its expm1 with Kahan's correction and a
    division: 5 u, times its condition number <= 1 for the x's error):
    ``u (2 |log_c| + 3 |x|) + 12 u + E_EXP``.  ``exp(-s)`` turns it into ``s`` times that, plus its
    own E_EXP and the float32 rounding of the stored T (u).  Sky pixels (``c / k``): the same with
    ``x = 0``.
    """
    return s * (U * (2 * np.abs(log_c) + 3 * np.abs(x)) + 12 * U + E_EXP) + E_EXP + U


def test_T_from_the_camera_origin_matches_float64_at_every_pixel(valley):
    """Within the float32 bound of :func:`t_error_bound` at every pixel (measured: at most 1.6e-6,
    24 % of the bound, with the bound at most 1.5e-5); missing the first 1 cm would be ~1e-4,
    above the bound."""
    sigma, b, oy = 0.01, 0.0138629, 2.0
    D = np.where(valley.hit, valley.distance, np.inf)
    s = sigma * exp_layer_depth(oy, valley.view[..., 1], D, b, 0.0)
    T = np.exp(-s)
    err = np.abs(valley.transmittance[..., 1] - T) / np.maximum(T, 1e-30)
    bound = t_error_bound(s, -b * oy, np.where(valley.hit, b * valley.view[..., 1] * valley.distance, 0.0))
    seen = T > 1e-6
    worst = np.unravel_index(np.argmax(np.where(seen, err / bound, 0)), err.shape)
    assert (err <= bound)[seen].all(), (err[worst], bound[worst], worst)
    first_cm = -np.expm1(-sigma * np.exp(-b * oy) * 0.01)  # T's relative change without the first 1 cm
    assert bound[seen].max() < first_cm / 3


def test_unreal_exact_extinction_has_no_transmittance_error_at_any_pixel(valley):
    """Unreal's fog with the exact density/falloff mapping: max |T_ue4 - T| over
    every surface pixel (silhouettes included) <= 1e-5 (was RMSE 0.0077, max 0.12,
    with box-filtered G-buffers)."""
    from fogref.mapping import PhysicalScene, from_physical

    model = from_physical("ue4", PhysicalScene.from_params(valley.params))
    res = model.evaluate(valley.camera, valley.world_positions(1e5), precision="float64")
    T_model = np.broadcast_to(np.asarray(res.transmittance), valley.transmittance.shape)
    assert np.abs(T_model - valley.transmittance)[valley.hit].max() < 1e-5


def test_surfaces_beyond_ten_km_are_hit(tmp_path, mitsuba):
    """open_plane: a 100 km ground seen from 300 m; rows just below the horizon hit
    it 10-100 km away (Mitsuba's default far clip would turn them into sky)."""
    W, H = 64, 36
    t = render_truth(
        tmp_path,
        "open_plane.xml",
        {"res": W, "resy": H, "camera_origin": "0, 300, 0", "camera_target": "0.3, 299.9, 1"},
        spp=1,
    )
    d = pinhole([0, 300, 0], [0.3, 299.9, 1], [0, 1, 0], 90, W, H)
    with np.errstate(divide="ignore"):
        t_ground = np.where(d[..., 1] < 0, -300.0 / d[..., 1], np.inf)
    p = d * t_ground[..., None]
    expect_hit = np.isfinite(t_ground) & (np.abs(p[..., 0]) < 1e5) & (np.abs(p[..., 2]) < 1e5)
    assert np.array_equal(t.hit, expect_hit)
    assert t.distance[t.hit].max() > 15_000
    np.testing.assert_allclose(t.distance[t.hit], t_ground[t.hit], rtol=2e-5)


def test_surface_stays_bounded_where_the_fog_is_opaque(tmp_path, mitsuba):
    """Fog opaque toward the horizon (sigma_t 0.02 /m, falloff 0.05 /m, camera 3 m
    up: T ~ 1e-12 at the horizon, 0.5-0.9 looking down).  ``surface`` is a ratio
    estimator: bounded by the brightest surface or sky radiance (sky 0.5, sunlit
    ground < 1), undefined (coverage 0) where T ~ 0."""
    t = render_truth(
        tmp_path, "open_plane.xml", {"res": 64, "resy": 36, "sigma_t": 0.02, "falloff": 0.05}, spp=16
    )
    assert np.isfinite(t.surface).all() and t.surface.min() >= 0 and t.surface.max() < 1.5
    opaque = t.transmittance.max(axis=-1) < 1e-7
    assert opaque.any() and not t.surface_valid[opaque].any()
    assert t.surface_valid[t.transmittance.min(axis=-1) > 0.5].all()
    # where defined, T * surface and the directly estimated attenuated surface agree
    # on average within their noise (a conservative bound: the two share samples)
    v = t.surface_valid & (t.transmittance.min(axis=-1) > 0.2)
    d = (t.transmittance * t.surface - t.attenuated_surface)[v]
    se = (
        np.sqrt(((t.transmittance * t.stderr["surface"]) ** 2 + t.stderr["attenuated_surface"] ** 2)[v].sum())
        / d.size
    )
    assert abs(d.mean()) < 4 * se, (d.mean(), se)


@pytest.mark.parametrize(
    "origin, target",
    [((0, 3, -13), (0, 0, -10)), ((300, 20, 200), (340, 0, 260))],
    ids=["near the origin", "300 m out"],
)
def test_the_written_ground_is_the_plane_y0_to_float32_rounding(tmp_path, mitsuba, origin, target):
    """``fogref scene --geometry plane``'s ground against the analytic plane y = 0, hit by the same
    (stored, float32) camera rays in float64.  Error analysis: Mitsuba's float32 hit point on a
    rectangle carries rounding of the order of u = 2^-24 times the magnitudes it is computed from:
    the rectangle's half-size h and centre c, the ray's origin o and length t; 8 u (h + |c| + |o| +
    t) bounds it.  A ground whose shapes are no larger than their distance from the origin
    allows (h + |c| <= 7 max(|x|, |z|, 8 m) at the point: 8 m tiles at the centre, rings 4 times
    wider) keeps it at float32 rounding of the point itself.  One 1e5 m rectangle missed the plane
    by up to 2.5 cm (P.Z took 9 values over 17.7 mm along one image row that has one depth)."""
    from fogref.render.render import render
    from fogref.scene.writer import write_scene

    W, H = 32, 18
    xml = tmp_path / "p.xml"
    write_scene(xml, geometry="plane", camera_origin=origin, camera_target=target, fov=30, res=W, resy=H)
    t = load_truth(render(xml, tmp_path / "p.exr", spp=1, progress=False, png=False))
    o = np.asarray(origin, dtype=np.float64)
    d = t.view.astype(np.float64)
    assert t.hit.all()  # every pixel looks down at the ground
    s = -o[1] / d[..., 1]
    exact = o + s[..., None] * d
    size = np.maximum(np.maximum(np.abs(exact[..., 0]), np.abs(exact[..., 2])), 8.0)
    bound = 8 * 2.0**-24 * (7 * size + np.linalg.norm(o) + s)
    err = np.linalg.norm(t.position - exact, axis=-1)
    assert (err <= bound).all(), (err.max(), bound[np.unravel_index(np.argmax(err / bound), err.shape)])
    if origin[0] == target[0]:  # a row that has one depth: P.Z spreads by rounding (it was 17.7 mm)
        assert np.ptp(t.position[H // 2, :, 2]) <= 2 * bound[H // 2].max()
