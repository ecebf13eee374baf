"""The ``fsi-lab`` command: the headless runner and its companions.

With ``--json`` exactly one JSON object goes to stdout (schemas: docs/json-output.md); logs and
progress bars go to stderr. Errors print one message naming the file, key or channel concerned
and exit non-zero (2 for bad input, 1 for a failed run, 130 for an aborted one).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path
from typing import Any, Sequence

from fsi_lab.errors import FsiLabError, InputFileError, ParameterError, ProfileError, RunAborted
from fsi_lab.events import DataBlock, EventBus, LogRecord, Progress, StateChanged
from fsi_lab.signals import INTERRUPTED, RunSignals, SignalNote

EXIT_FOR_STATUS = {"completed": 0, "failed": 1, "aborted": 130}
#: Most samples per channel ``fsi-lab simulate`` writes (about 2.9 hours at 204.8 kHz; it
#: simulates and writes a block at a time, so the bound is the disk: see cmd_simulate).
MAX_SIMULATED_SAMPLES = 2**31
LEVELS = {"DEBUG": 10, "INFO": 20, "WARNING": 30, "ERROR": 40}


# --------------------------------------------------------------------------- rendering
class Console:
    """Renders events on stderr: log lines, and a progress bar on a terminal."""

    def __init__(self, quiet: bool, verbose: bool) -> None:
        self.level = LEVELS["DEBUG"] if verbose else LEVELS["WARNING"] if quiet else LEVELS["INFO"]
        self.bar = None
        if not quiet and sys.stderr.isatty():
            from rich.console import Console as RichConsole
            from rich.progress import Progress as RichProgress

            self.bar = RichProgress(console=RichConsole(stderr=True), transient=True)
            self.bar.start()
            self.tasks: dict[str, Any] = {}

    def __call__(self, event) -> None:
        if isinstance(event, LogRecord):
            if LEVELS.get(event.level, 20) >= self.level:
                self._print(f"[{event.level.lower()}] {event.message}")
        elif isinstance(event, StateChanged):
            if self.level <= LEVELS["INFO"]:
                detail = f": {event.detail}" if event.detail else ""
                self._print(f"[state] {event.state}{detail}")
        elif isinstance(event, Progress) and self.bar is not None:
            task = self.tasks.get(event.stage)
            if task is None:
                task = self.tasks[event.stage] = self.bar.add_task(event.stage, total=1.0)
            self.bar.update(task, completed=event.fraction,
                            description=event.message or event.stage)
        elif isinstance(event, DataBlock):
            pass  # the headless runner has no live plot

    def _print(self, text: str) -> None:
        if self.bar is not None:
            self.bar.console.print(text, markup=False, highlight=False)
        else:
            print(text, file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.stop()
            self.bar = None


_json_emitted = False  # whether this command printed its one JSON object


def _emit_json(obj: dict[str, Any]) -> None:
    global _json_emitted
    from fsi_lab.summary import json_safe

    print(json.dumps(json_safe(obj), indent=2, default=_json_default, allow_nan=False))
    _json_emitted = True


def _json_default(value):
    try:
        import numpy as np

        if isinstance(value, np.ndarray):
            return value.tolist()
        if isinstance(value, np.generic):
            return value.item()
    except ImportError:  # pragma: no cover
        pass
    return str(value)


_plugins = None  # the plugins this command loaded (load_registry), once per command


def _loaded_plugins():
    """The plugins, loaded once per command (the parser needs their commands)."""
    global _plugins
    if _plugins is None:
        from fsi_lab.registry import load_registry

        _plugins = load_registry()
    return _plugins


def _registry():
    registry = _loaded_plugins()
    registry.check_hooks()  # a failing default-chain or views hook is named with the others
    for record in registry.records:
        if record.warning():
            print(f"[warning] {record.warning()}", file=sys.stderr)
    return registry


# --------------------------------------------------------------------------- commands
def cmd_run(args) -> int:
    from fsi_lab.profile import load_profile
    from fsi_lab.runner import Runner

    registry = _registry()
    profile = load_profile(args.profile, registry, args.set)
    bus = EventBus()
    console = Console(args.quiet or args.json, args.verbose)
    bus.subscribe(console)
    try:
        runner = Runner(profile, registry, args.out, bus=bus, analyze=not args.no_analysis)
        outcome = runner.run()
    finally:
        console.close()
    if args.json:
        _emit_json(outcome.as_json())
    else:
        print(f"run file:    {outcome.path}")
        error = f" ({outcome.error})" if outcome.error else ""
        print(f"exit status: {outcome.exit_status}{error}")
        if outcome.summary:
            print(format_summary(outcome.summary, registry))
    code = EXIT_FOR_STATUS[outcome.exit_status]
    if outcome.interrupted and code == 0:  # the record is complete, the command was not
        code = EXIT_FOR_STATUS["aborted"]
    refused = nothing_identified(outcome.summary, registry) \
        if code == 0 and outcome.summary else None
    if refused:  # as `fsi-lab analyze` says of the same file
        print(f"fsi-lab: error: {outcome.path}: {refused} (the run file is complete)",
              file=sys.stderr)
        code = 2
    if args.strict and not args.no_analysis:
        code = _strict_exit(outcome.summary or {}, code)
    if outcome.file_abandoned:
        # After a failed write HDF5 crashes in its own shutdown: leave without it, so that the
        # exit code says what happened (the bench is safe and the outcome printed).
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    return code


def cmd_sequence(args) -> int:
    """``fsi-lab sequence PLAN --out DIR`` and ``fsi-lab sequence --resume DIR``."""
    from fsi_lab import sequence as seq
    from fsi_lab.seqfile import SEQUENCE_FILE, locked

    if (args.plan is None) == (args.resume is None) or (args.resume and args.out):
        raise InputFileError("fsi-lab sequence: give a plan and --out DIR, or --resume DIR "
                             "alone (see fsi-lab sequence --help)")
    if args.plan is not None and args.out is None:
        raise InputFileError(f"fsi-lab sequence {args.plan}: --out DIR is needed (the "
                             "directory of the run files and the sequence record)")
    registry = _registry()
    if args.resume is not None:
        directory = args.resume
        if not (directory / SEQUENCE_FILE).is_file():
            raise InputFileError(f"{directory}: holds no {SEQUENCE_FILE}; expected the --out "
                                 "directory of an earlier fsi-lab sequence")
    else:
        directory = args.out
        plan, safety = seq.prepare(args.plan, registry)  # every run checked, nothing written
        if directory.exists() and not directory.is_dir():
            raise InputFileError(f"{directory}: is not a directory; expected the directory of "
                                 "the sequence's run files and record (--out)")
        directory.mkdir(parents=True, exist_ok=True)
    bus = EventBus()
    console = Console(args.quiet or args.json, args.verbose)
    bus.subscribe(console)
    try:
        with locked(directory):
            if args.resume is not None:
                plan, record = seq.resume(directory, registry)
                if record.attrs["status"] == "completed":
                    bus.log("INFO", f"[sequence] every run of {directory} completed already; "
                                    "nothing to resume")
            else:
                record = seq.create(plan, safety, directory)
            runner = seq.SequenceRunner(plan, record, registry, bus, args.signals,
                                        args.signal_note)
            status = record.attrs["status"]
            if status != "completed":
                with args.signals.held():
                    record.save()
                args.signals.raise_pending()
                status = runner.run()
    finally:
        console.close()
    if args.json:
        _emit_json(record.as_json())
    else:
        print(seq.format_record(record))
    code = seq.EXIT_FOR_STATUS[status]
    if code == 0 and record.attrs.get("nothing_identified"):  # as fsi-lab run of one such run
        print(f"fsi-lab: error: {directory}: nothing was identified: "
              f"{record.attrs['nothing_identified']}", file=sys.stderr)
        code = 2
    if runner.file_abandoned:  # as for fsi-lab run: HDF5 may crash in its own shutdown
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    return code


def cmd_analyze(args) -> int:
    """``fsi-lab analyze RUN.h5``; with several files, ``--jobs`` or ``--scheduler``, the
    batch (:func:`_analyze_batch`)."""
    from fsi_lab.batch import AnalyseTask, analyse_file

    if len(args.run) > 1 or args.jobs is not None or args.scheduler is not None:
        return _analyze_batch(args)
    registry = _registry()
    bus = EventBus()
    console = Console(args.quiet or args.json, args.verbose)
    bus.subscribe(console)
    bus.subscribe(args.signal_note.checkpoint)  # a signal whose exception was swallowed
    try:
        result = analyse_file(AnalyseTask(str(args.run[0]), tuple(args.set),
                                          args.mass_per_length), registry, bus)
        summary = result["summary"]
    finally:
        console.close()
    args.signal_note.check()
    if args.json:
        _emit_json(summary)
    else:
        print(format_summary(summary, registry))
    refused = nothing_identified(summary, registry) or result["refused"]
    if refused:
        kept = f"; {summary['not_stored']}" if summary.get("not_stored") else ""
        print(f"fsi-lab: error: {args.run[0]}: {refused}{kept}", file=sys.stderr)
        return 2
    return _strict_exit(summary, 0) if args.strict else 0


def batch_exit_code(files: list[dict[str, Any]], strict: bool) -> int:
    """The exit code of a batch: 130 interrupted; 1 when a file failed otherwise than on bad
    input (an analysis error, a dead worker); 2 when every failure is a refused file; with
    ``--strict``, 3 when every file was analysed but one has a refused result or a warning;
    else 0."""
    codes = [entry["exit_code"] for entry in files]
    if 130 in codes:
        return 130
    failed = [code for code in codes if code not in (0, EXIT_STRICT)]
    if failed:
        return 2 if all(code == 2 for code in failed) else 1
    return EXIT_STRICT if strict and EXIT_STRICT in codes else 0


def _analyze_batch(args) -> int:
    """``fsi-lab analyze A.h5 B.h5 ... [--jobs N | --scheduler ADDRESS]``: every file analysed
    (and its results stored) by the executor's workers, one progress bar, one JSON object
    with each file's summary or why it failed; a bad file or a dead worker fails only its
    file."""
    import time

    from fsi_lab.batch import AnalyseTask, analyse_file, require_mass_per_length
    from fsi_lab.executor import make_executor
    from fsi_lab.seqfile import is_sequence_record

    require_mass_per_length(args.mass_per_length)
    paths, seen, records = [], set(), []
    for path in args.run:  # a file given twice is analysed once (two writers would clash)
        key = os.path.realpath(path)
        if key in seen:
            continue
        seen.add(key)
        if is_sequence_record(Path(path)):   # a glob of a sequence's folder catches it
            records.append(path)
        else:
            paths.append(path)
    tasks = [AnalyseTask(str(path), tuple(args.set), args.mass_per_length) for path in paths]
    if args.set:
        refuse_bad_sets_once(tasks)
    files: list[dict[str, Any]] = [{"run": str(path), "status": "pending", "exit_code": 0}
                                   for path in paths]
    started = time.perf_counter()
    executor = make_executor(args.jobs, args.scheduler)
    bus = EventBus()
    console = Console(args.quiet or args.json, args.verbose)
    bus.subscribe(console)
    interrupted = ""
    done = 0
    try:
        with executor:
            for path in records:
                bus.log("WARNING", f"{path}: a sequence's record, not a run file: left out "
                                   "(its runs are the other files)")
            bus.log("INFO", f"analysing {len(tasks)} file{'s' * (len(tasks) != 1)} with "
                            f"{executor.describe()}")
            bus.emit(Progress("analyze", 0.0, f"0 of {len(tasks)} files"))
            for result in executor.map_unordered(analyse_file, tasks):
                entry = files[result.index]
                if result.ok:
                    summary = result.value["summary"]
                    problems = strict_problems(summary)
                    for level, sentence in result.value["messages"]:
                        bus.log(level, sentence)
                    entry.update(status="analysed", analysis=summary, problems=problems,
                                 messages=result.value["messages"],
                                 worker=result.value["worker"],
                                 exit_code=EXIT_STRICT if args.strict and problems else 0)
                    refused = nothing_identified(summary, _loaded_plugins()) \
                        or result.value["refused"]
                    if refused and summary.get("not_stored"):
                        refused += f"; {summary['not_stored']}"
                    if refused:
                        entry.update(error=refused, exit_code=2)
                        bus.log("ERROR", f"{entry['run']}: {refused}")
                else:
                    entry.update(status="failed", error=result.error,
                                 exit_code=result.exit_code, worker_died=result.worker_died)
                    bus.log("ERROR", result.error if entry["run"] in result.error
                            else f"{entry['run']}: {result.error}")
                done += 1
                bus.emit(Progress("analyze", done / len(tasks),
                                  f"{done} of {len(tasks)} files"))
                args.signal_note.check()
    except (KeyboardInterrupt, RunAborted) as exc:  # the workers are ended by now
        args.signals.silence()
        interrupted = str(exc) or INTERRUPTED
        for entry in files:
            if entry["status"] == "pending":
                entry.update(status="not analysed", error=f"interrupted: {interrupted}",
                             exit_code=130)
    finally:
        console.close()
    code = batch_exit_code(files, args.strict)
    counts = {"files": len(files), **{status: sum(e["status"] == status for e in files)
                                      for status in ("analysed", "failed", "not analysed")}}
    elapsed = time.perf_counter() - started
    if args.json:
        _emit_json({"files": files, "counts": counts, "executor": executor.as_json(),
                    "elapsed_s": elapsed, "interrupted": bool(interrupted),
                    "exit_code": code})
    else:
        for entry in files:
            print(f"== {entry['run']}: {entry['status']}")
            if entry["status"] == "analysed":
                print(format_summary(entry["analysis"]))
            else:
                print(f"  {entry['error']}")
        print(f"analysed {counts['analysed']} of {counts['files']} files"
              + (f", {counts['failed']} failed" if counts["failed"] else "")
              + (f", {counts['not analysed']} not analysed" if counts["not analysed"] else "")
              + f" in {elapsed:.1f} s with {executor.describe()}")
    if interrupted:
        print(f"fsi-lab: interrupted: {interrupted}", file=sys.stderr)
    if args.strict:
        for entry in files:
            for line in entry.get("problems", []):
                print(f"[strict] {entry['run']}: {line}", file=sys.stderr)
    return code


def aggregate_tasks(paths: list[Path], sets: list[str], mass_per_length: float | None):
    """The run files ``fsi-lab aggregate`` takes, and notes on what it left out: of each
    argument, a run file itself, or of a directory the completed runs of its sequence
    (labelled by their place in it, after the directory's name when several arguments are
    given) or its run files. A sequence's record (``sequence.h5``, which a glob of its
    directory catches) is left out with a note; a file given twice (also inside a directory
    given) counts once."""
    import dataclasses

    from fsi_lab.aggregate_extract import ExtractTask
    from fsi_lab.seqfile import SEQUENCE_FILE, is_sequence_record, load_record
    from fsi_lab.sequence import extract_tasks

    found: list[ExtractTask] = []
    notes: list[str] = []
    several = len(paths) > 1
    for path in paths:
        if path.is_dir():
            if (path / SEQUENCE_FILE).exists():
                tasks = extract_tasks(load_record(path), sets, mass_per_length)
                found.extend(dataclasses.replace(task, label=f"{path}: {task.label}")
                             if several else task for task in tasks)
                continue
            files = sorted(p for p in path.glob("*.h5") if not is_sequence_record(p))
            if not files:
                raise InputFileError(f"{path}: holds no run file (*.h5) and no sequence; "
                                     "expected run files or the --out directory of fsi-lab "
                                     "sequence")
            found.extend(ExtractTask(str(file), tuple(sets), mass_per_length) for file in files)
        elif is_sequence_record(path):
            notes.append(f"{path}: a sequence's record, not a run file: left out (its runs are "
                         f"the run files beside it; fsi-lab aggregate {path.parent} pools the "
                         "sequence's completed runs)")
        else:
            found.append(ExtractTask(str(path), tuple(sets), mass_per_length))
    if not found:
        raise InputFileError(f"{', '.join(map(str, paths))}: no run file to aggregate; "
                             "expected run files (.h5) or directories of them, or the --out "
                             "directory of fsi-lab sequence")
    given: dict[Path, ExtractTask] = {}
    for task in found:                     # one file under two names counts once
        given.setdefault(Path(task.path).resolve(), task)
    tasks = list(given.values())
    _refuse_copies([Path(task.path) for task in tasks])
    names = [Path(task.path).name for task in tasks]
    return [task if task.label else dataclasses.replace(
                task, label=Path(task.path).name if names.count(Path(task.path).name) == 1
                else task.path) for task in tasks], notes


def _refuse_copies(paths: list[Path]) -> None:
    """Refuse run files that are copies of one run (the same uuid): pooled as independent runs
    they would narrow the intervals and show no spread between runs. Files that cannot be read
    are left to the extraction, which names what is wrong with them."""
    import h5py

    from fsi_lab.runcheck import decode_attr

    seen: dict[str, Path] = {}
    for path in paths:
        try:
            with h5py.File(path, "r") as f:
                run_uuid = decode_attr(f.attrs.get("uuid"))
        except (OSError, ValueError):
            continue
        if not run_uuid:
            continue
        if run_uuid in seen:
            raise InputFileError(
                f"{path}: a copy of {seen[run_uuid]} (both hold run {run_uuid}); each run "
                "counts once in an aggregate: give one of them")
        seen[str(run_uuid)] = path


def check_aggregate_sets(sets: list[str]) -> None:
    """Refuse, once and before any run is read, a ``--set`` of ``fsi-lab aggregate`` that is
    not an analysis parameter. The specimen (mu + M, the mode shape) is each run's own, held by
    its run file: an aggregate that changed it would pool numbers that no run file explains."""
    accepted = ("fsi-lab aggregate sets analysis parameters only: "
                "analysis.ANALYSIS.PARAMETER=VALUE (fsi-lab plugins -v lists them), "
                "analysis.chain, analysis.channels or analysis.reference")
    for item in sets:
        key = item.partition("=")[0].strip()
        section = key.partition(".")[0].strip()
        if section == "analysis":
            continue
        if section == "specimen":
            raise ProfileError(
                f"--set {item!r}: the specimen (the beam, its fluid, the measuring point) is "
                "each run's own, held by its run file, and an aggregate that changed it would "
                f"give numbers no run file explains; {accepted}; give runs without a specimen "
                "their mu + M with --mass-per-length, or aggregate runs of the beam you mean")
        raise ProfileError(f"--set {item!r}: {key or item!r} is not an analysis parameter "
                           f"(the runs were recorded with their own); {accepted}")


def refuse_bad_sets_once(tasks) -> None:
    """Refuse, once and before any run is analysed, a ``--set`` value of a batch analysis or
    an aggregate (``tasks``: each with ``path`` and ``sets``) that the runs' analysis settings
    refuse (each run would otherwise fail with it, one error per run).
    Runs that cannot be read, or whose own settings are refused, are left to the extraction,
    which reports them run by run."""
    from fsi_lab.run_profile import analysis_profile
    from fsi_lab.runfile import read_run

    registry = _loaded_plugins()
    for task in tasks:
        try:
            analysis_profile(read_run(task.path, load_data=False), registry, task.sets)
        except ProfileError as exc:
            if any(f"--set {item}:" in str(exc) for item in task.sets):
                raise
        except FsiLabError:
            continue


def cmd_aggregate(args) -> int:
    """``fsi-lab aggregate RUN.h5 ... | DIR``: the runs' modes grouped by frequency, C_i and
    C_f fitted to the union of their free decays, backbones and damping curves on one
    amplitude axis, the spread between runs (fsi_lab.aggregate)."""
    from fsi_lab.aggregate import aggregate_extracts, extract_runs, format_aggregate
    from fsi_lab.batch import require_mass_per_length
    from fsi_lab.executor import make_executor

    require_mass_per_length(args.mass_per_length)
    check_aggregate_sets(args.set)
    tasks, notes = aggregate_tasks(args.runs, args.set, args.mass_per_length)
    if args.set:
        refuse_bad_sets_once(tasks)
    executor = make_executor(args.jobs, args.scheduler)
    bus = EventBus()
    console = Console(args.quiet or args.json, args.verbose)
    bus.subscribe(console)
    try:
        with executor:
            bus.log("INFO", f"identifying the modes of {len(tasks)} run"
                            f"{'s' * (len(tasks) != 1)} with {executor.describe()}")

            def done(count: int) -> None:
                bus.emit(Progress("aggregate", count / len(tasks),
                                  f"{count} of {len(tasks)} runs"))
                args.signal_note.check()

            extracts = extract_runs(tasks, executor, done)
        agg = aggregate_extracts(extracts)
        agg["notes"] = notes + agg["notes"]
    finally:
        console.close()
    for run in agg["runs"]:
        for error in run["errors"]:
            print(f"[error] {run['label']}: {error}", file=sys.stderr)
    if args.json:
        _emit_json({**agg, "executor": executor.as_json()})
    else:
        print(format_aggregate(agg))
    return agg["exit_code"]


def cmd_import(args) -> int:
    from fsi_lab.csv_import import import_csv

    delays = {}
    for item in args.delay:
        name, sep, text = item.partition("=")
        try:
            delays[name.strip()] = float(text)
        except ValueError:
            sep = ""
        if not sep:
            raise InputFileError(f"--delay {item}: expected NAME=SECONDS, e.g. "
                                 "tip_velocity=0.0011")
    sensitivities = {}
    for item in args.sensitivity:
        name, sep, text = item.partition("=")
        if not (sep and name.strip() and text.strip()):
            raise InputFileError(f"--sensitivity {item}: expected NAME=SENSITIVITY, e.g. "
                                 "tip_velocity=200mV/(mm/s)")
        if name.strip() in sensitivities:
            raise InputFileError(f"--sensitivity {item}: {name.strip()!r} is given twice; "
                                 "expected one sensitivity per column")
        sensitivities[name.strip()] = text.strip()
    notes: list[str] = []
    out = import_csv(args.csv, args.output, args.rate, args.reference, delays, sensitivities,
                     args.decimal_mark, notes, args.ignore_time, args.skip,
                     args.header_line)
    for text in notes:
        print(f"[note] {text}", file=sys.stderr)
    if args.json:
        _emit_json({"run": str(out), "notes": notes})
    else:
        print(f"wrote {out}")
    return 0


def cmd_show(args) -> int:
    from fsi_lab.runfile import read_analysis_overrides, read_analysis_summary, read_run
    from fsi_lab.summary import format_value

    if args.run.is_dir() or args.run.name == "sequence.h5":
        if args.strict:
            raise ParameterError(f"--strict: {args.run} is a sequence's record; expected a "
                                 "run file (fsi-lab show RUN.h5 --strict)")
        return _show_sequence(args)
    run = read_run(args.run, load_data=False)
    summary = read_analysis_summary(args.run)
    summary_text = _summary_text(args.run, summary) if summary else ""
    attrs = {k: v for k, v in run.attrs.items() if k not in ("profile", "traceback")}
    with_lengths = {name: {**run.channel_attrs[name], "samples": run.channel_samples[name]}
                    for name in run.channels}
    excitation = {k: v for k, v in (run.excitation or {}).items() if k != "waveform"} or None
    if excitation is not None:
        excitation["param_units"] = _excitation_units(excitation.get("plugin"))
    analysed_with = read_analysis_overrides(args.run) if summary else []
    info = {"run": str(args.run), "attrs": attrs, "instruments": run.instruments,
            "channels": with_lengths, "excitation": excitation, "analysis": summary,
            "analysis_overrides": analysed_with}
    warnings = []
    if attrs.get("exit_status") == "running":
        warnings.append(
            "this run never finished: the process that ran it died (kill -9, a crash, a power "
            "cut) before it could put the bench in its safe state and read it back; the record "
            "ends where its last flush did. Check the bench: fsi-lab safe PROFILE")
    info["warnings"] = warnings
    for text in warnings:
        print(f"[warning] {text}", file=sys.stderr)
    code = _show_strict_exit(args.run, summary, warnings) if args.strict else 0
    if args.json:
        _emit_json(info)
        return code
    print(f"{'run file:':<18}{args.run}")
    for key in ("kind", "uuid", "start_time", "stop_time", "exit_status", "stopped_early",
                "error", "software_version"):
        if attrs.get(key) not in (None, "", False):
            print(f"{key + ':':<18}{attrs[key]}")
    for role, inst in run.instruments.items():
        final = inst.get("final_state", {})
        print(f"instrument {role}: {inst.get('identity', '?')}; final state {final}")
    for name, meta in with_lengths.items():
        rate, t0 = run.channels[name].sample_rate, run.channels[name].t0
        print(f"channel {name}: {meta['quantity']} [{meta['units']}], {meta['samples']} samples "
              f"at {rate:g} Hz ({meta['samples'] / rate:.3f} s)"
              + (f", t0 = {t0:g} s" if t0 else ""))
    if run.reference:
        print(f"{'reference:':<18}{run.reference}")
    if excitation is not None:
        units = excitation["param_units"]
        given = ", ".join(f"{k} {format_value(v)}" + (f" {units[k]}" if units.get(k) else "")
                          for k, v in excitation.get("params", {}).items())
        print(f"{'excitation:':<18}{excitation.get('plugin', '?')}"
              + (f" ({given})" if given else ""))
    if analysed_with:  # the stored numbers are not the run's own settings' (fsi-lab analyze)
        print(f"{'analysed with:':<18}{' '.join(analysed_with)} (beyond the run's own settings)")
    if summary_text:
        print(summary_text)
    return code


def _show_strict_exit(path: Path, summary: dict[str, Any] | None, warnings: list[str]) -> int:
    """``show --strict``: :data:`EXIT_STRICT`, the reasons on stderr, when the run file's
    stored analysis has problems (:func:`strict_problems`), it holds none, or the run file
    itself is warned (``warnings``); else 0."""
    problems = [f"run: {text}" for text in warnings]
    if not summary:
        problems.append(f"no analysis stored: fsi-lab analyze {path}")
    else:
        problems.extend(strict_problems(summary))
    for line in problems:
        print(f"[strict] {line}", file=sys.stderr)
    return EXIT_STRICT if problems else 0


def _excitation_units(plugin: Any) -> dict[str, str]:
    """The units of an excitation plugin's parameters, by name, from the installed plugin
    (a run file records the values only); empty when it is not installed here."""
    try:
        return {p.name: p.unit
                for p in _loaded_plugins().get("excitation", str(plugin)).params}
    except FsiLabError:
        return {}


def _show_sequence(args) -> int:
    """``fsi-lab show DIR``: the sequence record in DIR (or the sequence.h5 named), with the
    results of an analysis stored in a run file after the sequence recorded the run."""
    from fsi_lab.seqfile import load_record
    from fsi_lab.sequence import format_record, running_note, with_later_analyses

    record = with_later_analyses(load_record(args.run))
    if args.json:
        info = record.as_json()
        if record.attrs["status"] == "running":
            info["note"] = running_note(record)
        _emit_json(info)
    else:
        print(format_record(record))
    return 0


def _summary_text(path: Path, summary: dict[str, Any]) -> str:
    """:func:`format_summary` of a run file's stored summary, refused (InputFileError) when it
    is not laid out as fsi-lab writes it."""
    try:
        return format_summary(summary, _loaded_plugins())
    except (AttributeError, KeyError, TypeError, ValueError, IndexError) as exc:
        raise InputFileError(
            f"{path}: /analysis attribute 'summary': not laid out as fsi-lab writes it "
            f"({type(exc).__name__}: {exc}); expected the summary of fsi-lab analyze (run it "
            "again)") from None


def cmd_plugins(args) -> int:
    registry = _registry()
    records = [r.as_dict() for r in registry.records]
    for record in records:
        descriptor = registry.descriptors.get(record["kind"] or "", {}).get(record["name"])
        record["params"] = [p.as_dict() for p in descriptor.params] if descriptor else []
        record["help"] = getattr(descriptor, "help", "") if descriptor else ""
        if record["kind"] == "analysis" and descriptor:   # the result kinds it declares
            record.update(requires=list(descriptor.requires), uses=list(descriptor.uses),
                          provides=descriptor.provides)
    records.sort(key=lambda r: (r["kind"] or "", r["name"]))
    if not registry.commands:  # called without the parser (in-process)
        registry.add_commands(argparse.ArgumentParser().add_subparsers())
    commands = [record.as_dict() for record in registry.commands]
    if args.json:
        _emit_json({"plugins": records, "commands": commands})
        return 0
    for record in records + [{**c, "kind": "command", "params": []} for c in commands]:
        line = f"{record['kind'] or '-':<11} {record['name']:<24} {record['status']:<8} " \
               f"{record['distribution']} {record['version']}"
        print(line + (f"  ({record['error']})" if record["error"] else ""))
        if args.verbose:
            if record["kind"] == "command":
                print(f"    fsi-lab {record['name']}: {record['help']}")
            if record.get("hooks") and not record["kind"]:
                print(f"    hooks {', '.join(record['hooks'])}")
            for key in ("requires", "uses"):
                if record.get(key):
                    print(f"    {key} {', '.join(record[key])}")
            if record.get("provides"):
                print(f"    provides {record['provides']}")
            for p in record["params"]:
                unit = f" [{p['unit']}]" if p["unit"] else ""
                print(f"    {p['name']}{unit} = {p['default']!r}: {p['help']}")
    return 0


def cmd_bench_access(args) -> int:
    """``fsi-lab safe`` and ``fsi-lab identify``: every instrument of the profile, outside a run."""
    from fsi_lab.bench_access import BenchInterrupted, probe_bench, problems, safe_bench
    from fsi_lab.errors import ProfileError
    from fsi_lab.profile import load_profile

    registry = _registry()
    # Only what opening the instruments needs: a mistake elsewhere must not stop a safe state.
    profile = load_profile(args.profile, registry, args.set,
                           sections=("bench", "specimen", "model", "shaker"))
    if not profile.roles:
        raise ProfileError(f"{args.profile}: bench: no instruments; expected [bench.<role>] tables")

    def log(level: str, text: str) -> None:
        print(f"[{level.lower()}] {text}", file=sys.stderr)

    interrupted = False
    try:
        report = (safe_bench if args.command == "safe" else probe_bench)(profile, registry, log)
    except BenchInterrupted as exc:  # every instrument was made safe first: show what was found
        report, interrupted = exc.report, True
    failed = sorted(problems(report))
    if args.json:
        _emit_json({"profile": str(args.profile), "instruments": report, "failed": failed,
                    "interrupted": interrupted})
    else:
        for role, info in report.items():
            verdict = "NOT confirmed safe" if role in failed else "safe"
            print(f"{role}: {info.get('identity') or verdict}")
            if info.get("output_found_on"):
                print("  output found ON (left on by a run that died?): switched off")
            for key in ("error", "safe_state_error"):
                if key in info:
                    print(f"  {key.replace('_', ' ')}: {info[key]}")
            for key in ("settings", "interlocks", "state"):
                if info.get(key):
                    print(f"  {key}: {info[key]}")
        if failed:
            print(f"not confirmed safe: {', '.join(failed)}", file=sys.stderr)
    if interrupted:
        return EXIT_FOR_STATUS["aborted"]
    return 1 if failed else 0


def cmd_profile_check(args) -> int:
    from fsi_lab.preflight import check_safety
    from fsi_lab.profile import load_profile

    registry = _registry()
    profile = load_profile(args.profile, registry, args.set)
    profile.require_runnable()
    _, _, report = check_safety(profile, registry)
    s = report.as_dict()
    result: dict[str, Any] = {"profile": str(args.profile), "valid": True, "safety": s}
    refusal = "" if report.ok else f"{args.profile}: refused: {'; '.join(report.problems)}"
    if refusal:  # the one message a refusal gets, as fsi-lab run gives it
        result.update(error=refusal, exit_code=2)
    if args.json:
        _emit_json(result)
    else:
        print(f"{args.profile}: valid" if s["ok"] else
              f"{args.profile}: its keys and values are valid, but its safety limits refuse "
              "the run it describes")
        print(f"safety: peak drive {s['peak_drive_v']:.4g} V (max {s['max_drive_v']:g}), "
              f"gain {s['gain']:g} (max {s['max_gain']:g}), predicted stroke "
              f"{s['predicted_stroke_mm']:.3g} mm (max {s['max_stroke_mm']:g}): "
              + ("ok" if s["ok"] else "REFUSED: " + "; ".join(s["problems"])))
    if refusal:
        print(f"fsi-lab: error: {refusal}", file=sys.stderr)
        return 2
    return 0


def _model_profile(args):
    from fsi_lab.errors import ProfileError
    from fsi_lab.profile import load_profile

    registry = _registry()
    profile = load_profile(args.profile, registry, args.set)
    if profile.specimen is None:
        raise ProfileError(f"{args.profile}: specimen: missing; the model needs [specimen]")
    return registry, profile


def cmd_model(args) -> int:
    from fsi_lab.modelling import beam_model, model_summary

    _, profile = _model_profile(args)
    model = beam_model(profile.specimen, profile.model, args.modes)
    summary = model_summary(model)
    if args.json:
        _emit_json(summary)
        return 0
    print(f"fluid: {summary['fluid']}; added mass ratio M/mu = {summary['added_mass_ratio']:.2f}; "
          f"theoretical C_f = {summary['c_f_theory']:.3g} kg/m^2 (rho_f C_d H / 2, C_d = "
          f"{summary['drag_coefficient']:g}: a steady drag estimate)")
    print(f"mu + M = {summary['total_mass_per_length']:.4g} kg/m (beam "
          f"{summary['mass_per_length']:.4g}, added fluid mass {summary['added_mass']:.4g}): "
          "the --mass-per-length of this beam's records imported from elsewhere")
    print(f"damping the model runs with ([model]; simulate and the simulated bench): "
          f"C_i = {model.damping.c_i:g} kg/(m s), C_f = {model.damping.c_f:g} kg/m^2")
    for n, f in enumerate(summary["natural_frequencies_hz"], start=1):
        print(f"  mode {n}: {f:.4f} Hz")
    return 0


def _check_room(output: Path, size: float) -> None:
    """Raise InputFileError when the folder of ``output`` (or its nearest existing parent) has
    less free space than ``size`` bytes and 5 % to spare."""
    import shutil

    folder = output.absolute().parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    free = shutil.disk_usage(folder).free
    if size * 1.05 > free:
        raise InputFileError(
            f"{output}: the simulated record would take {size / 1e9:.3g} GB and {folder} has "
            f"{free / 1e9:.3g} GB free; shorten --duration, lower --rate or write elsewhere")


def cmd_simulate(args) -> int:
    from fsi_lab.errors import ProfileError, RunAborted
    from fsi_lab.preflight import prepare_excitation
    from fsi_lab.runfile import new_run_path, software_version
    from fsi_lab.signals import RunSignals
    from fsi_lab.simulation import SIMULATED_CHANNELS, simulate_run

    registry, profile = _model_profile(args)
    if profile.excitation_plugin is None:
        raise ProfileError(f"{args.profile}: excitation: missing; simulate needs [excitation]")
    for name, value, unit in (("--duration", args.duration, "s"), ("--rate", args.rate, "Hz")):
        if not (math.isfinite(value) and value > 0):
            raise InputFileError(f"{name} {value}: expected a positive number of {unit}")
    samples = args.duration * args.rate
    if not 2 <= samples <= MAX_SIMULATED_SAMPLES:
        raise InputFileError(
            f"--duration {args.duration:g} s at --rate {args.rate:g} Hz makes {samples:,.0f} "
            f"samples per channel; expected 2 to {MAX_SIMULATED_SAMPLES:,}: change --duration "
            "or --rate")
    if args.output.exists():
        raise InputFileError(f"{args.output}: already exists; choose another output file")
    _check_room(args.output, samples * len(SIMULATED_CHANNELS) * 8)
    waveform, rate = prepare_excitation(profile, registry)
    _, run_uuid, started = new_run_path(args.output.parent)
    bus = EventBus()
    console = Console(args.quiet or args.json, args.verbose)
    bus.subscribe(console)
    # Ctrl+C and SIGTERM end the simulation between two blocks, recorded as aborted
    signals = RunSignals()
    signals.install()

    def progress(fraction: float) -> None:
        bus.emit(Progress("simulate", fraction, "simulating"))
        signals.raise_pending()

    try:
        with signals.held():
            simulate_run(profile, waveform, rate, args.duration, args.rate, args.output,
                         args.modes,
                         {"uuid": run_uuid, "start_time": started, "profile": profile.text,
                          "profile_path": profile.path, "overrides": list(profile.overrides),
                          "run_name": profile.run["name"],
                          "software_version": software_version()},
                         progress=progress)
    except (KeyboardInterrupt, RunAborted) as exc:
        console.close()
        reason = str(exc) or INTERRUPTED
        if args.json:
            _emit_json({"run": str(args.output), "exit_status": "aborted", "error": reason})
        print(f"fsi-lab: simulation aborted ({reason}); {args.output} holds the part simulated",
              file=sys.stderr)
        return EXIT_FOR_STATUS["aborted"]
    finally:
        signals.restore()
        console.close()
    if args.json:
        _emit_json({"run": str(args.output), "exit_status": "completed"})
    else:
        print(f"wrote {args.output}")
    return 0


def cmd_gui(args) -> int:
    try:
        from fsi_lab.gui.app import main as gui_main
    except ImportError as exc:
        raise FsiLabError(
            f"the GUI needs the 'gui' extra (PySide6, pyqtgraph): pip install 'fsi-lab[gui]' "
            f"({exc})"
        ) from None
    # Ctrl+C and SIGTERM are noted while the window is built, then the window handles them
    # (fsi_lab.gui.app.EndOnSignal: it closes as its close button does, exit code 130).
    with args.signals.held():
        return gui_main(args)


EXIT_STRICT = 3


def _warnings(entry: dict[str, Any]) -> list[tuple[str, str]]:
    """Every warning of a channel's or a component's summary as (key, sentence)
    (:func:`fsi_lab.summary.warnings_of`)."""
    from fsi_lab.summary import warnings_of

    return warnings_of(entry)


def strict_problems(summary: dict[str, Any]) -> list[str]:
    """What makes ``--strict`` fail: every refused result (an analysis or a component that
    failed) and every warning, channel-level or a component's, one line each, naming the
    channel, and the analysis or component."""
    problems = []
    for channel, info in summary.get("channels", {}).items():
        for error in info.get("errors", []):
            problems.append(f"channel {channel}: {error['message']}")
        problems.extend(f"channel {channel}{' ' + key if key else ''}: {w}"
                        for key, w in _warnings(info))
        for component in info.get("components", []):
            where = f"channel {channel} component {component['index']}"
            problems.extend(f"{where}{' ' + key if key else ''}: {w}"
                            for key, w in _warnings(component))
            for value in component.values():
                if isinstance(value, dict) and value.get("error"):
                    problems.append(f"{where}: {value['error']}")
    return list(dict.fromkeys(problems))


def nothing_identified(summary: dict[str, Any], registry) -> str | None:
    """Why nothing in an analysed record was identified, or None
    (:func:`fsi_lab.summary.nothing_identified`)."""
    from fsi_lab.summary import nothing_identified as why

    return why(summary, registry)


def _strict_exit(summary: dict[str, Any], code: int) -> int:
    """``code``, or :data:`EXIT_STRICT` with the problems on stderr when there are any."""
    problems = strict_problems(summary)
    if code != 0 or not problems:
        return code
    for line in problems:
        print(f"[strict] {line}", file=sys.stderr)
    return EXIT_STRICT


def _counting(expected: str):
    """An argparse type: a whole number >= 1, else an error saying ``expected``."""
    def count(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = 0
        if value < 1:
            raise argparse.ArgumentTypeError(f"{text!r}: expected {expected}")
        return value
    return count


#: ``--skip N``: a column number >= 1.
_column_number = _counting("a column number (1 is the file's first column)")
_line_number = _counting("a line number (1 is the file's first line)")
#: ``--jobs N``: a number of worker processes >= 1.
_jobs = _counting("a number of worker processes >= 1")


def _window_size(text: str) -> tuple[int, int]:
    """``WxH`` (e.g. ``1366x768``) for ``fsi-lab gui --size``."""
    try:
        width, height = (int(part) for part in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected WIDTHxHEIGHT in pixels, "
                                         "e.g. 1366x768") from None
    if not (320 <= width <= 16384 and 240 <= height <= 16384):
        raise argparse.ArgumentTypeError(f"{text!r}: width 320 to 16384 and height 240 to "
                                         "16384 pixels")
    return width, height


def format_summary(summary: dict[str, Any], registry=None) -> str:
    """The analysis summary as a few readable lines (:func:`fsi_lab.summary.format_summary`,
    with the plugins of this command)."""
    from fsi_lab.summary import format_summary as text

    return text(summary, registry if registry is not None else _loaded_plugins())


# --------------------------------------------------------------------------- parser
def _add_plugin_commands(sub, registry) -> None:
    """Subcommands the plugins add through the ``fsi_lab_addcommands(subparsers)`` hook; a
    command of the old ``fsi_lab.commands`` entry-point group is refused when asked for."""
    for record in registry.add_commands(sub):
        if record.status == "failed":
            print(f"[warning] commands of plugin {record.name} ({record.distribution}) "
                  f"skipped: {record.error}", file=sys.stderr)
        elif record.status == "refused" and record.name not in sub.choices:
            parser = sub.add_parser(record.name)
            parser.add_argument("ignored", nargs=argparse.REMAINDER)
            parser.set_defaults(func=_refused(record))


def _refused(record):
    def run(args) -> int:
        from fsi_lab.errors import PluginError

        raise PluginError(f"fsi-lab {record.name}: {record.distribution} {record.version} "
                          f"{record.error}")
    return run


class _Parser(argparse.ArgumentParser):
    """A usage error is one message (naming the command and the argument, and where to see
    what it accepts), and the one JSON object when ``--json`` was asked for; exit code 2."""

    json_requested = False

    def error(self, message: str):
        text = f"{self.prog}: {message} (see {self.prog} --help)"
        if self.json_requested:
            _emit_json({"error": text, "exit_code": 2})
        self.exit(2, f"fsi-lab: error: {text}\n")


def build_parser(json_requested: bool = False, registry=None) -> argparse.ArgumentParser:
    """The ``fsi-lab`` parser, with the subcommands of the plugins of ``registry`` (loaded
    when not given)."""
    _Parser.json_requested = json_requested
    parser = _Parser(
        prog="fsi-lab", description="Run and analyse vibration experiments on beams in fluid.")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def common(p, json_help=True):
        if json_help:
            p.add_argument("--json", action="store_true",
                           help="print one JSON object on stdout (docs/json-output.md)")
        p.add_argument("-q", "--quiet", action="store_true", help="no progress bars, warnings only")
        p.add_argument("-v", "--verbose", action="store_true", help="debug messages on stderr")

    p = sub.add_parser("run", help="run a profile on its bench and analyse the record")
    p.add_argument("profile", type=Path)
    p.add_argument("--out", type=Path, default=Path("runs"), help="directory of the run file")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a profile parameter, e.g. excitation.amplitude=0.5")
    p.add_argument("--no-analysis", action="store_true", help="acquire only")
    p.add_argument("--strict", action="store_true",
                   help="exit 3 when the run completed but a result was refused or warned")
    common(p)
    p.set_defaults(func=cmd_run)

    p = sub.add_parser("sequence", help="run a sequence plan (sweeps, repeats) run after run, "
                                        "or resume one")
    p.add_argument("plan", type=Path, nargs="?", metavar="PLAN.toml",
                   help="the plan: a base profile and its steps (see README, Sequences)")
    p.add_argument("--out", type=Path, metavar="DIR",
                   help="directory of the run files and the sequence record (sequence.h5)")
    p.add_argument("--resume", type=Path, metavar="DIR",
                   help="continue the sequence in DIR with its first run that did not complete")
    common(p)
    p.set_defaults(func=cmd_sequence)

    p = sub.add_parser("analyze", help="(re)run the analysis chain on run files, in parallel "
                                       "with --jobs or on a Dask cluster with --scheduler")
    p.add_argument("run", type=Path, nargs="+", metavar="RUN.h5")
    p.add_argument("--jobs", type=_jobs, metavar="N",
                   help="analyse the files in N local worker processes (one BLAS and one numba "
                        "thread each); several files give one JSON object with each file's "
                        "results or why it failed")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="send the files to the Dask scheduler at ADDRESS, e.g. "
                        "tcp://10.0.0.5:8786 (needs the extra fsi-lab[cluster])")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override an analysis parameter, analysis.ANALYSIS.PARAMETER=VALUE "
                        "(fsi-lab plugins -v lists them), or the specimen's, "
                        "specimen.KEY=VALUE (e.g. specimen.fluid=water); "
                        "analysis.chain+=NAME appends an analysis to the chain")
    p.add_argument("--strict", action="store_true",
                   help="exit 3 when a result was refused or carries a warning")
    p.add_argument("--mass-per-length", type=float, metavar="KG_PER_M",
                   help="mu + M for data without a specimen (kg/m); refused for a run that "
                        "has one (give its beam with --set specimen.KEY=VALUE)")
    common(p)
    p.set_defaults(func=cmd_analyze)

    p = sub.add_parser("aggregate", help="one answer from many runs: modes grouped by "
                                         "frequency, C_i and C_f fitted to all their decays, "
                                         "backbones and damping on one amplitude axis, the "
                                         "spread between runs")
    p.add_argument("runs", type=Path, nargs="+", metavar="RUN.h5|DIR",
                   help="run files and directories, in any mix: of a directory, the completed "
                        "runs of its sequence, or its run files; a sequence's record "
                        "(sequence.h5, as a glob of its directory catches it) is left out with "
                        "a note")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override an analysis parameter of every run: "
                        "analysis.ANALYSIS.PARAMETER=VALUE (fsi-lab plugins -v lists them), "
                        "analysis.chain, analysis.channels, analysis.reference; not the "
                        "specimen, which each run file holds (--mass-per-length gives mu + M "
                        "to runs without one)")
    p.add_argument("--mass-per-length", type=float, metavar="KG_PER_M",
                   help="mu + M for runs without a specimen (kg/m); refused for a run that "
                        "has one")
    p.add_argument("--jobs", type=_jobs, metavar="N",
                   help="identify the runs in N local worker processes")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="identify the runs on the Dask scheduler at ADDRESS "
                        "(fsi-lab[cluster])")
    common(p)
    p.set_defaults(func=cmd_aggregate)

    p = sub.add_parser("import", help="turn a CSV file ('name [unit]' header) into a run file")
    p.add_argument("csv", type=Path)
    p.add_argument("--rate", type=float, metavar="HZ",
                   help="sample rate; beside a time column, checked against it and kept exact")
    p.add_argument("--reference", metavar="NAME",
                   help="the base acceleration column (the analysis's reference channel)")
    p.add_argument("--delay", action="append", default=[], metavar="NAME=SECONDS",
                   help="signal delay of a column's sensor, e.g. tip_velocity=0.0011 (a "
                        "vibrometer's; `fsi-lab show` prints a run's as t0)")
    p.add_argument("--sensitivity", action="append", default=[], metavar="NAME=SENSITIVITY",
                   help="calibrate a column written in volts (V, mV or uV): its sensor's "
                        "sensitivity in volts per unit, e.g. tip_velocity=200mV/(mm/s) (a "
                        "vibrometer's decoder at 5 mm/s per V) or base=100mV/g")
    p.add_argument("--ignore-time", action="store_true",
                   help="leave the time column out and take the rate from --rate (a column "
                        "printed with too few digits, or time stamps with jitter)")
    p.add_argument("--decimal-mark", choices=(".", ","),
                   help="the decimal mark of a file separated by semicolons or tabs whose "
                        "values could be grouped in thousands (25.300: 25.3 or 25300?)")
    p.add_argument("--skip", action="append", default=[], type=_column_number, metavar="N",
                   help="leave out the file's column N (from 1; e.g. a hammer's force or a "
                        "sample index); may be repeated")
    p.add_argument("--header-line", type=_line_number, metavar="N",
                   help="the header row is the file's line N (from 1): the lines above it (an "
                        "export's notes on itself) are left out")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="RUN.h5")
    common(p)
    p.set_defaults(func=cmd_import)

    p = sub.add_parser("show", help="describe a run file, or the sequence in a directory")
    p.add_argument("run", type=Path)
    p.add_argument("--strict", action="store_true",
                   help="exit 3 when the run file's stored analysis has a refused or warned "
                        "result, or it holds none, or the run never finished")
    common(p)
    p.set_defaults(func=cmd_show)

    p = sub.add_parser("model", help="natural frequencies and damping of the profile's beam model")
    p.add_argument("profile", type=Path)
    p.add_argument("--modes", type=int, help="number of modes (default: model.modes)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    common(p)
    p.set_defaults(func=cmd_model)

    p = sub.add_parser("simulate", help="write a run file of the beam model driven by the profile")
    p.add_argument("profile", type=Path)
    p.add_argument("--duration", type=float, required=True, metavar="S")
    p.add_argument("--rate", type=float, required=True, metavar="HZ")
    p.add_argument("--modes", type=int, help="number of modes (default: model.modes)")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="OUT.h5")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    common(p)
    p.set_defaults(func=cmd_simulate)

    for name, text in (("safe", "put every instrument of the profile in its safe state "
                                "(amplifier output off first, source at 0 V) and read it back"),
                       ("identify", "identify every instrument of the profile, read its "
                                    "settings and interlocks, and leave it safe")):
        p = sub.add_parser(name, help=text)
        p.add_argument("profile", type=Path)
        p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
        common(p)
        p.set_defaults(func=cmd_bench_access)

    p = sub.add_parser("plugins", help="list the plugins found and their status")
    common(p)
    p.set_defaults(func=cmd_plugins)

    p = sub.add_parser("gui", help="open the desktop application")
    p.add_argument("paths", type=Path, nargs="*", metavar="PROFILE|RUN.h5",
                   help="a profile to run, or run files to open")
    p.add_argument("--screenshot", type=Path, metavar="OUT.png",
                   help="render the window with the given run's analysis, save it and exit "
                        "(offscreen: no display needed)")
    p.add_argument("--size", type=_window_size, metavar="WxH",
                   help="window size in pixels (default: what fits the screen, up to "
                        "1680x1050; 1366x768 for --screenshot)")
    p.add_argument("--view", metavar="NAME",
                   help="open the Analysis panel on the view titled NAME, or on the view "
                        "drawing the analysis NAME (its generic view if it has none)")
    p.set_defaults(func=cmd_gui)

    p = sub.add_parser("profile", help="profile tools")
    psub = p.add_subparsers(dest="profile_command", required=True, metavar="ACTION")
    c = psub.add_parser("check", help="validate a profile and its safety limits")
    c.add_argument("profile", type=Path)
    c.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    common(c)
    c.set_defaults(func=cmd_profile_check)

    _add_plugin_commands(sub, registry if registry is not None else _loaded_plugins())
    return parser


def main(argv: list[str] | None = None, started_with: Sequence[int] = ()) -> int:
    """``fsi-lab``: run a command and return its exit code.

    From the first line, Ctrl+C and SIGTERM end the command with exit code 130 and one message
    (a run first puts its bench in the safe state and finalises its file); the signal is also
    noted, so that one whose exception a library swallows is raised at the next checkpoint.

    Parameters
    ----------
    argv
        The command line after ``fsi-lab``; ``sys.argv[1:]`` when None.
    started_with
        Signals noted while the command was being imported (:mod:`fsi_lab.launch`, the
        console script's entry point, notes them): the first ends the command at once.
    """
    global _json_emitted, _plugins
    _plugins = None
    note = SignalNote()
    signals = RunSignals(on_signal=note)
    argv = sys.argv[1:] if argv is None else list(argv)
    wants_json = "--json" in argv
    try:
        signals.install()
        _json_emitted = False
        if started_with:  # noted by the launcher before these handlers were in place
            note(started_with[0])
            note.check()
        args = build_parser(json_requested=wants_json).parse_args(argv)
        args.signals, args.signal_note = signals, note
        return _run_command(args)
    except (KeyboardInterrupt, RunAborted) as exc:
        signals.silence()
        reason = str(exc) or INTERRUPTED
        if wants_json and not _json_emitted:
            _emit_json({"error": f"interrupted: {reason}", "exit_code": 130})
        print(f"fsi-lab: interrupted: {reason}", file=sys.stderr)
        return 130
    finally:
        signals.restore()


def _run_command(args) -> int:
    """``args.func(args)``, with the errors meant for the user turned into one message."""
    try:
        return args.func(args)
    except BrokenPipeError:  # the reader of stdout went away (`fsi-lab show RUN | head`)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    except (FsiLabError, OSError) as exc:
        if isinstance(exc, OSError):  # a file or folder the system refused: name it
            where = f"{exc.filename}: " if exc.filename else ""
            text, code = f"{where}{exc.strerror or exc}", 1
        else:
            text, code = str(exc), exc.exit_code
        if getattr(args, "json", False):
            _emit_json({"error": text, "exit_code": code})
        print(f"fsi-lab: error: {text}", file=sys.stderr)
        return code


if __name__ == "__main__":
    sys.exit(main())
