"""Long records analysed in segments, in bounded memory (issue 16; docs/streaming-analysis.md).

When a record's used channels (those analysed and the reference) hold more samples than the
analysis's budget (:func:`budget_of`: the profile's ``[analysis] segment_samples``, default
:data:`fsi_lab.segments.SEGMENT_SAMPLES`) even after its quiet tail is cut, ``fsi-lab analyze``
and the runner's analysis (:func:`fsi_lab.store.analyse_and_store`) take it in segments:

- the record is cut between its free decays (:func:`fsi_lab.segments.plan_segments`, from the
  channels' decimated envelopes read a chunk at a time), or at fixed lengths when it has no
  quiet stretch (random excitation), each segment within the budget;
- each segment is analysed by the profile's chain (:func:`fsi_lab.chain.run_chain`) as a
  record of its own, its channels read from the run file when the chain first uses them;
- its results are written into the rewrite of the run file as they come
  (:func:`fsi_lab.runfile.rewrite_analysis`): a dataset whose last axis runs along the samples
  is made once at the record's full length (chunked, NaN where no segment was analysed) and
  filled at the segment's offset; any other dataset (spectra, tables of extrema, curves) and
  the segment's attributes go to a group ``segment_NNNN`` of the analysis's group, their
  times from the segment's start. A per-sample dataset keeps every ``stride``-th sample of
  the record (:func:`stride_of`: the profile's ``[analysis] segment_stride``, or as many as
  leave :data:`STORED_PER_CYCLE` samples per cycle at the top of the highest mode's band, so
  an hour at 204.8 kS/s stores its components in about 2 GB instead of 40); the stride is
  the group's ``sample_stride`` attribute;
- the identification is pooled over the segments: the modes of the segments are grouped by
  frequency (:func:`fsi_lab.aggregate.group_modes`) and the damping law is fitted to the union
  of their free decays (:func:`fsi_lab.aggregate_fit.fit_union`, through the aggregation's
  summary of a group), so the summary gives one C_i and C_f per mode with intervals, how many
  segments and decays went into it, and each segment's own numbers;
- each analysed channel's spectrum over the whole record is Welch's (segments of
  :data:`WELCH_S` s, Hann, half overlapping, read a chunk at a time), stored as the group
  ``<channel>/segments`` with the table of the segments; no whole-record FFT is taken.

Memory is bounded by the budget (the chain's peak on one segment) plus the envelopes and the
summaries: kilobytes per segment.
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from fsi_lab import accuracy as method_accuracy
from fsi_lab.contract import AnalysisContext, ChannelData, Result
from fsi_lab.errors import FsiLabError
from fsi_lab.events import EventBus, Progress
from fsi_lab.registry import Registry
from fsi_lab.segments import SEGMENT_SAMPLES, Segment, SegmentPlan, plan_segments
from fsi_lab.sources import LazyChannelData, WindowSource, samples_of
from fsi_lab.summary import add_warnings, json_safe

#: Length of the Welch segments of a segmented record's spectrum, s.
WELCH_S = 8.0
#: Samples along the record in one HDF5 chunk of a per-sample result.
ROW_CHUNK = 1 << 16
#: Samples per cycle a stored per-sample result keeps at the top of the highest mode's band
#: (the band components hold nothing above it but what the filters let through).
STORED_PER_CYCLE = 40


def budget_of(analysis: Mapping[str, Any]) -> int:
    """The analysis's budget: samples of the used channels together in one segment."""
    value = analysis.get("segment_samples")
    return int(value) if value else SEGMENT_SAMPLES


def stride_of(analysis: Mapping[str, Any], sample_rate: float, ident: Any) -> int:
    """Every how many samples a per-sample result of the channel is stored: the profile's
    ``[analysis] segment_stride`` when given; else the most that keep
    :data:`STORED_PER_CYCLE` samples per cycle at the highest band edge of ``ident``'s modes
    (the channel's identification on its first segment), 1 when it has none.

    Parameters
    ----------
    analysis
        The profile's ``[analysis]`` values.
    sample_rate
        The channel's sample rate, Hz.
    ident
        The channel's :class:`fsi_lab.dsp.identify.Identification` on the first segment, or
        None.

    Returns
    -------
    int
        The stride, samples (at least 1).
    """
    value = analysis.get("segment_stride")
    if value:
        return int(value)
    edges = [float(max(m.band_hz)) for m in getattr(ident, "modes", None) or []
             if getattr(m, "band_hz", None) is not None]
    if not edges:
        return 1
    return max(1, int(sample_rate // (STORED_PER_CYCLE * max(edges))))


def used_channels(channels: Mapping[str, ChannelData], analysis: Mapping[str, Any]
                  ) -> list[str]:
    """The channels the chain uses: those analysed and the reference, as far as present."""
    from fsi_lab.chain import channels_to_analyse

    names = channels_to_analyse(channels, analysis.get("channels", []))
    reference = analysis.get("reference")
    return [n for n in dict.fromkeys(names + ([reference] if reference else []))
            if n in channels]


def segment_plan(channels: Mapping[str, ChannelData], analysis: Mapping[str, Any]
                 ) -> SegmentPlan | None:
    """How the record is cut, or None when its used channels fit the budget (the analysis in
    memory, unchanged). Judged on the record up to its quiet tail's cut
    (:func:`fsi_lab.chain.cut_quiet_tail`)."""
    from fsi_lab.chain import cut_quiet_tail

    budget = budget_of(analysis)
    used = used_channels(channels, analysis)
    if sum(len(samples_of(channels[n])) for n in used) <= budget:
        return None
    cut, _ = cut_quiet_tail(channels, used)
    if sum(len(samples_of(cut[n])) for n in used) <= budget:
        return None
    return plan_segments(((samples_of(cut[n]), cut[n].sample_rate) for n in used), budget)


def _segment_channel(channel: ChannelData, segment: Segment) -> LazyChannelData:
    """``channel`` over ``segment``, read when first used."""
    data = samples_of(channel)
    start, stop = segment.samples(channel.sample_rate, len(data))
    return LazyChannelData(channel.name, WindowSource(data, start, stop), channel.sample_rate,
                           channel.quantity, channel.unit, channel.t0)


class _SegmentBus(EventBus):
    """Passes the chain's events of segment ``index`` of ``count`` on to ``bus``, its progress
    as a share of the whole analysis."""

    def __init__(self, bus: EventBus, index: int, count: int, segment: Segment) -> None:
        super().__init__()
        self.bus, self.index, self.count, self.segment = bus, index, count, segment

    def emit(self, event: Any) -> None:
        if isinstance(event, Progress):
            if event.fraction >= 1.0 and self.index + 1 < self.count:
                return
            event = Progress(event.stage, (self.index + min(1.0, event.fraction)) / self.count,
                             f"segment {self.index + 1} of {self.count} "
                             f"({self.segment.start_s:.4g}-{self.segment.stop_s:.4g} s): "
                             f"{event.message}")
        self.bus.emit(event)


# --------------------------------------------------------------------------- storing
def _per_sample(array: np.ndarray, lengths: set[int]) -> bool:
    return array.ndim >= 1 and array.shape[-1] in lengths and array.shape[-1] > 1


def _store(root: Any, key: str, content: Mapping[str, Any], index: int, offset: int,
           total: int, lengths: set[int], stride: int) -> None:
    """One segment's result ``content`` of ``key`` into ``root`` (``/analysis`` of the
    rewrite): per-sample datasets at ``offset`` of their full-length dataset (``total``
    samples; sample ``j`` of it is the record's sample ``j * stride``), the rest in the group
    ``segment_NNNN``."""
    from fsi_lab.runfile import write_attrs

    group = root.require_group(key)
    own = group.create_group(f"segment_{index:04d}")
    # The first stored sample inside the segment, and where it sits in the segment.
    first = -(-offset // stride)
    skip = first * stride - offset
    for name, value in content.get("datasets", {}).items():
        array = np.asarray(value)
        unit = content.get("units", {}).get(name)
        axis = content.get("axes", {}).get(name)
        if _per_sample(array, lengths):
            dataset = group.get(name)
            rows = array.shape[:-1]
            stored = -(-total // stride)
            if dataset is None:
                dataset = group.create_dataset(
                    name, shape=rows + (stored,), maxshape=(None,) * len(rows) + (stored,),
                    dtype=np.float64 if array.dtype.kind == "f" else np.float32,
                    chunks=(1,) * len(rows) + (min(stored, ROW_CHUNK),), fillvalue=np.nan)
                dataset.attrs["filled"] = ("segment by segment at each segment's offset along "
                                           "the record, every sample_stride-th sample; NaN "
                                           "where no segment was analysed")
                dataset.attrs["sample_stride"] = stride
            elif any(r > d for r, d in zip(rows, dataset.shape[:-1])):
                dataset.resize(tuple(max(r, d) for r, d in zip(rows, dataset.shape[:-1]))
                               + (stored,))
            kept = array[..., skip::stride]
            where = tuple(slice(0, r) for r in rows) + (slice(first, first + kept.shape[-1]),)
            dataset[where] = kept
        else:
            dataset = own.create_dataset(name, data=array)
        if unit is not None:
            dataset.attrs["units"] = unit
        if axis is not None:
            dataset.attrs["axis"] = axis
    write_attrs(own, content.get("attrs", {}))
    if "params" in content and "params" not in group:
        write_attrs(group.create_group("params"), content["params"])


def _welch(root: Any, name: str, channel: ChannelData, plan: SegmentPlan,
           starts: list[int]) -> dict[str, Any]:
    """The channel's Welch spectrum over the whole record (read a chunk at a time) and the
    table of the segments, as ``<channel>/segments``; its summary."""
    from fsi_lab.dsp.spectrum import cross_spectra

    data = samples_of(channel)
    fs = float(channel.sample_rate)
    segment = int(min(len(data), 2 ** round(math.log2(max(16.0, WELCH_S * fs)))))
    spectra = cross_spectra(data, data, fs, segment=segment, step=segment // 2)
    psd = spectra.total()[0]
    group = root.require_group(f"{name}/segments")
    group.create_dataset("start_s", data=np.array([s.start_s for s in plan.segments]))
    group.create_dataset("stop_s", data=np.array([s.stop_s for s in plan.segments]))
    group.create_dataset("start_sample", data=np.array(starts, dtype=np.int64))
    group.create_dataset("welch_frequency", data=spectra.frequency).attrs["units"] = "Hz"
    group.create_dataset("welch_psd", data=psd).attrs["units"] = f"({channel.unit})^2/Hz"
    resolution = fs / segment
    attrs = {"status": "ok", "budget_samples": plan.budget, "budget_s": plan.budget_s,
             "cut": "fixed lengths" if plan.fixed else "quiet stretches between free decays",
             "welch": f"Hann segments of {segment} samples ({segment / fs:.4g} s), half "
                      f"overlapping, {int(spectra.counts.sum())} averaged; resolution "
                      f"{resolution:.4g} Hz",
             "resolution_hz": resolution}
    from fsi_lab.runfile import write_attrs

    write_attrs(group, attrs)
    top = int(np.argmax(psd[1:])) + 1 if psd.size > 1 else 0
    return {"welch_resolution_hz": resolution, "welch_segments": int(spectra.counts.sum()),
            "welch_peak_hz": float(spectra.frequency[top])}


# --------------------------------------------------------------------------- pooling
def _identification(typed: Mapping[str, Result]) -> Any:
    from fsi_lab.aggregate_extract import identification_of

    for result in typed.values():
        ident = identification_of(result)
        if ident is not None:
            return ident
    return None


def _segment_extract(name: str, index: int, segment: Segment, ident: Any, context: Any,
                     analysis_params: Mapping[str, Mapping[str, Any]], registry: Registry,
                     specimen: Any, mass_per_length: float | None) -> Any:
    """What the pooling keeps of one segment's identification (the aggregation's extract of a
    run: each mode's decays' extrema, its own law and curves; kilobytes), made at once so that
    the segment's samples are not kept. Raises FsiLabError when C_i and C_f cannot be given
    (no specimen and no mass per length)."""
    from fsi_lab.aggregate_extract import extract_modes

    label = f"segment {index + 1} ({segment.start_s:.4g}-{segment.stop_s:.4g} s)"
    extract = extract_modes(label, {name: (ident, context)}, analysis_params, specimen,
                            mass_per_length, registry)
    extract.path = str(index)
    return extract


def _pooled(extracts: list[Any]) -> tuple[list[dict], list[str]]:
    """The channel's modes pooled over its segments' extracts: one entry per mode (the
    aggregation's summary of a group of modes, its runs being the segments), and notes."""
    from fsi_lab.aggregate import group_modes, group_summary, plain

    labels = [extract.label for extract in extracts]
    notes = [f"{extract.label}: {e}" for extract in extracts for e in extract.errors]
    modes = []
    for members in group_modes(extracts):
        entry = group_summary(members, labels)
        entry.pop("curves", None)
        entry["segments"] = entry.pop("runs")
        entry["between_segments"] = entry.pop("between_runs")
        per_run = entry.pop("per_run")
        entry["per_segment"] = [{"segment": int(extracts[p].path) + 1,
                                 **{k: v for k, v in r.items() if k != "run"}}
                                for (p, _), r in zip(members, per_run)]
        modes.append(plain(json_safe(entry)))
    return modes, notes


def _merge_curves(channel_group: Any, modes: list[dict], starts_s: list[float]) -> None:
    """Each analysis's curves (a segment's datasets of one row per component: backbones,
    damping curves, extrema) gathered at the top of its group with one row per pooled mode
    (row m is the summary's component m): the rows of the segments' components that went into
    that mode, one after the other, times (unit s) moved onto the record's clock and free-decay
    indices counted on. Per-sample datasets are at the top already; tables that are not curves
    (two columns or fewer, such as bands) stay in the segments' groups."""
    from fsi_lab.runfile import write_attrs

    for group in channel_group.values():
        if not hasattr(group, "keys") or not group.attrs.get("segmented", False):
            continue
        segments = {int(k[len("segment_"):]): group[k] for k in group
                    if k.startswith("segment_")}
        names = sorted({n for g in segments.values() for n, d in g.items()
                        if getattr(d, "ndim", 0) == 2 and d.shape[1] > 2} - set(group))
        for name in names:
            rows, unit = [], None
            for mode in modes:
                parts, decays = [], 0.0
                for member in mode.get("per_segment", []):
                    index, k = member.get("segment", 0) - 1, member.get("component")
                    dataset = segments.get(index, {}).get(name)
                    if dataset is None or k is None or not 0 <= k < dataset.shape[0]:
                        continue
                    unit = dataset.attrs.get("units", unit)
                    row = np.asarray(dataset[k], dtype=np.float64)
                    if dataset.attrs.get("units") == "s":
                        row = row + starts_s[index]
                    elif name == "decay":
                        row = row + decays
                        decays = float(np.nanmax(row)) + 1.0 if np.isfinite(row).any() \
                            else decays
                    parts.append(row)
                rows.append(np.concatenate(parts) if parts else np.empty(0))
            width = max((r.size for r in rows), default=0)
            if not width:
                continue
            table = np.full((len(rows), width), np.nan)
            for m, row in enumerate(rows):
                table[m, :row.size] = row
            dataset = group.create_dataset(name, data=table)
            if unit is not None:
                dataset.attrs["units"] = unit
            write_attrs(dataset, {"merged": "one row per pooled mode (the summary's component "
                                            "index): the rows of the segments' components "
                                            "that went into it, in order; times on the "
                                            "record's clock"})


# --------------------------------------------------------------------------- the analysis
@dataclass
class _Tally:
    """What the segments leave of one analysed channel: the segment table's rows, the extracts
    to pool, the refusals, and why its modes are not pooled (empty when they are)."""

    rows: list[dict[str, Any]] = field(default_factory=list)
    extracts: list[Any] = field(default_factory=list)
    errors: list[dict[str, Any]] = field(default_factory=list)
    unpooled: str = ""

    def add(self, index: int, segment: Segment, info: Mapping[str, Any]) -> None:
        """Segment ``index``'s row of the table, from its chain summary ``info``."""
        row = {"segment": index + 1, "start_s": segment.start_s, "stop_s": segment.stop_s,
               "free_decays": segment.bursts,
               "components": [_component_numbers(c) for c in info.get("components", [])]}
        if info.get("errors"):
            row["errors"] = [e["message"] for e in info["errors"]]
            self.errors.extend({"plugin": e.get("plugin"),
                                "message": f"segment {index + 1} ({segment.start_s:.4g}-"
                                           f"{segment.stop_s:.4g} s): {e['message']}"}
                               for e in info["errors"])
        self.rows.append(row)


def _store_segment(root: Any, groups: Mapping[str, Mapping[str, Any]], index: int,
                   segment: Segment, cut: Mapping[str, ChannelData], strides: dict[str, int],
                   statuses: dict[str, list[str]]) -> None:
    """Write segment ``index``'s results (``groups``, as :func:`fsi_lab.chain.run_chain` gives
    them) into ``root``, each channel's per-sample ones every ``strides[channel]``-th sample;
    note each group's status in ``statuses``."""
    for key, content in groups.items():
        channel = cut[key.partition("/")[0]]
        total = len(samples_of(channel))
        start, stop = segment.samples(channel.sample_rate, total)
        analysed = content.get("attrs", {}).get("analysed_s")
        lengths = {stop - start} | ({int(math.ceil(analysed * channel.sample_rate))}
                                    if analysed else set())
        _store(root, key, content, index, start, total, lengths,
               strides[key.partition("/")[0]])
        statuses.setdefault(key, []).append(content["attrs"].get("status", "ok"))


def _mark_segmented(root: Any, statuses: Mapping[str, list[str]],
                    strides: Mapping[str, int]) -> None:
    """Each analysis group's attributes: how many segments it holds and how."""
    from fsi_lab.runfile import write_attrs

    for key, found in statuses.items():
        ok = found.count("ok")
        write_attrs(root[key], {
            "status": "ok" if ok else "failed", "segmented": True, "segments": len(found),
            "segments_ok": ok, "sample_stride": strides.get(key.partition("/")[0], 1),
            "layout": "per-sample datasets along the whole record, every sample_stride-th "
                      "sample, filled at each segment's offset (NaN where no segment was "
                      "analysed); the rest, and each segment's attributes, in segment_NNNN "
                      "(times from the segment's start: <channel>/segments/start_s)"})


def analyse_in_segments(path: Path, channels: Mapping[str, ChannelData],
                        analysis: Mapping[str, Any],
                        params: Mapping[str, Mapping[str, Any]], registry: Registry,
                        plan: SegmentPlan, specimen: Any = None,
                        mass_per_length: float | None = None,
                        bus: EventBus | None = None,
                        keep_earlier: Callable[[dict[str, Any]], bool] | None = None,
                        warnings: tuple[str, ...] = (),
                        overrides: tuple[str, ...] = ()) -> dict[str, Any]:
    """Analyse the record of run file ``path`` in the segments of ``plan`` and store the
    results in it (module notes); returns the ``analyze --json`` object. When
    ``keep_earlier`` says so of the summary, the rewrite is dropped: the file is left as it
    was, with the analysis it held. ``warnings`` (about the record as a whole) head every
    channel's warnings; ``overrides`` are stored as ``/analysis`` attribute ``overrides``.

    Parameters
    ----------
    path
        The run file (its ``/analysis`` is replaced).
    channels, analysis, params, registry, specimen, mass_per_length, bus
        As :func:`fsi_lab.chain.run_chain`.
    plan
        The segments (:func:`segment_plan`).

    Returns
    -------
    dict
        ``run`` and ``channels``: each analysed channel's summary, with ``segmented`` (the
        segments, the pooled modes, each segment's numbers; docs/json-output.md) and
        ``components`` (the pooled modes).
    """
    from fsi_lab.chain import channels_to_analyse, cut_quiet_tail, run_chain
    from fsi_lab.runfile import rewrite_analysis, utc_now, write_attrs

    bus = bus or EventBus()
    cut, tail = cut_quiet_tail(channels, used_channels(channels, analysis))
    names = channels_to_analyse(channels, analysis.get("channels", []))
    tallies = {n: _Tally() for n in names if n in cut}
    count = len(plan.segments)
    statuses: dict[str, list[str]] = {}
    strides: dict[str, int] = {}
    summary: dict[str, Any] = {"run": str(path), "channels": {}}
    # (raised in the rewrite, _KeepEarlier drops it, and is suppressed here)
    with contextlib.suppress(_KeepEarlier), rewrite_analysis(path) as handle:
        root = handle["analysis"]
        for index, segment in enumerate(plan.segments):
            own = {n: _segment_channel(c, segment) for n, c in cut.items()}
            typed: dict[str, dict[str, Result]] = {}
            groups, seg_summary = run_chain(own, analysis, params, registry, specimen,
                                            mass_per_length,
                                            _SegmentBus(bus, index, count, segment), typed)
            for name in {key.partition("/")[0] for key in groups} - set(strides):
                strides[name] = stride_of(analysis, cut[name].sample_rate,
                                          _identification(typed.get(name, {})))
            _store_segment(root, groups, index, segment, cut, strides, statuses)
            for name, tally in tallies.items():
                tally.add(index, segment, seg_summary.get(name, {}))
                ident = _identification(typed.get(name, {}))
                if ident is None or not getattr(ident, "modes", None) or tally.unpooled:
                    continue
                context = AnalysisContext(channel=own[name], channels=own, results={},
                                          specimen=specimen, mass_per_length=mass_per_length,
                                          reference=analysis.get("reference"))
                try:
                    tally.extracts.append(_segment_extract(
                        name, index, segment, ident, context, params, registry, specimen,
                        mass_per_length))
                except FsiLabError as exc:
                    tally.unpooled = f"the segments' modes are not pooled: {exc}"
            # nothing of this segment's samples is kept into the next one's analysis
            ident = context = None
            del own, groups, typed
        _mark_segmented(root, statuses, strides)
        bus.emit(Progress("analysis", 1.0, "pooling the segments' free decays"))
        for name, tally in tallies.items():
            starts = [s.samples(cut[name].sample_rate, len(samples_of(cut[name])))[0]
                      for s in plan.segments]
            welch = _welch(root, name, cut[name], plan, starts)
            modes, notes = ([], [tally.unpooled]) if tally.unpooled else \
                _pooled(tally.extracts)
            if name in root:
                _merge_curves(root[name], modes, [s.start_s for s in plan.segments])
            info: dict[str, Any] = {
                "components": [_pooled_component(i, m) for i, m in enumerate(modes)],
                "notes": [plan.note(), *([tail.note()] if tail.cut else []), *notes],
                "segmented": {"segments": count, "budget_samples": plan.budget,
                              "budget_s": plan.budget_s,
                              "cut": "fixed" if plan.fixed else "quiet",
                              "free_decays": plan.bursts,
                              "analysed_s": sum(s.stop_s - s.start_s for s in plan.segments),
                              "record_s": plan.record_s, **welch,
                              "modes": modes, "table": tally.rows}}
            if tally.errors:
                info["errors"] = tally.errors
            summary["channels"][name] = json_safe(info)
        for name in names:
            if name not in cut:
                summary["channels"][name] = {"errors": [{
                    "plugin": None, "message": f"channel {name!r} is not in the run; channels "
                                               f"are {', '.join(cut) or 'none'}"}]}
        add_warnings(summary, warnings)
        if keep_earlier is not None and keep_earlier(summary):
            raise _KeepEarlier
        write_attrs(root, {"analyzed_at": utc_now(), "summary": dict(summary),
                           "overrides": list(overrides)})
    bus.emit(Progress("analysis", 1.0, "analysis done"))
    return summary


class _KeepEarlier(Exception):
    """The new analysis is not stored: the run file keeps the one it held."""


def _component_numbers(component: Mapping[str, Any]) -> dict[str, Any]:
    """What the segment table keeps of one of a segment's components: its frequency and any
    C_i and C_f with their intervals, wherever an analysis put them."""
    out: dict[str, Any] = {"index": component.get("index"),
                           "frequency_hz": component.get("frequency_hz")}
    for value in component.values():
        if isinstance(value, dict) and "c_i_ci95" in value:
            out.update({k: value.get(k) for k in ("c_i", "c_i_ci95", "c_f", "c_f_ci95")})
            break
    return out


def _pooled_component(index: int, mode: Mapping[str, Any]) -> dict[str, Any]:
    """A pooled mode as a component of the channel's summary."""
    keys = ("frequency_hz", "frequency_range_hz", "segments", "decays", "extrema", "c_i",
            "c_i_ci95", "c_f", "c_f_ci95", "preferred_law", "fit_error")
    out = {"index": index, **{k: mode[k] for k in keys if k in mode}}
    if mode.get("c_i") is not None and mode.get("c_f") is not None:
        (a, b), (c, d) = mode["c_i_ci95"], mode["c_f_ci95"]
        out["pooled"] = (f"C_i = {mode['c_i']:.4g} kg/(m s) (95 %: {a:.4g} to {b:.4g}), "
                         f"C_f = {mode['c_f']:.4g} kg/m^2 (95 %: {c:.4g} to {d:.4g}) from "
                         f"{mode['decays']} decays in {mode['segments']} segment"
                         f"{'s' * (mode['segments'] != 1)}")
        if mode.get("pooled_by") == "weighted mean":
            out["pooled"] += ("; the segments' own C_i and C_f averaged (their modes were "
                              "fitted together with a close mode to the samples)")
        accuracy = (mode.get("widened") or {}).get("accuracy") or {}
        if any(f is None or f > 1.05 for f in accuracy.values()):
            out["pooled"] += f"; the method's accuracy ({method_accuracy.describe()}) included"
    return out

