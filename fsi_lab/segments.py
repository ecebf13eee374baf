"""Where a long record is cut into segments that the analysis chain takes one at a time.

A record whose used channels (those analysed and the reference) hold more samples than the
analysis's budget (:data:`SEGMENT_SAMPLES`, the profile's ``[analysis] segment_samples``) is
analysed in segments (:mod:`fsi_lab.segmented`), each no longer than the budget. The cuts are
found here, from the decimated envelope of every used channel (:func:`fsi_lab.dsp.envelope.
block_envelope`: the half range of blocks of :data:`fsi_lab.tails.BLOCK_S` s, read a chunk at a
time; an hour at 204.8 kS/s gives 72 000 numbers per channel), never from the samples whole:

- a block is *active* when a used channel's envelope is above :data:`~fsi_lab.dsp.envelope.
  ABOVE` times its floor (:func:`noise_floor`: a low quantile of its blocks, the level between
  free decays), else *quiet*; runs of active blocks closer than :data:`MERGE_S` s are one
  *burst* (a free decay and the excitation before it);
- bursts are gathered in order into segments while a segment, from a little quiet before its
  first burst to its last burst's end plus a quiet margin (:data:`TAIL_FACTOR` times its last
  burst's length, at least :data:`MIN_TAIL_S` s, as far as the next burst allows), fits the
  budget; so every cut lies in quiet blocks, between free decays, and no decay is cut;
- a burst longer than the budget is refused (:class:`~fsi_lab.errors.AnalysisError` naming its
  start, its length and the budget);
- a record with no quiet stretch (random excitation for its whole length: its largest block is
  less than :data:`RANGE` times its floor) is cut at fixed lengths of the budget, and the plan
  says so.

Quiet stretches between segments are not analysed (their per-sample results stay NaN).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Iterable

import numpy as np

from fsi_lab.dsp._signal import true_runs
from fsi_lab.dsp.envelope import ABOVE, REL_FLOOR, block_envelope
from fsi_lab.errors import AnalysisError
from fsi_lab.tails import BLOCK_S

#: Default budget of one segment: samples of all used channels together (2 used channels at
#: 204.8 kS/s: 4.9 s). The chain's peak memory grows by about 270 bytes per sample of the used
#: channels on top of about 0.4 GB (``bench/bench_long.py``: 1.48 GB at 3e6); at this size the
#: whole process peaked at 1.27 GB on the bench's 1 min record.
SEGMENT_SAMPLES = 2_000_000
#: Active runs of blocks closer than this (s) are one burst.
MERGE_S = 0.25
#: Quantile of a channel's blocks taken as its noise floor (the level between free decays: a
#: tenth of the record at least must be quiet for it).
FLOOR_QUANTILE = 0.1
#: A record whose every used channel's largest block is less than this many times its floor
#: has no quiet stretch between decays (random excitation): it is cut at fixed lengths.
RANGE = 30.0
#: Quiet kept after a segment's last burst: this many times that burst's length ...
TAIL_FACTOR = 2.0
#: ... and at least this many seconds (the noise the identification measures), and quiet kept
#: before a segment's first burst (s, at most half the gap to the burst before; the record's
#: first segment starts with the record when its first burst is closer to the start).
MIN_TAIL_S = 0.5
LEAD_S = 0.25


@dataclass(frozen=True)
class Segment:
    """One segment of a record: seconds from the record's start.

    Attributes
    ----------
    start_s, stop_s
        Where it starts and stops, s.
    bursts
        Free decays (bursts of activity) in it.
    """

    start_s: float
    stop_s: float
    bursts: int

    def samples(self, rate: float, length: int) -> tuple[int, int]:
        """Its ``[start, stop)`` in samples of a channel of ``rate`` Hz and ``length`` samples."""
        start = min(length, int(round(self.start_s * rate)))
        return start, min(length, max(start, int(round(self.stop_s * rate))))


@dataclass(frozen=True)
class SegmentPlan:
    """How a record is cut (module notes).

    Attributes
    ----------
    segments
        The segments, in order, not overlapping.
    record_s
        Length of the record, s.
    budget
        The budget: samples of all used channels in one segment.
    budget_s
        The budget as a length, s.
    fixed
        True when the record has no quiet stretch and was cut at fixed lengths.
    bursts
        Bursts (free decays) found in the record.
    """

    segments: list[Segment]
    record_s: float
    budget: int
    budget_s: float
    fixed: bool
    bursts: int
    notes: list[str] = field(default_factory=list)

    def note(self) -> str:
        """A sentence for the summary."""
        covered = sum(s.stop_s - s.start_s for s in self.segments)
        if self.fixed:
            return (f"the record ({self.record_s:.4g} s) is longer than the analysis budget "
                    f"({self.budget} samples of the used channels, {self.budget_s:.4g} s) and "
                    "has no quiet stretch between free decays (random excitation?): analysed "
                    f"in {len(self.segments)} segments cut at fixed lengths of "
                    f"{self.budget_s:.4g} s; a decay may be cut at their edges")
        count = len(self.segments)
        return (f"the record ({self.record_s:.4g} s) is longer than the analysis budget "
                f"({self.budget} samples of the used channels, {self.budget_s:.4g} s): "
                f"analysed in {count} segment{'s' * (count != 1)} cut in quiet stretches "
                f"between its {self.bursts} free decay{'s' * (self.bursts != 1)} "
                f"({covered:.4g} s analysed; the quiet between segments is not)")


def noise_floor(envelope: np.ndarray) -> float:
    """The level between free decays of a block envelope: its :data:`FLOOR_QUANTILE` quantile,
    at least :data:`~fsi_lab.dsp.envelope.REL_FLOOR` times its largest block (0: silent)."""
    top = float(np.max(envelope, initial=0.0))
    if not (top > 0.0 and math.isfinite(top)):
        return 0.0
    return max(REL_FLOOR * top, float(np.quantile(envelope, FLOOR_QUANTILE)))


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """``[start, stop)`` of the runs of True in ``mask``."""
    return [(int(a), int(b)) for a, b in zip(*true_runs(mask))]


def plan_segments(channels: Iterable[tuple[Any, float]], budget: int) -> SegmentPlan:
    """Cut a record into segments of at most ``budget`` samples of its used channels.

    Parameters
    ----------
    channels
        ``(samples, sample_rate)`` of each used channel (samples: an array or a source read by
        slices; rate in Hz).
    budget
        Samples of all used channels together in one segment, > 0.

    Returns
    -------
    SegmentPlan

    Raises
    ------
    AnalysisError
        A free decay (burst of activity) longer than the budget, naming its start and length.
    """
    channels = [(data, float(rate)) for data, rate in channels]
    if budget <= 0 or not channels:
        raise AnalysisError(f"segments: a budget of {budget} samples over {len(channels)} "
                            "channel(s); expected a positive budget and a channel")
    record_s = max(len(data) / rate for data, rate in channels)
    budget_s = budget / sum(rate for _, rate in channels)
    active = None
    spread = []
    for data, rate in channels:
        envelope = block_envelope(data, max(1, int(round(BLOCK_S * rate))))
        floor = noise_floor(envelope)
        top = float(np.max(envelope, initial=0.0))
        spread.append(top / floor if floor > 0 else 0.0)
        mask = envelope > ABOVE * floor if floor > 0 else np.zeros(envelope.size, bool)
        size = int(math.ceil(record_s / BLOCK_S))
        mask = np.concatenate((mask, np.zeros(max(0, size - mask.size), bool)))[:size]
        active = mask if active is None else active | mask
    if max(spread) < RANGE or not active.any() or active.all():
        return _fixed(record_s, budget, budget_s)
    merge = int(math.ceil(MERGE_S / BLOCK_S))
    bursts: list[list[int]] = []
    for a, b in _runs(active):
        if bursts and a - bursts[-1][1] <= merge:
            bursts[-1][1] = b
        else:
            bursts.append([a, b])
    spans = [(a * BLOCK_S, min(record_s, b * BLOCK_S)) for a, b in bursts]
    segments: list[Segment] = []
    i = 0
    previous_end = 0.0
    while i < len(spans):
        first = spans[i]
        lead = min(LEAD_S, 0.5 * (first[0] - previous_end)) if segments else LEAD_S
        start = max(previous_end, first[0] - max(0.0, lead))
        if first[1] - start > budget_s:
            raise AnalysisError(
                f"a free decay (a burst of activity on the used channels) from {first[0]:.4g} s "
                f"lasts {first[1] - first[0]:.4g} s, longer than the analysis budget of "
                f"{budget} samples of the used channels ({budget_s:.4g} s): a decay is never "
                "cut; raise analysis.segment_samples (e.g. --set analysis.segment_samples="
                f"{int(math.ceil(1.2 * (first[1] - start) / budget_s * budget))}) if memory "
                "allows")
        j = i
        while j + 1 < len(spans) and _stop(spans, j + 1, record_s) - start <= budget_s:
            j += 1
        stop = min(start + budget_s, _stop(spans, j, record_s))
        segments.append(Segment(start, stop, j - i + 1))
        previous_end = stop
        i = j + 1
    return SegmentPlan(segments, record_s, int(budget), budget_s, False, len(spans))


def _stop(spans: list[tuple[float, float]], j: int, record_s: float) -> float:
    """Where a segment whose last burst is ``spans[j]`` stops: its quiet margin after the
    burst, short of the next burst's lead."""
    a, b = spans[j]
    stop = b + max(MIN_TAIL_S, TAIL_FACTOR * (b - a))
    if j + 1 < len(spans):
        gap = spans[j + 1][0] - b
        stop = min(stop, b + gap - min(LEAD_S, 0.5 * gap))
    return min(stop, record_s)


def _fixed(record_s: float, budget: int, budget_s: float) -> SegmentPlan:
    count = max(1, int(math.ceil(record_s / budget_s - 1e-9)))
    edges = [min(record_s, k * budget_s) for k in range(count + 1)]
    return SegmentPlan([Segment(a, b, 0) for a, b in zip(edges[:-1], edges[1:])], record_s,
                       int(budget), budget_s, True, 0)
