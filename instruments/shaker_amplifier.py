"""Shaker power amplifier with interlocks (PA25E class) over VISA: serial or TCP, SCPI.

Command set: ``*IDN?``, ``*CLS``, ``SYST:ERR?``, ``OUTP 0|1``, ``OUTP?``, ``GAIN <V/V>``,
``GAIN?``, ``STAT:INTL?`` (interlock bitfield: bit 0 over-travel, 1 supply fault,
2 over-temperature, 3 over-current, 4 e-stop, 5 input clip, 6 watchdog), ``INTL:RES`` and
``MEAS:CURR?`` (A). Interlocks latch in the amplifier and force its output off; ``OUTP 1`` is
refused while one is active, and this driver checks them before asking.

A dead controller cannot leave the shaker driven: before the output goes on, the driver arms the
amplifier's communication watchdog (``SYST:WDOG:TIM <watchdog_s>``, ``SYST:WDOG ON``) and a
thread of this process feeds it (``SYST:WDOG:FEED``) four times per watchdog time for as long as
the run shows signs of life (:meth:`ShakerAmplifier.monitor`, called by the runner a few times a
second, within :data:`HEARTBEAT_S`). When the process is killed, crashes or freezes, or the
cable is pulled, the feeding stops and the amplifier switches its output off by itself after
``watchdog_s`` and latches its ``watchdog`` interlock. Why the amplifier and not a guardian
process: a guardian is one more process a crash, a job scheduler's kill of the process group or
a power cut of the PC takes down with the run, and it needs a second connection that a serial
amplifier cannot offer; the amplifier's own timer survives all of these. Amplifiers with such a
watchdog (a "communication timeout" or "watchdog" setting that switches the output off when the
host falls silent) are configured the same way; one that does not know ``SYST:WDOG`` (error
-113) is used without (the run records ``watchdog: "not offered"``), and the run then relies on
the bench lock and on the next command that opens the bench reporting outputs it found on.

On opening, the output state is read (``OUTP?``) before ``OUTP 0`` goes out, so that an output
left on by a run that died is reported (:attr:`ShakerAmplifier.found_on`). The driver is written
with the instrument kit (:mod:`fsi_lab.instruments.kit`): its settings are declared once, with
their commands, units and bounds, and the profile's ``gain`` and ``watchdog_s`` are made from
them; the take-over, the confirmed safe state and the state read back are the kit's.

Address: a VISA resource, e.g. ``TCPIP0::192.168.1.20::5025::SOCKET`` or
``ASRL/dev/ttyUSB0::INSTR`` (8N1 at ``baud_rate``), or ``embedded``.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Mapping
from typing import Any

from fsi_lab.contract import Amplifier, InstrumentPlugin
from fsi_lab.errors import InstrumentError
from fsi_lab.hookspecs import hookimpl
from fsi_lab.instruments.kit import SAFE_TIMEOUT_S, ScpiOutput, Setting, connect
from fsi_lab.params import Param

NAME = "shaker-amplifier"
#: Interlock name for each bit of ``STAT:INTL?``.
INTERLOCKS = ("over_travel", "supply_fault", "over_temperature", "over_current", "e_stop",
              "input_clip", "watchdog")
#: The watchdog is fed while the run has shown signs of life within this time, s.
HEARTBEAT_S = 10.0


class ShakerAmplifier(ScpiOutput, Amplifier):
    """An open amplifier. Use :func:`open_amplifier`."""

    NAME = NAME
    output = Setting("OUTP", "bool", choices=("1", "0"), help="Output stage on.")
    gain = Setting("GAIN", "float", "V/V", minimum=0.0, maximum=100.0, fmt=".6g",
                   accepted="the gain must lie within the amplifier's range",
                   help="Voltage gain of the amplifier.")
    interlock_bits = Setting("STAT:INTL", "int", readonly=True,
                             help="Latched interlocks, one bit each (INTERLOCKS).")
    current = Setting("MEAS:CURR", "float", "A", readonly=True, help="Output current.")
    watchdog_time = Setting("SYST:WDOG:TIM", "float", "s", minimum=0.0, maximum=60.0,
                            fmt=".6g",
                            help="The amplifier switches its output off when the run has been "
                                 "silent this long (a killed or frozen controller); 0: do not "
                                 "arm its watchdog.")
    watchdog_enabled = Setting("SYST:WDOG", "bool", help="Communication watchdog armed.")

    def __init__(self, link, identity: str, watchdog_s: float = 0.0,
                 found_on: bool | None = None) -> None:
        super().__init__(link, identity)
        self._gain: float | None = None
        self.watchdog_s = float(watchdog_s)
        #: Whether the output was on when the amplifier was opened (None: it could not be read).
        self.found_on = found_on
        #: "armed", "not offered" by the amplifier, "off" (watchdog_s = 0) or "not armed yet".
        self.watchdog = "off" if self.watchdog_s <= 0 else "not armed yet"
        self._alive_until = 0.0
        self._feeder: threading.Thread | None = None
        self._stop_feeding = threading.Event()

    def settings(self) -> dict[str, Any]:
        return {"visa_address": self.link.address, "gain_read_back": self._gain,
                "watchdog_s": self.watchdog_s, "watchdog": self.watchdog,
                "output_found_on": self.found_on}

    # ------------------------------------------------------------------ watchdog
    def monitor(self) -> None:
        """The run is alive: the watchdog is fed for :data:`HEARTBEAT_S` more."""
        self._alive_until = time.monotonic() + HEARTBEAT_S

    def _arm_watchdog(self) -> None:
        """Arm the amplifier's watchdog and start feeding it; without one, say so."""
        if self.watchdog_s <= 0 or self.watchdog == "not offered":
            return
        self.set("watchdog_time", self.watchdog_s, check=False)
        self.set("watchdog_enabled", True, check=False)
        refused = self.link.errors()
        if refused and all(e.startswith("-113") for e in refused):
            self.watchdog = "not offered"
            return
        if refused:
            raise InstrumentError(f"{self.where}: arming the watchdog "
                                  f"(SYST:WDOG:TIM {self.watchdog_s:g}; SYST:WDOG ON) was "
                                  f"refused: {'; '.join(refused)}")
        self.watchdog = "armed"
        self.monitor()
        self._stop_feeding.clear()
        if self._feeder is None or not self._feeder.is_alive():
            self._feeder = threading.Thread(target=self._feed, daemon=True,
                                            name="fsi-lab-amplifier-watchdog")
            self._feeder.start()

    def _feed(self) -> None:
        """Feed the watchdog four times per watchdog time while the run is alive."""
        period = self.watchdog_s / 4
        while not self._stop_feeding.wait(period):
            if time.monotonic() > self._alive_until:
                return  # the run stopped showing signs of life: let the watchdog act
            try:
                self.link.write("SYST:WDOG:FEED")
            except InstrumentError:
                return

    def _stop_watchdog_feeder(self) -> None:
        self._stop_feeding.set()
        feeder = self._feeder
        if feeder is not None and feeder is not threading.current_thread():
            feeder.join(timeout=self.watchdog_s + SAFE_TIMEOUT_S)

    # ------------------------------------------------------------------ the role
    def set_gain(self, gain: float) -> None:
        """Set the gain (V/V) and read it back."""
        self._gain = self.set("gain", gain, verify=True)

    def interlocks(self) -> dict[str, bool]:
        """Latched interlocks by name (``STAT:INTL?``)."""
        bits = self.interlock_bits
        if not 0 <= bits < 1 << len(INTERLOCKS):
            raise InstrumentError(f"{self.where}: STAT:INTL? answered {bits}; expected a "
                                  f"bitfield 0 to {(1 << len(INTERLOCKS)) - 1}")
        return {name: bool(bits >> bit & 1) for bit, name in enumerate(INTERLOCKS)}

    def enable_output(self, enabled: bool) -> None:
        """Switch the output stage on (refused while an interlock is latched) or off; the
        state is read back."""
        if enabled:
            active = [name for name, on in self.interlocks().items() if on]
            if active:
                raise InstrumentError(
                    f"{self.where}: output on refused: interlock {', '.join(active)} is "
                    "active; remove its cause, then clear it with INTL:RES (or set "
                    "reset_interlocks = true to do so when the amplifier is opened for a run)")
            self._arm_watchdog()
        self.output = enabled
        if self.output != enabled:
            raise InstrumentError(f"{self.where}: the output did not switch "
                                  f"{'on' if enabled else 'off'}")

    # ------------------------------------------------------------------ the kit's template
    def switch_off(self) -> None:
        """Output off; the watchdog disarmed when it was armed (the output is off: no trip to
        latch later)."""
        super().switch_off()
        if self.watchdog == "armed":
            self.set("watchdog_enabled", False, check=False)

    def safe_state(self) -> None:
        """Stop feeding the watchdog, then the kit's confirmed safe state: ``OUTP 0`` (and
        ``SYST:WDOG OFF``), confirmed by ``OUTP?``."""
        self._stop_watchdog_feeder()
        super().safe_state()

    def state_details(self, output_enabled: bool) -> dict[str, Any]:
        """Gain (V/V), latched interlocks and output current (A)."""
        return {"gain": self.gain,
                "interlocks": {k: v for k, v in self.interlocks().items() if v},
                "current_a": self.current}

    def close(self) -> None:
        self._stop_watchdog_feeder()
        super().close()


def open_amplifier(address: str, settings: dict[str, Any],
                   context: Mapping[str, Any]) -> ShakerAmplifier:
    """Connect, switch the output off, identify, clear the status and confirm the output off.

    ``OUTP?`` and then ``OUTP 0`` are the first things sent, before the identity is known, so
    that the output goes off even when the reply to ``*IDN?`` is unexpected and an output found
    on is reported (:attr:`ShakerAmplifier.found_on`); once the error queue is cleared ``OUTP 0``
    is sent again and checked (:meth:`~fsi_lab.instruments.kit.ScpiOutput.take_over`). Latched
    interlocks are cleared (``INTL:RES``) only when ``reset_interlocks`` is set and the
    instruments are opened for a run (``context["purpose"] == "run"``, the default);
    ``fsi-lab safe`` and ``identify`` open them ``"outside-run"`` and leave latched interlocks
    latched.

    Parameters
    ----------
    address
        VISA resource, or ``embedded`` for the simulated bench.
    settings
        Validated settings (:data:`PLUGIN` parameters).
    context
        The bench context shared by the profile's instruments (or a dict with its keys).
    """
    link = connect(NAME, "amplifier", address, settings, context, settings["baud_rate"])
    try:
        identity, found_on = ShakerAmplifier.take_over(link)
        if settings["reset_interlocks"] and context.get("purpose", "run") == "run":
            link.send_checked("INTL:RES")
    except BaseException:
        link.close()
        raise
    return ShakerAmplifier(link, identity, settings["watchdog_s"], found_on)


def check_amplifier(address: str, settings: dict[str, Any], plan: Mapping[str, Any]) -> None:
    """The instrument check of :class:`~fsi_lab.contract.InstrumentPlugin` (ValueError): an
    embedded address needs the embedded bench."""
    from fsi_lab.instruments.sim.embedded import check_embedded

    check_embedded(address, plan)


PLUGIN = InstrumentPlugin(
    name=NAME,
    role="amplifier",
    params=(
        ShakerAmplifier.gain.param(1.0),
        Param("reset_interlocks", "bool", "", False,
              help="Clear latched interlocks (INTL:RES) when the amplifier is opened for a run "
                   "(not by fsi-lab safe or identify)."),
        Param("baud_rate", "int", "Bd", 115200, minimum=1200, maximum=921600,
              help="Serial addresses only: line speed (8 data bits, no parity, 1 stop bit)."),
        Param("timeout_s", "float", "s", 2.0, minimum=0.05, maximum=60.0,
              help="Time allowed for each reply."),
        ShakerAmplifier.watchdog_time.param(1.0, name="watchdog_s"),
    ),
    open=open_amplifier,
    check=check_amplifier,
    help="Shaker power amplifier with latched interlocks, SCPI over serial or TCP (VISA).",
)


@hookimpl
def fsi_lab_instruments():
    return [PLUGIN]
