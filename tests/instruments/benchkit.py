"""Helpers for the instrument tests.

- :class:`ScriptedPeer` and :class:`PtyPeer` (from the conformance kit, :mod:`fsi_lab.testing`):
  a loopback peer (TCP, or a pseudo-terminal for serial drivers) that records every byte a
  driver sends and answers scripted replies, for tests that assert the exact bytes exchanged
  (PyMeasure's ``expected_protocol`` style); the kit's pytest plugin gives the ``tcp_peer``
  and ``pty_peer`` fixtures, re-exported here for the modules that import them.
- :func:`lab_registry`: the installed plugins plus the lab drivers and excitations of this
  package, taken from their modules' hook implementations (what their entry points name).
- :func:`bench_profile`: a profile on the embedded simulated bench.
- fixture ``sim_bench``, which stops what it starts.
"""

from __future__ import annotations

import threading
from pathlib import Path

import pytest

from fsi_lab.instruments import keysight33500, polytec, scpi_daq, shaker_amplifier
from fsi_lab.instruments.sim.bench import BenchOptions, SimBench
from fsi_lab.plugins.excitation import impulse_train, random_noise
from fsi_lab.profile import load_profile
from fsi_lab.registry import load_registry
from fsi_lab.runner import Runner
from fsi_lab.testing.peers import PtyPeer, Script, ScriptedPeer
from fsi_lab.testing.plugin import pty_peer, tcp_peer

LAB_MODULES = (keysight33500, shaker_amplifier, polytec, scpi_daq)
EXCITATION_MODULES = (impulse_train, random_noise)
BENCH_THREAD = "fsi-lab-sim-bench"


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
