"""In-process simulated instruments: a bench that lives inside the fsi-lab process.

They implement the same role interfaces as the hardware drivers, without any wire, so that the
core (profiles, safety, orchestration, run files, analysis) can be rehearsed and tested with
no hardware. The physics: source volts -> amplifier gain -> shaker armature on its suspension
-> base acceleration -> the beam's first mode in the fluid, with linear and quadratic damping ->
tip velocity; every channel gets Gaussian noise.

Fault settings (``fail_after_s``, ``interlock_after_s``) make an instrument die or trip an
interlock mid-run, for tests of the safe state.
"""

from __future__ import annotations

import time
from typing import Any, Mapping

import numpy as np
from scipy import signal

from fsi_lab.contract import Acquisition, Amplifier, InstrumentPlugin, SignalSource, Vibrometer
from fsi_lab.errors import InstrumentError
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param

INTERLOCKS = ("over_travel", "supply_fault", "over_temperature", "over_current", "e_stop",
              "input_clip")


def _bench(context: dict[str, Any]) -> dict[str, Any]:
    """Shared state of the simulated bench of one run."""
    return context.setdefault("inprocess", {
        "waveform": np.zeros(0), "waveform_rate": 1.0, "source_on": False, "start_time": None,
        "gain": 0.0, "output_enabled": False, "interlocks": dict.fromkeys(INTERLOCKS, False),
        "velocity_sensitivity": 8.0, "source_level_v": 0.0,
    })


class _Base:
    def __init__(self, name: str, address: str, settings: Mapping[str, Any],
                 context: dict[str, Any]) -> None:
        self._name = name
        self._address = address
        self._settings = dict(settings)
        self._bench = _bench(context)
        self._open = True
        self._opened_at = time.monotonic()

    def identify(self) -> str:
        self._alive()
        return f"fsi-lab,{self._name},SIM0001,0.1 (in-process at {self._address or 'default'})"

    def settings(self) -> dict[str, Any]:
        return dict(self._settings)

    def close(self) -> None:
        self._open = False

    def _alive(self) -> None:
        if not self._open:
            raise InstrumentError(f"{self._name}: connection closed")
        fail_after = self._settings.get("fail_after_s")
        if fail_after is not None and time.monotonic() - self._opened_at > fail_after:
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

    def read_state(self) -> dict[str, Any]:
        return {"output_enabled": self._bench["source_on"],
                "level_v": self._bench["source_level_v"]}


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
        trip_after = self._settings.get("interlock_after_s")
        if trip_after is not None and time.monotonic() - self._opened_at > trip_after:
            self._bench["interlocks"]["over_travel"] = True
            self._bench["output_enabled"] = False
        return dict(self._bench["interlocks"])

    def safe_state(self) -> None:
        # Deliberately does not check liveness of the link: the bench must always be safed.
        self._bench["output_enabled"] = False

    def read_state(self) -> dict[str, Any]:
        return {"output_enabled": self._bench["output_enabled"], "gain": self._bench["gain"],
                "interlocks": {k: v for k, v in self._bench["interlocks"].items() if v}}


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
    """Digitiser whose inputs carry 1: drive (V), 2: base acceleration, 3: tip velocity, 4: spare."""

    SIGNALS = {1: "drive", 2: "base_acceleration", 3: "tip_velocity", 4: "spare"}

    def configure(self, inputs: Mapping[str, int], sample_rate: float, duration: float) -> float:
        self._alive()
        bad = {name: i for name, i in inputs.items() if i not in self.SIGNALS}
        if bad:
            name, number = next(iter(bad.items()))
            raise InstrumentError(
                f"{self._name}: channel {name!r} uses input {number}; this digitiser has inputs "
                f"1 to {len(self.SIGNALS)}"
            )
        self._inputs = dict(inputs)
        self._rate = float(sample_rate)
        self._total = int(round(duration * sample_rate))
        self._block = max(1, int(round(self._settings["block_duration"] * sample_rate)))
        self._rng = np.random.default_rng(self._settings["seed"])
        self._build_filters()
        return self._rate

    def _build_filters(self) -> None:
        s = self._settings
        dt = 1.0 / self._rate
        ws = 2 * np.pi * s["shaker_hz"]
        # base acceleration per amplifier volt: s^2 ws^2 k / (s^2 + 2 zeta ws s + ws^2)
        b, a, _ = signal.cont2discrete(
            ([ws * ws * s["shaker_mm_per_volt"] * 1e-3, 0.0, 0.0],
             [1.0, 2 * s["shaker_damping"] * ws, ws * ws]), dt, method="bilinear")
        self._shaker = (np.ravel(b), np.ravel(a))
        self._shaker_zi = np.zeros(max(len(a), len(b)) - 1)
        self._beam_state = np.zeros(2)  # relative tip displacement (m) and velocity (m/s)

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

    def _beam(self, base_acc: np.ndarray) -> np.ndarray:
        """Tip velocity relative to the base: first mode, linear + quadratic damping (RK2)."""
        s = self._settings
        w = 2 * np.pi * s["beam_hz"]
        c1, c2 = 2 * s["beam_damping"] * w, s["beam_quadratic"]
        dt = 1.0 / self._rate
        x, v = self._beam_state
        out = np.empty_like(base_acc)
        for i, a_b in enumerate(base_acc):  # the in-process bench is small; clarity over speed
            acc = -a_b - c1 * v - c2 * abs(v) * v - w * w * x
            vm = v + 0.5 * dt * acc
            xm = x + 0.5 * dt * v
            accm = -a_b - c1 * vm - c2 * abs(vm) * vm - w * w * xm
            x, v = x + dt * vm, v + dt * accm
            out[i] = v
        self._beam_state[:] = (x, v)
        return out

    def read_block(self, timeout: float) -> dict[str, np.ndarray] | None:
        self._alive()
        if self._sent >= self._total:
            return None
        n = min(self._block, self._total - self._sent)
        pace = self._settings["realtime"]
        if pace:
            due = self._t_start + (self._sent + n) / self._rate
            wait = due - time.monotonic()
            if wait > timeout:
                raise InstrumentError(f"{self._name}: no block within {timeout:g} s")
            if wait > 0:
                time.sleep(wait)
        bench = self._bench
        drive = self._drive(self._sent, n)
        amp_out = drive * bench["gain"] * bench["output_enabled"]
        base, self._shaker_zi = signal.lfilter(*self._shaker, amp_out, zi=self._shaker_zi)
        velocity = self._beam(base)
        noise = self._settings["noise_v"]
        volts = {
            "drive": drive,
            "base_acceleration": base * self._settings["accelerometer_v_per_ms2"],
            "tip_velocity": velocity * bench["velocity_sensitivity"],
            "spare": np.zeros(n),
        }
        self._sent += n
        return {name: volts[self.SIGNALS[i]] + noise * self._rng.standard_normal(n)
                for name, i in self._inputs.items()}

    def safe_state(self) -> None:
        """Stops nothing physical; a digitiser cannot drive the shaker."""

    def read_state(self) -> dict[str, Any]:
        return {"samples_sent": int(getattr(self, "_sent", 0))}


FAIL = Param("fail_after_s", "float", "s", None, minimum=0.0,
             help="Simulated fault: stop answering this long after opening.")

PLUGINS = [
    InstrumentPlugin(
        "inprocess-source", "source",
        (Param("sample_rate", "float", "Hz", None, minimum=1.0,
               help="Playback rate of the waveform (default: the run's sample rate)."), FAIL),
        lambda address, settings, ctx: InProcessSource("source", address, settings, ctx),
        help="Simulated signal source inside the fsi-lab process."),
    InstrumentPlugin(
        "inprocess-amplifier", "amplifier",
        (Param("gain", "float", "V/V", 1.0, minimum=0.0, maximum=100.0,
               help="Voltage gain of the amplifier."),
         Param("interlock_after_s", "float", "s", None, minimum=0.0,
               help="Simulated fault: trip the over-travel interlock this long after opening."),
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
        (Param("block_duration", "float", "s", 0.1, minimum=0.001, maximum=1.0,
               help="Length of each streamed block."),
         Param("realtime", "bool", "", False, help="Pace blocks at the real acquisition rate."),
         Param("noise_v", "float", "V", 1e-4, minimum=0.0, help="RMS noise on every input."),
         Param("seed", "int", "", 0, help="Seed of the noise generator."),
         Param("shaker_hz", "float", "Hz", 30.0, minimum=1.0, help="Shaker suspension resonance."),
         Param("shaker_damping", "float", "", 0.08, minimum=0.0, help="Its damping ratio."),
         Param("shaker_mm_per_volt", "float", "mm/V", 0.5, minimum=0.0,
               help="Static base displacement per amplifier volt."),
         Param("beam_hz", "float", "Hz", 2.8, minimum=0.1, help="Beam first mode in the fluid."),
         Param("beam_damping", "float", "", 0.02, minimum=0.0, help="Its linear damping ratio."),
         Param("beam_quadratic", "float", "1/m", 5.0, minimum=0.0,
               help="Quadratic damping of the tip motion, c2/m."),
         Param("accelerometer_v_per_ms2", "float", "V/(m/s^2)", 0.0102, minimum=0.0,
               exclusive_minimum=True, help="Accelerometer sensitivity (100 mV/g)."), FAIL),
        lambda address, settings, ctx: InProcessAcquisition("acquisition", address, settings, ctx),
        help="Simulated digitiser with the bench physics behind its inputs."),
]


@hookimpl
def fsi_lab_instruments():
    return PLUGINS
