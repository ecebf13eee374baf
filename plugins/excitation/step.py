"""Step excitation: the source rises to ``amplitude`` over ``rise_time`` and holds it."""

from __future__ import annotations

import numpy as np

from fsi_lab.contract import ExcitationPlugin
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param
from fsi_lab.plugins.excitation._timebase import DELAY, DURATION, time_axis


def step(amplitude: float, rise_time: float, delay: float, duration: float,
         sample_rate: float) -> np.ndarray:
    """Step of ``amplitude`` V with a linear rise over ``rise_time`` s after ``delay`` s.

    Returns the source voltage sampled at ``sample_rate`` Hz for ``duration`` s.
    """
    t = time_axis(duration, sample_rate)
    if rise_time <= 0:
        return np.where(t >= delay, amplitude, 0.0)
    return amplitude * np.clip((t - delay) / rise_time, 0.0, 1.0)


PLUGIN = ExcitationPlugin(
    name="step",
    params=(
        Param("amplitude", "float", "V", 0.5, minimum=-10.0, maximum=10.0,
              help="Source voltage after the rise."),
        Param("rise_time", "float", "s", 0.001, minimum=0.0, maximum=10.0,
              help="Duration of the linear rise (0 for an ideal step)."),
        DELAY, DURATION,
    ),
    generate=lambda p, rate: step(p["amplitude"], p["rise_time"], p["delay"], p["duration"], rate),
    help="A step of the source voltage; the shaker base overshoots and rings on its suspension.",
    duration=lambda p: p["duration"],
)


@hookimpl
def fsi_lab_excitations():
    return [PLUGIN]
