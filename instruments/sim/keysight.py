"""Simulated Keysight 33522B arbitrary waveform generator (two channels, SCPI).

It identifies as ``Keysight Technologies,33522B,SIMULATED01,<firmware> (fsi-lab simulation)``:
a real model, so third-party drivers (PyMeasure's ``Agilent33500``, QCoDeS's
``Keysight33522B``) recognise it, with a serial number that says it is simulated.

What it models, per channel (``SOURce1:``/``SOURce2:``, ``OUTPut1``/``OUTPut2``,
``TRIGger1``/``TRIGger2``):

- the functions ``SIN``, ``SQU``, ``TRI``, ``RAMP``, ``PULS``, ``PRBS``, ``NOIS``, ``DC`` and
  ``ARB`` with frequency, phase, duty cycle, symmetry, pulse period, width and edges;
- the arbitrary waveform memory: ``DATA:ARB <name>,<block>`` (float32 in the byte order of
  ``FORM:BORD``) or ``DATA:ARB <name>,<v>,<v>,...`` (ASCII, -1 to 1), ``DATA:ARB:DAC`` (int16
  block or ASCII, -32767 to 32767), 8 to 1 000 000 points, a 16-bit DAC; a name already in
  memory is refused (-221) until ``DATA:VOL:CLE``;
- amplitude in ``VPP``, ``VRMS`` or ``DBM`` (``VOLT:UNIT``), offset, ``VOLT:HIGH``/``LOW``, with
  the instrument's limits (+-5 V into 50 ohm, +-10 V into a high impedance); the output load
  setting (a 50-ohm setting doubles the voltage at the amplifier's high-impedance input, as on
  the real instrument); output polarity; the output relay;
- bursts: triggered (``N`` cycles, or ``INF``) or gated, burst phase and internal period; the
  trigger source (``IMM``, ``EXT``, ``TIM``, ``BUS``), slope, count, delay and timer;
- the trigger output (``OUTP:TRIG``, ``OUTP:TRIG:SOUR CH1|CH2``, ``OUTP:TRIG:SLOP``), wired to
  the digitiser's external trigger: it fires when the channel it follows starts a burst;
- ``OUTP:SYNC`` and ``OUTP:SYNC:SOUR``; ``*TRG`` (channels whose trigger source is ``BUS``),
  ``TRIG<n>`` (channel n, whatever its source); queries with ``MIN``/``MAX``/``DEF``; the
  IEEE 488.2 common commands and the error queue (:class:`~.scpi.ScpiInstrument`).

One channel is wired to the amplifier's input and the digitiser's input 1 (``wired_channel``,
channel 1 unless the bench is told otherwise). Between triggered bursts the output rests at the
offset for the built-in functions and at the arb's first point for ``ARB``, as the real
instrument does: a waveform that should rest at 0 V must start at 0 V.

Simplifications: a trigger source other than ``BUS`` starts bursts at once when the output is
switched on (``IMM``, ``TIM`` at the internal period; ``EXT`` waits for a ``TRIG<n>``); gated
bursts play continuously; sweeps and modulation are not modelled.
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import TYPE_CHECKING

import numpy as np

from fsi_lab.instruments.sim import scpi
from fsi_lab.instruments.sim.scpi import ScpiError, ScpiInstrument
from fsi_lab.instruments.sim.specs import SOURCE_CHANNELS as CHANNELS

if TYPE_CHECKING:  # pragma: no cover
    from fsi_lab.instruments.sim.bench import SimBench

MODEL = "33522B"
SERIAL = "SIMULATED01"
IDENTITY = f"Keysight Technologies,{MODEL},{SERIAL},4.03-1.19 (fsi-lab simulation)"
MAX_POINTS = 1_000_000
MIN_POINTS = 8
DAC_LEVELS = 32767.0
MAX_SAMPLE_RATE = 250e6
MAX_FREQUENCY = 30e6
FUNCTIONS = {"SIN": "SIN", "SINUSOID": "SIN", "SQU": "SQU", "SQUARE": "SQU", "TRI": "TRI",
             "TRIANGLE": "TRI", "RAMP": "RAMP", "PULS": "PULS", "PULSE": "PULS", "PRBS": "PRBS",
             "NOIS": "NOIS", "NOISE": "NOIS", "ARB": "ARB", "ARBITRARY": "ARB", "DC": "DC"}
#: Vpp per Vrms of each function's shape.
CREST = {"SIN": 2 * math.sqrt(2), "SQU": 2.0, "TRI": 2 * math.sqrt(3), "RAMP": 2 * math.sqrt(3),
         "PULS": 2.0, "PRBS": 2.0, "NOIS": 2 * math.sqrt(2) * 3, "ARB": 2 * math.sqrt(2),
         "DC": 2.0}
INFINITE = 9.9e37


def _f(value: float) -> str:
    """A number as the 33500 prints it."""
    return f"{value:+.15E}"


class ChannelState:
    """Settings and output of one channel."""

    def __init__(self) -> None:
        self.arbs: dict[str, np.ndarray] = {}
        self.reset()

    def reset(self) -> None:
        """``*RST`` values (the arb memory is kept, as on the instrument)."""
        self.function = "SIN"
        self.frequency = 1000.0
        self.frequency_mode = "CW"
        self.phase_deg = 0.0
        self.square_duty = 50.0
        self.ramp_symmetry = 100.0
        self.pulse_period = 1e-3
        self.pulse_width = 1e-4
        self.pulse_hold = "WIDT"
        self.pulse_edge = 8.4e-9
        self.arb_name = ""
        self.arb_rate = 40000.0
        self.arb_filter = "STEP"
        self.arb_advance = "SRAT"
        self.amplitude_vpp = 0.1
        self.unit = "VPP"
        self.offset_v = 0.0
        self.load_ohm = 50.0
        self.inverted = False
        self.output_on = False
        self.burst = False
        self.burst_mode = "TRIG"
        self.burst_cycles = 1.0
        self.burst_phase = 0.0
        self.burst_period = 0.01
        self.gate_inverted = False
        self.trigger_source = "IMM"
        self.trigger_slope = "POS"
        self.trigger_count = 1.0
        self.trigger_delay = 0.0
        self.trigger_timer = 1e-3
        self.play_start: int | None = None  # world sample where the play started
        self._analog_cache: tuple | None = None

    # ------------------------------------------------------------------ derived
    @property
    def load_factor(self) -> float:
        """Voltage at a high-impedance input per volt set: the generator's 50-ohm source
        drives an open circuit to (50 + R) / R times the value set for a load of R ohms."""
        return 1.0 if math.isinf(self.load_ohm) else (50.0 + self.load_ohm) / self.load_ohm

    @property
    def triggered_burst(self) -> bool:
        """Bursts wait for a trigger (between them the output rests)."""
        return self.burst and self.burst_mode == "TRIG" and self.trigger_source in ("BUS", "EXT")

    def period(self) -> float:
        """Length of one cycle of the selected function, s (one pass of the arb)."""
        if self.function == "ARB":
            points = self.arbs.get(self.arb_name)
            return (points.size if points is not None else 1) / self.arb_rate
        if self.function == "PULS":
            return self.pulse_period
        return 1.0 / self.frequency

    # ------------------------------------------------------------------ output
    def volts(self, start: int, n: int, world_rate: float) -> np.ndarray:
        """Voltage at the output terminals for world samples ``start .. start + n``, V."""
        if not self.output_on or n <= 0:
            return np.zeros(max(n, 0))
        half = 0.5 * self.amplitude_vpp
        idx = np.arange(start, start + n)
        origin = 0 if self.play_start is None else self.play_start
        rel = idx - origin
        if self.triggered_burst:
            cycles = self.burst_cycles if self.burst_cycles < INFINITE else math.inf
            length = cycles * self.period() * world_rate
            inside = (rel >= 0) & (rel < length) if self.play_start is not None \
                else np.zeros(n, bool)
            shape = np.full(n, self._rest_level(world_rate))
            if inside.any():
                shape[inside] = self._shape(rel[inside], world_rate)
        else:
            shape = self._shape(rel, world_rate)
        if self.inverted:
            shape = -shape
        return self.load_factor * (self.offset_v + half * shape)

    def _rest_level(self, world_rate: float) -> float:
        """Where the output sits between triggered bursts (a shape value): the arb's first
        point, 0 for the other functions."""
        if self.function == "ARB":
            analog = self._analog(world_rate)
            return float(analog[0]) if analog.size else 0.0
        return 0.0

    def _shape(self, rel: np.ndarray, world_rate: float) -> np.ndarray:
        """The function's shape (-1..1) at samples ``rel`` from the start of play."""
        if self.function == "ARB":
            analog = self._analog(world_rate)
            if analog.size == 0:
                return np.zeros(rel.size)
            return analog[rel % analog.size]
        if self.function == "DC":
            return np.zeros(rel.size)
        t = rel / world_rate
        cycle = (t / self.period() + self.phase_deg / 360.0) % 1.0
        if self.function == "SIN":
            return np.sin(2 * np.pi * cycle)
        if self.function == "SQU":
            return np.where(cycle < self.square_duty / 100.0, 1.0, -1.0)
        if self.function in ("TRI", "RAMP"):
            sym = 0.5 if self.function == "TRI" else self.ramp_symmetry / 100.0
            rising = np.where(sym > 0, cycle / max(sym, 1e-12), 1.0)
            falling = np.where(sym < 1, (1.0 - cycle) / max(1.0 - sym, 1e-12), 1.0)
            return 2.0 * np.where(cycle < sym, rising, falling) - 1.0
        if self.function == "PULS":
            return np.where(cycle < self.pulse_width / self.pulse_period, 1.0, -1.0)
        # PRBS and noise: reproducible pseudo-random levels at the clock rate
        clock = np.floor(t * self.frequency).astype(np.int64)
        bits = (clock * 2654435761) >> 7 & 1
        if self.function == "PRBS":
            return 2.0 * bits - 1.0
        return np.sin(clock * 12.9898) * 0.3

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


def _ascii_points(data: bytes, low: float, high: float, what: str) -> np.ndarray:
    """Comma-separated numbers within [low, high] (``DATA:ARB`` lists), else -224/-222."""
    try:
        values = np.array(data.split(b","), dtype=float)
    except ValueError:
        raise ScpiError(-224, f"{what}: expected comma-separated numbers") from None
    if not np.all(np.isfinite(values)) or values.size and (
            values.min() < low or values.max() > high):
        raise ScpiError(-222, f"{what} must lie between {low:g} and {high:g}")
    return values


class KeysightSim(ScpiInstrument):
    """The generator's SCPI command set, acting on the bench.

    Parameters
    ----------
    bench
        The bench; ``bench.options.source_channel`` names the channel wired to the amplifier.
    """

    identity = IDENTITY

    def __init__(self, bench: "SimBench") -> None:
        super().__init__(bench)
        self.channels = {n: ChannelState() for n in range(1, CHANNELS + 1)}
        self.wired_channel = int(getattr(bench.options, "source_channel", 1) or 1)
        self._reset_global()
        c = self.commands
        c.add("*TRG", self._bus_trigger)
        c.add("TRIGger#[:IMMediate]", self._trigger_channel)
        c.add("FORMat:BORDer", self._border)
        c.add("FORMat:BORDer?", lambda a, s: "SWAP" if self.little_endian else "NORM")
        c.add("SYSTem:BEEPer[:IMMediate]", lambda a, s: None)
        c.add("DISPlay:TEXT", self._display)
        c.add("DISPlay:TEXT?", lambda a, s: f'"{self.display_text}"')
        c.add("DISPlay:TEXT:CLEar", lambda a, s: setattr(self, "display_text", ""))
        c.add("PHASe:SYNChronize", self._phase_sync)
        c.add("[SOURce#:]PHASe:SYNChronize", self._phase_sync)
        c.add("[SOURce#:]DATA:VOLatile:CLEar", self._clear)
        c.add("[SOURce#:]DATA:VOLatile:CATalog?", self._catalog)
        c.add("[SOURce#:]DATA:ARBitrary", self._data_arb)
        c.add("[SOURce#:]DATA:ARBitrary:DAC", self._data_arb_dac)
        c.add("[SOURce#:]FUNCtion[:SHAPe]", self._setter(
            "function", lambda a, ch: scpi.choice(a, FUNCTIONS)))
        c.add("[SOURce#:]FUNCtion[:SHAPe]?", self._getter(lambda ch: ch.function))
        c.add("[SOURce#:]FUNCtion:ARBitrary", self._select_arb)
        c.add("[SOURce#:]FUNCtion:ARBitrary?", self._getter(lambda ch: f'"{ch.arb_name}"'))
        self._numeric("FUNCtion:ARBitrary:SRATe", "arb_rate", 1e-6, MAX_SAMPLE_RATE, 40000.0,
                      "SA/S")
        c.add("[SOURce#:]FUNCtion:ARBitrary:FILTer", self._setter("arb_filter", lambda a, ch: (
            scpi.choice(a, {"NORM": "NORM", "NORMAL": "NORM", "STEP": "STEP", "OFF": "OFF"}))))
        c.add("[SOURce#:]FUNCtion:ARBitrary:FILTer?", self._getter(lambda ch: ch.arb_filter))
        c.add("[SOURce#:]FUNCtion:ARBitrary:ADVance", self._setter("arb_advance", lambda a, ch: (
            scpi.choice(a, {"TRIG": "TRIG", "TRIGGER": "TRIG", "SRAT": "SRAT",
                            "SRATE": "SRAT"}))))
        c.add("[SOURce#:]FUNCtion:ARBitrary:ADVance?", self._getter(lambda ch: ch.arb_advance))
        c.add("[SOURce#:]FUNCtion:ARBitrary:POINts?", self._getter(lambda ch: str(
            ch.arbs[ch.arb_name].size if ch.arb_name in ch.arbs else 0)))
        self._numeric("FREQuency[:CW]", "frequency", 1e-6, MAX_FREQUENCY, 1000.0, "HZ")
        c.add("[SOURce#:]FREQuency:MODE", self._setter("frequency_mode", lambda a, ch: (
            scpi.choice(a, {"CW": "CW", "FIX": "CW", "FIXED": "CW"}))))
        c.add("[SOURce#:]FREQuency:MODE?", self._getter(lambda ch: ch.frequency_mode))
        self._numeric("PHASe[:ADJust]", "phase_deg", -360.0, 360.0, 0.0, "DEG")
        self._numeric("FUNCtion:SQUare:DCYCle", "square_duty", 0.01, 99.99, 50.0, "PCT")
        self._numeric("FUNCtion:RAMP:SYMMetry", "ramp_symmetry", 0.0, 100.0, 100.0, "PCT")
        self._numeric("FUNCtion:PULSe:PERiod", "pulse_period", 33e-9, 1e6, 1e-3, "S")
        self._numeric("FUNCtion:PULSe:WIDTh", "pulse_width", 16e-9, 1e6, 1e-4, "S")
        c.add("[SOURce#:]FUNCtion:PULSe:DCYCle", self._pulse_duty)
        c.add("[SOURce#:]FUNCtion:PULSe:DCYCle?", self._getter(
            lambda ch: _f(100.0 * ch.pulse_width / ch.pulse_period)))
        c.add("[SOURce#:]FUNCtion:PULSe:HOLD", self._setter("pulse_hold", lambda a, ch: (
            scpi.choice(a, {"WIDT": "WIDT", "WIDTH": "WIDT", "DCYC": "DCYC",
                            "DCYCLE": "DCYC"}))))
        c.add("[SOURce#:]FUNCtion:PULSe:HOLD?", self._getter(lambda ch: ch.pulse_hold))
        self._numeric("FUNCtion:PULSe:TRANsition[:BOTH]", "pulse_edge", 8.4e-9, 1e-6, 8.4e-9,
                      "S")
        self._numeric("FUNCtion:PULSe:TRANsition:LEADing", "pulse_edge", 8.4e-9, 1e-6, 8.4e-9,
                      "S")
        self._numeric("FUNCtion:PULSe:TRANsition:TRAiling", "pulse_edge", 8.4e-9, 1e-6,
                      8.4e-9, "S")
        c.add("[SOURce#:]VOLTage:UNIT", self._unit)
        c.add("[SOURce#:]VOLTage:UNIT?", self._getter(lambda ch: ch.unit))
        c.add("[SOURce#:]VOLTage[:AMPLitude]", self._amplitude)
        c.add("[SOURce#:]VOLTage[:AMPLitude]?", self._amplitude_query)
        c.add("[SOURce#:]VOLTage:OFFSet", self._offset)
        c.add("[SOURce#:]VOLTage:OFFSet?", self._channel_query(
            lambda a, ch: _f(scpi.query_limit(a, -self._peak(ch) + 0.0005,
                                              self._peak(ch) - 0.0005, 0.0, ch.offset_v))))
        c.add("[SOURce#:]VOLTage:HIGH", self._level("high"))
        c.add("[SOURce#:]VOLTage:HIGH?", self._getter(
            lambda ch: _f(ch.offset_v + ch.amplitude_vpp / 2)))
        c.add("[SOURce#:]VOLTage:LOW", self._level("low"))
        c.add("[SOURce#:]VOLTage:LOW?", self._getter(
            lambda ch: _f(ch.offset_v - ch.amplitude_vpp / 2)))
        c.add("[SOURce#:]BURSt:STATe", self._setter("burst", lambda a, ch: scpi.boolean(a)))
        c.add("[SOURce#:]BURSt:STATe?", self._getter(lambda ch: "1" if ch.burst else "0"))
        c.add("[SOURce#:]BURSt:MODE", self._setter("burst_mode", lambda a, ch: scpi.choice(
            a, {"TRIG": "TRIG", "TRIGGERED": "TRIG", "GAT": "GAT", "GATED": "GAT"})))
        c.add("[SOURce#:]BURSt:MODE?", self._getter(lambda ch: ch.burst_mode))
        c.add("[SOURce#:]BURSt:NCYCles", self._setter("burst_cycles", lambda a, ch: float(round(
            scpi.number(a, 1, 1e8, words={**scpi.limits(1, 1e8, 1), "INF": INFINITE,
                                          "INFINITY": INFINITE})))))
        c.add("[SOURce#:]BURSt:NCYCles?", self._channel_query(
            lambda a, ch: _f(scpi.query_limit(a, 1, 1e8, 1, ch.burst_cycles))))
        self._numeric("BURSt:PHASe", "burst_phase", -360.0, 360.0, 0.0, "DEG")
        self._numeric("BURSt:INTernal:PERiod", "burst_period", 1e-6, 8e3, 0.01, "S")
        c.add("[SOURce#:]BURSt:GATE:POLarity", self._setter("gate_inverted", lambda a, ch: (
            scpi.choice(a, {"NORM": "NORM", "NORMAL": "NORM", "INV": "INV",
                            "INVERTED": "INV"}) == "INV")))
        c.add("[SOURce#:]BURSt:GATE:POLarity?", self._getter(
            lambda ch: "INV" if ch.gate_inverted else "NORM"))
        c.add("TRIGger#:SOURce", self._trigger_setter("trigger_source", lambda a: scpi.choice(
            a, {"IMM": "IMM", "IMMEDIATE": "IMM", "BUS": "BUS", "EXT": "EXT", "EXTERNAL": "EXT",
                "TIM": "TIM", "TIMER": "TIM"})))
        c.add("TRIGger#:SOURce?", self._trigger_getter(lambda ch: ch.trigger_source))
        c.add("TRIGger#:SLOPe", self._trigger_setter("trigger_slope", lambda a: scpi.choice(
            a, {"POS": "POS", "POSITIVE": "POS", "NEG": "NEG", "NEGATIVE": "NEG"})))
        c.add("TRIGger#:SLOPe?", self._trigger_getter(lambda ch: ch.trigger_slope))
        c.add("TRIGger#:COUNt", self._trigger_setter("trigger_count", lambda a: float(round(
            scpi.number(a, 1, 1e6, words={**scpi.limits(1, 1e6, 1), "INF": INFINITE,
                                          "INFINITY": INFINITE})))))
        c.add("TRIGger#:COUNt?", self._trigger_getter(lambda ch: _f(ch.trigger_count)))
        c.add("TRIGger#:DELay", self._trigger_setter("trigger_delay", lambda a: scpi.number(
            a, 0.0, 1000.0, words=scpi.limits(0.0, 1000.0, 0.0), unit="S")))
        c.add("TRIGger#:DELay?", self._trigger_getter(lambda ch: _f(ch.trigger_delay)))
        c.add("TRIGger#:TIMer", self._trigger_setter("trigger_timer", lambda a: scpi.number(
            a, 1e-6, 8000.0, words=scpi.limits(1e-6, 8000.0, 1e-3), unit="S")))
        c.add("TRIGger#:TIMer?", self._trigger_getter(lambda ch: _f(ch.trigger_timer)))
        c.add("OUTPut#[:STATe]", self._output)
        c.add("OUTPut#[:STATe]?", self._output_getter(lambda ch: "1" if ch.output_on else "0"))
        c.add("OUTPut#:LOAD", self._load)
        c.add("OUTPut#:LOAD?", self._output_getter(
            lambda ch: _f(INFINITE) if math.isinf(ch.load_ohm) else _f(ch.load_ohm)))
        c.add("OUTPut#:POLarity", self._polarity)
        c.add("OUTPut#:POLarity?", self._output_getter(
            lambda ch: "INV" if ch.inverted else "NORM"))
        c.add("OUTPut:TRIGger[:STATe]", self._global("trigger_out", scpi.boolean))
        c.add("OUTPut:TRIGger[:STATe]?", lambda a, s: "1" if self.trigger_out else "0")
        c.add("OUTPut:TRIGger:SOURce", self._global("trigger_out_channel", self._channel_word))
        c.add("OUTPut:TRIGger:SOURce?", lambda a, s: f"CH{self.trigger_out_channel}")
        c.add("OUTPut:TRIGger:SLOPe", self._global("trigger_out_slope", lambda a: scpi.choice(
            a, {"POS": "POS", "POSITIVE": "POS", "NEG": "NEG", "NEGATIVE": "NEG"})))
        c.add("OUTPut:TRIGger:SLOPe?", lambda a, s: self.trigger_out_slope)
        c.add("OUTPut:SYNC[:STATe]", self._global("sync", scpi.boolean))
        c.add("OUTPut:SYNC[:STATe]?", lambda a, s: "1" if self.sync else "0")
        c.add("OUTPut:SYNC:SOURce", self._global("sync_channel", self._channel_word))
        c.add("OUTPut:SYNC:SOURce?", lambda a, s: f"CH{self.sync_channel}")
        c.add("ABORt", self._abort)

    # ------------------------------------------------------------------ state
    def _reset_global(self) -> None:
        self.little_endian = False
        self.trigger_out = False
        self.trigger_out_channel = 1
        self.trigger_out_slope = "POS"
        self.sync = True
        self.sync_channel = 1
        self.display_text = ""

    def reset(self) -> None:
        """``*RST``: every channel and the global settings to their reset values."""
        for channel in self.channels.values():
            channel.reset()
        self._reset_global()

    def state_of(self, channel: int) -> ChannelState:
        """The state of ``channel`` (1 or 2)."""
        return self.channels[channel]

    @property
    def state(self) -> ChannelState:
        """The channel wired to the amplifier."""
        return self.channels[self.wired_channel]

    def output_volts(self, start: int, n: int, world_rate: float) -> np.ndarray:
        """Voltage the wired channel puts on the amplifier's input, world samples ``start ..
        start + n``, V."""
        return self.state.volts(start, n, world_rate)

    # ------------------------------------------------------------------ helpers
    @staticmethod
    def _number_of(suffixes: list) -> int:
        return scpi.suffix(suffixes[0] if suffixes else None, range(1, CHANNELS + 1))

    def _ch(self, suffixes: list) -> ChannelState:
        return self.channels[self._number_of(suffixes)]

    def _setter(self, attr: str, parse):
        def handler(args, suffixes):
            channel = self._ch(suffixes)
            setattr(channel, attr, parse(args, channel))
        return handler

    def _getter(self, answer):
        return lambda args, suffixes: answer(self._ch(suffixes))

    def _channel_query(self, answer):
        return lambda args, suffixes: answer(args, self._ch(suffixes))

    def _numeric(self, header: str, attr: str, low: float, high: float, default: float,
                 unit: str) -> None:
        """A numeric setting of each channel with its query (``MIN``/``MAX``/``DEF`` too)."""
        words = scpi.limits(low, high, default)
        self.commands.add(f"[SOURce#:]{header}", self._setter(
            attr, lambda a, ch: scpi.number(a, low, high, words=words, unit=unit)))
        self.commands.add(f"[SOURce#:]{header}?", self._channel_query(
            lambda a, ch: _f(scpi.query_limit(a, low, high, default, getattr(ch, attr)))))

    def _trigger_setter(self, attr: str, parse):
        def handler(args, suffixes):
            setattr(self._ch(suffixes), attr, parse(args))
        return handler

    def _trigger_getter(self, answer):
        return lambda args, suffixes: answer(self._ch(suffixes))

    _output_getter = _getter

    def _global(self, attr: str, parse):
        def handler(args, suffixes):
            setattr(self, attr, parse(args))
        return handler

    @staticmethod
    def _channel_word(args: bytes) -> int:
        word = scpi.choice(args, {"CH1": "CH1", "CH2": "CH2", "1": "CH1", "2": "CH2"})
        return int(word[-1])

    @staticmethod
    def _peak(channel: ChannelState) -> float:
        return 10.0 if math.isinf(channel.load_ohm) else 5.0

    def _limits(self, channel: ChannelState, amplitude: float, offset: float) -> None:
        peak = self._peak(channel)
        if amplitude < (0.002 if math.isinf(channel.load_ohm) else 0.001) or \
                amplitude / 2 + abs(offset) > peak + 1e-12:
            raise ScpiError(-222, f"amplitude {amplitude:g} Vpp with offset {offset:g} V "
                                  f"exceeds +-{peak:g} V into the set load")

    # ------------------------------------------------------------------ amplitude
    def _to_vpp(self, channel: ChannelState, value: float, unit: str) -> float:
        if unit == "VPP":
            return value
        if unit == "VRMS":
            return value * CREST[channel.function]
        if math.isinf(channel.load_ohm):
            raise ScpiError(-221, "dBm needs a finite load (OUTP:LOAD)")
        vrms = math.sqrt(1e-3 * channel.load_ohm * 10 ** (value / 10))
        return vrms * CREST[channel.function]

    def _from_vpp(self, channel: ChannelState, vpp: float) -> float:
        if channel.unit == "VPP":
            return vpp
        vrms = vpp / CREST[channel.function]
        if channel.unit == "VRMS":
            return vrms
        return 10 * math.log10(vrms ** 2 / channel.load_ohm / 1e-3)

    def _unit(self, args, suffixes):
        channel = self._ch(suffixes)
        unit = scpi.choice(args, {"VPP": "VPP", "VRMS": "VRMS", "DBM": "DBM"})
        if unit == "DBM" and math.isinf(channel.load_ohm):
            raise ScpiError(-221, "dBm needs a finite load (OUTP:LOAD)")
        channel.unit = unit

    def _amplitude(self, args, suffixes):
        channel = self._ch(suffixes)
        low = 0.002 if math.isinf(channel.load_ohm) else 0.001
        high = 2 * (self._peak(channel) - abs(channel.offset_v))
        word = scpi.text(args).upper()
        if word in scpi.limits(low, high, 0.1):
            value = scpi.limits(low, high, 0.1)[word]
        else:
            value = self._to_vpp(channel, scpi.number(
                args, unit="V" if channel.unit != "DBM" else None), channel.unit)
        self._limits(channel, value, channel.offset_v)
        channel.amplitude_vpp = value

    def _amplitude_query(self, args, suffixes):
        channel = self._ch(suffixes)
        low = 0.002 if math.isinf(channel.load_ohm) else 0.001
        high = 2 * (self._peak(channel) - abs(channel.offset_v))
        vpp = scpi.query_limit(args, low, high, 0.1, channel.amplitude_vpp)
        return _f(self._from_vpp(channel, vpp))

    def _offset(self, args, suffixes):
        channel = self._ch(suffixes)
        peak = self._peak(channel)
        value = scpi.number(args, -peak, peak, words=scpi.limits(
            -peak + channel.amplitude_vpp / 2, peak - channel.amplitude_vpp / 2, 0.0), unit="V")
        self._limits(channel, channel.amplitude_vpp, value)
        channel.offset_v = value

    def _level(self, which: str):
        def handler(args, suffixes):
            channel = self._ch(suffixes)
            peak = self._peak(channel)
            value = scpi.number(args, -peak, peak, unit="V")
            high = channel.offset_v + channel.amplitude_vpp / 2
            low = channel.offset_v - channel.amplitude_vpp / 2
            high, low = (value, low) if which == "high" else (high, value)
            if high <= low:
                raise ScpiError(-221, "the high level must stay above the low level")
            self._limits(channel, high - low, (high + low) / 2)
            channel.amplitude_vpp, channel.offset_v = high - low, (high + low) / 2
        return handler

    def _pulse_duty(self, args, suffixes):
        channel = self._ch(suffixes)
        duty = scpi.number(args, 0.0, 100.0, words=scpi.limits(0.0, 100.0, 10.0), unit="PCT")
        channel.pulse_width = channel.pulse_period * duty / 100.0

    # ------------------------------------------------------------------ arb memory
    def _border(self, args, suffixes):
        self.little_endian = scpi.choice(args, {"NORM": "NORM", "NORMAL": "NORM",
                                                "SWAP": "SWAP", "SWAPPED": "SWAP"}) == "SWAP"

    def _display(self, args, suffixes):
        self.display_text = scpi.text(args)[:40]

    def _phase_sync(self, args, suffixes):
        now = self.bench.world_now()
        for channel in self.channels.values():
            if channel.output_on and not channel.triggered_burst:
                channel.play_start = now

    def _clear(self, args, suffixes):
        channel = self._ch(suffixes)
        if channel.output_on and channel.function == "ARB":
            raise ScpiError(-221, "cannot clear the arb memory while an arb is playing")
        channel.arbs.clear()
        channel.arb_name = ""

    def _catalog(self, args, suffixes):
        names = self._ch(suffixes).arbs
        return ",".join(f'"{name}"' for name in names) or '""'

    def _arb_name(self, args: bytes, channel: ChannelState) -> tuple[str, bytes]:
        name_bytes, comma, rest = args.partition(b",")
        name = scpi.text(name_bytes).upper()
        rest = rest.lstrip()
        if not comma or not rest:
            raise ScpiError(-109, "expected DATA:ARB <name>,<block or values>")
        if not name or not name[0].isalpha() or len(name) > 12 or not name.replace(
                "_", "").isalnum():
            raise ScpiError(-224, f"arb name {name[:20]!r}: 1 to 12 letters, digits or _, "
                                  "starting with a letter")
        if name in channel.arbs:
            raise ScpiError(-221, f"arb {name!r} already exists in volatile memory; clear it "
                                  "first (DATA:VOL:CLE)")
        return name, rest

    def _store(self, channel: ChannelState, name: str, points: np.ndarray) -> None:
        if points.size > MAX_POINTS:
            raise ScpiError(-223, f"{points.size} points; at most {MAX_POINTS}")
        if points.size < MIN_POINTS:
            raise ScpiError(-222, f"{points.size} points; at least {MIN_POINTS}")
        channel.arbs[name] = np.round(points.astype(float) * DAC_LEVELS) / DAC_LEVELS

    def _data_arb(self, args, suffixes):
        channel = self._ch(suffixes)
        name, data = self._arb_name(args, channel)
        if data[:1] == b"#":
            payload = scpi.parse_ieee_block(data)
            if len(payload) % 4:
                raise ScpiError(-160, f"{len(payload)} bytes is not a whole number of float32 "
                                      "points")
            points = np.frombuffer(payload, dtype="<f4" if self.little_endian else ">f4")
            if not np.all(np.isfinite(points)) or np.max(np.abs(points), initial=0) > 1.0:
                raise ScpiError(-222, "arb points must lie between -1 and +1")
        else:
            points = _ascii_points(data, -1.0, 1.0, "arb points")
        self._store(channel, name, points)

    def _data_arb_dac(self, args, suffixes):
        channel = self._ch(suffixes)
        name, data = self._arb_name(args, channel)
        if data[:1] == b"#":
            payload = scpi.parse_ieee_block(data)
            if len(payload) % 2:
                raise ScpiError(-160, f"{len(payload)} bytes is not a whole number of int16 "
                                      "points")
            codes = np.frombuffer(payload, dtype="<i2" if self.little_endian else ">i2")
            if codes.size and codes.min() < -DAC_LEVELS:
                raise ScpiError(-222, "DAC codes must lie between -32767 and +32767")
        else:
            codes = _ascii_points(data, -DAC_LEVELS, DAC_LEVELS, "DAC codes")
            if np.any(codes != np.round(codes)):
                raise ScpiError(-224, "DAC codes must be integers")
        self._store(channel, name, codes.astype(float) / DAC_LEVELS)

    def _select_arb(self, args, suffixes):
        channel = self._ch(suffixes)
        name = scpi.text(args).upper()
        if name not in channel.arbs:
            raise ScpiError(-224, f"no arb named {name[:20]!r} in volatile memory")
        channel.arb_name = name

    # ------------------------------------------------------------------ output
    def _output(self, args, suffixes):
        channel = self._ch(suffixes)
        on = scpi.boolean(args)
        if on and not channel.output_on:
            channel.output_on = True
            channel.play_start = None if channel.triggered_burst else self.bench.world_now()
        elif not on:
            channel.output_on = False

    def _load(self, args, suffixes):
        channel = self._ch(suffixes)
        load = scpi.number(args, 1.0, 10e3, words={
            "INF": math.inf, "INFINITY": math.inf, "9.9E+37": math.inf, "9.9E37": math.inf,
            **scpi.limits(1.0, 10e3, 50.0)}, unit="OHM")
        if load >= 9.9e37:
            load = math.inf
        channel.load_ohm = load

    def _polarity(self, args, suffixes):
        self._ch(suffixes).inverted = scpi.choice(
            args, {"NORM": "NORM", "NORMAL": "NORM", "INV": "INV", "INVERTED": "INV"}) == "INV"

    # ------------------------------------------------------------------ triggers
    def _fire(self, numbers: list[int]) -> None:
        """Start a burst on the channels ``numbers`` now; the trigger output follows its
        channel."""
        now = self.bench.world_now()
        for number in numbers:
            self.channels[number].play_start = now
        if self.trigger_out and self.trigger_out_channel in numbers:
            self.bench.external_trigger()

    def _bus_trigger(self, args, suffixes):
        numbers = [n for n, ch in self.channels.items()
                   if ch.burst and ch.trigger_source == "BUS"]
        if not numbers:
            raise ScpiError(-211, "trigger ignored: no channel has BURS:STAT ON and "
                                  "TRIG:SOUR BUS")
        self._fire(numbers)

    def _trigger_channel(self, args, suffixes):
        number = self._number_of(suffixes)
        if not self.channels[number].burst:
            raise ScpiError(-211, f"trigger ignored: channel {number} is not in burst mode")
        self._fire([number])

    def _abort(self, args, suffixes):
        for channel in self.channels.values():
            channel.play_start = None
