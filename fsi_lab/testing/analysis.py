"""The analysis contract: what every analysis plugin must do, as tests its author inherits.

::

    from fsi_lab.testing import AnalysisContract

    class TestMyAnalysis(AnalysisContract):
        plugin = "my-analysis"          # its name, as installed (or its AnalysisPlugin)

pytest then runs, on this class, the tests below; each failure says what to change:

- it declares what it requires, uses and provides as result kinds that the installed analyses
  provide (a misspelt kind is found here, not in a user's run);
- on a good record (two decaying modes of a velocity channel, with a base acceleration
  reference) it writes what it declares: the typed result of the kind it provides, datasets
  that are numeric arrays with their units, values HDF5 stores and a JSON-ready summary, stored
  in a real run file and read back;
- it refuses an empty record, a too-short one, one holding NaN and a constant one with
  :class:`fsi_lab.errors.AnalysisError` (a clear message, not an IndexError from deep inside);
- it never changes its input: the channels and the typed results of earlier analyses are the
  same after it ran (they are made read-only while it runs, so that writing into them fails
  at the line that does it).

The analyses providing what it requires run before it on the same record (the installed ones);
``before`` names others. Override :meth:`channels` for an analysis that needs another record.
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
import pytest

from fsi_lab.chain import stored_result
from fsi_lab.contract import AnalysisContext, AnalysisPlugin, ChannelData, Result, SharedRecord
from fsi_lab.errors import FsiLabError
from fsi_lab.params import REQUIRED, validate
from fsi_lab.testing._common import (
    all_broken,
    broken,
    descriptor_of,
    difference,
    freeze,
    json_problem,
    with_plugin,
)

#: The bad records every analysis must refuse: (name, what it is, how it is made from the good
#: record's samples).
BAD_RECORDS = {
    "empty": ("an empty record (0 samples)", lambda x: x[:0]),
    "too-short": ("a record of 3 samples", lambda x: x[:3]),
    "nan": ("a record holding NaN", lambda x: np.where(np.arange(x.size) == x.size // 2,
                                                        np.nan, x)),
    "constant": ("a constant record", lambda x: np.full(x.size, 0.01)),
}


def two_decaying_modes(rate: float = 2000.0, seconds: float = 4.0, seed: int = 1
                       ) -> dict[str, ChannelData]:
    """What a run on the bench records after an impulse of the base: a base acceleration
    (m/s^2) with a half-sine pulse of 20 ms, then at rest, and the tip velocity (m/s) decaying
    freely from it in two modes, 17 Hz and 47 Hz, with a little noise on both."""
    t = np.arange(int(rate * seconds)) / rate
    rng = np.random.default_rng(seed)
    pulse = 0.02
    base = np.where(t < pulse, 2.0 * np.sin(np.pi * t / pulse), 0.0)
    free = np.clip(t - pulse, 0.0, None)
    tip = np.where(t >= pulse, 0.05 * np.exp(-0.8 * free) * np.sin(2 * np.pi * 17.0 * free)
                   + 0.01 * np.exp(-2.0 * free) * np.sin(2 * np.pi * 47.0 * free), 0.0)
    tip = tip + 1e-5 * rng.standard_normal(t.size)
    base = base + 1e-4 * rng.standard_normal(t.size)
    return {"tip": ChannelData("tip", tip, rate, "velocity", "m/s"),
            "base": ChannelData("base", base, rate, "acceleration", "m/s^2")}


class AnalysisOutcome:
    """What happened when the chain ran up to and including the analysis under test."""

    def __init__(self) -> None:
        self.before_failed: dict[str, str] = {}   # an analysis before it that failed: why
        self.context: AnalysisContext | None = None
        self.returned: Any = None
        self.raised: BaseException | None = None
        self.provided: dict[str, Result] = {}     # the typed results it was given
        self.provided_copy: dict[str, Result] = {}  # a deep copy taken before it ran


class AnalysisContract:
    """Contract tests of an analysis plugin; subclass it in a ``Test...`` class.

    Attributes
    ----------
    plugin
        Name of the analysis plugin as installed, or its :class:`AnalysisPlugin`.
    params
        Parameter values given to it (the others take their declared defaults; give the
        required ones).
    before
        Names of the analyses run before it on the same record; None: those (installed)
        providing what it requires, in an order the chain accepts.
    channel
        Name of the analysed channel of :meth:`channels`.
    reference
        Name of the base acceleration channel given to the analyses, or None.
    mass_per_length
        mu + M, kg/m, given to the analyses (``--mass-per-length``), or None.
    specimen
        The :class:`fsi_lab.specimen.Specimen` given to the analyses, or None.
    """

    plugin: str | AnalysisPlugin = ""
    params: dict[str, Any] = {}
    before: tuple[str, ...] | None = None
    channel = "tip"
    reference: str | None = "base"
    mass_per_length: float | None = 0.13
    specimen: Any = None

    # ------------------------------------------------------------------ what to override
    def channels(self) -> dict[str, ChannelData]:
        """The good record: every channel of it by name (:func:`two_decaying_modes`)."""
        return two_decaying_modes()

    # ------------------------------------------------------------------ helpers
    def _analysis(self, registry) -> AnalysisPlugin:
        return descriptor_of("analysis", self.plugin, registry, AnalysisPlugin)

    def _chain_before(self, registry, plugin: AnalysisPlugin) -> list[str]:
        if self.before is not None:
            return list(self.before)
        names: list[str] = []

        def need(analysis: AnalysisPlugin) -> None:
            for kind in analysis.requires:
                givers = [registry.get("analysis", n) for n in registry.names("analysis")
                          if n != plugin.name]
                giver = next((g for g in givers if g.provides == kind or g.name == kind), None)
                if giver is not None and giver.name not in names:
                    need(giver)
                    names.append(giver.name)

        need(plugin)
        return names

    def _params(self, plugin: AnalysisPlugin, values: dict[str, Any]) -> dict[str, Any]:
        missing = [p.name for p in plugin.params if p.default is REQUIRED and p.name not in values]
        if missing:
            broken(plugin.name, f"parameter(s) {', '.join(missing)} have no default: give "
                                "values in the test class's params")
        return validate(plugin.params, values, plugin.name)

    def _run(self, registry, channels: dict[str, ChannelData], frozen: bool = False
             ) -> AnalysisOutcome:
        """Run the analyses before it, then it, on ``channels[self.channel]``, as the chain
        does (typed results handed on); its own exception is kept, not turned into a message.
        ``frozen``: the typed results it is given are copied, then made read-only."""
        registry = with_plugin(registry, "analysis", self.plugin)
        plugin = self._analysis(registry)
        if self.channel not in channels:
            pytest.fail(f"channels() has no channel {self.channel!r} (the class attribute "
                        f"channel); it has {', '.join(channels)}", pytrace=False)
        outcome = AnalysisOutcome()
        provided: dict[str, Result] = {}
        results: dict[str, Any] = {}
        unavailable: dict[str, str] = {}
        shared = SharedRecord(channels[self.channel])
        for name in self._chain_before(registry, plugin) + [plugin.name]:
            analysis = plugin if name == plugin.name else registry.get("analysis", name)
            params = self._params(analysis, dict(self.params) if analysis is plugin else {})
            context = AnalysisContext(
                channel=channels[self.channel], channels=channels, results=dict(results),
                specimen=self.specimen, mass_per_length=self.mass_per_length,
                reference=self.reference, failed=dict(outcome.before_failed),
                provided=dict(provided), unavailable=dict(unavailable), shared=shared,
                plugin=name, declared=analysis.requires + analysis.uses)
            if analysis is plugin:
                missing = [k for k in plugin.requires if k not in provided and k not in results]
                if missing:  # the chain would not run it: the earlier analysis said why
                    return outcome
                outcome.context = context
                outcome.provided = provided
                if frozen:
                    outcome.provided_copy = copy.deepcopy(provided)
                    freeze(provided)
                try:
                    outcome.returned = plugin.run(context, params)
                except Exception as exc:  # noqa: BLE001 - judged by the test
                    outcome.raised = exc
                return outcome
            try:
                record, typed = stored_result(analysis, analysis.run(context, params))
            except Exception as exc:  # noqa: BLE001 - the chain records it and goes on
                outcome.before_failed[name] = f"{type(exc).__name__}: {exc}"
                if analysis.provides is not None:
                    unavailable[analysis.provides] = name
                continue
            results[name] = record
            if typed is not None:
                provided[typed.kind] = typed
        return outcome

    def _good(self, registry) -> tuple[AnalysisPlugin, AnalysisOutcome]:
        registry = with_plugin(registry, "analysis", self.plugin)
        plugin = self._analysis(registry)
        outcome = self._run(registry, self.channels())
        if outcome.before_failed and outcome.context is None:
            pytest.fail(f"{plugin.name}: the analyses run before it failed on the good record, "
                        f"so it was not run: {outcome.before_failed}; give a record they "
                        "accept (override channels()) or the analyses to run (before)",
                        pytrace=False)
        if outcome.raised is not None:
            exc = outcome.raised
            broken(plugin.name, f"failed on the good record of channel {self.channel!r} "
                                f"({type(exc).__name__}: {exc}); it must analyse a record such "
                                "as this one (or override channels() with the record it is made "
                                "for)")
        return plugin, outcome

    # ------------------------------------------------------------------ the contract
    def test_declares_what_it_requires_uses_and_provides(self, fsi_lab_registry):
        registry = with_plugin(fsi_lab_registry, "analysis", self.plugin)
        plugin = self._analysis(registry)
        others = [registry.get("analysis", n) for n in registry.names("analysis")
                  if n != plugin.name]
        kinds = {o.provides for o in others if o.provides} | {o.name for o in others}
        problems = []
        for what in ("requires", "uses"):
            for kind in getattr(plugin, what):
                if kind not in kinds:
                    known = ", ".join(sorted(k for k in kinds if k)) or "none"
                    problems.append(f"{what} {kind!r}, which no installed analysis provides "
                                    f"(kinds provided: {known}); fix the kind's name, or "
                                    "install the analysis that provides it")
        if not plugin.help:
            problems.append("has no help: give AnalysisPlugin(help=...) one sentence saying "
                            "what it computes (fsi-lab plugins shows it)")
        for param in plugin.params:
            if not param.help:
                problems.append(f"parameter {param.name!r} has no help: give Param(help=...) "
                                "(the GUI's tooltip, fsi-lab plugins -v)")
        all_broken(plugin.name, problems)

    def test_writes_what_it_declares_with_units(self, fsi_lab_registry, tmp_path):
        plugin, outcome = self._good(fsi_lab_registry)
        try:
            record, typed = stored_result(plugin, outcome.returned)
        except TypeError as exc:
            problem = str(exc)
        else:
            problem = ""
        if problem:
            broken(plugin.name, problem)
        if plugin.provides is not None and (typed is None or typed.kind != plugin.provides):
            broken(plugin.name, f"declares provides={plugin.provides!r} but returned no result "
                                "of that kind")
        if not (record.datasets or record.attrs or record.summary):
            broken(plugin.name, "wrote nothing: its result has no datasets, attrs or summary")
        for name, array in record.datasets.items():
            array = np.asarray(array)
            if array.dtype.kind not in "biufc":
                broken(plugin.name, f"dataset {name!r} is not numeric ({array.dtype}); store "
                                    "numbers in datasets, text in attrs")
            if name not in record.units:
                broken(plugin.name, f"dataset {name!r} has no unit: give it in units "
                                    f"(units={{{name!r}: 'm/s'}}; '' for a dimensionless one)")
        for name in record.units:
            if name not in record.datasets:
                broken(plugin.name, f"units names {name!r}, which is not one of its datasets "
                                    f"({', '.join(record.datasets) or 'none'})")
        for name, axis in record.axes.items():
            if name not in record.datasets or axis not in record.datasets:
                broken(plugin.name, f"axes {{{name!r}: {axis!r}}} must name two of its "
                                    "datasets")
            if np.shape(record.datasets[axis])[-1:] != np.shape(record.datasets[name])[-1:]:
                broken(plugin.name, f"dataset {name!r} is drawn against {axis!r}, whose length "
                                    "differs: an axis has one value per point of the dataset")
        problem = json_problem(record.summary)
        if problem:
            broken(plugin.name, f"its summary cannot be printed as JSON ({problem}); give "
                                "numbers, strings, lists and dicts")
        for entry in record.summary.get("components", []):
            if not isinstance(entry, dict) or "index" not in entry:
                broken(plugin.name, "each entry of its summary's 'components' must be a dict "
                                    "with the component's 'index'")
        self._stored_and_read_back(plugin, record, tmp_path)

    def _stored_and_read_back(self, plugin, record, tmp_path) -> None:
        """Store the result in a real run file as the chain does and read it back."""
        import h5py

        from fsi_lab.runfile import RunFileWriter, write_analysis

        path = tmp_path / "contract.h5"
        writer = RunFileWriter(path, {"uuid": "0" * 32, "start_time": "2026-01-01T00:00:00",
                                      "kind": "measured", "run_name": "contract",
                                      "profile": "", "software_version": "contract",
                                      "plugin_versions": {}, "profile_path": "",
                                      "overrides": []})
        channel = self.channels()[self.channel]
        writer.create_channel(channel.name, {"units": channel.unit, "quantity": channel.quantity,
                                             "sample_rate": channel.sample_rate, "t0": 0.0,
                                             "sensitivity": 1.0})
        writer.append(channel.name, np.asarray(channel.data))
        writer.set_attrs({"exit_status": "completed"})
        writer.close()
        key = f"{channel.name}/{plugin.name}"
        problem = ""
        try:
            write_analysis(path, {key: {"datasets": record.datasets, "units": record.units,
                                        "axes": record.axes,
                                        "attrs": {"status": "ok", **record.attrs},
                                        "params": {}}},
                           {"run": str(path), "channels": {channel.name: record.summary}})
        except FsiLabError as exc:
            problem = str(exc)
        if problem:
            broken(plugin.name, f"its result cannot be stored in a run file: {problem}; store "
                                "arrays in datasets and numbers or strings (or lists of them) "
                                "in attrs")
        with h5py.File(path, "r") as handle:
            group = handle[f"analysis/{key}"]
            for name in record.datasets:
                unit = group[name].attrs.get("units")
                unit = unit.decode() if isinstance(unit, bytes) else unit
                if unit != record.units[name]:
                    broken(plugin.name, f"dataset {name!r} was stored with unit {unit!r}, not "
                                        f"{record.units[name]!r}")

    @pytest.mark.parametrize("bad", list(BAD_RECORDS))
    def test_refuses_a_bad_record_with_a_clear_error(self, fsi_lab_registry, bad):
        what, make = BAD_RECORDS[bad]
        channels = dict(self.channels())
        good = channels[self.channel]
        data = make(np.asarray(good.data, dtype=float))
        channels[self.channel] = ChannelData(good.name, data, good.sample_rate, good.quantity,
                                             good.unit, good.t0)
        plugin = self._analysis(fsi_lab_registry)
        outcome = self._run(fsi_lab_registry, channels)
        if outcome.context is None:
            return  # an analysis it requires refused the record first: the chain says so
        exc = outcome.raised
        if exc is None:
            broken(plugin.name, f"accepted {what} of channel {self.channel!r} and returned "
                                f"{type(outcome.returned).__name__}; check the record and "
                                "raise fsi_lab.errors.AnalysisError saying what it lacks (e.g. "
                                f"'{plugin.name}: channel {self.channel}: {data.size} samples, "
                                "need at least ...')")
        if not isinstance(exc, FsiLabError):
            broken(plugin.name, f"raised {type(exc).__name__} ({exc}) on {what} of channel "
                                f"{self.channel!r}; check the record first and raise "
                                "fsi_lab.errors.AnalysisError naming the channel and the "
                                "condition")
        if not str(exc).strip():
            broken(plugin.name, f"refused {what} with an empty message; say what is wrong "
                                "with the record")

    def test_never_changes_its_input(self, fsi_lab_registry):
        channels = self.channels()
        kept = copy.deepcopy(channels)
        for channel in channels.values():
            np.asarray(channel.data).flags.writeable = False
        plugin = self._analysis(fsi_lab_registry)
        outcome = self._run(fsi_lab_registry, channels, frozen=True)
        if outcome.context is None:
            pytest.fail(f"{plugin.name}: the analyses before it failed on the good record: "
                        f"{outcome.before_failed}", pytrace=False)
        exc = outcome.raised
        if isinstance(exc, ValueError) and "read-only" in str(exc):
            broken(plugin.name, f"writes into its input ({exc}); work on a copy, e.g. "
                                "np.array(context.channel.data, dtype=float)")
        if exc is not None:
            broken(plugin.name, f"failed on the good record ({type(exc).__name__}: {exc})")
        changed = difference({n: c.data for n, c in kept.items()},
                             {n: c.data for n, c in channels.items()}, "channel") or \
            difference(outcome.provided_copy, outcome.provided, "context.result")
        if changed:
            broken(plugin.name, f"changed its input: {changed}; work on a copy")
