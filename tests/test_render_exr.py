"""Ground-truth EXR: channels add up, same seed -> same pixels, header, atomic
writes, resume after interruption, and clear errors for bad input."""

import subprocess
import sys

import numpy as np
import pytest
from conftest import ROOT, SCENES

from fogref.errors import FogrefError, ParameterError
from fogref.exrio import read_exr

pytestmark = pytest.mark.render
SMALL = {"res": 12, "resy": 8}


@pytest.fixture(scope="module")
def rendered(tmp_path_factory, mitsuba):
    from fogref.render.render import render

    d = tmp_path_factory.mktemp("exr")
    a = render(SCENES / "valley.xml", d / "a.exr", spp=8, seed=3, overrides=SMALL, progress=False, pass_spp=4)
    b = render(SCENES / "valley.xml", d / "b.exr", spp=8, seed=3, overrides=SMALL, progress=False, pass_spp=4)
    return d, read_exr(a), read_exr(b)


def test_parts_add_up(rendered):
    _, (c, _), _ = rendered
    for ch in "RGB":
        total = c[f"T.{ch}"] * c[f"surface.{ch}"] + c[f"inscatter.{ch}"]
        assert np.allclose(c[ch], total, rtol=1e-5, atol=1e-6)
        assert np.allclose(c[f"inscatter.{ch}"], c[f"single.{ch}"] + c[f"multiple.{ch}"], rtol=1e-6, atol=1e-7)
    assert all(np.isfinite(v).all() for v in c.values())
    assert ((c["T.R"] > 0) & (c["T.R"] <= 1)).all()
    assert c["hit"].max() == 1 and c["hit"].min() == 0  # ground and sky both in view


def test_same_seed_same_pixels(rendered):
    _, (a, _), (b, _) = rendered
    for k in a:
        assert np.array_equal(a[k], b[k]), k


def test_header_records_everything(rendered):
    _, (_, attrs), _ = rendered
    for k in ("fogref.params", "fogref.spp", "fogref.seed", "fogref.variant", "fogref.version", "fogref.mitsuba"):
        assert k in attrs, k
    p = attrs["fogref.params"]
    assert p["medium"]["falloff"] == pytest.approx(0.0138629)
    assert p["sun"]["direction"][1] > 0 and p["sky"]["radiance"] == [0.2, 0.3, 0.5]
    assert attrs["fogref.spp"] == 8 and attrs["fogref.seed"] == 3  # JSON-decoded by read_exr


def test_no_temporary_files_left(rendered):
    d, _, _ = rendered
    assert sorted(p.name for p in d.iterdir()) == ["a.exr", "a.png", "b.exr", "b.png"]


def test_resume_after_interruption(tmp_path, mitsuba, monkeypatch):
    """Kill the render after its first pass; the rerun resumes and gives the same pixels."""
    import fogref.render.render as R

    ref = R.render(SCENES / "valley.xml", tmp_path / "ref.exr", spp=8, seed=1, overrides=SMALL,
                   progress=False, pass_spp=4)
    calls = {"n": 0}
    real = R._atomic_savez

    def dying_savez(path, **kw):
        real(path, **kw)
        calls["n"] += 1
        raise KeyboardInterrupt

    monkeypatch.setattr(R, "_atomic_savez", dying_savez)
    out = tmp_path / "x.exr"
    with pytest.raises(KeyboardInterrupt):
        R.render(SCENES / "valley.xml", out, spp=8, seed=1, overrides=SMALL, progress=False, pass_spp=4)
    assert not out.exists() and (tmp_path / "x.exr.partial.npz").exists()
    monkeypatch.setattr(R, "_atomic_savez", real)
    R.render(SCENES / "valley.xml", out, spp=8, seed=1, overrides=SMALL, progress=False, pass_spp=4)
    a, b = read_exr(ref)[0], read_exr(out)[0]
    assert np.array_equal(a["R"], b["R"]) and not (tmp_path / "x.exr.partial.npz").exists()


def test_out_of_range_parameter_is_named(tmp_path, mitsuba):
    from fogref.render.render import render

    bad = tmp_path / "bad.xml"
    bad.write_text((SCENES / "valley.xml").read_text().replace('<float name="g" value="$g"/>',
                                                               '<float name="g" value="1.5"/>'))
    with pytest.raises(ParameterError, match=r"bad.xml.*'g'.*1.5.*outside \[-0.999, 0.999\]"):
        render(bad, tmp_path / "o.exr", spp=1, overrides=SMALL, progress=False)
    with pytest.raises(ParameterError, match=r"'falloff'.*outside"):
        render(SCENES / "valley.xml", tmp_path / "o.exr", spp=1, overrides={**SMALL, "falloff": -1},
               progress=False)


def test_malformed_xml_and_cli_message(tmp_path, mitsuba):
    bad = tmp_path / "broken.xml"
    bad.write_text("<scene version='3.0.0'><integrator type='fogpath'>")
    from fogref.render.render import render

    with pytest.raises(FogrefError, match="broken.xml: malformed XML"):
        render(bad, tmp_path / "o.exr", spp=1, progress=False)
    r = subprocess.run([sys.executable, "-m", "fogref.cli", "render", str(bad), "--out", str(tmp_path / "o.exr")],
                       capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 2 and "broken.xml: malformed XML" in r.stderr and "Traceback" not in r.stderr
    r = subprocess.run([sys.executable, "-m", "fogref.cli", "render", str(SCENES / "valley.xml"), "--spp", "0",
                        "--out", str(tmp_path / "o.exr")], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 2 and "--spp" in r.stderr
