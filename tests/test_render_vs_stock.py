"""fogpath against stock Mitsuba on the same scenes (statistical, family-wise alpha = 1e-3).

Each comparison renders several independent runs per method and applies Welch's
t-test per 4x4-pixel block with a Bonferroni correction (tests/stats.py).
"""

import numpy as np
import pytest
from render_scenes import STOCK_SEED0, base_scene, grid_medium, heightfog, render_runs
from stats import assert_agree

pytestmark = pytest.mark.render
ALPHA = 1e-3
RUNS, SPP = 8, 32


PROFILES = {
    "exponential": {},
    "two-layer": {"density2": 0.5, "falloff2": 0.01, "height2": 10.0},
    "hdrp": {"profile": "hdrp", "base_height": 5.0, "falloff": 0.08},
    "powerlaw": {"profile": "powerlaw", "start": 2.0, "end": 30.0, "power": 2.0},
    # the radiation fog's tabulated Mie phase (fogtabphase), which stock volpath samples too
    "exponential, Mie phase": {"phase": "mie"},
    # a Local Fog Volume added to the fog in the box (stock: the majorant adds the volume's bound)
    "exponential + Local Fog Volume": {
        "lfv_centre": [0.0, 6.0, 15.0],
        "lfv_radius": 8.0,
        "lfv_density": 4.0,
        "lfv_falloff": 0.05,
        "lfv_height": 6.0,
    },
}


def _medium(mi, kw):
    if kw.get("phase") == "mie":
        from fogref.mapping.droplet_fog import droplet_fog

        table = droplet_fog(None, "radiation").phase
        kw = dict(kw, phase=table.as_params(), g=table.mean_cosine)
    if "lfv_centre" in kw:
        kw = dict(kw, lfv_centre=mi.ScalarPoint3f(*kw["lfv_centre"]))
    return heightfog(mi, **kw)


@pytest.mark.parametrize("profile", list(PROFILES), ids=list(PROFILES))
def test_fogpath_matches_volpath_with_heightfog(mitsuba, profile):
    """Same medium, two estimators: fogpath's analytic free flight vs stock
    volpath's delta tracking against the plugin's per-ray majorant."""
    mi = mitsuba
    kw = PROFILES[profile]
    a = mi.load_dict(
        base_scene(mi, {"type": "fogpath", "max_depth": 8, "rr_depth": 100}, _medium(mi, kw)), parallel=False
    )
    b = mi.load_dict(
        base_scene(mi, {"type": "volpath", "max_depth": 8, "rr_depth": 100}, _medium(mi, kw)), parallel=False
    )
    ra, rb = render_runs(mi, a, RUNS, SPP), render_runs(mi, b, RUNS, SPP, seed0=STOCK_SEED0)
    assert np.isfinite(np.stack(ra)).all() and np.isfinite(np.stack(rb)).all()
    assert_agree(ra, rb, block=4, alpha=ALPHA, what=f"fogpath vs volpath+heightfog ({profile})")


def test_fogpath_matches_volpath_with_builtin_grid(mitsuba):
    """Stock ``heterogeneous`` (has_spectral_extinction=false) on a 2x256x2 grid:
    its interpolation bias is ~(b h)^2/8 ~ 1e-5 relative, far below the noise."""
    mi = mitsuba
    a = mi.load_dict(
        base_scene(mi, {"type": "fogpath", "max_depth": 8, "rr_depth": 100}, heightfog(mi)), parallel=False
    )
    b = mi.load_dict(
        base_scene(mi, {"type": "volpath", "max_depth": 8, "rr_depth": 100}, grid_medium(mi)), parallel=False
    )
    ra, rb = render_runs(mi, a, RUNS, SPP), render_runs(mi, b, RUNS, SPP, seed0=STOCK_SEED0)
    assert_agree(ra, rb, block=4, alpha=ALPHA, what="fogpath vs volpath+heterogeneous grid")


def test_zero_falloff_matches_stock_homogeneous(mitsuba):
    """falloff = 0 inside the box is a homogeneous medium: compare with stock
    ``homogeneous`` as the interior of a null-BSDF cube around the camera."""
    mi = mitsuba
    T = mi.ScalarTransform4f()
    lo, hi = np.array([-60.0, -1.0, -60.0]), np.array([60.0, 40.0, 60.0])
    homog = mi.load_dict(
        {"type": "homogeneous", "sigma_t": 0.03, "albedo": 0.9, "phase": {"type": "hg", "g": 0.5}},
        parallel=False,
    )
    sb = base_scene(mi, {"type": "volpath", "max_depth": 64, "rr_depth": 100}, homog)
    sb["fogbox"] = {
        "type": "cube",
        "to_world": T.translate(((lo + hi) / 2).tolist()).scale(((hi - lo) / 2).tolist()),
        "bsdf": {"type": "null"},
        "interior": homog,
    }
    sa = base_scene(mi, {"type": "fogpath", "max_depth": 8, "rr_depth": 100}, heightfog(mi, falloff=0.0))
    # volpath counts null-interface crossings as bounces; give it room (max_depth 64)
    # and compare with fogpath at max_depth 8, which both converge to within noise here.
    ra = render_runs(mi, mi.load_dict(sa, parallel=False), RUNS, SPP)
    rb = render_runs(mi, mi.load_dict(sb, parallel=False), RUNS, SPP, seed0=STOCK_SEED0)
    assert_agree(ra, rb, block=4, alpha=ALPHA, what="fogpath(falloff=0) vs homogeneous")


def test_fogpath_matches_volpath_with_envmap_sky(mitsuba):
    """An ``envmap`` sky (brighter toward the zenith, warm near the horizon) plus
    the sun: exercises NEE + MIS on a non-uniform infinite emitter."""
    mi = mitsuba
    h, w = 16, 32
    el = np.linspace(np.pi / 2, -np.pi / 2, h)[:, None, None]
    sky = np.where(
        el > 0, np.array([0.2, 0.3, 0.6]) * (0.4 + np.sin(el)) + np.array([0.3, 0.2, 0.1]) * np.cos(el), 0.05
    )
    bitmap = mi.Bitmap(np.ascontiguousarray(np.broadcast_to(sky, (h, w, 3)), dtype=np.float32))
    runs = {}
    for integ in ("fogpath", "volpath"):
        d = base_scene(mi, {"type": integ, "max_depth": 8, "rr_depth": 100}, heightfog(mi), sky=False)
        d["sky"] = {"type": "envmap", "bitmap": bitmap}
        seed0 = 1000 if integ == "fogpath" else STOCK_SEED0  # the stock method's own seeds
        runs[integ] = render_runs(mi, mi.load_dict(d, parallel=False), RUNS, SPP, seed0=seed0)
    assert_agree(
        runs["fogpath"], runs["volpath"], block=4, alpha=ALPHA, what="fogpath vs volpath, envmap sky"
    )
