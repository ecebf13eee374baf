"""Linear model of the shaker armature on its suspension, used to predict the stroke.

Base displacement x (m) responds to the amplifier output voltage u (V) as a second-order
system with static sensitivity ``k`` (m/V), natural frequency ``f_s`` and damping ratio
``zeta``:  x'' + 2 zeta w_s x' + w_s^2 x = w_s^2 k u.
"""

from __future__ import annotations

import numpy as np
from scipy import signal


def base_displacement(drive: np.ndarray, sample_rate: float, gain: float,
                      suspension_hz: float, damping_ratio: float, mm_per_volt: float) -> np.ndarray:
    """Base displacement (m) produced by a source waveform through amplifier and shaker.

    Parameters
    ----------
    drive
        Source voltage samples, V.
    sample_rate
        Rate of ``drive``, Hz.
    gain
        Amplifier voltage gain, V/V.
    suspension_hz
        Suspension resonance of the loaded shaker, Hz.
    damping_ratio
        Damping ratio of that resonance.
    mm_per_volt
        Static displacement per volt at the amplifier output, mm/V.

    Returns
    -------
    numpy.ndarray
        Displacement of the base, m, same length as ``drive`` followed by a free ring-down of
        five suspension periods (so that overshoot after the drive ends is included).
    """
    w = 2 * np.pi * suspension_hz
    tail = int(np.ceil(5 * sample_rate / suspension_hz))
    u = np.concatenate([np.asarray(drive, float) * gain, np.zeros(tail)])
    system = signal.cont2discrete(([w * w * mm_per_volt * 1e-3], [1.0, 2 * damping_ratio * w, w * w]),
                                  1.0 / sample_rate, method="bilinear")
    b, a = np.ravel(system[0]), np.ravel(system[1])
    return signal.lfilter(b, a, u)


def predicted_stroke_mm(drive: np.ndarray, sample_rate: float, gain: float,
                        shaker: dict) -> float:
    """Largest absolute base displacement, mm, predicted for ``drive`` (see the module doc)."""
    x = base_displacement(drive, sample_rate, gain, shaker["suspension_hz"],
                          shaker["damping_ratio"], shaker["mm_per_volt"])
    return float(np.max(np.abs(x))) * 1e3 if x.size else 0.0
