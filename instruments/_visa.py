"""A SCPI message link through pyvisa (pyvisa-py backend), shared by the SCPI drivers.

It turns every transport problem into an :class:`~fsi_lab.errors.InstrumentError` that names the
instrument, its address, the command and what happened; reads the error queue after each
configuration step; keeps each exchange whole when two threads share the link (a watchdog
feeder and the run); reads IEEE 488.2 definite-length blocks; and can reconnect with a short
timeout so that the safe state can still be reached after a garbled or missing reply.

Addresses are VISA resource names: ``TCPIP0::<host>::<port>::SOCKET`` (raw SCPI socket, e.g.
port 5025), ``TCPIP0::<host>::inst0::INSTR`` (VXI-11) or ``ASRL<device>::INSTR`` (serial, e.g.
``ASRL/dev/ttyUSB0::INSTR``).
"""

from __future__ import annotations

import contextlib
import functools
import re
import select
import socket
import threading
from collections.abc import Iterator

from fsi_lab.errors import InstrumentError

ADDRESS_EXAMPLES = ("TCPIP0::192.168.1.10::5025::SOCKET, TCPIP0::192.168.1.10::inst0::INSTR "
                    "or ASRL/dev/ttyUSB0::INSTR")
MAX_ERRORS = 32
_NO_ERROR = re.compile(r'^[+]?0\s*,')
_ERROR = re.compile(r'^[+-]?\d+\s*,\s*".*"$')
#: Most bytes of a definite-length block asked of the VISA library in one read (4 MiB: 0.34 s
#: at 100 Mbit/s, well within a reply timeout of a second or more).
BLOCK_PIECE = 1 << 22


def _address_hint(address: str) -> str:
    """What to check when ``address`` cannot be opened: the instrument, when the address is a
    well-formed VISA resource name, else the form one takes."""
    from pyvisa import rname

    try:
        rname.parse_resource_name(address)
    except rname.InvalidResourceName:
        return f"expected a VISA resource name such as {ADDRESS_EXAMPLES}"
    return ("check that the instrument is switched on and connected, and that the address "
            "(or serial port) is its own")


def _socket_of(resource) -> socket.socket | None:
    """The TCP socket under a pyvisa-py SOCKET resource, if there is one."""
    try:
        sock = getattr(resource.visalib.sessions[resource.session], "interface", None)
    except Exception:  # noqa: BLE001 - another backend, or a closed session
        return None
    return sock if isinstance(sock, socket.socket) else None


def _set_nodelay(resource) -> None:
    """Send small commands at once. Otherwise Nagle's algorithm holds a query written right
    after a command until the instrument's delayed acknowledgement (about 40 ms) arrives.
    pyvisa-py 0.8 accepts VI_ATTR_TCPIP_NODELAY on SOCKET sessions without applying it, so the
    option is set on the socket itself."""
    sock = _socket_of(resource)
    if sock is not None:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)


@contextlib.contextmanager
def _binary_reads(resource) -> Iterator[None]:
    """Reads inside the block end at their byte count only, not at a newline byte (the
    termination character is disabled, and restored afterwards)."""
    saved = resource.read_termination
    resource.read_termination = None
    try:
        yield
    finally:
        with contextlib.suppress(Exception):  # a closed session: connect() sets it again
            resource.read_termination = saved


def _exchange(method):
    """Run ``method`` holding the link's lock: its writes and reads are one exchange."""

    @functools.wraps(method)
    def locked(self, *args, **kwargs):
        with self.lock:
            return method(self, *args, **kwargs)
    return locked


class VisaLink:
    """One open VISA resource.

    Parameters
    ----------
    instrument
        Name used in messages (the plugin name).
    address
        VISA resource name.
    timeout_s
        Time allowed for each reply, s.
    baud_rate
        Serial resources only: line speed (8 data bits, no parity, one stop bit).
    """

    def __init__(self, instrument: str, address: str, timeout_s: float,
                 baud_rate: int = 115200) -> None:
        self.instrument = instrument
        self.address = address
        self.timeout_s = float(timeout_s)
        self.baud_rate = int(baud_rate)
        self.broken: str | None = None
        self._rm = None
        self._resource = None
        #: Held for each whole exchange (a query's write and read, a step and its error check).
        self.lock = threading.RLock()
        self.connect(self.timeout_s)

    # ------------------------------------------------------------------ connection
    @_exchange
    def connect(self, timeout_s: float) -> None:
        """(Re)open the resource; InstrumentError if it cannot be opened."""
        import pyvisa
        from pyvisa import constants

        self._close_resource()
        try:
            if self._rm is None:
                self._rm = pyvisa.ResourceManager("@py")
            resource = self._rm.open_resource(self.address,
                                              open_timeout=int(timeout_s * 1000))
        except Exception as exc:  # noqa: BLE001 - pyvisa raises many kinds for a bad address
            raise InstrumentError(
                f"{self.instrument} at {self.address}: cannot open the connection ({exc}); "
                f"{_address_hint(self.address)}") from None
        resource.timeout = int(timeout_s * 1000)
        resource.read_termination = "\n"
        resource.write_termination = "\n"
        if self.address.upper().endswith("::SOCKET"):
            _set_nodelay(resource)
        if self.address.upper().startswith("ASRL"):
            resource.baud_rate = self.baud_rate
            resource.data_bits = 8
            resource.parity = constants.Parity.none
            resource.stop_bits = constants.StopBits.one
        self._resource = resource
        self.broken = None

    def _close_resource(self) -> None:
        resource, self._resource = self._resource, None
        if resource is not None:
            with contextlib.suppress(Exception):
                resource.close()

    def close(self) -> None:
        """Close the resource (never raises). The resource manager stays open: pyvisa keeps one
        per VISA library for the whole process, shared by every link."""
        self._close_resource()

    @contextlib.contextmanager
    def timeout(self, seconds: float) -> Iterator[None]:
        """Use a different reply timeout inside the block."""
        resource = self._resource
        saved = resource.timeout if resource is not None else None
        if resource is not None:
            resource.timeout = int(seconds * 1000)
        try:
            yield
        finally:
            if resource is not None and self._resource is resource:
                with contextlib.suppress(Exception):
                    resource.timeout = saved

    @_exchange
    def recover(self, timeout_s: float) -> None:
        """Reconnect if an earlier exchange left the link out of step (safe state, read back)."""
        if self.broken is not None or self._resource is None:
            self.connect(timeout_s)

    # ------------------------------------------------------------------ exchanges
    def _fail(self, command: str, what: str) -> InstrumentError:
        self.broken = what
        shown = command if len(command) <= 60 else command[:57] + "..."
        return InstrumentError(f"{self.instrument} at {self.address}: {what} "
                               f"(after sending {shown!r})")

    def _io(self, command: str, action):
        import pyvisa
        from pyvisa import constants

        if self._resource is None:
            raise InstrumentError(f"{self.instrument} at {self.address}: the connection is closed")
        try:
            return action(self._resource)
        except pyvisa.errors.VisaIOError as exc:
            if exc.error_code == constants.StatusCode.error_timeout:
                seconds = self._resource.timeout / 1000 if self._resource.timeout else 0
                what = ("the instrument closed the connection" if self._peer_closed()
                        else f"no reply within {seconds:g} s")
            else:
                what = f"VISA error {exc.description}"
            raise self._fail(command, what) from None
        except ConnectionRefusedError:
            raise self._fail(command, "nothing answers at this address (connection refused): "
                                      "is the instrument on, and is the address right?") from None
        except OSError as exc:
            raise self._fail(command, f"the connection was lost ({exc.strerror or exc})") from None
        except BaseException:
            # Ctrl+C mid-exchange: a late reply may still come, so nothing read on this
            # connection can be trusted any more (the safe state reconnects).
            self.broken = f"the exchange of {command!r} was interrupted"
            raise

    def fail(self, command: str, what: str) -> InstrumentError:
        """The error to raise when the reply to ``command`` is not what was expected (``what``
        says how); the link is marked out of step, so that the safe state reconnects."""
        return self._fail(command, what)

    def _peer_closed(self) -> bool:
        """Whether the TCP peer has closed a socket resource (best effort)."""
        try:
            sock = _socket_of(self._resource)
            if sock is None:
                return False
            readable, _, _ = select.select([sock], [], [], 0)
            return bool(readable) and sock.recv(1, socket.MSG_PEEK) == b""
        except Exception:  # noqa: BLE001 - only a hint for the message
            return False

    @_exchange
    def write(self, command: str) -> None:
        """Send one command."""
        self._io(command, lambda r: r.write_raw(command.encode("ascii") + b"\n"))

    @_exchange
    def write_raw(self, command: str, data: bytes) -> None:
        """Send ``data`` (a whole message with its terminator); ``command`` names it."""
        self._io(command, lambda r: r.write_raw(data))

    @_exchange
    def query(self, command: str) -> str:
        """Send a query and return its reply line without the terminator."""
        self.write(command)
        raw = self._io(command, lambda r: r.read_raw())
        try:
            text = raw.decode("ascii")
        except UnicodeDecodeError:
            raise self._fail(command, f"garbled reply {raw[:40]!r} (check the line "
                                      "settings and the cable)") from None
        return text.rstrip("\r\n")

    @_exchange
    def read_block(self, command: str) -> bytes:
        """Send ``command`` and read its definite-length block reply (and the terminator).

        The header (``#<n><length>``) is read first, then the data and its newline in one read
        of the declared length (in pieces of at most :data:`BLOCK_PIECE` bytes, each of which
        must arrive within the reply timeout), with the termination character disabled: with it,
        pyvisa-py's socket session ends a read at every newline byte of the binary data, about
        every 256 bytes of int32 codes, and a 4-input block of 0.1 s at 204.8 kS/s took some
        1 500 reads instead of one.
        """
        self.write(command)

        def read(resource) -> bytes:
            with _binary_reads(resource):
                head = resource.read_bytes(2)
                if head[:1] != b"#" or not b"1" <= head[1:2] <= b"9":
                    raise ValueError(f"reply starts with {head!r}, not an IEEE 488.2 block (#<n>)")
                digits = head[1] - 0x30
                length_text = resource.read_bytes(digits)
                if not length_text.isdigit():
                    raise ValueError(f"block length {length_text!r} is not a number")
                length = int(length_text)
                data = resource.read_bytes(length + 1, chunk_size=min(length + 1, BLOCK_PIECE))
            if data[-1:] != b"\n":
                raise ValueError(f"block not followed by a newline but by {data[-1:]!r}")
            return data[:-1]

        try:
            return self._io(command, read)
        except ValueError as exc:
            raise self._fail(command, f"garbled reply: {exc}") from None

    # ------------------------------------------------------------------ typed queries
    def query_float(self, command: str) -> float:
        """A query whose reply is a number."""
        reply = self.query(command)
        try:
            return float(reply)
        except ValueError:
            raise self._fail(command, f"unexpected reply {reply!r}; expected a number") from None

    def query_int(self, command: str) -> int:
        """A query whose reply is an integer."""
        reply = self.query(command)
        try:
            return int(reply.strip().lstrip("+"))
        except ValueError:
            raise self._fail(command, f"unexpected reply {reply!r}; expected an integer") from None

    def query_bool(self, command: str) -> bool:
        """A query whose reply is 0/1 (or OFF/ON)."""
        reply = self.query(command).strip().upper()
        if reply in ("1", "ON"):
            return True
        if reply in ("0", "OFF"):
            return False
        raise self._fail(command, f"unexpected reply {reply!r}; expected 0 or 1")

    # ------------------------------------------------------------------ error queue
    @_exchange
    def errors(self) -> list[str]:
        """Empty the instrument's error queue (``SYST:ERR?``) and return its entries."""
        found = []
        for _ in range(MAX_ERRORS):
            reply = self.query("SYST:ERR?")
            if _NO_ERROR.match(reply):
                return found
            if not _ERROR.match(reply):
                raise self._fail("SYST:ERR?", f"unexpected reply {reply!r}; expected "
                                              '<code>,"<message>"')
            found.append(reply)
        return found

    @_exchange
    def check(self, step: str, accepted: str = "") -> None:
        """Raise InstrumentError if the error queue holds anything after ``step``."""
        found = self.errors()
        if found:
            hint = f"; {accepted}" if accepted else ""
            raise InstrumentError(f"{self.instrument} at {self.address}: {step} was refused: "
                                  f"{'; '.join(found)}{hint}")

    @_exchange
    def send_checked(self, command: str, accepted: str = "") -> None:
        """Send one configuration command and check the error queue after it."""
        self.write(command)
        self.check(repr(command), accepted)
