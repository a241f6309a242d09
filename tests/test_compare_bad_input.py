"""Every door of compare/check/the models gives a one-line error (exit 2 through the
CLI) or the right answer; each case through ``fogref.cli.main`` and through the Python API.

Tiny synthetic truths (8x6 px, :func:`fogref.compare.synthetic.synthetic_truth`), no renders.
"""

import json
import sys
import textwrap

import numpy as np
import pytest
from truth_factory import write_rgb, write_truth_exr

from fogref.cli import main
from fogref.compare.candidate import evaluate_model
from fogref.compare.check import assert_fog_matches, check
from fogref.compare.foreign import read_image
from fogref.compare.report import compare
from fogref.compare.synthetic import synthetic_truth
from fogref.errors import FogrefError, ParameterError
from fogref.mapping.build import build_model
from fogref.models.base import FogResult
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams

MODEL = UE4ExponentialHeightFog(UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2))
SHAPE = (6, 8)

USER_MODULE = """
import numpy as np
from fogref.models.base import FogResult


def _fog(positions, L, T=0.5):
    s = np.shape(positions)[:-1]
    return FogResult(inscatter=np.broadcast_to(L, (*s, 3)).copy(), transmittance=np.full((*s, 3), T))


class Boom:
    def evaluate(self, camera, positions, precision="float32"):
        raise RuntimeError("kaboom")


class Huge:
    def evaluate(self, camera, positions, precision="float32"):
        return _fog(positions, 1e300)


class NaNFog:
    def evaluate(self, camera, positions, precision="float32"):
        r = _fog(positions, 0.1)
        r.inscatter[1, 2, 0] = np.nan
        return r


class ReturnsNone:
    def evaluate(self, camera, positions, precision="float32"):
        return None


class ReturnsStrings:
    def evaluate(self, camera, positions, precision="float32"):
        return FogResult(inscatter="bright", transmittance="half")


class Counting:
    calls = 0

    def evaluate(self, camera, positions, precision="float32"):
        type(self).calls += 1
        return _fog(positions, 0.1)
"""


class NoFog:
    """T = 1, no inscatter: a fog-free scene."""

    def evaluate(self, camera, positions, precision="float32"):
        s = np.shape(positions)[:-1]
        return FogResult(inscatter=np.zeros((*s, 3)), transmittance=np.ones((*s, 3)))


@pytest.fixture
def user_module(tmp_path, monkeypatch):
    (tmp_path / "h9_user_fog.py").write_text(textwrap.dedent(USER_MODULE))
    (tmp_path / "h9_lazy_fog.py").write_text("def __getattr__(name):\n    raise ImportError('lazy boom')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    yield "h9_user_fog"
    for m in ("h9_user_fog", "h9_lazy_fog"):
        sys.modules.pop(m, None)


@pytest.fixture
def truth_exr(tmp_path):
    truth = synthetic_truth(MODEL, shape=SHAPE)
    return truth, write_truth_exr(truth, tmp_path / "truth.exr")


def _cli_error(capsys, args, *needles):
    """Run ``fogref`` with ``args``: exit 2 and one stderr line holding every needle, no traceback."""
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err and len(err.splitlines()) == 1, err
    for n in needles:
        assert n in err, (n, err)
    return err


def _compare(exr, out, *rest):
    return ["compare", str(exr), "--out", str(out), "--no-figures", *rest]


# ---------------------------------------------------------------- 1. models


def test_model_evaluate_raising_is_one_line(user_module, truth_exr, tmp_path, capsys):
    truth, exr = truth_exr
    _cli_error(
        capsys,
        _compare(exr, tmp_path / "r", "--model", f"{user_module}:Boom"),
        "model 'Boom'",
        "RuntimeError: kaboom",
        "h9_user_fog.py",
    )
    model = build_model(f"{user_module}:Boom")
    for call in (
        lambda: check(truth, model),
        lambda: evaluate_model(truth, model),
        lambda: compare(truth, model, tmp_path / "r2", figures=False),
    ):
        with pytest.raises(FogrefError, match="model 'Boom': evaluate.. raised RuntimeError: kaboom"):
            call()


@pytest.mark.parametrize(
    "cls, needle",
    [
        ("ReturnsNone", "returned NoneType without 'transmittance'"),
        ("ReturnsStrings", "not an array of numbers"),
    ],
)
def test_model_returning_none_or_strings_refused(user_module, truth_exr, tmp_path, capsys, cls, needle):
    truth, exr = truth_exr
    _cli_error(capsys, _compare(exr, tmp_path / "r", "--model", f"{user_module}:{cls}"), needle)
    with pytest.raises(FogrefError, match=needle):
        check(truth, build_model(f"{user_module}:{cls}"))


def test_module_getattr_raising_import_error(user_module, truth_exr, tmp_path, capsys):
    _, exr = truth_exr
    _cli_error(
        capsys,
        _compare(exr, tmp_path / "r", "--model", "h9_lazy_fog:Fog"),
        "h9_lazy_fog:Fog",
        "ImportError: lazy boom",
    )
    with pytest.raises(FogrefError, match="h9_lazy_fog:Fog.*ImportError: lazy boom"):
        build_model("h9_lazy_fog:Fog")


def test_nan_model_refused_with_count_and_first_pixel_in_check_and_report(
    user_module, truth_exr, tmp_path, capsys
):
    truth, exr = truth_exr
    _cli_error(
        capsys,
        _compare(exr, tmp_path / "r", "--model", f"{user_module}:NaNFog"),
        "1 pixel(s) are non-finite",
        "first at (x=2, y=1)",
    )
    model = build_model(f"{user_module}:NaNFog")
    for call in (lambda: check(truth, model), lambda: compare(truth, model, tmp_path / "r2", figures=False)):
        with pytest.raises(FogrefError, match=r"inscatter: 1 pixel\(s\) are non-finite .*\(x=2, y=1\)"):
            call()


# ---------------------------------------------------------------- 2. --param ranges


@pytest.mark.parametrize(
    "param, needle",
    [
        ("DirectionalInscatteringExponent=-5", "'DirectionalInscatteringExponent': -5 is outside (0, inf)"),
        ("SunLuminance=-1", "'SunLuminance': -1 is outside [0, inf)"),
        ("FogInscatteringColor=[-1,0,0]", "'FogInscatteringColor': (-1, 0, 0) is outside"),
        ("FogHeight=1e400", "'FogHeight': inf is not finite"),
    ],
)
def test_ue4_param_ranges(truth_exr, tmp_path, capsys, param, needle):
    _, exr = truth_exr
    _cli_error(capsys, _compare(exr, tmp_path / "r", "--model", "ue4", "--param", param), needle)
    key, _, value = param.partition("=")
    with pytest.raises(ParameterError, match="UE4FogParams"):
        build_model("ue4", {key: json.loads(value)})
    with pytest.raises(ParameterError):
        UE4FogParams(**{key: json.loads(value)})


@pytest.mark.parametrize(
    "model, param, needle",
    [
        ("hdrp", "meanFreePath=0", "'meanFreePath': 0 is outside (0, inf) m"),
        ("hdrp", "baseHeight=1e400", "'baseHeight': inf is not finite"),
        ("unity", "fogDensity=-0.1", "'fogDensity': -0.1 is outside [0, inf)"),
        ("unity", 'fogMode="exp3"', "did you mean"),
        ("filament", "maximumOpacity=2", "'maximumOpacity': 2 is outside [0, 1]"),
        ("box", "fog_color=[-1,0,0]", "'fog_color': (-1, 0, 0) is outside"),
        ("altitude", "_FogPower=true", "'_FogPower': True is not a number"),
        ("ue4", "SunLuminanse=1", "did you mean 'SunLuminance'"),
    ],
)
def test_other_models_param_ranges(truth_exr, tmp_path, capsys, model, param, needle):
    _, exr = truth_exr
    _cli_error(capsys, _compare(exr, tmp_path / "r", "--model", model, "--param", param), needle)
    key, _, value = param.partition("=")
    with pytest.raises(FogrefError, match="did you mean|parameter"):
        build_model(model, {key: json.loads(value)})


def test_empty_row_reads_no_pixels():
    res = check(synthetic_truth(MODEL, shape=SHAPE), MODEL, distance_bands=(1e6,))
    row = res.row("T", "d>1e+06m")
    assert row.verdict == "empty" and "no pixels" in row.describe() and "pass" not in row.describe()


# ---------------------------------------------------------------- 3. Radiance headers


def _hdr(path, header: bytes, res: bytes, payload: bytes = b"\x80\x80\x80\x81" * 48):
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n" + header + b"\n" + res + b"\n" + payload)
    return path


@pytest.mark.parametrize(
    "header, res, needle",
    [
        (b"EXPOSURE=abc\n", b"-Y 6 +X 8", "EXPOSURE='abc'"),
        (b"EXPOSURE=0\n", b"-Y 6 +X 8", "EXPOSURE='0'"),
        (b"", b"-Y six +X 8", "resolution line"),
        (b"", b"-Y -6 +X 8", "resolution line"),
        (b"", b"-Y 100000000 +X 100000000", "claims 100000000x100000000 pixels"),
    ],
)
def test_hdr_header_errors(truth_exr, tmp_path, capsys, header, res, needle):
    _, exr = truth_exr
    img = _hdr(tmp_path / "engine.hdr", header, res)
    err = _cli_error(capsys, _compare(exr, tmp_path / "r", "--image", str(img)), needle)
    assert str(img) in err
    with pytest.raises(FogrefError, match="engine.hdr: .*" + needle.split("=")[0]):
        read_image(img)


def test_hdr_valid_still_reads(tmp_path):
    img = read_image(_hdr(tmp_path / "ok.hdr", b"EXPOSURE=2\n", b"-Y 6 +X 8"))
    assert img.shape == (6, 8, 3) and np.isfinite(img).all()


# ---------------------------------------------------- 4. overflow, vacuous regions, zero reference


def test_overflowing_model_refused_with_reason_not_null(user_module, truth_exr, tmp_path, capsys):
    truth, exr = truth_exr
    _cli_error(
        capsys, _compare(exr, tmp_path / "r", "--model", f"{user_module}:Huge"), "beyond ±1e+30", "overflow"
    )
    model = build_model(f"{user_module}:Huge")
    for call in (lambda: check(truth, model), lambda: compare(truth, model, tmp_path / "r2", figures=False)):
        with pytest.raises(FogrefError, match="too large to measure"):
            call()


def test_vacuous_region_is_no_pixels_never_pass(tmp_path, capsys):
    # a truth that sees only sky: no surface pixels at all
    sky = synthetic_truth(MODEL, shape=SHAPE)
    sky.hit_fraction[:] = 0.0
    sky.surface_coverage[:] = 1.0
    exr = write_truth_exr(sky, tmp_path / "sky.exr")
    from fogref.gbuffer import load_truth

    truth = load_truth(exr)
    assert not truth.hit.any()
    res = check(truth, MODEL, {"final/surface": 0.05})
    row = res.row("final", "surface")
    assert row.pixels == 0 and row.verdict == "fail" and "no pixels" in row.note
    out = tmp_path / "r"
    rc = main(
        _compare(
            exr, out, "--model", "ue4", "--param", "FogDensity=0.02", "--tolerance", "final/surface=0.05"
        )
    )
    assert rc == 1
    page = (out / "index.md").read_text()
    assert "no pixels" in page
    assert "| final | surface | rel_rmse | — | — | 0.05 | fail (no pixels) | 0 |" in page


def test_fog_free_truth_against_inscatter_100_fails(tmp_path, capsys):
    truth = synthetic_truth(NoFog(), shape=SHAPE)
    exr = write_truth_exr(truth, tmp_path / "clear.exr")
    ins = write_rgb(tmp_path / "ins.exr", np.full((*SHAPE, 3), 100.0))
    assert main(_compare(exr, tmp_path / "r", "--inscatter", str(ins))) == 1
    final = write_rgb(tmp_path / "final.exr", truth.final + 100.0)
    assert main(_compare(exr, tmp_path / "r2", "--image", str(final))) == 1
    with pytest.raises(AssertionError, match="fog does not match"):
        assert_fog_matches(truth, {"inscatter": np.full((*SHAPE, 3), 100.0)}, errors_dir=tmp_path / "e")


# ---------------------------------------------------------------- 5. API arguments


@pytest.mark.parametrize("bad", [[0.05], "inscatter=0.05", 0.05])
def test_tolerances_not_a_dict(bad):
    truth = synthetic_truth(MODEL, shape=SHAPE)
    with pytest.raises(ParameterError, match="'tolerances': expected a dict.*'part/region'"):
        check(truth, MODEL, bad)
    with pytest.raises(ParameterError, match="'tolerances'"):
        assert_fog_matches(truth, MODEL, bad)


def test_tolerance_values_and_check_options_through_the_validator():
    truth = synthetic_truth(MODEL, shape=SHAPE)
    with pytest.raises(ParameterError, match=r"tolerances\['T'\]\['rel_rmse'\]': True is not a number"):
        check(truth, MODEL, {"T": True})
    with pytest.raises(ParameterError, match="'sky_distance': -1 is outside \\(0, inf\\) m"):
        check(truth, MODEL, sky_distance=-1)
    assert {r.part for r in check(truth, MODEL, parts="inscatter").rows} == {"inscatter"}


def test_truth_as_a_path_string_is_loaded(truth_exr, tmp_path):
    truth, exr = truth_exr
    assert check(str(exr), MODEL).verdict == check(truth, MODEL).verdict
    assert evaluate_model(str(exr), MODEL)["T"].shape == (*SHAPE, 3)
    assert assert_fog_matches(str(exr), MODEL).verdict == "pass"
    with pytest.raises(ParameterError, match="'truth'.*no such file"):
        check(str(tmp_path / "missing.exr"), MODEL)
    with pytest.raises(ParameterError, match="'truth': expected a Truth or the path"):
        check(42, MODEL)


@pytest.mark.parametrize("shape", [(0, 0), (6, 0), (6.5, 8), (6,), "6x8"])
def test_synthetic_truth_shape_refused(shape):
    with pytest.raises(ParameterError, match="'shape'"):
        synthetic_truth(MODEL, shape=shape)


# ---------------------------------------------------------------- 6. no output over an input


@pytest.mark.parametrize("name", ["errors.exr", "metrics.json", "index.md", "check.json"])
def test_truth_in_out_dir_named_as_an_output_refused(truth_exr, tmp_path, capsys, name):
    _, exr = truth_exr
    out = tmp_path / "r"
    out.mkdir()
    victim = out / name
    victim.write_bytes(exr.read_bytes())
    before = victim.read_bytes()
    _cli_error(capsys, _compare(victim, out, "--model", "ue4"), "--out", "over the input EXR")
    with pytest.raises(ParameterError, match="over the input truth"):
        compare(str(victim), MODEL, out, figures=False)
    assert victim.read_bytes() == before


def test_engine_image_in_out_dir_refused_through_a_symlink(truth_exr, tmp_path, capsys):
    truth, exr = truth_exr
    out = tmp_path / "r"
    (out / "heatmaps").mkdir(parents=True)
    img = write_rgb(out / "errors.exr", truth.final)
    before = img.read_bytes()
    link = tmp_path / "link"
    link.symlink_to(out)
    _cli_error(capsys, _compare(exr, link, "--image", str(img)), "over the input --image")
    png = out / "heatmaps" / "final.png"
    png.write_bytes(b"not really a png")
    _cli_error(capsys, _compare(exr, out, "--image", str(png)), "over the input --image")
    assert img.read_bytes() == before and png.read_bytes() == b"not really a png"


def test_assert_fog_matches_errors_dir_over_the_truth_refused(truth_exr, tmp_path):
    truth, exr = truth_exr
    victim = tmp_path / "errors.exr"
    victim.write_bytes(exr.read_bytes())
    before = victim.read_bytes()
    bad = {"inscatter": truth.inscatter * 2, "T": truth.transmittance}
    with pytest.raises(ParameterError, match="errors_dir.*over the input truth"):
        assert_fog_matches(str(victim), bad, errors_dir=tmp_path)
    assert victim.read_bytes() == before


@pytest.mark.parametrize("option", ["--json", "--junit"])
def test_gate_files_over_an_input_or_a_report_file_refused(truth_exr, tmp_path, capsys, option):
    _, exr = truth_exr
    before = exr.read_bytes()
    _cli_error(capsys, _compare(exr, tmp_path / "r", "--model", "ue4", option, str(exr)), option, "input EXR")
    _cli_error(
        capsys,
        _compare(exr, tmp_path / "r", "--model", "ue4", option, str(tmp_path / "r" / "metrics.json")),
        option,
        "over the output",
    )
    assert exr.read_bytes() == before and not (tmp_path / "r").exists()


# ---------------------------------------------------------------- 7. the model is evaluated once


def test_compare_evaluates_the_model_once(user_module, truth_exr, tmp_path):
    import h9_user_fog

    truth, exr = truth_exr
    h9_user_fog.Counting.calls = 0
    main(_compare(exr, tmp_path / "r", "--model", f"{user_module}:Counting"))
    assert h9_user_fog.Counting.calls == 1
    model = h9_user_fog.Counting()
    h9_user_fog.Counting.calls = 0
    result = check(truth, model)
    compare(truth, model, tmp_path / "r2", figures=False, check=result)
    assert h9_user_fog.Counting.calls == 1
    # a different precision is a different evaluation
    compare(truth, model, tmp_path / "r3", precision="float64", figures=False, check=result)
    assert h9_user_fog.Counting.calls == 2
