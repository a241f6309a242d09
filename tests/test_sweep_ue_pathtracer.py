"""``fogref sweep`` of kind ``ue_pathtracer``: UE's path-traced fog against the exact fog in closed form,
on the sweep package's TOML reader, design and Dask runner (no scene, no render).

The committed sweep ``reports/sweeps/ue_pathtracer`` loads as its 375 configurations, and rows of its
committed table are reproduced by :func:`fogref.study.ue_pathtracer.closed_form_row` to 1e-12
relative (deterministic quadrature: no noise), with the configuration ids the table records; a tiny
sweep runs on an in-process cluster.
"""

from __future__ import annotations

import csv
import logging
import math
from pathlib import Path

import pytest

import fogref.study.sweep as S
from fogref.errors import FogrefError
from fogref.study.ue_pathtracer import closed_form_row

COMMITTED = Path(__file__).resolve().parents[1] / "reports/sweeps/ue_pathtracer"
PARAMETERS = ("FogHeightFalloff", "FogDensityClamp", "VolumetricFogDistance", "FogHeight")

TINY = """
[sweep]
kind = "ue_pathtracer"
[fixed]
FogDensity = 0.02
camera = [0.0, 2.0, 0.0]
[sun]
direction = [0.0, 0.5, 1.0]
[views]
n_dirs = 12
distances = [10.0, 1000.0, 3]
ss_n_dirs = 6
ss_distances = [30.0, 300.0, 2]
ground = 0.0
[parameters.VolumetricFogDistance]
target = "ue_pathtracer.VolumetricFogDistance"
values = [3000.0, 100000.0]
[parameters.FogDensityClamp]
target = "ue_pathtracer.FogDensityClamp"
values = [1.0, 256.0]
[outputs]
plots = false
"""


def _toml(tmp_path, text: str) -> Path:
    p = tmp_path / "SWEEP.toml"
    p.write_text(text)
    return p


def test_the_committed_sweep_is_375_closed_form_configurations():
    spec = S.load_sweep(COMMITTED / "SWEEP.toml")
    configs = S.build_configs(spec)
    assert spec.kind == "ue_pathtracer" and list(spec.parameters) == list(PARAMETERS)
    assert len(configs) == 375 and len({c["id"] for c in configs}) == 375
    assert spec.closed_form["views"]["distances"] == [10.0, 20000.0, 12]
    assert spec.closed_form["fixed"]["camera"] == [0.0, 2.0, 0.0]


def test_rows_of_the_committed_table_reproduce():
    """Three rows of ``results.csv`` (a cylinder wall, a clamp, the sun) from the committed SWEEP.toml."""
    spec = S.load_sweep(COMMITTED / "SWEEP.toml")
    with open(COMMITTED / "results.csv", newline="") as f:
        table = list(csv.DictReader(f))
    for i in (0, 101, 374):
        want = table[i]
        cfg = next(
            c for c in S.build_configs(spec) if all(c["values"][k] == float(want[k]) for k in PARAMETERS)
        )
        got = closed_form_row(cfg["settings"], cfg["closed_form"])
        assert (want["config_id"], want["status"], want["model"]) == (cfg["id"], "ok", "ue_pathtracer")
        for k, v in got.items():
            if isinstance(v, bool):
                assert str(v) == want[k], (i, k)
            elif v is None or (want[k] == ""):
                assert v is None and want[k] == "", (i, k)
            else:
                assert math.isclose(v, float(want[k]), rel_tol=1e-12, abs_tol=1e-15), (i, k, v, want[k])


def test_a_tiny_sweep_runs_on_the_cluster_and_resumes(tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    p = _toml(tmp_path, TINY)
    with distributed.LocalCluster(
        n_workers=1,
        threads_per_worker=1,
        processes=False,
        dashboard_address=None,
        silence_logs=logging.CRITICAL,
    ) as c:
        info = S.run_sweep(p, scheduler=c.scheduler_address, progress=False)
        assert (info["configs"], info["ran"], info["failed"], info["rows"]) == (4, 4, 0, 4)
        again = S.run_sweep(p, scheduler=c.scheduler_address, progress=False)
        assert (again["ran"], again["rows"]) == (0, 4)
    with open(info["table"], newline="") as f:
        rows = list(csv.DictReader(f))
    spec = S.load_sweep(p)
    for cfg in S.build_configs(spec):
        row = next(r for r in rows if r["config_id"] == cfg["id"])
        want = closed_form_row(cfg["settings"], cfg["closed_form"])
        assert row["status"] == "ok" and row["model"] == "ue_pathtracer"
        assert math.isclose(float(row["opacity_rel_max"]), want["opacity_rel_max"], rel_tol=1e-11)
        assert row["departs"] == str(want["departs"])
    # a 30 m cylinder departs; with the fog height at the ground the clamp does not matter
    by = {(float(r["VolumetricFogDistance"]), float(r["FogDensityClamp"])): r for r in rows}
    assert by[(3000.0, 256.0)]["departs"] == "True"
    a, b = (float(by[(100000.0, c)]["opacity_rel_max"]) for c in (1.0, 256.0))
    assert math.isclose(a, b, rel_tol=1e-9)


@pytest.mark.parametrize(
    "edit, words",
    [
        (("[fixed]\n", "[fixed]\nFogDensty = 0.1\n"), ["[fixed]", "FogDensty", "FogDensity"]),
        (("values = [3000.0, 100000.0]", "values = [3000.0, -6000.0]"), ["VolumetricFogDistance", "-6000"]),
        (("[outputs]", "[render]\nspp = 4\n[outputs]"), ["unknown table", "render", "ue_pathtracer"]),
        (("plots = false", "plots = false\nperceptual = false"), ["[outputs]", "perceptual", "no images"]),
        (('kind = "ue_pathtracer"', 'kind = "closed"'), ["[sweep]", "kind", "ue_pathtracer"]),
        (("distances = [10.0, 1000.0, 3]", "distances = [10.0, 1.0, 3]"), ["[views]", "distances"]),
        (("direction = [0.0, 0.5, 1.0]", "direction = [0, 0, 0]"), ["[sun]", "direction"]),
        (
            ('"ue_pathtracer.FogDensityClamp"', '"ue_pathtracer.FogDensityClamps"'),
            ["FogDensityClamps", "did you mean 'FogDensityClamp'"],
        ),
    ],
)
def test_refusals_are_one_line(tmp_path, edit, words):
    p = _toml(tmp_path, TINY.replace(*edit))
    with pytest.raises(FogrefError) as e:
        S.load_sweep(p)
    msg = str(e.value)
    assert len(msg.splitlines()) == 1 and all(w in msg for w in words), msg
