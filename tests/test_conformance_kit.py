"""The conformance kit fails a sloppy plugin with messages that say what to fix, and runs as a
pytest plugin registered through the pytest11 entry point (as it does for a plugin author)."""

from importlib import metadata
from pathlib import Path

pytest_plugins = ["pytester"]

SLOPPY = Path(__file__).resolve().parent / "conformance" / "sloppy.py"

TESTS = '''
import pytest
from fsi_lab.testing import AnalysisContract, ExcitationContract, InstrumentContract
from sloppy import ANALYSIS, EXCITATION, INSTRUMENT


class TestSloppyPeak(AnalysisContract):
    plugin = ANALYSIS


class TestSloppySine(ExcitationContract):
    plugin = EXCITATION


class TestSloppyAmplifier(InstrumentContract):
    plugin = INSTRUMENT
    transport = "tcp"

    @pytest.fixture
    def address(self):
        return "TCPIP0::127.0.0.1::5025::SOCKET"
'''


def test_the_kit_is_a_pytest_plugin_of_the_pytest11_group():
    (found,) = [ep for ep in metadata.entry_points(group="pytest11") if ep.name == "fsi-lab"]
    assert found.value == "fsi_lab.testing.plugin" and found.dist.name == "fsi-lab"


def test_a_sloppy_plugin_fails_the_kit_saying_what_to_fix(pytester):
    pytester.makepyfile(sloppy=SLOPPY.read_text(), test_sloppy=TESTS)
    result = pytester.runpytest_subprocess("-q", "-p", "no:cacheprovider", "-W",
                                           "ignore::pytest.PytestAssertRewriteWarning")
    output = result.stdout.str()
    for sentence in (
            # the analysis
            "sloppy-peak: uses 'spectra', which no installed analysis provides (kinds provided: "
            "*); fix the kind's name, or install the analysis that provides it",
            "sloppy-peak: dataset 'level' has no unit: give it in units (units={'level': "
            "'m/s'}; '' for a dimensionless one)",
            "sloppy-peak: raised IndexError (index 0 is out of bounds for axis 0 with size 0) "
            "on an empty record (0 samples) of channel 'tip'; check the record first and raise "
            "fsi_lab.errors.AnalysisError naming the channel and the condition",
            "sloppy-peak: accepted a record of 3 samples of channel 'tip' and returned "
            "AnalysisResult; check the record and raise fsi_lab.errors.AnalysisError saying "
            "what it lacks *",
            "sloppy-peak: accepted a record holding NaN of channel 'tip' *",
            "sloppy-peak: writes into its input (output array is read-only); work on a copy, "
            "e.g. np.array(context.channel.data, dtype=float)",
            # the excitation
            "sloppy-sine: parameter 'amplitude' has no maximum: declare both bounds (Param(..., "
            "maximum=...)) so that a profile asking for more is refused before anything is sent",
            "sloppy-sine: parameter 'frequency' has no help: give Param(help=...)",
            "sloppy-sine: parameter 'frequency' (float) has no unit: give its SI unit (Param(..., "
            "unit='V')), or list it in the test class's dimensionless if it is a plain number",
            "sloppy-sine: gives different samples for the same parameters; derive any "
            "randomness from a seed parameter (np.random.default_rng(seed))",
            "sloppy-sine: its waveform with its defaults peaks at 1.5* V, beyond the 1 V its "
            "parameters allow (peak_limit)",
            # the driver
            "sloppy-amplifier: is not confirmed safe after safe_state(): driver "
            "'sloppy-amplifier': its state read back does not say that the output is off "
            "(read_state() gives no output_enabled; a driver of the amplifier role returns "
            "fsi_lab.contract.OutputState(output_enabled=<bool read from the instrument>))",
            "sloppy-amplifier: close() raised RuntimeError (already closed) the second time; "
            "it must not raise when already closed",
            "sloppy-amplifier: opened at TCPIP0::127.0.0.1::*::SOCKET, where nothing answers; "
            "ask the instrument who it is (identify) when opening, and fail with "
            "InstrumentError when it does not answer"):
        result.stdout.fnmatch_lines([f"*{sentence}*"])
    # what it does right passes: the constant record is refused, the frequency's bounds hold,
    # the driver is an Amplifier that identifies itself
    failed = {line.split(" ")[1] for line in output.splitlines() if line.startswith("FAILED ")}
    passing = {"TestSloppyPeak::test_refuses_a_bad_record_with_a_clear_error[constant]",
               "TestSloppySine::test_refuses_numbers_beyond_their_bounds[frequency-above]",
               "TestSloppyAmplifier::test_is_its_role_and_identifies_itself",
               "TestSloppyAmplifier::test_state_is_typed_and_stored_as_read"}
    failing = {"TestSloppyPeak::test_never_changes_its_input",
               "TestSloppySine::test_is_deterministic",
               "TestSloppyAmplifier::test_safe_state_is_confirmed"}
    assert not {f"test_sloppy.py::{name}" for name in passing} & failed
    assert {f"test_sloppy.py::{name}" for name in failing} <= failed
    assert "Traceback" not in output and "During handling" not in output  # no kit insides
    assert "ERROR" not in output
    outcomes = result.parseoutcomes()
    assert outcomes["failed"] >= 14 and outcomes["passed"] >= 8, outcomes


def test_a_plugin_the_kit_cannot_find_is_named_with_what_to_do(pytester):
    pytester.makepyfile(test_missing='''
from fsi_lab.testing import AnalysisContract, ExcitationContract

class TestMissing(AnalysisContract):
    plugin = "no-such-analysis"

class TestMissingExcitation(ExcitationContract):
    plugin = "no-such-excitation"
''')
    result = pytester.runpytest_subprocess("-q", "-p", "no:cacheprovider")
    result.stdout.fnmatch_lines([
        "*no-such-analysis: is not an installed analysis plugin (installed: *hvd*); install "
        "your distribution (pip install -e .) so that its entry point in the 'fsi_lab' group "
        "is found, or set plugin to the descriptor itself*",
        "*no-such-excitation: is not an installed excitation plugin*"])
    assert result.parseoutcomes()["failed"] >= 5
