"""The physical world behind the simulated instruments during one digitiser record.

Signal chain, sample by sample::

    source output (V) -> amplifier: gain, output relay, interlocks -> shaker armature on its
    suspension -> base displacement and acceleration -> beam in fluid -> absolute velocity at the
    measuring point -> vibrometer (delay, range, noise, clipping) -> digitiser input 3
    base acceleration -> IEPE accelerometer (mV/g, AC coupling) -> digitiser input 2
    source output -> digitiser input 1; input 4 is open (noise only)

The shaker and beam are :class:`fsi_lab.modelling.BenchPhysics` built from the profile's
``[shaker]``, ``[specimen]`` and ``[model]`` (the true damping). They run at the digitiser rate, or
at an integer multiple of it when the fixed-step integrator needs smaller steps for the highest
mode; then the digitiser's anti-aliasing filter (:class:`~.frontends.Decimator`) brings the
signals down to its rate. At the digitiser rate itself every simulated signal is band-limited far
below 0.45 fs, where that filter is flat, so no filtering is needed.

Interlocks are checked on every sample of the amplifier output: input clip (source beyond
``amp_input_limit_v``), over-current (output voltage over the coil resistance beyond
``max_current_a``), over-travel (base displacement beyond ``stroke_mm``). A trip latches, and
the output is zero from the next sample on.
"""

from __future__ import annotations

import copy
import math
from typing import TYPE_CHECKING

import numpy as np

from fsi_lab.instruments.sim.frontends import Accelerometer, Decimator, Digitiser, Vibrometer
from fsi_lab.instruments.sim.rates import oversampling
from fsi_lab.modelling import BenchPhysics

if TYPE_CHECKING:  # pragma: no cover
    from fsi_lab.instruments.sim.bench import SimBench

#: The digitiser's inputs and what is wired to them.
WIRING = {1: "drive", 2: "base_acceleration", 3: "tip_velocity", 4: "spare"}
OVERLOAD_TRANSIENT_S = 1e-3


class World:
    """One record of the bench: produces digitiser codes block by block.

    Parameters
    ----------
    bench
        The bench whose instruments' settings drive the world (read live at every block).
    model
        The beam (:class:`fsi_lab.beam.BeamModel`).
    sample_rate
        Digitiser rate, Hz.
    inputs
        Enabled digitiser inputs, in the order their codes are returned.
    ranges
        Input range of each of ``inputs``, V.
    iepe
        Whether each of ``inputs`` powers an IEPE sensor.
    """

    def __init__(self, bench: "SimBench", model, sample_rate: float, inputs: list[int],
                 ranges: list[float], iepe: list[bool]) -> None:
        self.bench = bench
        opts = bench.options
        self.rate = float(sample_rate)
        self.factor = oversampling(model, self.rate)
        self.world_rate = self.rate * self.factor
        self.physics = BenchPhysics(model, bench.shaker, self.world_rate,
                                    bench.specimen.measurement_point)
        self.decimator = Decimator(self.factor, 3) if self.factor > 1 else None
        self.inputs = list(inputs)
        self.ranges = np.asarray(ranges, dtype=float)
        self.iepe = dict(zip(inputs, iepe))
        self.rng = np.random.default_rng(opts.seed)
        self.accelerometer = Accelerometer(self.rate, opts.accelerometer_mv_per_g)
        self.digitiser = Digitiser(self.rng)
        self._vibrometer_setting: tuple | None = None
        self.vibrometer: Vibrometer | None = None
        self.produced = 0       # digitiser samples
        self.world_done = 0     # world samples simulated
        self.overloads: dict[int, float] = {}  # input -> record time of its first overload
        self.max_displacement_m = 0.0
        stroke = opts.stroke_mm * 1e-3
        self._fault_offset_v = 1.5 * opts.stroke_mm / bench.shaker["mm_per_volt"]
        self._stroke_m = stroke

    @property
    def data_time(self) -> float:
        """Record time reached by the digitiser, s."""
        return self.produced / self.rate

    # ------------------------------------------------------------------ world rate
    def _advance(self, n: int) -> np.ndarray:
        """Simulate ``n`` world samples; rows drive (V), base acceleration, tip velocity."""
        start = self.world_done
        drive = self.bench.source.output_volts(start, n, self.world_rate)
        u = self._amplify(drive, start)
        motion = self.physics.advance(u)
        self.world_done += n
        self.max_displacement_m = max(self.max_displacement_m,
                                      float(np.max(np.abs(motion["base_displacement"]))))
        return np.vstack([drive, motion["base_acceleration"], motion["tip_velocity"]])

    def _amplify(self, drive: np.ndarray, start: int) -> np.ndarray:
        """Amplifier output voltage for the source voltage ``drive``; trips interlocks."""
        amp = self.bench.amplifier.state
        opts = self.bench.options
        n = drive.size
        if not amp.output_on or amp.latched:
            amp.current_rms_a = 0.0
            return np.zeros(n)
        u = drive * amp.gain
        fault_t = self.bench.faults.physical_time("interlock")
        if fault_t is not None:
            k0 = max(0, int(math.ceil(fault_t * self.world_rate)) - start)
            if k0 < n:
                u[k0:] += self._fault_offset_v
        trips: list[tuple[int, str]] = []
        for name, mask in (("input_clip", np.abs(drive) > opts.amp_input_limit_v),
                           ("over_current", np.abs(u) > opts.max_current_a * opts.coil_ohm)):
            if mask.any():
                trips.append((int(mask.argmax()), name))
        probe = copy.deepcopy(self.physics.shaker)
        displacement, _ = probe.advance(u)
        over = np.abs(displacement) > self._stroke_m
        if over.any():
            trips.append((int(over.argmax()), "over_travel"))
        if trips:
            first = min(k for k, _ in trips)
            u[first + 1:] = 0.0
            amp.trip({name for k, name in trips if k == first},
                     time_s=(start + first) / self.world_rate)
        amp.current_rms_a = float(np.sqrt(np.mean(u * u))) / opts.coil_ohm if n else 0.0
        return u

    # ------------------------------------------------------------------ digitiser rate
    def produce(self, n: int) -> np.ndarray:
        """The next ``n`` samples of the enabled inputs as 24-bit codes, (n, inputs) int32."""
        if n <= 0:
            return np.zeros((0, len(self.inputs)), dtype=np.int32)
        if self.decimator is None:
            drive, acc, vel = self._advance(n)
        else:
            needed = self.decimator.inputs_needed(self.produced + n) - self.world_done
            if needed > 0:
                self.decimator.push(self._advance(needed))
            drive, acc, vel = self.decimator.pull(n)
        volts = np.zeros((n, len(self.inputs)))
        signals = {
            "drive": lambda: drive,
            "base_acceleration": lambda: self.accelerometer.output(acc, self.iepe.get(2, False)),
            "tip_velocity": lambda: self._vibrometer().output(vel),
            "spare": lambda: np.zeros(n),
        }
        # every sensor runs on every block so that its filters stay continuous
        computed = {name: make() for name, make in signals.items()}
        for column, number in enumerate(self.inputs):
            volts[:, column] = computed[WIRING[number]]
        self._overload_fault(volts, n)
        codes, first = self.digitiser.codes(volts, self.ranges)
        for column, index in enumerate(first):
            number = self.inputs[column]
            if index >= 0 and number not in self.overloads:
                self.overloads[number] = (self.produced + int(index)) / self.rate
        self.produced += n
        return codes

    def _vibrometer(self) -> Vibrometer:
        head = self.bench.vibrometer.state
        setting = (head.range_name, head.delay_s)
        if setting != self._vibrometer_setting:
            self.vibrometer = Vibrometer(self.rate, head.range_name, head.delay_s, self.rng)
            self._vibrometer_setting = setting
        return self.vibrometer

    def _overload_fault(self, volts: np.ndarray, n: int) -> None:
        t = self.bench.faults.physical_time("overload")
        if t is None or 3 not in self.inputs:
            return
        column = self.inputs.index(3)
        first = int(math.ceil(t * self.rate))
        last = first + max(1, int(round(OVERLOAD_TRANSIENT_S * self.rate)))
        lo, hi = max(first, self.produced), min(last, self.produced + n)
        if lo < hi:
            volts[lo - self.produced:hi - self.produced, column] = 1.5 * self.ranges[column]
