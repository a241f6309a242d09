"""fogref.study.budget: the chain telescopes exactly; closed-form steps vanish where they should."""

import numpy as np
import pytest
from budget_truth import budget_scene, synthetic_pixels

from fogref.mapping import base_params
from fogref.study import budget as B


def test_budget_telescopes_exactly():
    pf = budget_scene()
    px, sky = synthetic_pixels(pf)
    lobe = base_params(pf, DirectionalInscatteringColor=(1, 1, 1), DirectionalInscatteringExponent=5.0)
    model = base_params(
        pf,
        DirectionalInscatteringColor=(1.4, 1.3, 1.1),
        DirectionalInscatteringExponent=14.0,
        DirectionalInscatteringStartDistance=3000.0,
        FogMaxOpacity=0.95,
        FogCutoffDistance=150000.0,
    )
    S = B.chain(px, sky, pf, lobe, model)
    assert len(S) == len(B.STEPS) + 1
    r = B.attribute(S, px.hit)
    assert r["telescoping_residual"] < 1e-12
    assert r["share_sum"] == pytest.approx(1.0, abs=1e-12)
    E = S[-1] - S[0]
    assert r["total"]["rmse"]["all"] == pytest.approx(np.sqrt(np.mean(E**2)))
    keys = [s["key"] for s in r["steps"]]
    assert keys[0] == "multiple" and keys[-1] == "float32"
    # every effect is switched on here, so the engine-setting steps are not zero
    by = {s["key"]: s for s in r["steps"]}
    assert by["start_distance"]["rmse"]["all"] > 0 and by["opacity_cutoff"]["rmse"]["all"] > 0
    # a second chain gives noise estimates; identical chains give zero noise
    B.add_noise(r, S, S, px.hit)
    assert all(s["noise"]["pixel_rms"] == 0 for s in r["steps"])


def test_steps_vanish_for_an_unshadowed_closed_form_truth():
    pf = budget_scene()
    px, _ = synthetic_pixels(pf)
    cf = B.closed_forms(px, pf)
    px.single = cf["sun_att"] + cf["sky"]  # no shadows, unoccluded sky
    px.multiple = np.zeros_like(px.multiple)
    px.final = px.attenuated_surface + px.single
    model = base_params(pf)
    S = B.chain(px, cf["sky"], pf, model, model)
    r = B.attribute(S, px.hit)
    by = {s["key"]: s for s in r["steps"]}
    for k in ("multiple", "shadows", "sky", "refit", "start_distance", "opacity_cutoff"):
        assert by[k]["rmse"]["all"] < 1e-12, k
    assert by["float32"]["rmse"]["all"] < 1e-5


def test_markdown_and_plot(tmp_path):
    pf = budget_scene()
    px, sky = synthetic_pixels(pf)
    p = base_params(pf, DirectionalInscatteringColor=(1, 1, 1))
    S = B.chain(px, sky, pf, p, p)
    r = B.add_noise(B.attribute(S, px.hit), S, S, px.hit)
    md = B.markdown(r)
    assert "| 9 | [h]" in md and "100.000000 %" in md
    B.plot(r, tmp_path / "b.png")
    assert (tmp_path / "b.png").stat().st_size > 1000


def _opaque_horizon(px, rows=3):
    """The top ``rows`` rows: T underflowed to 0, no sample reached the surface (undefined, written 0)."""
    px.transmittance = px.transmittance.copy()
    px.transmittance[:rows] = 0.0
    px.surface_coverage = px.surface_coverage.copy()
    px.surface_coverage[:rows] = 0.0
    px.surface = px.surface.copy()
    px.surface[:rows] = 1.0e20  # never used: a leftover where surface is undefined
    px.attenuated_surface = px.transmittance * np.where(px.surface_valid[..., None], px.surface, 0.0)
    px.final = px.attenuated_surface + px.single + px.multiple
    return px


def test_budget_and_what_if_exclude_undefined_surface_and_stay_finite():
    pf = budget_scene()
    px, sky = synthetic_pixels(pf, rel_stderr=0.01)
    px = _opaque_horizon(px)
    model = base_params(pf, FogMaxOpacity=0.9)
    S = B.chain(px, sky, pf, model, model)
    r = B.attribute(S, px.hit, px.surface_valid, B.chain_noise(px, 0.01 * sky, model, model))
    assert r["excluded_pixels"] == 3 * px.shape[1] and r["pixels"] == px.hit.size - r["excluded_pixels"]
    assert np.isfinite(r["total"]["rmse"]["all"]) and r["total"]["rmse"]["all"] < 1.0
    assert r["share_sum"] == pytest.approx(1.0, abs=1e-12)
    rows = B.what_if(px, model, {"opacity": {"FogMaxOpacity": 0.5}})
    assert all(np.isfinite(x["rmse"]) and x["rmse"] < 1.0 for x in rows)
    assert f"{r['excluded_pixels']} excluded" in B.markdown(r)


def test_every_step_carries_its_noise_from_the_stderr_channels():
    pf = budget_scene()
    px, sky = synthetic_pixels(pf, rel_stderr=0.02)
    model = base_params(pf)
    S = B.chain(px, sky, pf, model, model)
    noise = B.chain_noise(px, 0.02 * sky, model, model)
    r = B.attribute(S, px.hit, px.surface_valid, noise)
    by = {s["key"]: s for s in r["steps"]}
    np.testing.assert_allclose(
        by["multiple"]["rmse_noise_floor"], np.sqrt(np.mean(px.stderr["multiple"] ** 2))
    )
    assert by["sun_attenuation"]["rmse_noise_floor"] == 0.0  # closed forms only
    for s in r["steps"]:
        assert {"rmse_noise_floor", "rmse_stderr", "below_noise"} <= set(s), s["key"]
    assert "rmse_noise_floor" in r["total"] and "noise floor" in B.markdown(r)
    # the start-distance and opacity steps are exactly 0 here (settings off): below the noise
    assert by["start_distance"]["below_noise"] and by["opacity_cutoff"]["below_noise"]


# -- Shapley budget ------------------------------------------------------------------


def test_shapley_two_additive_independent_effects_known_answer():
    """v(C) = |sum_{k in C} d_k|^2 with orthogonal d_1, d_2: phi_k = |d_k|^2 exactly."""
    rng = np.random.default_rng(0)
    d1 = np.zeros(100)
    d1[:50] = rng.normal(size=50)
    d2 = np.zeros(100)
    d2[50:] = rng.normal(size=50)
    d = {"a": d1, "b": d2}

    def v(C):
        return float(np.sum(sum((d[k] for k in C), np.zeros(100)) ** 2))

    phi = B.shapley_values(v, ["a", "b"])
    assert phi["a"] == pytest.approx(np.sum(d1**2), rel=1e-12)
    assert phi["b"] == pytest.approx(np.sum(d2**2), rel=1e-12)
    assert phi["a"] + phi["b"] == pytest.approx(v({"a", "b"}), rel=1e-12)
    # not orthogonal: the interaction 2<d1, d2> is split equally
    d["b"] = d2 + 0.5 * d1
    phi = B.shapley_values(v, ["b", "a"])
    cross = float(np.dot(d1, d["b"]))
    assert phi["a"] == pytest.approx(np.sum(d1**2) + cross, rel=1e-12)
    assert phi["b"] == pytest.approx(np.sum(d["b"] ** 2) + cross, rel=1e-12)


def test_shapley_values_do_not_depend_on_player_order():
    rng = np.random.default_rng(1)
    vecs = {k: rng.normal(size=7) for k in "abcde"}
    target = rng.normal(size=7)

    def v(C):  # a non-additive game
        x = sum((vecs[k] for k in C), np.zeros(7))
        return float(np.sum((target - np.tanh(x)) ** 2) - np.sum((target - np.tanh(0 * x)) ** 2))

    ref = B.shapley_values(v, list("abcde"))
    for perm in (list("edcba"), list("cadeb")):
        got = B.shapley_values(v, perm)
        for k in ref:
            assert got[k] == pytest.approx(ref[k], rel=1e-12, abs=1e-12)
    assert sum(ref.values()) == pytest.approx(v(set("abcde")) - v(set()), rel=1e-12)


def _shapley_setup(rel_stderr=0.0):
    pf = budget_scene()
    px, sky = synthetic_pixels(pf, rel_stderr=rel_stderr)
    lobe = base_params(pf, DirectionalInscatteringColor=(1, 1, 1), DirectionalInscatteringExponent=5.0)
    model = base_params(
        pf,
        DirectionalInscatteringColor=(1.4, 1.3, 1.1),
        DirectionalInscatteringExponent=14.0,
        DirectionalInscatteringStartDistance=3000.0,
        FogMaxOpacity=0.95,
        FogCutoffDistance=150000.0,
    )
    parts = B.shapley_parts(px, sky, pf, B.unreal_engine(lobe, model))
    return pf, px, sky, lobe, model, parts


def test_shapley_budget_ends_are_truth_and_model_and_shares_sum_to_one():
    pf, px, sky, lobe, model, parts = _shapley_setup()
    S = B.chain(px, sky, pf, lobe, model)
    np.testing.assert_allclose(B.coalition_image(parts, ()), S[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(B.coalition_image(parts, B.EFFECTS), S[-1], rtol=0, atol=1e-12)
    sh = B.shapley_budget(parts, px.surface_valid, resamples=50)
    assert sh["share_sum"] == pytest.approx(1.0, abs=1e-12)
    E = S[-1] - S[0]
    assert sh["total_sq"] == pytest.approx(float(np.sum(E**2)), rel=1e-10)
    assert sh["coalitions"] == 2 ** len(B.EFFECTS)
    assert all(r["share_noise"] >= 0 for r in sh["effects"])
    assert sh["largest"] == max(sh["effects"], key=lambda r: r["share"])["key"]
    # order-independent: the same shares with the effects permuted
    perm = list(B.EFFECTS)[::-1]
    sh2 = B.shapley_budget(parts, px.surface_valid, effects=perm, resamples=0)
    for r in sh["effects"]:
        r2 = next(x for x in sh2["effects"] if x["key"] == r["key"])
        assert r2["share"] == pytest.approx(r["share"], rel=1e-10, abs=1e-12)


def test_shapley_budget_two_independent_effects_known_answer():
    """Only multiple scattering (left half) and float32 (the engine's T, right half) differ from the
    truth; they are additive and act on disjoint pixels, so each Shapley share is its own squared
    norm over E^2, and every other effect's share is 0."""
    pf, px, sky, lobe, model, parts = _shapley_setup()
    h, w = px.shape
    left = np.zeros((h, w, 1))
    left[:, : w // 2] = 1.0
    rng = np.random.default_rng(7)
    mult = rng.uniform(0, 0.05, (h, w, 3)) * left
    dT = rng.uniform(-0.05, 0.05, (h, w, 3)) * (1 - left)
    T0 = np.full((h, w, 3), 0.6)
    engine = {
        k: (T0 + dT * k[B.CONFIG_EFFECTS.index("float32")], parts["sun_render"], parts["sky_render"])
        for k in parts["engine"]
    }
    p = dict(
        parts,
        att=px.surface * T0,
        multiple=mult,
        sun_att=parts["sun_render"],
        sun_noatt=parts["sun_render"],
        sky_cf=parts["sky_render"],
        engine=engine,
    )
    p["final"] = p["att"] + parts["sun_render"] + parts["sky_render"] + mult
    valid = np.ones((h, w), bool)
    sh = B.shapley_budget(p, valid, resamples=20)
    by = {r["key"]: r for r in sh["effects"]}
    e_m, e_f = float(np.sum(mult**2)), float(np.sum((px.surface * dT) ** 2))
    assert sh["total_sq"] == pytest.approx(e_m + e_f, rel=1e-12)
    assert by["multiple"]["share"] == pytest.approx(e_m / (e_m + e_f), rel=1e-10)
    assert by["float32"]["share"] == pytest.approx(e_f / (e_m + e_f), rel=1e-10)
    for k in B.EFFECTS:
        if k not in ("multiple", "float32"):
            assert abs(by[k]["share"]) < 1e-12, k


def test_shapley_in_markdown_and_plot_first(tmp_path):
    pf, px, sky, lobe, model, parts = _shapley_setup()
    S = B.chain(px, sky, pf, lobe, model)
    r = B.add_noise(B.attribute(S, px.hit), S, S, px.hit)
    r["shapley"] = B.add_shapley_seed_noise(
        B.shapley_budget(parts, px.surface_valid, resamples=20),
        B.shapley_budget(parts, px.surface_valid, resamples=0),
    )
    md = B.markdown(r)
    assert md.index("Shapley budget") < md.index("Telescoping chain (second view)") < md.index("| 9 | [h]")
    assert md.count("Port vs engine (ue4): no runnable engine here.") == 1
    top = next(x for x in r["shapley"]["effects"] if x["key"] == r["shapley"]["largest"])
    assert f"Largest term: **[{top['effect']}] {top['label']}**" in md
    B.plot(r, tmp_path / "b.png")
    assert (tmp_path / "b.png").stat().st_size > 1000


def test_study_text_names_the_largest_shapley_term():
    from fogref.study.unreal_report import readme

    pf, px, sky, lobe, model, parts = _shapley_setup()
    S = B.chain(px, sky, pf, lobe, model)
    r = B.add_noise(B.attribute(S, px.hit), S, S, px.hit)
    r["shapley"] = B.shapley_budget(parts, px.surface_valid, resamples=20)
    r["inputs"] = {"resolution": [px.shape[1], px.shape[0]]}
    summary = {
        "fit": {"unreal_editor": {"Fog Density": 0.1}, "error": {"n_views": 10, "rel_rmse": 0.1}},
        "exr": "x.exr",
        "compare": None,
        "provenance": {
            "scene": "scenes/valley.xml",
            "spp": 4,
            "seed": 0,
            "truth": "x.exr",
            "pixel_filter": "centre",
        },
    }
    text = readme(summary, r)
    top = max(r["shapley"]["effects"], key=lambda e: e["share"])
    assert f"Largest Shapley term: **[{top['effect']}] {top['label']}**" in text
    assert text.index("Largest Shapley term") < text.index("Largest term of the telescoping chain")


def test_shapley_with_the_colour_refit_folded_into_the_lobe():
    pf, px, sky, lobe, model, parts = _shapley_setup()
    S = B.chain(px, sky, pf, lobe, model)
    np.testing.assert_allclose(B.coalition_image(parts, (), fixed=("refit",)), S[0], rtol=0, atol=1e-12)
    sh = B.shapley_budget(parts, px.surface_valid, effects=B.EFFECTS_COLOURS_IN_LOBE, resamples=10)
    assert [r["key"] for r in sh["effects"]] == list(B.EFFECTS_COLOURS_IN_LOBE) and sh["fixed"] == ["refit"]
    assert sh["share_sum"] == pytest.approx(1.0, abs=1e-12)
    assert sh["total_sq"] == pytest.approx(float(np.sum((S[-1] - S[0]) ** 2)), rel=1e-10)
    md = B.shapley_markdown(sh, "### variant")
    assert md.startswith("### variant") and "Held on the engine's side in every coalition: refit." in md


def _played_without_memo(parts, valid, effects, fixed):
    """The budget's game as it was played before coalitions shared their values: every coalition's
    image, its valid pixels' squared errors summed over the channels, per bootstrap block."""
    from fogref.study.budget.shapley import BOOTSTRAP_BLOCK

    h, w = valid.shape
    by, bx = np.arange(h)[:, None] // BOOTSTRAP_BLOCK, np.arange(w)[None, :] // BOOTSTRAP_BLOCK
    ids = (by * ((w + BOOTSTRAP_BLOCK - 1) // BOOTSTRAP_BLOCK) + bx)[valid]
    nb = int(ids.max()) + 1

    def per_block(C):
        d = B.coalition_image(parts, C, fixed) - parts["final"]
        return np.bincount(ids, weights=np.sum(d[valid] ** 2, axis=-1), minlength=nb)

    return B.shapley_values(per_block, effects)


@pytest.mark.parametrize("droplets", [False, True])
@pytest.mark.parametrize("case", ["ue4", "ue4, colours in the lobe", "godot"])
def test_effective_coalitions_have_the_coalitions_images_and_the_budget_is_unchanged(droplets, case):
    """Every coalition of the budget's effects (Unreal's nine, or with the colours in the lobe, or
    Godot's, which lacks Unreal's own, each with "phase" for a droplet fog): its effective
    coalition's image equals its own bit for bit (one ulp of one pixel is detected), with the
    surface undefined on some pixels; 212 of the 512 coalitions of the nine are distinct.  The
    budget, which plays each effective coalition once, gives every effect's value and share bit for
    bit as the game played coalition by coalition (written here as it was)."""
    import dataclasses
    import itertools

    from fogref.mapping import from_physical
    from fogref.mapping.droplet_fog import droplet_fog

    pf, px, sky, lobe, model, parts = _shapley_setup(rel_stderr=0.05)
    if droplets:
        pf = dataclasses.replace(
            pf, medium=dataclasses.replace(pf.medium, phase=droplet_fog(None, "radiation").phase)
        )
    if case == "godot":
        godot = from_physical("godot", pf)
        parts = B.shapley_parts(px, sky, pf, B.model_engine(godot))
        effects = list(B.applicable_effects(godot, None, pf))
    else:
        parts = B.shapley_parts(px, sky, pf, B.unreal_engine(lobe, model))
        effects = list(B.EFFECTS if case == "ue4" else B.EFFECTS_COLOURS_IN_LOBE) + list(B.phase_effect(pf))
    fixed = tuple(k for k in B.CONFIG_EFFECTS if k not in effects)  # as shapley_budget holds them
    valid = px.surface_valid.copy()
    valid[: valid.shape[0] // 3, ::3] = False
    distinct = set()
    for n in range(len(effects) + 1):
        for C in itertools.combinations(effects, n):
            key = B.effective_coalition(parts, C, fixed)
            distinct.add(key)
            got, want = B.coalition_image(parts, key, fixed), B.coalition_image(parts, C, fixed)
            assert got.tobytes() == want.tobytes(), (C, sorted(key))
    if case == "ue4" and not droplets:
        assert len(distinct) == 212
    sh = B.shapley_budget(parts, valid, effects, resamples=20)
    reference = _played_without_memo(parts, valid, effects, fixed)
    phi = np.stack([reference[k] for k in effects]).sum(1)  # the budget's sums, in its order
    for row, value in zip(sh["effects"], phi, strict=True):
        assert row["phi"] == float(value) and row["share"] == float(value / phi.sum()), row["key"]
