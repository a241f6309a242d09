"""``fogref sweep``: the TOML schema, the designs, and a tiny sweep on a real two-worker Dask cluster.

The cluster test goes through the same code path as ``fogref sweep --scheduler ADDRESS``
(``run_sweep(..., scheduler=cluster.scheduler_address)``): it checks the table, that
one configuration with an invalid value is recorded with its error while the others
finish, that a second run does no new work, and that a truth is reused from the cache.
"""

import json
import time
from pathlib import Path

import numpy as np
import pytest

from fogref.errors import FogrefError
from fogref.study import sweep as S

ROOT = Path(__file__).resolve().parents[1]
VALLEY = (ROOT / "scenes" / "valley.xml").as_posix()


def sweep_toml(folder, body: str, cache=None) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    p = folder / "SWEEP.toml"
    cache = (cache or folder / "cache").as_posix()
    p.write_text(f'[sweep]\nname = "t"\nscenes = ["{VALLEY}"]\ncache = "{cache}"\n' + body)
    return p


MODELS = '[[models]]\nname = "ue4"\n'


# ---------------------------------------------------------------- schema and designs (no Mitsuba)


def test_grid_design_and_scaled_target(tmp_path):
    p = sweep_toml(
        tmp_path,
        MODELS + "[parameters.sun_elevation]\nvalues = [5, 30]\n"
        '[parameters.FogHeightFalloff]\ntarget = "falloff"\nscale = 0.0693147\nvalues = [0.1, 0.2, 0.4]\n',
    )
    spec = S.load_sweep(p)
    cfgs = S.build_configs(spec)
    assert len(cfgs) == 6 and len({c["id"] for c in cfgs}) == 6
    assert cfgs[1]["values"] == {"sun_elevation": 5, "FogHeightFalloff": 0.2}
    assert float(cfgs[1]["overrides"]["falloff"]) == pytest.approx(0.0138629, rel=1e-5)
    assert all(c["seed"] == 0 for c in cfgs)


def test_lhs_design_is_seeded_stratified_and_in_range(tmp_path):
    p = sweep_toml(
        tmp_path,
        MODELS + '[design]\nkind = "lhs"\nn = 8\nseed = 3\n[render]\nseed_policy = "per_config"\n'
        "[parameters.g]\nrange = [-0.5, 0.9]\n[parameters.sigma_t]\nrange = [1e-4, 1e-2]\nlog = true\n"
        '[parameters."ue4.StartDistance"]\nvalues = [0, 10]\n',
    )
    spec = S.load_sweep(p)
    pts = S.design_points(spec)
    assert pts == S.design_points(S.load_sweep(p))  # seeded
    g = np.array([q["g"] for q in pts])
    assert g.min() >= -0.5 and g.max() <= 0.9
    # Latin hypercube: one point in each of the 8 strata of every dimension
    assert sorted(((g + 0.5) / 1.4 * 8).astype(int)) == list(range(8))
    ls = np.log(np.array([q["sigma_t"] for q in pts]) / 1e-4) / np.log(100)
    assert sorted((ls * 8).astype(int)) == list(range(8))
    cfgs = S.build_configs(spec)
    assert len({c["seed"] for c in cfgs}) == 8  # per-config seeds
    assert {c["models"][0]["params"]["StartDistance"] for c in cfgs} == {0, 10}


@pytest.mark.parametrize(
    "body, needle",
    [
        (MODELS + "[parameters.not_a_default]\nvalues = [1]\n", "not a $default of every scene; allowed: ["),
        (MODELS + '[design]\nkind = "sobol"\n', "'sobol' is not one of grid, list, random, lhs"),
        (MODELS + "[render]\nspp = 0\n", "parameter 'spp': 0 is outside [1, 1048576]"),
        (MODELS + '[render]\nseed_policy = "random"\n', "'random' is not one of fixed, per_config"),
        (MODELS + "[parameters.g]\nvalue = [1]\n", "unknown key(s) ['value']"),
        (MODELS + '[parameters."hdrp.x"]\nvalues = [1]\n', "model label 'hdrp' is not a [[models]] label"),
        ('[[models]]\nname = "no_such_model"\n', "no_such_model"),
        (
            MODELS + '[design]\nkind = "list"\n[parameters.g]\nvalues = [0.1, 0.2]\n'
            "[parameters.albedo]\nvalues = [0.5]\n",
            "lengths differ",
        ),
        (MODELS + "[parameters.g]\nrange = [0.1, 0.2]\n", "needs num = number of points"),
    ],
)
def test_invalid_sweep_files_name_file_key_and_allowed_values(tmp_path, body, needle):
    p = sweep_toml(tmp_path, body)
    with pytest.raises(FogrefError) as e:
        S.load_sweep(p)
    assert str(p) in str(e.value) and needle in str(e.value)


# ---------------------------------------------------------------- a real two-worker cluster


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("dask.distributed")
    import logging

    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,
        silence_logs=logging.CRITICAL,
    ) as c:
        yield c


TINY = (
    "[render]\nspp = 4\noverrides = { res = 16, resy = 9, max_depth = 3 }\n"
    '[design]\nkind = "list"\n'
    "[parameters.sun_elevation]\nvalues = [5, 20, 40, 60]\n"
    "[parameters.g]\nvalues = [0.2, 0.6, 0.7, 0.8]\n"
    # Unreal refuses FogMaxOpacity = 5 when the model is built on the worker: that configuration fails
    '[parameters."ue4.FogMaxOpacity"]\nvalues = [1.0, 1.0, 5.0, 1.0]\n'
    '[execution]\nretries = 1\n[outputs]\nplot_metrics = ["final.all.rmse"]\n'
)


@pytest.mark.render
def test_sweep_on_two_worker_cluster_records_failure_resumes_and_reuses_truths(tmp_path, cluster):
    addr = cluster.scheduler_address
    p = sweep_toml(tmp_path, MODELS + TINY)
    info = S.run_sweep(p, scheduler=addr, progress=False, drjit_threads=1)
    assert (info["configs"], info["ran"], info["failed"], info["rows"]) == (4, 4, 1, 4)

    import pandas as pd

    df = pd.read_parquet(info["parquet"])
    assert len(pd.read_csv(info["table"])) == 4
    bad = df[df["status"] == "error"]
    assert len(bad) == 1 and bad["g"].iloc[0] == 0.7 and "FogMaxOpacity" in bad["error"].iloc[0]
    ok = df[df["status"] == "ok"]
    assert len(ok) == 3 and (ok["final.all.rmse"] > 0).all() and (ok["final.all.rmse_stderr"] >= 0).all()
    for col in (
        "spp",
        "seed",
        "fogref_version",
        "mitsuba_version",
        "truth_path",
        "truth_sha256",
        "render_seconds",
        "model",
        "model_parameters",
        "sun_elevation",
        "g",
    ):
        assert col in df.columns and ok[col].notna().all(), col
    assert not ok["truth_cached"].any() and len(list((tmp_path / "cache").rglob("*.exr"))) == 4
    assert (tmp_path / "plots" / "final.all.rmse_vs_sun_elevation.png").is_file()
    assert len(list((tmp_path / "configs").glob("*.json"))) == 4
    # the figures drawn on the cluster's workers are byte for byte the ones drawn here
    spec = S.load_sweep(p)
    here = S.plot_table(df, spec, tmp_path / "plots-here")
    assert sorted(f.name for f in here) == sorted(Path(f).name for f in info["plots"]) and len(here) == 3
    assert all(f.read_bytes() == (tmp_path / "plots" / f.name).read_bytes() for f in here)

    # resume: nothing is run again, the table is the same
    stamps = {f: f.stat().st_mtime_ns for f in (tmp_path / "configs").glob("*.json")}
    t0 = time.perf_counter()
    again = S.run_sweep(p, scheduler=addr, progress=False)
    assert again["ran"] == 0 and again["rows"] == 4 and time.perf_counter() - t0 < 20
    assert stamps == {f: f.stat().st_mtime_ns for f in (tmp_path / "configs").glob("*.json")}

    # new model parameters, same truths: the truths come from the cache (no render)
    q = sweep_toml(
        tmp_path / "second",
        MODELS.replace('"ue4"\n', '"ue4"\nparams = { StartDistance = 500.0 }\n') + TINY,
        cache=tmp_path / "cache",
    )
    third = S.run_sweep(q, scheduler=addr, progress=False, drjit_threads=1)
    df3 = pd.read_parquet(third["parquet"])
    assert third["ran"] == 4 and df3[df3["status"] == "ok"]["truth_cached"].all()
    assert all(
        json.loads(m)["StartDistance"] == 500.0 for m in df3[df3["status"] == "ok"]["model_parameters"]
    )


def test_plot_table_draws_each_figure_through_run_with_the_same_bytes(tmp_path):
    """``plot_table(..., run)`` hands every (parameter, metric) figure to ``run`` (here a pool of
    two fresh processes) and writes the PNGs it returns: the same files, byte for byte, as drawn in
    this process (one byte of one figure is detected)."""
    from concurrent.futures import ProcessPoolExecutor

    import pandas as pd

    p = sweep_toml(tmp_path, MODELS + TINY.replace('plot_metrics = ["final.all.rmse"]', "plots = true"))
    spec = S.load_sweep(p)
    rng = np.random.default_rng(3)
    df = pd.DataFrame(
        {
            "status": ["ok"] * 8 + ["error"],
            "model": ["ue4"] * 9,
            "sun_elevation": [5, 20, 40, 60] * 2 + [5],
            "g": [0.2, 0.6, 0.7, 0.8, 0.8, 0.7, 0.6, 0.2, 0.2],
            "final.all.rmse": rng.uniform(0.01, 1.0, 9),
            "final.all.rmse_stderr": rng.uniform(0.0, 0.01, 9),
            "final.all.relmse": rng.uniform(0.01, 1.0, 9),
        }
    )
    here = S.plot_table(df, spec, tmp_path / "here")
    calls = []

    def pool(f, jobs):
        calls.append(len(jobs))
        with ProcessPoolExecutor(2) as ex:
            return list(ex.map(f, *zip(*jobs)))

    there = S.plot_table(df, spec, tmp_path / "there", pool)
    assert calls == [len(here)] and len(here) == 2 * 2  # (rmse, relmse) x (sun_elevation, g)
    assert [f.name for f in here] == [f.name for f in there]
    assert all(a.read_bytes() == b.read_bytes() for a, b in zip(here, there))


def test_plot_table_hands_each_figure_its_points_means_and_error_bars(tmp_path):
    """What ``plot_table`` gives ``run`` per figure: per model (in name order) every ok
    configuration's parameter and metric, twice the metric's standard error, the metric's mean per
    parameter value (hand-computed), a log axis only for a positive metric spanning more than 20x,
    and a parameter that is not a number as text; nothing of pandas (a worker drawing it needs
    matplotlib alone)."""
    import pandas as pd

    p = sweep_toml(tmp_path, MODELS + TINY.replace('plot_metrics = ["final.all.rmse"]', "plots = true"))
    spec = S.load_sweep(p)
    df = pd.DataFrame(
        {
            "status": ["ok"] * 6 + ["error"],
            "model": ["ue4", "ue4", "ue4", "godot", "godot", "ue4", "ue4"],
            "sun_elevation": [5, 20, 5, 20, 20, 20, 5],
            "g": ["a", "b", "a", "b", "a", "b", "a"],
            "final.all.rmse": [1.0, 2.0, 3.0, 40.0, 0.5, 4.0, 99.0],
            "final.all.rmse_stderr": [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7],
            "final.all.relmse": [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0],
        }
    )
    jobs = []

    def record(f, js):
        jobs.extend(js)
        return [b"png"] * len(js)

    S.plot_table(df, spec, tmp_path / "plots", record)
    by = {(j[2], j[3]): j for j in jobs}
    assert sorted(by) == [
        (q, m) for q in ("g", "sun_elevation") for m in ("final.all.relmse", "final.all.rmse")
    ]
    series, name, _, _, log = by[("sun_elevation", "final.all.rmse")]
    assert name == spec.name and log  # 0.5 to 40: more than 20x
    godot, ue4 = series
    assert godot == {
        "model": "godot",
        "x": [20, 20],
        "y": [40.0, 0.5],
        "err": [0.8, 1.0],
        "mean_x": [20],
        "mean_y": [20.25],
    }
    assert ue4["x"] == [5, 20, 5, 20] and ue4["mean_x"] == [5, 20] and ue4["mean_y"] == [2.0, 3.0]
    assert ue4["err"] == pytest.approx([0.2, 0.4, 0.6, 1.2])
    series, _, _, _, log = by[("g", "final.all.relmse")]
    assert not log and series[1]["x"] == ["a", "b", "a", "b"] and series[1]["mean_x"] == ["a", "b"]
    assert series[1]["err"] is None  # no noise column
    assert all(type(v) in (str, int, float, bool, list, dict, type(None)) for j in jobs for v in j)


KILL = (
    "[render]\nspp = 4\noverrides = { res = 16, resy = 9, max_depth = 3 }\n"
    '[design]\nkind = "list"\n'
    "[parameters.sun_elevation]\nvalues = [5, 12, 20, 30, 40, 60]\n"
    "[parameters.g]\nvalues = [0.21, 0.31, 0.41, 0.51, 0.61, 0.71]\n"
    "[execution]\nretries = 1\n[outputs]\nplots = false\n"
)


@pytest.mark.render
def test_worker_killed_mid_sweep_is_recorded_and_nothing_else_is_lost(tmp_path):
    """SIGKILL one of two worker processes while it runs a configuration.

    The scheduler is told not to reschedule a task whose worker died
    (``allowed-failures = 0``), so that configuration is recorded as failed with
    Dask's KilledWorker error; every other configuration finishes (on the
    surviving worker or the one the nanny restarts), and ``retry_failed`` then
    completes the sweep without running the finished ones again.  (With Dask's
    default ``allowed-failures = 3`` the task is simply run again elsewhere.)
    """
    import logging
    import os
    import signal
    import threading

    dask = pytest.importorskip("dask")
    distributed = pytest.importorskip("dask.distributed")
    cfg = {
        "distributed.scheduler.allowed-failures": 0,
        # a lock held by the killed worker is freed after 3 s instead of 30 s
        "distributed.scheduler.locks.lease-timeout": "3s",
        "distributed.scheduler.locks.lease-validation-interval": "1s",
    }
    p = sweep_toml(tmp_path, MODELS + KILL)
    with (
        dask.config.set(cfg),
        distributed.LocalCluster(
            n_workers=2,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.CRITICAL,
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        addr = cluster.scheduler_address
        result = {}

        def sweep():
            try:
                result["info"] = S.run_sweep(p, scheduler=addr, progress=False, drjit_threads=1)
            except BaseException as e:  # noqa: BLE001 - reported by the assertion below
                result["error"] = e

        client.wait_for_workers(2)
        pids = client.run(os.getpid)  # asked before the sweep: between a look and the kill, no round trip
        th = threading.Thread(target=sweep, daemon=True)
        th.start()
        # wait until one configuration is finished and another is running, then kill its worker at
        # once: a round trip between the look and the kill let the worker finish what it was seen
        # running and start another configuration, which the kill then failed instead
        victim, deadline = None, time.time() + 300
        while victim is None and time.time() < deadline and th.is_alive():
            done = len(list((tmp_path / "configs").glob("*.json")))
            busy = {
                w: [k for k in keys if str(k).startswith("fogref-sweep-")]
                for w, keys in client.processing().items()
            }
            busy = {w: ks for w, ks in busy.items() if ks}
            if done >= 1 and busy:
                victim = sorted(busy)[0]
                killed_pid, in_flight, done_before = pids[victim], busy[victim], done
                os.kill(killed_pid, signal.SIGKILL)
            else:
                time.sleep(0.05)
        assert victim is not None, "no configuration was running on a worker"
        th.join(timeout=600)
        assert not th.is_alive(), "the sweep did not finish after a worker was killed"
        assert "error" not in result, repr(result.get("error"))
        info = result["info"]
        assert done_before < 6  # killed mid-sweep

        import pandas as pd

        df = pd.read_parquet(info["parquet"])
        assert info["configs"] == 6 and len(df) == 6 and len(list((tmp_path / "configs").glob("*.json"))) == 6
        bad, ok = df[df["status"] == "error"], df[df["status"] == "ok"]
        assert 1 <= len(bad) == info["failed"] <= len(in_flight)
        assert set("fogref-sweep-" + bad["config_id"]) <= set(in_flight)
        assert bad["error"].str.contains("KilledWorker|died|lost", case=False).all(), list(bad["error"])
        assert len(ok) == 6 - len(bad) and (ok["final.all.rmse"] > 0).all()
        assert not set(in_flight) & set("fogref-sweep-" + ok["config_id"][ok["worker_pid"] == killed_pid])

        # the recorded failures run again; the finished configurations are not touched
        stamps = {
            f: f.stat().st_mtime_ns
            for f in (tmp_path / "configs").glob("*.json")
            if json.loads(f.read_text())["status"] == "ok"
        }
        again = S.run_sweep(p, scheduler=addr, progress=False, drjit_threads=1, retry_failed=True)
        assert again["ran"] == len(bad) and again["failed"] == 0
        assert stamps == {f: f.stat().st_mtime_ns for f in stamps}
        df2 = pd.read_parquet(again["parquet"])
        assert len(df2) == 6 and (df2["status"] == "ok").all()


@pytest.mark.render
def test_budget_steps_per_configuration(tmp_path):
    """``[outputs] budget = true``: one sun-less render per configuration, Unreal's budget
    steps as columns; their shares of the squared error sum to 1.  A sun override is
    kept out of the sun-less render (Mitsuba refuses an unused ``$sun_elevation``)."""
    from fogref.study.budget import STEPS

    body = MODELS + (
        "[render]\nspp = 4\noverrides = { res = 16, resy = 9, max_depth = 3, sun_elevation = 20 }\n"
        "[outputs]\nbudget = true\nplots = false\n"
    )
    spec = S.load_sweep(sweep_toml(tmp_path, body))
    (cfg,) = S.build_configs(spec)
    (plain,) = S.build_configs(S.load_sweep(sweep_toml(tmp_path / "plain", body.split("[outputs]")[0])))
    assert cfg["budget"] and not plain["budget"] and cfg["id"] != plain["id"]  # a budget sweep is not resumed
    row = S.run_config(cfg)["rows"][0]
    shares = [row[f"budget.{k}.share"] for k, _, _ in STEPS]
    assert sum(shares) == pytest.approx(1.0, abs=1e-9)
    assert row["budget.total.rmse"] > 0 and row["budget.multiple.rmse_stderr"] >= 0
    assert (
        Path(row["budget.sky_only_truth"]).is_file() and len(list((tmp_path / "cache").rglob("*.exr"))) == 2
    )


@pytest.mark.render
def test_perceptual_false_leaves_out_flip_and_delta_e_columns_only(tmp_path):
    """``[outputs] perceptual = false``: the configuration's row lacks every ΔE2000 and FLIP column,
    and every other column is the one of the default sweep, bit for bit (the same truth, one
    comparison without its perceptual maps).  Its id differs (a default sweep's results are not
    resumed as its own), the default's id is the one it always had (no such key in it), and the
    default plots skip the perceptual metrics."""
    body = MODELS + "[render]\nspp = 4\noverrides = { res = 16, resy = 9, max_depth = 3 }\n"
    cache = tmp_path / "cache"
    full = S.load_sweep(sweep_toml(tmp_path / "full", body + "[outputs]\nplots = false\n", cache))
    lean = S.load_sweep(sweep_toml(tmp_path / "lean", body + "[outputs]\nperceptual = false\n", cache))
    (cf,), (cl,) = S.build_configs(full), S.build_configs(lean)
    assert cf["perceptual"] and not cl["perceptual"] and cf["id"] != cl["id"]
    assert cf["truth"] == cl["truth"]
    rf, rl = S.run_config(cf)["rows"][0], S.run_config(cl)["rows"][0]
    perceptual = {k for k in rf if ".delta_e2000" in k or ".flip" in k}
    assert len(perceptual) >= 24 and not perceptual & set(rl)
    skip = {"compare_seconds", "render_seconds", "truth_cached"}
    assert {k: v for k, v in rl.items() if k not in skip} == {
        k: v for k, v in rf.items() if k not in perceptual | skip
    }
    from fogref.study.sweep.table import plot_files, plotted_metrics

    kept = [m for m in plotted_metrics(full) if "delta_e" not in m and "flip" not in m]
    assert plotted_metrics(lean) == kept
    assert all("flip" not in p.name and "delta_e" not in p.name for p in plot_files(lean, tmp_path))


def test_perceptual_false_refuses_to_plot_a_perceptual_metric(tmp_path):
    """A plotted ΔE2000 or FLIP metric with ``perceptual = false`` is a one-line error naming the
    file, ``plot_metrics`` and the metric, not an empty figure."""
    plotted = 'plot_metrics = ["final.all.rmse", "final.all.flip_mean"]\n'
    body = MODELS + "[outputs]\nperceptual = false\n" + plotted
    with pytest.raises(FogrefError, match=r"SWEEP\.toml.*plot_metrics.*final\.all\.flip_mean"):
        S.load_sweep(sweep_toml(tmp_path, body))
