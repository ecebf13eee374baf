"""SCPI on the instrument side: message framing, header matching, error queue, binary blocks.

The simulated instruments parse what a real instrument parses: newline-terminated program
messages (several commands may be joined by ``;``), headers in short or long form in any case
(``SOUR1:FUNC:ARB:SRAT`` = ``source:function:arbitrary:srate``), optional nodes, numeric
suffixes, and IEEE 488.2 definite-length binary blocks (``#<n><length><bytes>``) whose bytes may
contain newlines.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Callable

#: Standard SCPI error numbers used by the simulated instruments.
ERRORS = {
    -100: "Command error",
    -102: "Syntax error",
    -109: "Missing parameter",
    -113: "Undefined header",
    -160: "Block data error",
    -221: "Settings conflict",
    -222: "Data out of range",
    -223: "Too much data",
    -224: "Illegal parameter value",
    -350: "Queue overflow",
}


class ScpiError(Exception):
    """Raised by a command handler: the instrument queues ``code`` with ``detail``."""

    def __init__(self, code: int, detail: str = "") -> None:
        super().__init__(f"{code} {ERRORS.get(code, 'Error')}; {detail}")
        self.code = code
        self.detail = detail


class ErrorQueue:
    """The instrument's error queue, read one entry per ``SYST:ERR?``."""

    LIMIT = 20

    def __init__(self) -> None:
        self._entries: list[tuple[int, str]] = []

    def push(self, code: int, detail: str = "") -> None:
        """Queue error ``code`` (see :data:`ERRORS`) with a detail; -350 once full."""
        if len(self._entries) >= self.LIMIT:
            self._entries[-1] = (-350, ERRORS[-350])
            return
        text = ERRORS.get(code, "Error") + (f"; {detail}" if detail else "")
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


# --------------------------------------------------------------------------- framing
def take_messages(buffer: bytearray) -> list[bytes]:
    """Remove every complete program message from ``buffer`` and return them.

    A message ends at a newline that is not inside a definite-length binary block; the
    newline (and a carriage return before it) is dropped. An incomplete message stays in the
    buffer.
    """
    messages = []
    start = 0
    i = 0
    n = len(buffer)
    while i < n:
        byte = buffer[i]
        if byte == 0x23 and i + 1 < n and 0x31 <= buffer[i + 1] <= 0x39:  # '#1'..'#9'
            digits = buffer[i + 1] - 0x30
            if i + 2 + digits > n:
                break  # header incomplete
            length_text = bytes(buffer[i + 2:i + 2 + digits])
            if not length_text.isdigit():
                i += 1
                continue
            end = i + 2 + digits + int(length_text)
            if end > n:
                break  # payload incomplete
            i = end
            continue
        if byte == 0x0A:
            message = bytes(buffer[start:i])
            if message.endswith(b"\r"):
                message = message[:-1]
            messages.append(message)
            start = i + 1
        i += 1
    del buffer[:start]
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
    node, ``#`` a numeric suffix, a trailing ``?`` a query.
    """

    def __init__(self, errors: ErrorQueue) -> None:
        self.errors = errors
        self._table: list[tuple[list[_Node], bool, Handler]] = []

    def add(self, pattern: str, handler: Handler) -> None:
        """Run ``handler`` for headers matching ``pattern`` (queries and settings apart)."""
        nodes, query = _compile(pattern)
        self._table.append((nodes, query, handler))

    def run(self, message: bytes) -> bytes | None:
        """Execute one program message; the joined replies of its queries, or None."""
        replies: list[bytes] = []
        for command in _split_commands(message):
            reply = self._run_one(command)
            if reply is not None:
                replies.append(reply)
        if not replies:
            return None
        return b";".join(replies) + b"\n"

    def _run_one(self, command: bytes) -> bytes | None:
        command = command.strip()
        if not command:
            return None
        header_bytes, _, args = command.partition(b" ")
        try:
            header = header_bytes.decode("ascii").upper()
        except UnicodeDecodeError:
            self.errors.push(-102, "header is not ASCII")
            return None
        query = header.endswith("?")
        tokens = [t for t in header.rstrip("?").lstrip(":").split(":")]
        for nodes, is_query, handler in self._table:
            if is_query != query:
                continue
            suffixes = _match(nodes, tokens)
            if suffixes is None:
                continue
            try:
                reply = handler(args.strip(), suffixes)
            except ScpiError as exc:
                self.errors.push(exc.code, exc.detail)
                return None
            if reply is None:
                return None
            return reply if isinstance(reply, bytes) else reply.encode("ascii")
        self.errors.push(-113, header)
        return None


def _split_commands(message: bytes) -> list[bytes]:
    """Split at ``;`` outside binary blocks and quoted strings."""
    parts, start, i, n = [], 0, 0, len(message)
    quote = None
    while i < n:
        c = message[i]
        if quote is not None:
            if c == quote:
                quote = None
        elif c in (0x22, 0x27):
            quote = c
        elif c == 0x23 and i + 1 < n and 0x31 <= message[i + 1] <= 0x39:
            digits = message[i + 1] - 0x30
            length = message[i + 2:i + 2 + digits]
            if length.isdigit():
                i += 2 + digits + int(length)
                continue
        elif c == 0x3B:
            parts.append(message[start:i])
            start = i + 1
        i += 1
    parts.append(message[start:])
    return parts


# --------------------------------------------------------------------------- arguments
def text(args: bytes) -> str:
    """Arguments as text (upper case stripped of quotes), -102 if not ASCII."""
    try:
        return args.decode("ascii").strip().strip('"').strip("'")
    except UnicodeDecodeError:
        raise ScpiError(-102, "argument is not ASCII") from None


def number(args: bytes, low: float | None = None, high: float | None = None,
           words: dict[str, float] | None = None) -> float:
    """A numeric argument within [low, high] (MIN/MAX/INF words as given), else -222/-109."""
    value_text = text(args).upper()
    if not value_text:
        raise ScpiError(-109, "a number is expected")
    if words and value_text in words:
        return words[value_text]
    try:
        value = float(value_text)
    except ValueError:
        raise ScpiError(-224, f"{value_text!r} is not a number") from None
    if value != value or (low is not None and value < low) or (high is not None and value > high):
        lo = "-inf" if low is None else f"{low:g}"
        hi = "inf" if high is None else f"{high:g}"
        bounds = f"{lo} to {hi}"
        raise ScpiError(-222, f"{value_text} outside {bounds}")
    return value


def boolean(args: bytes) -> bool:
    """ON/OFF/1/0."""
    word = text(args).upper()
    if word in ("ON", "1"):
        return True
    if word in ("OFF", "0"):
        return False
    raise ScpiError(-224, f"{word!r}; expected ON, OFF, 1 or 0")


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
