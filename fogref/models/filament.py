"""Google Filament height fog (``View::FogOptions``).

Follows Filament 1.53.4 (tag ``v1.53.4``): ``shaders/src/surface_fog.fs`` (the "Real-time
Atmospheric Effects in Games (Carsten Wenzel)" version, ``exp`` based) and
``PerViewUniforms::prepareFog`` (CPU: ``fogDensity = (density, -heightFalloff (camera.y -
height), density exp(-heightFalloff (camera.y - height)))``); the same GLSL is in the
1.53.4 web build's ``filament.wasm`` (gltfio's ubershaders).  Held to that web build (npm
``filament`` 1.53.4) in headless Chromium by ``tests/test_web_filament.py``: unlit quads, sun
term on, the default 8-bit canvas (``output="canvas"``) within 1/255.  The shader scales the fog
colour by ``iblLuminance`` (the indirect light's intensity times the camera's exposure): ``color`` here
is ``FogOptions.color`` times that (the test sets both to 1).

Units: Filament is y-up **metres** (same as fogref) and uses **exp** (not exp2):
density [1/m], heightFalloff [1/m], so the medium is exactly
``sigma_t(y) = density * exp(-heightFalloff * (y - height))`` [1/m] (one
:class:`~fogref.media.ExpLayer`).  Shader: ``h = falloff * view.y`` (view =
world - camera, unnormalised), line integral ``(A - density exp(y - h))/h = A (1 - exp(-h))/h``
(``A = density exp(y)``, ``y = -heightFalloff (camera.y - height)``) if ``|h| > 0.00125``
else ``A`` (zeroth-order branch: up to 0.06 % low; releases before ``surface_fog.fs`` had
``A (1 - exp(-h))/h`` with 0.01, up to 0.5 %), times
``max(d - distance, 0)``; note that the start distance only shortens the ray, the
density is still averaged from the camera (unlike Unreal).

Compositing: ``opacity = min(1 - exp(-integral), maximumOpacity)``,
``final = scene * (1 - opacity) + color * opacity + sun term``, with the sun term
``sunColor * pow(max(dot(view, l)/d, 0), inScatteringSize) * (1 - exp(-insc))``
when ``inScatteringSize > 0`` (``insc`` uses ``inScatteringStart``).  So
``transmittance = 1 - opacity`` (grey).  ``cutOffDistance`` (newer versions):
pixels farther than it get no fog.  Robustness (deviations): ``d`` is floored at
1e-30 in the sun term (the shader divides 0/0 at the camera), the density at the
camera is capped at the largest float, and where the shader's line integral is
not finite (``0 * inf`` far above the fog looking down) the log-form closed
form is used; float64 always uses that closed form (no 0.00125 branch).

Output (``output``): ``"linear"``, the fogged image as the colour pass writes it (a linear
render target, post-processing off; the blend above); ``"canvas"``, the default canvas of a
Filament ``View`` (post-processing on), whose colour-grading pass maps that image through the
engine's default ``ColorGrading``, transcribed from google/filament at the nearest commits
available here, later than ``v1.53.4`` (``filament/src/ToneMapper.cpp`` at
``0916f5bbbdeb3bfa553ce6ad2276652e570d4712``, ``filament/src/ColorSpaceUtils.h`` at
``082da86ca889c905cfdc8928fb8fbeff1c50b091``, ``filament/src/details/ColorGrading.cpp`` at
``1e3a258bf12047b681fad3be1d9bec60512c783f``, ``filament/src/materials/colorGrading/
colorGrading.mat`` at ``263d042924de0a13fe14d57a4fea4f538ac565f2``; the pass's GLSL as the
1.53.4 web build hands it to WebGL has the same LogC lookup and dithering) and held to the 1.53.4
web build by ``tests/test_web_filament.py``: a 32^3 LUT in ``RGB10_A2`` (quality MEDIUM), indexed by the
Alexa LogC (EI 1000) encoding of the linear sRGB colour, whose entries are the colour in
Rec.2020, tone-mapped by ``ACESLegacyToneMapper`` (:func:`aces_legacy`), back to sRGB,
clamped to [0, 1] and sRGB-encoded (``outputColorSpace`` Rec709-sRGB-D65); the pass samples it
trilinearly (:func:`colour_grade`) and the canvas rounds to 8 bits.  :meth:`FilamentFog.evaluate`
then returns a :class:`CanvasGrade`, whose :meth:`~CanvasGrade.display` is the canvas value
before its rounding; its ``transmittance`` and ``inscatter`` are the linear target's.  Filament's
temporal dithering (triangular noise under one 8-bit step) and FXAA (an edge filter), both on by
default, are not reproduced (fogref's pages turn them off).  Robustness (deviation): ACES's
chroma takes ``sqrt(max(., 0))`` (rounding can make its argument slightly negative, where C++'s
``sqrt`` gives NaN).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fogref import params as valid
from fogref.display import srgb_encode
from fogref.errors import ParameterError
from fogref.media import NP
from fogref.media.closed_form import phi
from fogref.models._num import dtype_of, grey, split
from fogref.models.base import FogResult, register
from fogref.models.threejs import srgb_transfer_eotf

OUTPUTS = ("linear", "canvas")


@dataclass(frozen=True)
class FilamentFogParams:
    """View::FogOptions (metres) plus the sun (``lightDirection``: toward the sun) and ``output``:
    "linear" (the colour pass) or "canvas" (the default canvas, see the module doc)."""

    distance: float = 0.0
    cutOffDistance: float = math.inf
    maximumOpacity: float = 1.0
    height: float = 0.0
    heightFalloff: float = 1.0
    color: tuple = (1.0, 1.0, 1.0)
    density: float = 0.1
    inScatteringStart: float = 0.0
    inScatteringSize: float = -1.0
    lightDirection: tuple = (0.0, 1.0, 0.0)
    lightColorIntensity: tuple = (1.0, 1.0, 1.0, 1.0)
    output: str = "linear"

    def __post_init__(self) -> None:
        src = "<FilamentFogParams>"
        if self.output not in OUTPUTS:
            raise ParameterError(src, "output", f"expected one of {OUTPUTS}, got {self.output!r}")
        for name in ("distance", "density", "heightFalloff"):
            object.__setattr__(self, name, valid.number(getattr(self, name), name, source=src, lo=0.0))
        object.__setattr__(
            self,
            "maximumOpacity",
            valid.number(self.maximumOpacity, "maximumOpacity", source=src, lo=0.0, hi=1.0),
        )
        object.__setattr__(self, "height", valid.number(self.height, "height", source=src, unit="m"))
        if not (isinstance(self.cutOffDistance, float) and self.cutOffDistance == math.inf):  # inf: none
            cut = valid.number(self.cutOffDistance, "cutOffDistance", source=src, lo=0.0, unit="m")
            object.__setattr__(self, "cutOffDistance", cut)
        for name in ("inScatteringStart", "inScatteringSize"):  # Filament: size < 0 turns it off
            object.__setattr__(self, name, valid.number(getattr(self, name), name, source=src))
        object.__setattr__(self, "color", valid.rgb(self.color, "color", source=src, lo=0.0))
        w = np.asarray(valid.vector(self.lightDirection, "lightDirection", source=src), dtype=np.float64)
        if not np.linalg.norm(w) > 0:
            raise ParameterError(src, "lightDirection", "(0, 0, 0) has no direction")
        object.__setattr__(self, "lightDirection", tuple(float(x) for x in w / np.linalg.norm(w)))
        lci = valid.vector(self.lightColorIntensity, "lightColorIntensity", source=src, n=4, lo=0.0)
        object.__setattr__(self, "lightColorIntensity", lci)


# filament/src/ColorSpaceUtils.h: each mat3f's nine values, listed by column; the products below
# are formed in float32, as its constexpr mat3f are
# fmt: off
(_XYZ_TO_SRGB, _SRGB_TO_XYZ, _REC2020_TO_XYZ, _XYZ_TO_REC2020,
 _AP1_TO_XYZ, _XYZ_TO_AP1, _AP1_TO_AP0, _AP0_TO_AP1) = (
    np.asarray(columns, dtype=np.float32).reshape(3, 3).T for columns in (
    (3.2404542, -0.9692660, 0.0556434, -1.5371385, 1.8760108, -0.2040259, -0.4985314, 0.0415560, 1.0572252),
    (0.4124560, 0.2126730, 0.0193339, 0.3575760, 0.7151520, 0.1191920, 0.1804380, 0.0721750, 0.9503040),
    (0.6369530, 0.2626983, 0.0000000, 0.1446169, 0.6780088, 0.0280731, 0.1688558, 0.0592929, 1.0608272),
    (1.7166634, -0.6666738, 0.0176425, -0.3556733, 1.6164557, -0.0427770, -0.2533681, 0.0157683, 0.9422433),
    (0.6624541811, 0.2722287168, -0.0055746495, 0.1340042065, 0.6740817658, 0.0040607335,
     0.1561876870, 0.0536895174, 1.0103391003),
    (1.6410233797, -0.6636628587, 0.0117218943, -0.3248032942, 1.6153315917, -0.0082844420,
     -0.2364246952, 0.0167563477, 0.9883948585),
    (0.6954522414, 0.0447945634, -0.0055258826, 0.1406786965, 0.8596711185, 0.0040252103,
     0.1638690622, 0.0955343182, 1.0015006723),
    (1.4514393161, -0.0765537734, 0.0083161484, -0.2365107469, 1.1762296998, -0.0060324498,
     -0.2149285693, -0.0996759264, 0.9977163014),
    )
)
# fmt: on
_REC2020_TO_AP0 = _AP1_TO_AP0 @ _XYZ_TO_AP1 @ _REC2020_TO_XYZ
_AP1_TO_REC2020 = _XYZ_TO_REC2020 @ _AP1_TO_XYZ
_LUMINANCE_AP1 = np.asarray([0.272229, 0.674082, 0.0536895], dtype=np.float32)
_HALF_MAX = np.float32(65504.0)
#: ``ColorGrading::Builder``'s default quality (MEDIUM): a LUT of 32^3 entries in ``RGB10_A2``
LUT_DIMENSION = 32


def _times(m: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``m * v`` for (..., 3) colours, float32."""
    return (v @ m.T).astype(np.float32)


def aces_legacy(rec2020: Any) -> np.ndarray:
    """Filament's ``ACESLegacyToneMapper``: ``aces::ACES(c, 1 / 0.6)`` of ``ToneMapper.cpp``, float32.

    Domain: linear Rec.2020 colours (..., 3) >= 0 (scene units at exposure 1).  Range: linear
    Rec.2020 display colours, about [0, 1] (the ACES RRT + ODT fit of a 100-nit monitor, dim
    surround, with Filament's brightness 1/0.6).

    >>> grey = np.array([[0.0, 0.0, 0.0], [0.18, 0.18, 0.18], [1.0, 1.0, 1.0]])
    >>> np.round(aces_legacy(grey).astype(float), 4).tolist()
    [[0.0, 0.0, 0.0], [0.2171, 0.218, 0.2203], [0.7759, 0.7605, 0.7177]]
    """
    f = np.float32
    ap0 = _times(_REC2020_TO_AP0, np.asarray(rec2020, dtype=f))
    # glow module
    lo, hi = ap0.min(axis=-1), ap0.max(axis=-1)
    sat = (np.maximum(hi, f(1e-5)) - np.maximum(lo, f(1e-5))) / np.maximum(hi, f(1e-2))
    r, g, b = ap0[..., 0], ap0[..., 1], ap0[..., 2]
    chroma = np.sqrt(np.maximum(b * (b - g) + g * (g - r) + r * (r - b), f(0.0)))
    yc = (b + g + r + f(1.75) * chroma) / f(3.0)
    x = (sat - f(0.4)) / f(0.2)
    t = np.maximum(f(1.0) - np.abs(x / f(2.0)), f(0.0))
    gain = f(0.05) * (f(1.0) + np.sign(x).astype(f) * (f(1.0) - t * t)) / f(2.0)
    mid = f(0.08)
    with np.errstate(divide="ignore", invalid="ignore"):
        glow = np.where(
            yc <= f(2.0 / 3.0) * mid, gain, np.where(yc >= f(2.0) * mid, f(0.0), gain * (mid / yc - f(0.5)))
        )
    ap0 = ap0 * (f(1.0) + glow)[..., None]
    # red modifier
    r, g, b = ap0[..., 0], ap0[..., 1], ap0[..., 2]
    hue = np.where(
        (r == g) & (g == b), f(0.0), np.degrees(np.arctan2(f(math.sqrt(3.0)) * (g - b), f(2.0) * r - g - b))
    )
    hue = np.where(hue < 0, hue + f(360.0), hue).astype(f)
    centred = np.where(hue > f(180.0), hue - f(360.0), hue)
    w = np.clip(f(1.0) - np.abs(f(2.0) * centred / f(135.0)), f(0.0), f(1.0))
    weight = (w * w * (f(3.0) - f(2.0) * w)) ** 2
    ap0[..., 0] = r + weight * sat * (f(0.03) - r) * (f(1.0) - f(0.82))
    # to AP1, global desaturation, brightness, the RRT + ODT fit
    ap1 = np.clip(_times(_AP0_TO_AP1, ap0), f(0.0), _HALF_MAX)
    y = (ap1 @ _LUMINANCE_AP1)[..., None]
    ap1 = (y + f(0.96) * (ap1 - y)) * (f(1.0) / f(0.6))
    post = (ap1 * (f(2.785085) * ap1 + f(0.107772))) / (ap1 * (f(2.936045) * ap1 + f(0.887122)) + f(0.806889))
    # dark to dim surround: gamma 0.9811 on Y in xyY
    xyz = _times(_AP1_TO_XYZ, post)
    s = np.maximum(xyz.sum(axis=-1), f(1e-5))
    cx, cy = xyz[..., 0] / s, xyz[..., 1] / s
    big_y = np.power(np.clip(xyz[..., 1], f(0.0), _HALF_MAX), f(0.9811))
    a = big_y / np.maximum(cy, f(1e-5))
    linear = _times(_XYZ_TO_AP1, np.stack([cx * a, big_y, (f(1.0) - cx - cy) * a], axis=-1))
    y = (linear @ _LUMINANCE_AP1)[..., None]
    return _times(_AP1_TO_REC2020, y + f(0.93) * (linear - y))


@functools.cache
def colour_grading_lut(dimension: int = LUT_DIMENSION) -> np.ndarray:
    """The LUT of Filament's default ``ColorGrading`` (``FColorGrading``'s constructor), float32.

    Returns ``(dimension,) * 3 + (3,)`` indexed ``[b, g, r]``: at ``LogC_to_linear(i / (dimension
    - 1))`` (floored at 0) of each channel, ``OETF_sRGB(saturate(Rec2020_to_sRGB *
    aces_legacy(sRGB_to_Rec2020 * v)))``, rounded to 10 bits (``RGB10_A2``); values in [0, 1].

    >>> lut = colour_grading_lut()
    >>> lut.shape, float(lut[0, 0, 0, 0]), round(float(lut[-1, -1, -1, 0]) * 1023)
    ((32, 32, 32, 3), 0.0, 1019)
    """
    f = np.float32
    i = np.arange(dimension, dtype=f) * (f(1.0) / f(dimension - 1))
    v = np.maximum(
        (np.power(f(10.0), (i - f(0.386036)) * (f(1.0) / f(0.244161))) - f(0.047996))
        * (f(1.0) / f(5.555556)),
        f(0.0),
    )
    b, g, r = np.meshgrid(v, v, v, indexing="ij")
    rgb = _times(_XYZ_TO_REC2020 @ _SRGB_TO_XYZ, np.stack([r, g, b], axis=-1))
    out = _times(_XYZ_TO_SRGB @ _REC2020_TO_XYZ, aces_legacy(rgb))
    out = srgb_encode(np.clip(out, f(0.0), f(1.0))).astype(f)
    return (np.floor(out * f(1023.0) + f(0.5)) / f(1023.0)).astype(f)


def colour_grade(linear: Any) -> np.ndarray:
    """The canvas value of Filament's colour-grading pass (``colorGrade`` of ``colorGrading.mat``).

    Domain: linear sRGB colours (..., 3) (negative values are taken as 0).  Range: sRGB-encoded
    [0, 1], float32, before the canvas's 8-bit rounding: the Alexa LogC (EI 1000) encoding of
    the colour places it in :func:`colour_grading_lut`, sampled trilinearly, clamped to its edges.

    >>> grey = np.array([[0.0, 0.0, 0.0], [0.18, 0.18, 0.18]])
    >>> np.round(colour_grade(grey).astype(float) * 255, 1).tolist()
    [[0.0, 0.0, 0.0], [128.1, 128.6, 129.3]]
    """
    f = np.float32
    lut = colour_grading_lut()
    n = lut.shape[0]
    x = np.maximum(np.asarray(linear, dtype=f), f(0.0))
    logc = f(0.244161 / math.log2(10.0)) * np.log2(f(5.555556) * x + f(0.047996)) + f(0.386036)
    u = np.clip(logc * f(n - 1), f(0.0), f(n - 1))  # texel space: the pass samples texel centres
    i0 = np.minimum(np.floor(u).astype(np.int64), n - 2)
    t = (u - i0).astype(f)
    out = np.zeros(x.shape, dtype=f)
    for corner in np.ndindex(2, 2, 2):  # (r, g, b) offsets
        w = np.prod([t[..., c] if o else f(1.0) - t[..., c] for c, o in enumerate(corner)], axis=0)
        out += w[..., None] * lut[i0[..., 2] + corner[2], i0[..., 1] + corner[1], i0[..., 0] + corner[0]]
    return out


@dataclass
class CanvasGrade(FogResult):
    """Fog on Filament's default canvas: the linear blend through its colour grading.

    ``transmittance`` and ``inscatter`` are the linear target's (see the module doc).

    Examples
    --------
    >>> fog = FilamentFog(FilamentFogParams(density=0.0, output="canvas"))
    >>> r = fog.evaluate([0.0, 0.0, 0.0], [[0.0, 0.0, -1.0]])
    >>> np.round(r.display(np.array([[1.0, 1.0, 1.0]])) * 255, 1).tolist()   # ACES legacy: 1 -> 230/255
    [[229.8, 225.5, 219.4]]
    """

    def display(self, scene_rgb: Any) -> np.ndarray:
        """The canvas value in [0, 1] (sRGB, before the 8-bit rounding) over a linear ``scene_rgb``."""
        return colour_grade(np.asarray(scene_rgb) * self.transmittance + self.inscatter)

    def composite(self, scene_rgb: Any) -> np.ndarray:
        """The canvas over a linear ``scene_rgb``, decoded to linear RGB (the sRGB EOTF)."""
        return srgb_transfer_eotf(self.display(scene_rgb), np.float32)


@register("filament")
class FilamentFog:
    """Filament height fog (see module doc)."""

    Params = FilamentFogParams

    def __init__(self, params: FilamentFogParams | None = None) -> None:
        self.params = params or FilamentFogParams()

    def evaluate(self, camera: Any, world_pos: Any, precision: str = "float32") -> FogResult:
        """Fog of each pixel: camera (3,), world_pos (..., 3) in metres."""
        dt = dtype_of(precision)
        q = self.params
        cam, wp = split(camera, world_pos)
        # CPU: density at the viewer's height
        with np.errstate(all="ignore"):
            y = dt(-q.heightFalloff) * (dt(cam[1]) - dt(q.height))
            A = dt(q.density) * np.exp(y)
            A = min(A, dt(np.finfo(dt).max))  # robustness: no inf density
        falloff = dt(q.heightFalloff)
        with np.errstate(all="ignore"):
            view = (wp - cam).astype(dt)
            h = falloff * view[..., 1]

            # robust line integral in log form (no 0 * inf when the camera is far above)
            def robust(hh: Any) -> Any:
                log_a = (math.log(q.density) if q.density > 0 else -1e4) - q.heightFalloff * (
                    cam[1] - q.height
                )
                h64 = hh.astype(np.float64)
                return np.where(
                    h64 > -1.0,
                    np.exp(min(log_a, 700.0)) * phi(NP, np.maximum(h64, -1.0)),
                    np.exp(np.minimum(log_a - h64, 700.0))
                    * (-np.expm1(np.minimum(h64, 0.0)))
                    / np.where(h64 < 0, -h64, 1.0),
                )

            if dt is np.float64:
                fi = robust(h)
            else:
                fi = np.where(np.abs(h) > dt(0.00125), (A - dt(q.density) * np.exp(y - h)) / h, A)
                bad = ~np.isfinite(fi)
                if np.any(bad):
                    fi[bad] = np.minimum(robust(h[bad]), np.finfo(dt).max).astype(dt)
            d = np.sqrt(np.sum(view * view, axis=-1))
            run = np.maximum(d - dt(q.distance), dt(0.0))
            integral = np.where(run > 0, fi * run, dt(0.0))
            if dt is np.float64:  # same value, without the cancellation of 1 - (1 - T)
                trans = np.maximum(np.exp(-integral), dt(1.0) - dt(q.maximumOpacity))
                opacity = dt(1.0) - trans
            else:
                opacity = np.minimum(dt(1.0) - np.exp(-integral), dt(q.maximumOpacity))
                trans = dt(1.0) - opacity
            fog_color = np.asarray(q.color, dtype=dt) * opacity[..., None]
            if q.inScatteringSize > 0:
                run_i = np.maximum(d - dt(q.inScatteringStart), dt(0.0))
                insc = np.where(run_i > 0, fi * run_i, dt(0.0))
                insc_opacity = dt(1.0) - np.exp(-insc)
                lc = q.lightColorIntensity
                sun = np.asarray(lc[:3], dtype=dt) * dt(lc[3])
                l = np.asarray(q.lightDirection, dtype=dt)
                amount = np.maximum(
                    (view[..., 0] * l[0] + view[..., 1] * l[1] + view[..., 2] * l[2])
                    / np.maximum(d, dt(1e-30)),
                    dt(0.0),
                )
                fog_color = (
                    fog_color + sun * (np.power(amount, dt(q.inScatteringSize)) * insc_opacity)[..., None]
                )
            if math.isfinite(q.cutOffDistance):
                cut = d > dt(q.cutOffDistance)
                trans = np.where(cut, dt(1.0), trans)
                fog_color = np.where(cut[..., None], dt(0.0), fog_color)
        result = CanvasGrade if q.output == "canvas" else FogResult
        return result(inscatter=fog_color.astype(dt), transmittance=grey(trans, dt))
