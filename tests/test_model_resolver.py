"""One resolver, one builder, one Unreal fit, end to end on one tiny truth.

A user's ``module:Class`` model and an entry-point model (a real ``*.dist-info`` with
``entry_points.txt`` on ``sys.path`` and ``PYTHONPATH``, so the sweep's worker
process finds it too) run through ``fogref compare``, ``fogref.check`` and ``fogref
sweep``; Unreal's parameters from ``fogref fit``, ``compare --from-scene``,
``fogref study`` and the sweep are the same, and so is the final RMSE.  One
sweep (16x9, 4 spp, one worker) renders the truth that every test here uses.
"""

import json
import os
import sys
import textwrap

import numpy as np
import pytest
from test_byo_models import MODULE

import fogref
from fogref.cli import main
from fogref.compare.check import check
from fogref.errors import FogrefError
from fogref.study import sweep as S

pytestmark = pytest.mark.render

USER_MODULE = "resolver_test_fog"
ENTRY_POINT = "resolver_ep_fog"
SPECS = {f"{USER_MODULE}:MyFog": "MyFog", ENTRY_POINT: ENTRY_POINT}  # model name -> sweep label
UNREAL_FIT = (
    "FogInscatteringColor",
    "DirectionalInscatteringColor",
    "DirectionalInscatteringExponent",
    "DirectionalInscatteringStartDistance",
)


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """A folder on sys.path and PYTHONPATH with the user's module and a dist-info naming its entry point."""
    root = tmp_path_factory.mktemp("site")
    (root / f"{USER_MODULE}.py").write_text(textwrap.dedent(MODULE))
    dist = root / "fogref_resolver_test-0.1.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: fogref-resolver-test\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text(f"[fogref.models]\n{ENTRY_POINT} = {USER_MODULE}:MyFog\n")
    old = os.environ.get("PYTHONPATH")
    sys.path.insert(0, str(root))
    os.environ["PYTHONPATH"] = os.pathsep.join([str(root)] + ([old] if old else []))
    yield root
    sys.path.remove(str(root))
    sys.modules.pop(USER_MODULE, None)
    if old is None:
        os.environ.pop("PYTHONPATH", None)
    else:
        os.environ["PYTHONPATH"] = old


@pytest.fixture(scope="module")
def swept(site, tmp_path_factory):
    """One configuration of valley.xml (16x9, 4 spp) with ue4, the module:Class and the entry-point model."""
    pd = pytest.importorskip("pandas")
    from test_sweep import VALLEY

    folder = tmp_path_factory.mktemp("sweep")
    models = "".join(f'[[models]]\nname = "{name}"\n' for name in ["ue4", *SPECS])
    (folder / "SWEEP.toml").write_text(
        f'[sweep]\nname = "resolver"\nscenes = ["{VALLEY}"]\ncache = "{(folder / "cache").as_posix()}"\n'
        + models
        + '[render]\nspp = 4\noverrides = { res = 16, resy = 9, max_depth = 3 }\n[design]\nkind = "list"\n'
        "[parameters.g]\nvalues = [0.6]\n"
    )
    info = S.run_sweep(folder / "SWEEP.toml", n_workers=1, progress=False, drjit_threads=1)
    df = pd.read_parquet(info["parquet"])
    assert (df["status"] == "ok").all(), df.get("error")
    rows = {r["model"]: r for r in df.to_dict("records")}
    return rows, rows["ue4"]["truth_path"]


def test_user_and_entry_point_models_through_sweep_compare_and_check(swept, tmp_path):
    rows, truth_path = swept
    truth = fogref.load_truth(truth_path)
    for name, label in SPECS.items():
        row = rows[label]
        assert row["model_name"] == name and row["final.all.rmse"] > 0
        out = tmp_path / label
        assert (
            main(["compare", truth_path, "--model", name, "--from-scene", "--out", str(out), "--no-figures"])
            == 1
        )  # fails: exit 1
        rmse = json.loads((out / "metrics.json").read_text())["metrics"]["final"]["all"]["rmse"]
        assert rmse == pytest.approx(row["final.all.rmse"], rel=1e-12)
        model = fogref.build_model(name, scene_params=truth.params)
        assert type(model).__name__ == "MyFog" and model.sigma == 0.003  # its from_physical
        assert (
            fogref.check(truth, model).row("T", "all").estimate
            == check(truth, model).row("T", "all").estimate
        )


def test_unknown_names_get_did_you_mean_everywhere(site, tmp_path):
    assert ENTRY_POINT in fogref.models.available_models()
    with pytest.raises(FogrefError, match=f"did you mean '{ENTRY_POINT}'"):
        fogref.resolve_model("resolver_ep_fgo")
    with pytest.raises(
        FogrefError, match="unknown fog model 'eu4'; did you mean 'ue4'.*installed: .*resolver_ep"
    ):
        fogref.build_model("eu4")
    from test_sweep import sweep_toml

    with pytest.raises(FogrefError, match=r"SWEEP.toml.*models\]\[0\].*did you mean 'MyFog'"):
        S.load_sweep(sweep_toml(tmp_path, f'[[models]]\nname = "{USER_MODULE}:MyFgo"\n'))


def _unreal(params: dict) -> list:
    """The fitted fields of Unreal's parameters (JSON from any of the paths), as a flat list of floats."""
    key = {"DirectionalInscatteringStartDistance_cm": "DirectionalInscatteringStartDistance"}
    out = {key.get(k, k): v for k, v in params.items() if key.get(k, k) in UNREAL_FIT}
    assert set(out) == set(UNREAL_FIT), sorted(out)
    return [float(x) for k in UNREAL_FIT for x in np.ravel(out[k])]


def test_fit_from_scene_study_and_sweep_give_the_same_unreal(swept, tmp_path, capsys):
    rows, truth_path = swept
    sweep_params = _unreal(json.loads(rows["ue4"]["model_parameters"]))

    out = tmp_path / "compare"
    assert (
        main(["compare", truth_path, "--model", "ue4", "--from-scene", "--out", str(out), "--no-figures"])
        == 1
    )  # Unreal fails: exit 1
    rep = json.loads((out / "metrics.json").read_text())
    capsys.readouterr()
    assert main(["fit", "--exr", truth_path]) == 0
    fit_doc = json.loads(capsys.readouterr().out)

    from fogref.study.unreal import run_study

    run_study(truth_path, tmp_path / "study", tmp_path / "renders", log=lambda *a: None)
    study_fit = json.loads((tmp_path / "study" / "fit.json").read_text())["fit"]
    study_rep = json.loads((tmp_path / "study" / "compare" / "metrics.json").read_text())

    paths = {
        "compare --from-scene": _unreal(rep["model"]["parameters"]),
        "fit": _unreal(fit_doc["unreal"]),
        "study fit.json": _unreal(study_fit["unreal"]),
        "study compare": _unreal(study_rep["model"]["parameters"]),
    }
    for where, p in paths.items():
        assert p == pytest.approx(sweep_params, rel=1e-12, abs=1e-12), where
    assert fit_doc["fit"]["directions_converged"] and fit_doc["fit"]["n_dirs"] >= 256
    rmse = rows["ue4"]["final.all.rmse"]
    assert rep["metrics"]["final"]["all"]["rmse"] == pytest.approx(rmse, rel=1e-12)
    assert study_rep["metrics"]["final"]["all"]["rmse"] == pytest.approx(rmse, rel=1e-12)
