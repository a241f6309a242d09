"""The skeleton of a fogref HTML page: head, inlined CSS and JavaScript, the viewer, sections.

A page is one file with no external reference (no ``src``/``href`` to a URL, no font, no
script from a CDN): it opens from ``file://`` with the network off.  Figures are PNG data
URIs; the viewer's images are half-float data (:mod:`fogref.html.inline`).
"""

from __future__ import annotations

import json
from pathlib import Path

from fogref.atomic import write_text_atomic
from fogref.html.assets import CSS, JS
from fogref.html.inline import esc, png_data_uri

VIEWER_HTML = """
<h2>Viewer</h2>
<p class="fr-note">Move over the picture to read a pixel (click to pin it); <b>f</b> or space flips A/B.
Exposure and false colour act on the linear values (half floats, relative precision 4.9e-4).</p>
<div id="fr-viewer">
<div id="fr-controls">
<label for="fr-part">part</label><select id="fr-part"></select>
<label for="fr-a">A</label><select id="fr-a"><option value="truth" selected>truth</option>
<option value="model">candidate</option><option value="error">error (false colour)</option></select>
<label for="fr-b">B</label><select id="fr-b"><option value="truth">truth</option>
<option value="model" selected>candidate</option><option value="error">error (false colour)</option></select>
<label for="fr-mode">show</label><select id="fr-mode"><option value="single" selected>A or B (flip)</option>
<option value="flicker">flicker A/B</option><option value="swipe">swipe A | B</option></select>
<span></span><button id="fr-flip" type="button">flip A/B (f)</button>
<label for="fr-exposure">exposure [stops]</label><input id="fr-exposure" type="range" min="-12" max="12"
 step="0.25" value="0">
<span></span><span id="fr-exposure-text"></span>
<label for="fr-errmode">error colours</label><select id="fr-errmode"><option value="signed" selected>signed
 (diverging)</option><option value="abs">absolute (viridis)</option></select>
<label for="fr-errscale">error scale [stops]</label><input id="fr-errscale" type="range" min="-10" max="10"
 step="0.5" value="0">
<span></span><span id="fr-errscale-text"></span>
<label for="fr-region">region</label><select id="fr-region"></select>
<label for="fr-swipe">swipe</label><input id="fr-swipe" type="range" min="0" max="1000" value="500">
<span>showing</span><b id="fr-showing"></b>
</div>
<div id="fr-stage"><canvas id="fr-canvas" width="1" height="1"></canvas>
<div id="fr-bar"></div><div id="fr-barlabels"><span id="fr-bar-lo"></span><span id="fr-bar-mid"></span>
<span id="fr-bar-hi"></span></div>
<table class="fr-table" id="fr-readout"><thead><tr><th>pixel <span id="ro-xy"></span></th><th>R</th>
<th>G</th><th>B</th></tr></thead><tbody>
<tr><th>truth ± stderr</th><td id="ro-truth-R"></td><td id="ro-truth-G"></td><td id="ro-truth-B"></td></tr>
<tr><th>candidate</th><td id="ro-model-R"></td><td id="ro-model-G"></td><td id="ro-model-B"></td></tr>
<tr><th>error</th><td id="ro-error-R"></td><td id="ro-error-G"></td><td id="ro-error-B"></td></tr>
<tr><th>error / noise</th><td id="ro-z-R"></td><td id="ro-z-G"></td><td id="ro-z-B"></td></tr>
</tbody></table>
<p class="fr-note">units: <span id="ro-units"></span>; regions: <span id="ro-regions"></span>.
error / noise: the error in standard errors of the truth's noise (per channel, or the mean over RGB when
only that is at hand).</p>
</div></div>
"""


def figure(path_or_bytes, caption: str) -> str:
    """A PNG figure embedded as a data URI, with its caption."""
    return (
        f'<figure><img alt="{esc(caption)}" src="{png_data_uri(path_or_bytes)}">'
        f"<figcaption>{esc(caption)}</figcaption></figure>"
    )


def verdict_badge(verdict: str) -> str:
    """The verdict as a coloured badge."""
    return f'<span class="verdict verdict-{esc(verdict)}">{esc(verdict)}</span>'


def page(title: str, sections: list[str], viewer: dict | None = None) -> str:
    """A whole page: ``sections`` (HTML strings) after the viewer of ``viewer`` (the data of
    :func:`fogref.html.viewer.viewer_data`; None: no viewer)."""
    data = ""
    if viewer is not None:
        blob = json.dumps(viewer, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")
        data = f'<script type="application/json" id="fr-data">{blob}</script>'
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f'<meta name="viewport" content="width=device-width"><title>{esc(title)}</title>'
        f"<style>{CSS}</style></head><body>\n<h1>{esc(title)}</h1>\n"
        + (VIEWER_HTML + _scale_note(viewer) if viewer is not None else "")
        + "\n".join(sections)
        + "\n"
        + data
        + f"\n<script>{JS}</script>\n</body></html>\n"
    )


def _scale_note(viewer: dict) -> str:
    """What the viewer shows of a large image (:func:`fogref.html.viewer.block_scale`)."""
    k = int(viewer.get("scale", 1))
    if k == 1:
        return ""
    (W, H), w, h = viewer["full_size"], viewer["width"], viewer["height"]
    return (
        f'<p class="fr-note">The image is {W}×{H} px; to keep this page small the viewer shows '
        f"{w}×{h}: each of its pixels is the mean of {k}×{k} pixels, its ± the standard error of "
        f"that mean, its regions those of the block's centre pixel, a block compared where all its "
        f"pixels are; the last {H - h * k} rows and {W - w * k} columns are left out. The tables and "
        "figures use every pixel.</p>\n"
    )


def write_page(path, title: str, sections: list[str], viewer: dict | None = None) -> Path:
    """Write :func:`page` to ``path`` atomically; returns the path."""
    path = Path(path)
    write_text_atomic(path, page(title, sections, viewer))
    return path
