"""Thread control for the processes convexguid starts (Monte Carlo pools, Dask workers).

numpy's BLAS (OpenBLAS) and OpenMP start one thread per core in every process that loads them. Two worker
processes on two cores then run four or more threads, which fight over the cores on the SCP's and the
simulations' many small dense products: the 20-run LPMPC Monte Carlo on 2 workers took 174 s with the default
threads and 27.5 s with ``OPENBLAS_NUM_THREADS=1`` (measured on 2 cores). Every worker process convexguid starts
therefore limits itself to one BLAS/OpenMP thread when it starts (threadpoolctl, which reaches the libraries
already loaded), so no user needs an environment variable for normal speed.

The main process is limited too, but only while convexguid works in it (:func:`single_threaded` around
``solve``, ``simulate`` and the benchmarks): the same 2-run Monte Carlo in process took 57.8 s with the default
threads and 5.4 s with one; the planning files are no slower with one thread (their dense blocks are at most a few
hundred wide). A caller's own numpy work keeps its threads.
"""

from __future__ import annotations

import contextlib
import signal
from collections.abc import Iterator

from threadpoolctl import threadpool_limits

WORKER_THREADS = 1
"""BLAS/OpenMP threads of each worker process: one per process, the processes share the cores."""


def _load_thread_pools() -> None:
    """Load the BLAS libraries convexguid uses, so that a limit reaches them all: threadpoolctl sets only the
    libraries already loaded, and SciPy's own OpenBLAS (``scipy.linalg``: the end game's QR, Cholesky and
    eigenvalues) loads at its first import. Measured: ``convexguid bench`` entered its one-thread block before that
    import, so SciPy's LAPACK kept two threads, and with another process busy on the second core the flat slew's
    warm SCP took 0.34 s instead of 0.02 s (its small factorizations waiting on the busy core)."""
    import scipy.linalg  # noqa: F401 - loaded for its thread pool


def limit_threads(threads: int = WORKER_THREADS) -> None:
    """Limit this process's BLAS and OpenMP thread pools to ``threads`` from now on."""
    _load_thread_pools()
    threadpool_limits(threads)


@contextlib.contextmanager
def single_threaded() -> Iterator[None]:
    """One BLAS/OpenMP thread inside the ``with`` block; the previous limits are restored after it."""
    _load_thread_pools()
    with threadpool_limits(WORKER_THREADS):
        yield


def pool_worker_init() -> None:
    """Initializer of a worker of a process pool: one BLAS/OpenMP thread, and Ctrl-C left to the parent (it
    reaches the whole process group; the parent decides)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    limit_threads()
