"""The analysis of one run file as a task (``fsi-lab analyze``, one file or many).

:func:`analysis_profile` builds what ``fsi-lab analyze`` analyses a run file with: the run's own
profile's ``[analysis]`` and ``[specimen]`` (or the default chain for imported data), the run's
recorded overrides of them, then the new ones. :func:`analyse_file` is the task each worker of a
batch runs (:mod:`fsi_lab.executor`): it analyses one file, stores the results in it as
``fsi-lab analyze`` does, and returns the summary.
"""

from __future__ import annotations

import os
import resource
import sys
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from fsi_lab.errors import InputFileError
from fsi_lab.run_profile import (  # noqa: F401 - where they were first found
    ANALYSIS_SECTIONS,
    analysis_profile,
    require_no_specimen,
    require_something_to_analyse,
    worker_registry,
)


def require_mass_per_length(value: float | None) -> None:
    """InputFileError unless ``value`` is None or a mass per length > 0 (kg/m)."""
    if value is not None and not (value > 0):
        raise InputFileError(f"--mass-per-length {value}: expected kg/m > 0")


@dataclass(frozen=True)
class AnalyseTask:
    """One file of ``fsi-lab analyze``: the run file, the ``--set`` overrides and
    ``--mass-per-length`` (kg/m, or None)."""

    path: str
    sets: tuple[str, ...] = ()
    mass_per_length: float | None = None


#: Why an analysis that identified nothing was not stored (``not_stored`` in its summary).
KEPT = ("this analysis is not stored: the file keeps the analysis stored in it before, which "
        "identified modes (fsi-lab show prints it)")
#: ... and one whose C_i and C_f failed where the stored one's were identified.
KEPT_COEFFICIENTS = ("this analysis is not stored: the file keeps the analysis stored in it "
                     "before, which identified C_i and C_f there (fsi-lab show prints it)")


def stored_identification(path: Path, registry) -> dict[str, Any] | None:
    """The summary of the analysis stored in run file ``path`` when it identified something,
    else None: a new analysis that identifies nothing does not replace it (a damaged record,
    an override that asks for what the record cannot give must not destroy results already
    written)."""
    from fsi_lab.runfile import read_analysis_summary
    from fsi_lab.summary import nothing_identified

    try:
        earlier = read_analysis_summary(path)
    except InputFileError:  # a damaged /analysis is replaced
        return None
    if earlier and nothing_identified(earlier, registry) is None \
            and any(info.get("components") for info in (earlier.get("channels") or {}).values()):
        return earlier
    return None


def with_coefficients(summary: dict[str, Any]) -> list[str]:
    """The channels of an analysis ``summary`` with C_i and C_f for a component."""
    return [name for name, info in (summary.get("channels") or {}).items()
            if any((c.get("equivalent_damping") or {}).get("c_i") is not None
                   for c in info.get("components") or [] if isinstance(c, dict))]


def coefficients_lost(earlier: dict[str, Any], summary: dict[str, Any], registry) -> str | None:
    """Why the analysis ``summary`` fails to give C_i and C_f on a channel whose components
    had them in the ``earlier`` (stored) one, or None: the analysis that provides them is
    among the channel's ``errors`` now (a parameter it needs missing, an override it cannot
    work with). That analysis is not stored, as one that identifies nothing is not."""
    from fsi_lab.summary import provides

    reasons = []
    for name in with_coefficients(earlier):
        now = (summary.get("channels") or {}).get(name) or {}
        failed = [error for error in now.get("errors", [])
                  if error.get("plugin")
                  and provides(registry, error["plugin"], "damping-coefficients")]
        if failed:
            reasons.append(f"channel {name}: {failed[0]['message']}")
    if not reasons:
        return None
    return "C_i and C_f were not identified where the stored analysis had them: " \
        + "; ".join(reasons)


def stored_mass_per_length(path: Path) -> float | None:
    """The ``--mass-per-length`` (kg/m) the analysis stored in run file ``path`` was computed
    with, or None (none given, never analysed, or unreadable)."""
    from fsi_lab.runfile import read_analysis_overrides

    try:
        overrides = read_analysis_overrides(path)
    except InputFileError:
        return None
    for text in overrides:
        key, _, value = text.partition("=")
        if key == "--mass-per-length":
            try:
                mass = float(value)
            except ValueError:
                return None
            return mass if mass > 0 else None
    return None


def analysed_with(task: AnalyseTask) -> tuple[str, ...]:
    """What the analysis of ``task`` is computed with beyond the run's own settings, as
    stored in ``/analysis`` attribute ``overrides``: its ``--set`` texts, and
    ``--mass-per-length=VALUE``."""
    from fsi_lab.runfile import analysis_overrides

    return analysis_overrides(task.sets, task.mass_per_length)


def cut_short(run) -> str | None:
    """A warning when ``run`` (a :class:`~fsi_lab.runfile.RunData`) did not complete: it was
    aborted (Ctrl+C, SIGTERM, Abort), failed, or never finished (its exit status still
    ``running``: the process died); its record may stop mid-decay, so every number read from
    it says so. None for a completed run, or imported data."""
    import tomllib

    status = run.attrs.get("exit_status") or "completed"
    if status == "completed":
        return None
    lengths = [run.channel_samples.get(name, 0) / channel.sample_rate
               for name, channel in run.channels.items() if channel.sample_rate > 0]
    recorded = max(lengths, default=0.0)
    planned = None
    try:
        planned = tomllib.loads(run.profile_text).get("run", {}).get("duration")
        for item in run.attrs.get("overrides", []):
            key, _, value = item.partition("=")
            if key.strip() == "run.duration":
                planned = value
        planned = float(planned) if planned is not None else None
    except (tomllib.TOMLDecodeError, AttributeError, TypeError, ValueError):
        planned = None
    length = f"{recorded:.4g} s" + (f" of the {planned:g} s planned" if planned else "")
    why = {"running": "never finished (its exit status is still 'running': the process that "
                      "ran it died, by kill -9, a crash or a power cut)",
           "aborted": "was aborted (Ctrl+C, SIGTERM or Abort)"}.get(
        status, f"ended {status}" + (f" ({run.attrs['error']})" if run.attrs.get("error")
                                     else ""))
    return (f"the run {why}: its record holds {length}, cut short where the run stopped, so "
            "a decay may end early or still be forced and every number here is read from a "
            "record the run did not finish")


def peak_rss_mib() -> float:
    """The largest resident memory this process has used so far, MiB."""
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / (1024.0 * 1024.0) if sys.platform == "darwin" else peak / 1024.0


def analyse_file(task: AnalyseTask, registry=None, bus=None) -> dict[str, Any]:
    """Analyse one run file and store the results in it, as ``fsi-lab analyze RUN.h5`` does.

    Returns
    -------
    dict
        ``summary`` (the object ``fsi-lab analyze --json`` prints for one file),
        ``refused`` (why the input was not what the analyses need although they ran, or None:
        :func:`fsi_lab.summary.uncalibrated`), ``messages`` (``[level, sentence]`` pairs on
        the file as a whole: the mass kept from the stored analysis, a stored analysis with
        C_i and C_f replaced by one without; logged on ``bus`` as they come, and returned
        for a batch's workers, which have none) and ``worker`` (``pid`` and
        ``peak_rss_mib``, the process's peak memory so far, MiB).

    Raises
    ------
    FsiLabError
        The file cannot be read or analysed (naming it), exit code 2 for bad input.
    """
    from fsi_lab.runfile import read_run, require_analysable
    from fsi_lab.store import analyse_and_store
    from fsi_lab.summary import nothing_identified, uncalibrated

    registry = registry if registry is not None else worker_registry()
    run = read_run(task.path, load_data=False, lazy=True)  # a channel is read when used
    require_analysable(run)
    profile = analysis_profile(run, registry, task.sets)
    require_mass_per_length(task.mass_per_length)
    require_no_specimen(run, profile, task.mass_per_length)
    require_something_to_analyse(run, profile)
    messages: list[list[str]] = []

    def say(level: str, sentence: str) -> None:
        messages.append([level, sentence])
        if bus is not None:
            bus.log(level, sentence)

    if task.mass_per_length is None and profile.specimen is None:
        mass = stored_mass_per_length(Path(task.path))
        if mass is not None:
            task = replace(task, mass_per_length=mass)
            say("INFO", f"{task.path}: mu + M = {mass:g} kg/m, the --mass-per-length the "
                        "analysis stored in the file was given (give --mass-per-length to "
                        "change it)")
    earlier = stored_identification(Path(task.path), registry)

    def lost(summary: dict[str, Any]) -> str | None:
        return coefficients_lost(earlier, summary, registry) if earlier else None

    def keep_earlier(summary: dict[str, Any]) -> bool:
        return earlier is not None and (nothing_identified(summary, registry) is not None
                                        or lost(summary) is not None)

    summary = analyse_and_store(Path(task.path), run.channels, profile.analysis,
                                profile.analysis_params, registry, profile.specimen,
                                task.mass_per_length, bus, keep_earlier,
                                tuple(filter(None, [cut_short(run)])),
                                analysed_with(task))
    if keep_earlier(summary):
        summary["not_stored"] = KEPT if nothing_identified(summary, registry) else \
            KEPT_COEFFICIENTS
    elif earlier is not None:
        dropped = sorted(set(with_coefficients(earlier)) - set(with_coefficients(summary)))
        if dropped:
            say("WARNING", f"{task.path}: the analysis stored before, with C_i and C_f on "
                           f"channel {', '.join(dropped)}, is replaced by this one, which has "
                           "none there (its chain gives none: run fsi-lab analyze again with "
                           "the chain that gave them to get them back)")
    quantities = {name: channel.quantity for name, channel in run.channels.items()}
    return {"summary": summary, "refused": uncalibrated(summary, quantities) or lost(summary),
            "messages": messages,
            "worker": {"pid": os.getpid(), "peak_rss_mib": peak_rss_mib()}}
