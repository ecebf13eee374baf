"""fsi-lab's own plugins pass the conformance kit (fsi_lab.testing), as a third party's must.

Each class is what a plugin author writes: the contract class, the plugin's name, and what the
plugin needs (a record, parameters, an instrument to talk to). The drivers of real instruments
are tested against the simulated bench, which answers on loopback sockets and pseudo-terminals.
"""

import numpy as np
import pytest

from fsi_lab.contract import ChannelData
from fsi_lab.instruments.sim.bench import BenchOptions, SimBench
from fsi_lab.specimen import Specimen
from fsi_lab.testing import (
    AnalysisContract,
    ExcitationContract,
    InstrumentContract,
    two_decaying_modes,
)


# ----------------------------------------------------------------------------- analyses
class TestSpectrum(AnalysisContract):
    plugin = "spectrum"


class TestHvd(AnalysisContract):
    plugin = "hvd"


class TestIntegrate(AnalysisContract):
    plugin = "integrate"
    before = ("hvd",)


class TestInstantaneous(AnalysisContract):
    plugin = "instantaneous"
    before = ("hvd", "integrate")


class TestBackbone(AnalysisContract):
    plugin = "backbone"
    before = ("hvd", "integrate")


class TestDamping(AnalysisContract):
    plugin = "damping"
    before = ("hvd", "integrate")


class TestEquivalentDamping(AnalysisContract):
    plugin = "equivalent-damping"
    before = ("hvd", "integrate", "damping")


class TestModalModel(AnalysisContract):
    """The beam model against a record: the wet beam of the demo profile (mu + M from it)."""

    plugin = "modal-model"
    before = ("hvd", "integrate", "damping", "equivalent-damping")
    mass_per_length = None
    params = {"c_i": 0.65, "c_f": 33.0}  # the kit's decays are linear: no C_f of their own

    @property
    def specimen(self):
        return Specimen.from_mapping({"fluid": "water"}, "contract")


class TestFrf(AnalysisContract):
    """The FRF needs a response to a broadband base motion: a resonance at 30 Hz driven by
    white base acceleration."""

    plugin = "frf"

    def channels(self):
        from scipy import signal

        rate, seconds = 1000.0, 20.0
        base = 0.1 * np.random.default_rng(2).standard_normal(int(rate * seconds))
        b, a = signal.iirpeak(30.0, 20.0, fs=rate)
        tip = signal.lfilter(b, a, base) * 0.01
        return {"tip": ChannelData("tip", tip, rate, "velocity", "m/s"),
                "base": ChannelData("base", base, rate, "acceleration", "m/s^2")}


def test_the_kits_good_record_is_what_the_chain_analyses():
    """The kit's record is a velocity channel with a base reference, as a run gives."""
    channels = two_decaying_modes()
    assert channels["tip"].quantity == "velocity" and channels["base"].quantity == "acceleration"
    assert channels["tip"].data.size == 8000 and channels["tip"].sample_rate == 2000.0


# ----------------------------------------------------------------------------- excitations
class TestStep(ExcitationContract):
    plugin = "step"


class TestRampDerivative(ExcitationContract):
    plugin = "ramp-derivative"

    def peak_limit(self, params):  # a pulse of the ramp's height over its duration
        return abs(params["height"]) / params["ramp_duration"]


class TestImpulseTrain(ExcitationContract):
    plugin = "impulse-train"
    dimensionless = ("count",)


class TestRandom(ExcitationContract):
    plugin = "random"
    dimensionless = ("seed",)

    def peak_limit(self, params):  # its help: "its peak is about 4 times" its RMS
        return 5.0 * params["rms"]


# ----------------------------------------------------------------------------- instruments
@pytest.fixture(scope="module")
def bench():
    """The simulated bench: the lab drivers talk to it over real sockets and a pty."""
    started = SimBench(options=BenchOptions(fast=True)).start()
    yield started
    started.stop()


class TestInprocessSource(InstrumentContract):
    plugin = "inprocess-source"

    @pytest.fixture
    def address(self):
        return ""


class TestInprocessAmplifier(TestInprocessSource):
    plugin = "inprocess-amplifier"


class TestInprocessVibrometer(TestInprocessSource):
    plugin = "inprocess-vibrometer"


class TestInprocessAcquisition(TestInprocessSource):
    plugin = "inprocess-acquisition"


class TestKeysight33500(InstrumentContract):
    plugin = "keysight33500"
    transport = "tcp"

    @pytest.fixture
    def address(self, bench):
        return bench.addresses["source"]


class TestShakerAmplifier(InstrumentContract):
    plugin = "shaker-amplifier"
    transport = "tcp"
    settings = {"gain": 1.0}

    @pytest.fixture
    def address(self, bench):
        return bench.addresses["amplifier"]


class TestScpiDaq(InstrumentContract):
    plugin = "scpi-daq"
    transport = "tcp"

    @pytest.fixture
    def address(self, bench):
        return bench.addresses["acquisition"]


class TestPolytec(InstrumentContract):
    plugin = "polytec"
    transport = "serial"

    @pytest.fixture
    def address(self, bench):
        return bench.addresses["vibrometer"]
