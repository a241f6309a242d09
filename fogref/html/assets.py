"""The CSS and JavaScript of fogref's HTML pages (inlined in every page: no file, no network).

The viewer's display transform is fogref's one transform, :func:`fogref.display.tone_map`:
``sRGB_OETF(clip(exposure * linear, 0, 1))`` (IEC 61966-2-1: ``12.92 x`` up to 0.0031308,
``1.055 x^(1/2.4) - 0.055`` above; non-finite values black), written to 8 bits as
``floor(255 v)`` like :func:`fogref.display.write_png`.  ``toneMap`` below is that formula;
``tests/test_html_browser.py`` checks that a probe pixel of the canvas equals Python's value.

Exposure: ``part exposure * 2^stops`` (the part's exposure is the report's:
:func:`fogref.display.exposure_for`, 1 for the transmittance).  False colour: the
signed error (mean over RGB, candidate - truth) on a diverging blue-white-red map with
symmetric limits ``±L``; the absolute error (mean over RGB of ``|error|``) on viridis over
``[0, L]``; ``L`` is the part's error limit (the 99th percentile of ``|error|``) times
``2^stops`` of the error-scale slider.  The colour bar under the canvas is labelled in the
part's units.
"""

from __future__ import annotations

CSS = """
body{font:14px/1.4 system-ui,sans-serif;margin:0 auto;max-width:1200px;padding:8px 16px;color:#222}
h1{font-size:20px}h2{font-size:17px;margin-top:28px;border-bottom:1px solid #ddd}h3{font-size:15px}
.fr-table{border-collapse:collapse;font-size:12px;margin:6px 0}
.fr-table td,.fr-table th{border:1px solid #ccc;padding:2px 6px;text-align:right;white-space:nowrap}
.fr-table th{background:#f3f3f3}.fr-wide{overflow-x:auto}
.v-fail td,.verdict-fail{background:#fdd}.v-pass td,.verdict-pass{background:#dfd}
.v-inconclusive td,.verdict-inconclusive{background:#ffd}
.verdict{display:inline-block;padding:2px 10px;border-radius:4px;font-weight:bold}
#fr-viewer{display:flex;flex-wrap:nowrap;gap:16px;align-items:flex-start}
#fr-controls{display:grid;grid-template-columns:max-content 210px;gap:4px 8px;align-content:start;
  font-size:13px}
#fr-stage{position:relative;flex:0 0 auto}
#fr-canvas{image-rendering:pixelated;cursor:crosshair;border:1px solid #888;display:block}
#fr-bar{height:12px;margin-top:4px;border:1px solid #888}
#fr-barlabels{display:flex;justify-content:space-between;font-size:12px}
#fr-readout td{font-family:ui-monospace,monospace}
#fr-stage .fr-note{max-width:720px}
figure{display:inline-block;margin:6px}figure img{max-width:560px;border:1px solid #ddd}
figcaption{font-size:12px;color:#555}
.fr-note{color:#555;font-size:12px}
"""

JS = r"""
(function () {
"use strict";
// half float -> float32 table (IEEE 754 binary16)
var H2F = new Float32Array(65536);
(function () {
  for (var h = 0; h < 65536; h++) {
    var s = (h & 0x8000) ? -1 : 1, e = (h >> 10) & 0x1f, m = h & 0x3ff;
    H2F[h] = e === 0 ? s * m * Math.pow(2, -24)
           : e === 31 ? (m ? NaN : s * Infinity) : s * (1 + m / 1024) * Math.pow(2, e - 15);
  }
})();
function bytesOf(b64) {
  var bin = atob(b64), out = new Uint8Array(bin.length);
  for (var i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
  return out;
}
function inflate(b64) {
  var stream = new Blob([bytesOf(b64)]).stream().pipeThrough(new DecompressionStream("deflate"));
  return new Response(stream).arrayBuffer().then(function (b) { return new Uint8Array(b); });
}
function decode(enc) {
  if (!enc) return Promise.resolve(null);
  return inflate(enc.data).then(function (raw) {
    if (enc.encoding === "u8-deflate") return {shape: enc.shape, data: raw};
    var n = raw.length / 2, out = new Float32Array(n), sc = enc.scale || 1;  // fogref.html.inline.encode_half
    for (var i = 0; i < n; i++) out[i] = H2F[raw[i] | (raw[n + i] << 8)] * sc;
    return {shape: enc.shape, data: out};
  });
}
// fogref.display.tone_map: sRGB OETF of clip(exposure * x, 0, 1); non-finite -> 0
function srgb(x) {
  if (!isFinite(x)) x = 0;
  x = Math.min(Math.max(x, 0), 1);
  return x <= 0.0031308 ? x * 12.92 : 1.055 * Math.pow(x, 1 / 2.4) - 0.055;
}
function toneMap(x, exposure) { return srgb(x * exposure); }
function to8(v) { return Math.floor(Math.min(Math.max(v, 0), 1) * 255); }
var DIVERGING = [[5,48,97],[33,102,172],[67,147,195],[146,197,222],[209,229,240],[247,247,247],
  [253,219,199],[244,165,130],[214,96,77],[178,24,43],[103,0,31]];
var VIRIDIS = [[68,1,84],[72,40,120],[62,74,137],[49,104,142],[38,130,142],[31,158,137],
  [53,183,121],[109,205,89],[180,222,44],[253,231,37]];
function lut(map, t) {
  t = Math.min(Math.max(isFinite(t) ? t : 0, 0), 1) * (map.length - 1);
  var i = Math.min(Math.floor(t), map.length - 2), f = t - i, a = map[i], b = map[i + 1];
  return [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2])];
}
window.fogrefToneMap = toneMap;

var el = document.getElementById("fr-data");
if (!el) { document.body.setAttribute("data-ready", "1"); return; }
var D = JSON.parse(el.textContent), W = D.width, H = D.height, N = W * H;
var $ = function (id) { return document.getElementById(id); };
var layers = {}, regionBits = null;
var state = {part: D.layers[0].part, a: "truth", b: "model", show: "a", mode: "single", stops: 0,
             errmode: "signed", errstops: 0, region: 0, swipe: 0.5, pin: null,
             hover: null};
var timer = null;

function layer() { return layers[state.part]; }
function has(which) {
  var L = layer();
  return which === "truth" || ((which === "model" || which === "error" || which === "z") && !!L.error);
}
function value(L, which, i, c) {  // linear value of channel c at pixel i
  var t = L.truth.data[3 * i + c];
  if (which === "truth") return t;
  var e = L.error ? L.error.data[3 * i + c] : NaN;
  return which === "model" ? t + e : e;
}
function stderrOf(L, i, c) {
  if (!L.stderr) return NaN;
  var k = L.stderr.shape[2];
  return L.stderr.data[k * i + (k === 1 ? 0 : c)];
}
function errLimit(L) { return (L.meta.error_limit || 1) * Math.pow(2, state.errstops); }
function colour(L, which, i) {
  if (which === "truth" || which === "model") {
    var ex = L.meta.exposure * Math.pow(2, state.stops);
    return [to8(toneMap(value(L, which, i, 0), ex)), to8(toneMap(value(L, which, i, 1), ex)),
            to8(toneMap(value(L, which, i, 2), ex))];
  }
  if (L.valid && !L.valid.data[i]) return [128, 128, 128];
  var e0 = value(L, "error", i, 0), e1 = value(L, "error", i, 1), e2 = value(L, "error", i, 2);
  var lim = errLimit(L);
  if (state.errmode === "abs") return lut(VIRIDIS, (Math.abs(e0) + Math.abs(e1) + Math.abs(e2)) / 3 / lim);
  return lut(DIVERGING, 0.5 + (e0 + e1 + e2) / 3 / lim / 2);
}
function shown() {
  if (state.mode === "single") return state.show === "a" ? state.a : state.b;
  return null;
}
function render() {
  var L = layer(), cv = $("fr-canvas"), ctx = cv.getContext("2d");
  var img = ctx.createImageData(W, H), px = img.data;
  var A = has(state.a) ? state.a : "truth", B = has(state.b) ? state.b : "truth";
  var cut = Math.round(state.swipe * W), one = shown(), bit = state.region;
  for (var y = 0; y < H; y++) for (var x = 0; x < W; x++) {
    var i = y * W + x, which;
    if (state.mode === "swipe") which = x < cut ? A : B;
    else which = (one === null ? (state.show === "a" ? A : B) : (has(one) ? one : "truth"));
    var c = colour(L, which, i);
    if (bit > 0 && regionBits && !(regionBits.data[i] & (1 << (bit - 1)))) c = [c[0] * 0.25, c[1] * 0.25,
      c[2] * 0.25 + 40];
    var o = 4 * i;
    px[o] = c[0]; px[o + 1] = c[1]; px[o + 2] = c[2]; px[o + 3] = 255;
  }
  if (state.mode === "swipe") for (var yy = 0; yy < H; yy++) {
    var q = 4 * (yy * W + Math.min(cut, W - 1)); px[q] = 255; px[q + 1] = 255; px[q + 2] = 0;
  }
  ctx.putImageData(img, 0, 0);
  var lim = errLimit(L), u = L.meta.units;
  $("fr-exposure-text").textContent = (L.meta.exposure * Math.pow(2, state.stops)).toPrecision(4) +
    " (" + (state.stops >= 0 ? "+" : "") + state.stops + " stops)";
  $("fr-errscale-text").textContent = "L = " + lim.toPrecision(3) + " " + u;
  var bar = $("fr-bar"), stops = [], map = state.errmode === "abs" ? VIRIDIS : DIVERGING;
  for (var k = 0; k < map.length; k++) stops.push("rgb(" + map[k].join(",") + ")");
  bar.style.background = "linear-gradient(to right," + stops.join(",") + ")";
  $("fr-bar-lo").textContent = state.errmode === "abs" ? "0" : (-lim).toPrecision(3);
  $("fr-bar-mid").textContent = (state.errmode === "abs" ? "|error|, mean over RGB [" :
    "error = candidate \u2212 truth, mean over RGB [") + u + "]" + (state.errmode === "abs" ? "" :
    " (red: too bright, blue: too dark)");
  $("fr-bar-hi").textContent = lim.toPrecision(3);
  $("fr-showing").textContent = state.mode === "swipe" ? A + " | " + B :
    (one === null ? (state.show === "a" ? A : B) : one);
  var at = state.pin || state.hover;  // the readout follows the part and the view
  if (at) readout(at[0], at[1]);
  var count = +(document.body.getAttribute("data-rendered") || 0) + 1;
  document.body.setAttribute("data-rendered", String(count));
}
function f(v) { return isFinite(v) ? v.toPrecision(5) : "\u2014"; }
function readout(x, y) {
  var L = layer(), i = y * W + x;
  $("ro-xy").textContent = "(" + x + ", " + y + ")";
  var names = [];
  for (var r = 0; r < D.regions.length; r++) {
    if (regionBits && (regionBits.data[i] & (1 << r))) names.push(D.regions[r]);
  }
  $("ro-regions").textContent = "all" + (names.length ? ", " + names.join(", ") : "");
  for (var c = 0; c < 3; c++) {
    var ch = "RGB"[c], t = value(L, "truth", i, c), s = stderrOf(L, i, c);
    $("ro-truth-" + ch).textContent = f(t) + (L.stderr ? " \u00b1 " + f(s) : "");
    $("ro-truth-" + ch).setAttribute("data-value", String(t));
    $("ro-truth-" + ch).setAttribute("data-stderr", String(s));
    var ok = !!L.error && !(L.valid && !L.valid.data[i]);
    $("ro-model-" + ch).textContent = ok ? f(value(L, "model", i, c)) : "\u2014";
    $("ro-error-" + ch).textContent = ok ? f(value(L, "error", i, c)) : "\u2014";
    var sd = L.noise ? L.noise.data[i] : stderrOf(L, i, c);
    $("ro-z-" + ch).textContent = ok && sd > 0 ? f(value(L, "error", i, c) / sd) : "\u2014";
  }
  $("ro-units").textContent = L.meta.units;
}
function populate() {
  var sel = $("fr-part");
  D.layers.forEach(function (l) {
    var o = document.createElement("option"); o.value = l.part;
    o.textContent = l.part + (l.error ? "" : " (truth only)"); sel.appendChild(o);
  });
  var rs = $("fr-region");
  ["all"].concat(D.regions).forEach(function (r, k) {
    var o = document.createElement("option"); o.value = String(k); o.textContent = r; rs.appendChild(o);
  });
}
function bind() {
  var on = function (id, ev, fn) { $(id).addEventListener(ev, function (e) { fn(e); render(); }); };
  on("fr-part", "change", function (e) { if (layers[e.target.value]) state.part = e.target.value; });
  on("fr-a", "change", function (e) { state.a = e.target.value; });
  on("fr-b", "change", function (e) { state.b = e.target.value; });
  on("fr-mode", "change", function (e) {
    state.mode = e.target.value;
    if (timer) { clearInterval(timer); timer = null; }
    if (state.mode === "flicker") timer = setInterval(function () {
      state.show = state.show === "a" ? "b" : "a"; render(); }, 600);
  });
  on("fr-flip", "click", function () {
    if (state.mode === "swipe") state.mode = "single", $("fr-mode").value = "single";
    state.show = state.show === "a" ? "b" : "a";
  });
  on("fr-exposure", "input", function (e) { state.stops = parseFloat(e.target.value); });
  on("fr-errmode", "change", function (e) { state.errmode = e.target.value; });
  on("fr-errscale", "input", function (e) { state.errstops = parseFloat(e.target.value); });
  on("fr-region", "change", function (e) { state.region = parseInt(e.target.value, 10); });
  on("fr-swipe", "input", function (e) { state.swipe = parseFloat(e.target.value) / 1000; });
  var cv = $("fr-canvas");
  var at = function (e) {
    var r = cv.getBoundingClientRect();
    return [Math.min(W - 1, Math.max(0, Math.floor((e.clientX - r.left) * W / r.width))),
            Math.min(H - 1, Math.max(0, Math.floor((e.clientY - r.top) * H / r.height)))];
  };
  cv.addEventListener("mousemove", function (e) {
    state.hover = at(e);
    if (!state.pin) readout(state.hover[0], state.hover[1]);
  });
  cv.addEventListener("click", function (e) {
    state.pin = state.pin ? null : at(e);
    var p = state.pin || at(e);
    readout(p[0], p[1]);
  });
  document.addEventListener("keydown", function (e) {
    if (e.key === "f" || e.key === " ") { e.preventDefault(); $("fr-flip").click(); }
  });
}
var jobs = [decode(D.region_bits).then(function (m) { regionBits = m; })];
D.layers.forEach(function (l) {
  var L = layers[l.part] = {part: l.part, meta: l, error: null};
  ["truth", "stderr", "error", "valid", "noise"].forEach(function (k) {
    jobs.push(decode(l[k]).then(function (a) { L[k] = a; }));
  });
});
window.fogrefViewer = {state: state, render: render, readout: readout, layers: layers, toneMap: toneMap};
Promise.all(jobs).then(function () {
  populate(); bind();
  var cv = $("fr-canvas"); cv.width = W; cv.height = H;
  cv.style.width = Math.min(4, Math.max(1, Math.floor(720 / W))) * W + "px";
  $("fr-bar").style.width = cv.style.width; $("fr-barlabels").style.width = cv.style.width;
  state.hover = [Math.floor(W / 2), Math.floor(H / 2)];
  render();
  document.body.setAttribute("data-ready", "1");
}).catch(function (err) { console.error("fogref viewer: " + err); });
})();
"""
