"""fogref.cluster's LocalCluster: the environment its worker processes start with."""

from __future__ import annotations

import os

import pytest

from fogref import cluster


def _worker_env(tmp_path, name: str) -> list:
    """``os.environ.get(name)`` in each worker of a one-worker LocalCluster started by connect."""
    client, local, _ = cluster.connect(None, 1, tmp_path / "workers.log", "test")
    try:
        return list(client.run(os.environ.get, name).values())
    finally:
        cluster.stop(client, local, tmp_path / "workers.log")


def test_local_workers_start_without_dasks_malloc_trim_threshold(tmp_path, monkeypatch):
    """Dask's nanny sets MALLOC_TRIM_THRESHOLD_=65536 in its workers, which makes glibc map and unmap
    every array over 128 KiB (the Unreal fit took 1.5x the CPU); connect's workers start without it, and
    keep Dask's other defaults (one BLAS and OpenMP thread)."""
    monkeypatch.delenv("MALLOC_TRIM_THRESHOLD_", raising=False)
    assert _worker_env(tmp_path, "MALLOC_TRIM_THRESHOLD_") == [None]
    assert _worker_env(tmp_path, "OMP_NUM_THREADS") == ["1"]


def test_local_workers_keep_a_malloc_trim_threshold_the_user_set(tmp_path, monkeypatch):
    monkeypatch.setenv("MALLOC_TRIM_THRESHOLD_", "131072")
    assert _worker_env(tmp_path, "MALLOC_TRIM_THRESHOLD_") == ["131072"]


@pytest.mark.parametrize("name", cluster.WORKER_UNSET_ENV)
def test_the_unset_variables_are_dasks_defaults(name):
    """Each variable connect leaves out is one Dask's nanny would set (so leaving it out does something)."""
    import dask
    import distributed  # noqa: F401  (its defaults join dask's configuration on import)

    assert name in dask.config.get("distributed.nanny.pre-spawn-environ")
