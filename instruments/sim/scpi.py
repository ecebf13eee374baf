"""SCPI on the instrument side: message framing, header matching, error queue, binary blocks,
and the IEEE 488.2 status model every simulated SCPI instrument shares.

The simulated instruments parse what a real instrument parses: newline-terminated program
messages (several commands may be joined by ``;``), headers in short or long form in any case
(``SOUR1:FUNC:ARB:SRAT`` = ``source:function:arbitrary:srate``), optional nodes, numeric
suffixes, and IEEE 488.2 definite-length binary blocks (``#<n><length><bytes>``) whose bytes may
contain newlines, carriage returns or any other white space: a block's bytes are never stripped.

Framing is incremental (:class:`Framer`): each byte received is looked at once, so a long line
arriving in many reads costs time in proportion to its length, never to the square of it.
Error texts are cut to 255 characters, as SCPI-99 (21.8) caps them.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Callable

#: Standard SCPI error numbers used by the simulated instruments.
ERRORS = {
    -100: "Command error",
    -102: "Syntax error",
    -104: "Data type error",
    -108: "Parameter not allowed",
    -109: "Missing parameter",
    -113: "Undefined header",
    -131: "Invalid suffix",
    -160: "Block data error",
    -200: "Execution error",
    -211: "Trigger ignored",
    -221: "Settings conflict",
    -222: "Data out of range",
    -223: "Too much data",
    -224: "Illegal parameter value",
    -350: "Queue overflow",
    -410: "Query INTERRUPTED",
}
#: Longest error text SCPI allows in a ``SYST:ERR?`` reply (the quoted part), characters.
MAX_ERROR_TEXT = 255
#: Bits of the IEEE 488.2 standard event status register (``*ESR?``).
ESR_OPC, ESR_QYE, ESR_DDE, ESR_EXE, ESR_CME, ESR_PON = 0x01, 0x04, 0x08, 0x10, 0x20, 0x80
#: Bits of the status byte (``*STB?``): error queue not empty (SCPI), message available,
#: event status summary, master summary status.
STB_EAV, STB_MAV, STB_ESB, STB_MSS = 0x04, 0x10, 0x20, 0x40


class ScpiError(Exception):
    """Raised by a command handler: the instrument queues ``code`` with ``detail``."""

    def __init__(self, code: int, detail: str = "") -> None:
        super().__init__(f"{code} {ERRORS.get(code, 'Error')}; {detail}")
        self.code = code
        self.detail = detail


def _esr_bit(code: int) -> int:
    """The event status bit an error of ``code`` sets (IEEE 488.2 11.5.1, SCPI 21.8)."""
    if -199 <= code <= -100:
        return ESR_CME
    if -299 <= code <= -200:
        return ESR_EXE
    if -399 <= code <= -300 or code > 0:
        return ESR_DDE
    if -499 <= code <= -400:
        return ESR_QYE
    return 0


class ErrorQueue:
    """The instrument's error queue, read one entry per ``SYST:ERR?``.

    It holds at most :attr:`LIMIT` entries; when it is full the newest entry is replaced by
    -350 "Queue overflow" and further errors are lost until it is read (SCPI-99 21.8.2). Each
    error sets its bit in the event status register of ``status`` when one is given.
    """

    LIMIT = 20

    def __init__(self, status: "Status | None" = None) -> None:
        self._entries: list[tuple[int, str]] = []
        self.status = status

    def push(self, code: int, detail: str = "") -> None:
        """Queue error ``code`` (see :data:`ERRORS`) with a detail; -350 once full."""
        if self.status is not None:
            self.status.esr |= _esr_bit(code)
        if len(self._entries) >= self.LIMIT:
            self._entries[-1] = (-350, ERRORS[-350])
            return
        text = ERRORS.get(code, "Error") + (f"; {detail}" if detail else "")
        text = text.replace('"', "'")
        if len(text) > MAX_ERROR_TEXT:
            text = text[:MAX_ERROR_TEXT - 3] + "..."
        self._entries.append((code, text))

    def pop(self) -> str:
        """``+0,"No error"`` or the oldest error as ``-222,"Data out of range; ..."``."""
        if not self._entries:
            return '+0,"No error"'
        code, text = self._entries.pop(0)
        return f'{code:+d},"{text}"'

    def clear(self) -> None:
        """``*CLS``: forget every queued error."""
        self._entries.clear()

    def __len__(self) -> int:
        return len(self._entries)


class Status:
    """The IEEE 488.2 status registers: event status (``*ESR?``), its enable (``*ESE``), the
    service request enable (``*SRE``) and the status byte computed from them (``*STB?``).

    The power-on bit of the event status register is set when the instrument is created.
    """

    def __init__(self) -> None:
        self.esr = ESR_PON
        self.ese = 0
        self.sre = 0

    def read_esr(self) -> int:
        """``*ESR?``: the event status register, cleared by the reading."""
        value, self.esr = self.esr, 0
        return value

    def stb(self, error_queue_nonempty: bool, message_available: bool) -> int:
        """``*STB?``: the status byte (reading it clears nothing)."""
        value = (STB_EAV if error_queue_nonempty else 0) | (STB_MAV if message_available else 0)
        if self.esr & self.ese:
            value |= STB_ESB
        if value & self.sre & ~STB_MSS:
            value |= STB_MSS
        return value


# --------------------------------------------------------------------------- framing
#: Bytes that matter to the framer outside a quoted string, and inside one.
_FRAME_SPECIAL = re.compile(rb"[\n\"'#]")
_FRAME_IN_QUOTE = {0x22: re.compile(rb'[\n"]'), 0x27: re.compile(rb"[\n']")}


class Framer:
    """Splits a byte stream into program messages, incrementally.

    A message ends at a newline that is neither inside a definite-length binary block nor
    (SCPI strings cannot span messages, so a newline ends it there too) anything else; the
    newline is dropped, and so is a carriage return before it unless that byte belongs to a
    block. Each byte is examined once however the stream is cut into reads; a block's payload
    is skipped by its announced length without being looked at.
    """

    def __init__(self) -> None:
        self._buffer = bytearray()
        self._scan = 0  # where the next look starts, in the current message
        self._quote: int | None = None
        self._block_end = -1  # just past the last block payload of the current message

    @property
    def pending(self) -> bytes:
        """Bytes received that do not yet make a complete message."""
        return bytes(self._buffer)

    def feed(self, data: bytes) -> list[bytes]:
        """Add ``data``; every message it completes, in order."""
        buf = self._buffer
        buf += data
        messages: list[bytes] = []
        start, i, n = 0, self._scan, len(buf)
        while i < n:
            if self._quote is not None:
                m = _FRAME_IN_QUOTE[self._quote].search(buf, i)
            else:
                m = _FRAME_SPECIAL.search(buf, i)
            if m is None:
                i = n
                break
            i = m.start()
            byte = buf[i]
            if byte == 0x0A:
                end = i
                if end > start and buf[end - 1] == 0x0D and end - 1 >= self._block_end:
                    end -= 1
                messages.append(bytes(buf[start:end]))
                start = i + 1
                i = start
                self._quote = None
                self._block_end = -1
            elif byte in (0x22, 0x27):
                self._quote = None if self._quote == byte else (
                    byte if self._quote is None else self._quote)
                i += 1
            else:  # '#': a definite-length block?
                if i + 1 >= n:
                    break  # wait for the byte after '#'
                digits = buf[i + 1] - 0x30
                if not 1 <= digits <= 9:
                    i += 1
                    continue
                if i + 2 + digits > n:
                    break  # the length is not all here yet
                length_text = bytes(buf[i + 2:i + 2 + digits])
                if not length_text.isdigit():
                    i += 1
                    continue
                end = i + 2 + digits + int(length_text)
                if end > n:
                    break  # the payload is not all here yet: look again from '#'
                self._block_end = end
                i = end
        if start:
            del buf[:start]
            i -= start
            if self._block_end >= 0:
                self._block_end -= start
        self._scan = i
        return messages


def take_messages(buffer: bytearray) -> list[bytes]:
    """Remove every complete program message from ``buffer`` and return them (one-shot form of
    :class:`Framer`; an incomplete message stays in the buffer)."""
    framer = Framer()
    messages = framer.feed(bytes(buffer))
    buffer[:] = framer.pending
    return messages


def ieee_block(payload: bytes) -> bytes:
    """``payload`` as an IEEE 488.2 definite-length block (``#<n><length><payload>``)."""
    length = str(len(payload)).encode()
    return b"#" + str(len(length)).encode() + length + payload


def parse_ieee_block(data: bytes) -> bytes:
    """The payload of a definite-length block that makes up all of ``data``.

    Raises
    ------
    ScpiError
        -160 when ``data`` is not exactly one well-formed block.
    """
    if len(data) < 2 or data[:1] != b"#" or not b"1" <= data[1:2] <= b"9":
        raise ScpiError(-160, "expected #<digits><length><bytes>")
    digits = data[1] - 0x30
    length_text = data[2:2 + digits]
    if len(length_text) != digits or not length_text.isdigit():
        raise ScpiError(-160, "bad block length")
    payload = data[2 + digits:]
    if len(payload) != int(length_text):
        raise ScpiError(-160, f"block announces {int(length_text)} bytes, carries {len(payload)}")
    return payload


# --------------------------------------------------------------------------- headers
@dataclass(frozen=True)
class _Node:
    short: str
    long: str
    optional: bool
    suffix: bool

    def match(self, token: str) -> tuple[bool, int | None]:
        """Whether ``token`` (upper case) names this node, and its numeric suffix."""
        digits = ""
        if self.suffix:
            m = re.fullmatch(r"([A-Z*]+)(\d*)", token)
            if not m:
                return False, None
            token, digits = m.group(1), m.group(2)
        if token not in (self.short, self.long):
            return False, None
        return True, int(digits) if digits else None


def _compile(pattern: str) -> tuple[list[_Node], bool]:
    """Nodes of a pattern such as ``[SOURce#:]FUNCtion:ARBitrary:SRATe?``."""
    query = pattern.endswith("?")
    pattern = pattern.rstrip("?")
    nodes = []
    for match in re.finditer(r"(\[)?:?([A-Za-z*]+)(#)?:?(\])?", pattern):
        word = match.group(2)
        short = "".join(c for c in word if c.isupper() or c == "*")
        nodes.append(_Node(short, word.upper(), bool(match.group(1)), bool(match.group(3))))
    return nodes, query


def _match(nodes: list[_Node], tokens: list[str]) -> list[int | None] | None:
    """Numeric suffixes (one per node) if ``tokens`` match ``nodes``, else None."""
    if not nodes:
        return [] if not tokens else None
    node = nodes[0]
    if tokens:
        ok, suffix = node.match(tokens[0])
        if ok:
            rest = _match(nodes[1:], tokens[1:])
            if rest is not None:
                return [suffix] + rest
    if node.optional:
        rest = _match(nodes[1:], tokens)
        if rest is not None:
            return [None] + rest
    return None


#: A handler receives the argument bytes (may be empty) and the numeric suffixes of the
#: header's nodes (None where absent), and returns the reply text (queries) or None.
Handler = Callable[[bytes, list], "str | bytes | None"]


class CommandSet:
    """Maps SCPI header patterns to handlers and runs program messages.

    Patterns use SCPI notation: upper-case letters are the short form, ``[...]`` an optional
    node, ``#`` a numeric suffix, a trailing ``?`` a query. In a message of several commands
    joined by ``;``, a header that does not start with ``:`` or ``*`` and names nothing from
    the root is looked up under the path of the command before it (SCPI-99 6.2.4).
    """

    def __init__(self, errors: ErrorQueue) -> None:
        self.errors = errors
        self._table: list[tuple[list[_Node], bool, Handler]] = []
        #: Replies of the message being run so far (what ``*STB?`` sees as MAV).
        self.replies_pending = 0

    def add(self, pattern: str, handler: Handler) -> None:
        """Run ``handler`` for headers matching ``pattern`` (queries and settings apart)."""
        nodes, query = _compile(pattern)
        self._table.append((nodes, query, handler))

    def run(self, message: bytes) -> bytes | None:
        """Execute one program message; the joined replies of its queries, or None."""
        replies: list[bytes] = []
        path: list[str] = []
        self.replies_pending = 0
        for command, protected in _split_commands(message):
            reply, path = self._run_one(command, protected, path)
            if reply is not None:
                replies.append(reply)
                self.replies_pending = len(replies)
        self.replies_pending = 0
        if not replies:
            return None
        return b";".join(replies) + b"\n"

    def _run_one(self, command: bytes, protected: int,
                 path: list[str]) -> tuple[bytes | None, list[str]]:
        """Run one command; its reply and the header path the next command starts from.

        ``protected`` bytes at the start of ``command`` (up to the end of its last binary
        block) are never stripped.
        """
        lead = len(command) - len(command.lstrip())
        command = command[:protected] + command[protected:].rstrip() if protected \
            else command.rstrip()
        command = command[lead:]
        if not command:
            return None, path
        split = _WHITESPACE.search(command)
        header_bytes = command[:split.start()] if split else command
        args = command[split.end():] if split else b""
        try:
            header = header_bytes.decode("ascii").upper()
        except UnicodeDecodeError:
            self.errors.push(-102, "header is not ASCII")
            return None, []
        query = header.endswith("?")
        bare = header.rstrip("?")
        tokens = bare.lstrip(":").split(":")
        candidates = [tokens]
        if path and not bare.startswith((":", "*")):
            candidates.append(path + tokens)
        for tried in candidates:
            found = self._find(tried, query)
            if found is None:
                continue
            handler, suffixes = found
            next_path = tried[:-1] if not bare.startswith("*") else path
            try:
                reply = handler(args, suffixes)
            except ScpiError as exc:
                self.errors.push(exc.code, exc.detail)
                return None, next_path
            if reply is None:
                return None, next_path
            return (reply if isinstance(reply, bytes) else reply.encode("ascii")), next_path
        self.errors.push(-113, header)
        return None, []

    def _find(self, tokens: list[str], query: bool):
        for nodes, is_query, handler in self._table:
            if is_query != query:
                continue
            suffixes = _match(nodes, tokens)
            if suffixes is not None:
                return handler, suffixes
        return None


#: SCPI white space (IEEE 488.2 7.4.1.2): bytes 0 to 32 except the newline.
_WHITESPACE = re.compile(rb"[\x00-\x09\x0b-\x20]+")
_SPLIT_SPECIAL = re.compile(rb"[;\"'#]")


def _split_commands(message: bytes) -> list[tuple[bytes, int]]:
    """Split at ``;`` outside binary blocks and quoted strings; each part with the length of
    its start that ends with its last binary block (0 if it has none), which is never
    stripped."""
    parts: list[tuple[bytes, int]] = []
    start, i, n = 0, 0, len(message)
    protected = 0
    while i < n:
        m = _SPLIT_SPECIAL.search(message, i)
        if m is None:
            break
        i = m.start()
        c = message[i]
        if c in (0x22, 0x27):
            close = message.find(bytes([c]), i + 1)
            i = n if close < 0 else close + 1
        elif c == 0x23:
            digits = message[i + 1] - 0x30 if i + 1 < n else 0
            length = message[i + 2:i + 2 + digits] if 1 <= digits <= 9 else b""
            if length.isdigit():
                i = min(n, i + 2 + digits + int(length))
                protected = i - start
            else:
                i += 1
        else:
            parts.append((message[start:i], protected))
            start = i + 1
            i = start
            protected = 0
    parts.append((message[start:], protected))
    return parts


# --------------------------------------------------------------------------- arguments
def text(args: bytes) -> str:
    """Arguments as text (upper case stripped of quotes), -102 if not ASCII."""
    try:
        return args.decode("ascii").strip().strip('"').strip("'")
    except UnicodeDecodeError:
        raise ScpiError(-102, "argument is not ASCII") from None


_NUMBER = re.compile(r"^([-+]?(?:\d+\.?\d*|\.\d+)(?:E[-+]?\d+)?)\s*([A-Z%]*)$")
#: SCPI unit prefixes (upper case, as suffixes are case-blind: ``M`` is milli, ``MA`` mega).
_PREFIXES = {"": 1.0, "EX": 1e18, "PE": 1e15, "T": 1e12, "G": 1e9, "MA": 1e6, "K": 1e3,
             "M": 1e-3, "U": 1e-6, "N": 1e-9, "P": 1e-12, "F": 1e-15, "A": 1e-18}
#: Units whose ``M`` prefix means mega by long usage (``MHZ``, ``MOHM``; SCPI-99 7.7.3).
_MEGA_M = ("HZ", "OHM")


def _unit_factor(suffix_text: str, unit: str | None) -> float | None:
    """The factor of a unit suffix such as ``MV`` or ``KHZ`` for ``unit``, None if foreign."""
    if not suffix_text:
        return 1.0
    if unit is None or not suffix_text.endswith(unit):
        return None
    prefix = suffix_text[:-len(unit)]
    if prefix == "M" and unit in _MEGA_M:
        return 1e6
    return _PREFIXES.get(prefix)


def number(args: bytes, low: float | None = None, high: float | None = None,
           words: dict[str, float] | None = None, unit: str | None = None) -> float:
    """A numeric argument within [low, high], else -222 (or -109 missing, -224 not a number,
    -131 a foreign unit suffix).

    Parameters
    ----------
    args
        The argument bytes.
    low, high
        Bounds of the accepted values, in the base unit.
    words
        Keywords accepted in place of a number (``MIN``, ``MAX``, ``DEF``, ``INF``...), by
        value.
    unit
        Base unit whose suffix may follow the number, with an SCPI prefix (``V``: ``100 MV``
        is 0.1; ``HZ``: ``1 KHZ`` is 1000).
    """
    value_text = text(args).upper()
    if not value_text:
        raise ScpiError(-109, "a number is expected")
    if words and value_text in words:
        return words[value_text]
    m = _NUMBER.match(value_text)
    if m is None:
        raise ScpiError(-224, f"{value_text[:40]!r} is not a number")
    factor = _unit_factor(m.group(2), unit)
    if factor is None:
        raise ScpiError(-131, f"{m.group(2)!r}; expected {unit or 'no unit'}")
    value = float(m.group(1)) * factor
    if value != value or (low is not None and value < low) or (high is not None and value > high):
        lo = "-inf" if low is None else f"{low:g}"
        hi = "inf" if high is None else f"{high:g}"
        bounds = f"{lo} to {hi}"
        raise ScpiError(-222, f"{value_text} outside {bounds}")
    return value


def limits(low: float, high: float, default: float) -> dict[str, float]:
    """The ``MIN``/``MAX``/``DEF`` keywords (and their long forms) for :func:`number`."""
    return {"MIN": low, "MINIMUM": low, "MAX": high, "MAXIMUM": high, "DEF": default,
            "DEFAULT": default}


def query_limit(args: bytes, low: float, high: float, default: float, current: float) -> float:
    """What a query with an optional ``MIN``/``MAX``/``DEF`` argument asks about: that value,
    or (no argument) the ``current`` one."""
    word = text(args).upper()
    if not word:
        return current
    table = limits(low, high, default)
    if word not in table:
        raise ScpiError(-224, f"{word[:40]!r}; expected MIN, MAX or DEF")
    return table[word]


def boolean(args: bytes) -> bool:
    """ON/OFF, or a number: 0 is OFF, anything that rounds to non-zero is ON (IEEE 488.2
    10.1.3)."""
    word = text(args).upper()
    if word == "ON":
        return True
    if word == "OFF":
        return False
    m = _NUMBER.match(word)
    if m and not m.group(2):
        return round(float(m.group(1))) != 0
    raise ScpiError(-224, f"{word[:40]!r}; expected ON, OFF, 1 or 0")


def choice(args: bytes, choices: dict[str, str]) -> str:
    """One of the keyword ``choices`` (keys are accepted spellings, values canonical names)."""
    word = text(args).upper()
    if word not in choices:
        allowed = ", ".join(sorted(set(choices.values())))
        raise ScpiError(-224, f"{word!r}; expected one of {allowed}")
    return choices[word]


def suffix(value: int | None, allowed: range, default: int = 1) -> int:
    """A header's numeric suffix, -113 if outside ``allowed``."""
    value = default if value is None else value
    if value not in allowed:
        raise ScpiError(-113, f"suffix {value} not in {allowed.start}..{allowed.stop - 1}")
    return value


def integer_word(args: bytes, low: int, high: int) -> int:
    """An integer register value within [low, high] (``*ESE``, ``*SRE``): a decimal number
    rounded to the nearest integer, else -222 or -224."""
    return int(round(number(args, low - 0.5, high + 0.499)))


# --------------------------------------------------------------------------- instruments
class ScpiInstrument:
    """A simulated SCPI instrument: the command set, the error queue and the IEEE 488.2
    mandatory common commands with the status model behind them.

    Common commands (IEEE 488.2 10): ``*IDN?`` (:attr:`identity`), ``*RST`` (:meth:`reset`),
    ``*CLS`` (error queue and event status register cleared, enables kept), ``*ESE``,
    ``*ESE?``, ``*ESR?`` (read and cleared), ``*SRE``, ``*SRE?``, ``*STB?`` (error queue not
    empty in bit 2, message available in bit 4, event summary in bit 5, master summary in
    bit 6), ``*OPC`` (sets the operation complete bit: commands here finish before the next
    one is read, so at once), ``*OPC?`` (``1``), ``*WAI`` and ``*TST?`` (``0``: self-test
    passed); also ``*OPT?`` (``0``: no options). SCPI's own: ``SYST:ERR[:NEXT]?``,
    ``SYST:ERR:COUN?``, ``SYST:VERS?``.

    Subclasses set :attr:`identity`, add their commands to :attr:`commands` and override
    :meth:`reset`; :meth:`handle` runs one message under the bench's lock.
    """

    identity = "fsi-lab,SIM,0,0"

    def __init__(self, bench) -> None:
        self.bench = bench
        self.connection: object = None  # of the message being run
        self.status = Status()
        self.errors = ErrorQueue(self.status)
        c = self.commands = CommandSet(self.errors)
        c.add("*IDN?", lambda a, s: self.identity)
        c.add("*RST", lambda a, s: self.reset())
        c.add("*CLS", self._cls)
        c.add("*ESE", self._ese)
        c.add("*ESE?", lambda a, s: str(self.status.ese))
        c.add("*ESR?", lambda a, s: str(self.status.read_esr()))
        c.add("*SRE", self._sre)
        c.add("*SRE?", lambda a, s: str(self.status.sre))
        c.add("*STB?", lambda a, s: str(self.status.stb(
            len(self.errors) > 0, self.commands.replies_pending > 0)))
        c.add("*OPC", self._opc)
        c.add("*OPC?", lambda a, s: "1")
        c.add("*WAI", lambda a, s: None)
        c.add("*TST?", lambda a, s: "0")
        c.add("*OPT?", lambda a, s: "0")
        c.add("SYSTem:ERRor[:NEXT]?", lambda a, s: self.errors.pop())
        c.add("SYSTem:ERRor:COUNt?", lambda a, s: str(len(self.errors)))
        c.add("SYSTem:VERSion?", lambda a, s: "1999.0")

    def reset(self) -> None:
        """``*RST``: the instrument's reset settings (the status registers are kept)."""

    def handle(self, message: bytes, connection: object = None) -> bytes | None:
        """Run one program message received on ``connection``; the reply bytes (with
        newline) or None."""
        with self.bench.lock:
            self.bench.catch_up()
            self.connection = connection
            self.received(connection)
            return self.commands.run(message)

    def received(self, connection: object) -> None:
        """Called for every program message, before it runs, with its connection."""

    def tick(self) -> None:
        """Called a few times a second by the bench, under its lock (timers)."""

    def _cls(self, args, suffixes):
        self.errors.clear()
        self.status.esr = 0

    def _ese(self, args, suffixes):
        self.status.ese = integer_word(args, 0, 255)

    def _sre(self, args, suffixes):
        self.status.sre = integer_word(args, 0, 255) & ~STB_MSS

    def _opc(self, args, suffixes):
        self.status.esr |= ESR_OPC
