"""Split a record into its free decays, from the signal itself.

An impulse train (or any record with several excitations) holds several free decays, each
started by a forced build-up. Estimates made from pairs or windows of peaks must never span two
of them, and the build-ups are no free vibration. :func:`split_decays` finds the decays from a
sequence of amplitudes in time (per-cycle peak amplitudes, or the maxima of blocks of the
record), with no knowledge of the excitation, so it works as well on imported data:

- the rises are looked for on the geometric mean of consecutive amplitudes, which cancels the
  alternation of positive and negative extrema about an offset (or a slower mode leaking into
  an HVD component);
- a new decay may start when that mean, having fallen by at least ``rise`` (default 2) below
  its peak, rises again more than ``rise`` times above its lowest value since the peak, and
  stays there for ``confirm`` consecutive points (3: a noise spike or the ripple of an HVD
  envelope is no excitation);
- it does start only when that rise is abrupt (:data:`ABRUPT`): an excitation (an impulse)
  lifts the amplitude far faster than the decay after it lets it down, whereas two modes
  beating, or a resonance passed during a sweep, swell about as slowly as they fade. Modes
  far enough apart beat as fast as an impulse rises; a short rise that only regains the
  level the amplitude fell from just before its low is such a beat (:data:`BEAT`), not a
  new decay;
- the previous decay ends at its lowest amplitude before the rise (that point included; the
  last of equally low ones, as where amplitudes below a noise floor count as the floor);
- a decay's peak is its largest amplitude, and its free part runs from the peak plus
  ``settle`` to the end of the decay minus ``guard``. A decay too short for both (its free part
  would hold no point) is left out; its points belong to no decay.

A record with one decay (a step, a ramp derivative) gives one decay whose free part starts at
its largest amplitude plus ``settle`` and runs to the last point.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from fsi_lab.dsp._signal import fail, moving_average
from fsi_lab.dsp.envelope import ABOVE, envelope_floor

#: Factor by which the amplitude must fall below a decay's peak and then rise above its lowest
#: value for a new decay to start: far above the ripple of HVD envelopes (a few %) and the
#: scatter of peaks near the noise floor (10 x the noise RMS: about +-15 %).
RISE_FACTOR = 2.0
#: Consecutive points that must stay above the rise threshold.
CONFIRM = 3

#: A decay's rise is abrupt when the area its amplitude gathers above the preceding low between
#: that low and its peak (the swell) is less than ABRUPT times the area above the same low
#: between its peak and its own low (the fade). An impulse swells in a cycle or so (a few
#: cycles through the HVD filters) and fades over many; two modes beating, or a resonance
#: passed during a sweep, swell about as slowly as they fade (a ratio of about 1 or more).
ABRUPT = 0.5
#: A short rise is two modes beating, not an excitation, when it regains no more than the
#: level the amplitude fell from just before its low: at least BEAT times the new peak within
#: as many points before the low as the rise takes, plus one. A beat's null is a narrow V
#: between two peaks, the earlier one the higher (the modes decay): 1.2 to 1.6 on 17 Hz
#: beside 24.65 or 27 Hz modes, on blocks of half a period, where the rise is as short as an
#: impulse's. An impulse lifts a decay far above where it had slowly fallen to: 0.4 to 0.73
#: in impulse trains 0.25 and 0.18 s apart.
BEAT = 0.9
#: The beat test is for rises this many points long or shorter, those the ABRUPT test takes
#: for impulses (modes 1.3 or more times apart beat within about two blocks); longer ones
#: it judges well, and on them a stretch of noise before a slow rise would pass for a beat.
BEAT_POINTS = 3
#: Most blocks :func:`decay_segments` splits a record into (longer blocks than a period of
#: the dominant frequency on very long records keep the split fast).
MAX_BLOCKS = 4000


@dataclass(frozen=True)
class FreeDecays:
    """The free decays of a record.

    The record is cut into regions, each an excitation's build-up and the decay after it; a
    region whose free part would hold no point is no decay (:func:`split_decays`).

    Attributes
    ----------
    peaks
        Time of each decay's largest amplitude, s.
    starts, ends
        The free part of each decay (``starts < ends``), s: from ``peaks + settle`` to the
        region's last point (its lowest amplitude before the next build-up) minus ``guard``
        (the last region: to the last point).
    bounds
        Time of the last point of each region but the last, s: points after ``bounds[j]``
        belong to region j + 1 (see :meth:`regions`).
    region
        Index of the region of each decay.
    """

    peaks: np.ndarray
    starts: np.ndarray
    ends: np.ndarray
    bounds: np.ndarray
    region: np.ndarray

    @property
    def count(self) -> int:
        """Number of decays."""
        return int(self.peaks.size)

    def regions(self, times: Any) -> np.ndarray:
        """Index of the region (a build-up and its decay) each time (s) belongs to,
        0..bounds.size."""
        return np.searchsorted(self.bounds, np.asarray(times, dtype=np.float64), side="left")

    def labels(self, times: Any) -> np.ndarray:
        """Index of the decay whose free part holds each time (s), -1 outside every free part."""
        t = np.asarray(times, dtype=np.float64)
        if self.count == 0:
            return np.full(t.shape, -1, dtype=np.int64)
        decay_of = np.full(self.bounds.size + 1, -1, dtype=np.int64)
        decay_of[self.region] = np.arange(self.count)
        k = decay_of[self.regions(t)]
        j = np.maximum(k, 0)
        inside = (k >= 0) & (t >= self.starts[j]) & (t <= self.ends[j])
        return np.where(inside, k, -1)


def split_decays(times: Any, amplitude: Any, *, settle: float = 0.0, guard: float = 0.0,
                 later_settle: float | None = None, first_build_up: bool | None = None,
                 rise: float = RISE_FACTOR, confirm: int = CONFIRM,
                 abrupt: float = ABRUPT) -> FreeDecays:
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
    abrupt
        Largest ratio of a rise's swell to its decay's fade (> 0, see :data:`ABRUPT`) for the
        rise to start a new decay.

    Returns
    -------
    FreeDecays
        No decay when ``times`` is empty; decays whose free part holds none of ``times`` are
        left out.
    """
    t, a = _check_split(times, amplitude, rise, confirm, abrupt)
    if t.size == 0:
        empty = np.empty(0)
        return FreeDecays(empty, empty, empty, empty, np.empty(0, dtype=np.int64))
    # mean[i] pairs a[i] and a[i + 1]; at a low m, mean[m] < mean[m - 1] gives
    # a[m + 1] <= a[m - 1]: a[m + 1] is still the decay, its last point.
    mean = np.sqrt(a[:-1]) * np.sqrt(a[1:]) if a.size > 1 else a.copy()   # (no underflow)
    lows = _abrupt_lows(mean, _rise_lows(mean, rise, confirm), abrupt, rise)
    last = [m + 1 for m in lows]
    edges = [0, *(i + 1 for i in last), a.size]
    peaks = [lo + int(np.argmax(a[lo:hi])) for lo, hi in zip(edges[:-1], edges[1:])]
    tp = t[peaks]
    bounds = t[last]
    ends = np.append(bounds - guard, t[-1])
    inside = np.arange(tp.size) > 0
    inside[0] = a[0] * rise < a[peaks[0]] if first_build_up is None else first_build_up
    starts = tp + np.where(inside, settle if later_settle is None else later_settle, settle)
    # A free part holds a point when a time lies in [start, end]; start < end as well.
    holds = (np.searchsorted(t, ends, side="right") > np.searchsorted(t, starts, side="left")) \
        & (starts < ends)
    return FreeDecays(peaks=tp[holds], starts=starts[holds], ends=ends[holds], bounds=bounds,
                      region=np.flatnonzero(holds))


def _check_split(times: Any, amplitude: Any, rise: float, confirm: Any, abrupt: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The times and amplitudes of :func:`split_decays` as float arrays, after its checks."""
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
    if not abrupt > 0.0:
        raise fail(func, f"abrupt = {abrupt!r}; expected a ratio > 0")
    return t, a


def _rise_lows(mean: np.ndarray, rise: float, confirm: int) -> list[int]:
    """Indices of the lows of ``mean`` followed by a confirmed rise (see the module notes)."""
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
        elif v <= av[mn]:
            mn = i
    return lows


def _abrupt_lows(mean: np.ndarray, lows: list[int], abrupt: float, rise: float) -> list[int]:
    """The ``lows`` (indices of ``mean``) whose rise is abrupt: the swell up to the largest
    value before the next low (or the end) is less than ``abrupt`` times the fade after it.

    Swell and fade are the areas above the low of the run of points around that largest value
    that stays above ``rise`` times the low: the rise that started the decay and the fall back
    to that level. A long lull before the rise (noise a little above the low, over many
    points) is no swell, and a fade that lingers on far below the peak no fade.

    The areas are sums over the points, not integrals in time: the sequence has holes where
    points were left out (cycles below the noise floor, at the lows), which an integral would
    count as a slow rise.
    """
    keep = []
    before = 0
    for lo, hi in zip(lows, [*lows[1:], mean.size - 1]):
        seg = mean[lo:hi + 1]
        excess = np.maximum(seg - seg[0], 0.0)
        pk = int(np.argmax(excess))
        if _beat(mean, before, lo, pk):
            continue
        low = np.flatnonzero(seg <= rise * seg[0])
        first = int(low[low < pk].max()) + 1 if np.any(low < pk) else 1
        after = low[low > pk]
        last = int(after.min()) if after.size else seg.size
        if float(np.sum(excess[first:pk])) < abrupt * float(np.sum(excess[pk + 1:last])):
            keep.append(lo)
            before = lo
    return keep


def _beat(mean: np.ndarray, before: int, lo: int, pk: int) -> bool:
    """Whether the rise from the low ``mean[lo]`` to its peak ``pk`` points later is two modes
    beating (see :data:`BEAT`): it is short (:data:`BEAT_POINTS`) and regains no more than
    the level the amplitude fell from just before the low (from ``before`` on, the start
    of the last decay)."""
    if not 1 <= pk <= BEAT_POINTS or lo <= before:
        return False
    fell_from = float(np.max(mean[max(before, lo - pk - 1):lo]))
    return fell_from >= BEAT * float(mean[lo + pk])


def decay_runs(labels: Any, size: int, func: str = "decay_runs") -> list[slice]:
    """Slices of the runs of consecutive equal ``labels`` (the decay or region of each of
    ``size`` points, in time order); one slice of every point when ``labels`` is None.

    Raises AnalysisError (naming ``func``) when ``labels`` does not hold ``size`` values.
    """
    if labels is None:
        return [slice(0, size)]
    d = np.asarray(labels)
    if d.shape != (size,):
        raise fail(func, f"decay labels have shape {d.shape}; expected one per point ({size})")
    cuts = np.flatnonzero(d[1:] != d[:-1]) + 1
    edges = np.concatenate(([0], cuts, [size]))
    return [slice(int(lo), int(hi)) for lo, hi in zip(edges[:-1], edges[1:])]


def smooth_per_decay(y: Any, regions: np.ndarray, half_width: int) -> np.ndarray:
    """Centred moving average (:func:`._signal.moving_average`, ``half_width`` points each
    side) within each run of equal ``regions`` (:func:`decay_runs`), so that no average mixes
    two decays."""
    y = np.asarray(y, dtype=np.float64)
    if half_width <= 0 or y.size == 0:
        return y.copy()
    out = np.empty_like(y)
    for run in decay_runs(regions, y.size, "smooth_per_decay"):
        out[run] = moving_average(y[run], half_width)
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

    The decays are split (:func:`split_decays`, so only abrupt rises start a decay) on the
    maxima of |x| over blocks of ``block`` s (about a period of the oscillation), leaving out
    the blocks below ``floor`` (unit of x: the noise before the excitation is no decay).
    """
    tb, ib, mb = block_maxima(x, fs, block)
    keep = mb >= floor
    decays = split_decays(tb[keep], mb[keep]) if keep.sum() >= 2 else None
    if decays is None or decays.count == 0:
        return int(np.argmax(np.abs(np.asarray(x, dtype=np.float64))))
    return int(ib[keep][int(np.searchsorted(tb[keep], decays.peaks[0]))])


def decay_segments(x: Any, fs: float, period: float, floor: float = 0.0,
                   confirm: int = CONFIRM) -> list[tuple[int, int]]:
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
        Block length, s: about one period of the record's dominant oscillation (half of one
        is enough: ``|x|`` peaks every half period).
    floor
        Noise level, unit of x: block maxima below it count as ``floor``, so that a new decay
        must rise :data:`RISE_FACTOR` times above the noise, not above a lull of the noise.
    confirm
        Consecutive block points that must stay above the rise threshold
        (:func:`split_decays`).

    Returns
    -------
    list of (int, int)
        ``[(0, len(x))]`` - the whole record - when it holds one decay (an amplitude that
        swells about as slowly as it fades, two modes beating, is no new excitation:
        :data:`ABRUPT`).
    """
    x = np.asarray(x, dtype=np.float64)
    n = x.size
    block = max(period, n / fs / MAX_BLOCKS)
    tb, ib, mb = block_maxima(x, fs, block)
    whole = [(0, n)]
    if floor > 0.0:
        # A known noise level: blocks below it count as it, so only a rise out of the noise
        # starts a decay (a lull of the noise does not).
        mb = np.maximum(mb, float(floor))
    else:
        # Blocks at the record's own floor (a quiet tail of noise, or rounding in a
        # simulation: :func:`.envelope.envelope_floor`) start no decay: a decay ends where it
        # reaches them.
        above = mb > ABOVE * envelope_floor(mb)
        tb, ib, mb = tb[above], ib[above], mb[above]
    if tb.size < 4:
        return whole
    decays = split_decays(tb, mb, confirm=confirm)
    if decays.count < 2:
        return whole
    starts = ib[np.searchsorted(tb, decays.peaks)]
    region_ends = np.append(ib[np.searchsorted(tb, decays.bounds)], n)
    stops = region_ends[decays.region]
    return [(int(a), int(b)) for a, b in zip(starts, stops) if b > a]


#: The base is still once its envelope has fallen below this fraction of its last peak.
QUIET_LEVEL = 0.05


def quiet_times(reference: Any, fs: float, *, level: float = QUIET_LEVEL,
                noise: float = 0.0) -> np.ndarray:
    """Times at which an excitation has died away: after each burst of the ``reference``
    record (the base acceleration), the first time its envelope falls below ``level`` times
    the burst's peak (or 3 x ``noise``, its noise RMS, when that is higher).

    A structure on a shaker is not free while the base still rings (a shaker's suspension
    rings for tenths of a second after a pulse): its motion is forced until then, and a
    damping fit that starts earlier mistakes the forcing for damping.

    Parameters
    ----------
    reference
        Samples of the excitation (any unit), 1-D.
    fs
        Sample rate, Hz.
    level
        Fraction of each burst's peak envelope below which the excitation counts as gone.
    noise
        RMS of the reference's noise (its unit).

    Returns
    -------
    numpy.ndarray
        Increasing times, s from the first sample; empty when the reference never calms down.
    """
    from scipy.signal import hilbert

    x = np.asarray(reference, dtype=np.float64)
    x = x - float(np.median(x))
    env = np.abs(hilbert(x))
    top = float(np.max(env)) if env.size else 0.0
    if top <= 0:
        return np.empty(0)
    # Bursts: where the envelope rises above half the record's largest, each burst's peak.
    loud = env >= 0.2 * top
    edges = np.flatnonzero(np.diff(loud.astype(np.int8)))
    starts = list(np.flatnonzero(loud[:1])) + [int(e) + 1 for e in edges if not loud[e]]
    out = []
    for s in starts:
        stop = s
        while stop < env.size and loud[stop]:
            stop += 1
        peak = s + int(np.argmax(env[s:max(stop, s + 1)]))
        threshold = max(level * float(env[peak]), 3.0 * noise)
        below = np.flatnonzero(env[peak:] < threshold)
        if below.size:
            out.append((peak + int(below[0])) / float(fs))
    return np.array(sorted(set(out)))
