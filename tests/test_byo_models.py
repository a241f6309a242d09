"""Custom fog models: ``--model module:Class`` and the ``fogref.models`` entry-point group."""

import json
import sys
import textwrap
from importlib.metadata import EntryPoint

import pytest
from truth_factory import write_truth_exr

from fogref.cli import main
from fogref.compare.check import check
from fogref.compare.synthetic import synthetic_truth
from fogref.errors import FogrefError
from fogref.mapping.build import build_model as build
from fogref.models import resolve
from fogref.models.resolve import resolve_model
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams

MODULE = '''
import numpy as np
from fogref.models.base import FogResult


class MyFog:
    """Homogeneous fog, grey: T = exp(-sigma d), inscatter = colour (1 - T)."""
    name = "my_fog"

    def __init__(self, sigma=0.002, colour=(0.2, 0.25, 0.3)):
        self.sigma, self.colour = sigma, np.asarray(colour, float)

    def evaluate(self, camera, positions, precision="float32"):
        d = np.linalg.norm(np.asarray(positions) - camera, axis=-1, keepdims=True)
        T = np.repeat(np.exp(-self.sigma * d), 3, -1)
        return FogResult(inscatter=self.colour * (1 - T), transmittance=T)

    @classmethod
    def from_physical(cls, physical):
        return cls(sigma=0.003)


class NotAModel:
    pass


class WrongSignature:
    def evaluate(self, camera):
        return None
'''


@pytest.fixture
def user_module(tmp_path, monkeypatch):
    (tmp_path / "my_engine_fog.py").write_text(textwrap.dedent(MODULE))
    monkeypatch.syspath_prepend(str(tmp_path))
    yield "my_engine_fog"
    sys.modules.pop("my_engine_fog", None)


def test_module_class_runs_through_compare_and_check(user_module, tmp_path):
    truth = synthetic_truth(UE4ExponentialHeightFog(UE4FogParams()), shape=(18, 32))
    exr = write_truth_exr(truth, tmp_path / "truth.exr")
    out = tmp_path / "report"
    # MyFog is not the truth's fog: the run completes and the verdict (exit 1) is fail
    assert (
        main(["compare", str(exr), "--model", f"{user_module}:MyFog", "--out", str(out), "--no-figures"]) == 1
    )
    metrics = json.loads((out / "metrics.json").read_text())
    assert "final" in metrics["metrics"] and metrics["check"]["verdict"] == "fail"
    model = build(f"{user_module}:MyFog")
    assert check(truth, model).row("T", "all").estimate > 0


def test_module_class_errors(user_module):
    with pytest.raises(FogrefError, match="no module named 'no_such_mod'"):
        resolve_model("no_such_mod:Fog")
    with pytest.raises(FogrefError, match="has no attribute 'MyFgo'; did you mean 'MyFog'"):
        resolve_model(f"{user_module}:MyFgo")
    with pytest.raises(FogrefError, match="NotAModel is not a fog model"):
        resolve_model(f"{user_module}:NotAModel")
    with pytest.raises(FogrefError, match="cannot be called as evaluate"):
        resolve_model(f"{user_module}:WrongSignature")
    with pytest.raises(FogrefError, match="did you mean 'unity'"):
        resolve_model("untiy")


def test_entry_point_group(user_module, monkeypatch):
    ep = EntryPoint(name="my_fog", value=f"{user_module}:MyFog", group="fogref.models")
    monkeypatch.setattr(resolve, "entry_point_models", lambda: {"my_fog": ep})
    assert resolve_model("my_fog").__name__ == "MyFog"
    assert "my_fog" in resolve.available_models()
