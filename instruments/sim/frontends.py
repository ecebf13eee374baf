"""Sensors and the digitiser's input stage of the simulated bench, block by block.

Each class is stateful (filters and delay lines carry over from block to block) and works at
the digitiser's sample rate unless stated otherwise.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import signal

from fsi_lab.instruments.sim.specs import (
    ADC_BITS,
    VIBROMETER_OUTPUT_V,
    VIBROMETER_RANGES,
    volts_per_code,
)
from fsi_lab.units import STANDARD_GRAVITY

#: RMS input noise of the digitiser as a fraction of the range (-114 dB of full scale).
ADC_NOISE_FRACTION = 2.0 ** -19
#: -3 dB corner of the AC coupling of an IEPE input (first order), Hz.
IEPE_HIGHPASS_HZ = 0.1


class DelayLine:
    """Delays a signal by ``delay`` samples (fractional part by linear interpolation).

    The signal is taken as zero before the first block (the bench starts at rest).
    """

    def __init__(self, delay: float) -> None:
        if delay < 0:
            raise ValueError(f"delay {delay} samples: expected >= 0")
        self.whole = int(math.floor(delay))
        self.fraction = float(delay - self.whole)
        self._history = np.zeros(self.whole + 1)

    def __call__(self, x: np.ndarray) -> np.ndarray:
        full = np.concatenate([self._history, x])
        h = self._history.size
        n = x.size
        # y[k] = x[k - whole - fraction], with x[k - whole] at full[h + k - whole]
        current = full[h - self.whole:h - self.whole + n]
        previous = full[h - self.whole - 1:h - self.whole - 1 + n]
        self._history = full[full.size - h:]
        return (1.0 - self.fraction) * current + self.fraction * previous


class Vibrometer:
    """Laser vibrometer: signal delay, range (sensitivity), noise and output clipping.

    Parameters
    ----------
    sample_rate
        Digitiser rate, Hz.
    range_name
        One of :data:`VIBROMETER_RANGES`.
    delay_s
        Signal delay of the sensor and decoder, s.
    rng
        Noise generator.
    """

    def __init__(self, sample_rate: float, range_name: str, delay_s: float,
                 rng: np.random.Generator) -> None:
        self.metres_per_volt, density = VIBROMETER_RANGES[range_name]
        self.noise_rms = density * math.sqrt(sample_rate / 2.0)  # m/s
        self._delay = DelayLine(delay_s * sample_rate)
        self._rng = rng

    def output(self, velocity: np.ndarray) -> np.ndarray:
        """Analogue output voltage for the absolute velocity (m/s) at the measuring point."""
        v = self._delay(velocity) + self.noise_rms * self._rng.standard_normal(velocity.size)
        return np.clip(v / self.metres_per_volt, -VIBROMETER_OUTPUT_V, VIBROMETER_OUTPUT_V)


class Accelerometer:
    """IEPE accelerometer on a digitiser input: no signal unless the input powers it (IEPE on),
    then ``mv_per_g`` times the acceleration through the input's AC coupling."""

    def __init__(self, sample_rate: float, mv_per_g: float) -> None:
        self.volts_per_ms2 = mv_per_g * 1e-3 / STANDARD_GRAVITY
        b, a = signal.butter(1, IEPE_HIGHPASS_HZ, "highpass", fs=sample_rate)
        self._b, self._a = b, a
        self._zi = np.zeros(1)

    def output(self, acceleration: np.ndarray, powered: bool) -> np.ndarray:
        """Voltage at the input for the base acceleration (m/s^2)."""
        if not powered:
            self._zi[:] = 0.0
            return np.zeros(acceleration.size)
        y, self._zi = signal.lfilter(self._b, self._a, acceleration * self.volts_per_ms2,
                                     zi=self._zi)
        return y


class Digitiser:
    """Input stage and ADC: noise, overload detection, clipping, 24-bit quantisation.

    ``codes(volts, ranges)`` returns int32 codes; ``scale(range)`` the volts per code.
    """

    FULL_SCALE = 2 ** (ADC_BITS - 1)

    def __init__(self, rng: np.random.Generator) -> None:
        self._rng = rng

    @classmethod
    def scale(cls, range_v: float) -> float:
        """Volts per code on an input of ``range_v``."""
        return volts_per_code(range_v)

    def codes(self, volts: np.ndarray, ranges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Quantise ``volts`` (n_samples, n_inputs) on inputs of ``ranges`` (n_inputs,).

        Returns the codes (int32, same shape) and, per input, the index of the first sample
        beyond the range (-1 if none).
        """
        noisy = volts + (ADC_NOISE_FRACTION * ranges) * self._rng.standard_normal(
            volts.shape, dtype=np.float32)
        over = np.abs(noisy) > ranges
        first = np.where(over.any(axis=0), over.argmax(axis=0), -1)
        full = self.FULL_SCALE
        codes = np.rint(noisy * (full / ranges))
        np.clip(codes, -full, full - 1, out=codes)
        return codes.astype(np.int32), first


class Decimator:
    """Anti-aliasing filter and decimation by ``factor`` for signals simulated at a higher rate.

    A linear-phase FIR low-pass (Kaiser window) flat to 0.45 of the output rate; its delay is
    compensated, as a dynamic signal analyser does, by reading the input ahead: output sample k
    is centred on input sample ``k * factor``. The input is taken as zero before the start.
    """

    def __init__(self, factor: int, channels: int, taps_per_side: int = 16) -> None:
        self.factor = int(factor)
        numtaps = 2 * taps_per_side * self.factor + 1
        self.h = signal.firwin(numtaps, 0.9 / self.factor, window=("kaiser", 8.0))
        self.lookahead = (numtaps - 1) // 2
        self._buffer = np.zeros((channels, self.lookahead))  # starts at input index -lookahead
        self._base = -self.lookahead
        self._next = 0

    def inputs_needed(self, outputs: int) -> int:
        """Input samples (from index 0) needed to emit ``outputs`` output samples in total."""
        return (outputs - 1) * self.factor + self.lookahead + 1 if outputs > 0 else 0

    def push(self, block: np.ndarray) -> None:
        """Append input samples, shape (channels, n)."""
        self._buffer = np.concatenate([self._buffer, block], axis=1)

    def pull(self, n: int) -> np.ndarray:
        """The next ``n`` output samples, shape (channels, n)."""
        start = self._next * self.factor - self.lookahead - self._base
        windows = np.lib.stride_tricks.sliding_window_view(self._buffer, self.h.size, axis=1)
        out = windows[:, start:start + n * self.factor:self.factor, :] @ self.h
        self._next += n
        keep_from = self._next * self.factor - self.lookahead - self._base
        self._buffer = self._buffer[:, keep_from:]
        self._base += keep_from
        return out
