"""Shared fixtures: the real example plugin distribution, profiles and the CLI in a subprocess."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from support import EXAMPLE_PLUGIN, SIM_PROFILE

from fsi_lab.registry import load_registry
from fsi_lab.workers import PINNED_ENV

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
# One BLAS and one numba thread in each test process (the workers of `make test`, started after
# this, inherit it; a user's own setting is kept): two worker processes of two busy threads
# each on two cores run slower than two of one (fsi_lab.workers; measured: test_identify.py
# in two workers, twice each way, 321 and 305 s of CPU unpinned, 251 and 220 s pinned).
for _name, _value in PINNED_ENV.items():
    os.environ.setdefault(_name, _value)


@pytest.fixture(scope="session", autouse=True)
def bench_lock_dir(tmp_path_factory):
    """Runs on real-instrument addresses take bench locks: in a directory of the session's
    own (inherited by the CLI's subprocesses), never the user's."""
    path = tmp_path_factory.mktemp("bench-locks")
    saved = os.environ.get("FSI_LAB_LOCK_DIR")
    os.environ["FSI_LAB_LOCK_DIR"] = str(path)
    yield path
    if saved is None:
        os.environ.pop("FSI_LAB_LOCK_DIR", None)
    else:
        os.environ["FSI_LAB_LOCK_DIR"] = saved


@pytest.fixture(scope="session")
def example_plugin_dir(tmp_path_factory) -> Path:
    """The example plugin distribution pip-installed into a directory of its own, from a copy
    of its source (a build writes into the tree it builds, and the test workers of
    ``make test`` would build the same tree at once)."""
    source = tmp_path_factory.mktemp("example-source") / "example_plugin"
    shutil.copytree(EXAMPLE_PLUGIN, source,
                    ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    target = tmp_path_factory.mktemp("site")
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-build-isolation",
         "--target", str(target), str(source)],
        check=True, timeout=300, capture_output=True,
    )
    return target


@pytest.fixture
def with_example_plugin(example_plugin_dir, monkeypatch) -> Path:
    """Put the installed example distribution on sys.path for in-process tests."""
    monkeypatch.syspath_prepend(str(example_plugin_dir))
    monkeypatch.setenv("PYTHONPATH", str(example_plugin_dir))
    return example_plugin_dir


@pytest.fixture
def registry():
    return load_registry()


@pytest.fixture
def sim_profile(tmp_path):
    """Write a small in-process bench profile; keyword arguments fill its blanks."""

    def make(duration=1.0, realtime="false", amplitude=0.5, amplifier_extra="",
             acquisition_extra="", analysis="", name="sim.toml") -> Path:
        path = tmp_path / name
        path.write_text(SIM_PROFILE.format(
            duration=duration, realtime=realtime, amplitude=amplitude,
            amplifier_extra=amplifier_extra, acquisition_extra=acquisition_extra,
            analysis=analysis))
        return path

    return make



@pytest.fixture(scope="module")
def dask_cluster():
    """A Dask scheduler and two worker processes (one thread each) on 127.0.0.1 for the
    module's tests, stopped afterwards; a worker that dies fails its task at once (the
    scheduler does not retry it on another worker)."""
    import dask
    from distributed import LocalCluster

    from fsi_lab.workers import PINNED_ENV

    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                               host="127.0.0.1", dashboard_address="127.0.0.1:0",
                               env=PINNED_ENV, silence_logs=50)
        try:
            yield cluster
        finally:
            cluster.close(timeout=30)
