"""Parameters and time base shared by the excitation plugins."""

from __future__ import annotations

import numpy as np

from fsi_lab.params import Param

DELAY = Param("delay", "float", "s", 0.1, minimum=0.0, maximum=60.0,
              help="Time at zero volts before the excitation starts.")
DURATION = Param("duration", "float", "s", 1.0, minimum=0.0, exclusive_minimum=True,
                 maximum=3600.0, help="Length of the waveform sent to the source.")


def time_axis(duration: float, sample_rate: float) -> np.ndarray:
    """Sample times 0, 1/rate, ... up to (not including) ``duration``, s."""
    return np.arange(int(round(duration * sample_rate))) / sample_rate
