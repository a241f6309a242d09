"""Tolerances of :func:`fogref.compare.check.check` and the verdict of an interval against one.

**Verdict** for a metric with tolerance ``tol`` (for the signed metrics the
tolerance bounds ``|bias|``): *pass* when the whole interval lies within the
tolerance, *fail* when it lies wholly outside, else *inconclusive*: the truth is
too noisy, or the image too small, to decide at this confidence.  Each of the
two wrong verdicts happens with probability at most ``(1 - confidence) / 2`` per
row.  :func:`fogref.compare.check.assert_fog_matches` treats inconclusive as a
failure unless told otherwise.
"""

from __future__ import annotations

from collections.abc import Mapping

from fogref.compare.intervals import METRICS, SIGNED
from fogref.errors import FogrefError, ParameterError, did_you_mean
from fogref.params import number

#: Default tolerances per part: metric -> largest acceptable value (``|value|`` for signed metrics).
DEFAULT_TOLERANCES: dict = {
    "T": {"rel_rmse": 0.01, "rel_bias": 0.005},
    "inscatter": {"rel_rmse": 0.05, "rel_bias": 0.02},
    "final": {"rel_rmse": 0.05, "rel_bias": 0.02},
    "composite": {"rel_rmse": 0.05, "rel_bias": 0.02},
}
#: The parts a tolerance may name.
PART_NAMES = ("T", "inscatter", "final", "composite")


def tolerance_table(tolerances, regions=None) -> dict:
    """Normalise ``tolerances`` to ``{(part, region|None): {metric: tol}}``.

    ``regions``: the region names that exist (default: any region is accepted).
    Unknown parts, regions and metrics are FogrefErrors with a did-you-mean; anything but a
    dict (or None) is a ParameterError naming ``tolerances`` and the accepted forms.

    >>> tolerance_table({"T/skyy": 0.1}, regions=("all", "surface", "sky"))
    Traceback (most recent call last):
    ...
    fogref.errors.FogrefError: tolerances: unknown region 'skyy' in 'T/skyy'; did you mean 'sky'? ...
    """
    table = {(p, None): dict(v) for p, v in DEFAULT_TOLERANCES.items()}
    if tolerances is not None and not isinstance(tolerances, Mapping):
        raise ParameterError(
            "api",
            "tolerances",
            f"expected a dict, got {type(tolerances).__name__} "
            f"{_short(tolerances)}: write {{'part': 0.05}} (rel_rmse), {{'part/region': "
            "0.05}} or {'part': {'rel_rmse': 0.05, 'bias': 0.01}}; None for the defaults",
        )
    for key, value in (tolerances or {}).items():
        part, _, region = str(key).partition("/")
        if part not in PART_NAMES:
            raise FogrefError(
                f"tolerances: unknown part '{part}' in '{key}'{did_you_mean(part, PART_NAMES)} "
                f"(parts: {', '.join(PART_NAMES)}; write 'part' or 'part/region')"
            )
        if region and regions is not None and region not in regions:
            raise FogrefError(
                f"tolerances: unknown region '{region}' in '{key}'{did_you_mean(region, regions)} "
                f"(regions: {', '.join(regions)})"
            )
        spec = value if isinstance(value, dict) else {"rel_rmse": value}
        clean = {}
        for metric, tol in spec.items():
            if metric not in METRICS:
                raise FogrefError(
                    f"tolerances['{key}']: unknown metric '{metric}'{did_you_mean(metric, METRICS)} "
                    f"(metrics: {', '.join(METRICS)})"
                )
            if tol is not None:  # a number (not a bool), finite, >= 0: the one validator
                tol = number(tol, f"tolerances['{key}']['{metric}']", source="api", lo=0.0)
            clean[metric] = tol
        k = (part, region or None)
        table[k] = {**table.get(k, {}), **clean} if region else {**table[(part, None)], **clean}
    return table


def user_set(tolerances) -> set:
    """The ``(part, region | None, metric)`` whose tolerance ``tolerances`` names; every other
    tolerance of :func:`tolerance_table` is one of :data:`DEFAULT_TOLERANCES`.  ``tolerances`` has
    passed :func:`tolerance_table`.

    >>> sorted(user_set({"T": 0.001, "inscatter/sky": {"rel_bias": None}}), key=str)
    [('T', None, 'rel_rmse'), ('inscatter', 'sky', 'rel_bias')]
    """
    named = set()
    for key, value in (tolerances or {}).items():
        part, _, region = str(key).partition("/")
        for metric in value if isinstance(value, dict) else ("rel_rmse",):
            named.add((part, region or None, metric))
    return named


def _short(x) -> str:
    text = repr(x)
    return text if len(text) <= 40 else text[:37] + "..."


def metric_verdict(metric: str, low: float, high: float, tol: float | None) -> str:
    """``pass``, ``fail`` or ``inconclusive`` for the interval ``[low, high]`` of ``metric``
    against ``tol`` (``|value|`` for the signed metrics); ``reported`` when ``tol`` is None.

    >>> metric_verdict("rel_rmse", 0.01, 0.03, 0.05), metric_verdict("bias", -0.2, 0.1, 0.15)
    ('pass', 'inconclusive')
    """
    if tol is None:
        return "reported"
    if metric in SIGNED:
        if -tol <= low and high <= tol:
            return "pass"
        return "fail" if (low > tol or high < -tol) else "inconclusive"
    if high <= tol:
        return "pass"
    return "fail" if low > tol else "inconclusive"
