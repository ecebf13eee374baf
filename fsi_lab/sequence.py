"""Headless test sequences: a plan's runs one after the other, each as ``fsi-lab run`` does it.

Every run's profile is validated and safety-checked before the first run starts
(:func:`~fsi_lab.plan.check_plan`). Each run is carried out by :class:`~fsi_lab.runner.Runner`,
which leaves the bench in its safe state (amplifier output off, source at 0 V, read back) at
the end of every run, however it ends; the next run starts only from that confirmed state. The
sequence stops when a run fails (unless the plan says ``on_failure = "continue"``), and always
when an interlock tripped, when the bench was not confirmed safe, or on Ctrl+C or SIGTERM (the
run in progress ends as ``fsi-lab run`` ends it). The record (:mod:`fsi_lab.seqfile`) is
rewritten before and after every run, so :func:`resume` continues with the first run that did
not complete, also after ``kill -9``; it first completes the analysis of a completed run whose
analysis was stopped (or failed), which the record then holds.

After every completed run the completed runs are aggregated (:mod:`fsi_lab.aggregate`: modes
grouped by frequency, C_i and C_f fitted to the union of their free decays, the curves on one
amplitude axis, the spread between runs) and the aggregation is stored in the record; each run
is identified once per process (through the sequence's executor), a resumed sequence
identifies the runs completed before first. With ``[plan.stop_when]`` the sequence stops, its
remaining runs skipped, once the aggregated quantity's interval is narrow enough.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fsi_lab.bench_access import unsafe_roles
from fsi_lab.errors import FsiLabError, InputFileError, ProfileError, RunAborted
from fsi_lab.events import EventBus, Progress
from fsi_lab.plan import (
    STOP_SYMBOLS,
    STOP_UNITS,
    Plan,
    PlannedRun,
    check_plan,
    is_seed,
    load_plan,
    require_stop_can_act,
)
from fsi_lab.registry import Registry
from fsi_lab.runfile import read_analysis_summary, read_run, utc_now
from fsi_lab.seqfile import SEQUENCE_FILE, SequenceRecord, compact_results, holder, load_record
from fsi_lab.signals import INTERRUPTED, RunSignals, SignalNote
from fsi_lab.summary import coefficient_words, nothing_identified

#: Exit code of ``fsi-lab sequence`` for each final status.
EXIT_FOR_STATUS = {"completed": 0, "failed": 1, "interrupted": 130, "running": 1}
#: How a completed run's ``error`` begins when its analysis identified nothing
#: (:func:`fsi_lab.summary.nothing_identified`).
NOTHING_IDENTIFIED = "nothing was identified: "
#: The settle wait is slept in slices this long, s (progress is reported after each).
SETTLE_SLICE_S = 0.5


def settle_wait(seconds: float) -> None:
    """One slice of the settle wait (Ctrl+C and SIGTERM end it at once)."""
    time.sleep(seconds)


def interlocks_tripped(final_states: dict[str, dict[str, Any]]) -> list[str]:
    """``role: name`` of every interlock an instrument reported active after the run."""
    tripped = []
    for role, state in final_states.items():
        locks = state.get("interlocks") if isinstance(state, dict) else None
        if isinstance(locks, dict):
            tripped.extend(f"{role}: {name}" for name, on in locks.items() if on)
    return tripped


def summarise_safety(report) -> dict[str, Any]:
    """The figures of a safety report a sequence's record keeps for each run."""
    data = report.as_dict()
    return {key: data[key] for key in ("peak_drive_v", "gain", "predicted_stroke_mm")}


@dataclass
class SequenceRunner:
    """Carries out the pending runs of a sequence and keeps its record.

    Parameters
    ----------
    plan
        The plan, checked (:func:`~fsi_lab.plan.check_plan`).
    record
        Its record, saved in the directory of the run files.
    registry
        Loaded plugins.
    bus
        Events of the runs and of the sequence (``[sequence]`` log lines, ``settle`` progress).
    signals
        The command's Ctrl+C and SIGTERM handling (installed, raising): held while the record
        is written, so that it is never cut short.
    note
        The command's note of a signal, checked before each run (one whose exception a library
        swallowed between two runs still stops the sequence).
    """

    plan: Plan
    record: SequenceRecord
    registry: Registry
    bus: EventBus
    signals: RunSignals
    note: SignalNote
    #: a run's file could not be finalised (a full disk): HDF5 may crash at exit
    file_abandoned: bool = False
    #: identifies the completed runs for the aggregation (None: in this process)
    executor: Any = None
    #: each completed run's identification, by run index (kept for the next aggregations)
    extracts: dict[int, Any] = field(default_factory=dict)
    _identified: dict[str, Any] = field(default_factory=dict)
    _runs_registry: Registry | None = None

    def run(self) -> str:
        """Run every run not completed yet, in order; returns the final status
        (``completed``, ``failed`` or ``interrupted``), also recorded."""
        status, error = "failed", "the sequence ended unexpectedly"
        try:
            status, error = self._loop()
        except (KeyboardInterrupt, RunAborted) as exc:
            reason = str(exc) or INTERRUPTED
            for entry in self.record.runs:
                if entry["status"] == "running":  # outside the run: its file says how it ended
                    settle_unfinished(self.record, entry, self.registry)
            status, error = "interrupted", f"interrupted between runs: {reason}"
        except BaseException as exc:
            error = f"{type(exc).__name__}: {exc}"
            raise
        finally:
            self.record.attrs.update(status=status, error=error, stop_time=utc_now())
            with self.signals.held():
                self.record.save()
            self.bus.log("INFO" if status == "completed" else "WARNING",
                         f"[sequence] {status}" + (f": {error}" if error else ""))
        return status

    def _loop(self) -> tuple[str, str]:
        ran = 0
        for entry, profile in analyses_to_complete(self.plan, self.record, self.registry):
            self._complete_analysis(entry, profile)
            self._save()
        if self._stale():  # resumed: the runs completed before, as the record does not hold
            stop = self._aggregate_safely()
            self._save()
            if stop is not None:
                return stop
        for entry, planned in zip(self.record.runs, self.plan.runs):
            if entry["status"] in ("completed", "skipped"):
                continue
            if ran and planned.settle_s > 0:
                self._settle(planned)
            self.note.check()
            ran += 1
            stop = self._run_one(entry, planned)
            if stop is not None:
                return stop
        failed = [e["index"] for e in self.record.runs
                  if e["status"] not in ("completed", "skipped")]
        if failed:
            return "failed", (f"{len(failed)} of {len(self.record.runs)} runs did not complete "
                              f"(run {', '.join(map(str, failed))}); fsi-lab sequence --resume "
                              f"{self.record.directory} runs them again")
        self._unmet()
        return "completed", ""

    def _unmet(self) -> None:
        """Record what a sequence whose every run completed did not reach: no run identified
        anything (``nothing_identified``: exit code 2, as ``fsi-lab run`` for one such run),
        or its ``[plan.stop_when]`` never stopped it (``stop_not_reached``)."""
        completed = self._completed()
        for key in ("nothing_identified", "stop_not_reached"):
            self.record.attrs.pop(key, None)
        refused = [entry for entry in completed
                   if entry.get("error", "").startswith(NOTHING_IDENTIFIED)]
        if completed and len(refused) == len(completed):
            self.record.attrs["nothing_identified"] = (
                f"none of the {len(completed)} completed runs identified a mode (run "
                f"{refused[0]['index']}: {refused[0]['error'][len(NOTHING_IDENTIFIED):]})")
            self.bus.log("ERROR", f"[sequence] {self.record.attrs['nothing_identified']}")
        stop = self.plan.stop_when
        if stop is not None and not self.record.attrs.get("stopped_early"):
            self.record.attrs["stop_not_reached"] = (
                f"[plan.stop_when] was never reached ({stop.describe()}) in "
                f"{len(completed)} completed run{'s' * (len(completed) != 1)}")
            self.bus.log("WARNING", f"[sequence] {self.record.attrs['stop_not_reached']}")

    def _settle(self, planned: PlannedRun) -> None:
        """Wait ``settle_s`` before ``planned``; the bench is in the safe state meanwhile."""
        self.bus.log("INFO", f"[sequence] settling {planned.settle_s:g} s before run "
                             f"{planned.index}")
        deadline = time.monotonic() + planned.settle_s
        while (left := deadline - time.monotonic()) > 0:
            settle_wait(min(left, SETTLE_SLICE_S))
            self.bus.emit(Progress("settle", 1.0 - max(0.0, deadline - time.monotonic())
                                   / planned.settle_s, f"settling before run {planned.index}"))

    def _save(self) -> None:
        """Write the record with Ctrl+C and SIGTERM held back, then raise one that came."""
        with self.signals.held():
            self.record.save()
        self.signals.raise_pending()

    def _run_one(self, entry: dict[str, Any], planned: PlannedRun) -> tuple[str, str] | None:
        """Carry out one run; None to go on, or the sequence's final status and why."""
        from fsi_lab.runner import Runner

        if entry["run_file"] or entry["status"] != "pending":
            entry["attempts"].append({key: entry[key] for key in (
                "run_file", "status", "start_time", "stop_time", "error")})
        profile = self.plan.profile_for(planned, self.registry)
        self._identified = {}
        runner = Runner(profile, self._capturing_registry(), self.record.directory,
                        bus=self.bus)
        path = runner.reserve_file()
        entry.update(status="running", run_file=path.name, start_time=utc_now(), stop_time="",
                     error="", interrupted=False, results={})
        self._save()
        self.bus.log("INFO", f"[sequence] {planned.label}: {path.name}")
        try:
            outcome = runner.run()
        except FsiLabError as exc:  # refused before anything was driven
            entry.update(status="failed", error=str(exc), stop_time=utc_now(), run_file="")
            self._save()
            return "failed", f"{planned.label}: refused: {exc}"
        error = outcome.error or ""
        if outcome.exit_status == "completed" and outcome.summary is None \
                and profile.analysis["chain"]:  # stopped, failed or skipped (a signal at its end)
            error = (f"{error or 'its analysis was skipped (interrupted as the run ended)'}; "
                     f"{self._resume_advice()}")
        if outcome.exit_status == "completed" and outcome.summary and not error:
            error = nothing_identified(outcome.summary, self.registry) or ""
        entry.update(status=outcome.exit_status, stop_time=utc_now(),
                     error=error, interrupted=outcome.interrupted,
                     run_file=outcome.path.name if outcome.path else "",
                     results=compact_results(outcome.summary),
                     analysed=outcome.summary is not None)
        self.file_abandoned = self.file_abandoned or outcome.file_abandoned
        stop = None
        if outcome.exit_status == "completed" and not (outcome.interrupted
                                                       or outcome.file_abandoned):
            # aggregated before the record is written: one write records the run and it
            # (killed meanwhile, the run is settled from its file and aggregated on resume)
            self._keep_identification(entry, profile)
            stop = self._aggregate_safely()
        with self.signals.held():
            self.record.save()
        label = planned.label
        if outcome.exit_status == "aborted" or outcome.interrupted:
            return "interrupted", f"{label}: {error or INTERRUPTED}"
        unsafe = unsafe_roles(outcome.final_states)
        if unsafe:
            return "failed", (f"{label}: the bench was NOT confirmed safe after the run ("
                              + "; ".join(f"{r}: {why}" for r, why in unsafe.items())
                              + "); check it by hand before resuming")
        tripped = interlocks_tripped(outcome.final_states)
        if tripped:
            return "failed", (f"{label}: interlock tripped ({', '.join(tripped)}); clear it "
                              "and check the bench before resuming")
        if outcome.file_abandoned:
            return "failed", f"{label}: {outcome.error}"
        if outcome.exit_status == "failed":
            if self.plan.on_failure == "stop":
                return "failed", f"{label} failed: {outcome.error}"
            self.bus.log("WARNING", f"[sequence] {label} failed ({outcome.error}); continuing "
                                    "(on_failure = \"continue\")")
        self.signals.raise_pending()
        return stop

    def _resume_advice(self) -> str:
        return (f"fsi-lab sequence --resume {self.record.directory} analyses it and records "
                f"its results in {SEQUENCE_FILE} too")

    def _complete_analysis(self, entry: dict[str, Any], profile) -> None:
        """Record the analysis of a completed run whose record holds none: the one its run
        file holds (``fsi-lab analyze`` stored it since), else one made now and stored in the
        run file as the run's own analysis is (its identification kept for the aggregation).
        An analysis that fails is logged and recorded in the run's ``error``; the sequence
        goes on."""
        from fsi_lab.store import analyse_and_store

        path = self.record.directory / entry["run_file"]
        label = run_label(entry)
        try:
            summary = read_analysis_summary(path)
            if summary is None:
                self.bus.log("INFO", f"[sequence] {label}: completed without its analysis; "
                                     f"analysing {path.name}")
                self._identified = {}
                run = read_run(path, load_data=False, lazy=True)  # a channel is read when used
                summary = analyse_and_store(path, run.channels, profile.analysis,
                                            profile.analysis_params, self._capturing_registry(),
                                            specimen=profile.specimen, bus=self.bus)
                self._keep_identification(entry, profile)
            else:
                self.bus.log("INFO", f"[sequence] {label}: recording the analysis its run file "
                                     f"holds ({path.name})")
        except (FsiLabError, OSError) as exc:
            entry["error"] = f"analysis not stored: {exc}; run fsi-lab analyze on the run file"
            self.bus.log("ERROR", f"[sequence] {label}: {entry['error']}")
            return
        entry.update(results=compact_results(summary), analysed=True,
                     error=nothing_identified(summary, self.registry) or "")

    def _aggregate_safely(self) -> tuple[str, str] | None:
        """:meth:`_aggregate`; an aggregation that fails is logged (the runs go on, the record
        keeps the previous aggregation), as a failing analysis is."""
        try:
            return self._aggregate()
        except Exception as exc:  # noqa: BLE001 - logged, the sequence goes on
            self.bus.log("ERROR", f"[sequence] the aggregation failed ({type(exc).__name__}: "
                                  f"{exc}); fsi-lab aggregate {self.record.directory} tries "
                                  "again")
            return None

    # ------------------------------------------------------------------ aggregation
    def _capturing_registry(self) -> Registry:
        """The registry the runs use: the same plugins, but the modes ``hvd`` (method
        ``bands``) identifies in a run's analysis are kept for its aggregation, so that a run
        is not identified twice."""
        if self._runs_registry is not None:
            return self._runs_registry
        hvd = self.registry.descriptors.get("analysis", {}).get("hvd")
        if hvd is None:
            self._runs_registry = self.registry
            return self.registry
        from fsi_lab.aggregate_extract import identification_of

        original = hvd.run

        def run(context, params):
            result = original(context, params)
            ident = identification_of(result)
            if ident is not None:
                self._identified[context.channel.name] = (ident, context)
            return result

        descriptors = {kind: dict(table) for kind, table in self.registry.descriptors.items()}
        descriptors["analysis"]["hvd"] = dataclasses.replace(hvd, run=run)
        self._runs_registry = Registry(descriptors, self.registry.records)
        return self._runs_registry

    def _keep_identification(self, entry: dict[str, Any], profile) -> None:
        """The extract of a run just completed, from the identification its analysis made
        (nothing when it made none: the aggregation identifies the run itself)."""
        from fsi_lab.aggregate_extract import ExtractTask, extract_identified

        if not self._identified or not entry["run_file"]:
            return
        task = ExtractTask(str(self.record.directory / entry["run_file"]), label=run_label(entry))
        try:
            self.extracts[entry["index"]] = extract_identified(task, self._identified, profile,
                                                               self.registry)
        except FsiLabError:
            pass  # (no specimen: the aggregation names it when it identifies the run)
        self._identified = {}

    def _completed(self) -> list[dict[str, Any]]:
        return [e for e in self.record.runs if e["status"] == "completed" and e["run_file"]]

    def _stale(self) -> bool:
        """Whether the record's aggregation misses completed runs (or holds others)."""
        held = (self.record.aggregate or {}).get("sequence_runs")
        return [e["index"] for e in self._completed()] != (held or [])

    def _aggregate(self) -> tuple[str, str] | None:
        """Identify the completed runs not identified yet, aggregate every completed run into
        the record, and check ``[plan.stop_when]``: the final status and why when it says
        stop, else None."""
        from fsi_lab.aggregate import aggregate_extracts, extract_runs
        from fsi_lab.executor import InProcess

        completed = self._completed()
        if not completed:
            return None
        tasks = [task for task, entry in zip(extract_tasks(self.record), completed)
                 if entry["index"] not in self.extracts]
        if tasks:
            by_file = {e["run_file"]: e["index"] for e in completed}
            for extract in extract_runs(tasks, self.executor or InProcess()):
                self.extracts[by_file[Path(extract.path).name]] = extract
                for error in extract.errors:
                    self.bus.log("WARNING", f"[sequence] not aggregated: {extract.label}: "
                                            f"{error}")
        agg = aggregate_extracts([self.extracts[e["index"]] for e in completed])
        agg["sequence_runs"] = [e["index"] for e in completed]
        self.record.aggregate = agg
        for mode in agg["modes"]:
            if "c_i" in mode:
                self.bus.log("INFO", f"[sequence] aggregate of {mode['runs']} run(s), mode at "
                                     f"{mode['frequency_hz']:.4g} Hz: C_i = {mode['c_i']:.4g} "
                                     f"kg/(m s), C_f = {mode['c_f']:.4g} kg/m^2")
        return self._stop_reached(agg, len(completed))

    def _stop_reached(self, agg: dict[str, Any], completed: int) -> tuple[str, str] | None:
        stop = self.plan.stop_when
        if stop is None or completed < stop.min_runs:
            return None
        mode = stop_mode(agg, stop)
        if mode is None or stop.quantity not in mode:
            return None
        value, (low, high) = mode[stop.quantity], mode[f"{stop.quantity}_ci95"]
        half = max(value - low, high - value) / abs(value) if value else float("inf")
        if half >= stop.relative_half_width:
            return None
        name, unit = STOP_SYMBOLS[stop.quantity], STOP_UNITS[stop.quantity]
        reason = (f"stopped after {completed} completed runs: {name} = {value:.4g} {unit} "
                  f"(95 %: {low:.4g} to {high:.4g} {unit}, +-{100 * half:.3g} %) at "
                  f"{mode['frequency_hz']:.4g} Hz is within the plan's "
                  f"+-{100 * stop.relative_half_width:g} %")
        warned = sum(1 for run in mode.get("per_run", []) if run.get("warnings"))
        if warned:
            # More runs narrow the interval, not an error the runs share: the stop says so.
            reason += (f"; {warned} of {len(mode['per_run'])} runs carry warnings on this mode "
                       "(the interval holds their noise and scatter, not an error they share: "
                       "read the aggregate's warnings beside it)")
        for entry in self.record.runs:
            if entry["status"] in ("pending", "failed", "aborted"):
                entry.update(status="skipped", error=f"not carried out: {reason}")
        self.record.attrs["stopped_early"] = reason
        self.bus.log("INFO", f"[sequence] {reason}")
        return "completed", ""


def prepare(plan_path: Path, registry: Registry) -> tuple[Plan, dict[int, dict[str, Any]]]:
    """Read ``plan_path`` and check every run's profile (nothing is written).

    Returns
    -------
    tuple
        The plan, and the safety figures of each run by index.

    Raises
    ------
    ProfileError
        A run is refused (:func:`~fsi_lab.plan.check_plan`), or the plan itself.
    """
    plan = load_plan(plan_path)
    require_stop_can_act(plan)
    reports = check_plan(plan, registry)
    return plan, {index: summarise_safety(report) for index, report in reports.items()}


def create(plan: Plan, safety: dict[int, dict[str, Any]], directory: Path) -> SequenceRecord:
    """A new record of ``plan`` in ``directory`` (call it holding the directory's lock).

    Raises
    ------
    InputFileError
        ``directory`` already holds a sequence.
    """
    if (directory / SEQUENCE_FILE).exists():
        raise InputFileError(
            f"{directory}: holds a sequence already ({SEQUENCE_FILE}); continue it with "
            f"fsi-lab sequence --resume {directory}, or choose another --out directory")
    return SequenceRecord.new(plan, directory, safety)


def resume(directory: Path, registry: Registry) -> tuple[Plan, SequenceRecord]:
    """The plan and record of the sequence in ``directory``, ready to continue: the plan and
    its base profile unchanged, the runs that did not complete checked again, the run that a
    killed process left behind settled from its run file.

    Raises
    ------
    InputFileError
        No record, or a damaged one.
    ProfileError
        The plan or the base profile changed since the sequence started, or a run to come is
        refused.
    """
    record = load_record(directory)
    attrs = record.attrs
    plan_path = Path(attrs["plan_path"])
    try:
        plan = load_plan(plan_path)
    except ProfileError as exc:
        raise ProfileError(f"{exc} (the plan of the sequence in {directory}; the record "
                           "holds its text)") from None
    for what, path, key in (("plan", plan.path, "plan"),
                            ("base profile", plan.profile_path, "profile")):
        text = plan.text if key == "plan" else plan.profile_text
        if text != attrs[key]:
            raise ProfileError(
                f"{path}: the sequence's {what} changed since the sequence in {directory} "
                f"started ({attrs['start_time']}); resuming would not carry out the plan it "
                f"recorded: put the file back as it was (the record holds it: fsi-lab show "
                f"{directory} --json) or start a new sequence in another directory")
    recorded = [list(e["overrides"]) for e in record.runs]
    if [list(r.overrides) for r in plan.runs] != recorded:
        def unseeded(overrides):
            return [o for o in overrides if not is_seed(o)]

        if [unseeded(r.overrides) for r in plan.runs] != [unseeded(o) for o in recorded]:
            raise ProfileError(f"{plan.path}: expands into other runs than the sequence in "
                               f"{directory} recorded; start a new sequence in another "
                               "directory")
        # a sequence started by a version that seeded the simulated bench otherwise (repeat k
        # with the profile's seed + k - 1): its runs keep the seeds it recorded
        plan = dataclasses.replace(plan, runs=tuple(
            dataclasses.replace(run, overrides=tuple(overrides))
            for run, overrides in zip(plan.runs, recorded)))
    for entry in record.runs:
        if entry["status"] == "running":
            settle_unfinished(record, entry, registry)
    if all(entry["status"] in ("completed", "skipped") for entry in record.runs) \
            and not analyses_to_complete(plan, record, registry):
        return plan, record  # nothing to resume: the record stays as it is
    remaining = tuple(r for r, e in zip(plan.runs, record.runs)
                      if e["status"] not in ("completed", "skipped"))
    reports = check_plan(plan, registry, remaining)
    for entry in record.runs:
        if entry["index"] in reports:
            entry["safety"] = summarise_safety(reports[entry["index"]])
    attrs["resumed"] = [*attrs.get("resumed", []), utc_now()]
    attrs.update(status="running", error="", stop_time="")
    return plan, record


def lacks_analysis(record: SequenceRecord, entry: dict[str, Any]) -> bool:
    """Whether ``entry`` is a completed run whose record holds no analysis results although
    its run file is there (its analysis was stopped, failed, or ended with the process)."""
    # (records written before ``analysed`` was kept: empty results stood for none)
    analysed = entry.get("analysed", bool(entry.get("results")))
    return (entry["status"] == "completed" and bool(entry["run_file"]) and not analysed
            and (record.directory / entry["run_file"]).is_file())


def analyses_to_complete(plan: Plan, record: SequenceRecord,
                         registry: Registry) -> list[tuple[dict[str, Any], Any]]:
    """The completed runs whose analysis the record lacks (:func:`lacks_analysis`) and can
    get: their run file holds one (stored by ``fsi-lab analyze`` since), or their profile has
    an analysis chain to make one. Each with its profile.

    Raises
    ------
    ProfileError
        A run's profile no longer parses (a plugin it names is gone).
    """
    todo = []
    for entry, planned in zip(record.runs, plan.runs):
        if not lacks_analysis(record, entry):
            continue
        profile = plan.profile_for(planned, registry)
        if profile.analysis["chain"] or _stored_summary(record, entry) is not None:
            todo.append((entry, profile))
    return todo


def _stored_summary(record: SequenceRecord, entry: dict[str, Any]) -> dict[str, Any] | None:
    """The analysis summary of ``entry``'s run file; None without one, or when the file cannot
    be read."""
    try:
        return read_analysis_summary(record.directory / entry["run_file"])
    except InputFileError:
        return None


def with_later_analyses(record: SequenceRecord) -> SequenceRecord:
    """``record`` as ``fsi-lab show`` presents it: a completed run whose record holds no
    analysis results but whose run file now holds an analysis (``fsi-lab analyze`` stored it
    after the sequence recorded the run) gets that analysis's results, with ``results_from``
    = ``"run file"`` and its error cleared. Only the runs in memory change: the record on disk
    is left to ``fsi-lab sequence --resume``."""
    for entry in record.runs:
        if lacks_analysis(record, entry):
            summary = _stored_summary(record, entry)
            if summary is not None:
                entry.update(results=compact_results(summary), results_from="run file",
                             analysed=True, error="")
    return record


def settle_unfinished(record: SequenceRecord, entry: dict[str, Any],
                      registry: Registry | None = None) -> None:
    """A run recorded as running whose end was not recorded (the process was killed, or
    interrupted just before or after the run): its run file says how it ended, completed (the
    record was not updated in time) or not; without one nothing was driven. A completed run
    whose stored analysis identified nothing gets that refusal as its error, as a run the
    sequence saw end does (judged with ``registry``, the plugins that analysed it)."""
    path = record.directory / entry["run_file"] if entry["run_file"] else None
    if path is None or not path.exists():
        entry.update(status="aborted", run_file="", stop_time=entry["stop_time"] or utc_now(),
                     error=entry["error"] or "ended before its run file was created (nothing "
                     "was driven)")
        return
    summary = None
    try:
        status = read_run(path, load_data=False).attrs.get("exit_status", "running")
        summary = read_analysis_summary(path) if status == "completed" else None
        error = ""
    except InputFileError as exc:
        status, error = "running", f"its run file cannot be read: {exc}"
    if status == "completed":
        refused = nothing_identified(summary, registry) if summary and registry else None
        entry.update(status="completed", results=compact_results(summary),
                     analysed=summary is not None,
                     error=(refused or "") if summary else "the sequence ended before the "
                     f"run's analysis was stored; fsi-lab sequence --resume {record.directory} "
                     "analyses it")
        return
    if status not in ("aborted", "failed"):
        status = "running"
        error = error or ("the sequence's process ended during the run (killed?); the run "
                          "file holds the record up to then")
    entry.update(status=status, error=error or entry["error"])


def running_note(record: SequenceRecord) -> str:
    """For a record whose status is ``running``: whether a process is running it now."""
    pid = holder(record.directory)
    if pid is not None:
        return f"running now (pid {pid})"
    return (f"its process ended without finishing it (killed?): fsi-lab sequence --resume "
            f"{record.directory} continues it")


def run_label(entry: dict[str, Any]) -> str:
    """``run 3 (excitation.height=0.01, repeat 1 of 2)``: a run of the record, for the
    aggregation."""
    details = [f"{path}={value}" for path, value in (entry.get("point") or {}).items()]
    if entry.get("repeats", 1) > 1:
        details.append(f"repeat {entry['repeat']} of {entry['repeats']}")
    return f"run {entry['index']}" + (f" ({', '.join(details)})" if details else "")


def extract_tasks(record: SequenceRecord, sets=(), mass_per_length: float | None = None):
    """An :class:`~fsi_lab.aggregate_extract.ExtractTask` per completed run of ``record``
    that has its run file."""
    from fsi_lab.aggregate_extract import ExtractTask

    return [ExtractTask(str(record.directory / entry["run_file"]), tuple(sets),
                        mass_per_length, run_label(entry))
            for entry in record.runs if entry["status"] == "completed" and entry["run_file"]]


def stop_mode(agg: dict[str, Any], stop) -> dict[str, Any] | None:
    """The aggregated mode ``[plan.stop_when]`` watches: on its channel (if named), nearest
    its frequency, or the one with the most extrema; None without one."""
    modes = [m for m in agg.get("modes", [])
             if stop.channel is None or m["channel"] == stop.channel]
    if not modes:
        return None
    if stop.frequency_hz:
        return min(modes, key=lambda m: abs(math.log(m["frequency_hz"] / stop.frequency_hz)))
    from fsi_lab.aggregate import main_mode

    return main_mode({"modes": modes})


def _describe_run(entry: dict[str, Any], total: int) -> str:
    details = [f"{path}={value}" for path, value in (entry.get("point") or {}).items()]
    if entry.get("repeats", 1) > 1:
        details.append(f"repeat {entry['repeat']} of {entry['repeats']}")
    name = entry.get("step_name") or ""
    step = f"step {entry['step']}" + (f" ({name!r})" if name else "")
    return f"run {entry['index']} of {total}: {step}" + (f", {', '.join(details)}"
                                                         if details else "")


def _component_lines(channel: str, c: dict[str, Any]) -> list[str]:
    """One component of a run's ``results``: a line with its frequency, C_i and C_f and how
    many warnings it carries, then one line per warning (records written before ``warnings``
    was kept have none)."""
    text = f"      {channel} component {c.get('index')}"
    if c.get("frequency_hz") is not None:
        text += f" at {c['frequency_hz']:.3f} Hz"
    if c.get("c_i") is None or c.get("c_f") is None:
        text += ": C_i and C_f not identified"
    else:
        text += f": {coefficient_words(c)}"
    warnings = c.get("warnings") or []
    if warnings:
        text += f" [{len(warnings)} warning{'s' if len(warnings) > 1 else ''}]"
    return [text, *(f"        warning: {w}" for w in warnings)]


def format_record(record: SequenceRecord) -> str:
    """The record in a few readable lines: the sequence, then one line per run with its
    status and run file, and under it one line per component of each analysed channel (its
    frequency, C_i and C_f) followed by the components' warnings."""
    attrs = record.attrs
    counts = record.counts()
    total = len(record.runs)
    lines = [f"{'sequence:':<13}{record.path}" + (f" ({attrs['name']})" if attrs.get("name")
                                                   else ""),
             f"{'plan:':<13}{attrs['plan_path']} (profile {attrs['profile_path']})"]
    status = f"{attrs['status']}: {counts['completed']} of {total} runs completed"
    if attrs["status"] == "running":
        status += f"; {running_note(record)}"
    lines.append(f"{'status:':<13}{status}")
    if attrs.get("error"):
        lines.append(f"{'why:':<13}{attrs['error']}")
    if attrs.get("stopped_early"):
        lines.append(f"{'stopped:':<13}{attrs['stopped_early']}")
    if attrs.get("stop_not_reached"):
        lines.append(f"{'not stopped:':<13}{attrs['stop_not_reached']}")
    if attrs.get("nothing_identified"):
        lines.append(f"{'identified:':<13}nothing: {attrs['nothing_identified']}")
    times = f"started {attrs['start_time']}"
    if attrs.get("resumed"):
        times += f", resumed {', '.join(attrs['resumed'])}"
    if attrs.get("stop_time"):
        times += f", ended {attrs['stop_time']}"
    lines.append(f"{'times:':<13}{times}")
    for entry in record.runs:
        text = f"  {_describe_run(entry, total)}: {entry['status']}"
        if entry["run_file"]:
            text += f", {entry['run_file']}"
        if entry.get("attempts"):
            text += f" ({len(entry['attempts'])} earlier attempt(s))"
        lines.append(text)
        if entry.get("results_from") == "run file":
            lines.append("      results read from its run file (analysed after the sequence "
                         f"recorded the run; fsi-lab sequence --resume {record.directory} "
                         f"records them in {SEQUENCE_FILE})")
        for channel, components in (entry.get("results") or {}).items():
            for component in components:
                lines.extend(_component_lines(channel, component))
        if entry["error"] and entry["status"] not in ("pending", "skipped"):
            lines.append(f"      {entry['error']}")
    if record.aggregate is not None:
        from fsi_lab.aggregate import format_aggregate

        lines.append(format_aggregate(record.aggregate))
    return "\n".join(lines)
