"""What a plugin provides: descriptors for the three plugin kinds and the instrument roles.

A plugin module implements one or more hooks of :mod:`fsi_lab.hookspecs`, each returning a list
of the descriptors below. The core checks every descriptor (see :func:`check_descriptor`) and
skips, with the reason, those that break the contract.
"""

from __future__ import annotations

import abc
import importlib
import re
from collections.abc import Callable, Hashable, Iterator, Mapping, MutableMapping
from dataclasses import dataclass, field, fields
from typing import Any, ClassVar, TypeVar

import numpy as np

from fsi_lab.errors import AnalysisError
from fsi_lab.params import Param

KINDS = ("instrument", "excitation", "analysis")
ROLES = ("source", "amplifier", "vibrometer", "acquisition")

R = TypeVar("R", bound="Result")


@dataclass(frozen=True)
class Deferred:
    """A function named ``"package.module:function"``, imported when it is first called.

    A descriptor may give its work this way (``run=Deferred("my_plugin._work:run")``, likewise
    ``generate``, ``open`` or ``check``), so that listing the plugins and checking a profile,
    which read only the descriptors, do not import what the work needs (scipy, numba): the
    module holding the descriptor stays light. A module that fails to import then fails the
    first call, where the chain reports it like any other failure of that plugin.
    """

    target: str

    def __post_init__(self) -> None:
        module, sep, name = self.target.partition(":")
        if not (module and sep and name):
            raise ValueError(f"Deferred({self.target!r}): expected 'package.module:function'")

    def load(self) -> Callable[..., Any]:
        """The named function (its module imported now, if it was not yet)."""
        module, _, name = self.target.partition(":")
        return getattr(importlib.import_module(module), name)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return self.load()(*args, **kwargs)


# --------------------------------------------------------------------------- instruments
@dataclass(frozen=True)
class RoleSetting:
    """A setting the runner reads, by this name, from the profile table of an instrument role.

    A role class lists them in :attr:`Instrument.run_settings`; a plugin of that role declares
    each as one of its parameters (with this type and unit, and choices among these), and must
    declare the ``required`` ones. :func:`check_descriptor` enforces it when the plugin is
    loaded, so that the runner never reads a name a driver could leave out or mean otherwise.

    Parameters
    ----------
    name
        Parameter name in ``[bench.<role>]``.
    type
        :class:`~fsi_lab.params.Param` type the runner expects (``"float"``, ``"str"``...).
    unit
        Unit the runner expects the value in (``"Hz"``, ``"V/V"``).
    required
        Every plugin of the role must declare it; otherwise it may leave it out (the runner then
        says what it assumes).
    help
        What the runner does with it.
    choices
        The values the runner understands, for strings.
    """

    name: str
    type: str
    unit: str
    required: bool
    help: str
    choices: tuple[str, ...] | None = None

    def problem(self, params: tuple[Param, ...]) -> str:
        """What is wrong with a plugin's ``params`` for this setting, in words; '' if nothing."""
        declared = next((p for p in params if p.name == self.name), None)
        wanted = f"{self.type} in {self.unit}" if self.unit else self.type
        if declared is None:
            return (f"declares no {self.name!r} parameter ({wanted}), which every plugin of "
                    f"this role must: {self.help}") if self.required else ""
        if declared.type != self.type or declared.unit != self.unit:
            got = f"{declared.type} in {declared.unit}" if declared.unit else declared.type
            return (f"parameter {self.name!r} is declared as {got}; the runner reads it as "
                    f"{wanted} ({self.help})")
        if self.choices is not None:
            extra = sorted(set(declared.choices or ()) - set(self.choices))
            if declared.choices is None or extra:
                return (f"parameter {self.name!r} must take its values among "
                        f"{', '.join(map(repr, self.choices))}"
                        + (f" (got {', '.join(map(repr, extra))})" if extra else ""))
        return ""


class InstrumentState(Mapping[str, Any]):
    """State read back from an instrument: named values, read like a dictionary (and equal to
    the dictionary of the same items). Every value is stored in the run file as read.

    Parameters
    ----------
    **values
        Named values (``level_v=0.0``, ``interlocks={...}``), in SI units named by the key.
    """

    def __init__(self, **values: Any) -> None:
        self._values = dict(values)

    def __getitem__(self, key: str) -> Any:
        return self._values[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({', '.join(f'{k}={v!r}' for k, v in self.items())})"


class OutputState(InstrumentState):
    """State read back from an instrument whose output can drive the shaker (a source, an
    amplifier): ``output_enabled`` is required and must be a bool read from the instrument.

    Parameters
    ----------
    output_enabled
        Whether the output reads on.
    **values
        Any further values read back (``level_v``, ``gain``).

    Raises
    ------
    TypeError
        ``output_enabled`` is not a bool (``"ON"``, ``1``, ``None`` are refused: a state that
        cannot say off does not confirm the output off).
    """

    def __init__(self, output_enabled: bool, **values: Any) -> None:
        if not isinstance(output_enabled, bool):
            raise TypeError(f"OutputState: output_enabled must be a bool read from the "
                            f"instrument; got {output_enabled!r} ({type(output_enabled).__name__})")
        super().__init__(output_enabled=output_enabled, **values)

    @property
    def output_enabled(self) -> bool:
        """Whether the output reads on."""
        return self._values["output_enabled"]


class Instrument(abc.ABC):
    """Common interface of every instrument role.

    Instruments are context managers: leaving the ``with`` block puts them in their safe state
    and closes the connection, whatever happened inside.
    """

    #: Whether the role's output can drive the shaker: its :meth:`read_state` must then give
    #: ``output_enabled`` (an :class:`OutputState`), or it is not confirmed safe.
    has_output: ClassVar[bool] = False
    #: Settings of the role's profile table that the runner reads (:class:`RoleSetting`).
    run_settings: ClassVar[tuple[RoleSetting, ...]] = ()

    @classmethod
    def run_setting(cls, name: str) -> RoleSetting:
        """The declared :class:`RoleSetting` ``name``; ValueError if the role declares none."""
        for setting in cls.run_settings:
            if setting.name == name:
                return setting
        raise ValueError(f"{cls.__name__} declares no run setting {name!r}; it declares "
                         f"{', '.join(s.name for s in cls.run_settings) or 'none'}")

    @abc.abstractmethod
    def identify(self) -> str:
        """Identity string as the instrument reports it (``*IDN?`` or equivalent)."""

    @abc.abstractmethod
    def safe_state(self) -> None:
        """Put the instrument where it cannot move the shaker: output off, source at 0 V."""

    @abc.abstractmethod
    def read_state(self) -> Mapping[str, Any]:
        """State read back from the instrument: an :class:`InstrumentState` (or a dict).

        A role with an output (:attr:`has_output`: a source, an amplifier) returns an
        :class:`OutputState`, whose ``output_enabled`` is a bool read from the instrument: a
        state without it, or with anything but False after the safe state, does not confirm the
        instrument safe and the run fails saying so, naming the driver.
        """

    def settings(self) -> dict[str, Any]:
        """Snapshot of the settings in force, stored in the run file."""
        return {}

    def monitor(self) -> None:
        """Check, while a record runs, that the instrument still answers and still holds the
        state the run set (a source's output on, a vibrometer's range); raise
        :class:`~fsi_lab.errors.InstrumentError` naming what went wrong otherwise.

        The runner calls it every fraction of a second during the record and once more at its
        end, so a timeout, a dropped connection or a garbled reply on an instrument the record
        does not otherwise talk to fails the run instead of passing unnoticed. The default
        checks nothing: a driver whose instrument can be asked should override it.
        """

    @abc.abstractmethod
    def close(self) -> None:
        """Release the connection. Must not raise if already closed."""

    def __enter__(self):
        return self

    def __exit__(self, *exc_info):
        try:
            self.safe_state()
        finally:
            self.close()


class SignalSource(Instrument):
    """Arbitrary waveform generator that produces the drive voltage."""

    has_output = True
    run_settings = (
        RoleSetting("sample_rate", "float", "Hz", False,
                    "the excitation is generated at this rate (unset: the run's sample_rate)"),
        RoleSetting("arb_filter", "str", "", False,
                    "how the source reconstructs its output between samples, which the safety "
                    "check predicts (undeclared: the worse of held and band-limited)",
                    choices=("normal", "step", "off")),
    )

    @abc.abstractmethod
    def load_waveform(self, samples: np.ndarray, sample_rate: float) -> None:
        """Upload ``samples`` (V) played at ``sample_rate`` (Hz), once per trigger."""

    @abc.abstractmethod
    def start(self) -> None:
        """Enable the output and play the loaded waveform once."""


class Amplifier(Instrument):
    """Shaker power amplifier with interlocks."""

    has_output = True
    run_settings = (
        RoleSetting("gain", "float", "V/V", True,
                    "the runner sets the amplifier to it and the safety check limits it"),
    )

    @abc.abstractmethod
    def set_gain(self, gain: float) -> None:
        """Set the voltage gain (V/V)."""

    @abc.abstractmethod
    def enable_output(self, enabled: bool) -> None:
        """Switch the output stage on or off."""

    @abc.abstractmethod
    def interlocks(self) -> dict[str, bool]:
        """Active interlocks by name (over_travel, supply_fault, ...); all False when clear."""


class Vibrometer(Instrument):
    """Laser vibrometer whose analogue output is digitised by the acquisition."""

    @abc.abstractmethod
    def sensitivity(self) -> float:
        """Output sensitivity of the velocity channel in V per (m/s)."""

    def delay(self) -> float:
        """Signal delay of the sensor, s; the run shifts the channel's t0 by it."""
        return 0.0


class Acquisition(Instrument):
    """Digitiser that streams calibrated-by-the-core voltage blocks (the record's rate and
    length come from the profile's ``[run]``, not from a setting of the digitiser)."""

    @abc.abstractmethod
    def configure(self, inputs: Mapping[str, int], sample_rate: float, duration: float) -> float:
        """Prepare to record the named ``inputs`` (name -> input number) for ``duration`` s.

        Returns the sample rate actually used, Hz.
        """

    @abc.abstractmethod
    def arm(self) -> None:
        """Start recording (the first block starts at t = 0 of the run)."""

    @abc.abstractmethod
    def read_block(self, timeout: float) -> dict[str, np.ndarray] | None:
        """Next block of samples in volts per input name; None when the record is complete.

        Raises InstrumentError if no block arrives within ``timeout`` seconds.
        """


ROLE_INTERFACES: dict[str, type[Instrument]] = {
    "source": SignalSource,
    "amplifier": Amplifier,
    "vibrometer": Vibrometer,
    "acquisition": Acquisition,
}


#: ``purpose`` of a :class:`BenchContext`: opened for a run, or to be made safe or identified
#: outside one (a driver then changes nothing it need not, e.g. it leaves latched interlocks
#: latched).
PURPOSES = ("run", "outside-run")


@dataclass(eq=False)
class BenchContext(MutableMapping[str, Any]):
    """What the instruments of one profile share while they are open.

    Drivers read its attributes (``context.purpose``); mapping access (``context["purpose"]``,
    ``context.get("bench")``, ``context.setdefault(...)``) still works, as it did when the
    context was a dict: keys that are not attributes (what a driver stores for the others, such
    as the embedded simulated bench) live in :attr:`extras`.

    Attributes
    ----------
    specimen
        The profile's beam and fluid (:class:`fsi_lab.specimen.Specimen`), or None.
    model
        The profile's ``[model]`` table (simulated instruments take their physics from it).
    shaker
        The profile's ``[shaker]`` table.
    bench
        The profile's ``[bench]`` table (``embedded``, ``fast``, ``fault``...).
    cleanup
        Callables the runner calls, last first, once every instrument is safe and closed (a
        simulated instrument stops its server there).
    purpose
        ``"run"``, or ``"outside-run"`` (:data:`PURPOSES`).
    extras
        Anything else drivers store, by key.
    """

    specimen: Any = None
    model: Mapping[str, Any] | None = None
    shaker: Mapping[str, Any] | None = None
    bench: dict[str, Any] = field(default_factory=dict)
    cleanup: list[Callable[[], None]] = field(default_factory=list)
    purpose: str = "run"
    extras: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.purpose not in PURPOSES:
            raise ValueError(f"purpose {self.purpose!r}; expected one of {', '.join(PURPOSES)}")

    @classmethod
    def _attributes(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls) if f.name != "extras")

    def __getitem__(self, key: str) -> Any:
        if key in self._attributes():
            return getattr(self, key)
        return self.extras[key]

    def __setitem__(self, key: str, value: Any) -> None:
        if key in self._attributes():
            setattr(self, key, value)
        else:
            self.extras[key] = value

    def __delitem__(self, key: str) -> None:
        if key in self._attributes():
            raise KeyError(f"{key!r} is an attribute of the bench context and cannot be removed")
        del self.extras[key]

    def __iter__(self) -> Iterator[str]:
        yield from self._attributes()
        yield from self.extras

    def __len__(self) -> int:
        return len(self._attributes()) + len(self.extras)


@dataclass(eq=False)
class RunPlan(BenchContext):
    """What an :class:`InstrumentPlugin`'s ``check`` is given: the :class:`BenchContext` of the
    run and the record it will ask for (:data:`RUN_PLAN_KEYS`), by attribute or by key.

    Attributes
    ----------
    inputs
        Digitiser input number per channel name.
    sample_rate
        Record sample rate asked of the digitiser, Hz.
    duration
        Record length, s.
    waveform_points
        Samples of the excitation waveform sent to the source.
    waveform_rate
        Rate the source plays the waveform at, Sa/s.
    """

    inputs: dict[str, int] = field(default_factory=dict)
    sample_rate: float = 0.0
    duration: float = 0.0
    waveform_points: int = 0
    waveform_rate: float = 0.0


@dataclass(frozen=True)
class InstrumentPlugin:
    """An instrument driver.

    ``open(address, settings, bench)`` returns an object implementing the role interface;
    ``settings`` has been validated against ``params``, which must declare the settings the
    role's class lists in ``run_settings`` (:class:`RoleSetting`). ``bench`` is the
    :class:`BenchContext` shared by all instruments of one run: the profile's ``specimen``,
    ``model``, ``shaker`` and ``bench`` sections (simulated instruments take their physics from
    them, and an embedded simulated bench is started by the first driver that needs it), a
    ``cleanup`` list of callables the runner calls after every instrument is safe and closed,
    and the ``purpose``: ``"run"``, or ``"outside-run"`` when the instrument is opened only to
    be made safe or identified (``fsi-lab safe``, ``fsi-lab identify``, the GUI's bench panel),
    when a driver must change nothing it need not (it leaves latched interlocks latched). It is
    also a mapping (``bench["purpose"]``), as the dict it replaced; a driver must accept a plain
    dict with the same keys too (tests open drivers with ``{}``).

    ``check(address, settings, plan)``, optional, raises ValueError with a message naming the
    setting and what the instrument accepts when the run ``plan`` describes would be refused by
    the instrument (an input it does not have, a range it does not offer, more points than its
    memory holds). It runs in ``fsi-lab profile check`` and before a run, before any instrument
    is opened, and must not talk to the instrument. ``plan`` is a :class:`RunPlan`: the bench
    context above plus the record (:data:`RUN_PLAN_KEYS`).
    """

    name: str
    role: str
    params: tuple[Param, ...]
    open: Callable[[str, dict[str, Any], BenchContext], Instrument]
    help: str = ""
    check: Callable[[str, dict[str, Any], Mapping[str, Any]], None] | None = None


#: Keys a :class:`InstrumentPlugin`'s ``check`` finds in its ``plan``, besides the bench
#: context's ``specimen``, ``model``, ``shaker`` and ``bench``.
RUN_PLAN_KEYS = {
    "inputs": "digitiser input number per channel name",
    "sample_rate": "record sample rate asked of the digitiser, Hz",
    "duration": "record length, s",
    "waveform_points": "samples of the excitation waveform sent to the source",
    "waveform_rate": "rate the source plays the waveform at, Sa/s",
}


# --------------------------------------------------------------------------- excitations
@dataclass(frozen=True)
class ExcitationPlugin:
    """A drive waveform.

    ``generate(params, sample_rate)`` returns the samples in volts at the source, starting at
    t = 0. Its peak absolute value is the peak drive that the safety check compares with the
    profile's limit. ``duration(params)``, optional, gives the waveform's length in seconds
    without generating it, so that a waveform too long for any source is refused first.
    """

    name: str
    params: tuple[Param, ...]
    generate: Callable[[dict[str, Any], float], np.ndarray]
    help: str = ""
    duration: Callable[[dict[str, Any]], float] | None = None


# --------------------------------------------------------------------------- analyses
@dataclass(frozen=True)
class ChannelData:
    """One recorded channel, calibrated (``data`` in ``unit``)."""

    name: str
    data: np.ndarray
    sample_rate: float
    quantity: str
    unit: str
    t0: float = 0.0


@dataclass
class AnalysisResult:
    """What the run file and the JSON summary keep of one analysis on one channel.

    A typed :class:`Result` gives it from :meth:`Result.record`; an analysis that provides
    nothing to later analyses may return it directly.

    Attributes
    ----------
    datasets
        Arrays stored under ``/analysis/<channel>/<plugin>/<name>``.
    units
        Unit of each dataset, by name (stored as the dataset's ``units`` attribute).
    attrs
        Scalar results stored as attributes of the plugin's group.
    summary
        JSON-ready dictionary merged into the channel's summary (``fsi-lab analyze --json``);
        a ``"components"`` list is merged with other plugins' entries by ``"index"``.
    values
        Any Python object, found by later analyses in ``context.results[plugin].values`` (how
        results passed between analyses before typed results; kept for the plugins written
        so).
    axes
        For a dataset drawn against another one of the same length (an amplitude against
        ``frequency``), that dataset's name, by the name of the dataset drawn (stored as the
        dataset's ``axis`` attribute): the GUI's generic view plots it so, with both units;
        a dataset without one is drawn against its sample index.
    """

    datasets: dict[str, np.ndarray] = field(default_factory=dict)
    units: dict[str, str] = field(default_factory=dict)
    attrs: dict[str, Any] = field(default_factory=dict)
    summary: dict[str, Any] = field(default_factory=dict)
    values: Any = None
    axes: dict[str, str] = field(default_factory=dict)


class Result(abc.ABC):
    """A typed result that an analysis hands to the later analyses of the chain.

    A subclass (normally a dataclass) names its :attr:`kind`, the name analyses give in their
    ``requires``, ``uses`` and ``provides``; a later analysis receives the object itself from
    :meth:`AnalysisContext.result`, and the run file and the JSON summary keep what
    :meth:`record` gives.
    """

    #: Name of the result kind: lower-case words joined by dashes (``"components"``).
    kind: ClassVar[str] = ""

    @abc.abstractmethod
    def record(self) -> AnalysisResult:
        """What the run file (datasets with units, attributes) and the summary keep of it."""


#: Longest gist of an earlier analysis's error repeated in the errors of those that needed it.
ERROR_GIST = 160


def error_gist(message: str) -> str:
    """The start of an analysis's error, for the message of an analysis that needed its
    result: without its ``"<analysis> on channel '<name>': "`` prefix, at most
    :data:`ERROR_GIST` characters (the whole message stands in the errors beside it)."""
    prefix = re.match(r"[^:']* on channel '[^']*': ", message)
    text = message[prefix.end():] if prefix else message
    if len(text) > ERROR_GIST:
        text = text[:ERROR_GIST].rsplit(" ", 1)[0] + " ..."
    return text


#: How an analysis that could not do without the result of one that failed before it on the
#: channel says so (:meth:`AnalysisContext.result`, :func:`fsi_lab.chain._missing`).
_FOR_WANT_OF = (re.compile(r"(?:[^:']* on channel '[^']*': )?(\S+) failed earlier in the "
                           r"chain on this channel, so its '[^']+' result is missing \("),
                re.compile(r"(?:[^:']* on channel '[^']*': )?needs the '[^']+' result, which "
                           r"(\S+) failed to give on this channel \("))


def failed_provider(message: str) -> str | None:
    """The analysis whose failure an error's ``message`` gives as its only reason, or None
    (an analysis that failed on its own account, or for more than one reason)."""
    for pattern in _FOR_WANT_OF:
        found = pattern.match(message)
        # (one reason: a second missing result would be named after a "; ")
        if found and message.count(" result, which ") + message.count(
                " result earlier in the chain on this channel, which did not run") <= 1:
            return found.group(1)
    return None


def for_want_of(provider: str) -> str:
    """What an analysis that could not do without ``provider``'s result is told to say once
    that failure has been said in full."""
    return f"no result, for want of {provider}'s ({provider} failed, above)"


def kind_name(kind: str | type[Result]) -> str:
    """The name of a result kind given by name or by its :class:`Result` class.

    Raises
    ------
    TypeError
        Neither a non-empty string nor a :class:`Result` subclass with a ``kind``.
    """
    if isinstance(kind, type) and issubclass(kind, Result):
        if not kind.kind:
            raise TypeError(f"{kind.__name__} names no kind (set its class attribute 'kind')")
        return kind.kind
    if isinstance(kind, str) and kind:
        return kind
    raise TypeError(f"{kind!r} is not a result kind: expected its name (a non-empty string) or "
                    "its fsi_lab.contract.Result class")


@dataclass(frozen=True)
class RecordSpectrum:
    """Single-sided amplitude spectrum of a whole record
    (:func:`fsi_lab.dsp.spectrum.amplitude_spectrum`, detrended), zero-padded to a fast FFT
    length.

    Attributes
    ----------
    frequency
        Frequencies, Hz, from 0 to ``sample_rate / 2`` in steps of ``sample_rate / nfft``.
    amplitude
        Amplitude in the unit of the record: a steady sinusoid of amplitude A shows a peak of
        height A.
    window
        Window (:data:`fsi_lab.dsp.choices.WINDOWS`).
    samples
        Length of the record.
    nfft
        FFT length: the smallest fast length (``scipy.fft.next_fast_len``) of at least
        ``samples`` (a record of 5 998 615 samples is transformed as 6 000 000: 0.2 s instead
        of 1.3 s).
    sample_rate
        Hz.
    """

    frequency: np.ndarray
    amplitude: np.ndarray
    window: str
    samples: int
    nfft: int
    sample_rate: float


def record_spectrum(x: Any, sample_rate: float, window: str = "decay") -> RecordSpectrum:
    """The :class:`RecordSpectrum` of samples ``x`` (any unit) taken at ``sample_rate`` Hz.

    Raises
    ------
    AnalysisError
        As :func:`fsi_lab.dsp.spectrum.amplitude_spectrum` (non-finite or constant samples,
        too few of them, an unknown window).
    """
    import scipy.fft

    from fsi_lab.dsp.spectrum import amplitude_spectrum

    samples = int(np.size(x))
    nfft = scipy.fft.next_fast_len(max(samples, 1), real=True)
    freqs, amplitude = amplitude_spectrum(x, sample_rate, window=window, nfft=nfft)
    return RecordSpectrum(freqs, amplitude, window, samples, nfft, float(sample_rate))


class SharedRecord:
    """What the analyses of one channel share, each computed once, when first asked: the
    record's spectrum per window (:meth:`spectrum`) and other values derived from the record
    (:meth:`once`).

    The chain makes one for each analysed channel and gives it to every analysis of that
    channel (:attr:`AnalysisContext.shared`), so that a 600 s record's spectrum is computed once
    for the chain rather than once per analysis that looks at it.

    Parameters
    ----------
    channel
        The channel whose record is shared.
    """

    def __init__(self, channel: ChannelData) -> None:
        self.channel = channel
        self._spectra: dict[str, RecordSpectrum] = {}
        self._values: dict[Hashable, Any] = {}

    def spectrum(self, window: str = "decay") -> RecordSpectrum:
        """The record's :class:`RecordSpectrum` with ``window``, computed on the first call."""
        found = self._spectra.get(window)
        if found is None:
            found = record_spectrum(self.channel.data, self.channel.sample_rate, window)
            self._spectra[window] = found
        return found

    def once(self, key: Hashable, compute: Callable[[], Any]) -> Any:
        """``compute()`` on the first call with ``key``, the same object on the later ones (a
        value derived from the record that several analyses use, such as its noise level)."""
        if key not in self._values:
            self._values[key] = compute()
        return self._values[key]


@dataclass
class AnalysisContext:
    """Everything an analysis may use besides its own parameters.

    Attributes
    ----------
    channel
        The channel being analysed.
    channels
        Every channel of the run by name (for transfer functions and the modal model).
    results
        What the analyses that ran earlier in the chain on this channel keep
        (:class:`AnalysisResult`), by plugin name.
    specimen
        The beam and fluid (:class:`fsi_lab.specimen.Specimen`) when the run has one, else None.
    mass_per_length
        mu + M in kg/m given on the command line for data without a specimen, else None.
    reference
        Name of the reference (base acceleration) channel, or None.
    progress
        Callable taking a fraction 0..1 for long analyses.
    failed
        Analyses that ran earlier in the chain on this channel and failed, by plugin name, with
        their error messages (an analysis that would use one must not quietly do without).
    provided
        Typed results of the analyses that ran earlier on this channel, by kind: read them with
        :meth:`result`.
    unavailable
        Kinds whose analysis failed earlier on this channel, with the name of that analysis.
    shared
        What the analyses of this channel share (:class:`SharedRecord`: its spectrum); made
        for the channel when not given.
    plugin
        Name of the analysis given the context, for messages (None when called directly).
    declared
        Kinds the analysis declared in ``requires`` and ``uses``: :meth:`result` gives no
        other (None: any, when an analysis is called directly).
    """

    channel: ChannelData
    channels: Mapping[str, ChannelData]
    results: Mapping[str, AnalysisResult]
    specimen: Any = None
    mass_per_length: float | None = None
    reference: str | None = None
    progress: Callable[[float], None] = lambda fraction: None
    failed: Mapping[str, str] = field(default_factory=dict)
    provided: Mapping[str, Result] = field(default_factory=dict)
    unavailable: Mapping[str, str] = field(default_factory=dict)
    shared: SharedRecord | None = None
    plugin: str | None = None
    declared: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        if self.shared is None:
            self.shared = SharedRecord(self.channel)

    def result(self, kind: str | type[R]) -> R | None:
        """The typed result of ``kind`` (its name, or its :class:`Result` class) that an
        earlier analysis provided on this channel; None when none in the chain provides it.

        Raises
        ------
        AnalysisError
            The analysis that provides it failed earlier on this channel (the message says
            which and why): an analysis must not quietly do without a result the chain asked
            for.
        TypeError
            The analysis reads a kind it declared in neither ``requires`` nor ``uses``, or the
            result is not of the class asked for.
        """
        name = kind_name(kind)
        if self.declared is not None and name not in self.declared:
            raise TypeError(f"{self.plugin or 'the analysis'} reads the {name!r} result but "
                            "declares it in neither requires nor uses; declare it (uses when "
                            "the analysis can do without it)")
        found = self.provided.get(name)
        if found is not None:
            if isinstance(kind, type) and not isinstance(found, kind):
                raise TypeError(f"the {name!r} result is a {type(found).__name__}; expected "
                                f"{kind.__name__}")
            return found  # type: ignore[return-value]
        provider = self.unavailable.get(name)
        if provider is not None:
            raise AnalysisError(
                f"{provider} failed earlier in the chain on this channel, so its {name!r} "
                f"result is missing ({provider}: "
                f"{error_gist(self.failed.get(provider, 'failed'))})")
        return None

    def spectrum(self, window: str = "decay") -> RecordSpectrum:
        """The channel's spectrum with ``window``, shared by the analyses of the channel
        (:meth:`SharedRecord.spectrum`)."""
        assert self.shared is not None
        return self.shared.spectrum(window)


def _kinds(value: Any, what: str, plugin: str) -> tuple[str, ...]:
    """``value`` (a tuple of kinds) as names; TypeError saying what to write otherwise."""
    if isinstance(value, str) or (isinstance(value, type) and issubclass(value, Result)):
        raise TypeError(f"analysis {plugin!r}: {what} must be a tuple of result kinds; got "
                        f"{value!r}: write {what}=({kind_name(value)!r},)")
    try:
        return tuple(kind_name(k) for k in value)
    except TypeError as exc:
        raise TypeError(f"analysis {plugin!r}: {what}: {exc}") from None


@dataclass(frozen=True)
class AnalysisPlugin:
    """An analysis step of the chain.

    ``run(context, params)`` returns a typed :class:`Result` of the kind the plugin
    ``provides`` (later analyses receive it; the run file and the summary keep its
    :meth:`Result.record`), or an :class:`AnalysisResult` when it provides nothing; it raises
    :class:`fsi_lab.errors.AnalysisError` with a message naming the condition that prevents it.

    ``requires`` names the kinds of result (:class:`Result` classes or their names) the
    analysis cannot do without: the profile check refuses a chain where no analysis before it
    provides one, and the chain does not run it on a channel where the analysis that provides
    one failed. ``uses`` names those it uses when an earlier analysis provides them (it does
    without otherwise); ``provides`` the kind of its own result. A name in ``requires`` that no
    analysis provides but that is an analysis of the chain (``requires=("hvd",)``, as the
    contract read before typed results) asks for that analysis to run earlier on the channel.
    """

    name: str
    params: tuple[Param, ...]
    run: Callable[[AnalysisContext, dict[str, Any]], Result | AnalysisResult]
    help: str = ""
    requires: tuple[Any, ...] = ()
    provides: Any = None
    uses: tuple[Any, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "requires", _kinds(self.requires, "requires", self.name))
        object.__setattr__(self, "uses", _kinds(self.uses, "uses", self.name))
        if self.provides is not None:
            if isinstance(self.provides, (tuple, list)):
                raise TypeError(f"analysis {self.name!r}: provides names one result kind (the "
                                f"kind of the Result its run returns); got {self.provides!r}")
            try:
                object.__setattr__(self, "provides", kind_name(self.provides))
            except TypeError as exc:
                raise TypeError(f"analysis {self.name!r}: provides: {exc}") from None


@dataclass(frozen=True)
class CliCommand:
    """An extra ``fsi-lab`` subcommand, added by a plugin's ``fsi_lab_addcommands(subparsers)``
    hook with :meth:`add_to` (e.g. ``fsi-lab bench``, which starts the simulated instruments).

    ``configure(parser)`` adds the arguments to an argparse parser; ``run(args)`` does the work
    and returns the exit code.
    """

    name: str
    help: str
    configure: Callable[[Any], None]
    run: Callable[[Any], int]

    def add_to(self, subparsers: Any) -> Any:
        """Add the command to ``subparsers`` (the ``fsi_lab_addcommands`` hook's argument);
        returns its parser."""
        parser = subparsers.add_parser(self.name, help=self.help)
        self.configure(parser)
        parser.set_defaults(func=self.run)
        return parser


DESCRIPTORS = {
    "instrument": InstrumentPlugin,
    "excitation": ExcitationPlugin,
    "analysis": AnalysisPlugin,
}


def check_descriptor(kind: str, descriptor: Any) -> None:
    """Raise TypeError or ValueError if ``descriptor`` breaks the contract of ``kind``."""
    expected = DESCRIPTORS[kind]
    if not isinstance(descriptor, expected):
        raise TypeError(f"returned {type(descriptor).__name__}, expected {expected.__name__}")
    if not isinstance(descriptor.name, str) or not descriptor.name:
        raise ValueError("has no name")
    if not all(isinstance(p, Param) for p in descriptor.params):
        raise TypeError(f"{descriptor.name}: params must be a tuple of fsi_lab.params.Param")
    names = [p.name for p in descriptor.params]
    if len(set(names)) != len(names):
        raise ValueError(f"{descriptor.name}: a parameter is declared twice")
    for attr in ("open", "generate", "run"):
        if hasattr(descriptor, attr) and not callable(getattr(descriptor, attr)):
            raise TypeError(f"{descriptor.name}: {attr} is not callable")
    for attr in ("check", "duration"):
        if getattr(descriptor, attr, None) is not None and not callable(getattr(descriptor, attr)):
            raise TypeError(f"{descriptor.name}: {attr} is not callable")
    if kind == "instrument" and descriptor.role not in ROLES:
        raise ValueError(
            f"{descriptor.name}: role {descriptor.role!r} is not one of {', '.join(ROLES)}"
        )
    if kind == "analysis" and descriptor.provides is not None \
            and descriptor.provides in descriptor.requires + descriptor.uses:
        raise ValueError(f"{descriptor.name}: provides {descriptor.provides!r} and also "
                         "requires or uses it; an analysis reads what earlier ones provide")
    if kind == "instrument":
        for setting in ROLE_INTERFACES[descriptor.role].run_settings:
            problem = setting.problem(descriptor.params)
            if problem:
                raise ValueError(f"{descriptor.name} ({descriptor.role}): {problem}")
