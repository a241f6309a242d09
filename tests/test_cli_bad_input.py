"""Every door of the newer command line (diff, batch compare, --json/--junit, the option parser)
gives one clear error line (exit 2), writes nothing over an input or a device, and loses no image
of a batch.  Tiny synthetic truths (8x6 px, :func:`fogref.compare.synthetic.synthetic_truth`), no
renders.
"""

from __future__ import annotations

import csv
import json
import os
import stat
import threading

import numpy as np
import pytest
from truth_factory import write_rgb, write_truth_exr

from fogref.cli import main
from fogref.compare.synthetic import synthetic_truth
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams

MODEL = UE4ExponentialHeightFog(UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2))
SHAPE = (6, 8)


@pytest.fixture
def truth_exr(tmp_path):
    return write_truth_exr(synthetic_truth(MODEL, shape=SHAPE), tmp_path / "truth.exr")


def _cli_error(capsys, args, *needles):
    """Run ``fogref`` with ``args``: exit 2 and one stderr line holding every needle, no traceback."""
    assert main([str(a) for a in args]) == 2
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err and len(err.splitlines()) == 1, err
    for n in needles:
        assert n in err, (n, err)
    return err


# ---------------------------------------------------------------- outputs over inputs, devices


@pytest.mark.parametrize("which", ["a", "b"])
def test_diff_json_over_an_input_refused(truth_exr, tmp_path, capsys, which):
    other = tmp_path / "other.exr"
    other.write_bytes(truth_exr.read_bytes())
    victim = truth_exr if which == "a" else other
    before = victim.read_bytes()
    _cli_error(capsys, ["diff", truth_exr, other, "--json", victim], "--json", "which is an input")
    assert victim.read_bytes() == before


def test_json_naming_a_folder_refused_before_the_work(truth_exr, tmp_path, capsys):
    folder = tmp_path / "somewhere"
    folder.mkdir()
    for args in (
        ["diff", truth_exr, truth_exr, "--json", folder],
        ["compare", truth_exr, "--model", "ue4", "--out", tmp_path / "r", "--junit", folder],
    ):
        err = _cli_error(capsys, args, str(folder), "is a folder")
        assert ".tmp" not in err
    assert not (tmp_path / "r").exists()  # refused before the check ran
    (tmp_path / "r2" / "report.html").mkdir(parents=True)
    _cli_error(capsys, ["diff", truth_exr, truth_exr, "--out", tmp_path / "r2"], "report.html", "is a folder")
    _cli_error(
        capsys,
        ["compare", truth_exr, "--model", "ue4", "--out", tmp_path / "r2", "--no-figures"],
        "report.html",
        "is a folder",
    )
    assert not (tmp_path / "r2" / "metrics.json").exists()


def test_json_and_junit_into_a_fifo_written_in_place(truth_exr, tmp_path, capsys):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    got: list[bytes] = []

    def read():
        with open(fifo, "rb") as f:
            got.append(f.read())

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    assert main(["diff", str(truth_exr), str(truth_exr), "--json", str(fifo)]) == 0
    reader.join(timeout=60)  # generous: only a hang (no writer) reaches it
    assert stat.S_ISFIFO(os.stat(fifo).st_mode), "the FIFO was replaced by a regular file"
    assert got and json.loads(got[0])["verdict"] == "equal within noise"


def test_json_to_stdout_with_a_dash(truth_exr, tmp_path, capsys):
    assert main(["diff", str(truth_exr), str(truth_exr), "--json", "-"]) == 0
    out = capsys.readouterr().out
    assert '"verdict": "equal within noise"' in out and not (tmp_path / "-").exists()


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
@pytest.mark.parametrize("option", ["--json", "--junit"])
def test_write_error_on_a_device_is_one_line_and_keeps_the_device(truth_exr, tmp_path, capsys, option):
    args = [
        "compare",
        truth_exr,
        "--model",
        "ue4",
        "--out",
        tmp_path / "r",
        "--no-figures",
        option,
        "/dev/full",
    ]
    assert main([str(a) for a in args]) == 2
    err = capsys.readouterr().err.strip()
    assert err.splitlines()[-1] == "fogref: error: /dev/full: could not write: No space left on device", err
    assert "Traceback" not in err and stat.S_ISCHR(os.stat("/dev/full").st_mode)
    _cli_error(capsys, ["diff", truth_exr, truth_exr, "--json", "/dev/full"], "No space left on device")
    assert stat.S_ISCHR(os.stat("/dev/full").st_mode)


# ---------------------------------------------------------------- batch compare


def test_batch_with_a_corrupt_and_a_wrong_size_image_reports_them_and_checks_the_rest(
    truth_exr, tmp_path, capsys
):
    from fogref.gbuffer import load_truth

    truth = load_truth(truth_exr)
    eng = tmp_path / "engine"
    eng.mkdir()
    write_rgb(eng / "a.exr", truth.final)
    (eng / "b.exr").write_bytes(b"not an EXR at all")
    write_rgb(eng / "c.exr", np.ones((3, 4, 3)))
    write_rgb(eng / "d.exr", truth.final * 1.5)
    out = tmp_path / "batch"
    rc = main(["compare", str(truth_exr), "--image", str(eng / "*.exr"), "--out", str(out), "--no-figures"])
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" not in err
    rows = list(csv.DictReader(open(out / "batch.csv")))
    assert [r["image"].rsplit("/", 1)[1] for r in rows] == ["a.exr", "b.exr", "c.exr", "d.exr"]
    assert [r["verdict"] for r in rows] == ["pass", "error", "error", "fail"]
    assert "b.exr" in rows[1]["error"] and "8x6" in rows[2]["error"].replace(" ", "")
    assert json.loads((out / "batch.json").read_text())["exit_code"] == 2
    assert "b.exr" in (out / "report.html").read_text()


def test_batch_pattern_skips_the_previous_runs_report_folders(truth_exr, tmp_path, capsys):
    from fogref.gbuffer import load_truth

    truth = load_truth(truth_exr)
    d = tmp_path / "d"
    d.mkdir()
    for name, scale in (("a", 1.0), ("b", 1.5)):
        write_rgb(d / f"{name}.exr", truth.final * scale)
    args = ["compare", str(truth_exr), "--image", str(d / "*"), "--out", str(d), "--no-figures"]
    assert main(args) == 1
    assert (d / "a").is_dir()  # the report folders of the first run now match the pattern
    capsys.readouterr()
    assert main(args) == 1
    assert "no such" not in capsys.readouterr().err
    assert len(list(csv.DictReader(open(d / "batch.csv")))) == 2


# ---------------------------------------------------------------- the option parser


def test_option_typo_has_a_did_you_mean(truth_exr, capsys):
    _cli_error(
        capsys, ["compare", truth_exr, "--model", "ue4", "--from-scne"], "did you mean '--from-scene'?"
    )


# ---------------------------------------------------------------- render on a cluster: no hang


SCENE = __import__("pathlib").Path(__file__).resolve().parents[1] / "scenes" / "valley.xml"


@pytest.fixture
def workerless_scheduler():
    """A running Dask scheduler with no worker (in this process)."""
    distributed = pytest.importorskip("dask.distributed")
    import logging

    with distributed.LocalCluster(
        n_workers=0, processes=False, dashboard_address=None, silence_logs=logging.CRITICAL
    ) as c:
        yield c.scheduler_address


def test_a_scheduler_without_workers_says_it_waits_then_times_out(workerless_scheduler, tmp_path, capsys):
    import time

    from fogref import cluster
    from fogref.errors import ParameterError

    t0 = time.monotonic()
    with pytest.raises(
        ParameterError, match=r"'--scheduler': no worker joined .* in 2 s \(--worker-timeout\)"
    ):
        cluster.connect(workerless_scheduler, None, tmp_path / "log", "fogref render", worker_timeout=2)
    assert time.monotonic() - t0 < 60  # generous: only a hang reaches it
    assert "waiting for a worker to join the scheduler" in capsys.readouterr().err


@pytest.mark.render
def test_render_on_a_scheduler_without_workers_is_one_error_line(workerless_scheduler, tmp_path, capsys):
    out = tmp_path / "x.exr"
    args = ["render", SCENE, "--out", out, "--quiet", "--set", "res=8", "--set", "resy=4", "--spp", "1"]
    assert main([str(a) for a in [*args, "--scheduler", workerless_scheduler, "--worker-timeout", "1"]]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 2 and "Traceback" not in lines[1], lines
    assert (
        "waiting for a worker to join the scheduler" in lines[0]
        and "(up to 1 s, --worker-timeout)" in lines[0]
    )
    assert lines[1].startswith("fogref: error:") and "no worker joined" in lines[1]
    assert not out.exists()
    _cli_error(capsys, [*args, "--worker-timeout", "1"], "--worker-timeout applies only with --scheduler")


def test_more_workers_than_cores_is_a_warning(monkeypatch, tmp_path, capsys):
    import dask.distributed

    from fogref import cluster

    class Started(Exception):
        pass

    def fake(**kw):
        raise Started(kw["n_workers"])

    monkeypatch.setattr(dask.distributed, "LocalCluster", fake)
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    with pytest.raises(Started):
        cluster.connect(None, 1000, tmp_path / "log", "fogref render")
    assert "warning: --workers 1000 on 2 cores" in capsys.readouterr().err


@pytest.mark.render
def test_sigterm_while_the_cluster_starts_stops_the_render_at_once(monkeypatch, tmp_path):
    """A LocalCluster starting many workers on a loaded machine takes minutes: a signal then ends it
    (KeyboardInterrupt, exit 130 through the CLI) instead of waiting for the start."""
    import signal
    import time

    from fogref import cluster
    from fogref.render.render import render

    def slow_start(*args, **kw):
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(120)  # a start that would take two minutes
        raise AssertionError("the signal did not end the start")

    monkeypatch.setattr(cluster, "connect", slow_start)
    t0 = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        render(SCENE, tmp_path / "x.exr", spp=1, overrides={"res": 8, "resy": 4}, progress=False, workers=2)
    assert time.monotonic() - t0 < 100


# ---------------------------------------------------------------- API doors


@pytest.mark.parametrize(
    "files, needle",
    [
        ({}, "results.csv: no such file"),
        ({"results.csv": "a,b\n1,2\n", "sweep.json": "[1, 2]"}, "sweep.json: holds a list, not the sweep's"),
        ({"results.csv": "a,b\n1,2\n", "sweep.json": "{oops"}, "sweep.json: not readable JSON"),
        ({"results.csv": ""}, "results.csv: not a readable table"),
    ],
)
def test_sweep_table_of_a_bad_folder_is_one_line(tmp_path, files, needle):
    from fogref.errors import FogrefError
    from fogref.html.notebook import sweep_table

    for name, text in files.items():
        (tmp_path / name).write_text(text)
    with pytest.raises(FogrefError) as e:
        sweep_table(tmp_path)
    assert needle in str(e.value) and "\n" not in str(e.value)


@pytest.mark.parametrize("res", [(16.7, 9), (16, 0), "16x9", (16,)])
def test_cached_truth_refuses_a_non_integer_resolution(tmp_path, res):
    from fogref.errors import ParameterError
    from fogref.render.cache import cached_truth

    with pytest.raises(ParameterError, match="cached_truth: parameter 'res'"):
        cached_truth(SCENE, res=res, cache_dir=tmp_path)
    assert not list(tmp_path.iterdir())


# ---------------------------------------------------------------- engine models, fit and translate


@pytest.mark.parametrize(
    "model, param, needle",
    [
        ("bevy", {"color": [-1, 0.5, 0.5, 1]}, "'color': (-1, 0.5, 0.5) is outside"),
        ("bevy", {"directional_light_color": [0.5, -2, 0.5, 1]}, "'directional_light_color'"),
        ("bevy", {"color": [1, 1, 1, 2]}, "'color alpha': 2 is outside [0, 1]"),
        ("threejs", {"color": [0.2, -0.1, 0.3]}, "'color': (0.2, -0.1, 0.3) is outside"),
        ("godot", {"fog_mode": "depth", "z_far": 0}, "'z_far': 0 is outside (0, inf)"),
        ("godot", {"fog_density": "nan"}, "'fog_density': nan is not finite"),
        ("bevy", {"density": "abc"}, "'density': 'abc' does not parse as a number"),
    ],
)
def test_engine_model_settings_out_of_range_refused(model, param, needle):
    from fogref.errors import ParameterError
    from fogref.mapping.build import build_model

    with pytest.raises(ParameterError) as e:
        build_model(model, param)
    assert needle in str(e.value), str(e.value)


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--from", "godot", "--param", "fog_density=nan"], "'fog_density': nan is not finite"),
        (
            ["--from", "godot", "--param", "fog_density=1e300"],
            "the fog is opaque",
        ),
        (
            ["--from", "bevy", "--param", 'falloff="Exponential"', "--param", "density=1e300"],
            "the fog is opaque",
        ),
        (["--from", "threejs", "--param", "density=1e300"], "the fog is opaque"),
    ],
)
def test_translate_of_settings_out_of_range_is_one_line(capsys, args, needle):
    err = _cli_error(capsys, ["translate", *args, "--to", "ue4", "--directions", "8"], needle)
    assert "cannot set [" not in err  # names the one parameter, not every parameter


# ---------------------------------------------------------------- fogref scene


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--sky", "constant", "--turbidity", "5"], "--turbidity applies only with --sky sunsky"),
        (["--turbidity", "5"], "--turbidity applies only with --sky sunsky"),
        (["--sky", "sunsky", "--sky-radiance", "0.5"], "--sky-radiance does not apply with --sky sunsky"),
        (["--sky", "sunsky", "--sun-irradiance", "5"], "--sun-irradiance does not apply with --sky sunsky"),
        (
            ["--ue-fog-density", "0.02", "--ue-pathtracer", "--ue-volumetric-fog-distance", "1e300"],
            "'--ue-volumetric-fog-distance': 1e+300 is outside [0.1, 1000000000] cm",
        ),
        (
            ["--ue-fog-density", "0.02", "--ue-pathtracer", "--ue-volumetric-fog-distance", "1e-30"],
            "'--ue-volumetric-fog-distance': 1e-30 is outside [0.1, 1000000000] cm",
        ),
    ],
)
def test_scene_options_that_do_not_apply_or_out_of_range_are_refused(tmp_path, capsys, args, needle):
    out = tmp_path / "s.xml"
    _cli_error(capsys, ["scene", "--out", out, *args], needle)
    assert not out.exists()


def test_sunsky_with_the_sun_below_the_horizon_is_a_note(tmp_path, capsys):
    out = tmp_path / "s.xml"
    assert main(["scene", "--out", str(out), "--sky", "sunsky", "--sun-elevation", "-10"]) == 0
    err = capsys.readouterr().err
    assert "note: the sun is 10.0 deg below the horizon" in err and "the truth is black" in err
    assert "the sun is 10.0 deg below the horizon" in out.read_text()  # the note is in the scene too


# ---------------------------------------------------------------- the HTML viewer in physical units


@pytest.mark.parametrize("scale", [5.4e5, 1e29, 1e-13])
def test_viewer_in_physical_units_reads_out_the_radiance_and_its_exposure(tmp_path, scale):
    """A sun of 1e6 and a sky of 1e5 give radiances near 5e5; 1e29 and 1e-13 are the extremes.  The page
    reads out every part to half precision (relative 2^-11) and sets its exposure from the unclipped
    truth.  Run in a subprocess: a native library (FLIP) used to exit() the process for 1e-13."""
    import re
    import subprocess
    import sys

    from fogref.display import exposure_for
    from fogref.gbuffer import load_truth
    from fogref.html.inline import decode_half

    s = repr(scale)
    fog = UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2, FogInscatteringColor=(scale,) * 3)
    light = {"surface_radiance": (scale,) * 3, "sky_radiance": (scale,) * 3}
    exr, out = tmp_path / "truth.exr", tmp_path / "r"
    write_truth_exr(synthetic_truth(UE4ExponentialHeightFog(fog), shape=SHAPE, **light), exr)
    args = ["compare", exr, "--model", "ue4", "--param", "FogDensity=0.02", "--param", "FogHeightFalloff=0.2"]
    args += ["--param", f"FogInscatteringColor=[{s},{s},{s}]", "--out", out, "--no-figures"]
    run = subprocess.run(
        [sys.executable, "-m", "fogref.cli", *map(str, args)], capture_output=True, text=True, timeout=600
    )
    assert run.returncode == 0, (run.returncode, run.stderr[-2000:])
    page = (out / "report.html").read_text()
    data = json.loads(
        re.search(r'<script type="application/json" id="fr-data">(.*?)</script>', page).group(1)
    )
    truth = load_truth(exr)
    layers = {L["part"]: L for L in data["layers"]}
    for part in ("final", "inscatter", "surface"):
        ref = getattr(truth, part)
        shown = decode_half(layers[part]["truth"])
        assert np.allclose(shown, ref, rtol=2.0**-10, atol=0), (part, shown.max(), ref.max())
        assert layers[part]["exposure"] == pytest.approx(exposure_for(ref), rel=1e-12)
    assert shown.max() == pytest.approx(truth.surface.max(), rel=2.0**-10)


# ---------------------------------------------------------------- fit uncertainties


@pytest.mark.slow  # a bootstrap of the Bevy fit: 10 s
def test_an_ill_posed_fit_says_so(capsys):
    assert main(["fit", "--model", "bevy", "--directions", "8"]) == 0
    out, err = capsys.readouterr()
    fit = json.loads(out)
    lobe = [f"directional_light_color[{i}]" for i in range(3)]
    assert set(lobe) <= set(fit["fit"]["ill_posed"])
    for k in lobe:  # the colour is not pinned to 1e-14 any more
        p = fit["parameters"][k]
        assert max(p["uncertainty"], p["spread"]) > abs(p["value"]), p
    assert "warning: bevy: directional_light_color[0]" in err and "not determined by the 8 directions" in err


@pytest.mark.slow
@pytest.mark.parametrize(
    "model", ["ue4", "unity", "hdrp", "filament", "altitude", "box", "godot", "bevy", "threejs"]
)
def test_fit_uncertainty_covers_refits_on_resampled_directions(model):
    """Every engine's fit at the fewest directions (8): the standard deviation of the fitted values over
    four refits on the same Fibonacci directions turned about the vertical (deterministic angles) is at
    most 3 x max(uncertainty, spread) of the fit, or the parameter is reported ill-posed.  Smallest
    error detected: an uncertainty 3x too small (measured: at most 2.1x, ue4 and filament)."""
    import math

    from fogref.mapping.fit import fit_model
    from fogref.mapping.physical import PhysicalScene
    from fogref.mapping.views import rotated_views, sample_views
    from fogref.media import ExpLayer, FogMedium

    fog = FogMedium(sigma_t=0.000960906, albedo=0.9, g=0.6, layers=(ExpLayer(1.0, 0.0138629, 0.0),))
    sun = (0.3999686, 0.1389891, 0.9059289)
    pf = PhysicalScene(fog, sun, (3.2, 2.9, 2.4), (0.2, 0.3, 0.5), (0.0, 2.0, 0.0))
    fit = fit_model(model, pf, views=8)
    refits = [
        fit_model(
            model, pf, views=rotated_views(sample_views(pf.camera, n_dirs=8), 2 * math.pi * (k + 0.37) / 4)
        )
        for k in range(4)
    ]
    for k, v in fit.values.items():
        std = float(np.std([v] + [r.values[k] for r in refits], ddof=1))
        bound = max(fit.uncertainty[k], fit.spread[k])
        assert std <= 3 * bound or k in fit.ill_posed, (k, v, std, fit.uncertainty[k], fit.spread[k])
