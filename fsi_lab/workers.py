"""Pools of worker processes that do not fight over the cores.

Each BLAS library (numpy and scipy each load their own OpenBLAS) and numba's parallel loops start
one thread per core in every process. Two worker processes on a 2-core machine thus run four
or more busy threads, which slows them down instead of speeding them up: analysing 50 files
took 61-70 s with two such processes against 24-26 s with one, and 14 s with two workers of one
thread each (issue 17). Every pool of workers fsi-lab starts therefore comes from
:func:`worker_pool`: one BLAS and one numba thread per worker, the parallelism being the
workers themselves.

The libraries read their thread count once, when they are loaded. A forked child inherits
libraries its parent loaded already, so setting the variables before a fork changes nothing
(measured: numpy's OpenBLAS kept two threads in each forked worker); the workers are therefore
fresh interpreters (``spawn``), started with the variables set. Forty validation trials
(``make validate``'s quadratic cases at 1 % noise and 10 kHz, median of 3 paired runs on 2
cores): two forked workers 9.0 s, one process 6.8 s, two pinned workers 5.1 s (their start-up
included).
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
from collections.abc import Iterator
from multiprocessing.pool import Pool

#: The environment of every worker: one thread for each BLAS (OpenBLAS, MKL, Apple's
#: Accelerate, OpenMP-based ones) and for numba.
PINNED_ENV = {
    "OMP_NUM_THREADS": "1",
    "OPENBLAS_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
    "VECLIB_MAXIMUM_THREADS": "1",
    "NUMBA_NUM_THREADS": "1",
}


@contextlib.contextmanager
def pinned_environment() -> Iterator[None]:
    """Set :data:`PINNED_ENV` in this process's environment for the block, for the fresh
    interpreters started inside it to inherit; the previous values are put back on leaving."""
    saved = {name: os.environ.get(name) for name in PINNED_ENV}
    os.environ.update(PINNED_ENV)  # what a spawned worker starts with
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def spawn_context() -> multiprocessing.context.SpawnContext:
    """The ``spawn`` start method: every worker a fresh interpreter (see the module notes)."""
    return multiprocessing.get_context("spawn")


@contextlib.contextmanager
def worker_pool(workers: int) -> Iterator[Pool]:
    """A :class:`multiprocessing.pool.Pool` of ``workers`` processes with one BLAS and one
    numba thread each (:data:`PINNED_ENV`), closed and joined on leaving the block.

    The workers are fresh interpreters (``spawn``): what they run and what they return must
    pickle, and the program's main module must be importable (``python -m ...`` or a script
    whose work is under ``if __name__ == "__main__":``). The variables stay set in the caller
    while the pool is open (a worker that dies is replaced, pinned too); the caller's own
    libraries are loaded already and keep their threads.

    Parameters
    ----------
    workers
        Number of processes (at least 1).
    """
    if workers < 1:
        raise ValueError(f"workers = {workers}: expected at least 1")
    with pinned_environment():
        pool = spawn_context().Pool(workers)
        try:
            yield pool
        except BaseException:
            pool.terminate()
            raise
        else:
            pool.close()
        finally:
            pool.join()
