"""An engine's own images, read and compared against a ground truth.

A rendering engineer's engine writes a picture of the same view as the truth
(same camera, same resolution, pixel-centred: one sample through each pixel's
centre, as fogref's default ``pixel_filter="centre"``).  This module reads it; each
image is compared, part by part (:func:`fogref.compare.check.check`):

================  ====================================  ===============================
engine image      what it is                            compared against the truth's
================  ====================================  ===============================
``image``         the engine's final picture            ``R,G,B`` (part ``final``)
``transmittance`` the fog's transmittance (fog factor)  ``T.*`` (part ``T``)
``inscatter``     the radiance the fog adds             ``inscatter.*`` (part ``inscatter``)
``fog_colour``    the fog colour ``C`` of a lerp,       ``inscatter.*``, as ``C * (1 - T)``
                  ``final = lerp(scene, C, 1 - T)``     (needs ``transmittance``)
================  ====================================  ===============================

**The final image means something only if the engine's surface lighting matches
the truth's ``surface`` part** (the radiance of the surfaces and sky before fog).
An engine lights its surfaces with its own shading, shadows and sky; any
difference there shows up in ``final`` and is not the fog's error.  The fair
comparison needs the engine's transmittance and inscatter: part ``composite`` is
the engine's fog composited over the truth's own surface radiance,
``surface * T_engine + inscatter_engine`` against ``surface * T + inscatter``, so
that only the fog differs.

Formats: OpenEXR (channels ``R,G,B``, or one channel ``Y`` for a grey image;
alpha is ignored), PNG (8-bit, or 16-bit grey), Radiance RGBE ``.hdr``/``.pic``.
``encoding``: ``"auto"`` (the default: an 8-bit PNG is display-referred sRGB, EXR and
HDR are linear), ``"linear"`` or ``"srgb"`` (the IEC 61966-2-1 decoding); the encoding
each image was read with is recorded (``EngineImages.encodings``) and reported.  ``exposure``: the engine's
exposure scale; values are divided by it (radiance images only, not the
transmittance).  Each image's resolution must be the truth's.

Examples
--------
>>> import numpy as np, tempfile, os
>>> from fogref.exrio import write_exr
>>> path = os.path.join(tempfile.mkdtemp(), "engine.exr")
>>> write_exr(path, {c: np.full((2, 3), 0.5) for c in "RGB"})
>>> read_image(path, exposure=2.0)[0, 0].tolist()
[0.25, 0.25, 0.25]
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from PIL import Image

from fogref.display import srgb_decode
from fogref.errors import FogrefError
from fogref.exrio import read_exr

ENCODINGS = ("auto", "linear", "srgb")
IMAGE_SUFFIXES = (".exr", ".png", ".hdr", ".pic")


# ---------------------------------------------------------------- readers


def _read_exr_rgb(path: Path) -> np.ndarray:
    ch, _ = read_exr(path)
    if all(c in ch for c in "RGB"):
        return np.stack([ch[c] for c in "RGB"], -1)
    if "Y" in ch:
        return np.repeat(ch["Y"][..., None], 3, -1)
    raise FogrefError(
        f"{path}: an EXR image needs channels R,G,B (or Y); it has {', '.join(sorted(ch)[:12])}"
    )


def _read_png(path: Path) -> np.ndarray:
    with path.open("rb") as f:
        head = f.read(26)
    if head[:8] != b"\x89PNG\r\n\x1a\n":
        raise FogrefError(f"{path}: not a PNG file")
    depth, colour_type = head[24], head[25]
    if depth == 16 and colour_type != 0:
        raise FogrefError(
            f"{path}: 16-bit colour PNG: it cannot be read at full precision here; "
            "write the engine's image as EXR or Radiance .hdr (or 8-bit PNG)"
        )
    try:
        with Image.open(path) as im:
            if depth == 16:
                a = np.asarray(im, dtype=np.float64) / 65535.0
                return np.repeat(a[..., None], 3, -1)
            a = np.asarray(im.convert("RGB"), dtype=np.float64) / 255.0
    except OSError as e:
        raise FogrefError(f"{path}: not a readable PNG ({e})") from e
    return a


def _read_hdr(path: Path) -> np.ndarray:
    """Radiance RGBE (``#?RADIANCE``/``#?RGBE``), flat or run-length encoded scanlines."""
    data = path.read_bytes()
    if not (data.startswith(b"#?RADIANCE") or data.startswith(b"#?RGBE")):
        raise FogrefError(f"{path}: not a Radiance HDR file (no '#?RADIANCE' signature)")
    end = data.find(b"\n\n")
    if end < 0:
        raise FogrefError(f"{path}: Radiance HDR header has no end (blank line)")
    header = data[:end].decode("latin-1")
    fmt = re.search(r"^FORMAT=(\S+)", header, re.M)
    if fmt and fmt.group(1) != "32-bit_rle_rgbe":
        raise FogrefError(f"{path}: Radiance format {fmt.group(1)}; only 32-bit_rle_rgbe is supported")
    scale = 1.0
    for m in re.finditer(r"^EXPOSURE=\s*(.*)$", header, re.M):
        try:
            x = float(m.group(1).strip())
        except ValueError:
            x = math.nan
        if not (math.isfinite(x) and x > 0):
            raise FogrefError(
                f"{path}: Radiance header EXPOSURE={m.group(1).strip()!r}: expected a finite "
                "number > 0 (the factor the pixels were multiplied by)"
            )
        scale *= x
    line_end = data.find(b"\n", end + 2)
    if line_end < 0:
        raise FogrefError(f"{path}: Radiance HDR has no resolution line after its header")
    res = data[end + 2 : line_end].decode("latin-1").split()
    if len(res) != 4 or res[0] != "-Y" or res[2] != "+X" or not all(_is_count(v) for v in (res[1], res[3])):
        raise FogrefError(
            f"{path}: Radiance resolution line {' '.join(res)[:60]!r}; only '-Y H +X W' with "
            "whole numbers H, W >= 1 is supported"
        )
    H, W = int(res[1]), int(res[3])
    payload = len(data) - (line_end + 1)
    # each pixel takes at least 4 bytes flat, and a run-length scanline at least 4 + 4 * 2 * ceil(W / 127)
    least = H * W * 4 if not 8 <= W < 32768 else H * (4 + 8 * -(-W // 127))
    if least > payload:
        raise FogrefError(
            f"{path}: Radiance header claims {W}x{H} pixels, which need at least {least} "
            f"bytes, but the file holds {payload} after its header (truncated, or a damaged "
            "header)"
        )
    buf = np.frombuffer(data, dtype=np.uint8, offset=line_end + 1)
    rgbe = np.empty((H, W, 4), np.uint8)
    pos = 0
    try:
        for y in range(H):
            if 8 <= W < 32768 and buf[pos] == 2 and buf[pos + 1] == 2 and (buf[pos + 2] & 0x80) == 0:
                if (int(buf[pos + 2]) << 8 | int(buf[pos + 3])) != W:
                    raise FogrefError(f"{path}: scanline {y} has the wrong width")
                pos += 4
                for c in range(4):
                    x = 0
                    while x < W:
                        n = int(buf[pos])
                        pos += 1
                        if n > 128:
                            n -= 128
                            rgbe[y, x : x + n, c] = buf[pos]
                            pos += 1
                        else:
                            if n == 0 or x + n > W:
                                raise FogrefError(f"{path}: corrupt run-length data in scanline {y}")
                            rgbe[y, x : x + n, c] = buf[pos : pos + n]
                            pos += n
                        x += n
            else:
                rgbe[y] = buf[pos : pos + 4 * W].reshape(W, 4)
                pos += 4 * W
    except (IndexError, ValueError):
        raise FogrefError(f"{path}: Radiance HDR data ends early ({H}x{W} expected)") from None
    e = rgbe[..., 3].astype(np.int32)
    f = np.where(e > 0, np.ldexp(1.0, e - 136), 0.0)
    return (rgbe[..., :3].astype(np.float64) + 0.5) * f[..., None] * (e[..., None] > 0) / scale


def _is_count(text: str) -> bool:
    """True for a whole number >= 1 written in decimal digits (no sign)."""
    return text.isdigit() and int(text) >= 1


def resolve_encoding(path, encoding: str = "auto") -> str:
    """The encoding an image is read with: ``encoding`` itself, or for ``"auto"`` ``"srgb"``
    for a PNG and ``"linear"`` for EXR/HDR.

    >>> resolve_encoding("engine.png"), resolve_encoding("engine.exr"), resolve_encoding("e.png", "linear")
    ('srgb', 'linear', 'linear')
    """
    if encoding not in ENCODINGS:
        raise FogrefError(f"{path}: encoding '{encoding}' (allowed: {', '.join(ENCODINGS)})")
    if encoding != "auto":
        return encoding
    return "srgb" if Path(path).suffix.lower() == ".png" else "linear"


def read_image(path, encoding: str = "auto", exposure: float = 1.0, radiance: bool = True) -> np.ndarray:
    """Read an engine's image as linear RGB.

    Parameters
    ----------
    path : str or Path
        ``.exr``, ``.png``, ``.hdr`` or ``.pic``.
    encoding : str
        ``"auto"`` (PNG: sRGB, else linear; see :func:`resolve_encoding`), ``"linear"`` or
        ``"srgb"`` (decoded with the IEC 61966-2-1 sRGB curve, :func:`fogref.display.srgb_decode`:
        colour-science's ``colour.cctf_decoding(x, function="sRGB")``, bit for bit).
    exposure : float
        The engine's exposure scale, finite and > 0: values are divided by it when
        ``radiance`` (a transmittance image is not scaled).
    radiance : bool
        The image holds radiance (False: a transmittance in [0, 1]).

    Returns
    -------
    ndarray
        ``(H, W, 3)`` float64, finite (FogrefError otherwise), linear.

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> from PIL import Image
    >>> path = os.path.join(tempfile.mkdtemp(), "engine.png")
    >>> Image.fromarray(np.full((2, 3, 3), 188, np.uint8)).save(path)
    >>> round(float(read_image(path, encoding="srgb")[0, 0, 0]), 3)
    0.503
    """
    path = Path(path)
    encoding = resolve_encoding(path, encoding)
    if not (isinstance(exposure, int | float) and math.isfinite(exposure) and exposure > 0):
        raise FogrefError(f"{path}: exposure {exposure!r} must be finite and > 0")
    if not path.is_file():
        raise FogrefError(f"{path}: no such image file")
    suffix = path.suffix.lower()
    reader = {".exr": _read_exr_rgb, ".png": _read_png, ".hdr": _read_hdr, ".pic": _read_hdr}.get(suffix)
    if reader is None:
        raise FogrefError(f"{path}: unknown image type '{suffix}' (readable: {', '.join(IMAGE_SUFFIXES)})")
    img = np.asarray(reader(path), dtype=np.float64)
    bad = ~np.isfinite(img)
    if bad.any():
        ys, xs = np.nonzero(bad.any(-1))
        raise FogrefError(
            f"{path}: {int(bad.any(-1).sum())} pixel(s) are NaN or infinite, first at (x={xs[0]}, y={ys[0]})"
        )
    if encoding == "srgb":
        img = srgb_decode(np.clip(img, 0.0, None))
    return img / float(exposure) if radiance else img


# ---------------------------------------------------------------- the engine's images


@dataclass
class EngineImages:
    """An engine's images of one view, linear RGB ``(H, W, 3)``; any of them may be None.

    final: the engine's picture; transmittance: its fog transmittance; inscatter: the
    radiance its fog adds.  sources: part -> file it came from; encodings: part -> the
    encoding it was read with (``linear``/``srgb``); encoding_option: what was asked
    (``auto``, ``linear``, ``srgb``); exposure: the engine's exposure scale (> 0).
    """

    final: np.ndarray | None = None
    transmittance: np.ndarray | None = None
    inscatter: np.ndarray | None = None
    sources: dict = field(default_factory=dict)
    encodings: dict = field(default_factory=dict)
    encoding_option: str = "auto"
    exposure: float = 1.0

    @property
    def shape(self) -> tuple[int, int] | None:
        for a in (self.final, self.transmittance, self.inscatter):
            if a is not None:
                return a.shape[:2]
        return None

    @property
    def description(self) -> str:
        return "engine images (" + ", ".join(f"{k}: {v}" for k, v in self.sources.items()) + ")"

    def as_dict(self) -> dict:
        """``{"final", "T", "inscatter"}`` -> image, for the parts given."""
        d = {"final": self.final, "T": self.transmittance, "inscatter": self.inscatter}
        return {k: v for k, v in d.items() if v is not None}


def load_engine_images(
    image=None,
    transmittance=None,
    inscatter=None,
    fog_colour=None,
    *,
    encoding: str = "auto",
    exposure: float = 1.0,
    shape=None,
    truth_name: str = "the truth",
) -> EngineImages:
    """Read an engine's images (any subset) and check their resolution.

    Parameters
    ----------
    image, transmittance, inscatter, fog_colour : path, optional
        The engine's final picture, fog transmittance, fog inscatter, or fog colour
        ``C`` (``final = lerp(scene, C, 1 - T)``, turned into ``inscatter = C (1 - T)``;
        needs ``transmittance``).  At least one.
    encoding, exposure :
        As :func:`read_image`; the transmittance is read linear and unscaled.
    shape : (int, int), optional
        ``(H, W)`` every image must have (the truth's).
    truth_name : str
        Named in the resolution error.

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> from fogref.exrio import write_exr
    >>> d = tempfile.mkdtemp()
    >>> write_exr(os.path.join(d, "t.exr"), {c: np.full((2, 3), 0.5) for c in "RGB"})
    >>> write_exr(os.path.join(d, "c.exr"), {c: np.full((2, 3), 0.2) for c in "RGB"})
    >>> e = load_engine_images(transmittance=os.path.join(d, "t.exr"), fog_colour=os.path.join(d, "c.exr"))
    >>> round(float(e.inscatter[0, 0, 0]), 6)
    0.1
    """
    if inscatter is not None and fog_colour is not None:
        raise FogrefError("give the engine's inscatter or its fog colour, not both")
    if fog_colour is not None and transmittance is None:
        raise FogrefError(
            f"{fog_colour}: a fog colour becomes inscatter as C * (1 - T): give the transmittance too"
        )
    paths = {
        "final": image,
        "transmittance": transmittance,
        "inscatter": inscatter if fog_colour is None else fog_colour,
    }
    paths = {k: Path(v) for k, v in paths.items() if v is not None}
    if not paths:
        raise FogrefError(
            "no engine image given (need at least one of the final image, transmittance, inscatter)"
        )
    if encoding not in ENCODINGS:
        raise FogrefError(f"encoding '{encoding}' (allowed: {', '.join(ENCODINGS)})")
    # a transmittance is data in [0, 1], not a colour: always read linear
    used = {k: resolve_encoding(p, encoding if k != "transmittance" else "linear") for k, p in paths.items()}
    imgs = {
        k: read_image(p, encoding=used[k], exposure=exposure, radiance=k != "transmittance")
        for k, p in paths.items()
    }
    want = tuple(shape) if shape is not None else None
    for k, a in imgs.items():
        h, w = a.shape[:2]
        if want is not None and (h, w) != want:
            raise FogrefError(
                f"{paths[k]}: {w}x{h} px, but {truth_name} is {want[1]}x{want[0]} px; "
                "render the engine's image at the truth's resolution (same camera)"
            )
        if want is None:
            want = (h, w)
    if fog_colour is not None:
        imgs["inscatter"] = imgs["inscatter"] * (1.0 - imgs["transmittance"])
    label = {k: k if k != "inscatter" or fog_colour is None else "fog_colour" for k in paths}
    return EngineImages(
        final=imgs.get("final"),
        transmittance=imgs.get("transmittance"),
        inscatter=imgs.get("inscatter"),
        sources={label[k]: str(p) for k, p in paths.items()},
        encodings={label[k]: e for k, e in used.items()},
        encoding_option=encoding,
        exposure=float(exposure),
    )
