"""fogref's command line: options declared once (fogref.cli.spec), defaults equal to the Python
API's, help for users, and every bad option refused as one line ``fogref: error: ...`` (exit 2)."""

from __future__ import annotations

import dataclasses
import importlib
import importlib.util
import inspect
import subprocess
import sys

import pytest

from fogref.cli import COMMANDS, main, parse
from fogref.cli.spec import MISSING, meta

ROOT = __import__("pathlib").Path(__file__).resolve().parents[1]
MODULES = {name: importlib.import_module(path) for name, path in COMMANDS.items()}


def _api(ref: str):
    module, _, name = ref.partition(":")
    obj = importlib.import_module(module)
    for part in name.split("."):
        obj = getattr(obj, part)
    return obj


def _norm(v):
    return tuple(_norm(x) for x in v) if isinstance(v, (list, tuple)) else v


def _api_defaults(cmd: str) -> dict[str, dict[str, object]]:
    """API function -> {parameter: default} of the functions a command's options name."""
    refs = {meta(f)["api"] for f in dataclasses.fields(MODULES[cmd].Options) if meta(f)["api"]}
    return {
        ref: {
            p.name: p.default
            for p in inspect.signature(_api(ref)).parameters.values()
            if p.default is not inspect.Parameter.empty
        }
        for ref in refs
    }


#: (command, option) -> (its default, the API's): the defaults that differ on purpose.
#: ``--processes``: the command draws a report's figures on every core;
#: the Python API in the calling process, because worker processes import a script's main module
#: (a script without an ``if __name__ == "__main__":`` guard would run again in each).
DIFFERENT_DEFAULTS = {("compare", "processes"): (None, 1), ("study", "processes"): (None, 1)}


@pytest.mark.parametrize("cmd", list(COMMANDS))
def test_every_default_equals_the_python_apis(cmd):
    """Each option tied to an API parameter has that parameter's default (a negated switch,
    ``--no-png``, the opposite of ``png=True``), but for :data:`DIFFERENT_DEFAULTS`; an option
    named like a parameter of the same API function must be tied to it."""
    apis = _api_defaults(cmd)
    checked = 0
    for f in dataclasses.fields(MODULES[cmd].Options):
        m = meta(f)
        refs = [m["api"]] if m["api"] else [r for r, ps in apis.items() if f.name in ps]
        if (cmd, f.name) in DIFFERENT_DEFAULTS:
            cli_default, api_default = DIFFERENT_DEFAULTS[cmd, f.name]
            assert refs and f.default == cli_default, (cmd, f.name, f.default)
            assert all(apis[r][f.name] == api_default for r in refs), (cmd, f.name, refs)
            continue
        for ref in refs:
            pname = m["api_name"] or f.name
            assert pname in apis[ref], f"{cmd} {f.name}: {ref} has no parameter '{pname}' with a default"
            want = apis[ref][pname]
            if m["negates"]:
                assert f.default is False and want is True, (cmd, f.name, ref)
            else:
                assert f.default is not MISSING and _norm(f.default) == _norm(want), (
                    cmd,
                    f.name,
                    f.default,
                    want,
                )
            checked += 1
    assert checked or cmd == "info", f"{cmd}: no option is tied to a Python API parameter"


def test_tied_constants_are_the_apis():
    from fogref.cli import compare, render
    from fogref.compare import foreign
    from fogref.exrio import EXR_COMPRESSIONS
    from fogref.render import render as R
    from fogref.render.variant import DEFAULT_VARIANT

    assert render.PIXEL_FILTERS == R.PIXEL_FILTERS and compare.ENCODINGS == foreign.ENCODINGS
    assert DEFAULT_VARIANT in render.VARIANTS
    assert render.EXR_COMPRESSIONS == EXR_COMPRESSIONS


def test_the_top_help_lists_every_command_with_one_line(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--help"])
    assert e.value.code == 0
    text = capsys.readouterr().out
    for name, module in MODULES.items():
        assert name in text and module.HELP.split()[0] in text, name
    assert "exit codes" in text


@pytest.mark.parametrize("cmd", list(COMMANDS))
def test_each_command_has_help_with_defaults_and_exit_codes(cmd, capsys):
    with pytest.raises(SystemExit) as e:
        main([cmd, "--help"])
    assert e.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "exit codes:" in text and "usage or input error" in text
    for f in dataclasses.fields(MODULES[cmd].Options):
        if isinstance(f.default, (int, float)) and not isinstance(f.default, bool):
            assert "(default " in text, (cmd, f.name)


def test_render_builds_only_its_own_parser():
    code = (
        "import sys; from fogref.cli import parse; parse(['render', 's.xml', '-o', 'x.exr']); "
        "bad = [m for m in ('fogref.compare', 'fogref.study', 'fogref.scene.writer', "
        "'fogref.render.render', 'fogref.cli.compare', 'fogref.cli.scene', 'dask', 'pandas', 'matplotlib', "
        "'mitsuba') if m in sys.modules]; assert not bad, bad"
    )
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-2000:]


def test_one_entry_point():
    import fogref.compare
    import fogref.study

    assert importlib.util.find_spec("fogref.compare.__main__") is None
    assert not hasattr(fogref.compare, "main") and not hasattr(fogref.compare, "add_cli")
    assert not hasattr(fogref.study, "main") and not hasattr(fogref.study, "add_cli")


OUT = ["-o", "x.exr"]
VALLEY = "scenes/valley.xml"


@pytest.mark.parametrize(
    "argv, words",
    [
        # an option given twice, a NAME given twice
        (["render", VALLEY, *OUT, "--spp", "4", "--spp", "8"], ["--spp", "given twice"]),
        (["render", VALLEY, *OUT, "--set", "res=4", "--set", "res=8"], ["--set", "'res' is given twice"]),
        (["render", VALLEY, "-o", "a.exr", "--out", "b.exr"], ["--out", "given twice"]),
        (
            ["compare", "t.exr", "--model", "ue4", "--param", "FogDensity=1", "--param", "FogDensity=2"],
            ["--param", "'FogDensity' is given twice"],
        ),
        (["scene", "--out", "s.xml", "--ground", "--no-ground"], ["--ground", "given twice"]),
        (
            ["compare", "t.exr", "--image", "e.exr", "--tolerance", "T=0.1", "--tolerance", "T:rel_rmse=0.2"],
            ["--tolerance", "T:rel_rmse is given twice"],
        ),
        (["sweep", "s.toml", "--scheduler", "tcp://a b"], ["--scheduler", "[PROTOCOL://]HOST[:PORT]"]),
        # options that do not apply to the chosen mode
        (
            ["compare", "t.exr", "--image", "e.exr", "--from-scene"],
            ["--from-scene", "does not apply", "--image"],
        ),
        (["compare", "t.exr", "--image", "e.exr", "--param", "FogDensity=1"], ["--param", "does not apply"]),
        (
            ["compare", "t.exr", "--image", "e.exr", "--precision", "float64"],
            ["--precision", "does not apply"],
        ),
        (
            ["compare", "t.exr", "--inscatter", "e.exr", "--sky-distance", "10"],
            ["--sky-distance", "does not apply"],
        ),
        (
            ["compare", "t.exr", "--model", "ue4", "--exposure", "2"],
            ["--exposure", "does not apply", "--model"],
        ),
        (["compare", "t.exr", "--model", "ue4", "--encoding", "srgb"], ["--encoding", "does not apply"]),
        (["compare", "t.exr", "--model", "ue4", "--image", "e.exr"], ["--model", "not both"]),
        (
            ["sweep", "s.toml", "--scheduler", "tcp://h:8786", "--workers", "2"],
            ["--workers", "does not apply"],
        ),
        # values out of range, not finite, not numbers, not one of the options
        (["render", VALLEY, *OUT, "--checkpoint-seconds", "-1"], ["--checkpoint-seconds", "-1", "[0, "]),
        (["render", VALLEY, *OUT, "--checkpoint-seconds", "nan"], ["--checkpoint-seconds", "not finite"]),
        (["render", VALLEY, *OUT, "--spp", "0"], ["--spp", "[1, 1048576]"]),
        (["render", VALLEY, *OUT, "--spp", "1.5"], ["--spp", "not an integer"]),
        (["render", VALLEY, *OUT, "--seed", "-1"], ["--seed", "[0, 2147483647]"]),
        (["render", VALLEY, *OUT, "--variant", "scalar_rgb"], ["--variant", "llvm_ad_rgb, cuda_ad_rgb"]),
        (["render", VALLEY, *OUT, "--pixel-filter", "gauss"], ["--pixel-filter", "centre, box"]),
        (["render", VALLEY, *OUT, "--set", "res"], ["--set", "NAME=VALUE"]),
        (["sweep", "s.toml", "--workers", "0"], ["--workers", "[1, 4096]"]),
        (["sweep", "s.toml", "--workers", "-1"], ["--workers", "[1, 4096]"]),
        (["sweep", "s.toml", "--drjit-threads", "-1"], ["--drjit-threads", "[1, 4096]"]),
        (["compare", "t.exr", "--model", "ue4", "--sky-distance", "0"], ["--sky-distance", "(0, inf) m"]),
        (
            ["compare", "t.exr", "--model", "ue4", "--precision", "float16"],
            ["--precision", "float32, float64"],
        ),
        (["compare", "t.exr", "--image", "e.png", "--exposure", "0"], ["--exposure", "(0, inf)"]),
        (["compare", "t.exr", "--image", "e.png", "--confidence", "1"], ["--confidence", "(0, 1)"]),
        (["fit", "--g", "1"], ["--g", "(-1, 1)"]),
        (["fit", "--sun-dir", "0", "0", "0"], ["--sun-dir", "not a direction"]),
        (["fit", "--sky", "1", "nan", "1"], ["--sky", "finite"]),
        (["study", "t.exr", "--max-opacity", "2"], ["--max-opacity", "[0, 1]"]),
        (["scene", "--out", "s.xml", "--fov", "abc"], ["--fov", "does not parse"]),
        # commands and arguments
        (["rendr"], ["unknown command 'rendr'", "did you mean 'render'"]),
        (["render", VALLEY], ["--out"]),
        (["render", VALLEY, *OUT, "--bogus"], ["--bogus"]),
    ],
)
def test_refusals_are_one_line_exit_2(argv, words, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)
    rc = main(argv)
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.startswith("fogref: error: ") and err.count("\n") == 1 and "Traceback" not in err, err
    for w in words:
        assert w in err, (w, err)


def test_parse_gives_values_and_what_was_given():
    module, o, given = parse(
        [
            "compare",
            "t.exr",
            "--model",
            "ue4",
            "--param",
            "FogDensity=0.05",
            "--tolerance",
            "T:rel_bias=0.001",
            "--distance-bands",
            "50,500",
        ]
    )
    assert module.NAME == "compare" and o.param == {"FogDensity": "0.05"} and o.precision == "float32"
    assert o.tolerance == {"T": {"rel_bias": 0.001}} and o.distance_bands == (50.0, 500.0)
    assert given == {"exr", "model", "param", "tolerance", "distance_bands"}
    _, o, _ = parse(["fit", "--sun-irradiance", "1", "2", "3", "--camera", "0", "2", "0"])
    assert o.sun_irradiance == (1.0, 2.0, 3.0) and o.camera == (0.0, 2.0, 0.0) and o.directions is None
