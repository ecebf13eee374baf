"""4-input SCPI digitiser (dynamic signal analyser class, 24-bit, up to 204.8 kS/s) over VISA.

Inputs: 1 drive, 2 base acceleration (IEPE accelerometer, mV/g; the input supplies its current
and is AC coupled), 3 tip velocity (vibrometer output), 4 spare. The driver enables the inputs the
profile's channels use, sets their ranges and IEPE supply, reads each input's scale (V per code),
sets the sample rate and record length and arms on the source's trigger output (or at once).
Blocks are fetched as they become available (``ACQ:STAT?`` then ``FETC? <n>``) as definite-length
blocks of little-endian int32 codes interleaved by sample, and returned in volts. An input that
exceeds its range stops the run with the input named.

Address: a VISA resource, e.g. ``TCPIP0::192.168.1.30::5025::SOCKET``, or ``embedded``.
"""

from __future__ import annotations

import re
import time
from collections.abc import Mapping
from typing import Any

import numpy as np

from fsi_lab.contract import Acquisition, InstrumentPlugin
from fsi_lab.errors import InstrumentError
from fsi_lab.hookspecs import hookimpl
from fsi_lab.instruments.kit import ScpiInstrument, Setting, checked_identity, connect
from fsi_lab.params import Param

NAME = "scpi-daq"
INPUTS = (1, 2, 3, 4)
MAX_RATE = 204800.0
#: Most samples per input a record may hold (``ACQ:POIN``, a 32-bit count).
MAX_POINTS = 2**31 - 1
SAFE_TIMEOUT_S = 1.0
_STATUS = re.compile(r"^(IDLE|WTRG|RUN|DONE|OVER),(\d+),(\d+)$")


class ScpiDaq(ScpiInstrument, Acquisition):
    """An open digitiser. Use :func:`open_daq`."""

    NAME = NAME
    byte_order = Setting("FORM:BORD", "str", choices=("NORM", "SWAP"),
                         help="Byte order of the int32 blocks (SWAP: little-endian).")
    input_enabled = Setting("INP{input}:STAT", "bool", help="Input digitised.")
    input_range = Setting("INP{input}:RANG", "float", "V", minimum=0.001, maximum=10.0, fmt="g",
                          accepted="input ranges go up to 10 V",
                          help="Input range (peak volts).")
    iepe_supply = Setting("INP{input}:IEPE", "bool",
                          help="IEPE current supplied to the sensor (AC coupled).")
    input_scale = Setting("INP{input}:SCAL", "float", "V", readonly=True,
                          help="Volts per code of the input at its range.")
    sample_rate = Setting("ACQ:SRAT", "float", "Hz", minimum=0.0, maximum=MAX_RATE,
                          accepted=f"up to {MAX_RATE:g} Hz", help="Sample rate.")
    points = Setting("ACQ:POIN", "int", minimum=1, maximum=MAX_POINTS,
                     help="Samples per input of the record.")
    trigger = Setting("TRIG:SOUR", "str", choices={"external": "EXT", "immediate": "IMM"},
                      help="Start the record on the source's trigger output, or when armed.")

    def __init__(self, link, settings: dict[str, Any], identity: str) -> None:
        super().__init__(link, identity)
        self.block_duration = float(settings["block_duration"])
        self.ranges = [float(r) for r in settings["ranges_v"]]
        self.iepe = {int(n) for n in settings["iepe_inputs"]}
        self.external = settings["trigger"] == "external"
        self._names: dict[int, list[str]] = {}
        self._order: list[int] = []
        self._scales = np.zeros(0)
        self._rate = 0.0
        self._total = 0
        self._fetched = 0
        self._block = 1
        self._configured: dict[str, Any] = {}

    def _where(self) -> str:
        return self.where

    def settings(self) -> dict[str, Any]:
        return {"visa_address": self.link.address, **self._configured}

    def configure(self, inputs: Mapping[str, int], sample_rate: float, duration: float) -> float:
        """Enable the used inputs, set ranges, IEPE supply, rate, record length and trigger."""
        problem = record_problem(inputs, sample_rate, duration)
        if problem:
            raise InstrumentError(f"{self._where()}: {problem}")
        names: dict[int, list[str]] = {}
        for name, number in inputs.items():
            names.setdefault(int(number), []).append(name)
        order = sorted(names)
        for number in INPUTS:
            self.set("input_enabled", number in names, input=number)
        scales, ranges = [], {}
        for number in order:
            self.set("input_range", self.ranges[number - 1], input=number)
            self.set("iepe_supply", number in self.iepe, input=number)
            ranges[number] = self.get("input_range", input=number)
            scales.append(self.get("input_scale", input=number))
        self.sample_rate = sample_rate
        rate = self.sample_rate
        total = round(duration * rate)
        self.points = total
        self.trigger = "external" if self.external else "immediate"
        self._names, self._order = names, order
        self._scales = np.asarray(scales)
        self._rate, self._total, self._fetched = rate, total, 0
        self._block = max(1, round(self.block_duration * rate))
        self._configured = {
            "sample_rate": rate, "points": total, "inputs": order,
            "ranges_v": {str(n): ranges[n] for n in order},
            "volts_per_code": {str(n): float(s) for n, s in zip(order, scales)},
            "iepe_inputs": sorted(n for n in order if n in self.iepe),
            "trigger": "external" if self.external else "immediate",
            "block_samples": self._block,
        }
        return rate

    def arm(self) -> None:
        """``INIT``: wait for the trigger (or start, with trigger = \"immediate\")."""
        self._fetched = 0
        self.link.send_checked("INIT")

    def _status(self) -> tuple[str, int, int]:
        reply = self.link.query("ACQ:STAT?")
        m = _STATUS.match(reply)
        if not m:
            self.link.broken = f"garbled status {reply!r}"
            raise InstrumentError(f"{self._where()}: garbled reply {reply!r} to 'ACQ:STAT?'; "
                                  "expected <state>,<available>,<overloads>")
        return m.group(1), int(m.group(2)), int(m.group(3))

    def _overload_message(self, bits: int) -> str:
        inputs = [n for n in INPUTS if bits >> (n - 1) & 1]
        named = ", ".join(f"input {n} ({'/'.join(self._names.get(n, ['unused']))}, range "
                          f"{self._configured['ranges_v'].get(str(n), '?')} V)" for n in inputs)
        return (f"{self._where()}: overload on {named} after {self._fetched} samples; the signal "
                "exceeded the input range: raise ranges_v for that input or lower the excitation")

    def read_block(self, timeout: float) -> dict[str, np.ndarray] | None:
        """The next block in volts per channel name; None once the record is complete."""
        want = min(self._block, self._total - self._fetched)
        if want <= 0:
            return None
        deadline = time.monotonic() + timeout
        while True:
            state, available, overloads = self._status()
            if overloads:
                raise InstrumentError(self._overload_message(overloads))
            if state == "OVER":
                raise InstrumentError(f"{self._where()}: acquisition buffer overrun after "
                                      f"{self._fetched} samples: blocks were not fetched in time")
            if available >= want:
                break
            if state == "IDLE":
                raise InstrumentError(f"{self._where()}: the acquisition stopped after "
                                      f"{self._fetched} of {self._total} samples (aborted?)")
            if state == "DONE":
                raise InstrumentError(f"{self._where()}: the record ended after "
                                      f"{self._fetched + available} of {self._total} samples")
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                if state == "WTRG":
                    raise InstrumentError(
                        f"{self._where()}: no trigger within {timeout:g} s: the digitiser waits "
                        "for the source's trigger output (wire it to the trigger input) or set "
                        "trigger = \"immediate\"")
                raise InstrumentError(f"{self._where()}: no block within {timeout:g} s "
                                      f"({available} of {want} samples available)")
            missing = (want - available) / self._rate if state == "RUN" else 0.02
            time.sleep(min(max(missing, 0.001), remaining, 0.25))
        payload = self.link.read_block(f"FETC? {want}")
        width = len(self._order)
        if len(payload) != want * width * 4:
            self.link.broken = "short block"
            raise InstrumentError(f"{self._where()}: FETC? {want} returned {len(payload)} "
                                  f"bytes; expected {want * width * 4} ({want} samples of "
                                  f"{width} inputs, int32)")
        # an overload inside this block: stop before it reaches the run file
        _, _, overloads = self._status()
        if overloads:
            raise InstrumentError(self._overload_message(overloads))
        codes = np.frombuffer(payload, dtype="<i4").reshape(want, width)
        volts = codes * self._scales
        self._fetched += want
        block = {}
        for column, number in enumerate(self._order):
            for name in self._names[number]:
                block[name] = volts[:, column].copy()
        return block

    def safe_state(self) -> None:
        """Stop the acquisition (``ABOR``); a digitiser cannot move the shaker."""
        with self.link.timeout(SAFE_TIMEOUT_S):
            self.link.recover(SAFE_TIMEOUT_S)
            self.link.write("ABOR")

    def read_state(self) -> dict[str, Any]:
        with self.link.timeout(SAFE_TIMEOUT_S):
            self.link.recover(SAFE_TIMEOUT_S)
            state, _available, overloads = self._status()
        return {"state": state, "samples_fetched": self._fetched,
                "overloaded_inputs": [n for n in INPUTS if overloads >> (n - 1) & 1]}



def record_problem(inputs: Mapping[str, int], sample_rate: float, duration: float) -> str:
    """What this digitiser cannot record of ``inputs`` (channel name -> input number) at
    ``sample_rate`` (Hz) for ``duration`` (s), in words; empty when it can."""
    bad = {name: n for name, n in inputs.items() if n not in INPUTS}
    if bad:
        name, number = next(iter(bad.items()))
        return f"channel {name!r} uses input {number}; this digitiser has inputs 1 to {len(INPUTS)}"
    if not 0 < sample_rate <= MAX_RATE:
        return f"sample rate {sample_rate:g} Hz; this digitiser samples at up to {MAX_RATE:g} Hz"
    points = round(duration * sample_rate)
    if points > MAX_POINTS:
        return (f"{points:,} samples per input ({duration:g} s at {sample_rate:g} Hz); a record "
                f"holds at most {MAX_POINTS:,}: shorten run.duration or lower run.sample_rate")
    return ""


def settings_problem(settings: Mapping[str, Any]) -> str:
    """What is wrong with validated ``settings`` for this digitiser, in words; empty if nothing."""
    if len(settings["ranges_v"]) != len(INPUTS):
        return (f"ranges_v has {len(settings['ranges_v'])} values; expected one per input "
                f"({len(INPUTS)})")
    bad = [n for n in settings["iepe_inputs"] if n not in INPUTS]
    if bad:
        return f"iepe_inputs names input {bad[0]:g}; expected inputs 1 to {len(INPUTS)}"
    return ""


def check_daq(address: str, settings: dict[str, Any], plan: Mapping[str, Any]) -> None:
    """The instrument check of :class:`~fsi_lab.contract.InstrumentPlugin` (ValueError)."""
    problem = settings_problem(settings) or record_problem(
        plan["inputs"], plan["sample_rate"], plan["duration"])
    if problem:
        raise ValueError(problem)
    from fsi_lab.instruments.sim.embedded import check_embedded_record

    check_embedded_record(address, plan)


def open_daq(address: str, settings: dict[str, Any], context: Mapping[str, Any]) -> ScpiDaq:
    """Connect, identify, reset, clear the status and choose little-endian blocks."""

    problem = settings_problem(settings)
    if problem:
        raise InstrumentError(f"{NAME}: {problem}")
    link = connect(NAME, "acquisition", address, settings, context)
    try:
        identity = checked_identity(NAME, link)
        link.write("*RST")
        link.write("*CLS")
        link.send_checked(ScpiDaq.byte_order.command_for("SWAP"))
    except BaseException:
        link.close()
        raise
    return ScpiDaq(link, settings, identity)


PLUGIN = InstrumentPlugin(
    name=NAME,
    role="acquisition",
    params=(
        Param("block_duration", "float", "s", 0.1, minimum=0.001, maximum=0.5,
              help="Length of each block fetched and streamed into the run file."),
        Param("ranges_v", "floats", "V", [10.0, 10.0, 10.0, 10.0],
              minimum=ScpiDaq.input_range.minimum, maximum=ScpiDaq.input_range.maximum,
              help="Input range of inputs 1 to 4 (peak volts)."),
        Param("iepe_inputs", "floats", "", [2.0], minimum=1, maximum=4,
              help="Inputs that supply IEPE current to their sensor (the accelerometer)."),
        ScpiDaq.trigger.param("external"),
        Param("timeout_s", "float", "s", 2.0, minimum=0.05, maximum=60.0,
              help="Time allowed for each reply."),
    ),
    open=open_daq,
    check=check_daq,
    help="4-input SCPI digitiser streaming int32 blocks (up to 204.8 kS/s) over VISA.",
)


@hookimpl
def fsi_lab_instruments():
    return [PLUGIN]
