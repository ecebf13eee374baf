"""The analysis of one run file as a task (``fsi-lab analyze``, one file or many).

:func:`analysis_profile` builds what ``fsi-lab analyze`` analyses a run file with: the run's own
profile's ``[analysis]`` and ``[specimen]`` (or the default chain for imported data), the run's
recorded overrides of them, then the new ones. :func:`analyse_file` is the task each worker of a
batch runs (:mod:`fsi_lab.executor`): it analyses one file, stores the results in it as
``fsi-lab analyze`` does, and returns the summary.
"""

from __future__ import annotations

import json
import os
import resource
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fsi_lab.errors import InputFileError

#: The sections of a run's profile the analysis reads.
ANALYSIS_SECTIONS = ("analysis", "specimen")


def analysis_profile(run, registry, sets: list[str] | tuple[str, ...] = ()):
    """The profile ``fsi-lab analyze`` analyses ``run`` (a :class:`~fsi_lab.runfile.RunData`)
    with: its ``[analysis]`` and ``[specimen]``, its recorded overrides of them, then ``sets``.

    Imported data (no profile) gets the default chain and the reference given on import.

    Raises
    ------
    ProfileError
        The profile, or an override, is refused (naming the run file and the key).
    """
    from fsi_lab.chain import default_chain
    from fsi_lab.profile import parse_profile

    text = run.profile_text
    if not text.strip():  # imported data: the default chain, and the reference given on import
        chain = default_chain(registry)
        text = "[analysis]\nchain = " + json.dumps(chain) + "\n"
        if run.reference:
            text += "reference = " + json.dumps(run.reference) + "\n"
    # The run's own --set overrides of what analysis reads come first, the new ones after.
    recorded = [item for item in run.attrs.get("overrides", [])
                if item.partition(".")[0].strip() in ANALYSIS_SECTIONS]
    return parse_profile(text, f"{run.path}:/profile", registry, recorded + list(sets),
                         sections=ANALYSIS_SECTIONS)


def require_something_to_analyse(run, profile) -> None:
    """InputFileError unless the run has a channel the chain analyses (named or by quantity)."""
    from fsi_lab.chain import channels_to_analyse

    if not channels_to_analyse(run.channels, profile.analysis.get("channels", [])):
        listed = ", ".join(f"{n} ({c.quantity}, {c.unit})" for n, c in run.channels.items())
        raise InputFileError(
            f"{run.path}: nothing to analyse: no velocity or displacement channel (channels: "
            f"{listed or 'none'}); an acceleration or voltage channel is analysed when named, "
            "e.g. --set analysis.channels=NAME")


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


_REGISTRY = None


def worker_registry():
    """The plugins, loaded once per worker process."""
    global _REGISTRY
    if _REGISTRY is None:
        from fsi_lab.registry import load_registry

        _REGISTRY = load_registry()
    return _REGISTRY


def peak_rss_mib() -> float:
    """The largest resident memory this process has used so far, MiB."""
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / (1024.0 * 1024.0) if sys.platform == "darwin" else peak / 1024.0


def analyse_file(task: AnalyseTask, registry=None, bus=None) -> dict[str, Any]:
    """Analyse one run file and store the results in it, as ``fsi-lab analyze RUN.h5`` does.

    Returns
    -------
    dict
        ``summary`` (the object ``fsi-lab analyze --json`` prints for one file) and
        ``worker`` (``pid`` and ``peak_rss_mib``, the process's peak memory so far, MiB).

    Raises
    ------
    FsiLabError
        The file cannot be read or analysed (naming it), exit code 2 for bad input.
    """
    from fsi_lab.chain import analyse_and_store
    from fsi_lab.runfile import read_run, require_analysable

    registry = registry if registry is not None else worker_registry()
    run = read_run(task.path, load_data=False, lazy=True)  # a channel is read when used
    require_analysable(run)
    profile = analysis_profile(run, registry, task.sets)
    require_mass_per_length(task.mass_per_length)
    require_something_to_analyse(run, profile)
    summary = analyse_and_store(Path(task.path), run.channels, profile.analysis,
                                profile.analysis_params, registry, profile.specimen,
                                task.mass_per_length, bus)
    return {"summary": summary, "worker": {"pid": os.getpid(), "peak_rss_mib": peak_rss_mib()}}
