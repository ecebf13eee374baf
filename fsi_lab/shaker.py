"""Linear model of the shaker armature on its suspension.

Base displacement x (m) responds to the amplifier output voltage u (V) as a second-order system
with static sensitivity ``k`` (m/V), natural frequency ``f_s`` and damping ratio ``zeta``::

    x'' + 2 zeta w_s x' + w_s^2 x = w_s^2 k u

It predicts the stroke for the safety check and produces the base motion of the simulated
bench and of ``fsi-lab simulate``. A step makes the base overshoot and ring at ``f_s``, as the
paper observed (about 30 Hz loaded, 47 Hz unloaded).

Both use the same discrete filters (:func:`discrete_filters`, the bilinear transform). The
bench's :class:`ShakerModel` runs them through :class:`fsi_lab.biquad.Biquads` (compiled with
numba, as the beam's integrator it feeds; the same numbers as ``scipy.signal.lfilter``, without
loading scipy.signal); the stroke prediction, which every ``fsi-lab profile check`` makes, runs
them through :func:`fsi_lab.lti.lfilter` and so loads neither.
"""

from __future__ import annotations

from typing import Iterable

import numpy as np

from fsi_lab import lti


def discrete_filters(sample_rate: float, suspension_hz: float, damping_ratio: float,
                     mm_per_volt: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """``(b, a)`` of the base displacement (m) and the base acceleration (m/s^2) per amplifier
    output volt, at ``sample_rate`` Hz (see :class:`ShakerModel` for the other parameters)."""
    w = 2 * np.pi * suspension_hz
    gain = w * w * mm_per_volt * 1e-3
    den = [1.0, 2 * damping_ratio * w, w * w]
    return [lti.bilinear(num, den, sample_rate) for num in ([gain], [gain, 0.0, 0.0])]


class ShakerModel:
    """Stateful discrete-time shaker: feed amplifier-output blocks, get base motion blocks.

    Parameters
    ----------
    sample_rate
        Rate of the input and output samples, Hz.
    suspension_hz
        Suspension resonance of the loaded shaker, Hz.
    damping_ratio
        Damping ratio of that resonance.
    mm_per_volt
        Static base displacement per volt at the amplifier output, mm/V.
    """

    def __init__(self, sample_rate: float, suspension_hz: float, damping_ratio: float,
                 mm_per_volt: float) -> None:
        from fsi_lab.biquad import Biquads  # compiled: the stroke prediction does without

        self._filters = Biquads(discrete_filters(sample_rate, suspension_hz, damping_ratio,
                                                 mm_per_volt))

    @classmethod
    def from_profile(cls, sample_rate: float, shaker: dict) -> "ShakerModel":
        """The model of a profile's ``[shaker]`` section."""
        return cls(sample_rate, shaker["suspension_hz"], shaker["damping_ratio"],
                   shaker["mm_per_volt"])

    def advance(self, amplifier_volts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Base displacement (m) and acceleration (m/s^2) for the next block of amplifier
        output voltage (V)."""
        out = self._filters.advance(np.asarray(amplifier_volts, dtype=float))
        return out[0], out[1]


def predicted_stroke_mm(drive: np.ndarray, sample_rate: float, gain: float,
                        shaker: dict) -> float:
    """Largest absolute base displacement, mm, for a source waveform.

    Parameters
    ----------
    drive
        Source voltage, V, at ``sample_rate`` Hz, as it reaches the amplifier (the model
        sees only these samples: see :mod:`fsi_lab.safety` for the output between them).
    gain
        Amplifier voltage gain, V/V.
    shaker
        A profile's ``[shaker]`` values.

    The drive is followed by five suspension periods at 0 V so that overshoot after the drive
    ends is included.
    """
    return stroke_of_blocks_mm([np.asarray(drive, dtype=float)], sample_rate, gain, shaker)


def stroke_of_blocks_mm(blocks: Iterable[np.ndarray], sample_rate: float, gain: float,
                        shaker: dict, rest_v: float = 0.0) -> float:
    """:func:`predicted_stroke_mm` of a drive given as consecutive blocks (V at
    ``sample_rate`` Hz), so that a long drive need not be held in memory at once, followed by
    ``rest_v`` (V) held for five suspension periods (where the source rests after it)."""
    (b, a), _ = discrete_filters(sample_rate, shaker["suspension_hz"], shaker["damping_ratio"],
                                 shaker["mm_per_volt"])
    state = np.zeros(2)
    largest, samples = 0.0, 0
    for block in blocks:
        displacement, state = lti.lfilter(b, a, np.asarray(block, dtype=float) * gain, state)
        if displacement.size:
            largest = max(largest, float(np.max(np.abs(displacement))))
        samples += displacement.size
    if samples == 0:
        return 0.0
    rest = np.full(int(np.ceil(5 * sample_rate / shaker["suspension_hz"])), rest_v * gain)
    tail, _ = lti.lfilter(b, a, rest, state)
    return max(largest, float(np.max(np.abs(tail)))) * 1e3
