"""Compare game fog models with the path-traced ground truth.

Modules (one concept each):

* :mod:`~fogref.compare.metrics`       RMSE, relMSE, ΔE2000, HDR-FLIP, per-pixel maps
* :mod:`~fogref.compare.report`        ``compare()``: evaluate a model on a truth
  (:func:`fogref.gbuffer.load_truth`, the one reader), write the report
* :mod:`~fogref.compare.check`         ``check()``: verdicts with confidence intervals
* :mod:`~fogref.compare.foreign`       an engine's images (EXR, PNG, HDR) as a candidate
* :mod:`~fogref.compare.binning`       errors binned by distance or sun angle
* :mod:`~fogref.compare.plots`         heatmaps, side-by-side pictures, binned plots
* :mod:`~fogref.compare.gate`          verdicts as exit codes, ``--json``/``--junit`` files

The model is built by :func:`fogref.mapping.build.build_model` (names resolved by
:func:`fogref.models.resolve.resolve_model`).  The command line, ``fogref compare``, is
:mod:`fogref.cli.compare`.
"""

from __future__ import annotations

from fogref.compare.report import DEFAULT_SKY_DISTANCE, compare

__all__ = ["DEFAULT_SKY_DISTANCE", "compare"]
