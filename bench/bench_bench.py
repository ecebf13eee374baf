"""The simulated bench: a fast run end to end (the cost of streaming in real time, the
bench's and the runner's, is in :mod:`bench.bench_stream`).

The rows are the wall time of ``fsi-lab run`` of the wet profile (10 s record at 10 kS/s)
on the fast embedded bench, from process start to exit: imports, bench start, configuration,
acquisition and run file, without and with the profile's analysis chain, median (min-max) of
:data:`~bench.table.REPEAT` runs; the reference is the record's length in real time.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench.table import REPEAT, Row, figure, median

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


def _timed_run(*extra: str) -> tuple[float, str]:
    with tempfile.TemporaryDirectory() as out:
        profile = wet_profile_on_the_bench(Path(out))
        started = time.perf_counter()
        proc = subprocess.run([sys.executable, "-m", "fsi_lab.cli", "run", str(profile),
                               "--set", "bench.fast=true", "--set", "run.duration=10",
                               "--out", out, "--json", *extra], check=False, capture_output=True,
                              text=True, timeout=300)
        wall = time.perf_counter() - started
    try:
        answer = json.loads(proc.stdout)
    except ValueError:
        answer = {}
    status = answer.get("exit_status") or f"error: {answer.get('error') or proc.stderr[-200:]}"
    return wall, status


def fast_run_rows() -> list[Row]:
    """Each run :data:`~bench.table.REPEAT` times (numba's cache as earlier rows left it)."""
    rows = []
    for extra, what in ((("--no-analysis",), "acquisition only"),
                        ((), "with the profile's analysis chain")):
        runs = [_timed_run(*extra) for _ in range(REPEAT)]
        walls = [wall for wall, _ in runs]
        statuses = sorted({status for _, status in runs})
        rows.append(Row(f"fsi-lab run, 10 s wet record at 10 kS/s, fast embedded bench, {what}",
                        f"{figure(walls, digits=2)} ({', '.join(statuses)})",
                        "10 s record in real time", "<= 5 s",
                        median(walls) <= 5.0 and statuses == ["completed"]))
    return rows


def rows() -> list[Row]:
    return fast_run_rows()
