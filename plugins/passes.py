"""How a render is split into passes: lanes per pass, samples per pass, pass seeds.

fogpath materialises every per-sample output of a pass before summing them per pixel
(:meth:`FogPathIntegrator.render_moments`), so a pass needs memory in proportion to its
lanes (pixels x samples): about 50 float32 values each.  The render driver
(:mod:`fogref.render.render`) and ``mi.render`` with fogpath both split the samples
with :func:`pass_sizes` under :data:`MAX_LANES` and seed pass ``k`` with
:func:`pass_seed`, so that neither needs memory for every sample at once.

**The passes define the pixels**: pass ``k`` draws its ``passes[k]`` samples per pixel from
the seed ``pass_seed(seed, k)``, and its float64 sums are added to the running sums in pass
order, so another split of the same ``spp`` gives other (equally valid) pixels.  The split
is therefore a function of the pixels, the spp and the back end only, never of the workers
that render it; a render is bitwise reproducible per split, which the truth records
(``fogref.passes``).  :data:`MAX_LANES` on the CPU is also what lets Dask workers share a
render (:mod:`fogref.render.distributed`): a render of ``P`` pixels and ``spp`` samples has
``ceil(spp / floor(MAX_LANES / P))`` passes (``spp`` when a pixel row of samples fills a pass).
"""

from __future__ import annotations

import hashlib
import os

from fogref.errors import FogrefError

#: Lanes (pixels x samples) per pass, by back end: ~50 MB of outputs per pass on the CPU
#: (2^18 lanes: a 320x180, 72 spp render is 18 passes of 4 spp, so up to 18 workers share it; a pass
#: of 230400 lanes is ~0.25 s of one core on scenes/valley.xml), ~6.6 GB on a GPU (2^25 lanes: on
#: an H200, 2^24 took 1.02x and 2^26 0.95x the time, ``reports/benchmarks/gpu.md``).
MAX_LANES = {"llvm": 1 << 18, "cuda": 1 << 25}
#: The environment variable that overrides :data:`MAX_LANES` (for a GPU with less memory).
MAX_LANES_VARIABLE = "FOGREF_MAX_LANES"


def max_lanes(variant: str) -> int:
    """Lanes per pass for a Mitsuba variant: ``$FOGREF_MAX_LANES`` when it is set (an integer
    from 1 to 2^31 - 1), else :data:`MAX_LANES` of the variant's back end.  Another value of the
    variable is a :class:`~fogref.errors.FogrefError` naming it and the range.

    >>> max_lanes("cuda_ad_rgb") > max_lanes("llvm_ad_rgb")
    True
    >>> os.environ[MAX_LANES_VARIABLE] = "4096"; max_lanes("cuda_ad_rgb")
    4096
    >>> os.environ[MAX_LANES_VARIABLE] = "lots"; max_lanes("cuda_ad_rgb")
    Traceback (most recent call last):
    ...
    fogref.errors.FogrefError: FOGREF_MAX_LANES='lots': the lanes (pixels x samples) per pass must be ...
    >>> del os.environ[MAX_LANES_VARIABLE]
    """
    value = os.environ.get(MAX_LANES_VARIABLE, "").strip()
    if not value:
        return MAX_LANES["cuda" if variant.startswith("cuda") else "llvm"]
    n = int(value) if value.isdigit() else 0
    if not 1 <= n <= 2**31 - 1:
        raise FogrefError(
            f"{MAX_LANES_VARIABLE}={value!r}: the lanes (pixels x samples) per pass must be an integer "
            f"from 1 to {2**31 - 1} (unset: {MAX_LANES['llvm']} on the CPU, {MAX_LANES['cuda']} on a GPU)"
        )
    return n


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
