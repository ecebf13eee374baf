"""A deliberately sloppy third-party plugin: an analysis, an excitation and an amplifier driver
that each break the contract in the ways authors do. tests/test_conformance_kit.py runs the
conformance kit on them (with pytester) and checks that each failure tells the author what to
fix. Not a plugin anyone should install."""

import numpy as np

from fsi_lab.contract import (
    Amplifier,
    AnalysisPlugin,
    AnalysisResult,
    ExcitationPlugin,
    InstrumentPlugin,
)
from fsi_lab.errors import AnalysisError
from fsi_lab.params import Param


def _peak(context, params):
    data = context.channel.data
    data -= data.mean()                      # changes the caller's record
    first = data[0]                          # IndexError on an empty record
    if np.ptp(data) == 0:
        raise AnalysisError(f"sloppy-peak: channel {context.channel.name} is constant")
    level = np.abs(data)
    return AnalysisResult(datasets={"level": level},   # no unit given
                          attrs={"first": float(first)}, summary={"peak": float(level.max())})


ANALYSIS = AnalysisPlugin("sloppy-peak", (), _peak, uses=("spectra",),   # a misspelt kind
                          help="Peak of the record.")


def _sine(params, rate):
    t = np.arange(int(params["duration"] * rate)) / rate
    wave = params["amplitude"] * np.sin(2 * np.pi * params["frequency"] * t)
    return wave + 0.5 + 0.01 * np.random.random(t.size)   # an offset, and unseeded noise


EXCITATION = ExcitationPlugin(
    "sloppy-sine",
    (Param("amplitude", "float", "V", 1.0, minimum=0.0, help="Peak voltage."),   # no maximum
     Param("frequency", "float", "", 10.0, minimum=0.1, maximum=1000.0),       # no unit, help
     Param("duration", "float", "s", 1.0, minimum=0.1, maximum=10.0, help="Length.")),
    _sine, help="A sine.", duration=lambda p: p["duration"])


class SloppyAmplifier(Amplifier):
    """Talks to nothing: opens anywhere, and forgets what the runner needs."""

    def __init__(self):
        self.closed = False
        self.gain = 0.0

    def identify(self):
        return "Sloppy,AMP-1,0001,1.0"

    def safe_state(self):
        self.gain = 0.0

    def read_state(self):
        return {"gain": self.gain}             # no output_enabled: not confirmed safe

    def set_gain(self, gain):
        self.gain = gain

    def enable_output(self, enabled):
        pass

    def interlocks(self):
        return {}

    def close(self):
        if self.closed:
            raise RuntimeError("already closed")
        self.closed = True


INSTRUMENT = InstrumentPlugin(
    "sloppy-amplifier", "amplifier",
    (Param("gain", "float", "V/V", 1.0, minimum=0.0, maximum=10.0, help="Gain."),),
    lambda address, settings, bench: SloppyAmplifier(), help="An amplifier driver.")
