"""The viewer's data: every part of a truth, a candidate's error, noise and region masks.

:func:`viewer_data` gathers, per part, the truth (``(H, W, 3)``, half floats), its per-pixel
standard error, the candidate's signed error (candidate - truth; the viewer shows the
candidate as truth + error), the pixels where the part is compared and the noise of the
error (:mod:`fogref.compare.noise`, mean over RGB), from

* a truth (:class:`fogref.gbuffer.Truth`): the parts ``final``, ``T``, ``inscatter``,
  ``single``, ``multiple``, ``surface`` and their ``stderr.*`` channels, and
* a compare report folder's ``errors.exr`` (:data:`fogref.compare.report.ERRORS_EXR_LAYOUT`):
  the compared parts' errors (``transmittance`` is the truth's ``T``).

Without the truth (a committed report whose truth is not at hand) the compared parts'
references come from ``errors.exr`` and the noise stands in for the standard error.
Regions: :func:`fogref.compare.regions.region_masks` (``surface``, ``sky``, distance bands),
one bit each.

**Size.** A page embeds about 65 bytes per pixel (the 7 parts, their standard errors and 4
errors of a compare page).  Above :data:`MAX_PIXELS` the viewer shows block means instead: each
of its pixels is the mean of ``scale x scale`` pixels (the smallest integer ``scale`` that brings
the image to at most :data:`MAX_PIXELS`), its standard error ``sqrt(sum se^2) / scale^2`` (the
pixels' noise is independent), a block compared where all its pixels are, its regions those of
its centre pixel; the last ``H mod scale`` rows and ``W mod scale`` columns are left out.  The
page says so; the metrics, tables and figures use every pixel.  So a page stays under about
10 MB for any truth (a 1920x1080 compare page: ``docs/reports.md``).
"""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from fogref.compare.regions import region_masks
from fogref.display import TRUTH_PARTS, part_exposures
from fogref.exrio import read_exr
from fogref.gbuffer import COMPARED_PARTS, part_attribute, part_group
from fogref.html.inline import encode_half, encode_mask

#: A report's part name -> the truth's part it is compared with.
REPORT_TO_TRUTH = {**{p: part_group(p) for p in COMPARED_PARTS}, "composite": "final"}
UNITS_RADIANCE = "radiance (the scene's units)"
#: The most pixels the viewer embeds (480 x 270); larger images are shown as block means.
MAX_PIXELS = 480 * 270


def block_scale(shape) -> int:
    """The side of the pixel blocks the viewer averages for an image of ``shape`` ``(H, W)``: 1 up
    to :data:`MAX_PIXELS` pixels, else the smallest integer that brings it under.

    >>> block_scale((180, 320)), block_scale((1080, 1920)), block_scale((2160, 3840))
    (1, 4, 8)
    """
    h, w = int(shape[0]), int(shape[1])
    k = 1
    while (h // k) * (w // k) > MAX_PIXELS:
        k += 1
    return k


def block_mean(a, k: int) -> np.ndarray:
    """``(H // k, W // k, ...)`` means of the ``k x k`` blocks of ``a`` ``(H, W, ...)``.

    >>> block_mean(np.arange(16.0).reshape(4, 4), 2).tolist()
    [[2.5, 4.5], [10.5, 12.5]]
    """
    a = np.asarray(a, np.float64)
    if k == 1:
        return a
    h, w = a.shape[0] // k, a.shape[1] // k
    return a[: h * k, : w * k].reshape(h, k, w, k, *a.shape[2:]).mean(axis=(1, 3))


def block_stderr(se, k: int) -> np.ndarray:
    """The standard error of :func:`block_mean` from the pixels' ``se`` (independent noise):
    ``sqrt(sum se^2) / k^2``, i.e. ``sqrt(block_mean(se^2) / k^2)``.

    >>> float(block_stderr(np.full((2, 2), 0.4), 2)[0, 0])
    0.2
    """
    return np.sqrt(block_mean(np.square(np.asarray(se, np.float64)), k)) / k


def _units(part: str) -> str:
    return "1 (transmittance)" if part_attribute(part) == "transmittance" else UNITS_RADIANCE


def _rgb(ch: dict, prefix: str) -> np.ndarray:
    return np.stack([np.asarray(ch[f"{prefix}.{c}"], np.float64) for c in "RGB"], -1)


def error_limit(error, valid=None) -> float:
    """The false-colour limit of an error image ``(H, W, 3)``: the 99th percentile of
    ``|mean over RGB|`` over ``valid`` pixels [the part's units]; > 0 (1 for a zero error).

    >>> error_limit(np.full((2, 2, 3), -0.5))
    0.5
    """
    e = np.abs(np.asarray(error, np.float64).mean(-1))
    e = e[valid] if valid is not None else e.ravel()
    e = e[np.isfinite(e)]
    if e.size == 0:
        return 1.0
    lim = float(np.percentile(e, 99))
    lim = lim if lim > 0 else float(e.max())
    return lim if lim > 0 else 1.0


def _truth_part(truth, part: str) -> tuple[np.ndarray, np.ndarray | None]:
    return truth.part(part), truth.stderr.get(part_attribute(part))


def viewer_data(
    truth=None,
    report_dir=None,
    *,
    title: str = "",
    distance_bands=None,
    stderr: bool = True,
    channels: dict | None = None,
) -> dict:
    """The viewer's JSON-ready data (see the module's docstring); ``truth`` and/or a compare
    report folder ``report_dir`` (with ``errors.exr`` and ``metrics.json``).  ``distance_bands``
    [m]: the region bands (default: the report's check settings, else ``(100, 1000)``);
    ``stderr``: embed the truth's per-channel standard error (False: smaller page, the noise
    of the error only); ``channels``: ``errors.exr``'s channels given directly instead of a folder."""
    ch, meta = dict(channels or {}), {}
    if report_dir is not None:
        rd = Path(report_dir)
        ch = read_exr(rd / "errors.exr")[0]
        if (rd / "metrics.json").is_file():
            meta = json.loads((rd / "metrics.json").read_text())
    compared = [p for p in REPORT_TO_TRUTH if f"{p}.error.R" in ch]
    if distance_bands is None:
        settings = (meta.get("check") or {}).get("settings") or {}
        distance_bands = settings.get("distance_bands_m", (100.0, 1000.0))
    if truth is not None:
        shape, geo = truth.shape, truth
    elif ch:
        hit = np.asarray(ch["hit"]) > 0.5
        shape = hit.shape
        geo = SimpleNamespace(shape=shape, hit=hit, sky=~hit, distance=np.asarray(ch["distance"], np.float64))
    else:
        raise ValueError("viewer_data needs a truth or a report folder")
    k = block_scale(shape)
    mean = lambda a: block_mean(a, k)  # noqa: E731
    se = lambda a: block_stderr(a, k)  # noqa: E731
    layers = []

    def add(name, truth_img, std, rpart, exposure):
        layer = {
            "part": name,
            "units": _units(name),
            "exposure": exposure,
            "truth": encode_half(mean(truth_img)),
            "stderr": encode_half(se(std)) if std is not None else None,
            "error": None,
            "valid": None,
            "noise": None,
            "error_limit": 1.0,
            "compared_as": rpart,
        }
        if rpart is not None:
            err, valid = _rgb(ch, f"{rpart}.error"), np.asarray(ch[f"{rpart}.valid"]) > 0.5
            # the error's noise (mean over RGB): embedded only where the truth's stderr is not (a model's
            # or engine's error has the truth's noise plus a rounding floor of 4 ulp)
            noise = None if std is not None else encode_half(se(ch[f"{rpart}.noise"]))
            if k > 1:
                err, valid = mean(np.where(valid[..., None], err, 0.0)), mean(valid) == 1.0
            layer.update(
                error=encode_half(err),
                valid=encode_mask(valid),
                noise=noise,
                error_limit=error_limit(err, valid),
            )
        layers.append(layer)

    by_truth = {REPORT_TO_TRUTH[p]: p for p in compared if p != "composite"}
    shown = []  # (name, truth image, its noise, the report's part)
    if truth is not None:
        names = list(TRUTH_PARTS) + (["attenuated_surface"] if "attenuated_surface" in by_truth else [])
        for p in names:
            img, std = _truth_part(truth, p)
            shown.append((p, img, std, by_truth.get(p)))
        if "composite" in compared:
            shown.append(("composite", truth.final, truth.stderr.get("final"), "composite"))
    else:
        for p in compared:
            name = REPORT_TO_TRUTH[p] if p != "composite" else "composite"
            shown.append((name, _rgb(ch, f"{p}.reference"), np.asarray(ch[f"{p}.noise"], np.float64), p))
    exposures = part_exposures({name: img for name, img, _, _ in shown})
    for name, img, std, rpart in shown:
        add(name, img, std if stderr else None, rpart, exposures[name])
    regions = {k: v for k, v in region_masks(geo, tuple(distance_bands)).items() if k != "all"}
    bits = np.zeros(shape, np.uint8)
    for i, m in enumerate(regions.values()):
        bits |= np.asarray(m, bool).astype(np.uint8) << i
    h, w = shape
    c = k // 2
    return {
        "width": int(w // k),
        "height": int(h // k),
        "scale": k,
        "full_size": [int(w), int(h)],
        "title": title,
        "layers": layers,
        "regions": list(regions),
        "region_bits": encode_mask(bits[c::k, c::k][: h // k, : w // k]),
    }
