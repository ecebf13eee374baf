"""In-process simulated instruments: a bench that lives inside the fsi-lab process.

They implement the same role interfaces as the hardware drivers, without any wire, so that the
core (profiles, safety, orchestration, run files, analysis) can be rehearsed and tested with
no hardware. The physics is the profile's own: source volts -> amplifier gain ->
shaker armature on its suspension (``[shaker]``) -> base acceleration -> the beam-in-fluid model
(``[specimen]`` and ``[model]``) -> tip velocity; every input gets Gaussian noise.

Fault settings (``fail_after_s``, ``interlock_after_s``) make an instrument die or trip an
interlock mid-run, for tests of the safe state. They count record time, the samples the digitiser
has delivered divided by the sample rate, never the wall clock: a fault set at 0.6 s strikes after
exactly 0.6 s of data, however slowly the machine opens the instruments or computes the physics,
and a run shorter than that never sees it.
"""

from __future__ import annotations

import time
from typing import Any, Mapping

import numpy as np

from fsi_lab.contract import (
    Acquisition,
    Amplifier,
    InstrumentPlugin,
    OutputState,
    SignalSource,
    Vibrometer,
)
from fsi_lab.errors import InstrumentError
from fsi_lab.hookspecs import hookimpl
from fsi_lab.modal_step import check_step
from fsi_lab.modelling import BenchPhysics, beam_model
from fsi_lab.params import Param

INTERLOCKS = ("over_travel", "supply_fault", "over_temperature", "over_current", "e_stop",
              "input_clip")


def _bench(context: dict[str, Any]) -> dict[str, Any]:
    """Shared state of the simulated bench of one run."""
    return context.setdefault("inprocess", {
        "waveform": np.zeros(0), "waveform_rate": 1.0, "source_on": False, "start_time": None,
        "gain": 0.0, "output_enabled": False, "interlocks": dict.fromkeys(INTERLOCKS, False),
        "velocity_sensitivity": 8.0, "source_level_v": 0.0,
        "record_s": 0.0,  # record time: samples delivered by the digitiser / sample rate
    })


class _Base:
    def __init__(self, name: str, address: str, settings: Mapping[str, Any],
                 context: dict[str, Any]) -> None:
        self._name = name
        self._address = address
        self._settings = dict(settings)
        self._bench = _bench(context)
        self._open = True

    def identify(self) -> str:
        self._alive()
        return f"fsi-lab,{self._name},SIM0001,0.1 (in-process at {self._address or 'default'})"

    def settings(self) -> dict[str, Any]:
        return dict(self._settings)

    def close(self) -> None:
        self._open = False

    def _due(self, setting: str) -> bool:
        """Whether the simulated fault ``setting`` (a record time, s) has struck."""
        after = self._settings.get(setting)
        return after is not None and self._bench["record_s"] >= after

    def _alive(self) -> None:
        if not self._open:
            raise InstrumentError(f"{self._name}: connection closed")
        if self._due("fail_after_s"):
            fail_after = self._settings["fail_after_s"]
            raise InstrumentError(
                f"{self._name} at {self._address or 'in-process'}: no answer (simulated "
                f"failure after {fail_after:g} s)"
            )


class InProcessSource(_Base, SignalSource):
    def load_waveform(self, samples: np.ndarray, sample_rate: float) -> None:
        self._alive()
        self._bench["waveform"] = np.asarray(samples, dtype=float).copy()
        self._bench["waveform_rate"] = float(sample_rate)

    def start(self) -> None:
        self._alive()
        self._bench["source_on"] = True

    def safe_state(self) -> None:
        self._bench["source_on"] = False
        self._bench["source_level_v"] = 0.0

    def read_state(self) -> OutputState:
        return OutputState(bool(self._bench["source_on"]), level_v=self._bench["source_level_v"])


class InProcessAmplifier(_Base, Amplifier):
    def set_gain(self, gain: float) -> None:
        self._alive()
        self._bench["gain"] = float(gain)

    def enable_output(self, enabled: bool) -> None:
        self._alive()
        if enabled and any(self._bench["interlocks"].values()):
            raise InstrumentError(f"{self._name}: output refused while an interlock is active")
        self._bench["output_enabled"] = bool(enabled)

    def interlocks(self) -> dict[str, bool]:
        self._alive()
        if self._due("interlock_after_s"):
            self._bench["interlocks"]["over_travel"] = True
            self._bench["output_enabled"] = False
        return dict(self._bench["interlocks"])

    def safe_state(self) -> None:
        # Deliberately does not check liveness of the link: the bench must always be safed.
        self._bench["output_enabled"] = False

    def read_state(self) -> OutputState:
        return OutputState(bool(self._bench["output_enabled"]), gain=self._bench["gain"],
                           interlocks={k: v for k, v in self._bench["interlocks"].items() if v})


class InProcessVibrometer(_Base, Vibrometer):
    RANGES = {"25mm/s/V": 0.025, "125mm/s/V": 0.125, "1000mm/s/V": 1.0}

    def __init__(self, *args) -> None:
        super().__init__(*args)
        self._bench["velocity_sensitivity"] = 1.0 / self.RANGES[self._settings["range"]]

    def sensitivity(self) -> float:
        return self._bench["velocity_sensitivity"]

    def delay(self) -> float:
        return float(self._settings["delay_s"])

    def safe_state(self) -> None:
        """A vibrometer cannot move anything: nothing to switch off."""

    def read_state(self) -> dict[str, Any]:
        return {"range": self._settings["range"]}


class InProcessAcquisition(_Base, Acquisition):
    """Digitiser whose inputs carry 1: drive (V), 2: base acceleration, 3: tip velocity, 4: spare.

    The physics behind the inputs is the profile's: ``[shaker]`` for the base motion and
    ``[specimen]`` with ``[model]`` for the beam (see :class:`fsi_lab.modelling.BenchPhysics`).
    """

    SIGNALS = {1: "drive", 2: "base_acceleration", 3: "tip_velocity", 4: "spare"}

    def __init__(self, name, address, settings, context) -> None:
        super().__init__(name, address, settings, context)
        self._context = context

    @classmethod
    def record_problem(cls, inputs: Mapping[str, int], specimen: Any) -> str:
        """What this digitiser cannot record of ``inputs`` (channel -> input number) for the
        profile's ``specimen``, in words; empty when it can."""
        bad = {name: i for name, i in inputs.items() if i not in cls.SIGNALS}
        if bad:
            name, number = next(iter(bad.items()))
            return (f"channel {name!r} uses input {number}; this digitiser has inputs 1 to "
                    f"{len(cls.SIGNALS)}")
        if specimen is None:
            return ("the simulated bench needs the profile's [specimen] (the beam whose "
                    "response it simulates)")
        return ""

    def configure(self, inputs: Mapping[str, int], sample_rate: float, duration: float) -> float:
        self._alive()
        specimen = self._context.get("specimen")
        problem = self.record_problem(inputs, specimen)
        if problem:
            raise InstrumentError(f"{self._name}: {problem}")
        self._inputs = dict(inputs)
        self._rate = float(sample_rate)
        self._total = int(round(duration * sample_rate))
        self._block = max(1, int(round(self._settings["block_duration"] * sample_rate)))
        self._rng = np.random.default_rng(self._settings["seed"])
        model = beam_model(specimen, self._context["model"])
        self._physics = BenchPhysics(model, self._context["shaker"], self._rate,
                                     specimen.measurement_point)
        return self._rate

    def arm(self) -> None:
        self._alive()
        self._sent = 0
        self._t_start = time.monotonic()

    def _drive(self, n0: int, n: int) -> np.ndarray:
        bench = self._bench
        t = (n0 + np.arange(n)) / self._rate
        wave, rate = bench["waveform"], bench["waveform_rate"]
        if not bench["source_on"] or wave.size == 0:
            return np.zeros(n)
        return np.interp(t, np.arange(wave.size) / rate, wave, left=0.0, right=0.0)

    def read_block(self, timeout: float) -> dict[str, np.ndarray] | None:
        self._alive()
        if self._sent >= self._total:
            return None
        n = min(self._block, self._total - self._sent)
        if self._settings["realtime"]:
            wait = self._t_start + (self._sent + n) / self._rate - time.monotonic()
            if wait > timeout:
                raise InstrumentError(f"{self._name}: no block within {timeout:g} s")
            if wait > 0:
                time.sleep(wait)
        bench = self._bench
        drive = self._drive(self._sent, n)
        motion = self._physics.advance(drive * bench["gain"] * bench["output_enabled"])
        volts = {
            "drive": drive,
            "base_acceleration": motion["base_acceleration"]
            * self._settings["accelerometer_v_per_ms2"],
            "tip_velocity": motion["tip_velocity"] * bench["velocity_sensitivity"],
            "spare": np.zeros(n),
        }
        self._sent += n
        bench["record_s"] = self._sent / self._rate
        noise = self._settings["noise_v"]
        return {name: volts[self.SIGNALS[i]] + noise * self._rng.standard_normal(n)
                for name, i in self._inputs.items()}

    def safe_state(self) -> None:
        """Stops nothing physical; a digitiser cannot drive the shaker."""

    def read_state(self) -> dict[str, Any]:
        self._alive()  # a digitiser that stopped answering cannot report its state either
        return {"samples_sent": int(getattr(self, "_sent", 0))}


def check_acquisition(address: str, settings: dict[str, Any], plan: Mapping[str, Any]) -> None:
    """The instrument check of :class:`~fsi_lab.contract.InstrumentPlugin` (ValueError): the
    channels' inputs, the specimen, and a beam model the simulation resolves at the record's
    sample rate."""
    problem = InProcessAcquisition.record_problem(plan["inputs"], plan["specimen"])
    if problem:
        raise ValueError(problem)
    check_step(beam_model(plan["specimen"], plan["model"]), plan["sample_rate"])


FAIL = Param("fail_after_s", "float", "s", None, minimum=0.0, maximum=86400.0,
             help="Simulated fault: stop answering once the record is this long (record time, "
                  "not wall-clock time).")

PLUGINS = [
    InstrumentPlugin(
        "inprocess-source", "source",
        (Param("sample_rate", "float", "Hz", None, minimum=1.0, maximum=10e6,
               help="Playback rate of the waveform (default: the run's sample rate)."), FAIL),
        lambda address, settings, ctx: InProcessSource("source", address, settings, ctx),
        help="Simulated signal source inside the fsi-lab process."),
    InstrumentPlugin(
        "inprocess-amplifier", "amplifier",
        (Param("gain", "float", "V/V", 1.0, minimum=0.0, maximum=100.0,
               help="Voltage gain of the amplifier."),
         Param("interlock_after_s", "float", "s", None, minimum=0.0, maximum=86400.0,
               help="Simulated fault: trip the over-travel interlock once the record is this "
                    "long (record time, not wall-clock time)."),
         FAIL),
        lambda address, settings, ctx: InProcessAmplifier("amplifier", address, settings, ctx),
        help="Simulated shaker amplifier with interlocks."),
    InstrumentPlugin(
        "inprocess-vibrometer", "vibrometer",
        (Param("range", "str", "", "125mm/s/V", choices=tuple(InProcessVibrometer.RANGES),
               help="Velocity range of the decoder."),
         Param("delay_s", "float", "s", 0.0, minimum=0.0, maximum=0.01,
               help="Signal delay of the sensor head and decoder."), FAIL),
        lambda address, settings, ctx: InProcessVibrometer("vibrometer", address, settings, ctx),
        help="Simulated laser vibrometer."),
    InstrumentPlugin(
        "inprocess-acquisition", "acquisition",
        (Param("block_duration", "float", "s", 0.1, minimum=0.001, maximum=0.5,
               help="Length of each streamed block."),
         Param("realtime", "bool", "", False, help="Pace blocks at the real acquisition rate."),
         Param("noise_v", "float", "V", 1e-4, minimum=0.0, maximum=10.0,
               help="RMS noise on every input."),
         Param("seed", "int", "", 0, minimum=0, maximum=2**32 - 1,
               help="Seed of the noise generator."),
         Param("accelerometer_v_per_ms2", "float", "V/(m/s^2)", 0.0102, minimum=1e-6,
               maximum=10.0, help="Accelerometer sensitivity (100 mV/g)."), FAIL),
        lambda address, settings, ctx: InProcessAcquisition("acquisition", address, settings, ctx),
        help="Simulated digitiser with the bench physics behind its inputs.",
        check=check_acquisition),
]


@hookimpl
def fsi_lab_instruments():
    return PLUGINS
