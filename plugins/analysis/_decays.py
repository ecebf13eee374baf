"""Split a record into its free decays, from the signal itself.

An impulse train (or any record with several excitations) holds several free decays, each
started by a forced build-up. Estimates made from pairs or windows of peaks must never span two
of them, and the build-ups are no free vibration. :func:`split_decays` finds the decays from a
sequence of amplitudes in time (per-cycle peak amplitudes, or the maxima of blocks of the
record), with no knowledge of the excitation, so it works as well on imported data:

- the rises are looked for on the geometric mean of consecutive amplitudes, which cancels the
  alternation of positive and negative extrema about an offset (or a slower mode leaking into
  an HVD component);
- a new decay starts when that mean, having fallen by at least ``rise`` (default 2) below its
  peak, rises again more than ``rise`` times above its lowest value since the peak, and stays
  there for ``confirm`` consecutive points (3: a noise spike or the ripple of an HVD envelope is
  no excitation); the previous decay ends at that lowest value;
- a decay's peak is its largest amplitude, and its free part runs from the peak plus
  ``settle`` to the end of the decay minus ``guard``.

A record with one decay (a step, a ramp derivative) gives one decay whose free part starts at
its largest amplitude plus ``settle`` and runs to the last point.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from fsi_lab.plugins.analysis._signal import fail, moving_average

#: Factor by which the amplitude must fall below a decay's peak and then rise above its lowest
#: value for a new decay to start: far above the ripple of HVD envelopes (a few %) and the
#: scatter of peaks near the noise floor (10 x the noise RMS: about +-15 %).
RISE_FACTOR = 2.0
#: Consecutive points that must stay above the rise threshold.
CONFIRM = 3


@dataclass(frozen=True)
class FreeDecays:
    """The free decays of a record.

    Attributes
    ----------
    peaks
        Time of each decay's largest amplitude, s.
    starts, ends
        The free part of each decay, s: from ``peaks + settle`` to the decay's lowest
        amplitude before the next build-up minus ``guard`` (the last decay: to the last point).
    bounds
        Time of the lowest amplitude of each decay but the last, s: points after ``bounds[k]``
        belong to the build-up of decay k + 1 (see :meth:`regions`).
    """

    peaks: np.ndarray
    starts: np.ndarray
    ends: np.ndarray
    bounds: np.ndarray

    @property
    def count(self) -> int:
        """Number of decays."""
        return int(self.peaks.size)

    def regions(self, times: Any) -> np.ndarray:
        """Index of the decay (with its build-up) each time (s) belongs to, 0..count-1."""
        return np.searchsorted(self.bounds, np.asarray(times, dtype=np.float64), side="left")

    def labels(self, times: Any) -> np.ndarray:
        """Index of the decay whose free part holds each time (s), -1 outside every free part."""
        t = np.asarray(times, dtype=np.float64)
        out = np.full(t.shape, -1, dtype=np.int64)
        if self.count == 0:
            return out
        k = np.clip(self.regions(t), 0, self.count - 1)
        inside = (t >= self.starts[k]) & (t <= self.ends[k])
        out[inside] = k[inside]
        return out


def split_decays(times: Any, amplitude: Any, *, settle: float = 0.0, guard: float = 0.0,
                 later_settle: float | None = None, first_build_up: bool | None = None,
                 rise: float = RISE_FACTOR, confirm: int = CONFIRM) -> FreeDecays:
    """Find the free decays in a sequence of amplitudes (see the module notes).

    Parameters
    ----------
    times
        Increasing times of the amplitudes, s.
    amplitude
        Amplitudes (> 0), any unit: per-cycle peak amplitudes, or block maxima of a record.
    settle
        Time after a decay's peak before its free part starts, s (HVD: the filters' smear).
    guard
        Time before a decay's lowest amplitude (the next build-up) where its free part ends, s.
    later_settle
        ``settle`` for the decays whose build-up lies inside the record, s (default:
        ``settle``), where filters applied to the whole record smear it: every decay after the
        first, and the first when the record rises to its peak from below 1 / ``rise`` of it.
    first_build_up
        Whether the first decay's build-up is in the record: None (default) to judge from the
        amplitudes as above, False when the record is known to start at the first decay's
        peak (an HVD component, whose early rise is the decomposition's own edge).
    rise
        Fall and rise factor that separates two decays (> 1).
    confirm
        Consecutive points (>= 1) that must stay above the rise threshold.

    Returns
    -------
    FreeDecays
        No decay when ``times`` is empty.
    """
    func = "split_decays"
    t = np.asarray(times, dtype=np.float64)
    a = np.asarray(amplitude, dtype=np.float64)
    if t.ndim != 1 or a.shape != t.shape:
        raise fail(func, f"times {t.shape} and amplitudes {a.shape} must be 1-D arrays of the "
                         "same length")
    if not rise > 1.0:
        raise fail(func, f"rise = {rise!r}; expected a factor > 1")
    if isinstance(confirm, bool) or not isinstance(confirm, (int, np.integer)) or confirm < 1:
        raise fail(func, f"confirm = {confirm!r}; expected an integer >= 1")
    if t.size == 0:
        empty = np.empty(0)
        return FreeDecays(empty, empty, empty, empty)
    # The lows are found on the mean of consecutive amplitudes: mean[i] pairs a[i] and a[i + 1].
    mean = np.sqrt(a[:-1] * a[1:]) if a.size > 1 else a.copy()
    av = mean.tolist()
    n = len(av)
    lows: list[int] = []
    pk = mn = 0
    for i in range(1, n):
        v = av[i]
        level = rise * av[mn]
        if mn > pk and av[pk] >= level and v > level and i + confirm <= n \
                and all(w > level for w in av[i:i + confirm]):
            lows.append(mn)
            pk = mn = i
        elif v > av[pk]:
            pk = mn = i
        elif v < av[mn]:
            mn = i
    edges = [0, *(m + 1 for m in lows), a.size]
    peaks = [lo + int(np.argmax(a[lo:hi])) for lo, hi in zip(edges[:-1], edges[1:])]
    tp = t[peaks]
    bounds = t[lows]
    ends = np.append(bounds - guard, t[-1])
    inside = np.arange(tp.size) > 0
    inside[0] = a[0] * rise < a[peaks[0]] if first_build_up is None else first_build_up
    starts = tp + np.where(inside, settle if later_settle is None else later_settle, settle)
    return FreeDecays(peaks=tp, starts=starts, ends=ends, bounds=bounds)


def smooth_per_decay(y: Any, regions: np.ndarray, half_width: int) -> np.ndarray:
    """Centred moving average (:func:`._signal.moving_average`, ``half_width`` points each
    side) within each decay's region, so that no average mixes two decays."""
    y = np.asarray(y, dtype=np.float64)
    if half_width <= 0 or y.size == 0:
        return y.copy()
    out = np.empty_like(y)
    cuts = np.flatnonzero(np.diff(regions)) + 1
    for lo, hi in zip(np.concatenate(([0], cuts)), np.concatenate((cuts, [y.size]))):
        out[lo:hi] = moving_average(y[lo:hi], half_width)
    return out


def block_maxima(x: Any, fs: float, block: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Largest |x| in consecutive blocks of ``block`` s: an amplitude sequence of a raw record
    for :func:`split_decays`. Returns the time (s) and index of each block's largest sample,
    and its magnitude (unit of x)."""
    ax = np.abs(np.asarray(x, dtype=np.float64))
    width = max(1, int(round(block * fs)))
    count = ax.size // width
    if count == 0:
        i = np.array([int(np.argmax(ax))])
        return i / fs, i, ax[i]
    rows = ax[:count * width].reshape(count, width)
    idx = np.argmax(rows, axis=1) + np.arange(count) * width
    if ax.size > count * width:                       # the incomplete last block
        idx = np.append(idx, count * width + int(np.argmax(ax[count * width:])))
    return idx / fs, idx, ax[idx]


def first_decay_peak(x: Any, fs: float, block: float, floor: float = 0.0) -> int:
    """Index of the largest sample of the record's first free decay: the largest sample of the
    record when it holds one decay, the peak of the first response of an impulse train.

    The decays are split (:func:`split_decays`) on the maxima of |x| over blocks of ``block`` s
    (about a period of the oscillation), leaving out the blocks below ``floor`` (unit of x: the
    noise before the excitation is no decay).
    """
    tb, ib, mb = block_maxima(x, fs, block)
    keep = mb >= floor
    if keep.sum() < 2:
        return int(np.argmax(np.abs(np.asarray(x, dtype=np.float64))))
    decays = split_decays(tb[keep], mb[keep])
    return int(ib[keep][int(np.searchsorted(tb[keep], decays.peaks[0]))])


#: A decay train's rises are abrupt: the amplitude a later decay gathers (above the low that
#: precedes it) between that low and its peak is less than ABRUPT times what it keeps between
#: its peak and its own low (its decay). Two modes beating swell as they fade (a ratio of
#: about 1, more when they decay): no train.
ABRUPT = 0.5
#: Most blocks :func:`decay_segments` splits a record into (longer blocks than a period of
#: the dominant frequency on very long records keep the split fast).
MAX_BLOCKS = 4000


def _abrupt_rises(tb: np.ndarray, mb: np.ndarray, decays: FreeDecays) -> bool:
    """Whether every later decay of ``decays`` rises abruptly (see :data:`ABRUPT`) in the block
    maxima ``mb`` (unit of the record) at times ``tb`` (s)."""
    peaks = np.searchsorted(tb, decays.peaks)
    lows = np.append(np.searchsorted(tb, decays.bounds), tb.size)
    for k in range(1, decays.count):
        lo, pk, hi = int(lows[k - 1]), int(peaks[k]), int(lows[k])
        weight = np.maximum(mb - mb[lo], 0.0)
        swell = float(np.sum(weight[lo + 1:pk]))
        fade = float(np.sum(weight[pk + 1:hi]))
        if not swell < ABRUPT * fade:
            return False
    return True


def decay_segments(x: Any, fs: float, period: float) -> list[tuple[int, int]]:
    """Index ranges ``[start, stop)`` of the free decays of a raw record, for estimates (a
    spectrum) that must not span two excitations.

    The decays are split (:func:`split_decays`) on the maxima of |x| over blocks of about one
    ``period`` (s, of the dominant oscillation; longer on very long records, at most
    :data:`MAX_BLOCKS` blocks). Each range runs from a decay's largest sample to the block of
    its lowest amplitude before the next build-up; the last one to the record's end.

    Parameters
    ----------
    x
        Samples, any unit.
    fs
        Sample rate, Hz.
    period
        Block length, s: about one period of the record's dominant oscillation.

    Returns
    -------
    list of (int, int)
        ``[(0, len(x))]`` - the whole record - when it holds one decay, or when the later
        decays do not rise abruptly (:data:`ABRUPT`: an amplitude that swells as it fades is
        two modes beating, not a new excitation).
    """
    x = np.asarray(x, dtype=np.float64)
    n = x.size
    block = max(period, n / fs / MAX_BLOCKS)
    tb, ib, mb = block_maxima(x, fs, block)
    whole = [(0, n)]
    if tb.size < 4:
        return whole
    mb = np.maximum(mb, 1e-300 * max(float(mb.max()), 1e-300))
    decays = split_decays(tb, mb)
    if decays.count < 2 or not _abrupt_rises(tb, mb, decays):
        return whole
    starts = ib[np.searchsorted(tb, decays.peaks)]
    stops = np.append(ib[np.searchsorted(tb, decays.bounds)], n)
    return [(int(a), int(b)) for a, b in zip(starts, stops) if b > a]
