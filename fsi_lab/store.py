"""Runs the analysis chain over a run file's channels and stores the results in it.

Below the analysis's budget (``[analysis] segment_samples``) the record is analysed in memory
(:func:`fsi_lab.chain.run_chain`) and its results written in one rewrite of the run file
(:func:`fsi_lab.runfile.write_analysis`); above it, in segments (:mod:`fsi_lab.segmented`).
``fsi-lab analyze`` (:func:`fsi_lab.batch.analyse_file`) and the runner's analysis call
:func:`analyse_and_store`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Mapping

from fsi_lab.contract import ChannelData
from fsi_lab.events import EventBus
from fsi_lab.registry import Registry


def analyse_and_store(path: Path, channels: Mapping[str, ChannelData],
                      analysis: Mapping[str, Any], params: Mapping[str, Mapping[str, Any]],
                      registry: Registry, specimen: Any = None,
                      mass_per_length: float | None = None,
                      bus: EventBus | None = None,
                      keep_earlier: Callable[[dict[str, Any]], bool] | None = None,
                      warnings: tuple[str, ...] = (),
                      overrides: tuple[str, ...] = ()) -> dict[str, Any]:
    """Run the chain and store it in the run file; returns the ``analyze --json`` object.

    A record whose used channels hold more samples than the analysis's budget
    (``segment_samples``) is analysed in segments (:mod:`fsi_lab.segmented`). When
    ``keep_earlier`` says so of the new summary, nothing is written: the file keeps the
    analysis it held (the file is left exactly as it was). ``warnings`` (about the record as a
    whole) head every channel's warnings. ``overrides`` (what ``fsi-lab analyze`` was given
    beyond the run's own settings) are stored as ``/analysis`` attribute ``overrides``."""
    from fsi_lab.chain import run_chain
    from fsi_lab.runfile import write_analysis
    from fsi_lab.segmented import analyse_in_segments, segment_plan
    from fsi_lab.summary import add_warnings

    plan = segment_plan(channels, analysis)
    if plan is not None:
        return analyse_in_segments(path, channels, analysis, params, registry, plan, specimen,
                                   mass_per_length, bus, keep_earlier, warnings, overrides)

    groups, channel_summaries = run_chain(channels, analysis, params, registry, specimen,
                                          mass_per_length, bus)
    summary = {"run": str(path), "channels": channel_summaries}
    add_warnings(summary, warnings)
    if keep_earlier is None or not keep_earlier(summary):
        write_analysis(path, groups, summary, {"overrides": list(overrides)})
    return summary
