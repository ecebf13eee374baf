"""``fsi-lab analyze`` on long records: 1, 10 and 60 min at 204.8 kS/s x 4 channels (and 15 s,
which today's analysis holds in memory on this machine: the per-sample figures of the rest).

Each record is written in a temporary folder, a chunk at a time, as a run file of the wet
profile (its analysis chain on ``tip_velocity``, the base acceleration as reference): the model's
response to the profile's pulse (the shaker and the 4-mode beam of :class:`fsi_lab.modelling.
BenchPhysics`, tip and mid-span velocity) over one period of :data:`PERIOD_S`, repeated for the
whole record - an impulse train, so that every part of the record holds a free decay to analyse -
with white noise on every channel (a noise bank read at random offsets, so the noise does not
repeat with the period). Channels: ``drive`` (V), ``base_acceleration`` (m/s^2),
``tip_velocity`` and ``mid_velocity`` (m/s).

Each row runs ``fsi-lab analyze RUN.h5`` as a user does, the whole process, once (these are
minutes of work), and gives its wall time, its peak resident memory (the largest of the process
and its children, from ``wait4``) and the samples it analysed per second (all channels). Next to
it, measured in the same run on the same file: the floor of reading the same bytes (every channel
with h5py, a chunk at a time) and numpy's ``rfft`` of one channel's length. Both run in a child
process under the same guard.

Guards: the free disk is checked first (the file, and a second copy for the rewrite that stores
the analysis); a record that does not fit is skipped with the reason. Every child process runs
under a memory limit of :data:`MEMORY_SHARE` of the memory available when the row starts (an
address-space limit set with ``resource.setrlimit`` in the child, and the resident memory
polled and the child stopped when it passes the limit), so that a row that would need more
memory than the machine has is stopped with the reason instead of swapping the machine to
death. Where numpy's FFT of the length does not fit either, its time is estimated (n log n) from
the longest length that did, and says so. The record is deleted after its row.

``BENCH_LONG_MINUTES`` (e.g. ``1,10``) chooses the lengths; the default is 0.25, 1, 10 and 60.
"""

from __future__ import annotations

import math
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from bench.table import ROOT, Row

RATE = 204_800.0
MINUTES = (0.25, 1.0, 10.0, 60.0)
CHANNELS = 4
PROFILE = ROOT / "profiles" / "wet-beam-sim.toml"
#: Period of the impulse train, s: the pulse's decays reach the noise well within it.
PERIOD_S = 10.0
#: Noise RMS of each channel (units of the channel).
NOISE = {"drive": 1e-5, "base_acceleration": 2e-3, "tip_velocity": 2e-5, "mid_velocity": 2e-5}
#: Samples written at a time.
CHUNK = 1 << 20
#: Share of the machine's available memory a child may use.
MEMORY_SHARE = 0.4
#: Virtual memory a Python process with numpy, numba and h5py maps beyond what it touches
#: (allowed on top of the resident limit in the address-space limit).
VIRTUAL_SLACK = 6 << 30
#: A target of issue 16, item 1 (analysis that streams), for the yardstick rows.
TARGET_RSS = 1.5e9


def _available_memory() -> float:
    """MemAvailable of /proc/meminfo, bytes."""
    with open("/proc/meminfo") as handle:
        for line in handle:
            if line.startswith("MemAvailable:"):
                return float(line.split()[1]) * 1024
    return 0.0


def _fsi_lab() -> list[str]:
    script = Path(sys.executable).with_name("fsi-lab")
    return [str(script)] if script.exists() else [sys.executable, "-m", "fsi_lab.cli"]


# --------------------------------------------------------------------------- the record
def _period() -> dict[str, np.ndarray]:
    """One period of the train: drive (V), base acceleration (m/s^2), tip and mid velocity
    (m/s) at :data:`RATE`, the model starting at rest."""
    from fsi_lab.modal_integrator import ModalSimulator
    from fsi_lab.modelling import beam_model
    from fsi_lab.preflight import prepare_excitation
    from fsi_lab.profile import load_profile
    from fsi_lab.registry import load_registry
    from fsi_lab.shaker import ShakerModel
    from fsi_lab.simulation import drive_block

    registry = load_registry()
    profile = load_profile(PROFILE, registry)
    waveform, rate = prepare_excitation(profile, registry)
    model = beam_model(profile.specimen, profile.model)
    gain = float(profile.roles["amplifier"].settings["gain"])
    n = int(PERIOD_S * RATE)
    drive = drive_block(waveform, rate, 0, n, RATE)
    _, acceleration = ShakerModel.from_profile(RATE, profile.shaker).advance(drive * gain)
    point = profile.specimen.measurement_point
    beam = ModalSimulator(model, RATE, [point, 0.5 * point], outputs=("absolute_velocity",))
    velocity = beam.advance(acceleration)["absolute_velocity"]
    return {"drive": drive, "base_acceleration": acceleration,
            "tip_velocity": np.ascontiguousarray(velocity[:, 0]),
            "mid_velocity": np.ascontiguousarray(velocity[:, 1])}


def write_record(path: Path, minutes: float, period: dict[str, np.ndarray]) -> int:
    """Write the run file of ``minutes`` of the train; returns the samples per channel."""
    from fsi_lab.runfile import RunFileWriter, utc_now

    total = int(round(minutes * 60.0 * RATE))
    quantities = {"drive": ("voltage", "V"), "base_acceleration": ("acceleration", "m/s^2"),
                  "tip_velocity": ("velocity", "m/s"), "mid_velocity": ("velocity", "m/s")}
    rng = np.random.default_rng(16)
    bank = rng.standard_normal(1 << 24)
    writer = RunFileWriter(path, {"kind": "simulated", "profile": PROFILE.read_text(),
                                  "profile_path": str(PROFILE), "overrides": [],
                                  "run_name": "long record (bench)", "uuid": "0" * 32,
                                  "start_time": utc_now()})
    try:
        for name, (quantity, unit) in quantities.items():
            writer.create_channel(name, {"units": unit, "quantity": quantity,
                                         "sample_rate": RATE, "t0": 0.0, "sensitivity": 1.0,
                                         "source_instrument": "model"})
        size = period["drive"].size
        for start in range(0, total, CHUNK):
            stop = min(total, start + CHUNK)
            index = np.arange(start, stop) % size
            for name in quantities:
                offset = int(rng.integers(0, bank.size - CHUNK))
                noise = bank[offset:offset + stop - start] * NOISE[name]
                writer.append(name, period[name][index] + noise)
        writer.set_attrs({"exit_status": "completed", "error": "", "traceback": "",
                          "stop_time": utc_now()})
    finally:
        writer.close()
    return total


# --------------------------------------------------------------------------- guarded children
class Stopped(Exception):
    """A child stopped by the memory guard."""


def _limit_memory(limit: float):
    def apply():
        virtual = int(limit + VIRTUAL_SLACK)
        resource.setrlimit(resource.RLIMIT_AS, (virtual, virtual))
    return apply


def _tree_rss(pid: int) -> float:
    """Resident memory of a process and its children, bytes (0 once it is gone)."""
    total = 0.0
    pending = [pid]
    while pending:
        current = pending.pop()
        try:
            with open(f"/proc/{current}/status") as handle:
                for line in handle:
                    if line.startswith("VmRSS:"):
                        total += float(line.split()[1]) * 1024
            with open(f"/proc/{current}/task/{current}/children") as handle:
                pending.extend(int(p) for p in handle.read().split())
        except (OSError, ValueError):
            continue
    return total


def guarded(argv: list[str], limit: float, timeout: float = 7200.0
            ) -> tuple[float, float, float]:
    """Run ``argv`` under the memory guard; its wall time (s), peak resident memory (bytes) and
    CPU time (s, user + system: what the load of a shared machine leaves alone).

    Raises
    ------
    Stopped
        It passed ``limit`` bytes of resident memory (stopped), or failed for lack of memory.
    RuntimeError
        It failed otherwise.
    """
    started = time.perf_counter()
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            cwd=ROOT, preexec_fn=_limit_memory(limit),
                            env={**os.environ, "PYTHONPATH": str(ROOT)})
    peak_polled = 0.0
    stopped = False
    while True:
        # wait4 (not Popen.poll, which would reap the child first) gives its resource usage.
        pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
        if pid:
            proc.returncode = os.waitstatus_to_exitcode(status)
            break
        rss = _tree_rss(proc.pid)
        peak_polled = max(peak_polled, rss)
        if rss > limit and not stopped:
            stopped = True
            proc.kill()
        elif time.perf_counter() - started > timeout:
            proc.kill()
            _, status, usage = os.wait4(proc.pid, 0)
            proc.returncode = os.waitstatus_to_exitcode(status)
            raise RuntimeError(f"{' '.join(argv[:3])}: no end within {timeout:g} s")
        time.sleep(0.2)
    elapsed = time.perf_counter() - started
    stderr = proc.stderr.read() if proc.stderr else ""
    proc.stderr.close()
    peak = max(peak_polled, usage.ru_maxrss * 1024.0)
    if stopped:
        raise Stopped(f"stopped after {elapsed:.0f} s at {peak / 1e9:.2f} GB resident, past "
                      f"its limit of {limit / 1e9:.2f} GB ({MEMORY_SHARE:.0%} of the memory "
                      "available)")
    code = proc.returncode
    if code != 0:
        if "MemoryError" in stderr or "Unable to allocate" in stderr or code == -9:
            last = (stderr.strip().splitlines() or [f"exit {code}"])[-1]
            raise Stopped(f"ran out of its limit of {limit / 1e9:.2f} GB after {elapsed:.0f} s "
                          f"({last[:120]})")
        raise RuntimeError(f"{' '.join(argv[:3])} exited {code}: {stderr[-400:]}")
    return elapsed, peak, usage.ru_utime + usage.ru_stime


def _read_floor(path: Path, limit: float) -> float:
    """Seconds to read every channel of ``path`` with h5py, a chunk at a time."""
    script = ("import sys, h5py, numpy\n"
              "with h5py.File(sys.argv[1], 'r') as f:\n"
              "    for d in f['channels'].values():\n"
              f"        for i in range(0, d.shape[0], {CHUNK}):\n"
              f"            numpy.asarray(d[i:i + {CHUNK}])\n")
    return guarded([sys.executable, "-c", script, str(path)], limit)[0]


def _fft_floor(samples: int, limit: float, folder: Path) -> float:
    """Seconds of numpy's rfft of ``samples`` random numbers (one channel's length), in a
    guarded child."""
    result = folder / "fft-seconds.txt"
    script = ("import sys, time, numpy\n"
              "x = numpy.random.default_rng(0).standard_normal(int(sys.argv[1]))\n"
              "started = time.perf_counter()\n"
              "numpy.fft.rfft(x)\n"
              "open(sys.argv[2], 'w').write(str(time.perf_counter() - started))\n")
    guarded([sys.executable, "-c", script, str(samples), str(result)], limit)
    return float(result.read_text())


# --------------------------------------------------------------------------- rows
def _size(size: float) -> str:
    return f"{size / 1e9:.1f} GB" if size >= 1e9 else f"{size / 1e6:.0f} MB"


def _row(minutes: float, period: dict, ffts: dict[int, float]) -> tuple[Row, dict]:
    """One record's row (and its time, when it was analysed); ``ffts`` collects the FFT floor
    per length, for an estimate where a length cannot be transformed in memory."""
    total = int(round(minutes * 60.0 * RATE))
    size = total * CHANNELS * 8
    name = (f"analyze {minutes:g} min @ {RATE / 1e3:g} kS/s x {CHANNELS} ch "
            f"({total * CHANNELS / 1e6:,.0f} M samples, {_size(size)})")
    target = f"RSS < {TARGET_RSS / 1e9:g} GB (issue 16 item 1)"
    with tempfile.TemporaryDirectory(prefix="fsi-lab-long-") as folder:
        free = shutil.disk_usage(folder).free
        if free < 2.2 * size:
            return Row(name, f"not run: {folder} has {_size(free)} free; the record and the "
                             f"analysis's rewrite of it need {_size(2.2 * size)}", "-",
                       target, None), {}
        path = Path(folder) / "long.h5"
        started = time.perf_counter()
        write_record(path, minutes, period)
        written = time.perf_counter() - started
        limit = MEMORY_SHARE * _available_memory()
        reference = []
        try:
            reference.append(f"h5py read {_read_floor(path, limit):.1f} s")
        except (Stopped, RuntimeError) as exc:
            reference.append(f"h5py read: {exc}")
        try:
            ffts[total] = _fft_floor(total, limit, Path(folder))
            reference.append(f"numpy rfft of {total:,} samples {ffts[total]:.2f} s")
        except (Stopped, RuntimeError) as exc:
            known = max(ffts, default=0)
            scaled = ffts[known] * total * math.log(total) / (known * math.log(known)) \
                if known else 0.0
            estimate = f"; n log n from {known:,}: {scaled:.1f} s" if known else ""
            reference.append(f"numpy rfft of {total:,}: {exc}{estimate}")
        reference.append(f"(written in {written:.0f} s)")
        try:
            # (about 6 s of CPU per million samples of a channel: an hour is 70 min of CPU)
            elapsed, peak, cpu = guarded([*_fsi_lab(), "analyze", str(path), "--quiet"], limit,
                                         timeout=max(7200.0, 40e-6 * total))
        except Stopped as exc:
            return Row(name, f"not analysed: {exc}", "; ".join(reference), target, False), {}
        rate = total * CHANNELS / elapsed
        ours = (f"{elapsed:.1f} s ({cpu:.0f} s CPU), peak RSS {peak / 1e9:.2f} GB "
                f"({peak / (total * CHANNELS):.0f} B/sample), {rate / 1e6:.2f} M samples/s")
        return (Row(name, ours, "; ".join(reference), target, peak < TARGET_RSS),
                {"minutes": minutes, "seconds": elapsed, "cpu": cpu})


def rows() -> list[Row]:
    wanted = os.environ.get("BENCH_LONG_MINUTES")
    minutes = [float(m) for m in wanted.split(",")] if wanted else list(MINUTES)
    period = _period()
    ffts: dict[int, float] = {}
    out, timed = [], []
    for m in minutes:
        row, measured = _row(m, period, ffts)
        print(f"  {row.name}: {row.ours}", file=sys.stderr, flush=True)
        out.append(row)
        if measured:
            timed.append(measured)
    tens = {t["minutes"]: (t["seconds"], t["cpu"]) for t in timed}
    for short, long in ((1.0, 10.0), (10.0, 60.0)):
        if short in tens and long in tens:
            k = long / short
            wall, cpu = (tens[long][i] / (k * tens[short][i]) for i in (0, 1))
            out.append(Row(f"  {long:g} min time / ({k:g} x {short:g} min time): linear in "
                           "length", f"{wall:.2f} wall, {cpu:.2f} CPU", "1.00",
                           "within 10 % (item 1)",
                           math.isfinite(wall) and abs(wall - 1.0) <= 0.10))
    return out
