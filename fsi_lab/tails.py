"""Quiet tails: the end of a record where every channel the analysis uses rests at its floor.

A lab record often runs on long after its last free decay has died away (the acquisition was
stopped late). That tail holds nothing to analyse but noise - or, in a noise-free simulation,
numbers sinking through the floating-point range - yet it would set the length of every window,
filter and model fit of the analysis, and its silence would reach numerical steps that expect a
signal. The analysis chain therefore analyses a record up to :data:`KEEP_FACTOR` times its active
span when its quiet tail is longer than that (:func:`analysed_end`), and says so.

Each channel's activity is judged on its decimated envelope (:mod:`fsi_lab.dsp.envelope`: the
half range of blocks of :data:`BLOCK_S` s, read a chunk at a time, so that a run file's dataset
need not be loaded; an hour at 204.8 kS/s gives 72 000 numbers): a channel is active up to its
last block above its floor (a tail of noise, or a share of its largest block far below any
acquisition's noise).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterable

from fsi_lab.dsp.envelope import active_blocks, block_envelope

#: Length of the envelope's blocks, s.
BLOCK_S = 0.05
#: A record is analysed up to this many times its active span (the span's end from the record's
#: start) when its quiet tail is longer: the band filters then still follow a decay a factor
#: of their noise gain below the broadband floor, and the noise left in is enough to measure it.
KEEP_FACTOR = 3.0


@dataclass(frozen=True)
class QuietTail:
    """Where a record's analysis stops.

    Attributes
    ----------
    record_s
        Length of the record, s (its longest channel).
    active_s
        End of the last block in which a channel used is above its floor, s from the start.
    analysed_s
        End of what is analysed, s: ``record_s``, or :data:`KEEP_FACTOR` x ``active_s`` when
        the quiet tail is longer.
    """

    record_s: float
    active_s: float
    analysed_s: float

    @property
    def cut(self) -> bool:
        """Whether the record is analysed short of its end."""
        return self.analysed_s < self.record_s

    def note(self) -> str:
        """A sentence for the summary."""
        return (f"the record's last {self.record_s - self.analysed_s:.4g} s are a quiet tail "
                f"(every channel used rests at its noise floor after {self.active_s:.4g} s): "
                f"analysed up to {self.analysed_s:.4g} s of {self.record_s:.4g} s")


def analysed_end(channels: Iterable[tuple[Any, float]]) -> QuietTail:
    """How much of a record to analyse, from the channels the analysis uses.

    Parameters
    ----------
    channels
        ``(samples, sample_rate)`` of each channel used (samples: an array or an
        ``h5py.Dataset``; rate in Hz).

    Returns
    -------
    QuietTail
        ``analysed_s`` is the record's length unless its quiet tail is longer than
        ``KEEP_FACTOR - 1`` times its active span.
    """
    record = active = 0.0
    for data, rate in channels:
        rate = float(rate)
        n = int(len(data))
        record = max(record, n / rate)
        block = max(1, int(round(BLOCK_S * rate)))
        active = max(active, min(n, active_blocks(block_envelope(data, block)) * block) / rate)
    keep = KEEP_FACTOR * active
    return QuietTail(record, active, keep if 0.0 < keep < record else record)
