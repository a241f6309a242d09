"""What :func:`fogref.compare.check.check` returns: a :class:`Row` per part, region and metric,
gathered in a :class:`CheckResult` that summarises them and writes them to files."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fogref.atomic import write_text_atomic
from fogref.compare.intervals import SIGNED
from fogref.errors import FogrefError
from fogref.exrio import write_exr


@dataclass
class Row:
    """One metric of one part in one region.

    ``estimate`` and the interval ``[low, high]`` (at the result's confidence) are
    None when the region has no pixels or the metric is undefined there (e.g.
    ``rel_bias`` of a zero reference); ``tolerance`` is None when the metric is only
    reported; ``verdict`` is ``pass``, ``fail``, ``inconclusive``, ``reported`` (no
    tolerance) or ``empty`` (no pixels, and no tolerance set for this region by name).
    A relative metric whose reference is zero, or indistinguishable from zero by its
    noise, cannot meet a relative tolerance: with one set it is ``fail`` and ``note``
    says why (give an absolute ``rmse``/``bias`` tolerance instead).  So does a
    ``part/region`` tolerance over a region with no pixels.

    ``z``: the statistic in standard errors from a perfect candidate's 0 (the squared
    scale for the RMSEs), for coverage and power studies; ``note``: why a verdict is
    what it is, when that is not the interval against the tolerance.

    ``spp_to_decide``: for an inconclusive row (intervals from the truth's per-pixel noise),
    the truth's sample count per pixel at which the interval would decide it at the current
    estimate (the noise variances scale as 1/spp, the error pattern held); None otherwise, or
    when no count would (the estimate sits on the tolerance).
    """

    part: str
    region: str
    metric: str
    estimate: float | None
    low: float | None
    high: float | None
    tolerance: float | None
    verdict: str
    pixels: int
    z: float | None = None
    note: str = ""
    spp_to_decide: int | None = None

    @classmethod
    def without_estimate(
        cls,
        part: str,
        region: str,
        metric: str,
        tolerance: float | None,
        verdict: str,
        pixels: int,
        note: str = "",
    ) -> "Row":
        """A row whose metric has no value (no pixels, or a zero reference): estimate, low and high None.

        >>> Row.without_estimate("inscatter", "sky", "rmse", None, "empty", 0).describe()
        'inscatter/sky rmse: no pixels (0 px)'
        """
        return cls(part, region, metric, None, None, None, tolerance, verdict, pixels, note=note)

    def describe(self) -> str:
        """One line: ``inscatter/sky rel_bias = 0.0498 [0.0471, 0.0524] > tolerance 0.02: fail``;
        a region without pixels says ``no pixels``."""
        note = f"; {self.note}" if self.note else ""
        if self.spp_to_decide is not None:
            note += f"; decided at {self.spp_to_decide} spp at this estimate"
        if self.estimate is None:
            verdict = "no pixels" if self.verdict == "empty" else self.verdict
            return f"{self.part}/{self.region} {self.metric}: {verdict} ({self.pixels} px{note})"
        tol = (
            ""
            if self.tolerance is None
            else f", tolerance {'|x| ' if self.metric in SIGNED else ''}<= {self.tolerance:g}"
        )
        return (
            f"{self.part}/{self.region} {self.metric} = {self.estimate:.4g} "
            f"[{self.low:.4g}, {self.high:.4g}]{tol}: {self.verdict} ({self.pixels} px{note})"
        )


def _excess(r: Row) -> float:
    """How far a row is over its tolerance (estimate / tolerance); a row without an estimate
    (no pixels, a zero reference) counts as infinitely far, so it is listed first."""
    if r.estimate is None:
        return float("inf")
    return abs(r.estimate) / r.tolerance if r.tolerance else 0.0


@dataclass
class CheckResult:
    """What :func:`~fogref.compare.check.check` returns: one :class:`Row` per part, region and metric.

    ``verdict``: ``fail`` if any row fails, else ``inconclusive`` if any row is,
    else ``pass``.  ``confidence``: two-sided level of every interval.  ``errors``:
    part -> ``(H, W, 3)`` signed error ``candidate - truth`` (0 where undefined).
    ``parts``: the :class:`~fogref.compare.candidate.CandidateParts` that were compared (the
    model's evaluated images among them), so a report on the same run does not evaluate the
    model again (:func:`fogref.compare.report.compare` with ``check=``).
    """

    rows: list
    confidence: float
    candidate: str
    truth: str
    settings: dict
    errors: dict = field(default_factory=dict, repr=False)
    parts: object = field(default=None, repr=False, compare=False)

    @property
    def verdict(self) -> str:
        v = {r.verdict for r in self.rows}
        return "fail" if "fail" in v else "inconclusive" if "inconclusive" in v else "pass"

    @property
    def passed(self) -> bool:
        return self.verdict == "pass"

    @property
    def method_text(self) -> str:
        """How the intervals were made, in words."""
        if self.settings.get("method") == "block":
            b = self.settings["block"]
            return f"{b}x{b} px block bootstrap, truth noise removed"
        return "from the truth's per-pixel noise, truth noise removed"

    def row(self, part: str, region: str, metric: str = "rel_rmse") -> Row:
        """The row of ``part``/``region``/``metric``; FogrefError listing what exists."""
        for r in self.rows:
            if (r.part, r.region, r.metric) == (part, region, metric):
                return r
        have = sorted({f"{r.part}/{r.region}" for r in self.rows})
        raise FogrefError(f"no row {part}/{region} {metric} (rows: {', '.join(have)})")

    def failures(self, include_inconclusive: bool = True) -> list:
        """Rows that failed (and, by default, the inconclusive ones), worst first."""
        keep = ("fail", "inconclusive") if include_inconclusive else ("fail",)
        bad = [r for r in self.rows if r.verdict in keep]
        return sorted(bad, key=lambda r: (r.verdict != "fail", -_excess(r)))

    def summary(self) -> str:
        """A text table of every row with a tolerance, then the verdict."""
        lines = [
            f"check: {self.candidate} vs {self.truth} ({self.confidence:.0%} intervals, {self.method_text})"
        ]
        lines += ["  " + r.describe() for r in self.rows if r.tolerance is not None]
        lines.append(f"verdict: {self.verdict}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-ready (no NaN): settings, verdict and rows."""
        return {
            "truth": self.truth,
            "candidate": self.candidate,
            "confidence": self.confidence,
            "verdict": self.verdict,
            "settings": self.settings,
            "rows": [dict(vars(r)) for r in self.rows],
        }

    def write(self, out_dir) -> Path:
        """Write ``check.json`` and ``errors.exr`` (signed error per part) to ``out_dir``;
        return the EXR path."""
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        ch = {}
        for part, e in self.errors.items():
            for i, c in enumerate("RGB"):
                ch[f"{part}.error.{c}"] = e[..., i]
            ch[f"{part}.abs_error"] = np.abs(e).mean(-1)
        big = float(np.finfo(np.float32).max)
        write_exr(
            out / "errors.exr",
            {k: np.clip(v, -big, big) for k, v in ch.items()},
            {"fogref.check": {"truth": self.truth, "candidate": self.candidate}},
        )
        write_text_atomic(out / "check.json", json.dumps(self.to_dict(), indent=2, allow_nan=False) + "\n")
        return out / "errors.exr"
