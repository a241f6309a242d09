"""``fogref info FILE.exr``: what a ground truth (or any EXR) holds.

Prints the size, the channels (grouped), the header's parameters (fog, sun, sky,
camera), spp, seed, pixel filter, schema, and for a fogref truth the noise level of
each Monte Carlo part (median and 95th percentile of the per-pixel relative
standard error, and the relative standard error of the part's image mean).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from fogref.errors import FogrefError


def _groups(names) -> list[str]:
    out: dict[str, list[str]] = {}
    for n in sorted(names):
        head, _, tail = n.rpartition(".")
        out.setdefault(head or "(RGB)", []).append(tail)
    return [f"{g}: {','.join(v)}" for g, v in out.items()]


def describe(path) -> str:
    """The text ``fogref info`` prints for ``path``.

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> from fogref.exrio import write_exr
    >>> p = os.path.join(tempfile.mkdtemp(), "x.exr")
    >>> write_exr(p, {c: np.zeros((2, 3)) for c in "RGB"}, {"fogref.spp": 4})
    >>> print(describe(p).splitlines()[1])
    size: 3x2 px, 3 channels
    """
    from fogref.exrio import read_exr

    channels, attrs = read_exr(path)
    h, w = next(iter(channels.values())).shape if channels else (0, 0)
    lines = [f"{path}", f"size: {w}x{h} px, {len(channels)} channels"]
    lines += ["channels:"] + ["  " + g for g in _groups(channels)]
    for key in ("fogref.schema", "fogref.spp", "fogref.seed", "fogref.pixel_filter", "fogref.scene",
                "fogref.scene_sha256", "fogref.overrides", "fogref.variant", "fogref.version", "fogref.mitsuba"):
        if key in attrs:
            v = attrs[key]
            lines.append(f"{key[7:]}: {v if isinstance(v, str) else json.dumps(v)}")
    params = attrs.get("fogref.params")
    if isinstance(params, dict):
        lines.append("parameters:")
        for k, v in params.items():
            lines.append(f"  {k}: {json.dumps(v)}")
    try:
        from fogref.gbuffer import truth_from_channels

        truth = truth_from_channels(channels, attrs, str(path))
    except FogrefError as e:
        lines.append(f"not a readable fogref truth: {e}")
        return "\n".join(lines)
    lines.append(f"pixels: {int(truth.hit.sum())} surface, {int(truth.sky.sum())} sky; "
                 f"identity |final - (attenuated_surface + inscatter)| max {truth.identity_residual():.2g}")
    lines.append("noise (relative standard error: per pixel median / p95; of the image mean):")
    for part in ("final", "transmittance", "inscatter", "attenuated_surface", "surface"):
        x, se = truth.part(part), truth.stderr[part]
        ok = np.abs(x) > 1e-12
        rel = np.abs(se[ok]) / np.abs(x[ok]) if ok.any() else np.zeros(1)
        mean = float(np.abs(x.mean()))
        rel_mean = float(np.sqrt((se**2).sum()) / x.size / mean) if mean > 0 else 0.0
        lines.append(f"  {part:20s} {np.median(rel):.3g} / {np.percentile(rel, 95):.3g}; {rel_mean:.3g}")
    return "\n".join(lines)


def run_info_command(args) -> int:
    """Handler of ``fogref info``: print :func:`describe` (quietly stops when the reader closes the pipe)."""
    text = describe(Path(args.exr))
    try:
        print(text)
        sys.stdout.flush()
    except BrokenPipeError:  # `fogref info x.exr | head`: not an error
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return 0


def add_cli(subparsers):
    """Add ``fogref info EXR`` to an argparse ``subparsers`` object; returns the parser."""
    p = subparsers.add_parser("info", help="channels, parameters, spp, seed and noise level of an EXR",
                              description=__doc__.splitlines()[0])
    p.add_argument("exr", help="a ground-truth EXR (or any EXR)")
    p.set_defaults(func=run_info_command)
    return p
