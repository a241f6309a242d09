"""How a render is split into passes: lanes per pass, samples per pass, pass seeds.

fogpath materialises every per-sample output of a pass before summing them per pixel
(:meth:`FogPathIntegrator.render_moments`), so a pass needs memory in proportion to its
lanes (pixels x samples): about 50 float32 values each.  The render driver
(:mod:`fogref.render.render`) and ``mi.render`` with fogpath both split the samples
with :func:`pass_sizes` under :data:`MAX_LANES` and seed pass ``k`` with
:func:`pass_seed`, so that neither needs memory for every sample at once.
"""

from __future__ import annotations

import hashlib

#: Lanes (pixels x samples) per pass, by back end: ~0.4 GB of outputs per pass on the
#: CPU, ~6.6 GB on a GPU.
MAX_LANES = {"llvm": 1 << 21, "cuda": 1 << 25}


def max_lanes(variant: str) -> int:
    """:data:`MAX_LANES` of a Mitsuba variant's back end.

    >>> max_lanes("cuda_ad_rgb") > max_lanes("llvm_ad_rgb")
    True
    """
    return MAX_LANES["cuda" if variant.startswith("cuda") else "llvm"]


def pass_sizes(n_pixels: int, spp: int, max_lanes: int) -> list[int]:
    """Samples per pixel of each pass: as few passes as ``max_lanes`` allows, as equal
    as possible (the larger ones first; no small last pass).

    >>> pass_sizes(100, 64, 10_000)
    [64]
    >>> pass_sizes(1000, 64, 10_000)
    [10, 9, 9, 9, 9, 9, 9]
    >>> pass_sizes(10, 3, 1)
    [1, 1, 1]
    """
    per = max(1, min(spp, max_lanes // max(n_pixels, 1)))
    n = -(-spp // per)
    return [spp // n + (1 if k < spp % n else 0) for k in range(n)]


def pass_seed(seed: int, k: int) -> int:
    """Seed of pass k: a 32-bit mix of the user's seed and the pass index.

    >>> pass_seed(0, 0) != pass_seed(0, 1)
    True
    """
    h = hashlib.blake2b(f"{seed}:{k}".encode(), digest_size=4).digest()
    return int.from_bytes(h, "little")
