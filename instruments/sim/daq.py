"""Simulated 4-input dynamic signal analyser (24-bit, up to 204.8 kS/s) with SCPI.

Commands (short forms; long forms and any case are accepted):

==========================  =================================================================
``*IDN?`` ``*RST`` ``*CLS``  identity, reset, clear the status (and the other IEEE 488.2
                             common commands, see :class:`~.scpi.ScpiInstrument`)
``SYST:ERR?``                next error, ``+0,"No error"`` when empty
``FORM:BORD NORM|SWAP``      byte order of the data blocks (big- or little-endian)
``ACQ:SRAT <Hz>``            sample rate, 1 to 204800 (``ACQ:SRAT?`` reads it back)
``ACQ:POIN <n>``             samples per input in the record
``INP<n>:STAT ON|OFF``       enable input n (1 to 4)
``INP<n>:RANG <V>``          input range: the smallest of 0.316, 1, 3.16, 10 V holding the value
``INP<n>:IEPE ON|OFF``       constant-current supply for an IEPE sensor (AC coupled)
``INP<n>:SCAL?``             volts per code of input n
``TRIG:SOUR IMM|EXT``        start at ``INIT`` or at the external trigger (the source's
                             trigger output)
``INIT``                     arm; ``ABOR`` stops
``ACQ:STAT?``                ``<state>,<samples available>,<overload bits>``; state is IDLE,
                             WTRG (waiting for the trigger), RUN, DONE or OVER (buffer overrun);
                             bit n-1 of the overload bits is set once input n exceeded its range
``FETC? <n>``                up to n samples per enabled input, as a definite-length block of
                             int32 codes, interleaved sample by sample in input order
==========================  =================================================================

Settings are refused (-221) while a record runs. In real time, samples become available at the
sample clock and the buffer holds :data:`BUFFER_SAMPLES` per input before it overruns; a fast
bench makes them available as soon as they are fetched.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from fsi_lab.instruments.sim import scpi
from fsi_lab.instruments.sim.scpi import ScpiError, ScpiInstrument
from fsi_lab.instruments.sim.specs import DIGITISER_RANGES, volts_per_code

if TYPE_CHECKING:  # pragma: no cover
    from fsi_lab.instruments.sim.bench import SimBench

IDENTITY = "fsi-lab,DSA4-SIM,SIMDSA4,1.0 (simulated)"
INPUTS = range(1, 5)
MAX_RATE = 204800.0
BUFFER_SAMPLES = 1 << 22
MAX_FETCH = 1 << 20


class DigitiserState:
    """Configuration and record of the digitiser."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        """``*RST`` values."""
        self.rate = 51200.0
        self.points = 1024
        self.enabled = {n: False for n in INPUTS}
        self.ranges = {n: 10.0 for n in INPUTS}
        self.iepe = {n: False for n in INPUTS}
        self.trigger = "IMM"
        self.little_endian = False
        self.mode = "IDLE"
        self.buffer: list[np.ndarray] = []
        self.buffered = 0
        self.fetched = 0

    @property
    def inputs(self) -> list[int]:
        """Enabled inputs in ascending order (the column order of the data blocks)."""
        return [n for n in INPUTS if self.enabled[n]]


class DigitiserSim(ScpiInstrument):
    """The digitiser's command set (with the IEEE 488.2 common commands), acting on the
    bench."""

    identity = IDENTITY

    def __init__(self, bench: "SimBench") -> None:
        super().__init__(bench)
        self.state = DigitiserState()
        c = self.commands
        c.add("FORMat:BORDer", self._border)
        c.add("FORMat:BORDer?", lambda a, s: "SWAP" if self.state.little_endian else "NORM")
        c.add("ACQuire:SRATe", self._rate)
        c.add("ACQuire:SRATe?", lambda a, s: f"{self.state.rate:.6f}")
        c.add("ACQuire:POINts", self._points)
        c.add("ACQuire:POINts?", lambda a, s: str(self.state.points))
        c.add("ACQuire:STATe?", self._status)
        c.add("INPut#:STATe", self._input(lambda n, a: self.state.enabled.__setitem__(
            n, scpi.boolean(a))))
        c.add("INPut#:STATe?", self._query(lambda n: "1" if self.state.enabled[n] else "0"))
        c.add("INPut#:RANGe", self._input(self._range))
        c.add("INPut#:RANGe?", self._query(lambda n: f"{self.state.ranges[n]:g}"))
        c.add("INPut#:IEPE", self._input(lambda n, a: self.state.iepe.__setitem__(
            n, scpi.boolean(a))))
        c.add("INPut#:IEPE?", self._query(lambda n: "1" if self.state.iepe[n] else "0"))
        c.add("INPut#:SCALe?", self._query(
            lambda n: f"{volts_per_code(self.state.ranges[n]):.9E}"))
        c.add("TRIGger:SOURce", self._trigger)
        c.add("TRIGger:SOURce?", lambda a, s: self.state.trigger)
        c.add("INITiate[:IMMediate]", self._init)
        c.add("ABORt", self._abort)
        c.add("FETCh?", self._fetch)

    # ------------------------------------------------------------------ record
    def store(self, codes: np.ndarray) -> None:
        """Keep produced codes until fetched; overrun when the buffer is full."""
        state = self.state
        if state.buffered + codes.shape[0] > BUFFER_SAMPLES:
            state.mode = "OVER"
            self.bench.end_record()
            self.errors.push(-350, "acquisition buffer overrun: samples were not fetched in time")
            return
        state.buffer.append(codes)
        state.buffered += codes.shape[0]

    def start(self) -> None:
        """The record starts now (t = 0): at INIT, or at the external trigger."""
        state = self.state
        state.mode = "RUN"
        self.bench.start_record(state.rate, state.points, state.inputs,
                                [state.ranges[n] for n in state.inputs],
                                [state.iepe[n] for n in state.inputs])

    def record_complete(self) -> None:
        """Every sample of the record has been simulated."""
        if self.state.mode == "RUN":
            self.state.mode = "DONE"

    def _pop(self, n: int) -> np.ndarray:
        state = self.state
        taken, count = [], 0
        while state.buffer and count < n:
            block = state.buffer[0]
            need = n - count
            if block.shape[0] <= need:
                taken.append(state.buffer.pop(0))
                count += block.shape[0]
            else:
                taken.append(block[:need])
                state.buffer[0] = block[need:]
                count += need
        state.buffered -= count
        width = len(state.inputs)
        return np.concatenate(taken) if taken else np.zeros((0, width), dtype=np.int32)

    # ------------------------------------------------------------------ commands
    def _idle(self) -> None:
        if self.state.mode in ("RUN", "WTRG"):
            raise ScpiError(-221, "the acquisition is running; send ABOR first")

    def _input(self, setter):
        def handler(args, suffixes):
            number = scpi.suffix(suffixes[0], INPUTS)
            self._idle()
            setter(number, args)
        return handler

    def _query(self, answer):
        def handler(args, suffixes):
            return answer(scpi.suffix(suffixes[0], INPUTS))
        return handler

    def reset(self) -> None:
        """``*RST``: the record ends and every setting takes its reset value."""
        self.bench.end_record()
        self.state.reset()

    def _border(self, args, suffixes):
        self.state.little_endian = scpi.choice(
            args, {"NORM": "NORM", "NORMAL": "NORM", "SWAP": "SWAP", "SWAPPED": "SWAP"}) == "SWAP"

    def _rate(self, args, suffixes):
        self._idle()
        self.state.rate = scpi.number(args, 1.0, MAX_RATE)

    def _points(self, args, suffixes):
        self._idle()
        self.state.points = int(scpi.number(args, 1, 2 ** 31 - 1))

    def _range(self, number, args):
        value = scpi.number(args, 0.0, DIGITISER_RANGES[-1])
        self.state.ranges[number] = next(r for r in DIGITISER_RANGES if r >= value)

    def _trigger(self, args, suffixes):
        self._idle()
        self.state.trigger = scpi.choice(args, {"IMM": "IMM", "IMMEDIATE": "IMM", "EXT": "EXT",
                                                "EXTERNAL": "EXT"})

    def _init(self, args, suffixes):
        self._idle()
        state = self.state
        if not state.inputs:
            raise ScpiError(-221, "no input is enabled (INP<n>:STAT ON)")
        self.bench.end_record()
        state.buffer.clear()
        state.buffered = 0
        state.fetched = 0
        if state.trigger == "EXT":
            state.mode = "WTRG"
        else:
            self.start()

    def _abort(self, args, suffixes):
        self.bench.end_record()
        self.state.mode = "IDLE"

    def _status(self, args, suffixes):
        state = self.state
        record = self.bench.record
        available = state.buffered
        if self.bench.options.fast and state.mode == "RUN" and record is not None:
            available += state.points - record.produced
        overloads = record.overloads if record is not None else self.bench.last_overloads
        bits = sum(1 << (n - 1) for n in overloads)
        return f"{state.mode},{available},{bits}"

    def _fetch(self, args, suffixes):
        state = self.state
        n = int(scpi.number(args, 1, 2 ** 31 - 1))
        n = min(n, MAX_FETCH)
        record = self.bench.record
        if self.bench.options.fast and record is not None and state.mode == "RUN":
            missing = min(n - state.buffered, state.points - record.produced)
            if missing > 0:
                self.bench.produce(missing)
        codes = self._pop(min(n, state.buffered))
        state.fetched += codes.shape[0]
        dtype = "<i4" if state.little_endian else ">i4"
        return scpi.ieee_block(codes.astype(dtype, copy=False).tobytes())
