"""What a person reads when a check fails, and the one-line summary of a truth.

* A failing ``assert_fog_matches`` in a user's pytest run reads like a pytest assertion: the
  user's line and the message, none of fogref's own source (its frames are hidden).
* The message says which failing rows are against the tolerances the user set and which are
  against fogref's defaults.
* ``repr(truth)`` is one short line, never the arrays.
"""

import re
import subprocess
import sys
import textwrap

from fogref.compare.check import assert_fog_matches
from fogref.compare.synthetic import synthetic_truth
from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams

MODEL = UE4ExponentialHeightFog(UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2))

#: a user's test: T 1 % too high against their tolerance of 0.1 %, inscatter 20 % too bright
#: against the default tolerances (which they never set)
USER_TEST = textwrap.dedent("""
    import fogref
    from fogref.compare.candidate import evaluate_model
    from fogref.compare.synthetic import synthetic_truth
    from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams


    def test_my_fog(tmp_path):
        model = UE4ExponentialHeightFog(UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2))
        truth = synthetic_truth(model, noise=0.01)
        parts = evaluate_model(truth, model)
        bad = {"T": 1.01 * parts["T"], "inscatter": 1.2 * parts["inscatter"]}
        fogref.assert_fog_matches(truth, bad, tolerances={"T": 0.001}, errors_dir=tmp_path)
    """)


def _bad_candidate():
    from fogref.compare.candidate import evaluate_model

    truth = synthetic_truth(MODEL, noise=0.01)
    parts = evaluate_model(truth, MODEL)
    return truth, {"T": 1.01 * parts["T"], "inscatter": 1.2 * parts["inscatter"]}


def test_a_failing_assertion_shows_the_users_line_and_the_message_not_fogrefs_source(tmp_path):
    (tmp_path / "test_user.py").write_text(USER_TEST)
    run = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "test_user.py"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,  # a hang only: the run takes a few seconds
    )
    out = run.stdout
    assert run.returncode == 1, out + run.stderr
    assert "fogref.assert_fog_matches(truth, bad" in out  # the user's line
    message = [ln for ln in out.splitlines() if ln.startswith("E ")]
    assert "AssertionError: fog does not match the truth" in message[0]
    # none of fogref's frames: neither its file nor its body
    assert "check.py" not in out and "raise AssertionError" not in out and "__tracebackhide__" not in out
    source = [ln for ln in out.splitlines() if ln.startswith("    ") and not ln.startswith("E ")]
    assert len(source) <= 12, out  # the user's test function, nothing else


def test_the_message_splits_the_tolerances_the_user_set_from_the_defaults(tmp_path):
    truth, bad = _bad_candidate()
    try:
        assert_fog_matches(truth, bad, tolerances={"T": 0.001}, errors_dir=tmp_path)
    except AssertionError as e:
        message = str(e)
    else:
        raise AssertionError("a 1 % error in T passed a 0.1 % tolerance")
    head, _, rest = message.partition("against the tolerances you set:\n")
    mine, _, defaults = rest.partition("against fogref's default tolerances")
    assert head and mine and defaults, message
    mine_rows = [ln for ln in mine.splitlines() if ln.startswith("  ")]
    default_rows = [ln for ln in defaults.splitlines() if ln.startswith("  ")]
    # the user set T's rel_rmse only: every row listed first is that one, in each region
    assert mine_rows and all(ln.startswith("  T/") and " rel_rmse = " in ln for ln in mine_rows), message
    assert "tolerance <= 0.001" in mine_rows[0]
    # T's rel_bias (default 0.005, the error is 1 %) and inscatter's rows (20 %) are the defaults':
    # 5 regions x (T rel_bias, inscatter rel_rmse and rel_bias, composite ...), 12 of them listed
    assert int(re.search(r"(\d+) against fogref's default tolerances", message)[1]) >= 15, message
    assert any(ln.startswith("  inscatter/") for ln in default_rows), message
    assert not any(ln.startswith("  inscatter/") for ln in mine_rows)
    # check.json says which tolerances the caller set
    import json

    assert json.loads((tmp_path / "check.json").read_text())["settings"]["tolerances_set"] == ["T:rel_rmse"]


def test_a_truths_repr_is_one_short_line():
    truth = synthetic_truth(MODEL, shape=(180, 320))
    text = repr(truth)
    assert "\n" not in text and len(text) < 200, text
    assert text.startswith("Truth(") and "320x180 px" in text and "array" not in text
