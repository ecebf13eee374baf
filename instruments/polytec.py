"""Polytec laser vibrometer over RS-232 (pyserial), Polytec's command grammar.

Lines ``Get|Set|GetDevInfo,<Device>,<index>,<Property>[,<value>]`` at 115200 baud 8N1,
terminated by LF; ``Get`` and ``GetDevInfo`` answer one line, ``Set`` answers nothing.

The controller's interface has two modes that add lines: ``Interface,0,Echo`` (every line
received is sent back before the answer) and ``Interface,0,Acknowledge`` (every ``Set`` is
answered). On opening the driver switches both off (``Set,Interface,0,Echo,Off``,
``Set,Interface,0,Acknowledge,Off``) and reads ``Get,Interface,0,Echo`` until it answers, so
that lines the modes produced before they went off are read and dropped; an echoed line is
recognised and skipped on every question anyway. It then locks the front panel for remote
control (``Set,Controller,0,Remote,LLO``, the value public OFV-5000 clients use; ``Local`` gives
the panel back and is sent on closing), discovers the velocity decoders at indices 0 to 3
(``GetDevInfo,VeloDec,<i>,Name``), checks the requested range against the decoder's list
(``GetDevInfo,VeloDec,<i>,Range``, read with or without a leading count of entries), sets it
(``Set,VeloDec,<i>,Range,125mm/s/V``) and reads every ``Set`` back with ``Get``. The range
gives the velocity channel's sensitivity (1/125 mm/s per V = 8 V/(m/s)); the decoder's
``SignalDelay`` is recorded and the run shifts the velocity channel's time origin by it.

Address: a serial device (``/dev/ttyUSB0``, ``COM3``), a pyserial URL (``rfc2217://host:port``,
``socket://host:port``) or ``embedded``.
"""

from __future__ import annotations

import re
from typing import Any, Mapping

from fsi_lab.contract import InstrumentPlugin, Vibrometer
from fsi_lab.errors import InstrumentError
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param

NAME = "polytec"
DECODER_SLOTS = 4
#: ``Controller,0,Remote`` values: remote control with the front panel locked, and local.
REMOTE = "LLO"
LOCAL = "Local"
#: Most lines read while waiting for the answer that shows echo and acknowledge are off.
SYNC_LINES = 8
ABSENT = ("Not Installed", "Not Available", "")
_RANGE = re.compile(r"^(\d+(?:\.\d+)?)(m|mm|um|µm)/s/V$")
_DELAY = re.compile(r"^\s*([-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?)\s*(s|ms|us|µs|ns)\s*$")
_UNIT = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "s": 1.0, "ms": 1e-3, "us": 1e-6,
         "µs": 1e-6, "ns": 1e-9}


def range_metres_per_volt(text: str) -> float:
    """``'125mm/s/V'`` -> 0.125 (m/s)/V; ValueError for anything else."""
    m = _RANGE.match(text.strip())
    if not m:
        raise ValueError(f"{text!r} is not a velocity range like 125mm/s/V")
    return float(m.group(1)) * _UNIT[m.group(2)]


def delay_seconds(text: str) -> float:
    """``'1100.00us'`` or ``'1.1 ms'`` -> seconds; ValueError for anything else."""
    m = _DELAY.match(text)
    if not m:
        raise ValueError(f"{text!r} is not a delay like 1100us")
    return float(m.group(1)) * _UNIT[m.group(2)]


def _serial_errors() -> tuple[type[BaseException], ...]:
    """What a failing serial port raises: pyserial's errors, OS errors and, on POSIX, termios
    errors (a port that vanished makes ``tcflush`` raise ``termios.error``, not an OSError)."""
    import serial

    errors: tuple[type[BaseException], ...] = (serial.SerialException, OSError)
    try:
        import termios
    except ImportError:  # pragma: no cover - Windows
        return errors
    return errors + (termios.error,)


class SerialLine:
    """A line-oriented serial port: one command, at most one reply line."""

    def __init__(self, port: str, baud_rate: int, timeout_s: float) -> None:
        import serial

        self.port = port
        self.timeout_s = timeout_s
        try:
            self.serial = serial.serial_for_url(port, baudrate=baud_rate, bytesize=8,
                                                parity="N", stopbits=1, timeout=timeout_s,
                                                write_timeout=timeout_s)
        except _serial_errors() + (ValueError,) as exc:
            # pyserial raises ValueError for a URL it cannot parse, its own error for a port
            # it cannot open (absent, busy, not permitted)
            hint = ("expected a device such as /dev/ttyUSB0 or COM3, or a pyserial URL such as "
                    "rfc2217://host:port" if isinstance(exc, ValueError) else
                    "check that the vibrometer is switched on and its cable plugged in, and "
                    "that the port is its own and free")
            raise InstrumentError(
                f"{NAME} at {port}: cannot open the serial port ({exc}); {hint}") from None
        self.serial.reset_input_buffer()

    def _error(self, line: str, what: str) -> InstrumentError:
        return InstrumentError(f"{NAME} at {self.port}: {what} (after sending {line!r})")

    def send(self, line: str) -> None:
        """Send one line (a ``Set``: no reply is expected)."""

        try:
            self.serial.write(line.encode("ascii") + b"\n")
            self.serial.flush()
        except _serial_errors() as exc:
            raise self._error(line, f"the serial port failed ({exc})") from None

    def read_line(self, line: str) -> str:
        """One reply line (stripped) to the question ``line`` just sent."""

        try:
            raw = self.serial.read_until(b"\n")
        except _serial_errors() as exc:
            raise self._error(line, f"the serial port failed ({exc})") from None
        if not raw.endswith(b"\n"):
            raise self._error(line, f"no reply within {self.timeout_s:g} s" +
                              (f" (got {raw!r})" if raw else ""))
        try:
            text = raw.decode("ascii").strip()
        except UnicodeDecodeError:
            raise self._error(line, f"garbled reply {raw!r}: check that the port runs at "
                                    "115200 baud 8N1 and the cable") from None
        if not text.isprintable():
            raise self._error(line, f"garbled reply {raw!r}")
        return text

    def ask(self, line: str) -> str:
        """Send ``line`` and return the reply line (an echo of ``line`` is skipped)."""

        try:
            self.serial.reset_input_buffer()  # a late reply to an interrupted question
        except _serial_errors() as exc:
            raise self._error(line, f"the serial port failed ({exc})") from None
        self.send(line)
        text = self.read_line(line)
        if text == line:  # the controller's echo mode
            text = self.read_line(line)
        return text

    def close(self) -> None:
        try:
            self.serial.close()
        except Exception:  # noqa: BLE001 - closing must not raise
            pass


class PolytecVibrometer(Vibrometer):
    """An open vibrometer. Use :func:`open_vibrometer`."""

    def __init__(self, line: SerialLine, controller: str, decoder: str, index: int,
                 range_name: str, ranges: list[str], delay_s: float, delay_source: str) -> None:
        self.line = line
        self.controller = controller
        self.decoder = decoder
        self.index = index
        self.range_name = range_name
        self.ranges = ranges
        self._delay = delay_s
        self._delay_source = delay_source

    def identify(self) -> str:
        return f"Polytec {self.controller}, velocity decoder {self.decoder} (VeloDec,{self.index})"

    def sensitivity(self) -> float:
        """V per (m/s) of the velocity output at the range in force."""
        return 1.0 / range_metres_per_volt(self.range_name)

    def delay(self) -> float:
        """Signal delay of the decoder, s."""
        return self._delay

    def settings(self) -> dict[str, Any]:
        return {"port": self.line.port, "decoder": self.decoder, "decoder_index": self.index,
                "range_read_back": self.range_name, "available_ranges": list(self.ranges),
                "sensitivity_v_per_m_s": self.sensitivity(), "signal_delay_s": self._delay,
                "signal_delay_source": self._delay_source}

    def monitor(self) -> None:
        """During the record: the decoder must still answer with the range the run set (the
        calibration of the velocity channel depends on it)."""
        got = self.line.ask(f"Get,VeloDec,{self.index},Range")
        if got != self.range_name:
            raise InstrumentError(f"{NAME} at {self.line.port}: the range reads {got!r} during "
                                  f"the record; the run set {self.range_name!r}")

    def safe_state(self) -> None:
        """A vibrometer has no output that can move the shaker: there is nothing to switch
        off, and nothing is sent (a dead serial link cannot delay the safe state)."""

    def read_state(self) -> dict[str, Any]:
        return {"range": self.line.ask(f"Get,VeloDec,{self.index},Range")}

    def close(self) -> None:
        """Give the front panel back (``Remote,Local``, best effort) and close the port."""
        try:
            self.line.send(f"Set,Controller,0,Remote,{LOCAL}")
        except InstrumentError:
            pass
        self.line.close()


def _quiet_interface(line: SerialLine) -> None:
    """Echo and acknowledge off, and every line they produced meanwhile read and dropped: the
    answer to ``Get,Interface,0,Echo`` is awaited among at most :data:`SYNC_LINES` lines."""
    line.send("Set,Interface,0,Echo,Off")
    line.send("Set,Interface,0,Acknowledge,Off")
    question = "Get,Interface,0,Echo"
    line.send(question)
    for _ in range(SYNC_LINES):
        answer = line.read_line(question)
        if answer in ("Off", "Not Available"):  # a controller without the echo mode
            return
        if answer == "On":
            raise InstrumentError(f"{NAME} at {line.port}: the controller's echo stays on after "
                                  "Set,Interface,0,Echo,Off")
    raise InstrumentError(f"{NAME} at {line.port}: no answer to {question!r} among "
                          f"{SYNC_LINES} lines; is this a Polytec controller?")


def parse_range_list(reply: str) -> list[str]:
    """The ranges of ``GetDevInfo,VeloDec,<i>,Range``: ``3,5mm/s/V,25mm/s/V,125mm/s/V`` or
    the same without the count; ValueError if an entry is not a range."""
    fields = [f.strip() for f in reply.split(",") if f.strip()]
    if fields and fields[0].isdigit():
        if int(fields[0]) != len(fields) - 1:
            raise ValueError(f"it announces {fields[0]} ranges and lists {len(fields) - 1}")
        fields = fields[1:]
    if not fields:
        raise ValueError("it lists no range")
    for field in fields:
        range_metres_per_volt(field)
    return fields


def _set_and_verify(line: SerialLine, target: str, value: str) -> None:
    """``Set,<target>,<value>``, then ``Get,<target>`` must answer ``value``."""
    line.send(f"Set,{target},{value}")
    got = line.ask(f"Get,{target}")
    if got != value:
        hint = " (is the controller in remote mode?)" if "Remote" not in target else ""
        raise InstrumentError(f"{NAME} at {line.port}: {target} reads back {got!r} after "
                              f"setting {value!r}{hint}")


def _discover(line: SerialLine) -> dict[int, str]:
    """Installed velocity decoders by index."""
    found = {}
    for index in range(DECODER_SLOTS):
        name = line.ask(f"GetDevInfo,VeloDec,{index},Name")
        if name not in ABSENT:
            found[index] = name
    return found


def check_vibrometer(address: str, settings: dict[str, Any], plan: Mapping[str, Any]) -> None:
    """The instrument check of :class:`~fsi_lab.contract.InstrumentPlugin` (ValueError): the
    range must read like a Polytec range, and the embedded bench's vibrometer offers only its
    own ranges, decoder and line speed."""
    try:
        range_metres_per_volt(settings["range"])
    except ValueError as exc:
        raise ValueError(f"range: {exc}") from None
    from fsi_lab.instruments.sim.embedded import check_embedded

    if not check_embedded(address, plan):
        return
    from fsi_lab.instruments.sim.specs import SERIAL_BAUD, VIBROMETER_DECODER, VIBROMETER_RANGES

    offered = {"range": tuple(VIBROMETER_RANGES), "decoder": ("auto", VIBROMETER_DECODER),
               "baud_rate": (SERIAL_BAUD,)}
    for key, accepted in offered.items():
        if settings[key] not in accepted:
            raise ValueError(f"{key}: {settings[key]!r} is not offered by the embedded simulated "
                             f"vibrometer; expected {' or '.join(map(repr, accepted))}")


def open_vibrometer(address: str, settings: dict[str, Any],
                    context: dict[str, Any]) -> PolytecVibrometer:
    """Open the port, take remote control, find the decoder, set and verify the range, read
    the signal delay."""
    if address.strip() in ("", "embedded"):
        from fsi_lab.instruments.sim.embedded import resolve_address

        address = resolve_address("vibrometer", NAME, address, context)
    line = SerialLine(address, settings["baud_rate"], settings["timeout_s"])
    try:
        _quiet_interface(line)
        controller = line.ask("GetDevInfo,Controller,0,Name")
        _set_and_verify(line, "Controller,0,Remote", REMOTE)
        decoders = _discover(line)
        wanted = settings["decoder"]
        chosen = [i for i, name in decoders.items() if wanted in ("auto", name)]
        if not chosen:
            listing = ", ".join(f"{n} (VeloDec,{i})" for i, n in decoders.items()) or "none"
            raise InstrumentError(f"{NAME} at {address}: no velocity decoder {wanted!r}; "
                                  f"installed: {listing}")
        index = chosen[0]
        reply = line.ask(f"GetDevInfo,VeloDec,{index},Range")
        try:
            ranges = parse_range_list(reply)
        except ValueError as exc:
            raise InstrumentError(f"{NAME} at {address}: unexpected range list {reply!r} "
                                  f"({exc}); expected [<count>,]<range>,...") from None
        if settings["range"] not in ranges:
            raise InstrumentError(f"{NAME} at {address}: range {settings['range']!r} is not "
                                  f"offered by {decoders[index]}; it offers {', '.join(ranges)}")
        _set_and_verify(line, f"VeloDec,{index},Range", settings["range"])
        if settings["delay_s"] is not None:
            delay, source = float(settings["delay_s"]), "profile"
        else:
            text = line.ask(f"Get,VeloDec,{index},SignalDelay")
            try:
                delay, source = delay_seconds(text), "decoder"
            except ValueError:
                raise InstrumentError(
                    f"{NAME} at {address}: the decoder reports its signal delay as {text!r}; "
                    "give it in the profile as delay_s") from None
    except BaseException:
        line.close()
        raise
    return PolytecVibrometer(line, controller, decoders[index], index, settings["range"],
                             ranges, delay, source)


PLUGIN = InstrumentPlugin(
    name=NAME,
    role="vibrometer",
    params=(
        Param("range", "str", "", "125mm/s/V",
              help="Velocity range of the decoder, as the controller names it (e.g. 25mm/s/V)."),
        Param("decoder", "str", "", "auto",
              help="Velocity decoder to use by name (e.g. VD-09); 'auto' takes the first found."),
        Param("delay_s", "float", "s", None, minimum=0.0, maximum=0.1,
              help="Signal delay of the sensor; unset: as the decoder reports it."),
        Param("baud_rate", "int", "Bd", 115200, minimum=1200, maximum=921600,
              help="Line speed of the RS-232 port (8 data bits, no parity, 1 stop bit)."),
        Param("timeout_s", "float", "s", 1.0, minimum=0.05, maximum=60.0,
              help="Time allowed for each reply."),
    ),
    open=open_vibrometer,
    check=check_vibrometer,
    help="Polytec laser vibrometer over RS-232 (Get/Set/GetDevInfo grammar).",
)


@hookimpl
def fsi_lab_instruments():
    return [PLUGIN]
