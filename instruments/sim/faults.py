"""Fault injection on the simulated bench, for rehearsing failures.

Link faults act on one instrument's connection from the moment the record has run
``after_s`` seconds (bench data time, so a fast bench fails at the same point of the record as
a real-time one):

``timeout``
    the instrument reads what it is sent and never answers again;
``drop``
    the instrument closes its connections once (a TCP reset, or the serial port vanishing);
``garble``
    the next reply is corrupted on the wire.

Physical faults act in the simulated world at that time:

``interlock``
    the amplifier's output stage develops a DC offset that pushes the shaker armature past its
    stroke, so the over-travel interlock trips (latched, output forced off);
``overload``
    a 1 ms transient of 1.5 times the input range reaches the digitiser's vibrometer input
    (input 3), which flags an overload.
"""

from __future__ import annotations

import math

LINK_FAULTS = ("timeout", "drop", "garble")
PHYSICAL_FAULTS = ("interlock", "overload")
FAULTS = ("none",) + LINK_FAULTS + PHYSICAL_FAULTS
ROLES = ("source", "amplifier", "vibrometer", "acquisition")
#: The instrument a link fault hits unless told otherwise: the one the run talks to all along.
DEFAULT_TARGET = "acquisition"


class FaultPlan:
    """One scheduled fault and its progress.

    Parameters
    ----------
    kind
        One of :data:`FAULTS`.
    after_s
        Record time (s from the start of the digitiser record) at which it happens.
    target
        Role whose link a link fault hits (default :data:`DEFAULT_TARGET`).
    """

    def __init__(self, kind: str = "none", after_s: float = 1.0, target: str | None = None) -> None:
        if kind not in FAULTS:
            raise ValueError(f"fault {kind!r}: expected one of {', '.join(FAULTS)}")
        target = target or DEFAULT_TARGET
        if target not in ROLES:
            raise ValueError(f"fault target {target!r}: expected one of {', '.join(ROLES)}")
        if not (after_s >= 0 and math.isfinite(after_s)):
            raise ValueError(f"fault time {after_s!r}: expected a number of seconds >= 0")
        self.kind = kind
        self.after_s = float(after_s)
        self.target = target
        self.immediate = False
        self.fired = False  # a one-shot fault (drop, garble) has happened

    def inject(self, kind: str, target: str | None = None) -> None:
        """Make ``kind`` happen now (tests; interlock and overload at record time 0)."""
        self.__init__(kind, 0.0, target)
        self.immediate = True

    def _due(self, data_time: float | None) -> bool:
        return self.immediate or (data_time is not None and data_time >= self.after_s)

    def link_action(self, role: str, data_time: float | None) -> str | None:
        """``"timeout"`` or ``"drop"`` if the next message to ``role`` is to meet that fault."""
        if self.kind not in ("timeout", "drop") or role != self.target or not self._due(data_time):
            return None
        if self.kind == "drop":
            if self.fired:
                return None
            self.fired = True
        return self.kind

    def garble_now(self, role: str, data_time: float | None) -> bool:
        """True (once) when the reply being sent by ``role`` is to be garbled."""
        if self.kind != "garble" or role != self.target or self.fired or not self._due(data_time):
            return False
        self.fired = True
        return True

    def physical_time(self, kind: str) -> float | None:
        """Record time of a physical fault of ``kind``, or None."""
        if self.kind != kind:
            return None
        return 0.0 if self.immediate else self.after_s

    def describe(self) -> str:
        """The fault in words, for logs."""
        if self.kind == "none":
            return "none"
        where = f" on the {self.target}" if self.kind in LINK_FAULTS else ""
        when = "now" if self.immediate else f"at {self.after_s:g} s of the record"
        return f"{self.kind}{where} {when}"


def garble(reply: bytes) -> bytes:
    """``reply`` as a line with framing errors: the top bit of every third byte of its first
    48 bytes is flipped; the terminating newline is kept."""
    body, newline = (reply[:-1], reply[-1:]) if reply.endswith(b"\n") else (reply, b"")
    data = bytearray(body)
    for i in range(0, min(len(data), 48), 3):
        data[i] ^= 0x80
    return bytes(data) + newline
