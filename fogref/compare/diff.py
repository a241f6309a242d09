"""``diff``: do two renders (or two images) differ beyond their noise?  No reference needed.

Either side is a ground truth (:func:`fogref.gbuffer.load_truth`, with its per-pixel
``stderr.*``/``corr.*`` noise) or a plain image (``.exr``, ``.png``, ``.hdr``; no noise).

* **Two truths** (two fogref versions, seeds or machines): :func:`fogref.compare.check.check`
  of B against A, the noise covariance of ``B - A`` being the sum of both truths'
  (:func:`fogref.compare.candidate.candidate_parts`), for the parts ``T``, ``inscatter`` and
  ``final``, in every region.  A row *differs* when its interval excludes "no difference":
  ``bias`` (mean of B - A) excludes 0, or the debiased ``rmse`` (noise removed) has a lower
  bound > 0.  The level is Bonferroni-corrected over the rows tested, so that ``confidence`` is
  that of the whole verdict: two renders of one scene with different seeds are ``equal within
  noise`` with probability about ``confidence``.
* **A truth and an image**: the same, with the truth's noise only (the image is the ``final``
  part).
* **Two images**: no noise is known; they are ``equal`` when ``max |B - A| <= tolerance``
  (absolute, in the images' units; default 0: bit-equal values).

Examples
--------
>>> import numpy as np
>>> a = np.zeros((2, 2, 3)); b = a.copy(); b[0, 0, 0] = 0.5
>>> r = diff_images(a, b)
>>> r.verdict, r.stats["max_abs"]
('differ', 0.5)
>>> diff_images(a, a).verdict
'equal'
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fogref.compare.check import check
from fogref.compare.foreign import read_image
from fogref.errors import FogrefError
from fogref.exrio import read_exr_header
from fogref.gbuffer import Truth, load_truth

#: Metrics a noisy diff tests, and how a row says "differ".
TESTED = ("bias", "rmse")
EQUAL_NOISY, EQUAL_EXACT, DIFFER = "equal within noise", "equal", "differ"


@dataclass
class DiffResult:
    """The verdict of :func:`diff`: ``"equal within noise"`` / ``"equal"`` / ``"differ"``.

    rows: the check rows tested (:class:`fogref.compare.results.Row`, at the corrected
    level), each with ``differs``; stats: for two images, ``rmse``, ``mean``, ``max_abs``
    [the images' units]; kinds: ``("truth"|"image", ...)`` of A and B; errors: part ->
    ``(H, W, 3)`` ``B - A``.
    """

    verdict: str
    a: str
    b: str
    kinds: tuple
    confidence: float
    row_confidence: float | None = None
    rows: list = field(default_factory=list)
    stats: dict = field(default_factory=dict)
    errors: dict = field(default_factory=dict, repr=False)

    @property
    def code(self) -> int:
        """Exit code: 0 equal, 1 differ."""
        return 1 if self.verdict == DIFFER else 0

    def lines(self) -> list[str]:
        """A text report: what was compared, each differing row (or the statistics), the verdict."""
        out = [f"diff: B = {self.b} ({self.kinds[1]}) against A = {self.a} ({self.kinds[0]})"]
        if self.rows:
            out.append(
                f"  {len(self.rows)} rows tested (bias, rmse of T, inscatter, final per region), "
                f"each at {self.row_confidence:.6g} (Bonferroni: {self.confidence:.0%} overall); "
                "noise of B - A: " + ("both truths'" if self.kinds == ("truth", "truth") else "the truth's")
            )
            bad = [r for r in self.rows if r.differs]
            out += ["  differs: " + r.describe().replace(": reported", "") for r in bad[:12]]
            if len(bad) > 12:
                out.append(f"  ... and {len(bad) - 12} more rows differ")
        for k, v in self.stats.items():
            out.append(f"  {k} = {v:.6g}")
        out.append(f"verdict: {self.verdict}")
        return out

    def to_dict(self) -> dict:
        """JSON-ready (no NaN)."""
        rows = [{**{k: v for k, v in vars(r).items()}, "differs": bool(r.differs)} for r in self.rows]
        return {
            "a": self.a,
            "b": self.b,
            "kinds": list(self.kinds),
            "verdict": self.verdict,
            "exit_code": self.code,
            "confidence": self.confidence,
            "row_confidence": self.row_confidence,
            "stats": self.stats,
            "rows": rows,
        }


def is_truth(path) -> bool:
    """True if ``path`` is an EXR written by ``fogref render`` (its header has ``fogref.schema``)."""
    if Path(path).suffix.lower() != ".exr":
        return False

    return "fogref.schema" in read_exr_header(path)[0]


def load_side(path, encoding: str = "auto", exposure: float = 1.0):
    """A ground truth (:class:`fogref.gbuffer.Truth`) or an image ``(H, W, 3)`` linear RGB."""
    if is_truth(path):
        return load_truth(path)

    return read_image(path, encoding=encoding, exposure=exposure)


def _row_differs(r) -> bool:
    if r.estimate is None or r.low is None:
        return False
    if r.metric == "bias":
        return r.low > 0 or r.high < 0
    return r.low > 0


def diff_images(a, b, tolerance: float = 0.0, names=("A", "B")) -> DiffResult:
    """Two noise-free images ``(H, W, 3)``: ``equal`` when ``max |b - a| <= tolerance`` [units, >= 0]."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    if a.shape != b.shape:
        raise FogrefError(f"{names[1]}: shape {b.shape[:2]} differs from {names[0]}'s {a.shape[:2]}")
    if not (math.isfinite(tolerance) and tolerance >= 0):
        raise FogrefError(f"tolerance: {tolerance!r} must be a finite number >= 0")
    e = b - a
    stats = {
        "rmse": float(np.sqrt(np.mean(e * e))),
        "mean": float(e.mean()),
        "max_abs": float(np.abs(e).max()),
    }
    verdict = EQUAL_EXACT if stats["max_abs"] <= tolerance else DIFFER
    return DiffResult(
        verdict, str(names[0]), str(names[1]), ("image", "image"), 1.0, stats=stats, errors={"final": e}
    )


def diff(
    a, b, *, confidence: float = 0.99, tolerance: float = 0.0, distance_bands=(100.0, 1000.0), names=None
) -> DiffResult:
    """Whether ``b`` differs from ``a`` beyond noise (see the module's docstring).

    ``a``, ``b``: :class:`~fogref.gbuffer.Truth` or ``(H, W, 3)`` images; ``confidence``: of the
    whole verdict, in (0, 1); ``tolerance``: for two images only [units]; ``distance_bands``
    [m]: the regions of :func:`fogref.compare.regions.region_masks`.
    """

    if not (isinstance(confidence, float | int) and 0 < confidence < 1):
        raise FogrefError(f"confidence: {confidence!r} must be in (0, 1)")
    ta, tb = isinstance(a, Truth), isinstance(b, Truth)
    names = names or (str(a.path) if ta else "A", str(b.path) if tb else "B")
    if not ta and not tb:
        return diff_images(a, b, tolerance, names)
    kinds = ("truth" if ta else "image", "truth" if tb else "image")
    if ta and tb:
        ref, cand, parts = a, b, ("T", "inscatter", "final")
    elif ta:
        ref, cand, parts = a, {"final": b}, ("final",)
    else:  # an image against a truth: B - A has the truth's noise; test A against B, flip the sign
        ref, cand, parts = b, {"final": a}, ("final",)
    n_regions = len(distance_bands or ()) + (4 if distance_bands else 3)
    n_tests = len(parts) * n_regions * len(TESTED)
    row_conf = 1.0 - (1.0 - confidence) / n_tests
    tol = {p: {m: None for m in ("rel_rmse", "rel_bias", "rmse", "bias")} for p in parts}
    res = check(ref, cand, tol, parts=list(parts), distance_bands=distance_bands, confidence=row_conf)
    rows = [r for r in res.rows if r.metric in TESTED]
    for r in rows:
        r.differs = _row_differs(r)
    errors = res.errors if ta else {k: -v for k, v in res.errors.items()}
    verdict = DIFFER if any(r.differs for r in rows) else EQUAL_NOISY
    return DiffResult(verdict, names[0], names[1], kinds, float(confidence), row_conf, rows, errors=errors)
