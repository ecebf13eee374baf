"""Batch analysis of 50 recorded runs: ``fsi-lab analyze`` one file after the other (serial),
with ``--jobs 2`` (two local worker processes) and with ``--scheduler`` on a local Dask cluster
of two workers, in one run (issue 12: >= 1.7x with 2 jobs on 2 cores; Dask within 15 % of the
local processes), with the peak memory of each worker.

The runs are recorded by the embedded simulated bench (``fsi-lab sequence`` of the wet-beam
profile at five excitation heights, 3 s each), each copied ten times: 50 files of the same
size and content mix. Each figure is the whole command, from process start to exit (the local
workers' start included; the Dask cluster is started once beforehand, as a user's cluster
would be). The three configurations are measured :data:`ROUNDS` times, in turn, so that a change
of the machine's load falls on all three alike; the load average (1 min) before and after each
measurement is reported, since the machine may be shared.
"""

from __future__ import annotations

import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench.table import ROOT, Row, figure

FILES = 50
HEIGHTS = (0.005, 0.0075, 0.01, 0.0125, 0.015)
#: Rounds of the three configurations (each a 50-file batch: minutes on a loaded machine).
ROUNDS = 3
PLAN = """[plan]
profile = "{profile}"
set = ["run.duration=3"]
[[step]]
[step.sweep]
"excitation.height" = [{heights}]
"""


def _record(folder: Path) -> list[Path]:
    """50 run files: five recorded runs, ten copies of each."""
    plan = folder / "plan.toml"
    plan.write_text(PLAN.format(profile=ROOT / "profiles" / "wet-beam-sim.toml",
                                heights=", ".join(map(str, HEIGHTS))))
    out = folder / "recorded"
    proc = subprocess.run([sys.executable, "-m", "fsi_lab.cli", "sequence", str(plan), "--out",
                           str(out), "-q"], capture_output=True, text=True, timeout=1800,
                          check=False, cwd=ROOT)
    if proc.returncode != 0:
        raise RuntimeError(f"recording the runs failed: {proc.stderr[-500:]}")
    recorded = sorted(out.glob("2*.h5"))
    files = []
    runs = folder / "runs"
    runs.mkdir()
    for k in range(FILES):
        target = runs / f"run{k:02d}.h5"
        shutil.copyfile(recorded[k % len(recorded)], target)
        files.append(target)
    return files


def _analyze(files: list[Path], *options: str) -> tuple[float, dict, tuple[float, float]]:
    """Wall time of ``fsi-lab analyze FILES OPTIONS --json`` (s), its JSON object and the
    1-minute load average before and after."""
    before = os.getloadavg()[0]
    started = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "fsi_lab.cli", "analyze", *map(str, files),
                           *options, "--json"], capture_output=True, text=True, timeout=3600,
                          check=False, cwd=ROOT)
    elapsed = time.perf_counter() - started
    if proc.returncode != 0:
        raise RuntimeError(f"fsi-lab analyze {' '.join(options)} exited {proc.returncode}: "
                           f"{proc.stderr[-500:]}")
    data = json.loads(proc.stdout)
    if data["counts"]["analysed"] != len(files):
        raise RuntimeError(f"fsi-lab analyze {' '.join(options)}: {data['counts']}")
    return elapsed, data, (before, os.getloadavg()[0])


def _peaks(data: dict) -> list[float]:
    """The peak resident memory of each worker process, MiB."""
    peak: dict[int, float] = {}
    for entry in data["files"]:
        worker = entry["worker"]
        peak[worker["pid"]] = max(peak.get(worker["pid"], 0.0), worker["peak_rss_mib"])
    return sorted(peak.values())


def rows() -> list[Row]:
    from distributed import LocalCluster

    from fsi_lab.workers import PINNED_ENV

    times: dict[str, list[float]] = {"serial": [], "jobs": [], "dask": []}
    loads: list[float] = []
    peaks: dict[str, list[float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        files = _record(Path(tmp))
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                          dashboard_address="127.0.0.1:0", env=PINNED_ENV,
                          silence_logs=50) as cluster:
            configs = {"serial": (), "jobs": ("--jobs", "2"),
                       "dask": ("--scheduler", cluster.scheduler_address)}
            for _ in range(ROUNDS):
                for name, options in configs.items():
                    elapsed, data, load = _analyze(files, *options)
                    times[name].append(elapsed)
                    loads.extend(load)
                    peaks[name] = _peaks(data)
    serial, jobs, dask = (statistics.median(times[k]) for k in ("serial", "jobs", "dask"))
    speedup = serial / jobs
    dask_gap = dask / jobs - 1.0
    load = f"load average {min(loads):.1f}-{max(loads):.1f} on {os.cpu_count()} cores"
    name = f"batch: fsi-lab analyze {FILES} recorded runs (3 s, whole chain)"
    memory = "; ".join(f"{label}: " + ", ".join(f"{p:.0f}" for p in peaks[key]) + " MiB"
                       for key, label in (("serial", "serial (one process)"),
                                          ("jobs", "--jobs 2"), ("dask", "Dask")))
    return [
        Row(f"{name}, serial", figure(times["serial"], digits=1), load, "-", None),
        Row(f"{name}, --jobs 2", f"{figure(times['jobs'], digits=1)}; {speedup:.2f}x",
            f"serial {serial:.1f} s", ">= 1.7x", speedup >= 1.7),
        Row(f"{name}, Dask LocalCluster, 2 workers",
            f"{figure(times['dask'], digits=1)}; {100 * dask_gap:+.0f} %",
            f"--jobs 2 {jobs:.1f} s", "at most 15 % slower than --jobs 2", dask_gap <= 0.15),
        Row(f"{name}, peak memory per worker", memory, "-", "-", None),
    ]


if __name__ == "__main__":
    from bench.table import render

    print(render(rows()))
