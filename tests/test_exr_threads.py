"""fogref's EXR reads and writes run OpenEXR's thread pool with one thread per core
(``fogref.exrio.use_every_core``), and the file does not depend on it.

* From OpenEXR's default (no thread), a write leaves the pool at the cores this process may run
  on; a larger pool set before is kept.
* A 72-channel, 64x48 file (3 ZIP blocks, 4 with PIZ) written with no thread and with the pool is
  the same byte for byte, and reads back the same values through the pool (smallest error
  detected: one byte of the file).
"""

import os

import numpy as np
import OpenEXR
import pytest

import fogref.exrio as X

CORES = len(os.sched_getaffinity(0))


@pytest.fixture
def pool():
    """OpenEXR's pool size, restored after the test."""
    before = OpenEXR.global_thread_count()
    yield
    OpenEXR.set_global_thread_count(before)


def _channels():
    rng = np.random.default_rng(5)
    ramp = np.linspace(0.0, 2.0, 48 * 64).reshape(48, 64)
    return {
        f"c{k:02d}": (ramp * k + 0.01 * rng.standard_normal(ramp.shape)).astype(np.float32) for k in range(72)
    }


def test_a_write_gives_the_pool_every_core_and_keeps_a_larger_one(tmp_path, pool):
    OpenEXR.set_global_thread_count(0)
    X.write_exr(tmp_path / "a.exr", {"R": np.ones((2, 3))})
    assert OpenEXR.global_thread_count() == CORES
    OpenEXR.set_global_thread_count(CORES + 3)
    X.read_exr(tmp_path / "a.exr")
    assert OpenEXR.global_thread_count() == CORES + 3


@pytest.mark.parametrize("compression", ["zip", "piz"])
def test_the_file_is_the_same_with_and_without_threads(tmp_path, pool, monkeypatch, compression):
    chans = _channels()
    monkeypatch.setattr(X, "use_every_core", OpenEXR.global_thread_count)  # the pool as set below
    OpenEXR.set_global_thread_count(0)
    X.write_exr(tmp_path / "none.exr", chans, compression=compression)
    OpenEXR.set_global_thread_count(max(CORES, 2))
    X.write_exr(tmp_path / "pool.exr", chans, compression=compression)
    assert (tmp_path / "none.exr").read_bytes() == (tmp_path / "pool.exr").read_bytes()
    back, _ = X.read_exr(tmp_path / "pool.exr")
    assert all(np.array_equal(back[k], v) for k, v in chans.items())
