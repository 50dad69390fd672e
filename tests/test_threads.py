"""Thread control: convexguid's work runs on one BLAS/OpenMP thread per process, the caller's limits come back."""

from __future__ import annotations

import multiprocessing

from threadpoolctl import threadpool_info

from convexguid.threads import pool_worker_init, single_threaded


def _blas_threads() -> list[int]:
    return [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]


def _blas_pools() -> dict[str, int]:
    return {lib["filepath"]: lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}


def test_single_threaded_limits_blas_inside_and_restores_it_after():
    before = _blas_pools()
    with single_threaded():
        assert all(n == 1 for n in _blas_threads())
    after = _blas_pools()
    assert {path: after[path] for path in before} == before


def _threads_inside_before_scipy_linalg(_: int) -> tuple[bool, list[int]]:
    import sys

    loaded = "scipy.linalg" in sys.modules
    with single_threaded():
        import scipy.linalg  # noqa: F401 - its OpenBLAS must be limited too, loaded before the block or not

        return loaded, _blas_threads()


def test_single_threaded_reaches_scipys_blas_loaded_after_it():
    with multiprocessing.get_context("spawn").Pool(1) as pool:
        loaded, threads = pool.map(_threads_inside_before_scipy_linalg, [0])[0]
    assert not loaded
    assert all(n == 1 for n in threads)


def _worker_threads(_: int) -> list[int]:
    return _blas_threads()


def test_pool_workers_start_single_threaded():
    with multiprocessing.get_context("spawn").Pool(1, initializer=pool_worker_init) as pool:
        assert all(n == 1 for n in pool.map(_worker_threads, [0])[0])
