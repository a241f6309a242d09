"""fogref.compare.metrics / binning, fogref.display: hand-computed values and edge cases."""

import subprocess
import sys

import colour
import numpy as np
import pytest

from fogref.compare import error_maps as E
from fogref.compare import metrics as M
from fogref.compare import perceptual as P
from fogref.compare.binning import angle_edges, binned_errors, log_distance_edges
from fogref.display import luminance, tone_map
from fogref.display import srgb_encode as srgb_oetf


def _rand(shape=(12, 16, 3), seed=0, scale=1.0):
    return np.random.default_rng(seed).random(shape) * scale


def test_rmse_and_relmse_hand_computed():
    r = np.array([[[1.0, 2.0, 0.0], [0.0, 0.0, 0.0]]])  # (1, 2, 3)
    x = np.array([[[2.0, 2.0, 0.0], [0.0, 0.0, 3.0]]])
    # squared errors: 1, 0, 0, 0, 0, 9 -> mean 10/6
    assert M.rmse(r, x) == pytest.approx(np.sqrt(10 / 6))
    eps = 0.01
    expected = (1 / (1 + eps) + 9 / eps) / 6
    assert M.relmse(r, x, eps=eps) == pytest.approx(expected)
    assert M.relmse(r, x) == pytest.approx((1 / (1 + M.RELMSE_EPS) + 9 / M.RELMSE_EPS) / 6)
    # masks: first pixel only
    assert M.rmse(r, x, mask=np.array([[True, False]])) == pytest.approx(np.sqrt(1 / 3))
    assert M.rmse(r, x, mask=np.array([[False, False]])) is None
    np.testing.assert_allclose(M.abs_error_map(r, x), [[1 / 3, 1.0]])
    np.testing.assert_allclose(M.signed_error(r, x), x - r)


def test_relmse_rejects_nonpositive_eps():
    with pytest.raises(ValueError):
        M.relmse(np.ones((1, 1, 3)), np.ones((1, 1, 3)), eps=0.0)


def test_shape_mismatch_is_an_error():
    with pytest.raises(ValueError, match="differ"):
        M.rmse(np.ones((2, 2, 3)), np.ones((2, 3, 3)))


def test_identical_images_give_exactly_zero():
    r = _rand(scale=5.0)
    assert M.rmse(r, r) == 0.0
    assert M.relmse(r, r) == 0.0
    assert np.all(P.delta_e2000_map(r, r) == 0.0)
    flip, _ = P.flip_map(r, r)
    assert flip.shape == r.shape[:2] and np.all(flip == 0.0)
    s = E.error_maps(r, r).summary()
    for k in ("rmse", "relmse", "mean_abs_error", "max_abs_error", "delta_e2000_mean", "flip_mean"):
        assert s[k] == 0.0, k


def test_delta_e2000_matches_colour_science_directly():
    ref = np.array([[0.2, 0.4, 0.6], [1.5, 0.1, 0.05], [0.0, 0.0, 0.0]])
    test = np.array([[0.25, 0.35, 0.6], [1.2, 0.2, 0.1], [0.01, 0.02, 0.0]])
    white = 2.0
    d65 = colour.RGB_COLOURSPACES["sRGB"].whitepoint

    def lab(rgb):
        return colour.XYZ_to_Lab(colour.RGB_to_XYZ(rgb / white, "sRGB", apply_cctf_decoding=False), d65)

    expected = colour.delta_E(lab(ref), lab(test), method="CIE 2000")
    np.testing.assert_allclose(P.delta_e2000_map(ref, test, white=white), expected, rtol=1e-12)
    # white = 1 maps linear (1, 1, 1) to L* = 100
    assert P.linear_rgb_to_lab(np.ones(3), 1.0)[0] == pytest.approx(100.0, abs=1e-3)


def test_delta_e2000_maps_are_colour_sciences_delta_e_bit_for_bit():
    """delta_e2000_maps (the reference converted to CIELAB once for every test image) against
    colour-science's delta_E (CIE 2000) of each pair through its RGB_to_XYZ and XYZ_to_Lab, on 200
    random image pairs: (H, W, 3), (N, 3) and (3,) shapes, 1e-8 to 1e4 radiances, greys (hue
    undefined), zero channels, negatives (clipped) and identical pairs; every value equal bit for
    bit (one ulp is detected)."""
    d65 = colour.RGB_COLOURSPACES["sRGB"].whitepoint

    def lab(rgb, white):
        x = np.clip(rgb, 0.0, None) / white
        return colour.XYZ_to_Lab(colour.RGB_to_XYZ(x, "sRGB", apply_cctf_decoding=False), d65)

    rng = np.random.default_rng(11)
    for k in range(200):
        shape = [(9, 16, 3), (7, 3), (3,), (2, 5, 3)][k % 4]
        scale = 10.0 ** rng.uniform(-8, 4)
        r = rng.random(shape) ** rng.uniform(0.2, 5.0) * scale
        x = r * rng.uniform(0.5, 1.5, shape) + rng.normal(0.0, 0.1 * scale, shape)
        if k % 5 == 0:
            x[..., 0], r[..., 1] = 0.0, 0.0
        if k % 7 == 0:
            x = r.copy()
        if k % 9 == 0:  # greys
            r = np.repeat(r.mean(axis=-1, keepdims=True), 3, axis=-1)
        white = float(rng.choice([1.0, scale, 0.37 * scale]))
        want = np.asarray(colour.delta_E(lab(r, white), lab(x, white), method="CIE 2000"), dtype=np.float64)
        got = P.delta_e2000_map(r, x, white=white)
        assert got.shape == want.shape and got.tobytes() == want.tobytes(), k
        many = P.delta_e2000_maps(r, [x, r], white=white)
        assert many[0].tobytes() == want.tobytes() and not np.any(many[1]), k


def test_a_comparison_and_an_srgb_image_do_not_import_colour_science(tmp_path):
    """compare's metrics (ΔE2000 among them) and an engine's sRGB PNG read in a fresh process leave
    colour-science unimported: its 0.4.7 import (0.8-1.4 s, its plotting package with pyplot and
    pandas) was a third of a small ``fogref compare``.  The values are its own (the tests above)."""
    code = f"""
import sys
import numpy as np
from PIL import Image
from fogref.compare.foreign import read_image
from fogref.compare.report import compare_metrics
from fogref.compare.synthetic import synthetic_truth
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams
fog = UE4ExponentialHeightFog(UE4FogParams())
m = compare_metrics(synthetic_truth(fog, shape=(9, 16)), fog)
assert 0.0 <= m["metrics"]["final"]["all"]["delta_e2000_mean"] < 1e3
Image.fromarray(np.full((2, 3, 3), 188, np.uint8)).save({str(tmp_path / "e.png")!r})
assert round(float(read_image({str(tmp_path / "e.png")!r}, encoding="srgb")[0, 0, 0]), 3) == 0.503
print(sorted(k for k in ("colour", "pandas", "matplotlib.pyplot") if k in sys.modules))
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "[]"


def test_delta_e2000_default_white_is_the_reference_p99_luminance():
    r = _rand(seed=1, scale=3.0)
    x = r * 1.2
    w = P.exposure_white(r)
    y = luminance(r).ravel()
    assert w == pytest.approx(np.percentile(y[y > 0], 99))
    np.testing.assert_allclose(P.delta_e2000_map(r, x), P.delta_e2000_map(r, x, white=w))
    # exposure-normalised: scaling both images leaves ΔE unchanged
    np.testing.assert_allclose(
        P.delta_e2000_map(10 * r, 10 * x), P.delta_e2000_map(r, x), rtol=1e-9, atol=1e-9
    )


def test_exposure_white_of_black_image_is_one():
    assert P.exposure_white(np.zeros((4, 4, 3))) == 1.0
    assert P.exposure_white(-np.ones((4, 4, 3))) == 1.0


def test_flip_detects_a_difference_and_stays_in_range():
    r = _rand(seed=2)
    flip, params = P.flip_map(r, r * 1.5)
    assert 0 < flip.mean() <= 1 and np.all(np.isfinite(flip))
    assert params["ppd"] == pytest.approx(P.FLIP_PPD, rel=1e-3)


def test_flip_black_reference_does_not_abort():
    # flip_evaluator exits the process when the reference has no positive luminance
    z = np.zeros((8, 8, 3))
    flip, _ = P.flip_map(z, z)
    assert np.all(flip == 0)
    t = z.copy()
    t[2:5, 2:5] = 1.0
    flip, params = P.flip_map(z, t)
    assert flip.max() > 0 and np.all(np.isfinite(flip))
    assert params["startExposure"] == params["stopExposure"]


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf, -5.0, 0.0, 1e30])
def test_bad_model_pixels_are_excluded_and_counted_never_zeroed(bad):
    r = _rand(seed=3)
    x = r.copy()
    x[3, 4, 1] = bad
    e = E.error_maps(r, x)
    for name in ("signed", "absolute", "squared", "relative_squared", "delta_e2000", "flip"):
        assert np.all(np.isfinite(getattr(e, name))), (bad, name)
    s = e.summary()
    assert all(np.isfinite(v) for v in s.values() if not isinstance(v, bool)), (bad, s)
    finite = np.isfinite(bad)
    assert s["model_nonfinite_pixels"] == s["excluded_pixels"] == (0 if finite else 1)
    assert s["pixels"] == r.shape[0] * r.shape[1] - (0 if finite else 1)
    assert M.count_nonfinite(x) == (0 if finite else 1)
    if not finite:  # the old code turned NaN into 0 and inf into FLT_MAX and averaged them in
        clean = E.error_maps(r, np.where(np.isfinite(x), x, r)).summary(e.valid)
        assert s["rmse"] == clean["rmse"] == 0.0


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_nonfinite_reference_is_refused(bad):
    r = _rand(seed=3)
    r[5, 6, :] = bad
    with pytest.raises(ValueError, match="non-finite"):
        E.error_maps(r, _rand(seed=4))
    with pytest.raises(ValueError, match="non-finite"):
        M.rmse(r, _rand(seed=4))


def test_inf_in_model_is_an_error_for_scalar_metrics():
    r = np.ones((4, 4, 3))
    x = r.copy()
    x[0, 0, 0] = np.inf
    with pytest.raises(ValueError, match="non-finite"):
        M.rmse(r, x)
    mask = np.ones((4, 4), bool)
    mask[0, 0] = False
    assert M.rmse(r, x, mask=mask) == 0.0


def test_vectorised_over_leading_axes():
    r, x = _rand((5, 3), seed=4), _rand((5, 3), seed=5)
    assert M.squared_error_map(r, x).shape == (5,)
    assert P.delta_e2000_map(r, x).shape == (5,)
    r4, x4 = _rand((2, 3, 4, 3), seed=6), _rand((2, 3, 4, 3), seed=7)
    assert M.relative_squared_error_map(r4, x4).shape == (2, 3, 4)


def test_binned_errors_hand_computed():
    r = np.zeros((1, 4, 3))
    x = np.array([[[1.0] * 3, [2.0] * 3, [3.0] * 3, [4.0] * 3]])
    e = E.error_maps(r, x, white=1.0)
    d = np.array([[1.0, 2.0, 10.0, 15.0]])
    edges = np.array([1.0, 5.0, 20.0, 100.0])
    b = binned_errors(d, {"p": e}, edges)
    assert b["pixels"] == [2, 2]  # third bin empty, dropped
    np.testing.assert_allclose(b["parts"]["p"]["rmse"], [np.sqrt(2.5), np.sqrt(12.5)])
    np.testing.assert_allclose(b["center"], [np.sqrt(5.0), np.sqrt(100.0)])
    masked = binned_errors(d, {"p": e}, edges, mask=np.array([[True, False, False, False]]))
    assert masked["pixels"] == [1]


def test_bin_edges():
    e = log_distance_edges(np.array([0.0, 1.0, 1000.0, np.inf]), n_bins=3)
    np.testing.assert_allclose(e, [1.0, 10.0, 100.0, 1000.0])
    assert log_distance_edges(np.zeros(4)).size == 0
    assert binned_errors(np.zeros((1, 1)), {}, np.empty(0))["pixels"] == []
    a = angle_edges(5.0)
    assert a[0] == 0 and a[-1] == 180 and len(a) == 37


def test_tone_map_is_exposure_clip_srgb():
    assert srgb_oetf(np.array([0.0, 1.0, 2.0, -1.0, np.nan])).tolist() == pytest.approx([0, 1, 1, 0, 0])
    assert srgb_oetf(np.array([0.18]))[0] == pytest.approx(0.4613561, rel=1e-6)
    np.testing.assert_allclose(tone_map(np.full(3, 0.09), 2.0), srgb_oetf(np.full(3, 0.18)))


@pytest.mark.parametrize("with_cov", [False, True], ids=["sigma only", "covariance"])
def test_a_summary_is_the_noise_functions_on_the_whole_images_bit_for_bit(with_cov):
    """``ErrorMaps.summary`` selects a region's pixels once for its three noise summaries; every
    value must be the one of ``mse_noise`` and ``mean_noise`` given the whole images and the mask
    (exact equality: the selection keeps the pixels' order)."""
    rng = np.random.default_rng(4)
    r, x = _rand(seed=1), _rand(seed=2)
    sigma = 0.05 * _rand(seed=3)
    cov = None
    if with_cov:
        a = 0.05 * rng.random((12, 16, 3, 3))
        cov = a @ np.swapaxes(a, -1, -2)
        sigma = np.sqrt(np.einsum("...ii->...i", cov))
    e = E.error_maps(r, x, white=1.0, sigma=sigma, noise_cov=cov, spp=16)
    mask = rng.random((12, 16)) < 0.4
    s = e.summary(mask)
    sel = mask & e.valid
    rm = M.mse_noise(e.signed, e.sigma, sel, None, cov=e.noise_cov, spp=16)
    rel = M.mse_noise(e.signed, e.sigma, sel, e.relative_weight, cov=e.noise_cov, spp=16)
    me = M.mean_noise(e.signed, e.sigma, sel, cov=e.noise_cov)
    assert s["rmse"] == float(np.sqrt(rm["mse"])) and s["rmse_noise_floor"] == np.sqrt(rm["noise_floor"])
    assert s["rmse_below_noise"] == rm["below_noise"]
    assert (s["relmse"], s["relmse_stderr"], s["relmse_noise_floor"]) == (
        rel["mse"],
        rel["stderr"],
        rel["noise_floor"],
    )
    assert s["relmse_below_noise"] == rel["below_noise"]
    assert (s["mean_error"], s["mean_error_stderr"]) == (me["mean"], me["stderr"])
