"""``fogtabphase`` samples exactly the density it evaluates: chi-square tests per phase function.

For each phase (a fog's Mie phase, the approximate Mie phase, and Mitsuba's own ``hg`` for
comparison), 2^20 directions are sampled for a random incoming direction; the cosine of each
with the ray's direction (computed from the returned vector, so the frame is tested too) is
binned on the table's own intervals, merged until every bin expects >= 20 samples, and the
counts are compared with the bins' exact probabilities (the integral of the piecewise-linear
density, float64; HG's closed-form CDF) by Pearson's chi-square test at alpha = 1e-4.  The
azimuth about the ray is tested the same way on 64 equal bins.  The test's power is shown on
a density 3 % off in the bins that hold the diffraction peak (the first 5 deg), which it
rejects.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from fogref.media import NP
from fogref.media.droplets import DROPLET_PRESETS
from fogref.media.mie import droplet_optics
from fogref.media.phase import TabulatedPhase, approx_mie_phase

N = 1 << 20
ALPHA = 1e-4


def _tables():
    mie = droplet_optics(DROPLET_PRESETS["radiation"]).grey_phase("mie radiation")
    approx = TabulatedPhase.from_function(lambda c: approx_mie_phase(NP, c, 6.0), label="approx-mie 6 um")
    return {"mie": mie, "approx-mie": approx}


def _sample(mi, plugin, seed):
    import drjit as dr

    rng = np.random.default_rng(seed)
    wi = rng.normal(size=3)
    wi /= np.linalg.norm(wi)
    mei = dr.zeros(mi.MediumInteraction3f, N)
    mei.wi = mi.Vector3f(*(float(x) for x in wi))
    mei.sh_frame = mi.Frame3f(mei.wi)
    sampler = mi.load_dict({"type": "independent"}, parallel=False)
    sampler.seed(seed, N)
    ctx = mi.PhaseFunctionContext(sampler)
    wo, w, pdf = plugin.sample(ctx, mei, sampler.next_1d(), sampler.next_2d())
    val, pdf2 = plugin.eval_pdf(ctx, mei, wo)
    local = mi.Frame3f(-mei.wi).to_local(wo)
    cos = np.array(local.z, dtype=np.float64)
    phi = np.arctan2(np.array(local.y), np.array(local.x))
    return cos, phi, np.array(w)[0], np.array(pdf), np.array(pdf2)


def _merged(edges_p):
    """Merge adjacent bins (edges, probabilities) until each expects >= 20 of N."""
    edges, probs = [edges_p[0][0]], []
    acc = 0.0
    for e, p in zip(edges_p[0][1:], edges_p[1]):
        acc += p
        if acc * N >= 20:
            edges.append(e)
            probs.append(acc)
            acc = 0.0
    if acc > 0:
        edges[-1] = edges_p[0][-1]
        probs[-1] += acc
    return np.array(edges), np.array(probs)


def _table_bins(table: TabulatedPhase, scale_peak: float = 1.0):
    c, v = np.asarray(table.cosines), np.asarray(table.values)
    p = 2 * math.pi * np.diff(c) * 0.5 * (v[1:] + v[:-1])
    if scale_peak != 1.0:  # a wrong density for the power check: the first 5 deg 3 % off
        peak = c[1:] > math.cos(math.radians(5.0))
        p[peak] *= scale_peak
        p /= p.sum()
    return _merged((c, p))


def _chi2(counts, probs):
    return stats.chisquare(counts, probs * counts.sum()).pvalue


@pytest.mark.parametrize("kind", ["mie", "approx-mie", "hg"])
def test_sampling_chi2(mitsuba, kind):
    mi = mitsuba
    if kind == "hg":
        g = 0.8
        plugin = mi.load_dict({"type": "hg", "g": g}, parallel=False)
        c = np.linspace(-1, 1, 4097)
        cdf = (1 - g * g) / (2 * g) * (1 / np.sqrt(1 + g * g - 2 * g * c) - 1 / (1 + g))
        edges, probs = _merged((c, np.diff(cdf) / cdf[-1]))
    else:
        table = _tables()[kind]
        plugin = mi.load_dict(table.as_params(), parallel=False)
        edges, probs = _table_bins(table)
    cos, phi, w, pdf, pdf2 = _sample(mi, plugin, seed=7)
    counts = np.histogram(np.clip(cos, -1, 1), edges)[0]
    assert counts.sum() == N
    p = _chi2(counts, probs)
    assert p > ALPHA, f"{kind}: sampled cosines differ from the density (chi2 p = {p:.2e})"
    counts_phi = np.histogram(phi, np.linspace(-math.pi, math.pi, 65))[0]
    assert _chi2(counts_phi, np.full(64, 1 / 64)) > ALPHA
    # exact sampling: weight 1 and the sample's pdf is eval_pdf's (to float32 rounding)
    assert np.all(w == 1.0)
    if kind != "hg":
        np.testing.assert_allclose(pdf, pdf2, rtol=2e-2)
        assert np.median(np.abs(pdf / pdf2 - 1)) < 1e-5


def test_chi2_power(mitsuba):
    """The same test rejects a density 3 % off within 5 deg of forward (Mie phase)."""
    table = _tables()["mie"]
    cos, *_ = _sample(mitsuba, mitsuba.load_dict(table.as_params(), parallel=False), seed=11)
    edges, probs = _table_bins(table, scale_peak=1.03)
    counts = np.histogram(np.clip(cos, -1, 1), edges)[0]
    assert _chi2(counts, probs) < ALPHA


def test_bad_table_is_one_line(mitsuba):
    with pytest.raises(Exception, match="fogtabphase: parameter 'cosines': must increase strictly"):
        mitsuba.load_dict({"type": "fogtabphase", "cosines": "-1, 0.5", "values": "1, 1"}, parallel=False)
