"""``check``: a statistically sound verdict on a fog model or an engine's images against a truth.

A ground truth is a Monte Carlo estimate: each pixel carries noise, and a
candidate that is *exactly* right still differs from it.  :func:`check` measures
the candidate's error with that noise taken out, gives a confidence interval for
every metric, and a verdict per part and region; :func:`assert_fog_matches` turns a
failing verdict into an ``AssertionError`` for a test suite.

The pieces, one module each:

* :mod:`fogref.compare.candidate`: what is compared (the parts ``T``, ``inscatter``,
  ``final``, ``composite`` of a model, an engine's images or another truth);
* :mod:`fogref.compare.regions`: where (``all``, ``surface``, ``sky``, distance bands);
* :mod:`fogref.compare.intervals`: the metrics ``rel_rmse``, ``rel_bias``, ``rmse``,
  ``bias`` and their confidence intervals (``method="noise"`` or ``"block"``);
* :mod:`fogref.compare.tolerances`: the tolerances and the verdict of an interval;
* :mod:`fogref.compare.results`: :class:`~fogref.compare.results.CheckResult`, its rows
  and files;
* :mod:`fogref.compare.synthetic`: a truth with known noise, for tests.

Why the intervals are built as they are: ``docs/design.md``, "check: statistics".

Examples
--------
>>> from fogref.compare.synthetic import synthetic_truth
>>> from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams
>>> model = UE4ExponentialHeightFog(UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2))
>>> truth = synthetic_truth(model, noise=0.02, seed=1)
>>> result = check(truth, model, tolerances={"inscatter": 0.02})
>>> result.verdict
'pass'
>>> result.row("inscatter", "all").verdict
'pass'
"""

from __future__ import annotations

import math
import os
import re
import tempfile
from functools import partial
from pathlib import Path

import numpy as np

from fogref.compare.candidate import as_truth, candidate_parts
from fogref.compare.intervals import (
    METRICS,
    SIGNED,
    block_bootstrap,
    block_sums,
    bootstrap_interval,
    estimates_from_sums,
    noise_sd,
    spp_to_decide,
)
from fogref.compare.paths import refuse_output_over_input
from fogref.compare.regions import region_masks
from fogref.compare.results import CheckResult, Row
from fogref.compare.tolerances import metric_verdict, tolerance_table, user_set
from fogref.errors import FogrefError
from fogref.gbuffer import Truth
from fogref.models.base import SKY_DISTANCE as DEFAULT_SKY_DISTANCE


def _finite(x) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def check(
    truth: Truth,
    candidate,
    tolerances: dict | None = None,
    *,
    parts=None,
    distance_bands=(100.0, 1000.0),
    confidence: float = 0.99,
    method: str = "noise",
    block: int = 8,
    n_boot: int = 2000,
    seed: int = 0,
    precision: str = "float32",
    sky_distance: float = DEFAULT_SKY_DISTANCE,
) -> CheckResult:
    """Check a fog model or an engine's images against a ground truth, with confidence intervals.

    Parameters
    ----------
    truth : Truth or path
        From :func:`fogref.gbuffer.load_truth` (or :func:`fogref.compare.synthetic.synthetic_truth`);
        a path (str or os.PathLike) to a ground-truth EXR is read with ``load_truth``.
    candidate : model, EngineImages, Truth or dict
        See :func:`fogref.compare.candidate.candidate_parts`.
    tolerances : dict, optional
        ``"part"`` or ``"part/region"`` -> a number (the ``rel_rmse`` tolerance) or a
        dict ``{metric: tolerance}``; ``None`` as a tolerance only reports the metric.
        Part keys apply to every region; ``part/region`` keys override them.  Defaults:
        :data:`fogref.compare.tolerances.DEFAULT_TOLERANCES` (relative, dimensionless: 0.05 is 5 %).
    parts : sequence of str, optional
        Parts to check (default: every part the candidate has).
    distance_bands : sequence of float
        Edges [m] of the distance-band regions, increasing, > 0; ``()`` for none.
    confidence : float
        Two-sided level of the intervals, in (0, 1); default 0.99.
    method : str
        ``"noise"`` (default): intervals from the truth's per-pixel noise, conditional
        on the view (see :func:`fogref.compare.intervals.noise_sd`); ``"block"``: block bootstrap over pixel
        blocks, which also counts the spatial variation of the candidate's error as
        uncertainty (the view as a sample of views) and covers noise that is
        correlated between pixels.
    block : int
        Side [px] of the bootstrap blocks (``method="block"``), >= 1; a region needs at
        least 2 blocks for ``method="block"`` (else its rows are ``empty``).
    n_boot : int
        Bootstrap replicates (``method="block"``), >= 100.
    seed : int
        Seed of the bootstrap (same seed, same intervals).
    precision, sky_distance :
        How a model is evaluated (see :func:`fogref.compare.candidate.evaluate_model`).

    Returns
    -------
    CheckResult
        Rows for every part, region and metric; ``result.verdict`` is ``pass``,
        ``fail`` or ``inconclusive``.

    Examples
    --------
    An inscatter 5 % too bright is caught; the exact one passes:

    >>> from fogref.compare.candidate import evaluate_model
    >>> from fogref.compare.synthetic import synthetic_truth
    >>> from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams
    >>> model = UE4ExponentialHeightFog(UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2))
    >>> truth = synthetic_truth(model, noise=0.02)
    >>> parts = evaluate_model(truth, model)
    >>> check(truth, {"T": parts["T"], "inscatter": 1.05 * parts["inscatter"]}).verdict
    'fail'
    >>> r = check(truth, {"inscatter": 1.05 * parts["inscatter"]}).row("inscatter", "all", "rel_bias")
    >>> round(r.estimate, 2), r.verdict
    (0.05, 'fail')
    >>> check(truth, parts).verdict
    'pass'
    """
    if not (isinstance(confidence, float | int) and 0 < confidence < 1):
        raise FogrefError(f"confidence: {confidence!r} must be in (0, 1)")
    if method not in ("noise", "block"):
        raise FogrefError(f"method: {method!r} must be 'noise' or 'block'")
    if not (isinstance(block, int) and block >= 1):
        raise FogrefError(f"block: {block!r} must be an integer >= 1 [px]")
    if not (isinstance(n_boot, int) and n_boot >= 100):
        raise FogrefError(f"n_boot: {n_boot!r} must be an integer >= 100")
    truth = as_truth(truth)
    regions = region_masks(truth, distance_bands)
    table = tolerance_table(tolerances, tuple(regions))
    cp = candidate_parts(truth, candidate, precision, sky_distance)
    wanted = list(cp.parts) if parts is None else [parts] if isinstance(parts, str) else list(parts)
    for p in wanted:
        if p not in cp.parts:
            raise FogrefError(f"part '{p}': {cp.name} has only {', '.join(cp.parts)}")
    alpha = (1.0 - confidence) / 2.0
    from scipy.special import ndtri  # the normal quantile, scipy.stats.norm.ppf's own, without scipy.stats

    z = float(ndtri(1.0 - alpha))
    z_one = float(ndtri(confidence))  # the one-sided upper bound where an RMSE's estimate is 0
    spp = int(truth.attrs.get("fogref.spp", 0) or 0)
    rows, errors = [], {}
    for k, part in enumerate(wanted):
        c, r, v, rv, ok = (
            cp.parts[part],
            cp.reference[part],
            cp.noise_cov[part],
            cp.ref_cov[part],
            cp.valid[part],
        )
        errors[part] = np.where(ok[..., None], c - r, 0.0)
        for j, (region, mask) in enumerate(regions.items()):
            m = mask & ok
            tols = {**table.get((part, None), {}), **table.get((part, region), {})}
            named = table.get((part, region), {})
            n_px = int(m.sum())
            if n_px == 0:
                for met in METRICS:
                    t = tols.get(met)
                    if named.get(met) is not None:
                        rows.append(
                            Row.without_estimate(
                                part,
                                region,
                                met,
                                t,
                                "fail",
                                0,
                                note=f"no pixels in region '{region}' for a tolerance set on it",
                            )
                        )
                    else:
                        rows.append(Row.without_estimate(part, region, met, t, "empty", 0))
                continue
            sums = block_sums(c, r, v, rv, m, block)
            total = sums.sum(0)
            point = estimates_from_sums(total)
            sums_point = {"_sq": total[0], "_power": total[1], "_err": total[2], "_ref": total[3]}
            sd = noise_sd(c, r, v, rv, m, spp, sums_point)
            # a reference indistinguishable from zero by its own noise has no relative error
            zero_ref = abs(float(total[3])) <= z * sd["_ref_sd"] or float(total[1]) <= 0
            if method == "block":
                reps = block_bootstrap(sums, n_boot, seed + 7919 * k + 104729 * j)
            for met in METRICS:
                tol = tols.get(met)
                if met.startswith("rel_") and zero_ref:
                    why = (
                        f"the reference {part} is zero over these pixels (or within its noise of zero): "
                        "no relative error exists; set an absolute tolerance (rmse, bias) instead"
                    )
                    rows.append(
                        Row.without_estimate(
                            part, region, met, tol, "reported" if tol is None else "fail", n_px, note=why
                        )
                    )
                    continue
                est = _finite(point[met])
                if method == "block":
                    rep = reps[met][np.isfinite(reps[met])]
                    ok_ci = est is not None and rep.size >= n_boot // 2 and len(sums) >= 2
                else:
                    ok_ci = est is not None and math.isfinite(sd[met])
                if not ok_ci:
                    rows.append(Row.without_estimate(part, region, met, tol, "empty", n_px))
                    continue
                zval = est / sd[met] if sd[met] > 0 else None
                if method == "block":
                    lo, hi = bootstrap_interval(est, rep, len(sums), alpha)
                else:
                    lo, hi = est - z * sd[met], est + z * sd[met]
                raw = est
                est, lo, hi = _own_scale(met, est, lo, hi, z_one * sd[met] if method == "noise" else None)
                verdict = metric_verdict(met, lo, hi, tol)
                to_decide = None
                if verdict == "inconclusive" and method == "noise" and spp >= 1:
                    sd_args = (c, r, v, rv, m, spp, sums_point)
                    to_decide = spp_to_decide(partial(_decided_at, met, raw, tol, sd_args, z, z_one), spp)
                rows.append(
                    Row(
                        part,
                        region,
                        met,
                        est,
                        lo,
                        hi,
                        tol,
                        verdict,
                        n_px,
                        z=_finite(zval) if zval is not None else None,
                        spp_to_decide=to_decide,
                    )
                )
    settings = {
        "method": method,
        "block": block,
        "n_boot": n_boot,
        "spp": spp,
        "seed": seed,
        "distance_bands_m": list(distance_bands or ()),
        "precision": precision,
        "sky_distance_m": sky_distance,
        "tolerances": {f"{p}{'/' + r if r else ''}": t for (p, r), t in table.items()},
        # which of them the caller set; the others are DEFAULT_TOLERANCES
        "tolerances_set": sorted(f"{p}{'/' + r if r else ''}:{m}" for p, r, m in user_set(tolerances)),
    }
    return CheckResult(rows, float(confidence), cp.name, str(truth.path), settings, errors, parts=cp)


def _decided_at(met: str, raw: float, tol: float, sd_args: tuple, z: float, z_one: float, n: int) -> bool:
    """Whether the interval of ``met`` around the estimate ``raw`` (squared scale for the RMSEs)
    decides against ``tol`` when the truth has ``n`` samples per pixel (noise method)."""
    sd_n = noise_sd(*sd_args, at_spp=n)[met]
    _, lo, hi = _own_scale(met, raw, raw - z * sd_n, raw + z * sd_n, z_one * sd_n)
    return metric_verdict(met, lo, hi, tol) != "inconclusive"


def _own_scale(met: str, est: float, lo: float, hi: float, floor: float | None) -> tuple:
    """An estimate and interval on the metric's own scale: the signed metrics as they are (None
    where not finite), the RMSEs from the squared scale (monotone), where the low end is <= 0
    one-sided, ``[0, upper]`` with ``upper`` at least ``floor`` (the noise method), never of
    zero width."""
    if met in SIGNED:
        return tuple(_finite(x) for x in (est, lo, hi))
    if lo <= 0 and floor is not None:
        hi = max(hi, floor)
    return tuple(math.sqrt(max(x, 0.0)) for x in (est, lo, hi))


def _default_errors_dir(result: CheckResult) -> Path:
    base = Path(os.environ.get("FOGREF_ERRORS_DIR") or Path(tempfile.gettempdir()) / "fogref-errors")
    name = re.sub(r"[^A-Za-z0-9_.-]+", "_", f"{Path(result.truth).stem}-{result.candidate}")[:80]
    return base / name


def assert_fog_matches(
    truth: Truth,
    candidate,
    tolerances: dict | None = None,
    *,
    inconclusive: str = "fail",
    errors_dir=None,
    **check_options,
) -> CheckResult:
    """Assert that ``candidate`` matches ``truth`` within ``tolerances``; return the :class:`CheckResult`.

    Runs :func:`check` (same arguments; ``truth`` may be a Truth or the path of its EXR).  On a
    failure it writes the error maps and
    ``check.json`` (:meth:`CheckResult.write`) and raises ``AssertionError`` whose
    message names each failing part and region, the metric's estimate and
    confidence interval against its tolerance, the confidence, and the folder of
    the error maps.

    Parameters
    ----------
    inconclusive : str
        What an inconclusive row does: ``"fail"`` (default: an unproven match is not
        a match; raise the sample count or the pixels: the interval narrows about as
        ``1/sqrt(spp * pixels)``; fogref's repository measures it in ``reports/check_power/``),
        ``"pass"``, or ``"skip"`` (``pytest.skip``).
    errors_dir : path, optional
        Where the maps go; default ``$FOGREF_ERRORS_DIR/<truth>-<candidate>``, else a
        folder under the system's temporary directory.

    Examples
    --------
    >>> from fogref.compare.synthetic import synthetic_truth
    >>> from fogref.models.ue4 import UE4ExponentialHeightFog, UE4FogParams
    >>> model = UE4ExponentialHeightFog(UE4FogParams(FogDensity=0.02, FogHeightFalloff=0.2))
    >>> truth = synthetic_truth(model, noise=0.02)
    >>> assert_fog_matches(truth, model).verdict
    'pass'
    """
    __tracebackhide__ = True  # pytest shows the caller's line and the message, not this body
    if inconclusive not in ("fail", "pass", "skip"):
        raise FogrefError(f"inconclusive: {inconclusive!r} must be 'fail', 'pass' or 'skip'")
    if errors_dir is not None:
        truth_file = truth if isinstance(truth, (str, os.PathLike)) else getattr(truth, "path", None)
        inputs = [("truth", truth_file)] + list(getattr(candidate, "sources", {}).items())
        outputs = [("errors_dir", Path(errors_dir) / f) for f in ("errors.exr", "check.json")]
        refuse_output_over_input(
            outputs, [(n, p) for n, p in inputs if isinstance(p, (str, os.PathLike))], "assert_fog_matches"
        )
    result = check(truth, candidate, tolerances, **check_options)
    failed = result.failures(include_inconclusive=False)
    undecided = [r for r in result.rows if r.verdict == "inconclusive"]
    if not failed and (not undecided or inconclusive == "pass"):
        return result
    if not failed and inconclusive == "skip":
        import pytest

        pytest.skip(f"fogref: {len(undecided)} inconclusive row(s), e.g. {undecided[0].describe()}")
    out = Path(errors_dir) if errors_dir is not None else _default_errors_dir(result)
    result.write(out)
    rows = failed + (undecided if inconclusive == "fail" else [])
    named = user_set(tolerances)
    set_here = [bool({(r.part, None, r.metric), (r.part, r.region, r.metric)} & named) for r in rows]
    yours = [r for r, s in zip(rows, set_here) if s]
    defaults = [r for r, s in zip(rows, set_here) if not s]
    lines = [
        f"fog does not match the truth: {result.candidate} vs {result.truth}",
        f"{len(failed)} row(s) fail, {len(undecided)} inconclusive, at {result.confidence:.0%} confidence "
        f"({result.method_text}):",
    ]
    for title, group in (
        ("against the tolerances you set", yours),
        (
            "against fogref's default tolerances, which you did not set (DEFAULT_TOLERANCES in "
            "fogref.compare.tolerances; set a part's metric to None to only report it)",
            defaults,
        ),
    ):
        if group:
            lines.append(f"{len(group)} {title}:")
            lines += ["  " + r.describe() + _how_much(r) for r in group[:12]]
            if len(group) > 12:
                lines.append(f"  ... and {len(group) - 12} more (check.json)")
    if undecided and inconclusive == "fail":
        lines.append(
            "inconclusive: the interval straddles the tolerance; render the truth with more samples "
            "or pixels (the interval narrows about as 1/sqrt(spp x pixels); help(fogref.check)), or pass "
            "inconclusive='pass'"
        )
    lines.append(
        f"error maps: {out / 'errors.exr'} (signed candidate - truth per part); rows: {out / 'check.json'}"
    )
    raise AssertionError("\n".join(lines))


def _how_much(r: Row) -> str:
    if r.tolerance is None or r.estimate is None or r.verdict != "fail":
        return ""
    bound = r.low if r.low > r.tolerance else -r.high
    return f"; at least {bound - r.tolerance:.3g} over the tolerance"
