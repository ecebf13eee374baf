"""The files ``fsi-lab plugin new`` writes, per kind (``$name``-style placeholders filled by
:func:`files`)."""

from __future__ import annotations

from string import Template

PYPROJECT = '''\
[build-system]
requires = ["setuptools>=68"]
build-backend = "setuptools.build_meta"

[project]
name = "fsi-lab-$name"
version = "0.1.0"
description = "$summary"
readme = "README.md"
requires-python = ">=3.11"
dependencies = ["fsi-lab"]

[project.optional-dependencies]
test = ["pytest>=8"]

# fsi-lab finds its plugins through this entry-point group, as it finds its own.
[project.entry-points.fsi_lab]
$name = "$package.plugin"

[tool.setuptools]
packages = ["$package"]

[tool.pytest.ini_options]
testpaths = ["tests"]

# fsi-lab's own rule set; fsi-lab is a library this plugin uses, the plugin's package its own.
[tool.ruff]
line-length = 100

[tool.ruff.lint]
select = ["E", "W", "F", "I", "N", "BLE"]

[tool.ruff.lint.isort]
known-first-party = ["$package"]
known-third-party = ["fsi_lab"]
'''

README = '''\
# fsi-lab-$name

$summary

$article $kind plugin for fsi-lab, written from `fsi-lab plugin new $kind $name`.

## Install

    pip install -e '.[test]'

into the environment where fsi-lab is installed (`test` brings pytest). `fsi-lab plugins` then
lists `$name` as `loaded` (or says why it is not).

## Test

    python -m pytest

runs fsi-lab's conformance kit on the plugin (`tests/test_$under.py`: the contract every
$kind plugin keeps, from `fsi_lab.testing`) and the plugin's own tests. Keep both passing as
you change it: each failure of the kit says what to fix.

## Use

$use

## Change it

$change
'''

ANALYSIS_USE = '''\
Name it in a profile's chain (`[analysis] chain = ["$name"]`, its parameters in
`[analysis.$name]`), or analyse a run file again with it:

    fsi-lab analyze RUN.h5 --set analysis.chain=$name --set analysis.$name.window=0.2

Its values are in the JSON summary (`fsi-lab analyze RUN.h5 --json`: `channels.<channel>.$under`)
and in the text summary; `fsi-lab gui RUN.h5 --view $name` draws its datasets (`rms` against
`time`, with their units) in a tab of its own.'''

ANALYSIS_CHANGE = '''\
- `$package/plugin.py` declares the analysis: its name, its parameters (each with its unit,
  bounds and help), what it requires from earlier analyses (`requires`, by result kind: e.g.
  `fsi_lab.plugins.analysis.results.Components` for hvd's decomposition) and what it provides.
  fsi-lab imports it whenever it lists plugins: keep it light.
- `$package/_compute.py` does the work, imported when the chain first runs it: it receives the
  channel (`context.channel`: data in `unit` at `sample_rate` Hz) and the parameters, refuses
  what it cannot analyse with `AnalysisError`, and returns what the run file keeps: datasets
  with their units (and `axes`: what each is drawn against), scalar attributes, and the JSON
  summary. Never write into `context.channel.data`.
- docs/writing-plugins.md of fsi-lab is the full tutorial.'''

ANALYSIS_PLUGIN = '''\
"""The ``$name`` analysis.

The RMS of the channel in windows of ``window`` s, and of the whole record.

This module declares the plugin; the work is in :mod:`._compute`, imported when the chain first
runs it (fsi-lab imports this module whenever it lists the plugins or checks a profile, so it
stays light: no scipy, no numba here).
"""

from fsi_lab.contract import AnalysisPlugin, Deferred
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param

PLUGIN = AnalysisPlugin(
    name="$name",
    params=(Param("window", "float", "s", 0.1, minimum=0.001, maximum=60.0,
                  help="Length of each window the RMS is taken over."),),
    run=Deferred("$package._compute:run"),
    help="RMS of the channel in windows of a given length, and of the whole record.",
    # requires=(Components,) would ask for hvd's decomposition before it (a result kind of
    # fsi_lab.plugins.analysis.results); provides=MyResult would hand a typed result on.
)


@hookimpl
def fsi_lab_analyses():
    return [PLUGIN]
'''

ANALYSIS_COMPUTE = '''\
"""The work of the ``$name`` analysis."""

import numpy as np
from fsi_lab.contract import AnalysisResult
from fsi_lab.errors import AnalysisError


def run(context, params):
    """RMS of ``context.channel`` in consecutive windows of ``params["window"]`` s.

    Parameters
    ----------
    context
        fsi_lab.contract.AnalysisContext: the channel (data in its unit, sample_rate in Hz).
    params
        Validated parameters: ``window`` (s).

    Returns
    -------
    AnalysisResult
        Datasets ``time`` (s, the middle of each window) and ``rms`` (the channel's unit),
        attributes ``overall_rms`` and ``windows``, and the summary's section named
        ``$under``.

    Raises
    ------
    AnalysisError
        A record shorter than two windows, holding NaN or infinite samples, or constant.
    """
    channel = context.channel
    x = np.asarray(channel.data, dtype=float)  # the record itself: read it, never write it
    size = round(params["window"] * channel.sample_rate)
    where = f"$name: channel {channel.name}"
    if size < 1:
        raise AnalysisError(f"{where}: a window of {params['window']:g} s is shorter than a "
                            f"sample at {channel.sample_rate:g} Hz; lengthen window")
    if x.size < 2 * size:
        raise AnalysisError(f"{where}: {x.size} samples; need at least two windows of {size} "
                            "samples (give a longer record or a shorter window)")
    if not np.all(np.isfinite(x)):
        raise AnalysisError(f"{where}: holds NaN or infinite samples")
    if np.ptp(x) == 0:
        raise AnalysisError(f"{where}: the record is constant ({x[0]:g} {channel.unit}): "
                            "nothing moves")
    count = x.size // size
    rms = np.sqrt(np.mean(x[:count * size].reshape(count, size) ** 2, axis=1))
    time = channel.t0 + (np.arange(count) + 0.5) * size / channel.sample_rate
    overall = float(np.sqrt(np.mean(x ** 2)))
    return AnalysisResult(
        datasets={"time": time, "rms": rms},
        units={"time": "s", "rms": channel.unit},
        axes={"rms": "time"},
        attrs={"overall_rms": overall, "windows": count},
        summary={"$under": {"overall_rms": overall,
                            "largest_window_rms": float(rms.max())}})
'''

ANALYSIS_TEST = '''\
"""Tests of the ``$name`` analysis.

fsi-lab's conformance kit, and its numbers against ground truth.
"""

import numpy as np
from fsi_lab.contract import AnalysisContext, ChannelData
from fsi_lab.testing import AnalysisContract

from $package._compute import run


class TestContract(AnalysisContract):
    """Declarations, results with units, bad records refused, input left unchanged."""

    plugin = "$name"


def test_the_rms_of_a_sine_is_its_amplitude_over_root_two():
    rate = 1000.0
    t = np.arange(2000) / rate
    channel = ChannelData("tip", 0.3 * np.sin(2 * np.pi * 10.0 * t), rate, "velocity", "m/s")
    result = run(AnalysisContext(channel, {"tip": channel}, {}), {"window": 0.1})
    # each 0.1 s window holds one whole period: exact to rounding
    np.testing.assert_allclose(result.datasets["rms"], 0.3 / np.sqrt(2), rtol=1e-12)
    np.testing.assert_allclose(result.datasets["time"], 0.05 + 0.1 * np.arange(20))
    assert result.attrs["windows"] == 20
'''

EXCITATION_USE = '''\
Name it in a profile (`[excitation] plugin = "$name"`, with its parameters); `fsi-lab profile
check PROFILE` checks them and the safety limits, and `fsi-lab run PROFILE` sends it. The GUI's
excitation designer shows its parameters and draws the waveform.'''

EXCITATION_CHANGE = '''\
- `$package/plugin.py` declares the excitation (its parameters, each with its unit, both bounds
  and help; `duration`, the waveform's length from the parameters) and generates the waveform:
  the source voltage in volts from t = 0, at the sample rate asked. Refuse a combination it
  cannot make with `ParameterError`; derive any randomness from a seed parameter.
- If its peak is not the sum of its parameters in V, say what it is in the test class
  (`peak_limit`), so that the kit can hold the waveform to it.
- docs/writing-plugins.md of fsi-lab is the full tutorial.'''

EXCITATION_PLUGIN = '''\
"""The ``$name`` excitation.

A burst of ``cycles`` periods of a sine after ``delay`` s.
"""

import numpy as np
from fsi_lab.contract import ExcitationPlugin
from fsi_lab.errors import ParameterError
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param


def generate(params, sample_rate):
    """Source voltage (V) of the burst at ``sample_rate`` Hz, from t = 0."""
    frequency = params["frequency"]
    if frequency >= sample_rate / 2:
        raise ParameterError(
            f"$name: frequency {frequency:g} Hz is not below "
            f"half the source sample rate {sample_rate:g} Hz")
    t = np.arange(round(params["duration"] * sample_rate)) / sample_rate
    since = t - params["delay"]
    on = (since >= 0) & (since < params["cycles"] / frequency)
    return np.where(on, params["amplitude"] * np.sin(2 * np.pi * frequency * since), 0.0)


PLUGIN = ExcitationPlugin(
    name="$name",
    params=(
        Param("amplitude", "float", "V", 0.5, minimum=0.0, maximum=10.0,
              help="Peak source voltage of the burst."),
        Param("frequency", "float", "Hz", 20.0, minimum=0.1, maximum=100000.0,
              help="Frequency of the sine."),
        Param("cycles", "int", "", 10, minimum=1, maximum=100000,
              help="Number of periods in the burst."),
        Param("delay", "float", "s", 0.1, minimum=0.0, maximum=60.0,
              help="Time at 0 V before the burst."),
        Param("duration", "float", "s", 2.0, minimum=0.0, exclusive_minimum=True,
              maximum=3600.0, help="Length of the waveform."),
    ),
    generate=generate,
    duration=lambda params: params["duration"],
    help="A burst of a given number of periods of a sine.",
)


@hookimpl
def fsi_lab_excitations():
    return [PLUGIN]
'''

EXCITATION_TEST = '''\
"""Tests of the ``$name`` excitation.

fsi-lab's conformance kit, and its waveform against ground truth.
"""

import numpy as np
from fsi_lab.params import validate
from fsi_lab.testing import ExcitationContract

from $package.plugin import PLUGIN


class TestContract(ExcitationContract):
    """Schema complete, waveform within its limits, deterministic, bounds enforced."""

    plugin = "$name"
    dimensionless = ("cycles",)


def test_the_burst_holds_its_cycles_after_its_delay():
    given = {"amplitude": 2.0, "frequency": 50.0, "cycles": 3, "delay": 0.1, "duration": 0.5}
    params = validate(PLUGIN.params, given, "$name")
    wave = PLUGIN.generate(params, 10000.0)
    t = np.arange(wave.size) / 10000.0
    assert wave.size == 5000 and np.all(wave[t < 0.1] == 0.0) and np.all(wave[t >= 0.16] == 0.0)
    np.testing.assert_allclose(wave.max(), 2.0, rtol=1e-6)
    inside = wave[(t >= 0.1) & (t < 0.16)]
    assert np.count_nonzero(np.diff(np.signbit(inside[1:]))) == 5  # 3 periods: 5 crossings
'''

INSTRUMENT_USE = '''\
Name it in a profile (`[bench.amplifier] plugin = "$name"`,
`address = "TCPIP0::<host>::<port>::SOCKET"`, `gain = 2.0`); `fsi-lab identify PROFILE` asks
it who it is and `fsi-lab safe PROFILE` makes it safe. As written it speaks the SCPI of
fsi-lab's simulated shaker amplifier (`fsi-lab bench` starts one on 127.0.0.1 and prints its
address).'''

INSTRUMENT_CHANGE = '''\
- `$package/plugin.py` is the driver, written with fsi-lab's instrument kit
  (`fsi_lab.instruments.kit`): each setting declared once (`Setting`: command, type, unit,
  bounds), checked before it is sent; `ScpiOutput` gives the take-over with the output off, the
  confirmed safe state and the typed state read back. Change the commands to your
  amplifier's, and what `interlocks()` reads.
- The tests run against fsi-lab's simulated amplifier; for your instrument, script its replies
  with `fsi_lab.testing.ScriptedPeer` (the exact bytes exchanged), as fsi-lab's own driver tests
  do.
- docs/writing-plugins.md of fsi-lab is the full tutorial.'''

INSTRUMENT_PLUGIN = '''\
"""The ``$name`` amplifier driver.

Written with fsi-lab's instrument kit.

It drives an amplifier that speaks SCPI over VISA (``*IDN?``, ``OUTP 0|1``, ``OUTP?``,
``GAIN <V/V>``, ``GAIN?``, ``STAT:INTL?``), as fsi-lab's simulated shaker amplifier does.
"""

from fsi_lab.contract import Amplifier, InstrumentPlugin
from fsi_lab.errors import InstrumentError
from fsi_lab.hookspecs import hookimpl
from fsi_lab.instruments.kit import ScpiOutput, Setting, connect
from fsi_lab.params import Param

NAME = "$name"
#: Interlock name for each bit of ``STAT:INTL?``.
INTERLOCKS = ("over_travel", "supply_fault", "over_temperature", "over_current", "e_stop",
              "input_clip", "watchdog")


class $cls(ScpiOutput, Amplifier):
    """An open amplifier; use :func:`open_amplifier`."""

    NAME = NAME
    output = Setting("OUTP", "bool", choices=("1", "0"), help="Output stage on.")
    gain = Setting("GAIN", "float", "V/V", minimum=0.0, maximum=20.0, fmt=".6g",
                   help="Voltage gain of the amplifier.")
    interlock_bits = Setting("STAT:INTL", "int", readonly=True, help="Latched interlocks.")

    def set_gain(self, gain):
        """Set the gain (V/V), checked against its bounds, and read it back."""
        self.set("gain", gain, verify=True)

    def interlocks(self):
        """Latched interlocks by name."""
        bits = self.interlock_bits
        return {name: bool(bits >> bit & 1) for bit, name in enumerate(INTERLOCKS)}

    def enable_output(self, enabled):
        """Output on (refused while an interlock is latched) or off."""
        active = [name for name, on in self.interlocks().items() if on]
        if enabled and active:
            raise InstrumentError(f"{self.where}: output on refused: interlock "
                                  f"{', '.join(active)} is active")
        self.output = enabled

    def state_details(self, output_enabled):
        """The gain (V/V), next to the output state the kit reads."""
        return {"gain": self.gain}


def open_amplifier(address, settings, bench):
    """Connect and take the amplifier over with its output off."""
    link = connect(NAME, "amplifier", address, settings, bench)
    try:
        identity, found_on = $cls.take_over(link)
    except BaseException:
        link.close()
        raise
    amplifier = $cls(link, identity)
    amplifier.found_on = found_on
    return amplifier


PLUGIN = InstrumentPlugin(
    name=NAME,
    role="amplifier",
    params=($cls.gain.param(1.0),
            Param("timeout_s", "float", "s", 2.0, minimum=0.05, maximum=60.0,
                  help="Time allowed for each reply.")),
    open=open_amplifier,
    help="SCPI amplifier driver written with fsi-lab's instrument kit.",
)


@hookimpl
def fsi_lab_instruments():
    return [PLUGIN]
'''

INSTRUMENT_TEST = '''\
"""Tests of the ``$name`` driver.

fsi-lab's conformance kit, against fsi-lab's simulated amplifier on a 127.0.0.1 socket
(through pyvisa-py, as in the lab).
"""

import pytest
from fsi_lab.contract import BenchContext
from fsi_lab.instruments.sim.bench import BenchOptions, SimBench
from fsi_lab.params import validate
from fsi_lab.testing import InstrumentContract

from $package.plugin import PLUGIN


@pytest.fixture(scope="module")
def bench():
    started = SimBench(options=BenchOptions(fast=True)).start()
    yield started
    started.stop()


class TestContract(InstrumentContract):
    """Its role, its identity, a confirmed safe state, a typed state, close twice, and a clear
    error from a peer that never answers."""

    plugin = "$name"
    transport = "tcp"

    @pytest.fixture
    def address(self, bench):
        return bench.addresses["amplifier"]


def test_the_gain_is_set_and_read_back(bench):
    settings = validate(PLUGIN.params, {}, "$name")
    driver = PLUGIN.open(bench.addresses["amplifier"], settings, BenchContext())
    try:
        driver.set_gain(2.5)
        assert driver.read_state()["gain"] == 2.5
    finally:
        driver.safe_state()
        driver.close()
'''

KINDS = {
    "analysis": {"summary": "RMS of a channel in windows of a given length (fsi-lab analysis).",
                 "use": ANALYSIS_USE, "change": ANALYSIS_CHANGE,
                 "plugin.py": ANALYSIS_PLUGIN, "_compute.py": ANALYSIS_COMPUTE,
                 "test": ANALYSIS_TEST},
    "excitation": {"summary": "A sine burst of a given number of periods (fsi-lab excitation).",
                   "use": EXCITATION_USE, "change": EXCITATION_CHANGE,
                   "plugin.py": EXCITATION_PLUGIN, "test": EXCITATION_TEST},
    "instrument": {"summary": "A SCPI shaker amplifier driver (fsi-lab instrument).",
                   "use": INSTRUMENT_USE, "change": INSTRUMENT_CHANGE,
                   "plugin.py": INSTRUMENT_PLUGIN, "test": INSTRUMENT_TEST},
}


def files(kind: str, name: str) -> dict[str, str]:
    """The files of a ``kind`` plugin called ``name``, by path in its distribution."""
    under = name.replace("-", "_")
    package = f"fsi_lab_{under}"
    spec = KINDS[kind]
    values = {"name": name, "under": under, "package": package, "kind": kind,
              "cls": "".join(part.title() for part in name.split("-")) + "Amplifier",
              "summary": spec["summary"], "article": "An" if kind[0] in "aeiou" else "A"}

    def fill(text: str) -> str:
        return Template(text).substitute(values)

    values["use"] = fill(spec["use"])
    values["change"] = fill(spec["change"])
    out = {"pyproject.toml": fill(PYPROJECT), "README.md": fill(README),
           f"{package}/__init__.py": f'"""The fsi-lab {kind} plugin ``{name}``."""\n',
           f"tests/test_{under}.py": fill(spec["test"])}
    for module in ("plugin.py", "_compute.py"):
        if module in spec:
            out[f"{package}/{module}"] = fill(spec[module])
    return out
