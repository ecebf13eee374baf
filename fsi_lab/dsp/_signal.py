"""Shared helpers of the analysis functions: input checks, padding, FFT-domain filters.

Every public function of :mod:`fsi_lab.dsp` checks its input with these helpers,
so that a bad record always gives the same clear :class:`fsi_lab.errors.AnalysisError`: the
message names the function, the condition found and what would be accepted.
"""

from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np
import scipy.fft as sfft
import scipy.linalg

from fsi_lab.errors import AnalysisError

#: Worker threads given to scipy.fft (the lab machines have 2 cores; pocketfft uses them for
#: batches of transforms, a single 1-D transform runs on one).
FFT_WORKERS = 2

#: Fewest samples per cycle of a component that the zero-crossing and peak refinement need
#: (the cubic crossing interpolation and the parabolic peak fit are then better than 1e-4).
MIN_SAMPLES_PER_CYCLE = 8


def fail(func: str, message: str) -> AnalysisError:
    """An :class:`AnalysisError` whose message starts with the function name."""
    return AnalysisError(f"{func}: {message}")


def check_rate(fs: Any, func: str) -> float:
    """Return the sample rate as a float, or raise if it is not a finite number > 0 (Hz)."""
    try:
        value = float(fs)
    except (TypeError, ValueError):
        raise fail(func, f"sample rate {fs!r} is not a number; expected a finite rate > 0 Hz") \
            from None
    if not math.isfinite(value) or value <= 0:
        raise fail(func, f"sample rate {value!r} Hz is not usable; expected a finite rate > 0 Hz")
    return value


def as_record(x: Any, func: str, *, min_samples: int = 16, name: str = "signal",
              allow_constant: bool = False, check_clipping: bool = True) -> np.ndarray:
    """Return ``x`` as a contiguous 1-D float64 array after checking it is analysable.

    Checks, in order: one-dimensional, at least ``min_samples`` samples, finite (no NaN or
    inf), not constant, not clipped (see :func:`clipped_fraction`).

    Raises
    ------
    AnalysisError
        Naming ``func``, the condition and what would be accepted.
    """
    try:
        arr = np.ascontiguousarray(x, dtype=np.float64)
    except (TypeError, ValueError):
        raise fail(func, f"{name} cannot be read as numbers; expected a 1-D array of floats") \
            from None
    if arr.ndim != 1:
        raise fail(func, f"{name} has shape {arr.shape}; expected a 1-D array of samples")
    if arr.size < min_samples:
        raise fail(func, f"{name} has {arr.size} samples, too short; need at least "
                         f"{min_samples} samples")
    finite = np.isfinite(arr)
    if not finite.all():
        bad = np.flatnonzero(~finite)
        raise fail(func, f"{name} contains {bad.size} NaN or infinite samples (first at index "
                         f"{bad[0]}); expected finite values - remove or interpolate them")
    lo = float(arr.min())
    hi = float(arr.max())
    if not allow_constant and hi - lo <= 1e-12 * max(abs(lo), abs(hi), 1e-300):
        raise fail(func, f"{name} is constant (every sample is {lo + 0.0:g}); expected an "
                         "oscillating record")
    if check_clipping:
        where = clipping(arr)
        if where is not None:
            raise fail(func, f"{name} looks clipped: {where}; the analysis needs an unclipped "
                             "record - lower the input range or the excitation")
    return arr


def true_runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """First and one-past-last indices of each run of consecutive True in a boolean array."""
    edges = np.flatnonzero(np.diff(np.concatenate(([0], mask.view(np.int8), [0]))))
    return edges[0::2], edges[1::2]


def clipping(x: np.ndarray) -> str | None:
    """Describe flat tops at the record's extreme values, or return None if there are none.

    A record is called clipped when its maximum (or minimum) value is held over 3 or more
    consecutive identical samples at two or more places, or over a single stretch longer than
    ``max(8, len(x) // 1000)`` samples. An analogue signal reaches its extreme once, so equal
    neighbours at the extreme betray a converter or amplifier at the end of its range. A
    record on a converter's grid holds its extreme over the samples the oscillation spends
    within one step of its crest: runs no longer than :func:`_crest_hold` allows (a slow mode
    sampled fast by a coarse converter) are not clipping. Nor are runs in a record's lead-in
    at its extreme (:func:`leading_hold`: a displacement held at its deflection before the
    release, on a coarse grid or printed to a few digits).
    """
    n = x.size
    long_run = max(8, n // 1000)
    step = None
    span = float(x.max() - x.min())
    for label, value in (("maximum", x.max()), ("minimum", x.min())):
        at = x == value
        at[:leading_hold(np.abs(x - value), span)] = False
        if at.sum() < 3:
            continue
        starts, stops = true_runs(at)
        lengths = stops - starts
        long = lengths >= 3
        flat = lengths[long]
        if flat.size >= 2 or (flat.size and flat.max() > long_run):
            step = _grid_step(x) if step is None else step
            if step and all(_crest_hold(x, int(a), int(b), float(value), step)
                            for a, b in zip(starts[long], stops[long])):
                continue
            return flat_message(label, float(value), flat)
    return None


#: A record's lead-in at its extreme stays within this share of its range of it.
HOLD_BAND = 0.1


def leading_hold(distance: np.ndarray, span: float) -> int:
    """Samples a record starts with at one of its extremes: the length of its lead-in whose
    ``distance`` from that extreme (unit of the record) stays within :data:`HOLD_BAND` of the
    record's ``span`` (its range). 0 when the record starts elsewhere; the whole length when
    it never leaves (a caller reading a record in chunks carries on in the next)."""
    away = distance > HOLD_BAND * span
    return int(np.argmax(away)) if away.any() else distance.size


def flat_message(label: str, value: float, flat: np.ndarray) -> str:
    """:func:`clipping`'s description of the runs ``flat`` (their lengths, samples) at the
    record's ``label`` ("maximum" or "minimum") ``value``."""
    return (f"the {label} {value:g} is held flat over {int(flat.sum())} samples in "
            f"{flat.size} place(s)")


def held_on_grid(x: np.ndarray, start: int, stop: int, value: float) -> bool:
    """Whether the run ``[start, stop)`` of samples equal to the extreme ``value`` is a crest
    held by the converter grid ``x`` lies on (:func:`_crest_hold`), not clipping; ``x`` holds
    the run and enough of the record around it to fall 16 grid steps below it on each side.
    False when ``x`` lies on no grid."""
    step = _grid_step(x)
    return bool(step) and _crest_hold(x, start, stop, value, step)


#: :func:`_crest_hold` measures a crest's width where the record falls CREST_DEPTH and 4 times
#: CREST_DEPTH grid steps below it ...
CREST_DEPTH = 4
#: ... and allows a run at the crest this many times as long as the curvature gives (noise
#: shortens runs).
CREST_MARGIN = 1.5


def _grid_step(x: np.ndarray) -> float:
    """The step of the converter grid the samples lie on (unit of x), or 0 when they do not
    lie on one: at least 16 and at most a quarter as many distinct values as samples, every
    gap between them a whole number of the smallest (within 1 %)."""
    values = np.unique(x)
    if not 16 <= values.size <= x.size // 4:
        return 0.0
    gaps = np.diff(values)
    step = float(gaps.min())
    ratio = gaps / step
    return step if float(np.max(np.abs(ratio - np.round(ratio)))) <= 0.01 else 0.0


def _crest_hold(x: np.ndarray, start: int, stop: int, value: float, step: float) -> bool:
    """Whether the run ``[start, stop)`` of samples equal to the extreme ``value`` is no longer
    than a smooth crest on a grid of ``step`` holds it. A crest of curvature k stays within d
    of its top over ``2 sqrt(2 d / k)`` samples: its widths at :data:`CREST_DEPTH` and 4 times
    that many steps below differ by that width at the first depth (a flat top of length L
    adds L to both), and the run at the top may last half that (one step, not CREST_DEPTH),
    times :data:`CREST_MARGIN`. False when the record does not fall that far on both
    sides."""
    widths = []
    for depth in (CREST_DEPTH, 4 * CREST_DEPTH):
        below = np.abs(x - value) >= depth * step
        left = np.flatnonzero(below[:start])
        right = np.flatnonzero(below[stop:])
        if not (left.size and right.size):
            return False
        widths.append((stop + int(right[0])) - int(left[-1]))
    return stop - start <= CREST_MARGIN * 0.5 * (widths[1] - widths[0]) + 2


def check_samples_per_cycle(frequency: float, fs: float, func: str,
                            minimum: float = MIN_SAMPLES_PER_CYCLE,
                            what: str = "component") -> None:
    """Raise if a ``frequency`` (Hz) has fewer than ``minimum`` samples per cycle at ``fs``."""
    if frequency <= 0:
        return
    spc = fs / frequency
    if spc < 0.97 * minimum:                 # 3 % for the frequency estimate
        raise fail(func, f"sample rate {fs:g} Hz is too low for the {what} at {frequency:.4g} Hz "
                         f"({spc:.1f} samples per cycle); need at least {minimum:g} samples per "
                         f"cycle, i.e. a rate >= {minimum * frequency:.4g} Hz")


def mirror_pad(x: np.ndarray, left: int, right: int) -> np.ndarray:
    """Extend ``x`` by even reflection about its end samples (``numpy.pad`` mode ``reflect``)."""
    return np.pad(x, (int(left), int(right)), mode="reflect")


def smooth_step(u: np.ndarray) -> np.ndarray:
    """Infinitely smooth step: 0 for u <= 0, 1 for u >= 1, C-infinity in between.

    Used for filter transition bands: a C-infinity frequency response has an impulse response
    that decays faster than any power of time, so filter transients stay close to the record
    ends.
    """
    u = np.clip(np.asarray(u, dtype=np.float64), 0.0, 1.0)
    out = np.empty_like(u)
    inner = (u > 0) & (u < 1)
    out[u <= 0] = 0.0
    out[u >= 1] = 1.0
    ui = u[inner]
    # 1 / (1 + exp(1/u - 1/(1-u))), written without overflow.
    z = 1.0 / ui - 1.0 / (1.0 - ui)
    out[inner] = 0.5 * (1.0 - np.tanh(0.5 * z))
    return out


def lowpass_gain(freqs: np.ndarray, cutoff: float, transition: float = 0.5) -> np.ndarray:
    """Zero-phase low-pass gain at ``freqs`` (Hz, may be negative).

    Flat (gain exactly 1) up to ``cutoff * (1 - transition)``, zero from
    ``cutoff * (1 + transition)``, C-infinity smooth in between; the gain is 0.5 at ``cutoff``.
    A flat pass band passes slowly varying envelopes (polynomial trends) without bias.
    """
    f = np.abs(freqs)
    lo = cutoff * (1.0 - transition)
    hi = cutoff * (1.0 + transition)
    return 1.0 - smooth_step((f - lo) / (hi - lo))


def highpass_gain(freqs: np.ndarray, corner: float, stop: float = 0.5) -> np.ndarray:
    """Zero-phase high-pass gain: 0 up to ``stop * corner`` (default half the corner), 1 from
    ``corner``, smooth between."""
    f = np.abs(freqs)
    return smooth_step((f - stop * corner) / ((1.0 - stop) * corner))


def moving_average(y: np.ndarray, half_width: int) -> np.ndarray:
    """Centred moving average over ``half_width`` points each side (the paper uses 5).

    Near the ends the window shrinks symmetrically so that every output stays centred on its
    point (a linear trend passes unchanged); the first and last points are left as they are.
    """
    y = np.asarray(y, dtype=np.float64)
    k = int(half_width)
    if k <= 0 or y.size < 3:
        return y.copy()
    n = y.size
    c = np.concatenate(([0.0], np.cumsum(y)))
    idx = np.arange(n)
    h = np.minimum(np.minimum(idx, n - 1 - idx), k)
    return (c[idx + h + 1] - c[idx - h]) / (2 * h + 1)


def rfft(x: np.ndarray, n: int | None = None) -> np.ndarray:
    """scipy.fft.rfft with the project's worker count."""
    return sfft.rfft(x, n=n, workers=FFT_WORKERS)


# ----------------------------------------------------------------------------- AR extension

#: Eigenvalues of the prediction's normal matrix below this share of the largest are rounding
#: (float64 sums of the stretch's products), not directions the data spans.
EIGEN_FLOOR = 1e-13
#: Ridge of the prediction's normal equations when no rank is given, relative to the mean
#: power of the stretch's lagged samples: small, so a clean decay is continued to 1e-9 of
#: itself (at 1e-6 the first samples of a rate reduction moved by 5e-4).
RIDGE = 1e-9


def normal_inverse(design: np.ndarray) -> np.ndarray:
    """``(A^T A)^+`` of a design matrix ``A`` (rows: observations, columns: parameters),
    computed on its columns scaled to unit norm and scaled back: parameters whose sizes span
    many decades (a frequency in rad/s beside a time offset in s on a kHz decay, a cubic
    stiffness beside a damping rate) would otherwise fall under the pseudo-inverse's cut-off
    and come out with no variance at all."""
    norms = np.linalg.norm(design, axis=0)
    norms[norms == 0.0] = 1.0
    unit = design / norms
    return np.linalg.pinv(unit.T @ unit) / np.outer(norms, norms)


def _lstsq_normal(basis: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Least squares by the normal equations (columns of ``basis`` normalised), tiny ridge."""
    gram = basis.conj().T @ basis
    rhs = basis.conj().T @ y
    gram[np.diag_indices_from(gram)] += 1e-12 * np.real(np.trace(gram)) / gram.shape[0]
    return scipy.linalg.solve(gram, rhs, assume_a="her", check_finite=False)


def ar_extend(x: np.ndarray, n_ext: int, order: int, stride: int, fit_length: int,
              max_growth: float = 20.0, rank: int | None = None,
              grow_above: float = 0.0) -> np.ndarray:
    """Continue ``x`` forward by ``n_ext`` samples with a damped-exponential (Prony) model.

    1. Poles: the linear-prediction model ``x[n] = c + sum_j a_j x[n - j * stride]``
       (j = 1..order) is fitted on the last ``fit_length`` samples, by least squares restricted
       to the ``rank`` principal directions of the data (Kumaresan-Tufts; keeps noise out of
       the poles) when ``rank`` is given. A sum of K damped sinusoids about a constant level
       needs ``rank >= 2 K + 1``. Predicting from samples ``stride`` apart keeps the fit well
       conditioned on heavily oversampled records.
    2. Amplitudes: least squares of the modes over the whole fitted stretch (noise in the last
       samples does not seed the continuation); modes with a negligible share are dropped.
    3. Continuation: the modes are continued from the last sample without a phase jump (unlike
       a mirror image). Growing modes (a decay read backwards grows) grow by at most
       ``max_growth`` over ``n_ext`` samples; modes slower than ``grow_above`` (cycles per
       sample: drift, noise) do not grow.

    Returns
    -------
    numpy.ndarray
        The ``n_ext`` predicted samples.
    """
    span = order * stride
    fit_length = int(min(fit_length, x.size))
    if n_ext <= 0:
        return np.zeros(0)
    if fit_length < span + 2 * order + 2:
        return np.full(n_ext, float(x[-1]))
    seg = x[-fit_length:]
    level = float(np.mean(seg))
    rows = np.lib.stride_tricks.sliding_window_view(seg - level, span + 1)[:, ::-1]
    target = rows[:, 0]
    lagged = rows[:, stride::stride]
    if rank is not None and rank < order + 1:
        # Kumaresan-Tufts: least squares restricted to the `rank` principal directions of the
        # data, which keeps measurement noise out of the predictor. Directions the data does
        # not span (eigenvalues at rounding level of the largest: a stretch that holds fewer
        # poles than the rank, or none) carry no information and are left out.
        design = np.concatenate((lagged, np.ones((rows.shape[0], 1))), axis=1)
        gram = design.T @ design
        evals, evecs = np.linalg.eigh(gram)
        kept = min(rank, int(np.sum(evals > EIGEN_FLOOR * evals[-1])))
        top = evecs[:, evals.size - kept:]
        sol = top @ ((top.T @ (design.T @ target)) / evals[evals.size - kept:])
        coef, c = sol[:-1], sol[-1]
    else:
        # Normal equations with a small ridge: fast, and well defined when the order exceeds
        # the number of poles the record needs (the extra poles then stay small). The
        # constant by centring (least squares with an intercept) and the ridge relative to
        # the stretch's own power: a column of ones beside the samples made the ridge depend
        # on the record's unit, and a decay of 1e-4 m/s was read 2 % apart from the same
        # decay in mm/s.
        lag_mean, target_mean = lagged.mean(axis=0), float(target.mean())
        lagged = lagged - lag_mean
        gram = lagged.T @ lagged
        ridge = RIDGE * np.trace(gram) / order + 1e-300
        coef = scipy.linalg.solve(gram + ridge * np.eye(order), lagged.T @ (target - target_mean),
                                  assume_a="pos", check_finite=False)
        c = target_mean - float(coef @ lag_mean) if np.all(np.isfinite(coef)) else math.nan
    if not (np.all(np.isfinite(coef)) and math.isfinite(c)):    # a silent or degenerate stretch:
        return np.full(n_ext, level)                             # hold the level
    denom = 1.0 - coef.sum()
    if abs(denom) > 1e-6:
        level += c / denom                  # the model's own mean level
    poles = np.roots(np.concatenate(([1.0], -coef)))
    poles = poles[poles != 0]               # (a mode gone within one stride: none to continue)
    # Modal continuation (Prony): per-sample exponents of the poles, amplitudes by least
    # squares over the whole fitted stretch (so noise in the last samples does not seed the
    # extension). A decay continued backwards in time grows: let it, up to max_growth over the
    # whole extension, so the envelope has no kink at the record end.
    expo = np.log(poles.astype(np.complex128)) / stride
    expo = expo[np.abs(expo.real) * fit_length < 40.0]     # modes that live over the stretch
    if expo.size == 0:
        return np.full(n_ext, level)
    # Amplitudes from every stride-th sample (about 10 per cycle of the highest mode: as good
    # a fit, stride times cheaper); the last sample is always included.
    nrel = -np.arange(fit_length - 1, -1, -stride, dtype=np.float64)[::-1]
    target = (seg - level)[fit_length - 1 + nrel.astype(np.int64)]
    basis = np.exp(np.outer(nrel, expo))
    norms = np.sqrt(np.sum(np.abs(basis) ** 2, axis=0))
    basis /= norms
    a = _lstsq_normal(basis, target)
    energy = np.abs(a) ** 2
    keep = energy > 1e-8 * energy.sum()
    if not keep.all():
        expo = expo[keep]
        norms = norms[keep]
        a = _lstsq_normal(basis[:, keep], target)
    a = a / norms
    expo_ext = expo.copy()
    # Slow poles (below grow_above, cycles/sample: drift or noise) are not allowed to grow.
    slow = np.abs(expo.imag) < 2.0 * math.pi * grow_above
    expo_ext.real = np.minimum(expo.real, np.where(slow, 0.0, math.log(max_growth) / n_ext))
    nnew = np.arange(1, n_ext + 1, dtype=np.float64)
    ext = np.real(np.exp(np.outer(nnew, expo_ext)) @ a)
    return ext + level


def fft_filtered(x: np.ndarray, fs: float, gain: Callable[[np.ndarray], np.ndarray],
                 pad: int) -> np.ndarray:
    """``x`` filtered in the frequency domain (zero phase) by ``gain(freqs)`` (freqs in Hz,
    0 to fs/2), each end mirror-padded by ``pad`` samples (at most ``len(x) - 1``) so the
    filter's transients stay off the record."""
    pad = max(0, min(int(pad), x.size - 1))
    m = sfft.next_fast_len(x.size + 2 * pad, real=True)
    xp = mirror_pad(x, pad, m - x.size - pad)
    spec = sfft.rfft(xp, workers=FFT_WORKERS)
    spec *= gain(np.arange(spec.size) * (fs / m))
    return sfft.irfft(spec, n=m, workers=FFT_WORKERS)[pad:pad + x.size]


def _band_limited(x: np.ndarray, fs: float, cutoff: float) -> np.ndarray:
    """``x`` low-passed at ``cutoff`` (flat to it, zero from 1.25 cutoff), mirror-padded;
    unchanged if the cut-off is near the Nyquist frequency. Removes broadband noise before a
    prediction model is fitted to the record."""
    if 1.25 * cutoff >= 0.45 * fs or x.size < 16:
        return x
    return fft_filtered(x, fs, lambda f: 1.0 - smooth_step((f - cutoff) / (0.25 * cutoff)),
                        int(8 * fs / cutoff))


#: :func:`bandpass` keeps nothing below BAND_LOW_STOP x its low edge ...
BAND_LOW_STOP = 0.5
#: ... nor above BAND_HIGH_STOP x its high edge.
BAND_HIGH_STOP = 1.5


#: The smear of :func:`bandpass`, in units of 1 / (width of its low transition band): a
#: neighbouring mode's abrupt onset (an impulse), stopped by the filter, leaves a transient in
#: the pass band that falls below 1e-3 of the onset within about this many units (measured:
#: 1.4e-3 of a 10 x larger 14 Hz mode's onset 1 s after it through a [3.4, 7.5] Hz band).
BAND_SMEAR = 1.0


def bandpass_smear(low: float) -> float:
    """Time (s) over which :func:`bandpass` with low edge ``low`` (Hz) smears an abrupt onset:
    BAND_SMEAR / ((1 - BAND_LOW_STOP) low)."""
    return BAND_SMEAR / ((1.0 - BAND_LOW_STOP) * float(low))


def bandpass(x: np.ndarray, fs: float, low: float, high: float) -> np.ndarray:
    """Zero-phase band-pass with a flat pass band, in the frequency domain.

    The gain is exactly 1 from ``low`` to ``high`` (a mode inside keeps its amplitude and
    decay: no bias on the envelope), exactly 0 below ``BAND_LOW_STOP * low`` and above
    ``BAND_HIGH_STOP * high``, and infinitely smooth in between (:func:`smooth_step`: the
    filter's response to an onset dies out within about :func:`bandpass_smear`).

    Parameters
    ----------
    x
        Samples, any unit U (1-D, finite).
    fs
        Sample rate, Hz.
    low, high
        Edges of the pass band, Hz, ``0 < low < high`` (checked by the caller).

    Returns
    -------
    numpy.ndarray
        The filtered record, U, same length (each end mirror-padded by ``8 / low`` s or the
        record's length, whichever is shorter).
    """
    # lowpass_gain(f, c, w) is flat to c (1 - w) and zero from c (1 + w).
    top = 0.5 * (1.0 + BAND_HIGH_STOP) * high
    width = (BAND_HIGH_STOP - 1.0) / (BAND_HIGH_STOP + 1.0)
    return fft_filtered(np.asarray(x, dtype=np.float64), fs,
                        lambda f: highpass_gain(f, low, BAND_LOW_STOP)
                        * lowpass_gain(f, top, width), int(8 * fs / low))


def predict_pad(x: np.ndarray, fs: float, peaks: np.ndarray, left: int, right: int,
                max_growth: float = 20.0, rank: int | None = None, modes: int = 0
                ) -> np.ndarray:
    """Extend ``x`` by ``left`` and ``right`` samples predicted by :func:`ar_extend`.

    ``peaks`` are the record's significant spectral peak frequencies (Hz); with ``modes`` (the
    number of components expected, if more than the peaks) they set the model order (two poles
    per mode plus 8, at most 48), the rank kept (two per mode plus 2), the
    prediction stride (about 10 strides per cycle of the highest peak) and the fitted stretch
    (8 cycles of the lowest peak, at most half the record). Each extension is tapered smoothly to
    zero over its outer half, so the padded record wraps around without a jump.
    """
    f_hi = float(np.max(peaks))
    f_lo = float(np.min(peaks))
    stride = max(1, int(fs / (10.0 * f_hi)))
    modes = max(int(np.size(peaks)), int(modes))
    order = int(min(48, 2 * modes + 8))
    fit = min(x.size // 2, max(4 * order * stride, int(8.0 * fs / f_lo)))
    if rank is None:
        rank = min(order, 2 * modes + 2)
    slow = 0.5 * f_lo / fs
    # The model is fitted to the end stretches low-passed at 3 x the highest peak: broadband
    # noise would bias its poles.
    guard = int(8 * fs / (3.0 * f_hi))
    span = min(x.size, fit + 2 * guard)
    first = _band_limited(x[:span], fs, 3.0 * f_hi)
    last = _band_limited(x[-span:], fs, 3.0 * f_hi)
    head = ar_extend(first[::-1], left, order, stride, fit, max_growth, rank, slow)[::-1]
    tail = ar_extend(last, right, order, stride, fit, max_growth, rank, slow)
    if head.size:
        head *= smooth_step(np.linspace(0.0, 2.0, head.size))
    if tail.size:
        tail *= smooth_step(np.linspace(2.0, 0.0, tail.size))
    return np.concatenate((head, x, tail))
