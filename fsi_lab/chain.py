"""Runs the profile's analysis chain over the channels of a run and collects the results.

Each analysis declares the kinds of typed result it requires, uses and provides
(:class:`fsi_lab.contract.AnalysisPlugin`); :func:`check_chain` holds a chain to them when the
profile is checked, and :func:`run_chain` hands each analysis the typed results of the earlier
ones and the channel's shared record (:class:`fsi_lab.contract.SharedRecord`: its spectrum,
computed once). A failing analysis is recorded (in the run file and the summary) with its
reason; the chain goes on with the other channels, and with the analyses that do not need the
failed one. A record that ends in a long quiet tail is analysed up to a few times its active
span (:mod:`fsi_lab.tails`).
"""

from __future__ import annotations

import math
import traceback
from typing import Any, Mapping, Sequence

from fsi_lab.contract import (
    AnalysisContext,
    AnalysisPlugin,
    AnalysisResult,
    ChannelData,
    Result,
    SharedRecord,
    error_gist,
    failed_provider,
    for_want_of,
)
from fsi_lab.errors import FsiLabError, ParameterError
from fsi_lab.events import EventBus, Progress
from fsi_lab.registry import Registry
from fsi_lab.sources import head_of, samples_of
from fsi_lab.specimen import defaults_note
from fsi_lab.summary import json_safe
from fsi_lab.tails import QuietTail, analysed_end

ANALYSED_QUANTITIES = ("velocity", "displacement")


def default_chain(registry: Registry) -> list[str]:
    """The chain of data that comes without a profile (``fsi-lab import``, then ``analyze``):
    the analyses the plugins put in it (the ``fsi_lab_default_chain`` hook), each after the
    analyses providing what it requires or uses.

    An analysis comes after every analysis of the chain it depends on, at the first place that
    allows (by the longest path of dependencies to it), analyses at the same place in the order
    of their names; one whose required kinds no analysis of the chain provides is left out.

    Parameters
    ----------
    registry
        Loaded plugins.

    Returns
    -------
    list of str
        Analysis names, in the order to run them (:func:`check_chain` accepts it).
    """
    plugins = {name: registry.get("analysis", name) for name in registry.default_chain_names()}
    while True:  # leave out what cannot run, until every requirement is met
        kinds = {p.provides for p in plugins.values() if p.provides} | set(plugins)
        unmet = [name for name, p in plugins.items() if not set(p.requires) <= kinds]
        if not unmet:
            break
        for name in unmet:
            del plugins[name]
    after = {name: {other for other, q in plugins.items() if other != name and (
                 q.provides in p.requires + p.uses or other in p.requires)}
             for name, p in plugins.items()}
    level: dict[str, int] = {}

    def place(name: str, seen: tuple[str, ...] = ()) -> int:
        if name not in level:
            if name in seen:  # a cycle of declarations: cannot be ordered
                raise ParameterError(f"default chain: {' -> '.join(seen + (name,))} depend on "
                                     "each other")
            level[name] = 1 + max((place(n, seen + (name,)) for n in after[name]), default=-1)
        return level[name]

    return sorted(plugins, key=lambda name: (place(name), name))


def check_chain(chain: Sequence[str], registry: Registry, where: str = "analysis.chain") -> None:
    """Check that every analysis of ``chain`` finds what it declares it needs before it.

    Each kind an analysis ``requires`` must be provided by an analysis earlier in the chain
    (or, as the contract read before typed results, name an analysis earlier in the chain); a
    kind it ``uses`` must not be provided only by an analysis after it (it would do without it,
    and the analyses after both would mix the two).

    Parameters
    ----------
    chain
        Names of the analysis plugins, in order (each must be loaded).
    registry
        Loaded plugins.
    where
        Profile key named in the message.

    Raises
    ------
    ParameterError
        Naming the analysis, the kind it misses, and which analysis to add or move.
    """
    plugins = [registry.get("analysis", name) for name in chain]
    installed = [registry.get("analysis", name) for name in registry.names("analysis")]
    for i, plugin in enumerate(plugins):
        before, after = plugins[:i], plugins[i + 1:]
        for kind in plugin.requires:
            if any(p.provides == kind or p.name == kind for p in before):
                continue
            later = [p.name for p in after if p.provides == kind or p.name == kind]
            givers = [p.name for p in installed if p.provides == kind or p.name == kind]
            if later:
                hint = f"{later[0]} provides it after {plugin.name}: move {later[0]} before it"
            elif givers:
                hint = f"add {' or '.join(givers)} before {plugin.name}"
            else:
                hint = "no installed analysis provides it"
            raise ParameterError(f"{where}: {plugin.name} requires the {kind!r} result, which no "
                                 f"analysis before it in the chain provides; {hint} (chain: "
                                 f"{', '.join(chain)})")
        for kind in plugin.uses:
            if any(p.provides == kind for p in before):
                continue
            later = [p.name for p in after if p.provides == kind]
            if later:
                raise ParameterError(
                    f"{where}: {plugin.name} uses the {kind!r} result of {later[0]}, which runs "
                    f"after it; move {later[0]} before {plugin.name} (chain: "
                    f"{', '.join(chain)})")


def stored_result(plugin: AnalysisPlugin, out: Any) -> tuple[AnalysisResult, Result | None]:
    """What the chain keeps of what ``plugin.run`` returned: the stored form and the typed
    result handed to later analyses; TypeError saying what the plugin should return."""
    if isinstance(out, Result):
        if out.kind != plugin.provides:
            declared = f"declares provides={plugin.provides!r}" if plugin.provides else \
                "declares no provides"
            raise TypeError(f"returned a result of kind {out.kind!r} but {declared}; declare "
                            f"provides={out.kind!r}")
        record = out.record()
        if not isinstance(record, AnalysisResult):
            raise TypeError(f"{type(out).__name__}.record() returned {type(record).__name__}, "
                            "expected AnalysisResult")
        return record, out
    if isinstance(out, AnalysisResult):
        if plugin.provides is not None:
            raise TypeError(f"returned an AnalysisResult but declares provides="
                            f"{plugin.provides!r}; return the typed result of that kind (an "
                            "fsi_lab.contract.Result), whose record() is stored")
        return out, None
    raise TypeError(f"returned {type(out).__name__}, expected "
                    + ("a Result" if plugin.provides else "an AnalysisResult"))


def merge_summary(into: dict[str, Any], part: Mapping[str, Any]) -> None:
    """Merge one analysis's summary into a channel summary (``components`` by ``index``;
    NaN and infinities as None, so that the summary is JSON)."""
    for key, value in json_safe(dict(part)).items():
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


def left_out_note(channels: Mapping[str, ChannelData], wanted: list[str],
                  reference: str | None) -> str | None:
    """The note that the record's acceleration channels (other than the reference) are not
    analysed, when the chain picks its channels by quantity (none named); else None."""
    left = [n for n, c in channels.items() if c.quantity == "acceleration" and n != reference]
    if wanted or not left:
        return None
    return (f"{', '.join(left)} (acceleration): not analysed; with no channel named only the "
            "velocity and displacement channels are; an acceleration channel is analysed "
            f"(integrated to velocity) when named, --set analysis.channels={left[0]}, or is "
            f"the base's motion as the reference, --set analysis.reference={left[0]}")


def cut_quiet_tail(channels: Mapping[str, ChannelData], used: list[str]
                   ) -> tuple[dict[str, ChannelData], QuietTail]:
    """The channels up to where the analysis of the record stops (:func:`fsi_lab.tails.
    analysed_end`, judged on the ``used`` channels: those analysed and the reference), and
    that judgement. Channels of one sample rate keep one length. Channels read lazily
    (:class:`~fsi_lab.sources.LazyChannelData`) are judged a chunk at a time and stay unread."""
    tail = analysed_end((samples_of(channels[n]), channels[n].sample_rate) for n in used
                        if n in channels)
    if not tail.cut:
        return dict(channels), tail
    cut = {}
    for name, channel in channels.items():
        keep = min(len(samples_of(channel)), int(math.ceil(tail.analysed_s
                                                           * channel.sample_rate)))
        cut[name] = head_of(channel, keep)
    return cut, tail


def run_chain(channels: Mapping[str, ChannelData], analysis: Mapping[str, Any],
              params: Mapping[str, Mapping[str, Any]], registry: Registry,
              specimen: Any = None, mass_per_length: float | None = None,
              bus: EventBus | None = None,
              keep_typed: dict[str, dict[str, Result]] | None = None
              ) -> tuple[dict[str, dict], dict[str, Any]]:
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
    keep_typed
        When given, receives each analysed channel's typed results (by kind) once its chain
        has run (:mod:`fsi_lab.segmented` pools the segments' identifications from them).

    Returns
    -------
    groups, summary
        ``groups`` maps ``"<channel>/<plugin>"`` to what :func:`fsi_lab.runfile.write_analysis`
        stores; ``summary`` maps channel names to their merged JSON summaries.
    """
    bus = bus or EventBus()
    groups: dict[str, dict] = {}
    summary: dict[str, Any] = {}
    wanted = analysis.get("channels", [])
    names = channels_to_analyse(channels, wanted)
    reference = analysis.get("reference")
    left_out = left_out_note(channels, wanted, reference)
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
        provided: dict[str, Result] = {}
        unavailable: dict[str, str] = {}
        shared = SharedRecord(channels[channel_name])
        for plugin_name in chain:
            bus.emit(Progress("analysis", done / total, f"{channel_name}: {plugin_name}"))
            done += 1
            key = f"{channel_name}/{plugin_name}"
            plugin_params = dict(params.get(plugin_name, {}))
            plugin = None
            try:
                plugin = registry.get("analysis", plugin_name)
                missing = [_missing(kind, unavailable, failed) for kind in plugin.requires
                           if kind not in provided and kind not in results]
                if missing:
                    raise FsiLabError(f"needs {'; '.join(missing)}")
                context = AnalysisContext(
                    channel=channels[channel_name], channels=channels, results=dict(results),
                    specimen=specimen, mass_per_length=mass_per_length,
                    reference=analysis.get("reference"), failed=dict(failed),
                    provided=dict(provided), unavailable=dict(unavailable), shared=shared,
                    plugin=plugin_name, declared=plugin.requires + plugin.uses,
                )
                record, typed = stored_result(plugin, plugin.run(context, plugin_params))
            except Exception as exc:  # noqa: BLE001 - recorded, the chain goes on
                message = str(exc) if isinstance(exc, FsiLabError) else (
                    f"{type(exc).__name__}: {exc}"
                )
                where = f"{plugin_name} on channel {channel_name!r}"
                if not message.startswith(where):  # every message names plugin and channel
                    message = f"{where}: {message}"
                provider = failed_provider(message)
                said = provider in failed and failed_provider(failed[provider]) is None
                bus.log("ERROR", f"analysis {plugin_name} on channel {channel_name}: "
                        + (for_want_of(provider) if said else message))
                channel_summary.setdefault("errors", []).append(
                    {"plugin": plugin_name, "message": message})
                groups[key] = {"attrs": {"status": "failed", "error": message,
                                         "traceback": traceback.format_exc()},
                               "params": plugin_params}
                failed[plugin_name] = message
                if plugin is not None and plugin.provides is not None:
                    provided.pop(plugin.provides, None)
                    unavailable[plugin.provides] = plugin_name
                continue
            results[plugin_name] = record
            if typed is not None:
                provided[typed.kind] = typed
                unavailable.pop(typed.kind, None)
            groups[key] = {"datasets": record.datasets, "units": record.units,
                           "axes": record.axes,
                           "attrs": {"status": "ok", **record.attrs,
                                     **({"analysed_s": tail.analysed_s} if tail.cut else {})},
                           "params": plugin_params}
            merge_summary(channel_summary, record.summary)
        if tail.cut:
            channel_summary["notes"] = [tail.note(), *channel_summary.get("notes", [])]
        if (said := defaults_note(specimen)) is not None:
            channel_summary["notes"] = [said, *channel_summary.get("notes", [])]
        if left_out is not None:
            channel_summary["notes"] = [*channel_summary.get("notes", []), left_out]
        summary[channel_name] = channel_summary
        if keep_typed is not None:
            keep_typed[channel_name] = provided
    bus.emit(Progress("analysis", 1.0, "analysis done"))
    return groups, summary


def _missing(kind: str, unavailable: Mapping[str, str], failed: Mapping[str, str]) -> str:
    """Why a required ``kind`` is not there, in words."""
    provider = unavailable.get(kind) or (kind if kind in failed else None)
    if provider is not None:
        return (f"the {kind!r} result, which {provider} failed to give on this channel "
                f"({error_gist(failed.get(provider, 'failed'))})")
    return f"the {kind!r} result earlier in the chain on this channel, which did not run"
