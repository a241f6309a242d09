"""compare on schema-2 truths: undefined surface, Monte Carlo noise, signed maps, provenance, CLI errors.

Synthetic truths only (tests/truth_factory.py), no renders.
"""

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from truth_factory import as_truth, truth_attrs, truth_channels

from fogref.compare import compare
from fogref.compare import metrics as M
from fogref.compare.error_maps import error_maps
from fogref.compare.plots import plot_error_heatmaps
from fogref.errors import FogrefError
from fogref.exrio import write_exr

W, H = 24, 16
CAMERA = np.array([0.0, 30.0, 0.0])
SIGMA = 0.004  # 1/m, grey


@dataclass
class Result:
    inscatter: np.ndarray
    transmittance: np.ndarray


@dataclass
class GreyParams:
    sigma: float = SIGMA
    ambient: float = 0.5
    max_opacity: float = 1.0
    gain: float = 1.0


class GreyFog:
    """Homogeneous grey fog; ``max_opacity`` < 1 keeps T >= 1 - max_opacity (as Unreal's FogMaxOpacity)."""

    name = "grey_test"
    Params = GreyParams

    def __init__(self, params=None, **kw):
        self.params = params or GreyParams(**kw)

    def evaluate(self, camera, world_pos, precision="float64"):
        p = self.params
        d = np.linalg.norm(np.asarray(world_pos, float) - camera, axis=-1)[..., None]
        t = np.maximum(np.exp(-p.sigma * d), 1.0 - p.max_opacity) * np.ones(3)
        return Result(inscatter=p.gain * p.ambient * (1.0 - t), transmittance=t)


def horizon_truth(rel_stderr=0.01, undefined_surface=0.0, horizon_rows=4):
    """A lake: ground below the horizon, the last ``horizon_rows`` rows above it see the far
    ground at 1e5 m where T underflows to 0, and the sky (T = 0) on top."""
    ys, xs = np.mgrid[0:H, 0:W]
    u = (xs + 0.5) / W * 2 - 1
    v = 1 - (ys + 0.5) / H * 2
    view = np.stack([0.5 * u, 0.4 * v - 0.15, -np.ones_like(u)], -1)
    view /= np.linalg.norm(view, axis=-1, keepdims=True)
    ground = view[..., 1] < 0
    dist = np.where(ground, -CAMERA[1] / np.where(ground, view[..., 1], -1.0), 0.0)
    far = np.zeros_like(ground)
    first_ground = np.argmax(ground, axis=0)
    for x in range(W):  # the rows just above the ground see a far shore
        far[max(first_ground[x] - horizon_rows, 0) : first_ground[x], x] = True
    dist = np.where(far, 1.0e5, dist)
    hit = ground | far
    pos = np.where(hit[..., None], CAMERA + view * dist[..., None], 0.0)
    T = np.where(hit, np.exp(-SIGMA * dist), 0.0)[..., None] * np.ones(3)
    T = T.astype(np.float32).astype(np.float64)  # exp(-400) underflows to 0, as in the float32 file
    surface = np.where(hit[..., None], np.array([0.3, 0.35, 0.2]), np.array([0.2, 0.3, 0.5]))
    inscatter = 0.5 * (1.0 - T)
    coverage = (T.max(-1) > 0).astype(float)
    ch = truth_channels(
        T=T,
        surface=surface,
        inscatter=inscatter,
        distance=dist,
        position=pos,
        view=view,
        hit=hit,
        coverage=coverage,
        rel_stderr=rel_stderr,
    )
    if undefined_surface:
        for c in ("surface.R", "surface.G", "surface.B"):
            ch[c] = np.where(coverage > 0, ch[c], undefined_surface)
    params = {
        "camera": {"origin": CAMERA.tolist()},
        "medium": {"sigma_t": SIGMA},
        "sun": None,
        "sky": {"radiance": 0.5},
    }
    attrs = truth_attrs(
        params,
        spp=32,
        seed=7,
        scene="scenes/lake.xml",
        overrides={"res": W, "resy": H},
        pixel_filter="centre",
        scene_sha256="ab" * 32,
    )
    return ch, attrs


def _undefined(ch):
    return int(np.count_nonzero(ch["surface_coverage"] == 0))


def test_opaque_horizon_gives_finite_composite_and_counts_excluded_pixels(tmp_path):
    ch, attrs = horizon_truth()
    truth = as_truth(ch, attrs)
    assert np.any(truth.transmittance[truth.hit] == 0), "the far shore's T must underflow to 0"
    excluded = _undefined(ch)
    assert excluded >= 4 * W  # far shore and sky
    rep = compare(truth, GreyFog(max_opacity=0.9), tmp_path / "r", precision="float64", figures=False)
    for part in ("final", "attenuated_surface"):
        s = rep["metrics"][part]["all"]
        assert s["excluded_pixels"] == excluded and s["pixels"] == W * H - excluded, part
        assert math.isfinite(s["rmse"]) and s["rmse"] < 1.0, part  # the old surface = Tsurface/T gave 3.8e19
    for part in ("transmittance", "inscatter"):
        assert (
            rep["metrics"][part]["all"]["pixels"] == W * H
            and rep["metrics"][part]["all"]["excluded_pixels"] == 0
        )
    assert rep["diagnostics"]["surface_undefined_pixels"] == excluded
    assert any("surface radiance is undefined" in w for w in rep["warnings"])
    page = (tmp_path / "r" / "index.md").read_text()
    assert f"(surface undefined): {excluded}" in page


def test_undefined_surface_values_are_never_used(tmp_path):
    """Whatever the file holds where surface is undefined (0, or a huge leftover), the metrics agree."""
    reps = []
    for k, junk in enumerate((0.0, 1.0e20)):
        ch, attrs = horizon_truth(undefined_surface=junk)
        reps.append(
            compare(
                as_truth(ch, attrs),
                GreyFog(max_opacity=0.9),
                tmp_path / str(k),
                precision="float64",
                figures=False,
            )
        )
    for part in ("final", "attenuated_surface"):
        a, b = reps[0]["metrics"][part]["all"], reps[1]["metrics"][part]["all"]
        assert a["rmse"] == b["rmse"] and a["mean_error"] == b["mean_error"], part


def test_exact_model_is_below_the_noise_and_a_wrong_one_is_not(tmp_path):
    ch, attrs = horizon_truth(rel_stderr=0.02)
    truth = as_truth(ch, attrs)
    exact = compare(truth, GreyFog(), tmp_path / "exact", precision="float64", figures=False)
    wrong = compare(truth, GreyFog(gain=1.3), tmp_path / "wrong", precision="float64", figures=False)
    for part in ("final", "inscatter", "transmittance", "attenuated_surface"):
        s = exact["metrics"][part]["all"]
        assert s["rmse_below_noise"] and s["mean_error_below_noise"], (part, s)
    s = wrong["metrics"]["inscatter"]["all"]
    assert not s["rmse_below_noise"] and not s["mean_error_below_noise"]
    assert s["mean_error"] > 0 and s["rmse_debiased"] > 0
    # the noise floor is the RMS of the per-pixel standard error (plus float32 storage)
    se = truth.stderr["inscatter"]
    assert s["rmse_noise_floor"] == pytest.approx(np.sqrt(np.mean(se**2)), rel=1e-3)
    for key in (
        "rmse_stderr",
        "relmse_stderr",
        "relmse_noise_floor",
        "mean_error_stderr",
        "mean_abs_error_noise_floor",
        "delta_e2000_mean_noise_floor",
        "flip_mean_noise_floor",
    ):
        assert key in s and s[key] >= 0, key
    page = (tmp_path / "wrong" / "index.md").read_text()
    assert "RMSE noise floor" in page and "above the noise (too bright)" in page
    assert "below the noise" in (tmp_path / "exact" / "index.md").read_text()


def test_mse_noise_matches_a_monte_carlo_experiment():
    """The noise floor and stderr of mse_noise agree with 400 noisy truths of one fixed model."""
    rng = np.random.default_rng(1)
    bias = rng.normal(0, 0.02, (20, 20, 3))
    sigma = rng.uniform(0.01, 0.05, (20, 20, 3))
    mses = []
    for _ in range(400):
        d = bias + sigma * rng.standard_normal(bias.shape)
        mses.append(M.mse_noise(d, sigma))
    est = np.array([m["mse"] for m in mses])
    assert np.mean(est) == pytest.approx(np.mean(bias**2) + np.mean(sigma**2), rel=0.01)
    assert mses[0]["noise_floor"] == pytest.approx(np.mean(sigma**2))
    # channels are independent here, so the correlated-channel bound overestimates; it must not underestimate
    sd = np.std(est)
    assert sd <= np.mean([m["stderr"] for m in mses]) <= 2.5 * sd


def test_metrics_json_records_the_truth(tmp_path):
    ch, attrs = horizon_truth()
    path = tmp_path / "lake.exr"
    write_exr(path, ch, attrs)
    rep = compare(path, GreyFog(), tmp_path / "r", figures=False)
    t = json.loads((tmp_path / "r" / "metrics.json").read_text())["truth"]
    assert t == rep["truth"]
    assert (t["spp"], t["seed"], t["scene"], t["overrides"], t["pixel_filter"]) == (
        32,
        7,
        "scenes/lake.xml",
        {"res": W, "resy": H},
        "centre",
    )
    assert t["pixel_exact"] and t["scene_sha256"] == "ab" * 32
    assert "--set res=24" in (tmp_path / "r" / "index.md").read_text()


def test_signed_error_map_is_diverging(tmp_path):
    """Too bright on the left half, too dark on the right: the signed panel shows red and blue."""
    import matplotlib.image as mpimg

    r = np.full((H, W, 3), 0.5)
    x = r.copy()
    x[:, : W // 2] += 0.2
    x[:, W // 2 :] -= 0.2
    e = error_maps(r, x, white=1.0)
    assert e.signed.mean(-1)[0, 0] > 0 > e.signed.mean(-1)[0, -1]
    png = plot_error_heatmaps(e, "final", "radiance", tmp_path / "h.png")
    img = mpimg.imread(png)[..., :3]
    left = img[:, : img.shape[1] // 5]  # the first of five panels: the signed error
    red = (left[..., 0] > left[..., 1] + 0.3) & (left[..., 0] > left[..., 2] + 0.3)
    blue = (left[..., 2] > left[..., 0] + 0.3) & (left[..., 2] > left[..., 1] + 0.1)
    assert red.sum() > 50 and blue.sum() > 50


def test_old_or_foreign_exr_is_refused(tmp_path):
    ch, attrs = horizon_truth()
    old = dict(attrs)
    old.pop("fogref.schema")
    write_exr(tmp_path / "old.exr", ch, old)
    with pytest.raises(FogrefError, match="schema"):
        compare(tmp_path / "old.exr", GreyFog(), tmp_path / "r")
    write_exr(tmp_path / "foreign.exr", {"R": np.zeros((2, 2)), "G": np.zeros((2, 2)), "B": np.zeros((2, 2))})
    with pytest.raises(FogrefError, match="not a fogref ground truth"):
        compare(tmp_path / "foreign.exr", GreyFog(), tmp_path / "r")


def test_no_truth_is_sanitised_in_compare_or_study():
    root = Path(__file__).resolve().parents[1] / "fogref"
    for folder in ("compare", "study"):
        for py in (root / folder).glob("*.py"):
            text = py.read_text()
            assert "nan_to_num" not in text and "sanitize(" not in text, py


@pytest.fixture
def grey_registered():
    from fogref.models.base import BUILTIN_MODELS

    BUILTIN_MODELS[GreyFog.name] = GreyFog
    yield
    BUILTIN_MODELS.pop(GreyFog.name, None)


@pytest.mark.parametrize("value", ["0", "-5", "nan", "inf"])
def test_cli_sky_distance_out_of_range(tmp_path, capsys, value, grey_registered):
    from fogref.cli import main

    ch, attrs = horizon_truth()
    write_exr(tmp_path / "t.exr", ch, attrs)
    rc = main(
        [
            "compare",
            str(tmp_path / "t.exr"),
            "--model",
            "grey_test",
            f"--sky-distance={value}",
            "--out",
            str(tmp_path / "r"),
            "--no-figures",
        ]
    )
    err = capsys.readouterr().err
    assert rc == 2 and "--sky-distance" in err and "(0, inf) m" in err
    assert "Traceback" not in err and not (tmp_path / "r").exists()


def test_cli_prints_noise_and_warnings(tmp_path, capsys, grey_registered):
    from fogref.cli import main

    ch, attrs = horizon_truth()
    write_exr(tmp_path / "t.exr", ch, attrs)
    assert (
        main(
            [
                "compare",
                str(tmp_path / "t.exr"),
                "--model",
                "grey_test",
                "--out",
                str(tmp_path / "r"),
                "--no-figures",
                "--precision",
                "float64",
            ]
        )
        == 1
    )  # the grey model fails: exit 1
    out = capsys.readouterr()
    assert "noise floor" in out.out and "±" in out.out
    assert "warning" in out.err and "undefined" in out.err
