"""Instantaneous frequency from zero crossings and instantaneous amplitude from extrema.

Londono et al. (2015), the paper's Eq. 3: with ``t_i`` the interpolated zero-crossing times,

    f(t_i) = 1 / (t_{i+1} - t_{i-1})

(one full period centred on ``t_i``), and the instantaneous amplitude is the extremum between
two crossings. Numerical choices:

- the offset is removed first (a DC offset of 1 % of the amplitude biases full-period
  frequencies by up to 2.5 %): by default from the extrema, the median of the binomial means
  (e_k + 4 e_{k+1} + 6 e_{k+2} + 4 e_{k+3} + e_{k+4}) / 16 of successive extrema (exact to
  fourth order in the decrement on a decay, where a plain mean is biased), iterated three
  times;
- crossing times are interpolated with the cubic through the four samples around each sign
  change (exact to about 1e-5 of a period at 8 samples per cycle);
- chatter (several sign changes within a tenth of a half period, from noise near zero) is merged
  into one crossing, the least-squares line through the chatter samples;
- extrema are refined around the largest sample: by a least-squares parabola over +-5 % of the
  local period (at most +-32 samples) from 20 samples per cycle on, below that by the sinusoid
  through the three samples around it at the local frequency (exact for a sinusoid);
- the amplitude paired with ``f(t_i)`` is the geometric mean of the two extrema adjacent to
  ``t_i`` (the two half cycles of the period measured): unbiased on exponential decays;
- an optional centred moving average (the paper: 5 points each side) of frequency and of the
  logarithm of the amplitude.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numba
import numpy as np

from fsi_lab.dsp._signal import MIN_SAMPLES_PER_CYCLE, as_record, check_rate, fail, moving_average
from fsi_lab.dsp.choices import OFFSETS  # "cycles": from successive extrema (see module doc)


@dataclass(frozen=True)
class Instantaneous:
    """Zero-crossing frequency and extremum amplitude of one record.

    Attributes
    ----------
    crossing_times
        Interpolated zero-crossing times, s (from the first sample, t = 0).
    frequency_times
        ``t_i`` at which each frequency is given (interior crossings), s.
    frequency
        ``1 / (t_{i+1} - t_{i-1})``, Hz.
    amplitude
        Instantaneous amplitude at ``frequency_times`` (geometric mean of the two adjacent
        extrema), unit of the record.
    peak_times
        Refined times of the extrema (one between each pair of crossings), s.
    peak_values
        Refined signed extremum values (offset removed), unit of the record.
    peak_frequency
        Frequency interpolated at ``peak_times``, Hz.
    offset
        Offset removed before the analysis, unit of the record.
    """

    crossing_times: np.ndarray
    frequency_times: np.ndarray
    frequency: np.ndarray
    amplitude: np.ndarray
    peak_times: np.ndarray
    peak_values: np.ndarray
    peak_frequency: np.ndarray
    offset: float

    @property
    def peak_amplitudes(self) -> np.ndarray:
        """``|peak_values|``, unit of the record."""
        return np.abs(self.peak_values)


# ----------------------------------------------------------------------------- crossings
def _sign_changes(x: np.ndarray) -> np.ndarray:
    """Indices i with x[i] and x[i+1] on different sides of zero (x[i] == 0 counts as +)."""
    s = x >= 0
    return np.flatnonzero(s[1:] != s[:-1])


def _cubic_root(x: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Fractional crossing position in [0, 1] after sample idx, by the cubic through
    x[idx-1..idx+2] (linear where the neighbours are missing)."""
    n = x.size
    y1 = x[idx]
    y2 = x[idx + 1]
    u = y1 / (y1 - y2)                                      # linear estimate
    inner = (idx >= 1) & (idx + 2 < n)
    if inner.any():
        i = idx[inner]
        y0, a1, a2, y3 = x[i - 1], x[i], x[i + 1], x[i + 2]
        # Lagrange cubic on nodes -1, 0, 1, 2 written as a polynomial in s.
        c0 = a1
        c1 = -y0 / 3.0 - a1 / 2.0 + a2 - y3 / 6.0
        c2 = y0 / 2.0 - a1 + a2 / 2.0
        c3 = -y0 / 6.0 + a1 / 2.0 - a2 / 2.0 + y3 / 6.0
        s = u[inner].copy()
        for _ in range(6):
            f = ((c3 * s + c2) * s + c1) * s + c0
            d = (3.0 * c3 * s + 2.0 * c2) * s + c1
            ok = d != 0
            s = np.where(ok, s - np.where(ok, f / np.where(ok, d, 1.0), 0.0), s)
            s = np.clip(s, 0.0, 1.0)
        u[inner] = s
    return u


def _crossings(x: np.ndarray, merge: float) -> np.ndarray:
    """Crossing positions in samples; sign changes closer than ``merge`` samples are merged."""
    idx = _sign_changes(x)
    if idx.size == 0:
        return np.empty(0)
    pos = idx + _cubic_root(x, idx)
    if idx.size < 2 or merge <= 0:
        return pos
    # Group sign changes whose gaps are below `merge` (chatter around zero).
    gaps = np.diff(idx)
    breaks = np.flatnonzero(gaps > merge)
    starts = np.concatenate(([0], breaks + 1))
    ends = np.concatenate((breaks + 1, [idx.size]))
    out = []
    for a, b in zip(starts, ends):
        if b - a == 1:
            out.append(pos[a])
        elif (b - a) % 2 == 0:
            continue                        # an even number of changes: no net crossing
        else:
            lo, hi = idx[a], idx[b - 1] + 1
            t = np.arange(lo, hi + 1, dtype=np.float64)
            slope, icpt = np.polyfit(t, x[lo:hi + 1], 1)
            root = -icpt / slope if slope != 0 else 0.5 * (lo + hi)
            out.append(float(np.clip(root, lo, hi)))
    return np.asarray(out)


# ----------------------------------------------------------------------------- extrema
@numba.njit(cache=True)
def _segment_argmax(ax: np.ndarray, bounds: np.ndarray) -> np.ndarray:
    out = np.empty(bounds.size - 1, dtype=np.int64)
    for k in range(bounds.size - 1):
        lo = bounds[k]
        hi = max(bounds[k + 1], lo + 1)
        best = lo
        for i in range(lo, hi):
            if ax[i] > ax[best]:
                best = i
        out[k] = best
    return out


def _refine_extrema(x: np.ndarray, idx: np.ndarray, half: np.ndarray, wdt: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Refined extremum position (samples) and value around the largest samples ``idx``.

    ``half`` = 1 (fewer than 20 samples per cycle): the sinusoid through the three samples
    idx-1, idx, idx+1 with the local angular step ``wdt`` (rad/sample), exact for a sinusoid.
    Otherwise a least-squares parabola over idx +- half samples.
    """
    pos = idx.astype(np.float64)
    val = x[idx].astype(np.float64)
    three = np.flatnonzero((half == 1) & (idx >= 1) & (idx + 1 < x.size)
                           & (wdt > 0) & (wdt < 0.5 * np.pi))
    if three.size:
        i = idx[three]
        y0 = x[i]
        sin_part = (x[i - 1] - x[i + 1]) / (2.0 * np.sin(wdt[three]))
        amp = np.hypot(y0, sin_part) * np.sign(y0)
        # sin_part is -sin(w p) for a peak p samples after i (x[i - 1] - x[i + 1] of a cosine
        # centred at p): the peak lies at i + p.
        pos[three] = i - np.arctan2(sin_part * np.sign(y0), np.abs(y0)) / wdt[three]
        val[three] = amp
    for w in np.unique(half[half > 1]):
        sel = np.flatnonzero((half == w) & (idx - w >= 0) & (idx + w < x.size))
        if sel.size == 0:
            continue
        u = np.arange(-w, w + 1, dtype=np.float64)
        win = x[idx[sel, None] + u.astype(np.int64)[None, :]]
        s0 = u.size
        s2 = np.sum(u ** 2)
        s4 = np.sum(u ** 4)
        sy = win.sum(axis=1)
        suy = win @ u
        su2y = win @ (u ** 2)
        c = (s0 * su2y - s2 * sy) / (s0 * s4 - s2 * s2)
        bcoef = suy / s2
        a = (sy - c * s2) / s0
        ok = c != 0
        vert = np.where(ok, -bcoef / (2.0 * np.where(ok, c, 1.0)), 0.0)
        ok &= np.abs(vert) <= max(1.0, 0.5 * w)
        pos[sel[ok]] = idx[sel[ok]] + vert[ok]
        val[sel[ok]] = a[ok] - bcoef[ok] ** 2 / (4.0 * c[ok])
    return pos, val


@dataclass(frozen=True)
class HalfCycles:
    """Zero crossings and the extremum of each half cycle of an oscillation.

    Attributes
    ----------
    crossings
        Interpolated zero-crossing times, s from the first sample.
    times
        Refined time of each extremum, s; one per half cycle, in order, from the first
        complete extremum of the record (one before the first crossing counts when it is a
        true maximum of |x|, not the record's edge).
    values
        Refined signed extremum values, unit of the record.
    """

    crossings: np.ndarray
    times: np.ndarray
    values: np.ndarray


def half_cycles(x: Any, fs: float, frequency: float) -> HalfCycles:
    """Zero crossings and refined extrema of a band-limited oscillation about zero.

    Unlike :func:`instantaneous`, the record's first and last partial half cycles keep their
    extremum when it is a true maximum of ``|x|`` (a free decay recorded from its first
    extremum, or from release, loses no cycle), and no offset is removed (the band signals of
    :func:`fsi_lab.dsp.bands.split` hold none).

    Parameters
    ----------
    x
        Samples, unit U (1-D, finite).
    fs
        Sample rate, Hz.
    frequency
        Approximate frequency of the oscillation, Hz (sets the merge of chatter near zero: sign
        changes closer than 5 % of a period are one crossing).

    Returns
    -------
    HalfCycles

    Examples
    --------
    >>> import numpy as np
    >>> from fsi_lab.dsp.instantaneous import half_cycles
    >>> t = np.arange(1000) / 1000.0
    >>> hc = half_cycles(np.sin(2 * np.pi * 5 * t), 1000.0, 5.0)
    >>> np.round(hc.times[:2], 4).tolist(), np.round(hc.values[:2], 4).tolist()
    ([0.05, 0.15], [1.0, -1.0])
    """
    y = as_record(x, "half_cycles", min_samples=8, check_clipping=False, allow_constant=True)
    fs = check_rate(fs, "half_cycles")
    spc = fs / frequency if frequency > 0 else float(y.size)
    cross = _crossings(y, 0.05 * spc)
    if cross.size == 0:
        return HalfCycles(cross / fs, np.empty(0), np.empty(0))
    bounds = np.concatenate(([0], np.ceil(cross), [y.size])).astype(np.int64)
    bounds = np.clip(bounds, 0, y.size)
    ay = np.abs(y)
    imax = _segment_argmax(ay, bounds)
    keep = np.ones(imax.size, dtype=bool)
    for j in (0, imax.size - 1):                 # the partial half cycles at the edges
        i = imax[j]
        keep[j] = 0 < i < y.size - 1 and ay[i] >= ay[i - 1] and ay[i] >= ay[i + 1] \
            and ay[i] > 0.0
    hp = np.diff(np.concatenate(([cross[0] - 0.5 * spc], cross, [cross[-1] + 0.5 * spc])))
    half = np.clip(np.rint(0.1 * hp).astype(np.int64), 1, 32)
    pos, val = _refine_extrema(y, imax, half, np.pi / np.maximum(hp, 1e-9))
    return HalfCycles(cross / fs, pos[keep] / fs, val[keep])


# ----------------------------------------------------------------------------- offset
def _extrema(y: np.ndarray, merge: float, refine: bool = True
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Crossings (samples), refined extremum positions (samples) and values of ``y``
    (``refine=False``: the largest samples themselves, a quick first estimate)."""
    cross = _crossings(y, merge)
    if cross.size < 2:
        return cross, np.empty(0), np.empty(0)
    bounds = np.concatenate((np.ceil(cross[:-1]), [np.floor(cross[-1]) + 1])).astype(np.int64)
    bounds = np.clip(bounds, 0, y.size)
    imax = _segment_argmax(np.abs(y), bounds)
    if not refine:
        return cross, imax.astype(np.float64), y[imax]
    hp = np.diff(cross)
    # +-5 % of the period, at most +-32 samples (plenty for the noise; keeps it fast).
    half = np.clip(np.rint(0.1 * hp).astype(np.int64), 1, 32)
    ppos, pval = _refine_extrema(y, imax, half, np.pi / np.maximum(hp, 1e-9))
    return cross, ppos, pval


def _remove_offset(x: np.ndarray, mode: Any, merge: float, func: str) -> tuple[np.ndarray, float]:
    """Subtract the offset; ``"cycles"`` uses the extrema (see :func:`instantaneous`)."""
    if isinstance(mode, (int, float)) and not isinstance(mode, bool):
        return x - float(mode), float(mode)
    if mode == "none" or mode is None:
        return x, 0.0
    if mode not in OFFSETS:
        raise fail(func, f"offset = {mode!r}; expected one of {', '.join(OFFSETS)} or a number")
    off = float(np.mean(x))
    if mode == "cycles":
        for it in range(3):
            _, _, pval = _extrema(x - off, merge, refine=it == 2)
            if pval.size < 3:
                break
            # Successive extrema alternate about the offset; the binomial mean of five,
            # (1, 4, 6, 4, 1) / 16, cancels a geometric decay to fourth order in the
            # decrement (three extrema, (1, 2, 1) / 4, when there are fewer than five).
            if pval.size >= 5:
                mids = (pval[:-4] + 4.0 * pval[1:-3] + 6.0 * pval[2:-2] + 4.0 * pval[3:-1]
                        + pval[4:]) / 16.0
            else:
                mids = 0.25 * (pval[:-2] + 2.0 * pval[1:-1] + pval[2:])
            off += float(np.median(mids))
    return x - off, off


def noise_rms(x: np.ndarray, fs: float, f_dom: float) -> float:
    """RMS of white noise in ``x``, from the median amplitude spectrum above 3 f_dom."""
    n = x.size
    w = np.hanning(n)
    spec = np.abs(np.fft.rfft((x - x.mean()) * w))
    k0 = int(np.ceil(3.0 * f_dom * n / fs))
    if k0 >= spec.size - 8:
        return 0.0
    med = float(np.median(spec[k0:]))
    return med / (np.sqrt(np.log(2.0)) * np.sqrt(np.sum(w * w)))


# ----------------------------------------------------------------------------- main
def instantaneous(x: Any, fs: float, *, offset: Any = "cycles", smooth: int = 0,
                  min_amplitude: float | None = None, noise_floor: float | None = None,
                  frequency_hint: float | None = None) -> Instantaneous:
    """Zero-crossing instantaneous frequency and extremum amplitude (paper Eq. 3).

    Parameters
    ----------
    x
        Samples, any unit U (1-D, finite, not constant, not clipped); an oscillation about a
        constant level, e.g. one HVD component or a free decay.
    fs
        Sample rate, Hz.
    offset
        ``"cycles"`` (default: mean over a whole number of cycles, iterated), ``"mean"``,
        ``"none"``, or a number (U) to subtract.
    smooth
        Half-width of a centred moving average of the frequency and of ln(amplitude), points
        (0 = none; the paper uses 5).
    min_amplitude
        Drop the cycles whose amplitude is below this fraction of the largest (0 = keep all).
        None (default): drop those below 10 x the RMS of the record's white noise, estimated
        from the median of its spectrum above 3 x the dominant frequency - the tail of a decay
        that has sunk into noise.
    noise_floor
        Used when ``min_amplitude`` is None: drop the cycles whose amplitude is below this
        absolute value (U) instead of the automatic estimate (for a band-limited component,
        whose own spectrum shows no noise floor, the caller knows the noise better).
    frequency_hint
        Approximate frequency of the oscillation, Hz, when the caller knows it (used for the
        sample-rate check and the chatter merge instead of a spectrum of the record).

    Returns
    -------
    Instantaneous
        Times in s from the first sample, frequencies in Hz, amplitudes in U.

    Raises
    ------
    AnalysisError
        Bad sample rate, NaN/inf, constant, clipped or too short record; fewer than 3 zero
        crossings (no oscillation about the offset); fewer than 8 samples per cycle.
    """
    func = "instantaneous"
    fs = check_rate(fs, func)
    x = as_record(x, func, min_samples=8)
    if isinstance(smooth, bool) or not isinstance(smooth, (int, np.integer)) or smooth < 0:
        raise fail(func, f"smooth = {smooth!r}; expected an integer >= 0 (points each side)")
    if min_amplitude is not None and not (0.0 <= float(min_amplitude) < 1.0):
        raise fail(func, f"min_amplitude = {min_amplitude!r}; expected a fraction in [0, 1)")
    # Dominant frequency (for the rate check and the chatter merge): the largest spectral
    # peak, or the median crossing interval when the spectrum has no peak.
    from fsi_lab.dsp.spectrum import spectral_peaks
    if frequency_hint is not None and frequency_hint > 0:
        peaks_f = np.array([float(frequency_hint)])
    else:
        peaks_f = spectral_peaks(x, fs, window="decay", min_relative=0.05, max_peaks=1,
                                 smoothing=0.05).frequencies
    if peaks_f.size:
        f_dom = float(peaks_f[0])
    else:
        raw = _sign_changes(x - np.mean(x))
        f_dom = fs / (2.0 * float(np.median(np.diff(raw)))) if raw.size > 2 else 0.0
    spc = fs / f_dom if f_dom > 0 else float("inf")
    merge = 0.1 * spc / 2.0 if np.isfinite(spc) else 0.0
    y, off = _remove_offset(x, offset, merge, func)
    cross, ppos, pval = _extrema(y, merge)
    if cross.size < 3:
        raise fail(func, f"found {cross.size} zero crossing(s) after removing an offset of "
                         f"{off:.4g}; need at least 3 (one full cycle about the offset) - is the "
                         "record an oscillation?")
    if spc < 0.97 * MIN_SAMPLES_PER_CYCLE:   # 3 % for the peak estimate
        raise fail(func, f"sample rate {fs:g} Hz is too low for the oscillation at about "
                         f"{f_dom:.4g} Hz ({spc:.1f} samples per cycle); need at least "
                         f"{MIN_SAMPLES_PER_CYCLE} samples per cycle, i.e. a rate >= "
                         f"{MIN_SAMPLES_PER_CYCLE * f_dom:.4g} Hz")
    if min_amplitude is None and noise_floor is not None:
        floor = float(noise_floor)
    elif min_amplitude is None:
        floor = 10.0 * noise_rms(y, fs, f_dom)
    else:
        floor = float(min_amplitude) * float(np.max(np.abs(pval)))

    # Frequency at interior crossings; amplitude = geometric mean of adjacent extrema.
    t_c = cross / fs
    freq = 1.0 / (t_c[2:] - t_c[:-2])
    t_f = t_c[1:-1]
    amp_pk = np.abs(pval)
    amp = np.sqrt(amp_pk[:-1] * amp_pk[1:])

    if floor > 0:
        keep = amp >= floor
        t_f, freq, amp = t_f[keep], freq[keep], amp[keep]
        keep_pk = amp_pk >= floor
        ppos, pval = ppos[keep_pk], pval[keep_pk]
        if freq.size == 0:
            raise fail(func, f"no cycle has an amplitude above {floor:.4g} (the noise floor or "
                             "min_amplitude); the record holds no measurable oscillation")
    if smooth:
        freq = moving_average(freq, smooth)
        amp = np.exp(moving_average(np.log(np.maximum(amp, 1e-300)), smooth))
    t_p = ppos / fs
    f_pk = np.interp(t_p, t_f, freq)
    return Instantaneous(crossing_times=t_c, frequency_times=t_f, frequency=freq, amplitude=amp,
                         peak_times=t_p, peak_values=pval, peak_frequency=f_pk, offset=off)
