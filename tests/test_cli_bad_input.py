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
