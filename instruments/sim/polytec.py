"""Simulated Polytec vibrometer (PDV-100 class) speaking Polytec's RS-232 grammar.

Lines are ``Get|Set|GetDevInfo,<Device>,<index>,<Property>[,<value>]`` terminated by LF, at
115200 baud 8N1. ``Get`` and ``GetDevInfo`` answer one line; ``Set`` answers nothing (read it
back with ``Get``). ``Controller,0,Remote`` is ``Local`` (front panel in control) or ``LLO``
(remote control, panel locked out), as public OFV-5000 clients use it; decoder settings change
only in ``LLO``, otherwise a ``Set`` is silently ignored. Unknown properties answer
``Not Available``; a decoder index with nothing installed answers ``Not Installed`` to
``GetDevInfo,VeloDec,<i>,Name``.

The interface modes: with ``Interface,0,Echo`` ``On`` every line received is sent back first;
with ``Interface,0,Acknowledge`` ``On`` every ``Set`` is answered with :data:`ACKNOWLEDGE` (the
text is this simulation's: the references at hand do not give it). Both power up as the bench
options say (off by default).

The velocity decoder sits at ``decoder_index`` (0 by default) among indices 0 to 3; its ranges
are those of :data:`~.specs.VIBROMETER_RANGES`; it powers up in ``25mm/s/V``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from fsi_lab.instruments.sim.specs import VIBROMETER_DECODER as DECODER
from fsi_lab.instruments.sim.specs import VIBROMETER_RANGES

if TYPE_CHECKING:  # pragma: no cover
    from fsi_lab.instruments.sim.bench import SimBench

CONTROLLER = "PDV-100"
VERSION = "1.0 (simulated)"
DECODER_SLOTS = 4
POWER_UP_RANGE = "25mm/s/V"
MAX_FREQUENCY = "22kHz"
NOT_AVAILABLE = "Not Available"
ACKNOWLEDGE = "OK"
REMOTE_VALUES = ("Local", "LLO")


class VibrometerState:
    """Remote mode, decoder range and signal delay."""

    def __init__(self, delay_s: float, decoder_index: int, echo: bool = False,
                 acknowledge: bool = False) -> None:
        self.remote = "Local"
        self.echo = bool(echo)
        self.acknowledge = bool(acknowledge)
        self.range_name = POWER_UP_RANGE
        self.delay_s = float(delay_s)
        self.decoder_index = int(decoder_index)


class PolytecSim:
    """The vibrometer's line protocol, acting on the bench."""

    def __init__(self, bench: "SimBench") -> None:
        self.bench = bench
        opts = bench.options
        self.state = VibrometerState(opts.vibrometer_delay_s, opts.vibrometer_decoder_index,
                                     getattr(opts, "vibrometer_echo", False),
                                     getattr(opts, "vibrometer_acknowledge", False))

    def handle(self, line: bytes, connection: object = None) -> bytes | None:
        """Answer one line; the reply (with LF, after the echo in echo mode) or None."""
        with self.bench.lock:
            self.bench.catch_up()
            echo = self.state.echo  # the line is echoed as received, before it takes effect
            reply = self._run(line)
            if reply is None and self.state.acknowledge and line.startswith(b"Set,"):
                reply = ACKNOWLEDGE
        out = (line.rstrip(b"\r") + b"\n") if echo else b""
        if reply is not None:
            out += reply.encode("ascii") + b"\n"
        return out or None

    def _run(self, line: bytes) -> str | None:
        try:
            fields = line.decode("ascii").strip().split(",")
        except UnicodeDecodeError:
            return None
        if len(fields) < 4 or not fields[2].isdigit():
            return None if fields and fields[0] == "Set" else NOT_AVAILABLE
        verb, device, index, prop = fields[0], fields[1], int(fields[2]), fields[3]
        value = ",".join(fields[4:])
        if verb == "GetDevInfo":
            return self._dev_info(device, index, prop)
        if verb == "Get":
            return self._get(device, index, prop)
        if verb == "Set":
            self._set(device, index, prop, value)
            return None
        return NOT_AVAILABLE

    def _decoder(self, device: str, index: int) -> bool:
        return device == "VeloDec" and index == self.state.decoder_index

    def _dev_info(self, device: str, index: int, prop: str) -> str:
        if device == "Controller" and index == 0:
            return {"Name": CONTROLLER, "Version": VERSION,
                    "Remote": ",".join([str(len(REMOTE_VALUES)), *REMOTE_VALUES])}.get(
                prop, NOT_AVAILABLE)
        if device == "Interface" and index == 0 and prop in ("Echo", "Acknowledge"):
            return "2,Off,On"
        if device == "VeloDec" and 0 <= index < DECODER_SLOTS:
            if not self._decoder(device, index):
                return "Not Installed" if prop == "Name" else NOT_AVAILABLE
            if prop == "Name":
                return DECODER
            if prop == "Range":
                return ",".join([str(len(VIBROMETER_RANGES)), *VIBROMETER_RANGES])
        return NOT_AVAILABLE

    def _get(self, device: str, index: int, prop: str) -> str:
        if device == "Controller" and index == 0 and prop == "Remote":
            return self.state.remote
        if device == "Interface" and index == 0 and prop == "Echo":
            return "On" if self.state.echo else "Off"
        if device == "Interface" and index == 0 and prop == "Acknowledge":
            return "On" if self.state.acknowledge else "Off"
        if device == "Controller" and index == 0 and prop == "Name":
            return CONTROLLER
        if self._decoder(device, index):
            if prop == "Range":
                return self.state.range_name
            if prop == "Name":
                return DECODER
            if prop == "SignalDelay":
                return f"{self.state.delay_s * 1e6:.2f}us"
            if prop == "MaxFreq":
                return MAX_FREQUENCY
        return NOT_AVAILABLE

    def _set(self, device: str, index: int, prop: str, value: str) -> None:
        if device == "Controller" and index == 0 and prop == "Remote" and value in REMOTE_VALUES:
            self.state.remote = value
            return
        if device == "Interface" and index == 0 and prop in ("Echo", "Acknowledge") \
                and value in ("On", "Off"):
            setattr(self.state, prop.lower(), value == "On")
            return
        if self.state.remote != "LLO":
            return
        if self._decoder(device, index) and prop == "Range" and value in VIBROMETER_RANGES:
            self.state.range_name = value
