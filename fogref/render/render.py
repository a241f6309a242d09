"""Render a fogref scene to a ground-truth EXR (see :mod:`fogref.exrio` for channels).

Rendering runs in passes of at most ``pass_spp`` samples per pixel; each pass has
its own seed derived from ``seed``, so the same ``(seed, spp, pass_spp)`` gives
identical pixels.  After every pass the running sum is checkpointed atomically
next to the output (``<out>.partial.npz``); an interrupted run started again with
the same arguments resumes from it.
"""

from __future__ import annotations

import hashlib
import json
import time
from pathlib import Path

import numpy as np

from fogref._version import __version__
from fogref.atomic import atomic_write, savez_atomic
from fogref.errors import FogrefError
from fogref.exrio import write_exr

PASS_SPP = 16


def pass_seed(seed: int, k: int) -> int:
    """Seed of pass k: a 32-bit mix of the user's seed and the pass index."""
    h = hashlib.blake2b(f"{seed}:{k}".encode(), digest_size=4).digest()
    return int.from_bytes(h, "little")


def _atomic_savez(path: Path, **arrays):
    """The checkpoint writer (a seam: the resume test interrupts the run here)."""
    savez_atomic(path, **arrays)


def split_channels(img: np.ndarray, names: list[str]) -> dict:
    """Turn the integrator's mean tensor into the EXR's channel dict.

    ``surface = Tsurface / T`` (transmittance-weighted mean surface radiance per
    pixel; 0 where T = 0), so that ``R,G,B = T * surface + inscatter`` holds per
    pixel to float precision, and ``inscatter = single + multiple``.
    """
    c = {n: img[..., i] for i, n in enumerate(names)}
    out = {}
    for ch in "RGB":
        T = c[f"T.{ch}"]
        ts = c[f"Tsurface.{ch}"]
        single, multiple = c[f"single.{ch}"], c[f"multiple.{ch}"]
        out[ch] = c[ch]
        out[f"T.{ch}"] = T
        out[f"surface.{ch}"] = np.where(T > 0, ts / np.where(T > 0, T, 1.0), 0.0)
        out[f"single.{ch}"] = single
        out[f"multiple.{ch}"] = multiple
        out[f"inscatter.{ch}"] = single + multiple
    for n in ("distance", "P.X", "P.Y", "P.Z", "view.X", "view.Y", "view.Z", "hit"):
        out[n] = c[n]
    return {k: np.nan_to_num(v.astype(np.float32), nan=0.0, posinf=0.0, neginf=0.0) for k, v in out.items()}


def tonemap_png(rgb: np.ndarray, path: Path, exposure: float | None = None) -> float:
    """Write an 8-bit sRGB preview: exposure (default: mean luminance -> 0.18),
    then the sRGB encoding (colour-science), clipped.  Returns the exposure used."""
    import colour
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lum = rgb @ np.array([0.2126, 0.7152, 0.0722])
    if exposure is None:
        m = float(np.mean(lum))
        exposure = 0.18 / m if m > 0 else 1.0
    img = np.clip(colour.cctf_encoding(np.clip(rgb * exposure, 0, None), function="sRGB"), 0, 1)
    atomic_write(path, lambda tmp: plt.imsave(tmp, img, format="png"))
    return exposure


def render(scene_path, out, spp: int = 64, seed: int = 0, variant: str | None = None,
           overrides: dict | None = None, pass_spp: int = PASS_SPP, progress: bool = True,
           resume: bool = True, png: bool = True) -> Path:
    """Render ``scene_path`` with ``spp`` samples per pixel into the EXR ``out``.

    ``overrides``: XML ``$name`` defaults to replace (e.g. ``{"res": 64}``).
    Returns the EXR path.  Raises FogrefError/ParameterError for bad input.
    """
    from fogref.render.variant import set_variant

    if not isinstance(spp, int) or not 1 <= spp <= 1 << 20:
        raise FogrefError(f"--spp: {spp} outside [1, 1048576]")
    if not isinstance(seed, int) or not 0 <= seed < 1 << 31:
        raise FogrefError(f"--seed: {seed} outside [0, 2^31)")
    variant = set_variant(variant)
    import drjit as dr
    import mitsuba as mi

    from fogref.render.scene import load_scene

    scene, desc = load_scene(scene_path, overrides)
    integrator = scene.integrator()
    names = ["R", "G", "B"] + list(integrator.aov_names())
    if "T.R" not in names:
        raise FogrefError(f"{scene_path}: the scene's integrator must be 'fogpath' to write a ground-truth EXR")
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    ckpt = out.with_name(out.name + ".partial.npz")
    key = json.dumps({"scene": str(Path(scene_path).resolve()), "spp": spp, "seed": seed, "variant": variant,
                      "overrides": overrides or {}, "pass_spp": pass_spp}, sort_keys=True)
    passes = [min(pass_spp, spp - s) for s in range(0, spp, pass_spp)]
    acc, done = None, 0
    if resume and ckpt.exists():
        try:
            z = np.load(ckpt, allow_pickle=False)
            if str(z["key"]) == key:
                acc, done = z["acc"], int(z["done"])
        except Exception:
            acc, done = None, 0
    from tqdm import tqdm

    t0 = time.perf_counter()
    timings = []
    with tqdm(total=spp, initial=sum(passes[:done]), unit="spp", disable=not progress,
              desc=Path(scene_path).name) as bar:
        for k in range(done, len(passes)):
            ts = time.perf_counter()
            img = mi.render(scene, spp=passes[k], seed=pass_seed(seed, k))
            part = np.array(img, dtype=np.float64) * passes[k]
            dr.sync_thread()
            timings.append(time.perf_counter() - ts)
            acc = part if acc is None else acc + part
            _atomic_savez(ckpt, acc=acc, done=np.array(k + 1), key=np.array(key))
            bar.update(passes[k])
    mean = acc / spp
    channels = split_channels(mean, names)
    attrs = {
        "fogref.params": desc,
        "fogref.spp": str(spp),
        "fogref.seed": str(seed),
        "fogref.variant": variant,
        "fogref.version": __version__,
        "fogref.mitsuba": mi.__version__,
        "fogref.scene": str(scene_path),
        "fogref.overrides": overrides or {},
        "fogref.render_seconds": {"total": time.perf_counter() - t0, "passes": timings},
    }
    write_exr(out, channels, attrs)
    if png:
        rgb = np.stack([channels[c] for c in "RGB"], axis=-1)
        tonemap_png(rgb, out.with_suffix(".png"))
    ckpt.unlink(missing_ok=True)
    return out
