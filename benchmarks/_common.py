"""Shared timing helpers for the benchmarks (wall clock, Dr.Jit kernel history)."""

from __future__ import annotations

import os
import platform
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

import fogref  # noqa: E402

fogref.set_variant()  # LLVM, the variant ($FOGREF_VARIANT or llvm_ad_rgb), the plugins


def timed_render(scene, spp: int, seed: int, channels=slice(0, 3)):
    """(rgb float64 image, wall seconds): ``mi.render`` then ``dr.sync_thread()``
    inside the timed region; the copy to numpy is outside it."""
    t0 = time.perf_counter()
    img = mi.render(scene, spp=spp, seed=seed)
    dr.eval(img)
    dr.sync_thread()
    t = time.perf_counter() - t0
    return np.array(img, dtype=np.float64)[..., channels], t


def warm_ladder(scenes, ladder, seed: int, first_done: bool = True) -> None:
    """Render every scene of ``scenes`` at every spp of ``ladder`` until its timed renders replay:
    each spp is its own kernel (compiled or loaded on its first call), and fogpath traces a pass's
    first call and records its ``RECORD_FROM_CALL``-th (``fogref_plugins.fogpath``).
    ``first_done``: each scene was already rendered once at ``ladder[0]``."""
    from fogref_plugins.fogpath import RECORD_FROM_CALL

    for spp in ladder:
        for _ in range(RECORD_FROM_CALL - (first_done and spp == ladder[0])):
            for scene in scenes:
                timed_render(scene, spp, seed)


def kernel_profile(scene, spp: int, seed: int) -> dict:
    """One render with Dr.Jit's kernel history on: where the wall time goes."""
    dr.kernel_history_clear() if hasattr(dr, "kernel_history_clear") else dr.kernel_history()
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        t0 = time.perf_counter()
        img = mi.render(scene, spp=spp, seed=seed)
        dr.eval(img)
        dr.sync_thread()
        wall = time.perf_counter() - t0
        hist = dr.kernel_history()
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    jit = [k for k in hist if str(k.get("type")).endswith("JIT")]
    other = [k for k in hist if not str(k.get("type")).endswith("JIT")]
    main = max(jit, key=lambda k: k["execution_time"]) if jit else None
    largest = max(jit, key=lambda k: k.get("operation_count") or 0) if jit else None  # the path kernel
    exec_ms = sum(k["execution_time"] for k in hist)
    return {
        "spp": spp,
        "wall_s": wall,
        "kernels": len(hist),
        "jit_kernels": len(jit),
        "exec_s_all": exec_ms / 1e3,
        "exec_s_main_kernel": (main["execution_time"] / 1e3) if main else None,
        "main_kernel_ops": main.get("operation_count") if main else None,
        "main_kernel_size": main.get("size") if main else None,
        "exec_s_other_jit": sum(k["execution_time"] for k in jit if k is not main) / 1e3,
        "exec_s_non_jit": sum(k["execution_time"] for k in other) / 1e3,
        "codegen_s": sum(k.get("codegen_time", 0.0) for k in jit) / 1e3,
        "backend_s": sum(k.get("backend_time", 0.0) for k in jit) / 1e3,
        "host_overhead_s": wall - exec_ms / 1e3,  # Python tracing, scene/film set-up, launches
        # the largest kernel (most operations): compiled here (neither in memory nor on disk)?
        "largest_kernel_compiled": bool(largest and not largest["cache_hit"]),
        "largest_kernel_compile_s": (
            (largest.get("codegen_time", 0.0) + largest.get("backend_time", 0.0)) / 1e3
            if largest and not largest["cache_hit"]
            else 0.0
        ),
    }


def machine_info() -> dict:
    cpu = platform.processor()
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "python": platform.python_version(),
        "mitsuba": mi.__version__,
        "drjit": dr.__version__,
        "variant": mi.variant(),
        "llvm": os.environ.get("DRJIT_LIBLLVM_PATH", ""),
    }


def median(xs):
    return float(statistics.median(xs))


def final_and_multiple_channels():
    """The channels of a fogpath ``mi.render`` image (R,G,B, then the AOVs) that the variance
    benchmarks keep: R,G,B of the final image, then ``multiple.R,G,B``."""
    from fogref import gbuffer

    names = gbuffer.sample_channel_names()
    return [0, 1, 2] + [3 + names.index(f"multiple.{c}") for c in "RGB"]


def part_variances(scene, spp: int, seeds) -> dict:
    """Per-pixel variance of one sample of each part of :data:`fogref.gbuffer.SQUARED_GROUPS`,
    summed over pixels and RGB, from a fogpath ``render_moments`` of ``spp`` samples per seed:
    part -> one value per seed (radiance^2 in the scene's unit, linear Rec.709 RGB)."""
    from fogref import gbuffer

    integ = scene.integrator()
    names = ["R", "G", "B"] + integ.aov_names()
    out: dict = {}
    for s in seeds:
        sums, sq = integ.render_moments(scene, 0, s, spp)
        sums, sq = np.array(sums, np.float64), np.array(sq, np.float64)
        for k, g in enumerate(gbuffer.SQUARED_GROUPS):
            idx = [names.index(c) for c in (["R", "G", "B"] if g == "final" else gbuffer.channel_names(g))]
            m = sums[..., idx] / spp
            out.setdefault(g, []).append(float((sq[..., 3 * k : 3 * k + 3] / spp - m * m).sum()))
    return out


def chi2_per_pixel(a, b):
    """Mean over pixels and RGB of (difference of the two stacks' means)^2 / (its variance from
    their spreads): ~1 when the two stacks of independent renders estimate the same image."""
    var = np.maximum(a.var(0, ddof=1) / len(a) + b.var(0, ddof=1) / len(b), 1e-30)
    return float(((a.mean(0) - b.mean(0)) ** 2 / var).mean())
