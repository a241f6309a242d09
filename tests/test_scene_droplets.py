"""``fogref scene --visibility V --droplets NAME``: fog from physical quantities, written, read
back and rendered.

The written scene is read back through the same path ``fogref render`` takes
(:func:`fogref.render.load.describe_scene` and :func:`fogref.media.params.medium_from_params`)
and checked against Koschmieder's law in closed form (the green channel's extinction is
``-ln(eps) / V`` to 1e-12) and against the droplets' Mie optics (the phase table and ``g``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fogref.cli import main
from fogref.mapping.droplet_fog import droplet_fog
from fogref.media.params import medium_from_params
from fogref.render.load import describe_scene


def cli(capsys, argv) -> tuple[int, str]:
    rc = main([str(a) for a in argv])
    err = capsys.readouterr().err
    if rc != 0:
        assert err.startswith("fogref: error: ") and err.count("\n") == 1, err
        assert "Traceback" not in err, err
    return rc, err


def _medium(path):
    desc = describe_scene(path)
    return medium_from_params(desc["medium"], str(path)), desc


@pytest.mark.parametrize("contrast, k", [(None, 3.912023005428146), ("0.05", 2.995732273553991)])
def test_droplet_scene(tmp_path, capsys, contrast, k):
    out = tmp_path / "fog.xml"
    args = ["scene", "--out", out, "--visibility", 300, "--droplets", "radiation"]
    rc, err = cli(capsys, args + (["--contrast", contrast] if contrast else []))
    assert rc == 0, err
    assert "drop the phase's shape" in err and "droplets/cm^3" in err  # the notes say what is kept
    m, desc = _medium(out)
    assert m.sigma_t[1] == pytest.approx(k / 300.0, rel=1e-12)
    assert max(m.sigma_t) / min(m.sigma_t) < 1.03 and min(m.albedo) > 0.9999
    ref = droplet_fog(300.0, "radiation").phase
    assert m.phase is not None and m.phase.label == "mie radiation fog"
    np.testing.assert_allclose(m.phase.values, ref.values, rtol=1e-8)
    assert m.g == pytest.approx(ref.mean_cosine, abs=1e-9)  # 9-digit values in the XML
    assert float(desc["medium"]["g"]) == pytest.approx(ref.mean_cosine, abs=1e-5)  # the XML's $g
    xml = out.read_text()
    assert '<phase type="fogtabphase">' in xml and "g above is its mean cosine" in xml


def test_visibility_alone_is_koschmieder(tmp_path, capsys):
    out = tmp_path / "k.xml"
    rc, err = cli(capsys, ["scene", "--out", out, "--visibility", 1000, "--g", 0.7])
    assert rc == 0, err
    m, _ = _medium(out)
    assert m.sigma_t == pytest.approx((-math.log(0.02) / 1000.0,) * 3, rel=1e-12)
    assert m.phase is None and m.g == 0.7


@pytest.mark.parametrize("phase, label", [("approx-mie", "approx-mie 6 um"), ("hg", None)])
def test_droplet_phases(tmp_path, capsys, phase, label):
    out = tmp_path / "p.xml"
    rc, err = cli(
        capsys, ["scene", "--out", out, "--droplets", "radiation", "--phase", phase, "--grey-extinction"]
    )
    assert rc == 0, err
    m, _ = _medium(out)
    assert m.sigma_t[0] == m.sigma_t[1] == m.sigma_t[2]
    if label is None:
        assert m.phase is None and m.g == pytest.approx(droplet_fog(None, "radiation").g, abs=1e-5)
    else:
        assert m.phase.label == label


@pytest.mark.parametrize(
    "extra, needle",
    [
        (["--visibility", 300, "--sigma-t", 0.01], "not with --sigma-t"),
        (["--droplets", "radiation", "--g", 0.5], "not with --g"),
        (["--droplets", "radiation", "--albedo", 0.8], "not with --albedo"),
        (["--visibility", 300, "--ue-fog-density", 0.02], "not with --ue-fog-density"),
        (["--phase", "mie"], "need --visibility or --droplets"),
        (["--contrast", 0.05], "need --visibility or --droplets"),
        (["--visibility", 0], "visibility"),
        (["--visibility", 300, "--contrast", 1.5], "contrast"),
        (["--droplets", "drizzle"], "droplets"),
        (["--visibility", 300, "--phase", "mie"], "'mie' needs droplets"),
    ],
)
def test_bad_input_is_one_line(tmp_path, capsys, extra, needle):
    out = tmp_path / "bad.xml"
    rc, err = cli(capsys, ["scene", "--out", out, *extra])
    assert rc == 2 and needle in err, err
    assert not out.exists()


def test_g_against_the_phase_is_refused():
    table = droplet_fog(None, "radiation").phase.as_params()
    with pytest.raises(Exception, match="parameter 'g'.*mean cosine"):
        medium_from_params({"g": 0.3, "phase": table}, "<t>")


@pytest.mark.render
def test_droplet_scene_renders(tmp_path, capsys, mitsuba):
    """The written scene renders through ``fogref render`` (its table, thousands of characters
    long, is not taken for a file name) and the truth's parameters carry the phase."""
    out = tmp_path / "fog.xml"
    assert cli(capsys, ["scene", "--out", out, "--visibility", 500, "--droplets", "radiation"])[0] == 0
    exr = tmp_path / "t.exr"
    rc, err = cli(
        capsys,
        ["render", out, "--spp", 2, "--set", "res=8", "--set", "resy=6", "--out", exr, "--quiet", "--no-png"],
    )
    assert rc == 0, err
    from fogref.gbuffer import load_truth

    truth = load_truth(exr)
    assert truth.params["medium"]["phase"]["label"] == "mie radiation fog"
    assert np.isfinite(truth.final).all() and truth.final.mean() > 0
    assert main(["info", str(exr)]) == 0  # the table is summarised, not printed
    info = capsys.readouterr().out
    assert '"phase": "fogtabphase \'mie radiation fog\', 752 cosines"' in info and len(info) < 20000


def test_hg_only_closed_forms_refuse_a_tabulated_phase():
    """The sky's projection onto the phase (the fits' sunsky term) is HG's: refused, one line."""
    from fogref.mapping.physical import PhysicalScene
    from fogref.mapping.views import sky_projection

    medium = droplet_fog(300.0, "radiation").medium_params()
    pf = PhysicalScene.from_params({"scene": "t.xml", "medium": medium})
    with pytest.raises(
        Exception, match="parameter 'phase': the sky's projection .* assumes a Henyey-Greenstein"
    ):
        sky_projection(pf, np.array([[0.0, 0.0, 1.0]]), sky=lambda w: np.ones((len(w), 3)))
