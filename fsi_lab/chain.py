"""Runs the profile's analysis chain over the channels of a run and collects the results.

A failing analysis is recorded (in the run file and the summary) with its reason; the chain goes
on with the other channels, and with the analyses that do not need the failed one. A record that
ends in a long quiet tail is analysed up to a few times its active span (:mod:`fsi_lab.tails`).
"""

from __future__ import annotations

import dataclasses
import math
import traceback
from pathlib import Path
from typing import Any, Mapping

from fsi_lab.contract import AnalysisContext, AnalysisResult, ChannelData
from fsi_lab.errors import FsiLabError
from fsi_lab.events import EventBus, Progress
from fsi_lab.registry import Registry
from fsi_lab.runfile import write_analysis
from fsi_lab.tails import QuietTail, analysed_end

#: Chain used for data that comes without a profile (``fsi-lab import``), where installed.
DEFAULT_CHAIN = ("spectrum", "hvd", "integrate", "instantaneous", "backbone", "damping",
                 "equivalent-damping")
ANALYSED_QUANTITIES = ("velocity", "displacement")


def merge_summary(into: dict[str, Any], part: Mapping[str, Any]) -> None:
    """Merge one analysis's summary into a channel summary (``components`` by ``index``)."""
    for key, value in part.items():
        if key == "components":
            existing = {c["index"]: c for c in into.setdefault("components", [])}
            for component in value:
                target = existing.get(component["index"])
                if target is None:
                    target = {"index": component["index"]}
                    into["components"].append(target)
                    existing[component["index"]] = target
                for name, item in component.items():
                    if name == "warnings":      # every plugin's sentences are kept
                        kept = target.setdefault("warnings", [])
                        kept.extend(w for w in item if w not in kept)
                    else:
                        target[name] = item
            into["components"].sort(key=lambda c: c["index"])
        elif isinstance(value, dict) and isinstance(into.get(key), dict):
            into[key].update(value)
        else:
            into[key] = value


def channels_to_analyse(channels: Mapping[str, ChannelData], wanted: list[str]) -> list[str]:
    """The named channels, or every velocity and displacement channel when none is named."""
    if wanted:
        return list(wanted)
    return [n for n, c in channels.items() if c.quantity in ANALYSED_QUANTITIES]


def cut_quiet_tail(channels: Mapping[str, ChannelData], used: list[str]
                   ) -> tuple[dict[str, ChannelData], QuietTail]:
    """The channels up to where the analysis of the record stops (:func:`fsi_lab.tails.
    analysed_end`, judged on the ``used`` channels: those analysed and the reference), and
    that judgement. Channels of one sample rate keep one length."""
    tail = analysed_end((channels[n].data, channels[n].sample_rate) for n in used
                        if n in channels)
    if not tail.cut:
        return dict(channels), tail
    cut = {}
    for name, channel in channels.items():
        keep = min(channel.data.size, int(math.ceil(tail.analysed_s * channel.sample_rate)))
        cut[name] = dataclasses.replace(channel, data=channel.data[:keep])
    return cut, tail


def run_chain(channels: Mapping[str, ChannelData], analysis: Mapping[str, Any],
              params: Mapping[str, Mapping[str, Any]], registry: Registry,
              specimen: Any = None, mass_per_length: float | None = None,
              bus: EventBus | None = None) -> tuple[dict[str, dict], dict[str, Any]]:
    """Run every analysis of ``analysis["chain"]`` on each analysed channel.

    Parameters
    ----------
    channels
        All channels of the run.
    analysis
        The profile's ``[analysis]`` values: ``chain``, ``channels``, ``reference``.
    params
        Validated parameters per analysis plugin.
    registry
        Loaded plugins.
    specimen
        The run's :class:`~fsi_lab.specimen.Specimen`, or None.
    mass_per_length
        mu + M, kg/m, for data without a specimen, or None.
    bus
        Receives progress and log events.

    Returns
    -------
    groups, summary
        ``groups`` maps ``"<channel>/<plugin>"`` to what :func:`fsi_lab.runfile.write_analysis`
        stores; ``summary`` maps channel names to their merged JSON summaries.
    """
    bus = bus or EventBus()
    groups: dict[str, dict] = {}
    summary: dict[str, Any] = {}
    names = channels_to_analyse(channels, analysis.get("channels", []))
    reference = analysis.get("reference")
    channels, tail = cut_quiet_tail(channels, names + ([reference] if reference else []))
    chain = list(analysis.get("chain", []))
    total = max(1, len(names) * len(chain))
    done = 0
    for channel_name in names:
        if channel_name not in channels:
            summary[channel_name] = {"errors": [{
                "plugin": None,
                "message": f"channel {channel_name!r} is not in the run; channels are "
                           f"{', '.join(channels) or 'none'}"}]}
            continue
        channel_summary: dict[str, Any] = {"components": []}
        results: dict[str, AnalysisResult] = {}
        failed: dict[str, str] = {}
        for plugin_name in chain:
            bus.emit(Progress("analysis", done / total, f"{channel_name}: {plugin_name}"))
            done += 1
            key = f"{channel_name}/{plugin_name}"
            plugin_params = dict(params.get(plugin_name, {}))
            try:
                plugin = registry.get("analysis", plugin_name)
                missing = [r for r in plugin.requires if r not in results]
                if missing:
                    raise FsiLabError(
                        f"needs {', '.join(missing)} earlier in the chain on this channel, "
                        "which did not run or failed"
                    )
                context = AnalysisContext(
                    channel=channels[channel_name], channels=channels, results=results,
                    specimen=specimen, mass_per_length=mass_per_length,
                    reference=analysis.get("reference"), failed=dict(failed),
                )
                result = plugin.run(context, plugin_params)
                if not isinstance(result, AnalysisResult):
                    raise TypeError(
                        f"returned {type(result).__name__}, expected AnalysisResult"
                    )
            except Exception as exc:  # noqa: BLE001 - recorded, the chain goes on
                message = str(exc) if isinstance(exc, FsiLabError) else (
                    f"{type(exc).__name__}: {exc}"
                )
                where = f"{plugin_name} on channel {channel_name!r}"
                if not message.startswith(where):  # every message names plugin and channel
                    message = f"{where}: {message}"
                bus.log("ERROR", f"analysis {plugin_name} on channel {channel_name}: {message}")
                channel_summary.setdefault("errors", []).append(
                    {"plugin": plugin_name, "message": message})
                groups[key] = {"attrs": {"status": "failed", "error": message,
                                         "traceback": traceback.format_exc()},
                               "params": plugin_params}
                failed[plugin_name] = message
                continue
            results[plugin_name] = result
            groups[key] = {"datasets": result.datasets, "units": result.units,
                           "attrs": {"status": "ok", **result.attrs,
                                     **({"analysed_s": tail.analysed_s} if tail.cut else {})},
                           "params": plugin_params}
            merge_summary(channel_summary, result.summary)
        if tail.cut:
            channel_summary["notes"] = [tail.note(), *channel_summary.get("notes", [])]
        summary[channel_name] = channel_summary
    bus.emit(Progress("analysis", 1.0, "analysis done"))
    return groups, summary


def analyse_and_store(path: Path, channels: Mapping[str, ChannelData],
                      analysis: Mapping[str, Any], params: Mapping[str, Mapping[str, Any]],
                      registry: Registry, specimen: Any = None,
                      mass_per_length: float | None = None,
                      bus: EventBus | None = None) -> dict[str, Any]:
    """Run the chain and store it in the run file; returns the ``analyze --json`` object."""
    groups, channel_summaries = run_chain(channels, analysis, params, registry, specimen,
                                          mass_per_length, bus)
    summary = {"run": str(path), "channels": channel_summaries}
    write_analysis(path, groups, summary)
    return summary
