"""Isolated spikes and dropouts in a record: samples far off what their neighbours say.

A vibrometer loses its signal for an instant (speckle, a particle or a bubble in the water the
beam crosses), a digitiser or a transfer drops a bit: one sample stands far off the oscillation
its neighbours trace. Forty of them, at a third of the record's largest value, read C_i 4 %
low and C_f 6 % high without a word (their energy is broadband: part of it falls into each
mode's band and lifts the extrema the damping laws are fitted to).

Each sample is compared with the cubic through its two neighbours on each side; a spike is a
sample whose difference from that cubic stands :data:`SPIKE_Z` times above the typical
difference around it (medians over :data:`LOCAL_SAMPLES`, robust to the spike itself) and
above that of its neighbours, whose own differences bear its mark (:data:`MARKS`: a step or a
kink, as a release or a kick gives, is no spike). On a band-limited record sampled at 6 or
more samples per cycle the cubic is within 17 % of the oscillation's amplitude (1 % at 13
samples per cycle), so the typical difference holds the noise and that interpolation error
alike. The noise is taken as Gaussian: noise with far heavier tails (Student's t with 3
degrees of freedom) has a few samples in 1e4 flagged. Spikes within 4 samples of each other,
and runs of spiking samples, spoil each other's marks and are not found.

A dropout is a run of samples the instrument held or zeroed while it had no signal: twenty
runs of 3 to 30 zeroed samples in a 17 Hz decay read C_f 7 to 16 % high without a word. It is
found as :data:`DROPOUT_MIN` or more exactly equal samples that the record jumps into or out
of by :data:`DROPOUT_Z` times its typical sample-to-sample change around them (equal samples
of a quantised record, near an extremum, change by one step: none is taken), or as more than
:data:`DROPOUT_MIN` of them inside noise whose samples change by :data:`DROPOUT_FINE`
converter steps (the record's smallest change) or more (a 24-bit converter, floating point:
equal samples are then no chance, however small the signal), and filled by linear prediction
from both sides (:func:`without_dropouts`). A gap of more than a fraction of a period is
beyond prediction: the caller decides which to fill (:func:`fsi_lab.dsp.identify.identify`
fills those up to a period of the record's dominant oscillation).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.ndimage import maximum_filter1d, median_filter

from fsi_lab.dsp._signal import as_record, true_runs

#: A spike's difference from its neighbours' cubic, in units of the local typical difference
#: (robust standard deviation). White noise reaches 8 standard deviations once in 1e15
#: samples.
SPIKE_Z = 8.0
#: Samples over which the typical difference is taken, the larger of the medians over each
#: (a median: a spike and the four neighbours whose cubics it enters do not move it; over
#: the shorter it follows a decay's fall, over the longer a short run of small noise does not
#: lower it).
LOCAL_SAMPLES = (25, 101)
#: Samples at each end of the record that are not judged (the cubic needs two on each side,
#: and a record that starts at a release has a kink at its first sample).
EDGE = 3
#: How far its neighbours' differences may stray from a spike's mark: this share of the
#: spike's difference, and this many typical differences (the noise's).
SIGNATURE_SLACK, SIGNATURE_NOISE = 0.12, 2.0
#: The differences from the neighbours' cubic around (2 samples either side of) a spike, a
#: kink and a step, as shares of the middle one.
MARKS = {"spike": (1 / 6, -2 / 3, 1.0, -2 / 3, 1 / 6), "kink": (0.0, -0.5, 1.0, -0.5, 0.0),
         "step up": (1 / 3, -1.0, 1.0, -1 / 3, 0.0), "step down": (0.0, -1 / 3, 1.0, -1.0, 1 / 3)}
#: Floor of the typical difference, relative to the record's largest value (a record with
#: exact zeros, as a simulation's still start).
FLOOR = 1e-6
#: A dropout: at least DROPOUT_MIN equal samples, entered or left by a jump of DROPOUT_Z
#: times the typical change between samples over DROPOUT_SPAN samples on each side.
DROPOUT_MIN, DROPOUT_Z, DROPOUT_SPAN = 3, 8.0, 50
#: ... or a run longer than DROPOUT_MIN where the typical change is this many converter steps
#: (the smallest change in the record): equal samples are then no chance.
DROPOUT_FINE = 100.0
#: Second differences at least this share of the first (median over the span): noise (white
#: noise has about 1.7), not a smooth signal (a mode sampled at 6 or more samples per cycle has
#: at most 1).
DROPOUT_NOISY = 1.2
#: Linear prediction across a dropout: the largest order, and the samples of context per
#: order (at least) it is fitted to on each side.
PREDICTION_ORDER, CONTEXT_PER_ORDER = 16, 4


def _neighbour_cubic(x: np.ndarray) -> np.ndarray:
    """Each inner sample's value from the cubic through its two neighbours on each side."""
    out = x.copy()
    out[2:-2] = (-x[:-4] + 4.0 * x[1:-3] + 4.0 * x[3:-1] - x[4:]) / 6.0
    return out


def find_spikes(x: Any) -> np.ndarray:
    """Indices of isolated spikes in a record (see the module notes).

    Parameters
    ----------
    x
        Samples in any unit U, 1-D (at least 64), sampled at 6 or more samples per cycle of its
        highest oscillation.

    Returns
    -------
    numpy.ndarray
        Increasing sample indices (int64); empty when the record holds none.

    Raises
    ------
    AnalysisError
        A record that cannot be read (see :func:`._signal.as_record`).

    Examples
    --------
    >>> import numpy as np
    >>> from fsi_lab.dsp.spikes import find_spikes
    >>> t = np.arange(2000) / 1000.0
    >>> x = np.exp(-t) * np.sin(2 * np.pi * 17 * t)
    >>> x += 1e-3 * np.random.default_rng(0).standard_normal(t.size)
    >>> x[[300, 1200]] += [0.4, -0.3]
    >>> find_spikes(x).tolist()
    [300, 1200]
    """
    y = as_record(x, "find_spikes", min_samples=64, check_clipping=False, allow_constant=True)
    # The differences' scale from their steps as well: a record quantised to a step holds
    # stretches of equal samples whose differences are exactly 0.
    steps = np.abs(np.diff(y))
    step = float(np.min(steps[steps > 0])) if np.any(steps > 0) else 0.0
    signed = y - _neighbour_cubic(y)
    diff = np.abs(signed)
    # (the first and last two samples have no cubic: their typical difference is their
    # neighbours')
    typical = np.empty(y.size)
    typical[2:-2] = 1.4826 * np.maximum.reduce([
        median_filter(diff[2:-2], size=size, mode="mirror") for size in LOCAL_SAMPLES])
    typical[:2], typical[-2:] = typical[2], typical[-3]
    typical = np.maximum(typical, max(FLOOR * float(np.max(np.abs(y))), step))
    candidate = (diff > SPIKE_Z * typical) & (diff >= maximum_filter1d(diff, 5))
    candidate[:EDGE] = candidate[-EDGE:] = False
    k = np.flatnonzero(candidate)
    # A spike's own mark: it enters its neighbours' cubics, their differences -2/3 and 1/6 of
    # its own. A kink or a step leaves other marks (MARKS): the differences around each
    # candidate must follow the spike's closely, and better than any other's.
    around = signed[k[:, None] + np.arange(-2, 3)[None, :]]
    misfit = {}
    for name, mark in MARKS.items():
        mark = np.asarray(mark)
        scale = around @ mark / (mark @ mark)
        misfit[name] = np.max(np.abs(around - scale[:, None] * mark[None, :]), axis=1)
    slack = SIGNATURE_SLACK * diff[k] + SIGNATURE_NOISE * typical[k]
    spike = misfit.pop("spike")
    keep = (spike <= slack) & np.all([spike < other for other in misfit.values()], axis=0)
    return k[keep].astype(np.int64)


def without_spikes(x: Any, spikes: np.ndarray) -> np.ndarray:
    """The record with each of ``spikes`` (sample indices, as :func:`find_spikes` gives them)
    replaced by the cubic through its two neighbours on each side.

    Parameters
    ----------
    x
        Samples, unit U, 1-D.
    spikes
        Indices of isolated samples to replace, none within 2 of the ends.

    Returns
    -------
    numpy.ndarray
        A copy of ``x``, U.

    Examples
    --------
    >>> import numpy as np
    >>> from fsi_lab.dsp.spikes import without_spikes
    >>> x = np.sin(np.arange(100) / 5.0)
    >>> y = x.copy()
    >>> y[40] += 3.0
    >>> print(f"{without_spikes(y, np.array([40]))[40] - x[40]:.1e}")
    -2.6e-04
    """
    y = np.array(x, dtype=np.float64)
    if len(spikes):
        y[spikes] = _neighbour_cubic(y)[spikes]
    return y


def find_dropouts(x: Any) -> np.ndarray:
    """Runs of samples an instrument held or zeroed (see the module notes).

    Parameters
    ----------
    x
        Samples in any unit U, 1-D (at least 64).

    Returns
    -------
    numpy.ndarray
        ``(count, 2)`` int64 array of ``[start, stop)`` sample ranges, increasing; runs that
        touch the record's first or last sample (a still lead-in, a record that ends at rest)
        are not dropouts.

    Raises
    ------
    AnalysisError
        A record that cannot be read (see :func:`._signal.as_record`).

    Examples
    --------
    >>> import numpy as np
    >>> from fsi_lab.dsp.spikes import find_dropouts
    >>> t = np.arange(2000) / 1000.0
    >>> x = np.exp(-t) * np.sin(2 * np.pi * 17 * t)
    >>> x[510:525] = 0.0
    >>> find_dropouts(x).tolist()
    [[510, 525]]
    """
    y = as_record(x, "find_dropouts", min_samples=64, check_clipping=False,
                  allow_constant=True)
    starts, stops = true_runs(np.diff(y) == 0.0)
    # (a run of k equal differences is k + 1 equal samples; a run at either end is none)
    stops = stops + 1
    keep = (stops - starts >= DROPOUT_MIN) & (starts > 0) & (stops < y.size)
    starts, stops = starts[keep], stops[keep]
    steps = np.abs(np.diff(y))
    bends = np.abs(np.diff(y, 2))
    floor = FLOOR * float(np.max(np.abs(y)))
    step = float(np.min(steps[steps > 0])) if np.any(steps > 0) else 0.0   # a converter's
    jumps = np.maximum(np.abs(y[starts] - y[starts - 1]), np.abs(y[stops] - y[stops - 1]))
    out = []
    for start, stop, jump in zip(starts, stops, jumps):
        if jump == 0.0:
            continue
        window = np.r_[max(0, start - 1 - DROPOUT_SPAN):start - 1, stop:min(stop + DROPOUT_SPAN,
                                                                              steps.size)]
        around = steps[window]
        moving = around[around > 0]
        if moving.size < 4:
            continue
        typical = max(float(np.median(moving)), floor)
        if jump > DROPOUT_Z * typical:
            out.append((start, stop))
            continue
        # A longer run inside noise whose samples change by a hundred converter steps (the
        # record's smallest change): equal samples there are no chance (about once in 1e7
        # for four), entered or left with the noise's own step. (A smooth signal, as a
        # simulation's exact zeros after a pulse or a record printed to a few digits near an
        # extremum, is no noise: its second differences are far smaller than its first.)
        bend = bends[window[window < bends.size]]
        noisy = float(np.median(bend)) >= DROPOUT_NOISY * typical
        if (noisy and stop - start > DROPOUT_MIN and jump >= 0.25 * typical
                and typical >= DROPOUT_FINE * step):
            out.append((start, stop))
    return np.array(out, dtype=np.int64).reshape(-1, 2)


def _predict(context: np.ndarray, count: int) -> np.ndarray | None:
    """``count`` samples after ``context`` (samples, any unit) by a least-squares
    autoregressive model fitted to it; None when it is too short for one."""
    order = min(PREDICTION_ORDER, context.size // CONTEXT_PER_ORDER)
    if order < 2:
        return None
    rows = np.lib.stride_tricks.sliding_window_view(context, order + 1)
    coef, *_ = np.linalg.lstsq(rows[:, :-1], rows[:, -1], rcond=None)
    out = np.empty(count)
    state = list(context[-order:])
    for k in range(count):
        out[k] = float(np.dot(coef, state[-order:]))
        state.append(out[k])
    return out


def without_dropouts(x: Any, dropouts: np.ndarray) -> np.ndarray:
    """The record with each dropout (``[start, stop)`` ranges, as :func:`find_dropouts` gives
    them) replaced by linear prediction from both sides: an autoregressive model fitted to the
    samples before it predicts forwards, one fitted to those after it backwards, and the two
    are blended across the gap (by a raised cosine); the context on each side stops at the
    neighbouring dropouts, and a side too short for a model leaves the other's prediction
    (a straight line between the gap's ends when neither has one).

    Parameters
    ----------
    x
        Samples, unit U, 1-D.
    dropouts
        ``(count, 2)`` increasing, non-overlapping ``[start, stop)`` ranges inside the record.

    Returns
    -------
    numpy.ndarray
        A copy of ``x``, U.

    Examples
    --------
    >>> import numpy as np
    >>> from fsi_lab.dsp.spikes import without_dropouts
    >>> x = np.sin(2 * np.pi * np.arange(400) / 40.0)
    >>> y = x.copy()
    >>> y[200:212] = 0.0
    >>> bool(np.max(np.abs(without_dropouts(y, np.array([[200, 212]])) - x)) < 1e-9)
    True
    """
    y = np.array(x, dtype=np.float64)
    ranges = np.asarray(dropouts, dtype=np.int64).reshape(-1, 2)
    for k, (start, stop) in enumerate(ranges):
        gap = stop - start
        before = int(ranges[k - 1][1]) if k else 0
        after = int(ranges[k + 1][0]) if k + 1 < len(ranges) else y.size
        reach = CONTEXT_PER_ORDER * PREDICTION_ORDER * 2 + gap
        forward = _predict(y[max(before, start - reach):start], gap)
        backward = _predict(y[stop:min(after, stop + reach)][::-1], gap)
        if forward is None and backward is None:
            y[start:stop] = np.linspace(y[start - 1], y[stop], gap + 2)[1:-1]
            continue
        if forward is None:
            forward = backward[::-1]
        if backward is None:
            backward = forward[::-1]
        weight = 0.5 + 0.5 * np.cos(np.pi * (np.arange(gap) + 1.0) / (gap + 1.0))
        y[start:stop] = weight * forward + (1.0 - weight) * backward[::-1]
    return y
