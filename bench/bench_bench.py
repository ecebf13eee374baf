"""The simulated bench: a fast run end to end (the cost of streaming in real time, the
bench's and the runner's, is in :mod:`bench.bench_stream`).

The rows are the wall time of ``fsi-lab run`` of the wet profile (10 s record at 10 kS/s)
on the fast embedded bench, from process start to exit: imports, bench start, configuration,
acquisition and run file, without and with the profile's analysis chain, median (min-max) of
:data:`~bench.table.REPEAT` runs, cold (an empty numba cache for each run: the simulated beam
and the analysis compile) and warm (the cache filled). The reference is the record's length in
real time, and the floor a process that imports numpy and h5py and writes the record.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench.table import REPEAT, Row, figure, median, process_times

ROOT = Path(__file__).resolve().parents[1]


EMBEDDED_BENCH = """[bench]
embedded = true
fast = true

[bench.source]
plugin = "keysight33500"
address = "embedded"

[bench.amplifier]
plugin = "shaker-amplifier"
address = "embedded"
gain = 2.0

[bench.vibrometer]
plugin = "polytec"
address = "embedded"
range = "125mm/s/V"

[bench.acquisition]
plugin = "scpi-daq"
address = "embedded"

"""


def wet_profile_on_the_bench(directory: Path) -> Path:
    """The wet profile (its physics, excitation and analysis chain) with its instruments on the
    fast embedded bench."""
    text = (ROOT / "profiles" / "wet-beam-sim.toml").read_text()
    if 'address = "embedded"' not in text:
        first = min(text.index(key) for key in ("[bench]", "[bench.") if key in text)
        text = text[:first] + EMBEDDED_BENCH + text[text.index("[channels."):]
    path = directory / "wet-bench.toml"
    path.write_text(text)
    return path


def _timed_run(extra: tuple[str, ...], cache: Path) -> tuple[float, str]:
    """Wall time of one ``fsi-lab run`` of the wet profile on the fast embedded bench, s, with
    numba's cache in ``cache``; and how the run ended."""
    with tempfile.TemporaryDirectory() as out:
        profile = wet_profile_on_the_bench(Path(out))
        started = time.perf_counter()
        proc = subprocess.run([sys.executable, "-m", "fsi_lab.cli", "run", str(profile),
                               "--set", "bench.fast=true", "--set", "run.duration=10",
                               "--out", out, "--json", *extra], check=False, capture_output=True,
                              text=True, timeout=600,
                              env={**os.environ, "NUMBA_CACHE_DIR": str(cache)})
        wall = time.perf_counter() - started
    try:
        answer = json.loads(proc.stdout)
    except ValueError:
        answer = {}
    status = answer.get("exit_status") or f"error: {answer.get('error') or proc.stderr[-200:]}"
    return wall, status


#: The floor of a run: a process that imports numpy and h5py and writes a record of the wet
#: profile's three channels (10 s at 10 kS/s) into an HDF5 file.
WRITE_RECORD = ("import sys, h5py, numpy; f = h5py.File(sys.argv[1], 'w'); "
                "[f.create_dataset(n, data=numpy.random.default_rng(0).normal(size=100000)) "
                "for n in ('drive', 'base_acceleration', 'tip_velocity')]; f.close()")


def fast_run_rows() -> list[Row]:
    """Each run :data:`~bench.table.REPEAT` times cold (an empty numba cache for each) and
    warm (the cache filled by an untimed run), next to the floor measured as many times; the
    target is the warm run's (a cold row fails only if a run did not complete)."""
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        floor = process_times([sys.executable, "-c", WRITE_RECORD, str(Path(folder) / "f.h5")])
        reference = (f"10 s record in real time; floor (import numpy, h5py, write the record) "
                     f"{figure(floor, digits=2)}")
        for extra, what in ((("--no-analysis",), "acquisition only"),
                            ((), "with the profile's analysis chain")):
            cold_cache, warm_cache = Path(folder) / "cold", Path(folder) / "warm"
            cold = []
            for _ in range(REPEAT):
                shutil.rmtree(cold_cache, ignore_errors=True)
                cold.append(_timed_run(extra, cold_cache))
            shutil.rmtree(warm_cache, ignore_errors=True)
            _timed_run(extra, warm_cache)  # fills the cache
            warm = [_timed_run(extra, warm_cache) for _ in range(REPEAT)]
            for runs, when, warmed in ((cold, "cold (empty numba cache)", False),
                                       (warm, "warm (cache filled)", True)):
                walls = [wall for wall, _ in runs]
                statuses = sorted({status for _, status in runs})
                done = statuses == ["completed"]
                rows.append(Row(f"fsi-lab run, 10 s wet record at 10 kS/s, fast embedded bench, "
                                f"{what}, {when}",
                                f"{figure(walls, digits=2)} ({', '.join(statuses)})", reference,
                                "<= 5 s" if warmed else "-",
                                median(walls) <= 5.0 and done if warmed else None if done
                                else False))
    return rows


def rows() -> list[Row]:
    return fast_run_rows()
