"""Helpers for the instrument tests.

- :class:`ScriptedPeer` and :class:`PtyPeer`: a loopback peer (TCP, or a pseudo-terminal for
  serial drivers) that records every byte a driver sends and answers scripted replies, for
  tests that assert the exact bytes exchanged (PyMeasure's ``expected_protocol`` style).
- :func:`lab_registry`: the installed plugins plus the lab drivers and excitations of this
  package, taken from their modules' hook implementations (what their entry points name).
- :func:`bench_profile`: a profile on the embedded simulated bench.
- fixtures ``tcp_peer``, ``pty_peer`` and ``sim_bench``, which stop what they start.
"""

from __future__ import annotations

import os
import select
import socket
import threading
import time
import tty
from pathlib import Path

import pytest

from fsi_lab.instruments import keysight33500, polytec, scpi_daq, shaker_amplifier
from fsi_lab.instruments.sim.bench import BenchOptions, SimBench
from fsi_lab.plugins.excitation import impulse_train, random_noise
from fsi_lab.profile import load_profile
from fsi_lab.registry import load_registry
from fsi_lab.runner import Runner

LAB_MODULES = (keysight33500, shaker_amplifier, polytec, scpi_daq)
EXCITATION_MODULES = (impulse_train, random_noise)
BENCH_THREAD = "fsi-lab-sim-bench"
#: (expected bytes, reply): the reply is None, bytes, or (delay s, bytes) for a slow instrument.
Script = list[tuple[bytes, "bytes | tuple[float, bytes] | None"]]


def lab_registry():
    """Loaded plugins, with the lab drivers and excitations added if their entry points are
    not installed yet."""
    registry = load_registry()
    for module in LAB_MODULES:
        for descriptor in module.fsi_lab_instruments():
            registry.descriptors["instrument"].setdefault(descriptor.name, descriptor)
    for module in EXCITATION_MODULES:
        for descriptor in module.fsi_lab_excitations():
            registry.descriptors["excitation"].setdefault(descriptor.name, descriptor)
    return registry


def settings(module, **values) -> dict:
    """Validated settings of a driver module's plugin."""
    from fsi_lab.params import validate

    return validate(module.PLUGIN.params, values, module.PLUGIN.name)


# --------------------------------------------------------------------------- scripted peers
class _Peer:
    """Runs a script on a thread: read exactly the expected bytes, then send the reply."""

    def __init__(self, script: Script, timeout: float = 5.0) -> None:
        self.script = script
        self.timeout = timeout
        self.received = bytearray()
        self.errors: list[str] = []
        self._thread = threading.Thread(target=self._run, daemon=True, name="scripted-peer")
        self._stop = threading.Event()

    def start(self):
        self._open()
        self._thread.start()
        return self

    def _run(self) -> None:
        try:
            self._accept()
            for step, (expected, reply) in enumerate(self.script):
                got = self._read(len(expected))
                self.received += got
                if got != expected:
                    self.errors.append(f"step {step}: expected {expected!r}, got {got!r}")
                    return
                if isinstance(reply, tuple):  # (seconds, bytes): a slow instrument
                    self._stop.wait(reply[0])
                    reply = reply[1]
                if reply:
                    self._send(reply)
            self.received += self._read(1 << 20, quiet=0.2)  # anything sent after the script
        except Exception as exc:  # noqa: BLE001 - reported by finish()
            self.errors.append(f"{type(exc).__name__}: {exc}")

    def _read(self, count: int, quiet: float | None = None) -> bytes:
        data = bytearray()
        deadline = time.monotonic() + (quiet if quiet is not None else self.timeout)
        while len(data) < count and not self._stop.is_set():
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                break
            chunk = self._recv(count - len(data), min(remaining, 0.05))
            if chunk is None:
                break
            data += chunk
        return bytes(data)

    def finish(self) -> bytes:
        """Wait for the script to end; the bytes received."""
        self._thread.join(self.timeout + 2)
        assert not self._thread.is_alive(), "the scripted peer did not finish"
        return bytes(self.received)

    def expect_all(self) -> None:
        """Assert that the driver sent exactly the script's bytes and nothing more."""
        received = self.finish()
        assert not self.errors, self.errors
        assert received == b"".join(expected for expected, _ in self.script)

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(self.timeout + 2)
        self._close()


class ScriptedPeer(_Peer):
    """A TCP peer on 127.0.0.1; :attr:`address` is its VISA resource name."""

    def _open(self) -> None:
        self._server = socket.socket()
        self._server.bind(("127.0.0.1", 0))
        self._server.listen(1)
        self._server.settimeout(self.timeout)
        self.address = f"TCPIP0::127.0.0.1::{self._server.getsockname()[1]}::SOCKET"
        self._conn = None

    def _accept(self) -> None:
        self._conn, _ = self._server.accept()

    def _recv(self, count: int, wait: float) -> bytes | None:
        readable, _, _ = select.select([self._conn], [], [], wait)
        if not readable:
            return b""
        try:
            chunk = self._conn.recv(count)
        except ConnectionResetError:  # the driver closed with our reply unread
            return None
        return chunk or None

    def _send(self, data: bytes) -> None:
        self._conn.sendall(data)

    def _close(self) -> None:
        for sock in (self._conn, self._server):
            if sock is not None:
                sock.close()


class PtyPeer(_Peer):
    """A serial peer on a pseudo-terminal; :attr:`address` is the device path."""

    def _open(self) -> None:
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        self.address = os.ttyname(self._slave)

    def _accept(self) -> None:
        pass

    def _recv(self, count: int, wait: float) -> bytes | None:
        readable, _, _ = select.select([self._master], [], [], wait)
        if not readable:
            return b""
        return os.read(self._master, count)

    def _send(self, data: bytes) -> None:
        os.write(self._master, data)

    def _close(self) -> None:
        for fd in (self._master, self._slave):
            try:
                os.close(fd)
            except OSError:
                pass


def _peer_fixture(cls):
    peers: list[_Peer] = []

    def make(script: Script) -> _Peer:
        peer = cls(script).start()
        peers.append(peer)
        return peer

    return peers, make


@pytest.fixture
def tcp_peer():
    peers, make = _peer_fixture(ScriptedPeer)
    yield make
    for peer in peers:
        peer.stop()


@pytest.fixture
def pty_peer():
    peers, make = _peer_fixture(PtyPeer)
    yield make
    for peer in peers:
        peer.stop()


# --------------------------------------------------------------------------- the bench
def bench_threads() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name == BENCH_THREAD and t.is_alive()]


@pytest.fixture
def sim_bench():
    """Start simulated benches (fast unless told otherwise); all are stopped at the end."""
    benches: list[SimBench] = []

    def make(specimen=None, model=None, shaker=None, **options) -> SimBench:
        options.setdefault("fast", True)
        bench = SimBench(specimen, model, shaker, BenchOptions(**options)).start()
        benches.append(bench)
        return bench

    yield make
    for bench in benches:
        bench.stop()
    assert not bench_threads(), "a simulated bench thread outlived its test"


BENCH_PROFILE = """
[run]
duration = {duration}
sample_rate = {sample_rate}
block_duration = 0.05

[safety]
max_drive_v = 2.0
max_gain = 10.0
max_stroke_mm = 5.0

[shaker]
suspension_hz = 30.0
damping_ratio = 0.08
mm_per_volt = 0.5

[specimen]
fluid = "{fluid}"

[model]
{model}

[bench]
embedded = {embedded}
fast = {fast}
fault = "{fault}"
fault_after_s = {fault_after_s}

[bench.source]
plugin = "keysight33500"
address = "{source}"

[bench.amplifier]
plugin = "shaker-amplifier"
address = "{amplifier}"
gain = 2.0

[bench.vibrometer]
plugin = "polytec"
address = "{vibrometer}"
range = "125mm/s/V"

[bench.acquisition]
plugin = "scpi-daq"
address = "{acquisition}"
timeout_s = {timeout_s}
block_duration = 0.05

[channels.drive]
quantity = "voltage"
unit = "V"
input = 1

[channels.base_acceleration]
quantity = "acceleration"
unit = "m/s^2"
sensitivity = {accelerometer}
input = 2

[channels.tip_velocity]
quantity = "velocity"
unit = "m/s"
input = 3
sensor = "vibrometer"

[excitation]
{excitation}
"""

WET_MODEL = "c_i = 0.65\nc_f = 33.0"
RAMP = ('plugin = "ramp-derivative"\nheight = 0.01\nramp_duration = 0.02\ndelay = 0.1\n'
        'duration = 0.5')
#: 100 mV/g, the simulated accelerometer, in V/(m/s^2).
ACCELEROMETER = 0.1 / 9.80665


def bench_profile(path: Path, duration: float = 1.0, sample_rate: float = 10000.0,
                  fast: bool = True, fault: str = "none", fault_after_s: float = 0.3,
                  timeout_s: float = 2.0, fluid: str = "water", model: str = WET_MODEL,
                  excitation: str = RAMP, addresses: dict | None = None) -> Path:
    """Write a profile on the embedded bench (or on the instruments at ``addresses``, by role)
    and return its path."""
    roles = ("source", "amplifier", "vibrometer", "acquisition")
    where = {role: (addresses or {}).get(role, "embedded") for role in roles}
    path.write_text(BENCH_PROFILE.format(
        duration=duration, sample_rate=sample_rate, fast=str(fast).lower(), fault=fault,
        fault_after_s=fault_after_s, timeout_s=timeout_s, fluid=fluid, model=model,
        excitation=excitation, accelerometer=ACCELEROMETER,
        embedded=str(addresses is None).lower(), **where))
    return path


def run_profile(path: Path, registry, out: Path):
    """Run a profile in this process; the :class:`~fsi_lab.runner.RunOutcome`."""
    profile = load_profile(path, registry)
    return Runner(profile, registry, out, analyze=False).run()
