"""The simulated generator driven by the instrument libraries labs already use: PyMeasure's
``Agilent33500`` and QCoDeS's ``Keysight33522B`` drivers (test-only dependencies), through
pyvisa-py on a 127.0.0.1 socket. Every property they offer is read, settings are written, an
arb is uploaded, and the instrument's error queue must stay empty."""

import numpy as np
import pytest
from benchkit import sim_bench

pymeasure = pytest.importorskip("pymeasure", reason="the dev extra installs pymeasure")
qcodes = pytest.importorskip("qcodes", reason="the dev extra installs qcodes")


def _properties(obj) -> list[str]:
    """Names of the readable instrument properties of a PyMeasure instrument or channel."""
    names = []
    for name in dir(type(obj)):
        attribute = getattr(type(obj), name, None)
        if isinstance(attribute, property) and attribute.fget is not None \
                and not name.startswith("_"):
            names.append(name)
    return names


def _no_errors(read_error) -> list[str]:
    errors = []
    for _ in range(25):
        reply = read_error()
        if reply.startswith(("+0,", "0,")):
            return errors
        errors.append(reply)
    return errors


@pytest.fixture
def pymeasure_generator(sim_bench):
    from pymeasure.instruments.agilent import Agilent33500

    bench = sim_bench()
    generator = Agilent33500(bench.addresses["source"], visa_library="@py", timeout=2000,
                             read_termination="\n", write_termination="\n")
    yield bench, generator
    generator.adapter.close()


def test_pymeasure_reads_every_property_with_no_instrument_error(pymeasure_generator):
    bench, generator = pymeasure_generator
    read = {}
    for target in (generator, generator.ch_1, generator.ch_2):
        for name in _properties(target):
            try:
                read[(id(target), name)] = getattr(target, name)
            except LookupError:  # a write-only setting (PyMeasure raises for those)
                continue
    assert len(read) > 60
    assert generator.id.startswith("Keysight Technologies,33522B,SIMULATED")
    assert generator.ch_1.output is False and generator.ch_2.shape == "SIN"
    assert generator.next_error[0] == 0
    assert _no_errors(lambda: generator.ask("SYST:ERR?").strip()) == []


def test_pymeasure_sets_an_arb_burst_and_triggers_it(pymeasure_generator):
    bench, generator = pymeasure_generator
    channel = generator.ch_1
    channel.data_volatile_clear()
    ramp = list(range(-16000, 16000, 500))
    channel.data_arb("RAMPDAC", ramp, data_format="DAC")
    channel.data_arb("RAMPFLT", np.linspace(-1, 1, 50).round(4).tolist(), data_format="float")
    channel.arb_file = "RAMPDAC"
    channel.shape = "ARB"
    channel.arb_srate = 1e4
    channel.arb_filter = "STEP"
    channel.amplitude_unit = "VPP"
    channel.amplitude = 0.5
    channel.offset = 0.1
    channel.phase = 90
    channel.burst_state = True
    channel.burst_mode = "TRIGGERED"
    channel.burst_ncycles = 3
    generator.trigger_source = "BUS"
    generator.ext_trig_out = True
    channel.output = True
    generator.trigger()
    assert generator.complete == "1"
    assert channel.arb_file.strip('"') == "RAMPDAC"
    assert (channel.amplitude, channel.offset, channel.burst_ncycles) == (0.5, 0.1, 3)
    assert channel.voltage_high == pytest.approx(0.35)
    assert _no_errors(lambda: generator.ask("SYST:ERR?").strip()) == []
    stored = bench.source.state_of(1).arbs
    assert np.allclose(stored["RAMPDAC"] * 32767, ramp)
    assert stored["RAMPFLT"].size == 50
    # the real instrument refuses a name already in memory
    channel.data_arb("RAMPDAC", ramp, data_format="DAC")
    assert generator.ask("SYST:ERR?").startswith('-221,"Settings conflict; arb \'RAMPDAC\'')


@pytest.fixture
def qcodes_generator(sim_bench):
    from qcodes.instrument import Instrument
    from qcodes.instrument_drivers.Keysight import Keysight33522B

    bench = sim_bench()
    generator = Keysight33522B("fsilab_sim_33522b", bench.addresses["source"], visalib="@py",
                               timeout=2, terminator="\n", silent=True)
    yield bench, generator
    generator.close()
    Instrument.close_all()


def test_qcodes_takes_a_full_snapshot_and_uploads_an_arb_with_no_instrument_error(
        qcodes_generator):
    bench, generator = qcodes_generator
    snapshot = generator.snapshot(update=True)
    values = {f"{module}.{name}": p.get("value")
              for module in ("ch1", "ch2", "sync")
              for name, p in snapshot["submodules"][module]["parameters"].items()}
    missing = sorted(name for name, value in values.items() if value is None)
    assert not missing, missing
    assert len(values) >= 40
    assert generator.IDN()["model"] == "33522B"
    assert generator.IDN()["serial"] == "SIMULATED01"
    assert generator.error() == (0, "No error")
    generator.ch2.burst_ncycles("INF")
    generator.ch2.trigger_count(5)
    generator.ch2.output_polarity("INV")
    generator.sync.source(2)
    assert generator.ch2.burst_ncycles() == float("inf")
    assert (generator.ch2.trigger_count(), generator.sync.source()) == (5, 2)
    generator.write("FORM:BORD SWAP")
    points = np.sin(np.linspace(0, 2 * np.pi, 1000, endpoint=False))
    generator.visa_handle.write_binary_values("SOUR2:DATA:ARB QSINE,", points, datatype="f",
                                              is_big_endian=False)
    generator.write("SOUR2:FUNC:ARB QSINE")
    generator.ch2.function_type("ARB")
    assert generator.ch2.function_type() == "ARB"
    assert generator.ask("SOUR2:FUNC:ARB:POIN?") == "1000"
    assert generator.error() == (0, "No error")
    assert np.allclose(bench.source.state_of(2).arbs["QSINE"], points, atol=1 / 32767)
