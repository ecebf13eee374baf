"""Worker pools (fsi_lab.workers): every worker runs one BLAS and one numba thread, counted in
the worker itself from the libraries it has loaded, not only from its environment."""

import ctypes
import os

import pytest

from fsi_lab.workers import PINNED_ENV, worker_pool

#: How each OpenBLAS build that numpy and scipy ship names its thread count function.
_GET_THREADS = ("scipy_openblas_get_num_threads64_", "scipy_openblas_get_num_threads",
                "openblas_get_num_threads64_", "openblas_get_num_threads")


def threads_here(_=None) -> dict:
    """In the calling process, after numpy, scipy's BLAS and numba are loaded: the threads of
    every OpenBLAS library mapped into the process, numba's threads and the pinned variables."""
    import numba
    import numpy as np
    import scipy.linalg

    np.dot(np.ones((2, 2)), np.ones((2, 2)))
    scipy.linalg.solve(np.eye(2), np.ones(2))
    with open("/proc/self/maps") as maps:
        libraries = sorted({line.split()[-1] for line in maps if "openblas" in line.lower()})
    blas = {}
    for library in libraries:
        handle = ctypes.CDLL(library)
        name = next((n for n in _GET_THREADS if hasattr(handle, n)), None)
        if name is not None:
            blas[os.path.basename(library)] = getattr(handle, name)()
    return {"pid": os.getpid(), "blas": blas, "numba": numba.get_num_threads(),
            "env": {name: os.environ.get(name) for name in PINNED_ENV}}


def test_each_worker_runs_one_blas_and_one_numba_thread(monkeypatch):
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "2")  # a user's setting, restored afterwards
    monkeypatch.delenv("NUMBA_NUM_THREADS", raising=False)
    with worker_pool(2) as pool:
        seen = pool.map(threads_here, range(4), chunksize=1)
        assert os.environ["NUMBA_NUM_THREADS"] == "1"  # a replaced worker is pinned too
    assert os.getpid() not in {s["pid"] for s in seen}
    for worker in seen:
        assert worker["env"] == PINNED_ENV
        assert worker["numba"] == 1
        # numpy's and scipy's wheels each bring an OpenBLAS; another BLAS needs its own probe
        assert len(worker["blas"]) >= 2, worker
        assert set(worker["blas"].values()) == {1}, worker
    assert os.environ["OPENBLAS_NUM_THREADS"] == "2" and "NUMBA_NUM_THREADS" not in os.environ


def test_a_pool_needs_a_worker():
    with pytest.raises(ValueError, match="workers = 0: expected at least 1"), worker_pool(0):
        pass
