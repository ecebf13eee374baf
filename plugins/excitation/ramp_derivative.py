"""Derivative of a ramp: a rectangular pulse whose area is the ramp's height."""

from __future__ import annotations

import numpy as np

from fsi_lab.contract import ExcitationPlugin
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param
from fsi_lab.plugins.excitation._timebase import DELAY, DURATION, time_axis


def ramp_derivative(height: float, ramp_duration: float, delay: float, duration: float,
                    sample_rate: float) -> np.ndarray:
    """Rectangular pulse of ``height / ramp_duration`` V lasting ``ramp_duration`` s.

    It is the time derivative of a ramp that climbs ``height`` V·s over ``ramp_duration`` s,
    starting ``delay`` s into a record of ``duration`` s sampled at ``sample_rate`` Hz.
    """
    t = time_axis(duration, sample_rate)
    level = height / ramp_duration
    return np.where((t >= delay) & (t < delay + ramp_duration), level, 0.0)


PLUGIN = ExcitationPlugin(
    name="ramp-derivative",
    params=(
        Param("height", "float", "V*s", 0.01, minimum=-10.0, maximum=10.0,
              help="Height of the ramp whose derivative is sent (pulse area)."),
        Param("ramp_duration", "float", "s", 0.02, minimum=0.0, exclusive_minimum=True,
              maximum=10.0, help="Duration of the ramp, i.e. width of the pulse."),
        DELAY, DURATION,
    ),
    generate=lambda p, rate: ramp_derivative(p["height"], p["ramp_duration"], p["delay"],
                                             p["duration"], rate),
    help="The derivative of a ramp (a rectangular pulse); excites the second wet mode strongly.",
    duration=lambda p: p["duration"],
)


@hookimpl
def fsi_lab_excitations():
    return [PLUGIN]
