"""``benchmarks/time_vs_error.py --reference-from``: a previous run is reused only when its
settings are this run's (the seeds, and so the stored errors, depend on all of them).

No render: the checks read the previous run's JSON and the scene list.  Deterministic
(no statistics): each mismatch must give its one-line error, a match must return the file.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.fixture(scope="module")
def tva():
    sys.path.insert(0, str(BENCH))
    try:
        import time_vs_error

        yield time_vs_error
    finally:
        sys.path.remove(str(BENCH))


def _args(**over):
    a = dict(res=(32, 18), ladder=[1, 4], ref_spp=512, max_depth=8, scenes=["zero_falloff"])
    a.update(over)
    return SimpleNamespace(**a)


def _write(tmp_path, tva, **cfg_over):
    import _scenes

    cfg = {
        "res": [32, 18],
        "ladder": [1, 4],
        "ref_spp": 512,
        "max_depth": 8,
        "repeats": {"1": tva.REPEATS[1], "4": tva.REPEATS[4]},
    }
    cfg.update(cfg_over)
    methods = {m: {} for m in _scenes.methods_for("zero_falloff")}
    path = tmp_path / "prev.json"
    path.write_text(json.dumps({"config": cfg, "scenes": {"zero_falloff": {"methods": methods}}}))
    return str(path)


def test_a_matching_previous_run_is_returned(tmp_path, tva):
    path = _write(tmp_path, tva)
    prev = tva.load_previous(path, _args())
    assert list(prev["scenes"]) == ["zero_falloff"]


@pytest.mark.parametrize(
    ("over", "key"),
    [
        ({"res": [96, 54]}, "res"),
        ({"ladder": [1, 4, 16]}, "ladder"),
        ({"ref_spp": 2048}, "ref_spp"),
        ({"max_depth": 16}, "max_depth"),
        ({"repeats": {"1": 1, "4": 5}}, "repeats"),
    ],
)
def test_each_differing_setting_is_refused_by_name(tmp_path, tva, over, key):
    path = _write(tmp_path, tva, **over)
    with pytest.raises(SystemExit, match=f"--reference-from {path}: its {key} is"):
        tva.load_previous(path, _args())


def test_a_missing_scene_or_other_methods_are_refused(tmp_path, tva):
    path = _write(tmp_path, tva)
    with pytest.raises(SystemExit, match="has no scene 'valley'"):
        tva.load_previous(path, _args(scenes=["valley"]))
    d = json.loads(Path(path).read_text())
    d["scenes"]["zero_falloff"]["methods"].pop("homogeneous")
    Path(path).write_text(json.dumps(d))
    with pytest.raises(SystemExit, match="the seeds would differ"):
        tva.load_previous(path, _args())


def test_a_file_that_is_not_a_run_is_refused(tmp_path, tva):
    bad = tmp_path / "x.json"
    bad.write_text("[1, 2")
    with pytest.raises(SystemExit, match="not a time_vs_error.json"):
        tva.load_previous(str(bad), _args())
    with pytest.raises(SystemExit, match="not a time_vs_error.json"):
        tva.load_previous(str(tmp_path / "absent.json"), _args())
