"""Streaming the digitiser: what 4 inputs at 204.8 kS/s cost the runner, next to the floor.

The simulated bench runs in real time in a process of its own (``fsi-lab bench`` with the wet
profile's beam), its instruments on loopback TCP. Each of :data:`~bench.table.REPEAT`
repetitions is a fresh Python process (nothing the table imported before is in it) that, against
that bench, in this order:

1. runs the wet profile with a fourth channel at 204.8 kS/s for :data:`STREAM_SECONDS` with
   :class:`~fsi_lab.runner.Runner` (no analysis): the process's CPU time (``time.process_time``:
   every thread of the runner, its HDF5 file and the amplifier's watchdog feeder included, the
   bench excluded) from the state ``running`` to ``finalizing``, per second of record. The
   first record of the process is the cold figure, a second one the warm figure;
2. streams the same record through the digitiser driver alone (trigger immediate), and again
   with each block read by pyvisa's ``query_binary_values``, the way pyvisa reads a binary block
   (with the read termination character enabled): the reference for the block reads;
3. reads the same bytes (0.1 s blocks of 4 x 4 B x 204.8 kS/s, sent in real time by a thread)
   from a loopback socket in one ``recv_into`` loop: the floor, the CPU time of the reading
   thread alone (``time.thread_time``).

The bench process's CPU time per second of the runner's records is the simulated bench's own
row (real time, so it must keep up: every sample arrives, no overrun).
"""

from __future__ import annotations

import json
import os
import re
import select
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from bench.table import REPEAT, Row, figure, median

ROOT = Path(__file__).resolve().parents[1]
STREAM_RATE = 204800.0
STREAM_SECONDS = 5.0
BLOCK_SECONDS = 0.1
INPUTS = 4
#: The runner's target, % of one core per second of record (issue 17).
RUNNER_TARGET = 15.0
#: The simulated bench's own target, % of one core.
BENCH_TARGET = 25.0
TICKS = os.sysconf("SC_CLK_TCK")
SPARE_CHANNEL = """[channels.spare]
quantity = "voltage"
unit = "V"
sensitivity = 1.0
input = 4

"""


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of process ``pid`` and its threads, s (from /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICKS


def _readline(proc: subprocess.Popen, timeout: float) -> str:
    ready, _, _ = select.select([proc.stdout], [], [], timeout)
    return proc.stdout.readline() if ready else ""


def start_real_time_bench(directory: Path) -> tuple[subprocess.Popen, dict]:
    """``fsi-lab bench`` of the wet profile in real time (its ``fast = true`` turned off), in a
    process of its own; the process and its JSON line (addresses and profile snippet)."""
    text = (ROOT / "profiles" / "wet-beam-sim.toml").read_text()
    profile = directory / "real-time-bench.toml"
    profile.write_text(re.sub(r"(?m)^fast = true\b.*$", "fast = false", text))
    proc = subprocess.Popen([sys.executable, "-m", "fsi_lab.instruments.sim.cli", str(profile),
                             "--json", "--quiet"], stdout=subprocess.PIPE, text=True, cwd=ROOT)
    line = _readline(proc, 120.0)
    if not line:
        proc.kill()
        proc.wait(timeout=30)
        raise RuntimeError("the simulated bench did not print its addresses within 120 s")
    return proc, json.loads(line)


def stream_profile(snippet: str, seconds: float) -> str:
    """The wet profile on the bench whose ``[bench.*]`` tables are ``snippet``, with a fourth
    channel (input 4), at :data:`STREAM_RATE` for ``seconds``."""
    text = (ROOT / "profiles" / "wet-beam-sim.toml").read_text()
    head, tail = text[:text.index("[bench]")], text[text.index("[channels.drive]"):]
    tail = tail.replace("[excitation]", SPARE_CHANNEL + "[excitation]", 1)
    head = re.sub(r"(?m)^sample_rate = .*$", f"sample_rate = {STREAM_RATE}", head, count=1)
    head = re.sub(r"(?m)^duration = .*$", f"duration = {seconds}", head, count=1)
    return head + "[bench]\nembedded = false\n\n" + snippet + "\n" + tail


# --------------------------------------------------------------------------- in the child
def runner_record(profile_path: Path, out_dir: Path, bench_pid: int) -> dict:
    """One run of ``profile_path``: the runner's and the bench's CPU time from ``running`` to
    ``finalizing``, s, its wall time, s, and its exit status."""
    from fsi_lab.events import EventBus, StateChanged
    from fsi_lab.profile import load_profile
    from fsi_lab.registry import load_registry
    from fsi_lab.runner import Runner

    registry = load_registry()
    profile = load_profile(profile_path, registry)
    marks: dict[str, tuple[float, float, float]] = {}

    def mark(event) -> None:
        if isinstance(event, StateChanged) and event.state in ("running", "finalizing"):
            marks.setdefault(event.state, (time.process_time(), cpu_seconds(bench_pid),
                                           time.perf_counter()))

    bus = EventBus()
    bus.subscribe(mark)
    outcome = Runner(profile, registry, out_dir, bus=bus, analyze=False).run()
    if outcome.exit_status != "completed" or set(marks) != {"running", "finalizing"}:
        raise RuntimeError(f"the streaming run ended {outcome.exit_status}: {outcome.error}")
    (cpu0, bench0, wall0), (cpu1, bench1, wall1) = marks["running"], marks["finalizing"]
    return {"cpu": cpu1 - cpu0, "bench_cpu": bench1 - bench0, "wall": wall1 - wall0}


def _pyvisa_blocks(link) -> None:
    """Make ``link`` read each block with pyvisa's ``query_binary_values``."""
    import numpy as np

    def read_block(command: str) -> bytes:
        with link.lock:
            return link._io(command, lambda r: r.query_binary_values(
                command, datatype="i", is_big_endian=False, container=np.array,
                header_fmt="ieee", expect_termination=True).tobytes())

    link.read_block = read_block


def driver_record(address: str, seconds: float, pyvisa_reads: bool) -> float:
    """CPU time of this process, s, while the digitiser driver streams 4 inputs at
    :data:`STREAM_RATE` for ``seconds`` (trigger immediate); with ``pyvisa_reads`` each block
    is read by pyvisa's ``query_binary_values``."""
    from fsi_lab.instruments import scpi_daq
    from fsi_lab.params import validate

    plugin = scpi_daq.PLUGIN
    daq = plugin.open(address, validate(plugin.params, {"block_duration": BLOCK_SECONDS,
                                                        "trigger": "immediate"}, "acquisition"),
                      {})
    try:
        if pyvisa_reads:
            _pyvisa_blocks(daq.link)
        rate = daq.configure({f"in{n}": n for n in range(1, INPUTS + 1)}, STREAM_RATE, seconds)
        samples = 0
        started = time.process_time()
        daq.arm()
        while (block := daq.read_block(5.0)) is not None:
            samples += block["in1"].size
        cpu = time.process_time() - started
    finally:
        daq.safe_state()
        daq.close()
    if samples != round(seconds * rate):
        raise RuntimeError(f"the driver streamed {samples} samples of {round(seconds * rate)}")
    return cpu


def floor_record(seconds: float) -> float:
    """CPU time of a thread reading ``seconds`` of 4 inputs at :data:`STREAM_RATE` (int32,
    0.1 s blocks sent in real time by another thread) from a loopback socket in one
    ``recv_into`` loop, s."""
    block = bytes(INPUTS * 4 * round(STREAM_RATE * BLOCK_SECONDS))
    blocks = round(seconds / BLOCK_SECONDS)
    server = socket.create_server(("127.0.0.1", 0))
    server.settimeout(30.0)
    failed: list[BaseException] = []

    def send() -> None:
        try:
            with socket.create_connection(server.getsockname(), timeout=30.0) as sock:
                start = time.monotonic()
                for k in range(blocks):
                    time.sleep(max(0.0, start + (k + 1) * BLOCK_SECONDS - time.monotonic()))
                    sock.sendall(block)
        except BaseException as exc:  # noqa: BLE001 - reported by the reader
            failed.append(exc)

    sender = threading.Thread(target=send, daemon=True)
    sender.start()
    with server, server.accept()[0] as conn:
        conn.settimeout(30.0)
        buffer = memoryview(bytearray(1 << 20))
        total, wanted = 0, len(block) * blocks
        started = time.thread_time()
        while total < wanted:
            got = conn.recv_into(buffer)
            if not got:
                break
            total += got
        cpu = time.thread_time() - started
    sender.join(30.0)
    if failed or total != wanted:
        raise RuntimeError(f"the floor read {total} of {wanted} bytes ({failed})")
    return cpu


def child(config: dict) -> None:
    """One repetition (a fresh process): print the measured CPU times as one JSON line."""
    directory = Path(config["directory"])
    profile = directory / "stream.toml"
    profile.write_text(stream_profile(config["snippet"], config["seconds"]))
    seconds = config["seconds"]
    cold = runner_record(profile, directory / "runs", config["bench_pid"])
    warm = runner_record(profile, directory / "runs", config["bench_pid"])
    ours = driver_record(config["acquisition"], seconds, pyvisa_reads=False)
    pyvisa = driver_record(config["acquisition"], seconds, pyvisa_reads=True)
    floor = floor_record(seconds)
    print(json.dumps({"cold": cold, "warm": warm, "driver": ours, "pyvisa": pyvisa,
                      "floor": floor}))


# --------------------------------------------------------------------------- the rows
CHILD = "import json, sys; from bench.bench_stream import child; child(json.loads(sys.argv[1]))"


def measure(repeat: int = REPEAT, seconds: float = STREAM_SECONDS) -> list[dict]:
    """``repeat`` repetitions against one real-time bench; what :func:`child` printed."""
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        directory = Path(tmp)
        bench, started = start_real_time_bench(directory)
        env = {**os.environ, "FSI_LAB_LOCK_DIR": str(directory / "locks")}
        try:
            for k in range(repeat):
                config = {"directory": str(directory), "snippet": started["profile"],
                          "acquisition": started["addresses"]["acquisition"],
                          "bench_pid": bench.pid, "seconds": seconds}
                proc = subprocess.run(
                    [sys.executable, "-c", CHILD, json.dumps(config)], check=False,
                    capture_output=True, text=True, cwd=ROOT, env=env, timeout=300 + 10 * seconds)
                if proc.returncode != 0:
                    raise RuntimeError(f"streaming repetition {k + 1} failed: "
                                       f"{proc.stderr[-800:]}")
                results.append(json.loads(proc.stdout.strip().splitlines()[-1]))
        finally:
            bench.terminate()
            try:
                bench.wait(timeout=30)
            except subprocess.TimeoutExpired:
                bench.kill()
                bench.wait(timeout=30)
    return results


def rows() -> list[Row]:
    results = measure()
    seconds = STREAM_SECONDS

    def share(values: list[float]) -> list[float]:
        return [v / seconds for v in values]  # CPU s per s of record

    floor = share([r["floor"] for r in results])
    floor_text = f"floor (one recv loop, same bytes) {figure(floor, '%', 100, 2)}"
    what = f"4 ch x {STREAM_RATE / 1000:g} kS/s, {seconds:g} s records"
    out = []
    for key, when in (("cold", "cold (first record of a process)"), ("warm", "warm")):
        ours = share([r[key]["cpu"] for r in results])
        in_time = all(r[key]["wall"] < seconds + 1.0 for r in results)
        out.append(Row(f"runner streams {what} from the real-time sim digitiser (loopback, run "
                       f"file), {when}: CPU per s of record", figure(ours, "%", 100, 2),
                       floor_text, f"< {RUNNER_TARGET:g} % of one core",
                       median(ours) * 100 < RUNNER_TARGET and in_time))
    ours = share([r["driver"] for r in results])
    pyvisa = share([r["pyvisa"] for r in results])
    out.append(Row(f"digitiser driver alone streams {what}: CPU per s of record",
                   figure(ours, "%", 100, 2),
                   f"pyvisa query_binary_values {figure(pyvisa, '%', 100, 2)}; {floor_text}",
                   "< pyvisa's block reads", median(ours) < median(pyvisa)))
    bench = [r[key]["bench_cpu"] / r[key]["wall"] for r in results for key in ("cold", "warm")]
    in_time = all(r[key]["wall"] < seconds + 1.0 for r in results for key in ("cold", "warm"))
    out.append(Row(f"sim bench (real time) while the runner streams {what}: bench CPU / wall",
                   figure(bench, "%", 100, 1), "real time: every sample, no overrun",
                   f"<= {BENCH_TARGET:g} % of one core", median(bench) * 100 <= BENCH_TARGET
                   and in_time))
    return out
