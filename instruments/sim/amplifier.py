"""Simulated shaker power amplifier (PA25E class) with a SCPI command set.

Commands: the IEEE 488.2 common commands (``*IDN?``, ``*RST``, ``*CLS``, ``*ESR?``, ``*OPC?``...,
see :class:`~.scpi.ScpiInstrument`), ``SYST:ERR?``, ``OUTP 0|1|ON|OFF``, ``OUTP?``,
``GAIN <V/V>`` (0 to 50), ``GAIN?``, ``STAT:INTL?`` (interlock bitfield, see
:data:`INTERLOCK_BITS`), ``INTL:RES`` and ``MEAS:CURR?`` (RMS output current over the last
simulated block, A).

Interlocks latch and force the output off; ``OUTP 1`` is refused (error -221) while one is
latched. ``INTL:RES`` clears the latched interlocks whose cause has gone (an e-stop still pressed,
a supply fault or an over-temperature still present stay latched).

The communication watchdog (a dead controller cannot leave the shaker driven):

==========================  =================================================================
``SYST:WDOG:TIM <s>``        watchdog time, 0.1 to 60 s (``MIN``/``MAX``/``DEF`` = 1 s);
                             ``SYST:WDOG:TIM?`` reads it
``SYST:WDOG ON|OFF``         arm or disarm it; ``SYST:WDOG?`` reads it
``SYST:WDOG:FEED``           does nothing but feed it
==========================  =================================================================

Armed, it is fed by every program message that arrives on the connection that armed it (other
connections, a monitoring client's, do not feed it). When none has arrived for the watchdog time,
the output is switched off and the ``watchdog`` interlock (bit 6) latches, whatever happened to
the controller: a crash, a kill, a frozen process, a pulled cable. ``*RST`` disarms it, and so
does the trip.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

from fsi_lab.instruments.sim import scpi
from fsi_lab.instruments.sim.scpi import ScpiError, ScpiInstrument

if TYPE_CHECKING:  # pragma: no cover
    from fsi_lab.instruments.sim.bench import SimBench

IDENTITY = "fsi-lab,PA25E-SIM,SIMPA25,1.0 (simulated)"
MAX_GAIN = 50.0
#: Bit of each interlock in the ``STAT:INTL?`` bitfield.
INTERLOCK_BITS = {"over_travel": 0, "supply_fault": 1, "over_temperature": 2,
                  "over_current": 3, "e_stop": 4, "input_clip": 5, "watchdog": 6}
#: Watchdog time bounds and default, s.
WATCHDOG_MIN_S, WATCHDOG_MAX_S, WATCHDOG_DEFAULT_S = 0.1, 60.0, 1.0
#: Interlocks whose cause persists until it is removed on the bench.
PERSISTENT = ("supply_fault", "over_temperature", "e_stop")


class AmplifierState:
    """Output relay, gain and interlocks."""

    def __init__(self) -> None:
        self.gain = 0.0
        self.output_on = False
        self.latched: set[str] = set()
        self.causes: set[str] = set()  # persistent causes still present
        self.current_rms_a = 0.0
        self.trips: list[tuple[float | None, str]] = []  # (record time, interlock) history
        self.watchdog_s = WATCHDOG_DEFAULT_S
        self.watchdog_armed = False
        self.watchdog_owner: object = None  # the connection that armed it
        self.watchdog_fed = 0.0  # time.monotonic() of the last feed

    def trip(self, names: set[str], time_s: float | None = None) -> None:
        """Latch ``names`` and switch the output off."""
        self.latched |= set(names)
        self.output_on = False
        self.trips.extend((time_s, name) for name in sorted(names))

    @property
    def bits(self) -> int:
        """The ``STAT:INTL?`` bitfield of the latched interlocks."""
        return sum(1 << INTERLOCK_BITS[name] for name in self.latched)


class AmplifierSim(ScpiInstrument):
    """The amplifier's command set (with the IEEE 488.2 common commands), acting on the
    bench."""

    identity = IDENTITY

    def __init__(self, bench: "SimBench") -> None:
        super().__init__(bench)
        self.state = AmplifierState()
        c = self.commands
        c.add("OUTPut[:STATe]", self._output)
        c.add("OUTPut[:STATe]?", lambda a, s: "1" if self.state.output_on else "0")
        c.add("GAIN", self._gain)
        c.add("GAIN?", lambda a, s: f"{self.state.gain:.6g}")
        c.add("STATus:INTLock?", lambda a, s: str(self.state.bits))
        c.add("INTLock:RESet", self._reset_interlocks)
        c.add("MEASure:CURRent?", lambda a, s: f"{self.state.current_rms_a:.6E}")
        c.add("SYSTem:WDOG[:STATe]", self._watchdog)
        c.add("SYSTem:WDOG[:STATe]?", lambda a, s: "1" if self.state.watchdog_armed else "0")
        c.add("SYSTem:WDOG:TIMe", self._watchdog_time)
        c.add("SYSTem:WDOG:TIMe?", lambda a, s: "{:.6g}".format(scpi.query_limit(
            a, WATCHDOG_MIN_S, WATCHDOG_MAX_S, WATCHDOG_DEFAULT_S, self.state.watchdog_s)))
        c.add("SYSTem:WDOG:FEED", lambda a, s: None)

    def set_cause(self, name: str, present: bool) -> None:
        """Press or release the e-stop, or raise or clear a supply or temperature fault."""
        if name not in PERSISTENT:
            raise ValueError(f"{name!r}: expected one of {', '.join(PERSISTENT)}")
        with self.bench.lock:
            self.bench.catch_up()
            if present:
                self.state.causes.add(name)
                self.state.trip({name})
            else:
                self.state.causes.discard(name)

    def reset(self) -> None:
        """``*RST``: output off, gain 0, watchdog disarmed (latched interlocks stay latched)."""
        self.state.output_on = False
        self.state.gain = 0.0
        self.state.watchdog_armed = False

    def received(self, connection: object) -> None:
        """A message on the connection that armed the watchdog feeds it."""
        if self.state.watchdog_armed and connection is self.state.watchdog_owner:
            self.state.watchdog_fed = time.monotonic()

    def tick(self) -> None:
        """The watchdog: trip when its connection has been silent for the watchdog time."""
        state = self.state
        if state.watchdog_armed and time.monotonic() - state.watchdog_fed > state.watchdog_s:
            state.watchdog_armed = False
            state.trip({"watchdog"}, self.bench.data_time)

    def _watchdog(self, args, suffixes):
        on = scpi.boolean(args)
        state = self.state
        state.watchdog_armed = on
        state.watchdog_owner = self.connection if on else None
        state.watchdog_fed = time.monotonic()

    def _watchdog_time(self, args, suffixes):
        self.state.watchdog_s = scpi.number(
            args, WATCHDOG_MIN_S, WATCHDOG_MAX_S,
            words=scpi.limits(WATCHDOG_MIN_S, WATCHDOG_MAX_S, WATCHDOG_DEFAULT_S), unit="S")

    def _output(self, args, suffixes):
        on = scpi.boolean(args)
        if on and self.state.latched:
            raise ScpiError(-221, "interlock active: " + ", ".join(sorted(self.state.latched)))
        self.state.output_on = on

    def _gain(self, args, suffixes):
        self.state.gain = scpi.number(args, 0.0, MAX_GAIN)

    def _reset_interlocks(self, args, suffixes):
        self.state.latched &= self.state.causes
