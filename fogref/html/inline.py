"""What an HTML page of fogref embeds, encoded inline: float images, masks, PNGs, tables.

Float images are stored as IEEE 754 half floats (numpy ``float16``: 11 significant bits,
a relative rounding error of at most 2^-11 ~ 4.9e-4, range ±65504), pixel-interleaved,
byte-shuffled (all low bytes, then all high bytes: what makes them compress) and
zlib-deflated, then base64-encoded.  The page's JavaScript inflates them with the
browser's own ``DecompressionStream("deflate")`` (no library, no network) and decodes the
half floats exactly, so exposure changes in the viewer act on the linear values, not on
a re-tone-mapped 8-bit picture.  An image whose largest magnitude is outside
[2^-6, 2^14] (radiance in photometric units, 1e5 and more; or 1e-13) is stored divided by
a power of two, ``scale``, that brings it to [1024, 2048), and decoded times ``scale``
(exactly: a power of two), so no value is clipped at the half range (±65504) or lost
below it; non-finite values are stored as 0.

Examples
--------
>>> import numpy as np
>>> img = np.array([[[0.0, 0.5, 2.0]]])
>>> enc = encode_half(img)
>>> enc["shape"], enc["encoding"]
([1, 1, 3], 'f16-shuffle-deflate')
>>> decode_half(enc).tolist()
[[[0.0, 0.5, 2.0]]]
>>> sun = encode_half(np.array([[[5.4e5, 1.0e5, 3.0]]]))        # beyond the half range: scaled
>>> sun["scale"], decode_half(sun).tolist()
(512.0, [[[540160.0, 99968.0, 3.0]]])
>>> decode_mask(encode_mask(np.array([[True, False]]))).tolist()
[[1, 0]]
>>> table_html(["a", "b"], [[1, "x<y"]]).split("<tbody>")[1]
'<tr><td>1</td><td>x&lt;y</td></tr></tbody></table>'
"""

from __future__ import annotations

import base64
import html
import io
import math
import zlib

import numpy as np
from PIL import Image

from fogref.display import TRUTH_PARTS, part_exposures, tone_map

#: Largest finite half float.
HALF_MAX = 65504.0
ENCODING = "f16-shuffle-deflate"
#: zlib level of the embedded arrays (0-9).  On a 320x180 truth's 14 RGB images, level 1 deflates
#: 7.6x faster than 9 (96 against 729 ms) into 4.9 % more bytes (``reports/benchmarks/compare_speed.md``).
DEFLATE_LEVEL = 1


def encode_half(image) -> dict:
    """``{"shape": [H, W, C], "encoding", "data": base64}`` of a float image ``(H, W)`` or ``(H, W, C)``.

    Domain: any real array (non-finite values -> 0).  ``scale`` (a power of two, 1 for a largest
    magnitude in [2^-6, 2^14]) divides the array before it is rounded to half precision; the
    decoded values (:func:`decode_half`) are the array to a relative 2^-11.
    """
    a = np.asarray(image, dtype=np.float64)
    if a.ndim == 2:
        a = a[..., None]
    a = np.where(np.isfinite(a), a, 0.0)
    top = float(np.abs(a).max(initial=0.0))
    scale = 1.0 if (top == 0.0 or 2.0**-6 <= top <= 2.0**14) else 2.0 ** (math.floor(math.log2(top)) - 10)
    h = np.clip(a / scale, -HALF_MAX, HALF_MAX).astype("<f2")
    raw = np.ascontiguousarray(h).reshape(-1).view(np.uint8).reshape(-1, 2).T.tobytes()
    out = {
        "shape": [int(s) for s in h.shape],
        "encoding": ENCODING,
        "data": base64.b64encode(zlib.compress(raw, DEFLATE_LEVEL)).decode("ascii"),
    }
    if scale != 1.0:
        out["scale"] = scale
    return out


def decode_half(enc: dict) -> np.ndarray:
    """The float64 array of :func:`encode_half`'s output (what the page's JavaScript decodes)."""
    raw = np.frombuffer(zlib.decompress(base64.b64decode(enc["data"])), np.uint8)
    n = raw.size // 2
    pairs = np.stack([raw[:n], raw[n:]], -1).reshape(-1)
    return pairs.view("<f2").astype(np.float64).reshape(enc["shape"]) * float(enc.get("scale", 1.0))


def encode_mask(mask) -> dict:
    """A ``(H, W)`` array of small non-negative integers (< 256: a bool mask or region bits)
    as ``{"shape", "encoding": "u8-deflate", "data"}``."""
    a = np.asarray(mask).astype(np.uint8)
    return {
        "shape": [int(s) for s in a.shape],
        "encoding": "u8-deflate",
        "data": base64.b64encode(zlib.compress(a.tobytes(), DEFLATE_LEVEL)).decode("ascii"),
    }


def decode_mask(enc: dict) -> np.ndarray:
    """The ``uint8`` array of :func:`encode_mask`'s output."""
    return np.frombuffer(zlib.decompress(base64.b64decode(enc["data"])), np.uint8).reshape(enc["shape"])


def png_data_uri(path_or_bytes) -> str:
    """A PNG file (path) or PNG bytes as a ``data:image/png;base64,...`` URI."""
    data = path_or_bytes if isinstance(path_or_bytes, bytes) else open(path_or_bytes, "rb").read()
    return "data:image/png;base64," + base64.b64encode(data).decode("ascii")


def thumbnail_uri(linear_rgb, exposure: float, width: int = 160) -> str:
    """A PNG thumbnail of a linear image, at most ``width`` px wide [px >= 1], tone-mapped by
    :func:`fogref.display.tone_map` at ``exposure``, as a data URI."""
    px = (np.clip(tone_map(linear_rgb, exposure), 0, 1) * 255).astype(np.uint8)
    return png_thumbnail_uri(px, width, smooth=True)


def png_thumbnail_uri(px, width: int, smooth: bool) -> str:
    """8-bit pixels ``px`` (H, W, 3) as a PNG data URI, shrunk to at most ``width`` px wide [px >= 1]
    (the height in proportion, >= 1) with bilinear (``smooth``) or nearest-neighbour filtering."""
    im = Image.fromarray(px)
    if im.width > width:
        resample = Image.BILINEAR if smooth else Image.NEAREST
        im = im.resize((int(width), max(1, round(im.height * width / im.width))), resample)
    buf = io.BytesIO()
    im.save(buf, format="PNG")
    return png_data_uri(buf.getvalue())


def esc(x) -> str:
    """``x`` as HTML text (``&``, ``<``, ``>``, quotes escaped)."""
    return html.escape(str(x), quote=True)


def fmt(v, digits: int = 4) -> str:
    """A number for a table: ``digits`` significant digits; None/NaN -> an em dash.

    >>> fmt(0.000123456), fmt(None), fmt(3), fmt(True)
    ('0.0001235', '—', '3', 'yes')
    """
    if v is None:
        return "—"
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return f"{float(v):.{digits}g}" if np.isfinite(v) else "—"
    return str(v)


def fmt_noise(v, noise, unit: str = "", max_decimals: int = 6) -> str:
    """``v ± noise`` rounded to the noise: the noise to one significant digit (two when it starts
    with 1), the value to the same decimal place (at most ``max_decimals``); a zero or missing noise
    gives ``v`` to 4 significant digits.

    >>> fmt_noise(101.49, 6.35, " %"), fmt_noise(-114.8, 15.2, " %"), fmt_noise(-1e-14, 7e-15, " %", 1)
    ('101 ± 6 %', '-115 ± 15 %', '0.0 ± 7e-15 %')
    >>> fmt_noise(0.144750137, 6.98e-05)
    '0.14475 ± 7e-05'
    """
    if v is None or not np.isfinite(v):
        return "—"
    if noise is None or not np.isfinite(noise) or noise <= 0:
        return f"{fmt(float(v))}{unit}"
    exp = int(np.floor(np.log10(noise)))
    digits = 2 if f"{noise:.1e}".startswith("1") else 1
    decimals = min(max(0, digits - 1 - exp), max_decimals)
    text = f"{float(v):.{decimals}f}"
    if float(text) == 0:
        text = text.lstrip("-")
    shown = f"{noise:.{digits}g}" if decimals == max_decimals else f"{noise:.{decimals}f}"
    return f"{text} ± {shown}{unit}"


def table_html(header, rows, classes=None) -> str:
    """An HTML table; ``rows``: sequences of cells (formatted with :func:`fmt`, escaped);
    ``classes``: one CSS class per row (e.g. its verdict), or None."""
    head = "".join(f"<th>{esc(h)}</th>" for h in header)
    body = []
    for i, row in enumerate(rows):
        cls = f' class="{esc(classes[i])}"' if classes and classes[i] else ""
        body.append(f"<tr{cls}>" + "".join(f"<td>{esc(fmt(c))}</td>" for c in row) + "</tr>")
    return f'<table class="fr-table"><thead><tr>{head}</tr></thead><tbody>{"".join(body)}</tbody></table>'


def check_rows_html(rows, confidence: float | None = None) -> str:
    """The rows of a :class:`~fogref.compare.results.CheckResult` (objects or dicts) as a table, each
    row classed by its verdict (``v-pass``, ``v-fail``, ``v-inconclusive``, ...)."""

    def get(r, k):
        return r.get(k) if isinstance(r, dict) else getattr(r, k)

    out, cls = [], []
    for r in rows:
        est, lo, hi = get(r, "estimate"), get(r, "low"), get(r, "high")
        ci = "—" if est is None or lo is None else f"[{fmt(lo)}, {fmt(hi)}]"
        out.append(
            [
                get(r, "part"),
                get(r, "region"),
                get(r, "metric"),
                est,
                ci,
                get(r, "tolerance"),
                get(r, "verdict"),
                get(r, "pixels"),
            ]
        )
        cls.append("v-" + str(get(r, "verdict")))
    level = "" if confidence is None else f" ({confidence:.0%})"
    return table_html(
        ["part", "region", "metric", "estimate", f"interval{level}", "tolerance", "verdict", "pixels"],
        out,
        cls,
    )


#: The CSS of notebook displays (a page has its own, :mod:`fogref.html.assets`).
NOTEBOOK_CSS = (
    "<style>.fr-table{border-collapse:collapse;font:12px sans-serif}.fr-table td,.fr-table th"
    "{border:1px solid #ccc;padding:2px 6px;text-align:right}.v-fail td{background:#fdd}"
    ".v-pass td{background:#dfd}.v-inconclusive td{background:#ffd}</style>"
)


def _diverging_thumb(error, width: int = 160) -> str:
    """A PNG thumbnail (data URI) of a signed error ``(H, W, 3)``: its mean over RGB on a blue-white-red
    map with symmetric limits (the 99th percentile of ``|error|``)."""
    e = np.asarray(error, np.float64).mean(-1)
    e = np.where(np.isfinite(e), e, 0.0)
    lim = float(np.percentile(np.abs(e), 99)) or float(np.abs(e).max()) or 1.0
    t = np.clip(e / lim, -1, 1)
    red = np.stack([np.ones_like(t), 1 - t, 1 - t], -1)
    blue = np.stack([1 + t, 1 + t, np.ones_like(t)], -1)
    rgb = np.where((t >= 0)[..., None], red, blue)
    return png_thumbnail_uri((np.clip(rgb, 0, 1) * 255).astype(np.uint8), width, smooth=False)


def _figures_row(items) -> str:
    fig = '<figure style="display:inline-block;margin:4px">'
    img = '<img style="image-rendering:pixelated;width:160px" src="{}">'
    cap = '<figcaption style="font-size:11px">{}</figcaption></figure>'
    return "<div>" + "".join(fig + img.format(u) + cap.format(esc(c)) for c, u in items) + "</div>"


def truth_html(truth) -> str:
    """A truth's notebook display: thumbnails of the parts the viewer shows
    (:data:`fogref.display.TRUTH_PARTS`: ``final``, ``T``, ``inscatter``, ``single``,
    ``multiple``, ``surface``) at the viewer's exposures (:func:`fogref.display.part_exposures`)
    and its provenance."""
    images = {p: truth.part(p) for p in TRUTH_PARTS}
    thumbs = [(p, thumbnail_uri(images[p], ex)) for p, ex in part_exposures(images).items()]
    h, w = truth.shape
    a = truth.attrs
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = truth.stderr["final"] / np.abs(truth.final)
    rel_noise = float(np.median(rel[np.isfinite(rel)])) if np.isfinite(rel).any() else None
    rows = [
        ["path", str(truth.path)],
        ["size", f"{w}×{h} px"],
        ["spp", truth.spp],
        ["seed", a.get("fogref.seed")],
        ["scene", a.get("fogref.scene")],
        ["median relative stderr of final", rel_noise],
        ["sun", "yes" if truth.sun_direction is not None else "no"],
    ]
    return (
        NOTEBOOK_CSS
        + "<div><b>fogref Truth</b>"
        + _figures_row(thumbs)
        + table_html(["", ""], rows)
        + "</div>"
    )


def check_html(result) -> str:
    """A :class:`~fogref.compare.results.CheckResult`'s notebook display: the verdict, thumbnails of the
    signed error of each part, and the rows with a tolerance (all rows when none has one)."""
    rows = [r for r in result.rows if r.tolerance is not None] or list(result.rows)
    thumbs = [(f"{p}: candidate − truth", _diverging_thumb(e)) for p, e in result.errors.items()]
    colour = {"pass": "#dfd", "fail": "#fdd"}.get(result.verdict, "#ffd")
    return (
        NOTEBOOK_CSS + f"<div><b>fogref check</b>: {esc(result.candidate)} vs {esc(result.truth)} "
        f'<span style="background:{colour};padding:1px 8px;font-weight:bold">'
        f"{esc(result.verdict)}</span> "
        f"({result.confidence:.0%} intervals, {esc(result.method_text)})"
        + _figures_row(thumbs)
        + check_rows_html(rows, result.confidence)
        + "</div>"
    )
