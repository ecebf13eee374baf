"""Run orchestration: configure -> arm -> excite and acquire -> finalize -> analyze.

Whatever ends a run (success, an error, Ctrl+C, SIGTERM, an instrument that stops answering,
an abort from the GUI), the amplifier output is disabled and the source set to 0 V first; then
the instruments' state is read back and the run file is finalized with its exit status.

What the process cannot do once it is dead (``kill -9``, a crash, a power cut) the bench does:
the amplifier's driver arms its watchdog, which switches the output off when the run falls
silent; and a run on real instruments holds a lock on them (:mod:`fsi_lab.bench_lock`), so the
next run refuses to start until ``fsi-lab safe`` has looked at a bench left by a run that died.
During the record every instrument is asked a few times a second whether it still answers
(:meth:`~fsi_lab.contract.Instrument.monitor`), so a link fault anywhere fails the run.

A run can also be stopped early (:meth:`Runner.stop`): the acquisition ends after the block in
hand, the bench goes to the same safe state, and the shortened record is a completed run that is
analysed like any other (root attribute ``stopped_early``).
"""

from __future__ import annotations

import signal
import threading
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fsi_lab.bench_access import OPEN_ORDER, bench_context, safe_and_close, unsafe_roles
from fsi_lab.bench_lock import BenchLock
from fsi_lab.contract import ROLE_INTERFACES, BenchContext, Instrument
from fsi_lab.errors import FsiLabError, InputFileError, InstrumentError, RunAborted
from fsi_lab.events import DataBlock, EventBus, Progress, StateChanged
from fsi_lab.preflight import check_safety, run_setting
from fsi_lab.profile import Profile
from fsi_lab.registry import Registry
from fsi_lab.runfile import (
    INTERRUPTED,
    RunFileWriter,
    new_run_path,
    read_run,
    software_version,
    utc_now,
)
from fsi_lab.safety import SafetyReport, require_safe
from fsi_lab.signals import RunSignals
from fsi_lab.store import analyse_and_store

INTERLOCK_POLL_S = 0.2


@dataclass
class RunOutcome:
    """How a run ended."""

    path: Path | None
    exit_status: str
    error: str | None = None
    traceback: str = ""
    safety: SafetyReport | None = None
    summary: dict[str, Any] | None = None
    final_states: dict[str, dict[str, Any]] = field(default_factory=dict)
    stopped_early: bool = False
    #: the run file could not be finalised and was given up (a full disk)
    file_abandoned: bool = False
    #: Ctrl+C or SIGTERM arrived after the record was complete (while it was finalised, or
    #: during its analysis): the run completed, the command was interrupted
    interrupted: bool = False

    def as_json(self) -> dict[str, Any]:
        return {
            "run": str(self.path) if self.path else None,
            "exit_status": self.exit_status,
            "stopped_early": self.stopped_early,
            "interrupted": self.interrupted,
            "error": self.error,
            "safety": self.safety.as_dict() if self.safety else None,
            "final_state": self.final_states,
            "analysis": self.summary,
        }


def require_directory(out_dir: Path) -> None:
    """InputFileError when ``out_dir`` (``--out``), or the first of its parents that exists,
    is not a directory: the run file could not be created, and nothing may be driven first."""
    existing = next((p for p in (Path(out_dir), *Path(out_dir).parents) if p.exists()), None)
    if existing is not None and not existing.is_dir():
        beside = f" ({existing} is a file)" if existing != Path(out_dir) else ""
        raise InputFileError(f"{out_dir}: is not a directory{beside}; expected the directory "
                             "of the run file (--out)")


class Runner:
    """Runs one profile on its bench and writes one run file.

    Parameters
    ----------
    profile
        A validated, runnable profile.
    registry
        Loaded plugins.
    out_dir
        Directory of the run file.
    bus
        Event bus; the CLI renders it, the GUI subscribes to it.
    analyze
        Run the analysis chain after a completed acquisition.
    """

    def __init__(self, profile: Profile, registry: Registry, out_dir: str | Path,
                 bus: EventBus | None = None, analyze: bool = True) -> None:
        profile.require_runnable()
        self.profile = profile
        self.registry = registry
        self.out_dir = Path(out_dir)
        self.bus = bus or EventBus()
        self.analyze = analyze
        self._abort = threading.Event()
        self._abort_reason = "aborted by the operator"
        self._stop = threading.Event()
        self._file: tuple[Path, str, str] | None = None
        self.instruments: dict[str, Instrument] = {}
        # Shared by the instruments of this run; simulated ones find the physics here, and
        # register in "cleanup" what must be stopped once every instrument is closed.
        self.bench_context: BenchContext = bench_context(profile)

    def reserve_file(self) -> Path:
        """The run file this run will write, chosen now (a sequence records it before the
        run starts, so that a run killed mid-way is found again); the file is created by
        :meth:`run`."""
        if self._file is None:
            require_directory(self.out_dir)
            self._file = new_run_path(self.out_dir)
        return self._file[0]

    def abort(self) -> None:
        """Ask the run to stop as soon as possible and go to the safe state (thread-safe)."""
        self._abort.set()

    def stop(self) -> None:
        """End the acquisition after the current block and keep the run (thread-safe).

        The bench goes to its safe state as on every exit; unlike :meth:`abort`, the record is
        a completed run (marked ``stopped_early``) and the analysis chain runs on it. Before
        the excitation has started, a stop ends the run as aborted: there is nothing to keep.
        """
        self._stop.set()

    # ------------------------------------------------------------------ the run
    def run(self) -> RunOutcome:
        """Carry out the run. Raises only for problems found before anything was started
        (bad profile, safety limits); every later problem ends up in the outcome."""
        require_directory(self.out_dir)  # before anything reaches an instrument
        waveform, rate, report = check_safety(self.profile, self.registry)
        require_safe(report, self.profile.path)
        self.bus.log("INFO", f"safety check passed: peak drive {report.peak_drive_v:.3g} V, "
                             f"gain {report.gain:g}, predicted stroke "
                             f"{report.predicted_stroke_mm:.3g} mm")
        path, run_uuid, started = self._file or new_run_path(self.out_dir)
        lock = BenchLock(self.profile)
        lock.acquire(str(path))  # refused (nothing opened or written) while another run holds it
        try:
            signals = RunSignals(on_signal=self._signalled)
            signals.install()
        except BaseException:
            lock.release()
            raise
        outcome = RunOutcome(path=None, exit_status="failed", safety=report)
        writer: RunFileWriter | None = None
        try:
            writer = RunFileWriter(path, self._root_attrs(run_uuid, started))
            outcome.path = path
            self.bus.log("INFO", f"writing {path}")
            writer.write_excitation(waveform, rate, {
                "plugin": self.profile.excitation_plugin,
                "plugin_version": self.registry.version_of("excitation",
                                                           self.profile.excitation_plugin),
                "peak_drive_v": report.peak_drive_v,
                "predicted_stroke_mm": report.predicted_stroke_mm,
            }, self.profile.excitation)
            outcome.stopped_early = self._acquire(writer, waveform, rate)
            outcome.exit_status = "completed"
        except (KeyboardInterrupt, RunAborted) as exc:
            outcome.exit_status = "aborted"
            outcome.error = str(exc) or INTERRUPTED
        except Exception as exc:  # noqa: BLE001 - any failure ends in the safe state
            outcome.exit_status = "failed"
            outcome.error = str(exc) if isinstance(exc, FsiLabError) else (
                f"{type(exc).__name__}: {exc}")
            outcome.traceback = traceback.format_exc()
        finally:
            try:
                self._finish(signals, writer, outcome)
            finally:
                # released only once the bench is safe and the file final: a run killed before
                # leaves its lock, and the next one refuses until `fsi-lab safe` has looked
                lock.release()
        # From here to the end Ctrl+C and SIGTERM end only the analysis (the record is safe);
        # the run's handlers also set the abort flag, checked at every progress event.
        try:
            self.bus.emit(StateChanged(outcome.exit_status, outcome.error or ""))
            if signals.pending:
                outcome.interrupted = True
                if outcome.exit_status == "completed":  # (an aborted run has no analysis)
                    self.bus.log("WARNING", "interrupted while finalizing the completed record: "
                                            "the analysis is skipped")
            elif outcome.exit_status == "completed" and self.analyze \
                    and self.profile.analysis["chain"]:
                self._analyse_into(outcome)
        except (KeyboardInterrupt, RunAborted) as exc:
            outcome.interrupted = True
            if outcome.exit_status == "completed" and outcome.summary is None:
                outcome.error = (f"the analysis was stopped ({str(exc) or 'Ctrl+C'}); the record "
                                 "is complete: run `fsi-lab analyze` on the file")
                self.bus.log("WARNING", outcome.error)
        finally:
            signals.restore()
        return outcome

    def _finish(self, signals: RunSignals, writer: RunFileWriter | None,
                outcome: RunOutcome) -> None:
        """Safe state, then the run file finalised, with Ctrl+C and SIGTERM held back.

        A signal that arrives in the instant before they are held back raises here: it is
        noted as held and the safe state is carried out all the same (it is never skipped).
        """
        for _ in range(3):
            try:
                with signals.held():
                    outcome.final_states = self._safe_state_all()
                    self._require_bench_safe(outcome)
                    self._finalize(writer, outcome)
                return
            except (KeyboardInterrupt, RunAborted) as exc:
                signals.pending.append(signal.SIGINT if isinstance(exc, KeyboardInterrupt)
                                       else signal.SIGTERM)
        raise RunAborted("the safe state was interrupted three times; check the bench by hand")

    def _analyse_into(self, outcome: RunOutcome) -> None:
        """Run the chain on the completed record into ``outcome.summary``; a signal ends it
        (raised), also one whose exception a library swallowed (the abort flag is checked at
        every progress event and at the end)."""
        unsubscribe = self.bus.subscribe(self._checkpoint)
        try:
            outcome.summary = self._analyse(outcome.path)
        except (FsiLabError, OSError) as exc:  # the record is safe; only the analysis is lost
            outcome.error = f"analysis not stored: {exc}; run `fsi-lab analyze` on the file"
            self.bus.log("ERROR", outcome.error)
        finally:
            unsubscribe()
        if self._abort.is_set():
            outcome.interrupted = True
            outcome.error = (f"{self._abort_reason} at the end of the analysis"
                             + ("; its results were stored" if outcome.summary else ""))
            self.bus.log("WARNING", outcome.error)

    def _checkpoint(self, event) -> None:
        """Event-bus subscriber: raise the abort at every progress event once requested."""
        if isinstance(event, Progress):
            self._check_abort()

    def _root_attrs(self, run_uuid: str, started: str) -> dict[str, Any]:
        versions = {r.name: f"{r.distribution} {r.version}" for r in self.registry.records
                    if r.status == "loaded"}
        return {
            "uuid": run_uuid,
            "start_time": started,
            "kind": "measured",
            "run_name": self.profile.run["name"],
            "software_version": software_version(),
            "plugin_versions": versions,
            "profile": self.profile.text,
            "profile_path": self.profile.path,
            "overrides": list(self.profile.overrides),
        }

    def _open_instruments(self, writer: RunFileWriter) -> None:
        for role in OPEN_ORDER:
            config = self.profile.roles.get(role)
            if config is None:
                continue
            self.bus.emit(Progress("configure", 0.0, f"opening {role} ({config.plugin})"))
            descriptor = self.registry.get("instrument", config.plugin)
            instrument = descriptor.open(config.address, dict(config.settings),
                                         self.bench_context)
            interface = ROLE_INTERFACES[role]
            if not isinstance(instrument, interface):
                close = getattr(instrument, "close", None)
                if callable(close):
                    close()
                raise InstrumentError(
                    f"bench.{role}: plugin {config.plugin!r} returned "
                    f"{type(instrument).__name__}, which is not a {interface.__name__}"
                )
            self.instruments[role] = instrument
            if role == "amplifier":  # nothing may drive the shaker before we arm
                instrument.safe_state()
            if getattr(instrument, "found_on", None):
                self.bus.log("WARNING", f"{role}: its output was ON when the run opened it (left "
                                        "on by a run that died?); it was switched off first")
            identity = instrument.identify()
            writer.write_instrument(role, {
                "identity": identity, "plugin": config.plugin, "address": config.address,
                "plugin_version": self.registry.version_of("instrument", config.plugin),
            }, {})
            self.bus.log("INFO", f"{role}: {identity}")
        self._record_settings(writer)

    def _record_settings(self, writer: RunFileWriter, roles: tuple[str, ...] | None = None
                         ) -> None:
        """Store each instrument's settings (of ``roles``, or every one): the profile's,
        updated by what the driver reports."""
        for role, instrument in self.instruments.items():
            if roles is not None and role not in roles:
                continue
            settings = {**self.profile.roles[role].settings, **instrument.settings()}
            writer.write_instrument(role, {}, settings)

    def _acquire(self, writer: RunFileWriter, waveform: np.ndarray, rate: float) -> bool:
        """Record the run; True if the operator stopped it before the record was complete."""
        profile = self.profile
        self.bus.emit(StateChanged("configuring"))
        self._open_instruments(writer)
        source, amplifier = self.instruments["source"], self.instruments["amplifier"]
        acquisition = self.instruments["acquisition"]
        vibrometer = self.instruments.get("vibrometer")
        source.load_waveform(waveform, rate)
        amplifier.set_gain(float(run_setting(profile, "amplifier", "gain")))
        inputs = {name: c.input for name, c in profile.channels.items()}
        sample_rate = acquisition.configure(inputs, profile.run["sample_rate"],
                                            profile.run["duration"])
        sensitivities: dict[str, float] = {}
        for name, channel in profile.channels.items():
            sensitivity, t0 = channel.sensitivity, 0.0
            if channel.sensor == "vibrometer" and vibrometer is not None:
                sensitivity, t0 = vibrometer.sensitivity(), -vibrometer.delay()
            sensitivities[name] = sensitivity
            writer.create_channel(name, {
                "units": channel.unit, "quantity": channel.quantity,
                "sample_rate": sample_rate, "t0": t0, "sensitivity": sensitivity,
                "sensitivity_units": f"V/({channel.unit})", "input": channel.input,
                "source_instrument": channel.sensor or "acquisition",
            })
        self._record_settings(writer)  # now with what configuration set (rates, ranges)
        writer.flush()
        self._check_abort()

        acquisition.arm()
        amplifier.enable_output(True)
        # what switching the output on set: the amplifier's watchdog, armed (or not offered)
        self._record_settings(writer, ("amplifier",))
        self.bus.emit(StateChanged("armed"))
        self._check_abort()
        if self._stop.is_set():
            raise RunAborted("stopped by the operator before the excitation started")
        source.start()
        self.bus.emit(StateChanged("running"))
        duration = profile.run["duration"]
        timeout = max(2.0, 4 * profile.run["block_duration"])
        samples = 0
        last_poll = 0.0
        stopped = False
        while True:
            self._check_abort()
            block = acquisition.read_block(timeout)
            if block is None:
                break
            size = self._check_block(block, sensitivities)
            calibrated = {}
            for name, sensitivity in sensitivities.items():
                values = np.asarray(block[name], dtype=float) / sensitivity
                writer.append(name, values)
                calibrated[name] = values
            t0 = samples / sample_rate
            samples += size
            if writer.flush_if_due():
                self.bus.log("DEBUG", f"flushed {samples} samples per channel")
            self.bus.emit(DataBlock(t0, sample_rate, calibrated))
            self.bus.emit(Progress("acquire", min(1.0, samples / (duration * sample_rate)),
                                   f"{samples / sample_rate:.2f} s of {duration:g} s"))
            now = time.monotonic()
            if now - last_poll >= INTERLOCK_POLL_S:
                last_poll = now
                self._check_interlocks(amplifier)
                self._monitor()
            if self._stop.is_set() and samples < round(duration * sample_rate):
                self.bus.log("INFO", f"stopped by the operator after {samples / sample_rate:.3g} s "
                                     f"of {duration:g} s")
                stopped = True
                break
        # A fast bench can finish between two polls: a trip or a fault must never pass as
        # completed.
        self._check_interlocks(amplifier)
        self._monitor()
        writer.flush()
        return stopped

    def _check_block(self, block: dict[str, Any], channels: dict[str, Any]) -> int:
        """Samples per channel of a block from the digitiser; it must hold every channel of the
        profile, all of the same length (the channels stay aligned in time)."""
        plugin = self.profile.roles["acquisition"].plugin
        missing = sorted(set(channels) - set(block))
        if missing:
            raise InstrumentError(
                f"acquisition ({plugin}): a block lacks channel(s) {', '.join(missing)}; "
                f"expected {', '.join(sorted(channels))}"
            )
        sizes = {name: int(np.size(block[name])) for name in channels}
        if len(set(sizes.values())) > 1:
            raise InstrumentError(
                f"acquisition ({plugin}): a block's channels differ in length "
                f"({', '.join(f'{n} {k}' for n, k in sizes.items())}); expected equal lengths"
            )
        return next(iter(sizes.values()), 0)

    def _monitor(self) -> None:
        """Every instrument the record does not read (all but the acquisition) must still
        answer and hold its state (:meth:`~fsi_lab.contract.Instrument.monitor`)."""
        for role in ("source", "amplifier", "vibrometer"):
            instrument = self.instruments.get(role)
            if instrument is None:
                continue
            try:
                instrument.monitor()
            except InstrumentError as exc:
                raise InstrumentError(f"{role} failed during the record: {exc}") from None

    @staticmethod
    def _check_interlocks(amplifier) -> None:
        tripped = [name for name, on in amplifier.interlocks().items() if on]
        if tripped:
            raise InstrumentError(
                f"amplifier interlock tripped: {', '.join(tripped)}; the output was switched "
                "off by the amplifier"
            )

    def _signalled(self, signum: int) -> None:
        """Ctrl+C or SIGTERM: also an abort request, which the run checks at every step, should
        the exception the handler raises be lost in a library's cleanup code."""
        self._abort_reason = INTERRUPTED if signum == signal.SIGINT \
            else f"received {signal.Signals(signum).name}"
        self._abort.set()

    def _check_abort(self) -> None:
        if self._abort.is_set():
            raise RunAborted(self._abort_reason)

    def _safe_state_all(self) -> dict[str, dict[str, Any]]:
        """Safe state for every opened instrument, amplifier first; then read their state back."""
        self.bus.emit(StateChanged("finalizing"))
        plugins = {role: config.plugin for role, config in self.profile.roles.items()}
        return safe_and_close(self.instruments, self.bench_context.cleanup, self.bus.log, plugins)

    def _require_bench_safe(self, outcome: RunOutcome) -> None:
        """A run that leaves an instrument not confirmed safe has failed, however it ended."""
        unsafe = unsafe_roles(outcome.final_states,
                              {role: config.plugin for role, config in self.profile.roles.items()})
        if not unsafe:
            return
        note = "NOT confirmed safe after the run: " + "; ".join(
            f"{role}: {why}" for role, why in unsafe.items()) + "; check the bench by hand"
        outcome.exit_status = "failed"
        outcome.stopped_early = False
        outcome.error = f"{outcome.error}; {note}" if outcome.error else note

    def _finalize(self, writer: RunFileWriter | None, outcome: RunOutcome) -> None:
        """Final states and the ending into the file, then close it; a file that cannot be
        written any more fails the run (what was flushed before stays)."""
        if writer is None or writer.closed:
            return
        try:
            for role, state in outcome.final_states.items():
                writer.write_final_state(role, state)
            writer.set_attrs({
                "stop_time": utc_now(),
                "exit_status": outcome.exit_status,
                "stopped_early": outcome.stopped_early,
                "error": outcome.error or "",
                "traceback": outcome.traceback,
            })
            writer.close()
        except Exception as exc:  # noqa: BLE001 - e.g. a full disk: report, do not crash
            writer.abandon()
            outcome.file_abandoned = True
            note = (f"the run file {outcome.path} could not be finalised ({type(exc).__name__}: "
                    f"{exc}); it holds at most what was flushed before")
            outcome.exit_status = "failed"
            outcome.error = f"{outcome.error}; {note}" if outcome.error else note
            self.bus.log("ERROR", note)
            return
        self.bus.log("INFO", f"run {outcome.exit_status}: {outcome.path}")

    def _analyse(self, path: Path) -> dict[str, Any]:
        self.bus.emit(StateChanged("analyzing"))
        run = read_run(path, load_data=False, lazy=True)  # a channel is read when used
        return analyse_and_store(path, run.channels, self.profile.analysis,
                                 self.profile.analysis_params, self.registry,
                                 specimen=self.profile.specimen, bus=self.bus)
