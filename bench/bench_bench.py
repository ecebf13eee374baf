"""The simulated bench: real-time streaming cost, and a fast run end to end.

Row 1 starts ``fsi-lab bench`` (real time) in a process of its own, drives it with the lab
drivers (source, amplifier, digitiser over loopback TCP) through a record of all 4 inputs at
204.8 kS/s, and divides the CPU time the bench process spent during the record (user + system,
from /proc) by the record's wall time. The reference is the real-time budget of the record; the
target is a quarter of one core. The record must also complete without an overrun, i.e. the
bench kept pace.

Rows 2 and 3 are the wall time of ``fsi-lab run`` of the wet profile (10 s record at 10 kS/s)
on the fast embedded bench, from process start to exit: imports, bench start, configuration,
acquisition and run file, without and with the profile's analysis chain, median (min-max) of
:data:`~bench.table.REPEAT` runs; the reference is the record's length in real time.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from bench.table import REPEAT, Row, figure, median

ROOT = Path(__file__).resolve().parents[1]
STREAM_RATE = 204800.0
STREAM_SECONDS = 10.0
TICKS = os.sysconf("SC_CLK_TCK")


def _cpu_seconds(pid: int) -> float:
    """User + system CPU time of process ``pid`` and its threads, s."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICKS


def _start_bench(*args: str) -> tuple[subprocess.Popen, dict]:
    proc = subprocess.Popen([sys.executable, "-m", "fsi_lab.instruments.sim.cli",
                             str(ROOT / "profiles" / "wet-beam-sim.toml"), "--json", "--quiet",
                             *args], stdout=subprocess.PIPE, text=True)
    line = proc.stdout.readline()
    if not line:
        proc.kill()
        raise RuntimeError("the simulated bench did not start")
    return proc, json.loads(line)["addresses"]


def streaming_row() -> Row:
    from fsi_lab.instruments import keysight33500, scpi_daq, shaker_amplifier
    from fsi_lab.params import validate

    proc, addresses = _start_bench()
    opened = []
    try:
        def open_(module, role, settings):
            plugin = module.PLUGIN
            instrument = plugin.open(addresses[role], validate(plugin.params, settings, role), {})
            opened.append(instrument)
            return instrument

        amplifier = open_(shaker_amplifier, "amplifier", {"gain": 1.0})
        source = open_(keysight33500, "source", {})
        daq = open_(scpi_daq, "acquisition", {"block_duration": 0.1})
        drive = 0.05 * np.sin(2 * np.pi * 17.0 * np.arange(int(20000)) / 20000.0)
        source.load_waveform(drive, 20000.0)
        amplifier.set_gain(1.0)
        rate = daq.configure({"drive": 1, "acc": 2, "vel": 3, "spare": 4}, STREAM_RATE,
                             STREAM_SECONDS)
        daq.arm()
        amplifier.enable_output(True)
        cpu0, wall0 = _cpu_seconds(proc.pid), time.perf_counter()
        source.start()
        samples = 0
        while (block := daq.read_block(5.0)) is not None:
            samples += block["vel"].size
        wall = time.perf_counter() - wall0
        cpu = _cpu_seconds(proc.pid) - cpu0
    finally:
        for instrument in opened:
            instrument.safe_state()
            instrument.close()
        proc.terminate()
        proc.wait(timeout=30)
    share = cpu / wall
    kept_pace = samples == int(round(STREAM_SECONDS * rate)) and wall < STREAM_SECONDS + 1.0
    return Row(f"sim bench streams 4 ch x {rate / 1000:g} kS/s for {STREAM_SECONDS:g} s "
               "(bench CPU / wall)",
               f"{share:.1%} of a core ({cpu:.2f} s CPU in {wall:.2f} s)",
               f"real time: {STREAM_SECONDS:g} s record", "<= 25 % of one core, in real time",
               share <= 0.25 and kept_pace)


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
                               "--out", out, "--json", *extra], capture_output=True, text=True,
                              timeout=300)
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
    return [streaming_row(), *fast_run_rows()]
