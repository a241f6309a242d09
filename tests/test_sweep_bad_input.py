"""``fogref sweep``: bad-input and fault cases, each a one-line error or correct behaviour.

Every refusal is a :class:`~fogref.errors.FogrefError` (most a ``ParameterError``) of one line naming
the sweep file, the key and what is allowed; nothing is built, rendered or written before it.  The
cases that run work use tiny renders (16 x 9 pixels or less, 1 spp).
"""

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from terminal_signals import sigint_default

from fogref.errors import FogrefError, ParameterError
from fogref.study import sweep as S

ROOT = Path(__file__).resolve().parents[1]
VALLEY = ROOT / "scenes" / "valley.xml"
MODELS = '[[models]]\nname = "ue4"\n'
TINY = "[render]\nspp = 1\noverrides = { res = 8, resy = 4, max_depth = 2 }\n"


def _toml(folder: Path, body: str, scene: Path = VALLEY, name: str = "SWEEP.toml") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    p = folder / name
    p.write_text(
        f'[sweep]\nname = "t"\nscenes = ["{scene.as_posix()}"]\ncache = "{(folder / "cache").as_posix()}"\n'
        + body
    )
    return p


def _refused(p: Path, *needles: str, cls=FogrefError) -> str:
    """load_sweep refuses ``p`` in one line naming the file and every needle."""
    with pytest.raises(cls) as e:
        S.load_sweep(p)
    msg = str(e.value)
    assert "\n" not in msg and str(p) in msg, msg
    for n in needles:
        assert n in msg, (n, msg)
    return msg


# ---------------------------------------------------------------- the TOML's values (no Mitsuba)


@pytest.mark.parametrize(
    "body, needles",
    [
        # duplicate values: two configurations would be the same render
        (
            MODELS + "[parameters.sun_elevation]\nvalues = [5, 20, 5]\n",
            ("[parameters.sun_elevation]", "5", "twice"),
        ),
        (MODELS + '[design]\nkind = "random"\nn = 4\n[parameters.g]\nvalues = [0.1, 0.1]\n', ("twice",)),
        (
            MODELS + '[design]\nkind = "list"\n[parameters.g]\nvalues = [0.1, 0.1]\n'
            "[parameters.sun_elevation]\nvalues = [5, 5]\n",
            ("[design]", "twice"),
        ),
        (MODELS + "[parameters.g]\nscale = 0\nvalues = [0.1, 0.2]\n", ("'scale'", "0")),
        # pixel_filter
        (
            MODELS + '[render]\npixel_filter = "gauss"\n',
            ("[render]", "'pixel_filter'", "'gauss'", "centre, box"),
        ),
        (MODELS + '[render]\npixel_filter = "cntre"\n', ("did you mean 'centre'",)),
        # wrong value types
        (
            MODELS + '[design]\nkind = "random"\nn = true\n[parameters.g]\nrange = [0.1, 0.5]\n',
            ("[design]", "'n'", "True"),
        ),
        (
            MODELS + '[design]\nkind = "lhs"\nn = "4"\n[parameters.g]\nrange = [0.1, 0.5]\n',
            ("'n'", "'4'", "without quotes"),
        ),
        (
            MODELS + '[design]\nkind = "lhs"\nn = 4\nseed = "x"\n[parameters.g]\nrange = [0.1, 0.5]\n',
            ("[design]", "'seed'", "'x'"),
        ),
        (MODELS + '[render]\nseed = "x"\n', ("[render]", "'seed'", "'x'")),
        (MODELS + "[render]\nspp = 1.5\n", ("'spp'", "1.5", "[1, 1048576]")),
        (MODELS + "[render]\nspp = true\n", ("'spp'", "True")),
        (MODELS + "[execution]\nretries = -1\n", ("[execution]", "'retries'", "[0, 100]")),
        (MODELS + '[outputs]\nplots = "yes"\n', ("[outputs]", "'plots'", "true or false")),
        (MODELS + '[parameters.g]\nrange = ["a", 1]\nnum = 2\n', ("'range'", "'a'")),
        (MODELS + "[parameters.g]\nrange = [0.1, 0.5]\nnum = true\n", ("'num'",)),
        (MODELS + '[parameters.g]\nrange = [0.1, 0.5]\nlog = "yes"\n', ("'log'",)),
        (MODELS + '[parameters."ue4.FogDensity"]\nvalues = ["thick", 0.02]\n', ("'values'", "'thick'")),
        ('[[models]]\nname = "ue4"\nfrom_scene = "yes"\n', ("'from_scene'",)),
        ('[[models]]\nname = "ue4"\nparams = { FogDensity = "x" }\n', ("'FogDensity'", "'x'")),
        # an unknown model parameter, swept or fixed, with did-you-mean
        (
            MODELS + '[parameters."ue4.Bogus"]\nvalues = [1, 2]\n',
            ("[parameters.ue4.Bogus]", "no parameter 'Bogus'", "FogDensity"),
        ),
        (MODELS + '[parameters."ue4.FogDensty"]\nvalues = [1, 2]\n', ("did you mean 'FogDensity'",)),
        ('[[models]]\nname = "ue4"\nparams = { Bogus = 1 }\n', ("'ue4'", "no parameter 'Bogus'")),
        (MODELS + "[parameters.sun_elevaton]\nvalues = [1, 2]\n", ("did you mean 'sun_elevation'",)),
        # values the scene refuses: resolution, and the medium's own physical ranges
        (MODELS + "[render]\noverrides = { res = 0 }\n", ("[render]", "res", "0")),
        (MODELS + "[render]\noverrides = { sigma_t = [1e9] }\n", ("[render]", "sigma_t", "100")),
        (MODELS + "[render]\noverrides = { res = { x = 1 } }\n", ("[render]", "overrides.res")),
        (MODELS + "[parameters.res]\nvalues = [16, 0]\n", ("[parameters.res]", "value 0", "res")),
        (MODELS + "[parameters.sigma_t]\nvalues = [1e9]\n", ("[parameters.sigma_t]", "sigma_t", "100")),
        (MODELS + "[parameters.g]\nvalues = [0.5, 1.5]\n", ("[parameters.g]", "value 1.5", "0.999")),
        (
            MODELS + '[design]\nkind = "lhs"\nn = 4\n[parameters.albedo]\nrange = [0.5, 2]\n',
            ("[parameters.albedo]", "albedo"),
        ),
        (
            MODELS + '[parameters.sun_elevation]\nvalues = ["high", 5]\n',
            ("[parameters.sun_elevation]", "'high'"),
        ),
        (MODELS + "[parameters.sun_elevation]\nvalues = [true, 5]\n", ("[parameters.sun_elevation]",)),
        (
            MODELS + '[parameters.FogHeightFalloff]\ntarget = "falloff"\nscale = 1e6\nvalues = [0.1, 0.2]\n',
            ("[parameters.FogHeightFalloff]", "falloff"),
        ),
        # two labels of one target, and a target both swept and fixed
        (
            MODELS
            + '[parameters.g]\nvalues = [0.3, 0.5]\n[parameters.phase]\ntarget = "g"\nvalues = [0.8]\n',
            ("[parameters.phase]", "'g' is also swept by [parameters.g]"),
        ),
        (
            MODELS + '[parameters."ue4.FogDensity"]\nvalues = [0.01]\n[parameters.density_again]\n'
            'target = "ue4.FogDensity"\nvalues = [0.02]\n',
            ("also swept",),
        ),
        (
            MODELS + "[render]\noverrides = { g = 0.5 }\n[parameters.g]\nvalues = [0.3, 0.8]\n",
            ("[parameters.g]", "fixed in [render].overrides"),
        ),
        (
            '[[models]]\nname = "ue4"\nparams = { FogDensity = 0.02 }\n'
            '[parameters."ue4.FogDensity"]\nvalues = [0.01]\n',
            ("fixed in the [[models]] 'ue4' params",),
        ),
        # the table must stay inside the output folder
        (MODELS + '[outputs]\ntable = "../escaped"\n', ("[outputs]", "'table'", "leaves the output folder")),
        (MODELS + '[outputs]\ntable = "/tmp/escaped"\n', ("leaves the output folder",)),
        (MODELS + '[outputs]\ntable = "sub/../../escaped"\n', ("leaves the output folder",)),
    ],
)
def test_bad_sweep_values_are_one_line_errors(tmp_path, body, needles):
    _refused(_toml(tmp_path, body), *needles)


def test_table_in_a_subfolder_is_fine(tmp_path):
    assert (
        S.load_sweep(_toml(tmp_path, MODELS + '[outputs]\ntable = "tables/results"\n')).table
        == "tables/results"
    )


def test_a_repeated_scene_is_refused(tmp_path):
    p = _toml(tmp_path, MODELS)
    p.write_text(
        p.read_text().replace(
            f'scenes = ["{VALLEY.as_posix()}"]', f'scenes = ["{VALLEY.as_posix()}", "{VALLEY.as_posix()}"]'
        )
    )
    _refused(p, "'scenes'", "twice")


def test_two_labels_of_one_default_never_record_values_the_render_did_not_use(tmp_path):
    """The table names the g each configuration rendered (it once said g = 0.8 and g = 0.3 where both
    rendered g = 0.5)."""
    body = (
        MODELS + '[design]\nkind = "list"\n[parameters.g]\nvalues = [0.8, 0.3]\n'
        '[parameters.anisotropy]\ntarget = "g"\nvalues = [0.5, 0.5]\n'
    )
    _refused(_toml(tmp_path, body), "[parameters.anisotropy]", "'g' is also swept")


# ---------------------------------------------------------------- a design is sized before it is built


def test_a_huge_grid_is_refused_with_its_size_and_the_limit_before_it_is_built(tmp_path):
    vals = "[" + ", ".join(str(x) for x in range(1, 254)) + "]"
    body = MODELS + "".join(
        f'[parameters."ue4.{k}"]\nvalues = {vals}\n'
        for k in ("StartDistance", "FogCutoffDistance", "EndDistance", "DirectionalInscatteringStartDistance")
    )
    t0 = time.perf_counter()
    msg = _refused(
        _toml(tmp_path, body),
        "[design]",
        "4.097e+09 configurations",
        "limit is 100000",
        "max_configs",
        cls=ParameterError,
    )
    assert time.perf_counter() - t0 < 30, msg


def test_the_limit_is_set_in_the_design_table(tmp_path):
    body = MODELS + "[design]\nmax_configs = 2\n[parameters.g]\nvalues = [0.1, 0.2, 0.3]\n"
    _refused(_toml(tmp_path, body), "3 configurations", "limit is 2")
    body = MODELS + '[design]\nkind = "random"\nn = 1000000000\n[parameters.g]\nrange = [0.1, 0.5]\n'
    _refused(_toml(tmp_path, body), "'n'", "[1, 100000]")
    body = MODELS + "[parameters.g]\nrange = [0.1, 0.5]\nnum = 1000000000\n"
    _refused(_toml(tmp_path, body), "'num'", "[1, 100000]")


# ---------------------------------------------------------------- the id covers every file the scene loads


def _scene_with_mesh(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "box.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    text = VALLEY.read_text().replace(
        "</scene>",
        '    <shape type="obj"><string name="filename" value="box.obj"/><ref id="rock"/></shape>\n</scene>',
    )
    (folder / "scene.xml").write_text(text)
    return folder / "scene.xml"


def test_editing_a_mesh_the_scene_loads_changes_the_configuration_id(tmp_path):
    scene = _scene_with_mesh(tmp_path / "s")
    p = _toml(tmp_path, MODELS + TINY, scene=scene)
    (before,) = S.build_configs(S.load_sweep(p))
    (tmp_path / "s" / "box.obj").write_text("v 0 0 8\nv 1 0 8\nv 0 1 8\nf 1 2 3\n")  # moved 8 m
    (after,) = S.build_configs(S.load_sweep(p))
    assert before["id"] != after["id"] and before["truth"] != after["truth"]
    assert before["scene_sha256"] == after["scene_sha256"]  # the XML did not change


def test_a_missing_mesh_is_one_line(tmp_path):
    scene = _scene_with_mesh(tmp_path / "s")
    (tmp_path / "s" / "box.obj").unlink()
    with pytest.raises(FogrefError, match="box.obj") as e:
        S.build_configs(S.load_sweep(_toml(tmp_path, MODELS + TINY, scene=scene)))
    assert "\n" not in str(e.value)


# ---------------------------------------------------------------- no output replaces an input


def _done(p: Path) -> list:
    """Record every configuration as finished (no render), as an earlier run would have."""
    spec = S.load_sweep(p)
    cfgs = S.build_configs(spec)
    (Path(spec.out) / "configs").mkdir(parents=True, exist_ok=True)
    for c in cfgs:
        (Path(spec.out) / "configs" / f"{c['id']}.json").write_text(
            json.dumps({"id": c["id"], "status": "ok", "provenance": {}, "rows": []})
        )
    return cfgs


def test_a_sweep_file_named_sweep_json_is_not_overwritten(tmp_path):
    p = _toml(tmp_path, MODELS + TINY, name="sweep.json")
    _done(p)
    text = p.read_text()
    with pytest.raises(FogrefError, match="would replace the input") as e:
        S.run_sweep(p, progress=False)
    assert str(p) in str(e.value) and "\n" not in str(e.value)
    assert p.read_text() == text and not (tmp_path / "results.csv").exists()


def test_the_table_may_not_replace_a_scene(tmp_path):
    scene = tmp_path / "results.csv"
    scene.write_text(VALLEY.read_text())
    p = _toml(tmp_path, MODELS + TINY, scene=scene)
    _done(p)
    with pytest.raises(FogrefError, match="would replace the input .*results.csv .a scene"):
        S.run_sweep(p, progress=False)
    assert scene.read_text() == VALLEY.read_text()


def test_a_plot_may_not_replace_a_texture_the_scene_loads(tmp_path):
    (tmp_path / "plots").mkdir()
    tex = tmp_path / "plots" / "final.all.rmse_vs_g.png"
    tex.write_bytes(b"\x89PNG not really")
    link = tmp_path / "tex.png"
    link.symlink_to(tex)  # through a symlink: resolved paths are compared
    text = VALLEY.read_text().replace(
        "</scene>",
        '    <texture type="bitmap" id="t"><string name="filename" value="tex.png"/></texture>\n</scene>',
    )
    (tmp_path / "scene.xml").write_text(text)
    p = _toml(tmp_path, MODELS + TINY + "[parameters.g]\nvalues = [0.3]\n", scene=tmp_path / "scene.xml")
    _done(p)
    with pytest.raises(FogrefError, match="a plot.*tex.png"):
        S.run_sweep(p, progress=False)
    assert tex.read_bytes() == b"\x89PNG not really"


# ---------------------------------------------------------------- the command's own options


@pytest.mark.parametrize(
    "kw, needle",
    [
        ({"scheduler": "garbage"}, "'--scheduler': 'garbage' is not a Dask scheduler address"),
        ({"scheduler": ""}, "'--scheduler'"),
        ({"n_workers": 0}, "'--workers': 0 is outside [1, 4096]"),
        ({"n_workers": -1}, "'--workers': -1 is outside"),
        ({"drjit_threads": -1}, "'--drjit-threads': -1 is outside"),
    ],
)
def test_bad_options_fail_in_one_line_before_any_work(tmp_path, kw, needle):
    p = _toml(tmp_path, MODELS + TINY)
    with pytest.raises(ParameterError) as e:
        S.run_sweep(p, progress=False, **kw)
    assert needle in str(e.value) and "\n" not in str(e.value)
    assert not (tmp_path / "sweep.json").exists() and not (tmp_path / "configs").exists()


# ---------------------------------------------------------------- malformed result files, Ctrl-C (render)


@pytest.fixture(scope="module")
def inprocess_cluster():
    distributed = pytest.importorskip("dask.distributed")
    import logging

    with distributed.LocalCluster(
        n_workers=1,
        threads_per_worker=1,
        processes=False,
        dashboard_address=None,
        silence_logs=logging.CRITICAL,
    ) as c:
        yield c


def test_a_result_file_with_missing_fields_is_set_aside_not_a_traceback(tmp_path, capsys):
    p = _toml(tmp_path, MODELS + TINY + "[parameters.g]\nvalues = [0.3, 0.6]\n[outputs]\nplots = false\n")
    spec = S.load_sweep(p)
    a, b = S.build_configs(spec)
    cdir = tmp_path / "configs"
    cdir.mkdir()
    for c in (a, b):
        (cdir / f"{c['id']}.json").write_text(json.dumps({"id": c["id"], "status": "ok"}))  # no rows
    assert S.run._todo([a], cdir, retry_failed=False) == [a]  # run again
    assert S.write_table(spec, [a, b])["rows"] == 0  # the table of what is there
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 2 and all("no 'provenance' object; set aside as" in line for line in err), err
    assert {f.name for f in cdir.iterdir()} == {f"{a['id']}.json.bad", f"{b['id']}.json.bad"}


@pytest.mark.render
def test_a_result_file_holding_a_list_is_set_aside_with_a_warning_and_run_again(
    tmp_path, inprocess_cluster, capsys
):
    p = _toml(tmp_path, MODELS + TINY + "[outputs]\nplots = false\n")
    (a,) = S.build_configs(S.load_sweep(p))
    cdir = tmp_path / "configs"
    cdir.mkdir()
    (cdir / f"{a['id']}.json").write_text("[]\n")
    info = S.run_sweep(p, scheduler=inprocess_cluster.scheduler_address, progress=False)
    assert (info["ran"], info["failed"], info["rows"]) == (1, 0, 1)
    err = capsys.readouterr().err
    warnings = [line for line in err.splitlines() if "set aside" in line]
    assert len(warnings) == 1 and "Traceback" not in err
    assert f"{a['id']}.json: holds a list, not a result object; set aside as" in warnings[0]
    assert (cdir / f"{a['id']}.json.bad").read_text() == "[]\n"
    assert json.loads((cdir / f"{a['id']}.json").read_text())["status"] == "ok"


#: wall-clock limit [s] of each wait below, for a hang only: generous on a loaded machine
HANG_S = 900
_CTRL_C = textwrap.dedent("""
    import sys
    from fogref.study.sweep import run_sweep
    try:
        run_sweep(sys.argv[1], n_workers=1, progress=False)
    except KeyboardInterrupt as e:
        print(e, file=sys.stderr)
        sys.exit(130)
    """)


@pytest.mark.render
def test_ctrl_c_stops_the_local_cluster_in_one_line_and_logs_the_workers(tmp_path):
    body = (
        MODELS + "[render]\nspp = 1\noverrides = { res = 16, resy = 9, max_depth = 2 }\n"
        "[parameters.sun_elevation]\nvalues = [" + ", ".join(str(x) for x in range(5, 45)) + "]\n"
        "[outputs]\nplots = false\n"
    )
    p = _toml(tmp_path, body)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen(
        [sys.executable, "-c", _CTRL_C, str(p)],
        cwd=tmp_path,
        env=env,
        text=True,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
        preexec_fn=sigint_default,  # Ctrl-C raises, even when the suite runs in the background
    )
    log = tmp_path / "sweep-workers.log"
    # the event: the first configuration's result is on disk, so the cluster runs; the clock only
    # catches a hang (HANG_S, far above the ~20 s this takes on a loaded 2-core machine)
    deadline = time.monotonic() + HANG_S
    while proc.poll() is None and not list((tmp_path / "configs").glob("*.json")):
        assert time.monotonic() < deadline, f"no configuration finished in {HANG_S} s: a hang"
        time.sleep(0.2)
    assert proc.poll() is None, proc.communicate()
    os.killpg(proc.pid, signal.SIGINT)  # like Ctrl-C in a terminal: the sweep and its workers
    out, err = proc.communicate(timeout=HANG_S)  # a hang only
    assert proc.returncode == 130, err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    assert "interrupted" in lines[0] and "cluster is stopped" in lines[0] and str(log) in lines[0]
    assert log.is_file()


def test_a_ctrl_c_that_a_library_swallowed_still_ends_the_sweep_interrupted(
    tmp_path, inprocess_cluster, monkeypatch
):
    """The signal is remembered: a sweep whose configurations all finish after a Ctrl-C whose
    KeyboardInterrupt was caught inside a library (Dask, tqdm) still ends interrupted (exit 130)."""
    p = _toml(tmp_path, MODELS + TINY + "[outputs]\nplots = false\n")

    def run_swallowing(*args):
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)
        except KeyboardInterrupt:  # a library's own handling
            pass
        return 0

    monkeypatch.setattr(S.run, "_run", run_swallowing)
    with pytest.raises(KeyboardInterrupt, match="interrupted with 0 of 1 configurations done"):
        S.run_sweep(p, scheduler=inprocess_cluster.scheduler_address, progress=False)
