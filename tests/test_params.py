"""fogref.params, the one validator: what it accepts, what it refuses and what it says."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fogref import params as P
from fogref.errors import ParameterError

S = "src"


@pytest.mark.parametrize(
    "value, kw, want",
    [
        (0.5, {}, 0.5),
        ("0.5", {}, 0.5),
        (" 2 ", {}, 2.0),
        (np.float32(0.25), {}, 0.25),
        (np.int64(3), {}, 3.0),
        (np.array(1.5), {}, 1.5),
        (0, {"lo": 0}, 0.0),
        (1, {"hi": 1}, 1.0),
        ("1e-300", {"lo": 0, "lo_open": True}, 1e-300),
    ],
)
def test_number_accepts(value, kw, want):
    assert P.number(value, "x", source=S, **kw) == want


@pytest.mark.parametrize(
    "value, kw, words",
    [
        (True, {}, ["True", "bool"]),
        (np.bool_(False), {}, ["bool"]),
        (math.nan, {}, ["nan", "not finite"]),
        ("nan", {}, ["not finite"]),
        (math.inf, {}, ["inf", "not finite"]),
        ("1e400", {}, ["not finite"]),
        ("-inf", {"lo": 0}, ["not finite", "[0, inf)"]),
        ("abc", {}, ["'abc'", "does not parse"]),
        ("", {}, ["does not parse"]),
        (None, {}, ["expected a number"]),
        ([1.0], {}, ["expected a number"]),
        (0, {"lo": 0, "lo_open": True, "unit": "m"}, ["0 is outside (0, inf) m"]),
        (1, {"lo": -1, "hi": 1, "lo_open": True, "hi_open": True}, ["1 is outside (-1, 1)"]),
        (-0.5, {"lo": 0, "hi": 1, "unit": "1/m"}, ["-0.5 is outside [0, 1] 1/m"]),
        (1001, {"lo": 0, "hi": 1e3}, ["[0, 1000]"]),
    ],
)
def test_number_refuses_with_value_and_range(value, kw, words):
    with pytest.raises(ParameterError) as e:
        P.number(value, "falloff", source=S, **kw)
    msg = str(e.value)
    assert msg.startswith("src: parameter 'falloff': ") and "\n" not in msg
    for w in words:
        assert w in msg, (w, msg)


def test_integer():
    assert P.integer("64", "n", source=S, lo=1) == 64 and P.integer(36.0, "n", source=S) == 36
    assert P.integer("1e3", "n", source=S) == 1000 and P.integer(np.int32(5), "n", source=S) == 5
    for bad, word in (
        (True, "bool"),
        (16.7, "not an integer"),
        ("2.5", "not an integer"),
        ("x", "does not parse"),
        (math.nan, "not an integer"),
        (0, "0 is outside [1, 8]"),
        (9, "[1, 8]"),
    ):
        with pytest.raises(ParameterError, match=None) as e:
            P.integer(bad, "n", source=S, lo=1, hi=8)
        assert word in str(e.value), (bad, str(e.value))


def test_angle_has_degrees():
    assert P.angle("45", "sun_elevation", source=S, lo=-90, hi=90) == 45.0
    with pytest.raises(ParameterError, match=r"1000 is outside \[-90, 90\] deg"):
        P.angle(1000, "sun_elevation", source=S, lo=-90, hi=90)


def test_rgb_and_vector():
    assert P.rgb(0.5, "a", source=S) == (0.5, 0.5, 0.5) == P.rgb([0.5], "a", source=S)
    assert P.rgb("1, 2 3", "a", source=S) == (1.0, 2.0, 3.0) == P.rgb(np.array([1, 2, 3]), "a", source=S)
    assert P.vector((0, 2, 0), "c", source=S) == (0.0, 2.0, 0.0)
    for bad, word in (
        ([1, 2], "expected 1 or 3 numbers, got 2"),
        ([1, 2, 3, 4], "got 4"),
        ([0.1, math.nan, 0.1], "not finite"),
        ([0.1, -1, 0.1], "(0.1, -1, 0.1) is outside"),
        ([True, 1, 1], "bool"),
        ("a b c", "does not parse"),
        (None, "expected 1 or 3 numbers"),
    ):
        with pytest.raises(ParameterError) as e:
            P.rgb(bad, "albedo", source=S, lo=0, hi=1)
        assert word in str(e.value), (bad, str(e.value))
    with pytest.raises(ParameterError, match="expected 3 numbers, got 1"):
        P.vector(1.0, "c", source=S)


def test_choice_says_did_you_mean():
    assert P.choice("box", "f", ("centre", "box"), S) == "box"
    with pytest.raises(ParameterError, match=r"'center' is not one of centre, box; did you mean 'centre'\?"):
        P.choice("center", "f", ("centre", "box"), S)
    with pytest.raises(ParameterError, match="is not one of"):
        P.choice(None, "f", ("centre", "box"), S)


def test_path(tmp_path):
    (tmp_path / "a.xml").write_text("<scene/>")
    assert P.path(tmp_path / "a.xml", "scene", source=S, must_exist=True) == tmp_path / "a.xml"
    assert P.path(tmp_path, "d", source=S, must_exist=True, kind="dir") == tmp_path
    for bad, kw, word in (
        ("", {}, "empty path"),
        (3, {}, "expected a path"),
        (tmp_path / "b.xml", {"must_exist": True}, "no such file"),
        (tmp_path, {"must_exist": True}, "it is a folder"),
    ):
        with pytest.raises(ParameterError) as e:
            P.path(bad, "scene", source=S, **kw)
        assert word in str(e.value)


def test_format_range():
    assert P.format_range(0, 1) == "[0, 1]" and P.format_range(0, lo_open=True, unit="m") == "(0, inf) m"
    assert P.format_range(-0.999, 0.999) == "[-0.999, 0.999]" and P.format_range(1, 1 << 20) == "[1, 1048576]"


def test_the_old_doors_use_it():
    """The media's and compare's validators give fogref.params' messages."""
    from fogref.compare.report import check_sky_distance
    from fogref.media.medium import check_layer_param
    from fogref.media.protocol import number, profile_entry, rgb

    with pytest.raises(ParameterError, match=r"'layer0.falloff': -1 is outside \[0, 1000\]"):
        check_layer_param("s.xml", 0, "falloff", -1, 0.0, 1e3)
    with pytest.raises(ParameterError, match="'floor': nan is not finite"):
        P.number(math.nan, "floor", source="s.xml", lo=-1e7, hi=1e7)  # fog_medium's floor
    with pytest.raises(ParameterError, match="'g': True is not a number"):
        number({"g": True}, "g", 0.0, "s.xml")
    with pytest.raises(ParameterError, match="'sigma_t': 1e400|not finite"):
        rgb("1e400", "sigma_t", "s.xml", 0.0, 1e2)
    with pytest.raises(ParameterError, match=r"'sky_distance': inf is not finite"):
        check_sky_distance(math.inf)
    with pytest.raises(ParameterError, match="did you mean 'exponential'|is not one of"):
        profile_entry("exponental")
