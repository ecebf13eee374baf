"""The simulated bench: four instruments on real wires around one simulated world.

============  ===========================  ==========================================
role          wire                         address
============  ===========================  ==========================================
source        TCP (SCPI socket)            ``TCPIP0::127.0.0.1::<port>::SOCKET``
amplifier     TCP, and a pseudo-terminal   ``TCPIP0::127.0.0.1::<port>::SOCKET``,
                                           ``ASRL/dev/pts/<n>::INSTR``
vibrometer    pseudo-terminal (RS-232)     ``/dev/pts/<n>``
acquisition   TCP (SCPI socket)            ``TCPIP0::127.0.0.1::<port>::SOCKET``
============  ===========================  ==========================================

Servers bind 127.0.0.1 only. The world advances with the digitiser's record: in real time the
samples due by the wall clock are simulated whenever any instrument is addressed (so a command
takes effect at the moment it arrives); a fast bench simulates samples when they are fetched.
The source's trigger output is wired to the digitiser's external trigger input.

The world's physics (its filters need scipy, the beam integrator numba) is loaded by the first
record, and at start only when :attr:`BenchOptions.warm_up` asks for it: a bench started only
to make its instruments safe or identify them (``fsi-lab safe``) needs neither.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from fsi_lab.instruments.sim.amplifier import AmplifierSim
from fsi_lab.instruments.sim.daq import DigitiserSim
from fsi_lab.instruments.sim.faults import FaultPlan, garble
from fsi_lab.instruments.sim.keysight import KeysightSim
from fsi_lab.instruments.sim.polytec import PolytecSim
from fsi_lab.instruments.sim.rates import oversampling
from fsi_lab.instruments.sim.transport import LoopThread, PtyEndpoint, TcpEndpoint
from fsi_lab.modelling import BenchPhysics, beam_model

if TYPE_CHECKING:  # pragma: no cover
    from fsi_lab.instruments.sim.world import World

ROLES = ("source", "amplifier", "vibrometer", "acquisition")
#: Period of the instruments' timers (the amplifier's watchdog), s.
TICK_S = 0.05


@dataclass
class BenchOptions:
    """How the simulated bench behaves, and the hardware it imitates.

    Attributes
    ----------
    fast
        Simulate as fast as the client fetches instead of at the sample clock.
    fault, fault_after_s, fault_target
        Injected fault (see :mod:`.faults`), record time at which it happens (s) and, for link
        faults, the role whose link it hits.
    seed
        Seed of the noise generators.
    ports
        TCP port per role (``source``, ``amplifier``, ``acquisition``); 0 or absent: any free one.
    stroke_mm
        Mechanical stroke of the shaker armature, zero to peak (over-travel interlock), mm.
    coil_ohm, max_current_a
        Shaker coil resistance (ohm) and the over-current limit of the amplifier (A, peak).
    amp_input_limit_v
        Amplifier input level beyond which the input-clip interlock trips, V.
    vibrometer_delay_s
        Signal delay of the vibrometer, s.
    vibrometer_decoder_index
        Index of the velocity decoder among the controller's slots 0 to 3.
    vibrometer_echo, vibrometer_acknowledge
        The vibrometer controller's interface modes at power-up (echo every line, answer
        every ``Set``).
    accelerometer_mv_per_g
        Sensitivity of the IEPE accelerometer on the base, mV/g.
    source_channel
        The generator's channel (1 or 2) wired to the amplifier and the digitiser's input 1.
    log
        Called with a line of text for each notable event (record start, trips, faults).
    warm_up
        Load the compiled beam integrator at start, so that the first record does not wait
        for it; a bench that will record nothing (its instruments only made safe or
        identified) starts faster without.
    """

    fast: bool = False
    fault: str = "none"
    fault_after_s: float = 1.0
    fault_target: str | None = None
    seed: int = 0
    ports: dict[str, int] = field(default_factory=dict)
    stroke_mm: float = 8.8
    coil_ohm: float = 4.0
    max_current_a: float = 10.0
    amp_input_limit_v: float = 5.0
    vibrometer_delay_s: float = 1.1e-3
    vibrometer_decoder_index: int = 0
    vibrometer_echo: bool = False
    vibrometer_acknowledge: bool = False
    accelerometer_mv_per_g: float = 100.0
    source_channel: int = 1
    log: Callable[[str], None] | None = None
    warm_up: bool = True


def physics_sections(specimen=None, model: dict | None = None,
                     shaker: dict | None = None) -> tuple[Any, dict, dict]:
    """Validated specimen, ``[model]`` and ``[shaker]`` values, defaults where None."""
    from fsi_lab.params import validate
    from fsi_lab.profile import MODEL_PARAMS, SHAKER_PARAMS
    from fsi_lab.specimen import Specimen

    specimen = specimen if specimen is not None else Specimen.from_mapping({})
    model = dict(model) if model is not None else validate(MODEL_PARAMS, {}, "model")
    shaker = dict(shaker) if shaker is not None else validate(SHAKER_PARAMS, {}, "shaker")
    return specimen, model, shaker


class SimBench:
    """A complete simulated bench.

    Parameters
    ----------
    specimen, model, shaker
        The profile's ``[specimen]`` (a :class:`fsi_lab.specimen.Specimen`), ``[model]`` and
        ``[shaker]`` values: the true physics of the bench (defaults: the schemas' defaults).
    options
        :class:`BenchOptions`.

    Use :meth:`start` and :meth:`stop` (or ``with SimBench(...) as bench``); :attr:`addresses`
    gives where each instrument answers.
    """

    def __init__(self, specimen=None, model: dict | None = None, shaker: dict | None = None,
                 options: BenchOptions | None = None) -> None:
        self.specimen, self.model, self.shaker = physics_sections(specimen, model, shaker)
        self.options = options or BenchOptions()
        self.beam = beam_model(self.specimen, self.model)
        self.lock = threading.RLock()
        self.faults = FaultPlan(self.options.fault, self.options.fault_after_s,
                                self.options.fault_target)
        self.source = KeysightSim(self)
        self.amplifier = AmplifierSim(self)
        self.vibrometer = PolytecSim(self)
        self.digitiser = DigitiserSim(self)
        self.record: World | None = None
        self.last_overloads: dict[int, float] = {}
        self._points = 0
        self._t0 = 0.0
        self._loop: LoopThread | None = None
        self._endpoints: dict[str, Any] = {}
        self._reported_trips = 0

    # ------------------------------------------------------------------ lifecycle
    def start(self) -> "SimBench":
        """Start the servers and the pseudo-terminals; returns self."""
        if self.options.warm_up:
            self._warm_up()
        self._loop = LoopThread("fsi-lab-sim-bench")
        self._loop.start()
        ports = self.options.ports
        handlers = {"source": self.source.handle, "amplifier": self.amplifier.handle,
                    "acquisition": self.digitiser.handle}
        try:
            for role, handle in handlers.items():
                endpoint = TcpEndpoint(self._exchange(role, handle), ports.get(role, 0) or 0)
                self._loop.run(endpoint.start())
                self._endpoints[role] = endpoint
            for key, role, handle in (("vibrometer", "vibrometer", self.vibrometer.handle),
                                      ("amplifier_serial", "amplifier", self.amplifier.handle)):
                endpoint = PtyEndpoint(self._exchange(role, handle))
                self._loop.run(endpoint.start())
                self._endpoints[key] = endpoint
        except BaseException:
            self.stop()
            raise
        self._loop.loop.call_soon_threadsafe(self._tick)
        self._log(f"simulated bench ready ({'fast' if self.options.fast else 'real time'}; "
                  f"fault: {self.faults.describe()})")
        return self

    def _tick(self) -> None:
        """On the loop, every :data:`TICK_S`: the instruments' timers (the amplifier's
        watchdog), with the world caught up to now."""
        if self._loop is None:
            return
        try:
            with self.lock:
                self.catch_up()
                for instrument in (self.source, self.amplifier, self.digitiser):
                    instrument.tick()
                self._report_trips()
        finally:
            if self._loop is not None:
                self._loop.loop.call_later(TICK_S, self._tick)

    def stop(self) -> None:
        """Close every connection and the servers, stop the loop thread (idempotent)."""
        loop, self._loop = self._loop, None
        if loop is None:
            return
        try:
            for endpoint in self._endpoints.values():
                loop.run(endpoint.stop())
        finally:
            loop.stop()
            with self.lock:
                self.record = None

    def __enter__(self) -> "SimBench":
        return self.start()

    def __exit__(self, *exc_info) -> None:
        self.stop()

    @property
    def running(self) -> bool:
        """Whether the servers are up."""
        return self._loop is not None

    def _warm_up(self) -> None:
        """Load the world's physics now rather than in the middle of a record: the front
        ends' filters (scipy.signal, a second or more to import) and the compiled shaker and
        integrator (numba)."""
        from fsi_lab.instruments.sim.world import World  # noqa: F401 - loaded for its filters

        rate = 10000.0 * oversampling(self.beam, 10000.0)
        BenchPhysics(self.beam, self.shaker, rate,
                     self.specimen.measurement_point).advance(np.zeros(8))

    # ------------------------------------------------------------------ addresses
    @property
    def addresses(self) -> dict[str, str]:
        """Address of each instrument, in the form its driver takes."""
        e = self._endpoints
        if not e:
            raise RuntimeError("the simulated bench is not started")
        return {
            "source": f"TCPIP0::127.0.0.1::{e['source'].port}::SOCKET",
            "amplifier": f"TCPIP0::127.0.0.1::{e['amplifier'].port}::SOCKET",
            "amplifier_serial": f"ASRL{e['amplifier_serial'].path}::INSTR",
            "vibrometer": e["vibrometer"].path,
            "acquisition": f"TCPIP0::127.0.0.1::{e['acquisition'].port}::SOCKET",
        }

    # ------------------------------------------------------------------ the wire
    def _exchange(self, role: str, handle: Callable[[bytes, object], bytes | None]):
        def exchange(message: bytes, connection: object = None) -> tuple[bytes | None, bool]:
            with self.lock:
                self.catch_up()
                action = self.faults.link_action(role, self.data_time)
                if action == "timeout":
                    return None, False
                if action == "drop":
                    self._log(f"fault: the {role} drops its connection")
                    return None, True
                try:
                    reply = handle(message, connection)
                except Exception as exc:  # noqa: BLE001 - a simulation failure, not the client's
                    self._log(f"the simulated {role} failed on {message[:40]!r}: "
                              f"{type(exc).__name__}: {exc}; it drops its connection")
                    return None, True
                if reply is not None and self.faults.garble_now(role, self.data_time):
                    self._log(f"fault: the {role}'s reply is garbled")
                    reply = garble(reply)
                return reply, False
        return exchange

    def inject_fault(self, kind: str, target: str | None = None) -> None:
        """Make a fault happen now (see :meth:`.faults.FaultPlan.inject`); ``"none"`` ends
        a persistent one."""
        with self.lock:
            self.faults.inject(kind, target)
            self._log(f"fault injected: {self.faults.describe()}")

    # ------------------------------------------------------------------ the world
    @property
    def data_time(self) -> float | None:
        """Record time reached, s (None when no record has started)."""
        return self.record.data_time if self.record is not None else None

    def start_record(self, rate: float, points: int, inputs: list[int], ranges: list[float],
                     iepe: list[bool]) -> None:
        """A digitiser record starts now: the world is at rest at t = 0."""
        from fsi_lab.instruments.sim.world import World  # the physics: see the module's notes

        self.record = World(self, self.beam, rate, inputs, ranges, iepe)
        self._points = int(points)
        self._t0 = time.monotonic()
        self._log(f"record started: {points} samples at {rate:g} Hz on inputs "
                  f"{', '.join(map(str, inputs))}")

    def end_record(self) -> None:
        """Stop simulating (abort, reset, new record); keep the record's overloads."""
        if self.record is not None:
            self.last_overloads = dict(self.record.overloads)
            self.record = None

    def world_now(self) -> int:
        """World sample reached (0 when no record runs: the next record's start)."""
        return self.record.world_done if self.record is not None else 0

    def external_trigger(self) -> None:
        """The source's trigger output fires: a digitiser waiting for it starts its record."""
        if self.digitiser.state.mode == "WTRG":
            self.digitiser.start()

    def produce(self, n: int) -> None:
        """Simulate ``n`` more digitiser samples (at most to the end of the record)."""
        record = self.record
        if record is None:
            return
        n = min(n, self._points - record.produced)
        if n <= 0:
            return
        self.digitiser.store(record.produce(n))
        self._report_trips()
        if record.produced >= self._points:
            self.digitiser.record_complete()

    def catch_up(self) -> None:
        """In real time, simulate the samples the sample clock has produced by now."""
        record = self.record
        if record is None or self.options.fast or self.digitiser.state.mode != "RUN":
            return
        due = min(self._points, int(math.floor((time.monotonic() - self._t0) * record.rate)))
        self.produce(due - record.produced)

    def _report_trips(self) -> None:
        trips = self.amplifier.state.trips
        for time_s, name in trips[self._reported_trips:]:
            when = f" at {time_s:.4f} s" if time_s is not None else ""
            self._log(f"amplifier interlock {name} tripped{when}; output forced off")
        self._reported_trips = len(trips)

    def _log(self, text: str) -> None:
        if self.options.log is not None:
            self.options.log(text)
