"""Multi-channel EXR files with the official OpenEXR bindings, written atomically.

fogref's ground-truth EXR layout (all float32, one value per pixel):

=================  ==========================================================
``R,G,B``          total radiance = ``T * surface + inscatter``
``T.R,T.G,T.B``    transmittance camera -> first surface (or infinity), closed form
``inscatter.*``    radiance added by the medium (= ``single.* + multiple.*``)
``surface.*``      radiance leaving the first surface toward the camera, before fog
``single.*``       medium single scattering (first medium vertex, direct light)
``multiple.*``     all other medium-added radiance
``distance``       distance to the first surface [m] (0 where the ray escapes)
``P.X,P.Y,P.Z``    world position of the first surface [m] (0 where it escapes)
``hit``            1 where the camera ray hits a surface, else 0
=================  ==========================================================

Header attributes are strings prefixed ``fogref.`` (JSON where structured):
``fogref.params`` (the scene's fog, sun, sky, camera), ``fogref.spp``,
``fogref.seed``, ``fogref.variant``, ``fogref.version``, ``fogref.mitsuba``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from fogref.atomic import atomic_write
from fogref.errors import FogrefError

GROUPS = ("", "T.", "inscatter.", "surface.", "single.", "multiple.")


def write_exr(path, channels: dict, attrs: dict | None = None) -> None:
    """Write ``channels`` (name -> HxW float array) atomically to ``path``.

    ``attrs``: header attributes; non-string values are stored as JSON strings.
    The file appears only when complete (written to a temporary file in the same
    folder, then renamed).
    """
    import OpenEXR

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    for k, v in (attrs or {}).items():
        header[k] = v if isinstance(v, str) else json.dumps(v)
    chans = {k: np.ascontiguousarray(np.nan_to_num(np.asarray(v, dtype=np.float32))) for k, v in channels.items()}

    def write(tmp):
        with OpenEXR.File(header, chans) as f:
            f.write(tmp)

    atomic_write(path, write)


def read_exr(path) -> tuple[dict, dict]:
    """Read an EXR: returns ``(channels, attrs)``; channels are HxW float32 arrays.

    ``fogref.*`` attributes that hold JSON are decoded.
    """
    import OpenEXR

    path = Path(path)
    if not path.is_file():
        raise FogrefError(f"{path}: no such EXR file")
    try:
        with OpenEXR.File(str(path), separate_channels=True) as f:
            chans = {k: np.array(v.pixels, dtype=np.float32) for k, v in f.channels().items()}
            header = dict(f.header())
    except Exception as e:
        raise FogrefError(f"{path}: not a readable EXR file ({e})") from e
    attrs = {}
    for k, v in header.items():
        if isinstance(v, str) and k.startswith("fogref."):
            try:
                v = json.loads(v)
            except ValueError:
                pass
        attrs[k] = v
    return chans, attrs


def rgb(channels: dict, group: str = "") -> np.ndarray:
    """Stack ``group``'s R,G,B channels into an HxWx3 array (group '' is the total)."""
    return np.stack([channels[group + c] for c in "RGB"], axis=-1)
