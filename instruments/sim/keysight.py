"""Simulated Keysight 33521B-class arbitrary waveform generator (one channel, SCPI).

What it models: the arbitrary waveform memory (``DATA:ARB`` with a float32 definite-length
block in the byte order of ``FORM:BORD``, points in -1..1, 8 to 1 000 000 of them, a 16-bit DAC),
``FUNC ARB``/``SIN``, the arb sample rate and filter, amplitude in Vpp and offset with the
instrument's limits, the output load setting (a 50-ohm setting doubles the voltage at the
amplifier's high-impedance input, as on the real instrument), the output relay, triggered
bursts of one cycle started by ``*TRG`` or ``TRIG`` with ``TRIG:SOUR BUS``, the trigger output
(wired to the digitiser's external trigger) and the error queue read by ``SYST:ERR?``.

Simplifications: with ``TRIG:SOUR IMM`` (or bursts off) the waveform repeats back to back from
the moment the output is switched on; between bursts the output rests at the first point.
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import TYPE_CHECKING

import numpy as np

from fsi_lab.instruments.sim import scpi
from fsi_lab.instruments.sim.scpi import CommandSet, ErrorQueue, ScpiError
from fsi_lab.instruments.sim.specs import SOURCE_CHANNELS as CHANNELS

if TYPE_CHECKING:  # pragma: no cover
    from fsi_lab.instruments.sim.bench import SimBench

IDENTITY = "fsi-lab,33521B-SIM,SIM33500,1.0 (simulated)"
MAX_POINTS = 1_000_000
MIN_POINTS = 8
DAC_LEVELS = 32767.0
MAX_SAMPLE_RATE = 160e6


class SourceState:
    """Settings and output of the generator's channel 1."""

    def __init__(self) -> None:
        self.arbs: dict[str, np.ndarray] = {}
        self.reset()

    def reset(self) -> None:
        """``*RST`` values."""
        self.function = "SIN"
        self.frequency = 1000.0
        self.arb_name = ""
        self.arb_rate = 40000.0
        self.arb_filter = "NORM"
        self.amplitude_vpp = 0.1
        self.offset_v = 0.0
        self.load_ohm = 50.0
        self.output_on = False
        self.burst = False
        self.trigger_source = "IMM"
        self.trigger_out = False
        self.play_start: int | None = None  # world sample where the play started
        self._analog_cache: tuple | None = None

    # ------------------------------------------------------------------ output
    @property
    def load_factor(self) -> float:
        """Voltage at a high-impedance input per volt set: the generator's 50-ohm source
        drives an open circuit to (50 + R) / R times the value set for a load of R ohms."""
        return 1.0 if math.isinf(self.load_ohm) else (50.0 + self.load_ohm) / self.load_ohm

    def volts(self, start: int, n: int, world_rate: float) -> np.ndarray:
        """Voltage at the output terminals for world samples ``start .. start + n``, V."""
        if not self.output_on or n <= 0:
            return np.zeros(max(n, 0))
        half = 0.5 * self.amplitude_vpp
        idx = np.arange(start, start + n)
        origin = 0 if self.play_start is None else self.play_start
        if self.function == "SIN":
            shape = np.sin(2 * np.pi * self.frequency * (idx - origin) / world_rate)
        else:
            analog = self._analog(world_rate)
            if analog.size == 0:
                shape = np.zeros(n)
            elif self.burst and self.trigger_source != "IMM":
                shape = np.full(n, analog[0])
                if self.play_start is not None:
                    rel = idx - self.play_start
                    inside = (rel >= 0) & (rel < analog.size)
                    shape[inside] = analog[rel[inside]]
            else:
                shape = analog[(idx - origin) % analog.size]
        return self.load_factor * (self.offset_v + half * shape)

    def _analog(self, world_rate: float) -> np.ndarray:
        """The selected arb as the output stage plays it, resampled to ``world_rate``."""
        points = self.arbs.get(self.arb_name)
        if points is None:
            return np.zeros(0)
        key = (id(points), world_rate, self.arb_rate, self.arb_filter)
        if self._analog_cache is not None and self._analog_cache[0] == key:
            return self._analog_cache[1]
        analog = resample_arb(points.astype(float), self.arb_rate, world_rate, self.arb_filter)
        self._analog_cache = (key, analog)
        return analog


def resample_arb(points: np.ndarray, arb_rate: float, world_rate: float,
                 arb_filter: str) -> np.ndarray:
    """Arb ``points`` played at ``arb_rate`` (Sa/s) seen at ``world_rate`` (Hz).

    ``OFF`` holds each point (zero-order hold); ``NORM`` and ``STEP`` reconstruct a
    band-limited signal (polyphase FIR), which also removes content the world rate cannot hold.
    """
    if arb_rate == world_rate:
        return points
    n_out = int(round(points.size * world_rate / arb_rate))
    if arb_filter == "OFF":
        return points[np.minimum((np.arange(n_out) * arb_rate / world_rate).astype(int),
                                 points.size - 1)]
    ratio = Fraction(world_rate / arb_rate).limit_denominator(2000)
    if float(ratio) and abs(float(ratio) - world_rate / arb_rate) < 1e-9 * world_rate / arb_rate:
        # scipy.signal loads when a record plays an arb, not when the bench is only made safe
        from scipy.signal import resample_poly

        out = resample_poly(points, ratio.numerator, ratio.denominator)
        return out[:n_out]
    t = np.arange(n_out) / world_rate
    return np.interp(t, np.arange(points.size) / arb_rate, points)


class KeysightSim:
    """The generator's SCPI command set, acting on the bench."""

    def __init__(self, bench: "SimBench") -> None:
        self.bench = bench
        self.state = SourceState()
        self.errors = ErrorQueue()
        self.little_endian = False
        c = self.commands = CommandSet(self.errors)
        c.add("*IDN?", lambda a, s: IDENTITY)
        c.add("*RST", self._rst)
        c.add("*CLS", lambda a, s: self.errors.clear())
        c.add("*OPC?", lambda a, s: "1")
        c.add("*TRG", self._trigger)
        c.add("TRIGger#", self._trigger)
        c.add("SYSTem:ERRor[:NEXT]?", lambda a, s: self.errors.pop())
        c.add("FORMat:BORDer", self._border)
        c.add("FORMat:BORDer?", lambda a, s: "SWAP" if self.little_endian else "NORM")
        c.add("[SOURce#:]DATA:VOLatile:CLEar", self._clear)
        c.add("[SOURce#:]DATA:ARBitrary", self._data_arb)
        c.add("[SOURce#:]FUNCtion", self._function)
        c.add("[SOURce#:]FUNCtion?", self._ch(lambda: "ARB" if self.state.function == "ARB"
                                              else "SIN"))
        c.add("[SOURce#:]FUNCtion:ARBitrary", self._select_arb)
        c.add("[SOURce#:]FUNCtion:ARBitrary?", self._ch(lambda: f'"{self.state.arb_name}"'))
        c.add("[SOURce#:]FUNCtion:ARBitrary:SRATe", self._srate)
        c.add("[SOURce#:]FUNCtion:ARBitrary:SRATe?", self._ch(lambda: f"{self.state.arb_rate:.9E}"))
        c.add("[SOURce#:]FUNCtion:ARBitrary:FILTer", self._filter)
        c.add("[SOURce#:]FUNCtion:ARBitrary:FILTer?", self._ch(lambda: self.state.arb_filter))
        c.add("[SOURce#:]FREQuency", self._frequency)
        c.add("[SOURce#:]VOLTage:UNIT", self._unit)
        c.add("[SOURce#:]VOLTage:UNIT?", self._ch(lambda: "VPP"))
        c.add("[SOURce#:]VOLTage[:AMPLitude]", self._amplitude)
        c.add("[SOURce#:]VOLTage[:AMPLitude]?", self._ch(lambda: f"{self.state.amplitude_vpp:.9E}"))
        c.add("[SOURce#:]VOLTage:OFFSet", self._offset)
        c.add("[SOURce#:]VOLTage:OFFSet?", self._ch(lambda: f"{self.state.offset_v:.9E}"))
        c.add("[SOURce#:]BURSt:MODE", self._burst_mode)
        c.add("[SOURce#:]BURSt:NCYCles", self._ncycles)
        c.add("[SOURce#:]BURSt:STATe", self._burst_state)
        c.add("[SOURce#:]BURSt:STATe?", self._ch(lambda: "1" if self.state.burst else "0"))
        c.add("TRIGger#:SOURce", self._trigger_source)
        c.add("TRIGger#:SOURce?", self._ch(lambda: self.state.trigger_source))
        c.add("OUTPut#", self._output)
        c.add("OUTPut#?", self._ch(lambda: "1" if self.state.output_on else "0"))
        c.add("OUTPut#:LOAD", self._load)
        c.add("OUTPut#:LOAD?", self._ch(lambda: "9.9E+37" if math.isinf(self.state.load_ohm)
                                        else f"{self.state.load_ohm:.9E}"))
        c.add("OUTPut:TRIGger", self._trigger_out)
        c.add("OUTPut:TRIGger?", lambda a, s: "1" if self.state.trigger_out else "0")
        c.add("ABORt", self._abort)

    def handle(self, message: bytes) -> bytes | None:
        """Run one program message; the reply bytes (with newline) or None."""
        with self.bench.lock:
            self.bench.catch_up()
            return self.commands.run(message)

    # ------------------------------------------------------------------ helpers
    @staticmethod
    def _channel(suffixes: list) -> None:
        scpi.suffix(suffixes[0] if suffixes else None, range(1, CHANNELS + 1))

    def _ch(self, answer):
        def handler(args, suffixes):
            self._channel(suffixes)
            return answer()
        return handler

    def _limits(self, amplitude: float, offset: float) -> None:
        peak = 10.0 if math.isinf(self.state.load_ohm) else 5.0
        if amplitude < (0.002 if math.isinf(self.state.load_ohm) else 0.001) or \
                amplitude / 2 + abs(offset) > peak:
            raise ScpiError(-222, f"amplitude {amplitude:g} Vpp with offset {offset:g} V "
                                  f"exceeds +-{peak:g} V into the set load")

    # ------------------------------------------------------------------ commands
    def _rst(self, args, suffixes):
        self.state.reset()
        self.little_endian = False

    def _border(self, args, suffixes):
        self.little_endian = scpi.choice(args, {"NORM": "NORM", "NORMAL": "NORM",
                                                "SWAP": "SWAP", "SWAPPED": "SWAP"}) == "SWAP"

    def _clear(self, args, suffixes):
        self._channel(suffixes)
        if self.state.output_on and self.state.function == "ARB":
            raise ScpiError(-221, "cannot clear the arb memory while an arb is playing")
        self.state.arbs.clear()
        self.state.arb_name = ""

    def _data_arb(self, args, suffixes):
        self._channel(suffixes)
        name_bytes, comma, block = args.partition(b",")
        name = scpi.text(name_bytes).upper()
        if not comma or not block.strip():
            raise ScpiError(-109, "expected DATA:ARB <name>,<block>")
        if not name or not name[0].isalpha() or len(name) > 12:
            raise ScpiError(-224, f"arb name {name!r}: 1 to 12 characters starting with a letter")
        payload = scpi.parse_ieee_block(block.strip())
        if len(payload) % 4:
            raise ScpiError(-160, f"{len(payload)} bytes is not a whole number of float32 points")
        points = np.frombuffer(payload, dtype="<f4" if self.little_endian else ">f4")
        if points.size > MAX_POINTS:
            raise ScpiError(-223, f"{points.size} points; at most {MAX_POINTS}")
        if points.size < MIN_POINTS:
            raise ScpiError(-222, f"{points.size} points; at least {MIN_POINTS}")
        if not np.all(np.isfinite(points)) or np.max(np.abs(points)) > 1.0:
            raise ScpiError(-222, "arb points must lie between -1 and +1")
        self.state.arbs[name] = np.round(points.astype(float) * DAC_LEVELS) / DAC_LEVELS

    def _function(self, args, suffixes):
        self._channel(suffixes)
        self.state.function = scpi.choice(args, {"ARB": "ARB", "ARBITRARY": "ARB",
                                                  "SIN": "SIN", "SINUSOID": "SIN"})

    def _select_arb(self, args, suffixes):
        self._channel(suffixes)
        name = scpi.text(args).upper()
        if name not in self.state.arbs:
            raise ScpiError(-224, f"no arb named {name!r} in volatile memory")
        self.state.arb_name = name

    def _srate(self, args, suffixes):
        self._channel(suffixes)
        self.state.arb_rate = scpi.number(args, 1e-6, MAX_SAMPLE_RATE)

    def _filter(self, args, suffixes):
        self._channel(suffixes)
        self.state.arb_filter = scpi.choice(args, {"NORM": "NORM", "NORMAL": "NORM",
                                                   "STEP": "STEP", "OFF": "OFF"})

    def _frequency(self, args, suffixes):
        self._channel(suffixes)
        self.state.frequency = scpi.number(args, 1e-6, 30e6)

    def _unit(self, args, suffixes):
        self._channel(suffixes)
        scpi.choice(args, {"VPP": "VPP"})

    def _amplitude(self, args, suffixes):
        self._channel(suffixes)
        value = scpi.number(args, 0.0, 20.0)
        self._limits(value, self.state.offset_v)
        self.state.amplitude_vpp = value

    def _offset(self, args, suffixes):
        self._channel(suffixes)
        value = scpi.number(args, -10.0, 10.0)
        self._limits(self.state.amplitude_vpp, value)
        self.state.offset_v = value

    def _burst_mode(self, args, suffixes):
        self._channel(suffixes)
        scpi.choice(args, {"TRIG": "TRIG", "TRIGGERED": "TRIG"})

    def _ncycles(self, args, suffixes):
        self._channel(suffixes)
        if scpi.number(args, 1, 1e8) != 1:
            raise ScpiError(-222, "this simulation plays bursts of one cycle only")

    def _burst_state(self, args, suffixes):
        self._channel(suffixes)
        self.state.burst = scpi.boolean(args)

    def _trigger_source(self, args, suffixes):
        self._channel(suffixes)
        self.state.trigger_source = scpi.choice(
            args, {"IMM": "IMM", "IMMEDIATE": "IMM", "BUS": "BUS", "EXT": "EXT",
                   "EXTERNAL": "EXT"})

    def _output(self, args, suffixes):
        self._channel(suffixes)
        on = scpi.boolean(args)
        if on and not self.state.output_on:
            self.state.output_on = True
            if not (self.state.burst and self.state.trigger_source != "IMM"):
                self.state.play_start = self.bench.world_now()
        elif not on:
            self.state.output_on = False

    def _load(self, args, suffixes):
        self._channel(suffixes)
        load = scpi.number(args, 1.0, 10e3, words={"INF": math.inf, "INFINITY": math.inf,
                                                   "9.9E+37": math.inf})
        self.state.load_ohm = load

    def _trigger_out(self, args, suffixes):
        self.state.trigger_out = scpi.boolean(args)

    def _trigger(self, args, suffixes):
        state = self.state
        if not (state.burst and state.trigger_source == "BUS"):
            raise ScpiError(-221, "a bus trigger needs BURS:STAT ON and TRIG:SOUR BUS")
        if state.trigger_out:
            self.bench.external_trigger()
        state.play_start = self.bench.world_now()

    def _abort(self, args, suffixes):
        self.state.play_start = None
