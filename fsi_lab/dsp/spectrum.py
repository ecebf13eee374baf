"""Amplitude spectra with interpolated peak picking (the paper's Figs. 5, 9, 11).

Functions
---------
amplitude_spectrum
    Single-sided amplitude spectrum of a record: a steady sinusoid of amplitude A shows a peak
    of height A (window gain corrected).
find_peaks_interpolated
    Peaks of a spectrum above a relative threshold, with frequencies refined by a parabola
    through the log-amplitudes of the three bins around each peak.
spectral_peaks
    Both in one call.
averaged_spectrum
    RMS average of the amplitude spectra of segments of a record (Welch-style).
free_decay_peaks
    Peaks for automatic choices: those of the whole record for one free decay, of its decays'
    averaged spectrum for several (an impulse train, whose whole spectrum is a comb).
cross_spectra
    Welch auto and cross spectra of two records, averaged within groups of consecutive
    segments (the groups give a jackknife interval to whatever is computed from the spectra).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
import scipy.signal as ssig
from scipy.ndimage import maximum_filter1d

from fsi_lab.dsp._signal import as_record, check_rate, fail, rfft
from fsi_lab.dsp.choices import WINDOWS
from fsi_lab.dsp.decays import decay_segments

#: Fewest samples of a free decay for :func:`free_decay_peaks` to average the decays' spectra.
MIN_SEGMENT = 64


#: Windows and ramps up to this many samples are cached (a run's records share their lengths);
#: longer ones, of long records, are made for each use rather than held for the process.
CACHED_SAMPLES = 1 << 18


def _window(name: str, n: int) -> np.ndarray:
    """Window samples (read-only; cached up to :data:`CACHED_SAMPLES`); ``"decay"`` is flat
    over the first half and a half-Hann over the second, which keeps the early, large part of a
    free decay (and fast-decaying modes) at full weight."""
    return _cached_window(name, n) if n <= CACHED_SAMPLES else _make_window(name, n)


@functools.lru_cache(maxsize=8)
def _cached_window(name: str, n: int) -> np.ndarray:
    return _make_window(name, n)


def _make_window(name: str, n: int) -> np.ndarray:
    if name == "boxcar":
        w = np.ones(n)
    elif name == "decay":
        w = np.ones(n)
        k = n // 2
        w[n - k:] = 0.5 * (1.0 + np.cos(np.pi * np.arange(1, k + 1) / k))
    else:
        w = ssig.get_window(name, n, fftbins=False)
    w.setflags(write=False)
    return w


def _ramp(n: int) -> np.ndarray:
    """Centred ramp i - (n - 1) / 2 (read-only; cached up to :data:`CACHED_SAMPLES`)."""
    return _cached_ramp(n) if n <= CACHED_SAMPLES else _make_ramp(n)


@functools.lru_cache(maxsize=8)
def _cached_ramp(n: int) -> np.ndarray:
    return _make_ramp(n)


def _make_ramp(n: int) -> np.ndarray:
    t = np.arange(n, dtype=np.float64) - 0.5 * (n - 1)
    t.setflags(write=False)
    return t


def _detrend(x: np.ndarray) -> np.ndarray:
    """x minus its least-squares straight line (closed form, no matrix solve)."""
    t = _ramp(x.size)
    slope = float(np.sum(t * x)) / float(np.sum(t * t))     # (no BLAS thread wake-up)
    out = x - x.mean()
    out -= slope * t
    return out


def amplitude_spectrum(x: Any, fs: float, *, window: str = "hann", detrend: bool = True,
                       nfft: int | None = None, _func: str = "amplitude_spectrum"
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Single-sided amplitude spectrum.

    Parameters
    ----------
    x
        Samples, any unit U (1-D, finite, not constant).
    fs
        Sample rate, Hz.
    window
        One of ``"hann"``, ``"blackmanharris"``, ``"flattop"``, ``"boxcar"``, ``"decay"``
        (flat, then a half-Hann over the second half: for free decays).
    detrend
        Remove the least-squares straight line first (offset and drift).
    nfft
        FFT length (zero padding for a finer frequency grid); default ``len(x)``.

    Returns
    -------
    freqs : numpy.ndarray
        Frequencies, Hz, from 0 to fs/2.
    amplitude : numpy.ndarray
        Amplitude, U: a steady sinusoid of amplitude A appears with peak height A.

    Raises
    ------
    AnalysisError
        Bad sample rate, non-finite or constant samples, fewer than 16 samples, unknown window.
    """
    fs = check_rate(fs, _func)
    x = as_record(x, _func, min_samples=16, check_clipping=False)
    if window not in WINDOWS:
        raise fail(_func, f"window {window!r} is unknown; expected one of {', '.join(WINDOWS)}")
    if detrend:
        x = _detrend(x)
    n = x.size
    if nfft is None:
        nfft = n
    if nfft < n:
        raise fail(_func, f"nfft = {nfft} is shorter than the record ({n} samples); expected "
                          f"nfft >= {n}")
    w = _window(window, n)
    spec = np.abs(rfft(x * w, n=nfft))
    spec *= 2.0 / w.sum()
    spec[0] *= 0.5
    if nfft % 2 == 0:
        spec[-1] *= 0.5
    freqs = np.arange(spec.size) * (fs / nfft)
    return freqs, spec


def averaged_spectrum(x: Any, fs: float, segments: Sequence[tuple[int, int]], *,
                      window: str = "decay") -> tuple[np.ndarray, np.ndarray]:
    """RMS average of the amplitude spectra of segments of a record (Welch-style, one segment
    per free decay of an impulse train).

    Each segment is detrended and windowed over its own length (:func:`amplitude_spectrum`)
    and zero-padded to the longest, so all share one frequency grid. The average resolves about
    1 / (segment length): the comb of lines 1 / spacing apart that a periodic train puts on the
    spectrum of the whole record merges into one peak per mode.

    Parameters
    ----------
    x
        Samples, any unit U (1-D, finite).
    fs
        Sample rate, Hz.
    segments
        Index ranges ``[start, stop)`` of ``x``, each at least 16 samples long.
    window
        As in :func:`amplitude_spectrum` (default ``"decay"``: each segment is a free decay).

    Returns
    -------
    freqs : numpy.ndarray
        Hz, from 0 to fs/2, step fs / (longest segment length).
    amplitude : numpy.ndarray
        RMS of the segments' amplitude spectra, U.

    Raises
    ------
    AnalysisError
        No segment, or a segment that :func:`amplitude_spectrum` refuses.
    """
    x = np.asarray(x, dtype=np.float64)
    if len(segments) == 0:
        raise fail("averaged_spectrum", "no segment given; expected at least one index range")
    nfft = max(stop - start for start, stop in segments)
    power = None
    for start, stop in segments:
        freqs, a = amplitude_spectrum(x[start:stop], fs, window=window, nfft=nfft,
                                      _func="averaged_spectrum")
        power = a * a if power is None else power + a * a
    return freqs, np.sqrt(power / len(segments))


def _running_max(a: np.ndarray, width: float) -> np.ndarray:
    """Maximum of ``a`` over bins k (1 +- width) (at least +-1 bin), octave by octave (the
    window of each octave is that of its lower edge)."""
    out = np.empty_like(a)
    out[0] = a[0]
    n = a.size
    k = 1
    while k < n:
        k2 = min(2 * k, n)
        h = max(1, int(width * k))
        lo = max(0, k - h)
        hi = min(n, k2 + h)
        out[k:k2] = maximum_filter1d(a[lo:hi], size=2 * h + 1, mode="nearest")[k - lo:k2 - lo]
        k = k2
    return out


@dataclass(frozen=True)
class SpectralPeaks:
    """Peaks of an amplitude spectrum, by decreasing amplitude.

    Attributes
    ----------
    frequencies
        Interpolated peak frequencies, Hz.
    amplitudes
        Peak heights (interpolated), unit of the spectrum.
    """

    frequencies: np.ndarray
    amplitudes: np.ndarray


def find_peaks_interpolated(freqs: Any, amplitude: Any, *, min_relative: float = 0.01,
                            max_peaks: int | None = None, smoothing: float = 0.0,
                            fmin: float = 0.0, _func: str = "find_peaks_interpolated"
                            ) -> SpectralPeaks:
    """Peaks of a spectrum, refined by parabolic interpolation of the log amplitude.

    Parameters
    ----------
    freqs
        Uniform frequency grid, Hz (as returned by :func:`amplitude_spectrum`).
    amplitude
        Spectrum values (> = 0) on that grid.
    min_relative
        Keep peaks whose prominence is at least this fraction of the largest peak (0..1).
    max_peaks
        Keep at most this many (the largest).
    smoothing
        Relative half-width of a running maximum applied before the search (0.02: each
        frequency f takes the largest value over f +- 2 %); merges the ripples of chirped or
        noisy spectra and side lobes into their peak, keeps peak heights. The reported
        frequency is then refined on the unsmoothed spectrum near the smoothed peak.
    fmin
        Ignore peaks below this frequency, Hz.

    Returns
    -------
    SpectralPeaks
        Sorted by decreasing amplitude; empty arrays if the spectrum has no peak.
    """
    f = np.asarray(freqs, dtype=np.float64)
    a = np.asarray(amplitude, dtype=np.float64)
    if f.shape != a.shape or f.ndim != 1 or f.size < 3:
        raise fail(_func, f"freqs {f.shape} and amplitude {a.shape} must be 1-D arrays of the "
                          "same length >= 3")
    if not (0.0 < min_relative < 1.0):
        raise fail(_func, f"min_relative = {min_relative!r}; expected a fraction in (0, 1)")
    df = f[1] - f[0]
    if smoothing > 0:
        # Running maximum over f (1 +- smoothing), on a geometric grid of ratio
        # 1 + smoothing / 4: ripples and side lobes closer than the smoothing merge into their
        # peak, while peak heights (narrow or broad) are kept.
        start = max(fmin, df)
        ratio = 1.0 + smoothing / 4.0
        count = int(np.log(f[-1] / start) / np.log(ratio)) + 2
        bins = np.unique(np.clip(np.rint(start * ratio ** np.arange(count) / df)
                                 .astype(np.int64), 1, f.size - 1))
        search = _running_max(a, smoothing)[bins]
        grid_f = f[bins]
    else:
        search = a
        bins = np.arange(f.size)
        grid_f = f
    use = grid_f >= fmin
    top = search[use].max() if use.any() else 0.0
    if top <= 0:
        return SpectralPeaks(np.empty(0), np.empty(0))
    idx, _ = ssig.find_peaks(search, prominence=min_relative * top)
    idx = bins[idx[grid_f[idx] >= fmin]]
    out_f = []
    out_a = []
    seen = set()
    for i in idx:
        if smoothing > 0:
            half = max(1, int(np.ceil(smoothing * f[i] / df)))
            lo = max(1, i - half)
            hi = min(a.size - 1, i + half + 1)
            j = lo + int(np.argmax(a[lo:hi]))
        else:
            j = i
        if j in seen:                   # two smoothed peaks refined onto the same bin
            continue
        if smoothing > 0 and not (a[j] >= a[j - 1] and a[j] >= a[min(j + 1, a.size - 1)]):
            continue                    # the running maximum's step on a flank: no peak

        seen.add(j)
        fj, aj = _parabolic(f, a, j)
        out_f.append(fj)
        out_a.append(aj)
    order = np.argsort(out_a)[::-1]
    freqs_out = np.asarray(out_f)[order]
    amps_out = np.asarray(out_a)[order]
    if max_peaks is not None:
        freqs_out = freqs_out[:max_peaks]
        amps_out = amps_out[:max_peaks]
    return SpectralPeaks(freqs_out, amps_out)


def _parabolic(f: np.ndarray, a: np.ndarray, j: int) -> tuple[float, float]:
    """Vertex of the parabola through the log amplitudes at bins j-1, j, j+1."""
    if j <= 0 or j >= a.size - 1:
        return float(f[j]), float(a[j])
    y0, y1, y2 = np.log(np.maximum(a[j - 1:j + 2], 1e-300))
    den = y0 - 2.0 * y1 + y2
    if den >= 0:
        return float(f[j]), float(a[j])
    p = 0.5 * (y0 - y2) / den
    p = min(max(p, -0.5), 0.5)
    df = f[1] - f[0]
    return float(f[j] + p * df), float(np.exp(y1 - 0.25 * (y0 - y2) * p))


def spectral_peaks(x: Any, fs: float, *, window: str = "hann", min_relative: float = 0.01,
                   max_peaks: int | None = None, smoothing: float = 0.0, fmin: float = 0.0,
                   nfft: int | None = None) -> SpectralPeaks:
    """Peaks of the amplitude spectrum of a record (see :func:`amplitude_spectrum` and
    :func:`find_peaks_interpolated` for the parameters). Frequencies in Hz, amplitudes in the
    unit of ``x``: with ``window="flattop"`` the amplitude of a steady sinusoid is exact to
    about 0.1 %; with ``"hann"`` the log-parabola interpolation is within about 3 %."""
    f, a = amplitude_spectrum(x, fs, window=window, nfft=nfft, _func="spectral_peaks")
    peaks = find_peaks_interpolated(f, a, min_relative=min_relative, max_peaks=max_peaks,
                                    smoothing=smoothing, fmin=fmin, _func="spectral_peaks")
    if window == "flattop" and peaks.frequencies.size:
        # The flat-top window's bins are exact amplitudes already; a parabola would overshoot.
        df = f[1] - f[0]
        k = np.clip(np.rint(peaks.frequencies / df).astype(np.int64), 0, a.size - 1)
        peaks = SpectralPeaks(peaks.frequencies, a[k])
    return peaks


def free_decay_peaks(x: Any, fs: float, *, min_relative: float = 0.01,
                     smoothing: float = 0.05,
                     spectrum: tuple[np.ndarray, np.ndarray] | None = None) -> SpectralPeaks:
    """Peaks of the spectrum of a record's free decays, for automatic choices (HVD's
    frequencies and cut-offs, the integration's high-pass).

    A record with several free decays (an impulse train) is not read whole: its spectrum is a
    comb of lines 1 / spacing apart around each mode, which would pass for separate peaks. Its
    peaks are those of the RMS average of its decays' spectra (:func:`averaged_spectrum` over
    :func:`.decays.decay_segments`), which resolves about 1 / spacing, so each mode's comb
    merges into one peak. A record with one decay gets the peaks of its whole spectrum. Both
    use the ``"decay"`` window and ignore peaks below two frequency steps.

    Parameters
    ----------
    x
        Samples, any unit U (1-D, finite, not constant).
    fs
        Sample rate, Hz.
    min_relative, smoothing
        As in :func:`find_peaks_interpolated`.
    spectrum
        The whole record's ``"decay"``-window amplitude spectrum, ``(frequency Hz, amplitude
        U)``, when it is already at hand (a spectrum shared by several analyses); computed
        otherwise.

    Returns
    -------
    SpectralPeaks
        Frequencies (Hz) and amplitudes (U, of the averaged spectrum for several decays), by
        decreasing amplitude; empty when the record shows no peak.
    """
    x = as_record(x, "free_decay_peaks", min_samples=16, check_clipping=False)
    fmin = 2.0 * fs / x.size
    if spectrum is None:
        peaks = spectral_peaks(x, fs, window="decay", min_relative=min_relative,
                               smoothing=smoothing, fmin=fmin)
    else:
        peaks = find_peaks_interpolated(*spectrum, min_relative=min_relative,
                                        smoothing=smoothing, fmin=fmin, _func="free_decay_peaks")
    if peaks.frequencies.size == 0:
        return peaks
    segments = decay_segments(x, fs, 1.0 / float(peaks.frequencies[0]))
    shortest = min(stop - start for start, stop in segments)
    if len(segments) < 2 or shortest < MIN_SEGMENT:
        return peaks
    f, a = averaged_spectrum(x, fs, segments, window="decay")
    merged = find_peaks_interpolated(f, a, min_relative=min_relative, smoothing=smoothing,
                                     fmin=max(fmin, 2.0 * fs / shortest),
                                     _func="free_decay_peaks")
    return merged if merged.frequencies.size else peaks


#: Samples transformed at once by :func:`cross_spectra` (bounds its memory on long records).
_CHUNK_SAMPLES = 1 << 21


@dataclass(frozen=True)
class CrossSpectra:
    """Welch spectra of a reference x and a response y, per group of consecutive segments.

    Attributes
    ----------
    frequency
        Hz, from 0 to fs/2, step fs / segment.
    sxx, syy
        One-sided auto spectral densities, shape (groups, bins), U_x^2/Hz and U_y^2/Hz: the
        mean over each group's segments (as :func:`scipy.signal.welch` over those segments).
    sxy
        One-sided cross spectral density conj(X) Y, shape (groups, bins), U_x U_y/Hz.
    counts
        Segments averaged in each group, shape (groups,).
    segment, step
        Samples per segment and between segment starts.
    window
        Window name (:func:`scipy.signal.get_window`, periodic).
    fs
        Sample rate, Hz.
    """

    frequency: np.ndarray
    sxx: np.ndarray
    syy: np.ndarray
    sxy: np.ndarray
    counts: np.ndarray
    segment: int
    step: int
    window: str
    fs: float

    def total(self, leave_out: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Sxx, Syy, Sxy averaged over every segment, or over all groups but ``leave_out``."""
        weights = self.counts.astype(np.float64)
        if leave_out is not None:
            weights = weights.copy()
            weights[leave_out] = 0.0
        weights = weights / weights.sum()
        return weights @ self.sxx, weights @ self.syy, weights @ self.sxy


def cross_spectra(x: Any, y: Any, fs: float, *, segment: int, step: int, window: str = "hann",
                  groups: int = 1, _func: str = "cross_spectra") -> CrossSpectra:
    """Welch auto and cross spectra of two records, averaged within groups of segments.

    The segments (``segment`` samples, starts ``step`` apart, each detrended by its mean and
    windowed) are split into ``groups`` runs of consecutive segments of near-equal counts; each
    group's spectra are the means over its segments. Averaged over all segments (see
    :meth:`CrossSpectra.total`) they equal :func:`scipy.signal.welch` and
    :func:`scipy.signal.csd` with the same settings; left out one group at a time they give a
    jackknife estimate of the variance of anything computed from them, which accounts for the
    correlation between neighbouring frequency bins that a per-bin formula misses.

    Parameters
    ----------
    x, y
        Reference and response records of the same length, units U_x and U_y (1-D, finite,
        checked by the caller): arrays, or sources read a chunk of segments at a time
        (:class:`fsi_lab.sources.DatasetSource`: the same numbers, to the bit).
    fs
        Sample rate, Hz.
    segment
        Samples per segment (resolution fs / segment).
    step
        Samples between segment starts (segment / 2 for 50 % overlap).
    window
        A window name for :func:`scipy.signal.get_window`.
    groups
        Number of groups, 1 to the number of segments.

    Returns
    -------
    CrossSpectra

    Raises
    ------
    AnalysisError
        Fewer segments than groups, or an unknown window.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> x = rng.standard_normal(8192)
    >>> s = cross_spectra(x, 2.0 * x, 100.0, segment=512, step=256, groups=4)
    >>> sxx, syy, sxy = s.total()
    >>> bool(np.allclose(sxy[1:] / sxx[1:], 2.0))
    True
    """
    streamed = hasattr(x, "read") or hasattr(y, "read")
    xa = x if streamed else np.asarray(x, dtype=np.float64)
    ya = y if streamed else np.asarray(y, dtype=np.float64)
    size = int(len(xa))
    n_seg = 1 + (size - segment) // step if size >= segment else 0
    if not 1 <= groups <= n_seg:
        raise fail(_func, f"{n_seg} segment(s) of {segment} samples cannot make {groups} "
                          "group(s); expected at least one segment per group")
    try:
        w = ssig.get_window(window, segment)
    except ValueError as exc:
        raise fail(_func, f"window {window!r}: {exc}") from None
    scale = 2.0 / (fs * float(np.sum(w * w)))
    bins = segment // 2 + 1
    owner = np.arange(n_seg) * groups // n_seg          # group of each segment, contiguous
    counts = np.bincount(owner, minlength=groups)
    sxx = np.zeros((groups, bins))
    syy = np.zeros((groups, bins))
    sxy = np.zeros((groups, bins), dtype=np.complex128)
    per_chunk = max(1, _CHUNK_SAMPLES // segment)
    offsets = np.arange(segment)
    for first in range(0, n_seg, per_chunk):
        seg = np.arange(first, min(n_seg, first + per_chunk))
        idx = seg[:, None] * step + offsets[None, :]
        if streamed:  # this chunk's stretch of each record, read from its source
            lo, hi = int(seg[0]) * step, int(seg[-1]) * step + segment
            idx -= lo
            xs = np.asarray(xa[lo:hi], dtype=np.float64)[idx]
            ys = np.asarray(ya[lo:hi], dtype=np.float64)[idx]
        else:
            xs = xa[idx]
            ys = ya[idx]
        xs -= xs.mean(axis=1, keepdims=True)
        ys -= ys.mean(axis=1, keepdims=True)
        fx = rfft(xs * w)
        fy = rfft(ys * w)
        for g in np.unique(owner[seg]):
            rows = owner[seg] == g
            sxx[g] += np.sum(fx[rows].real ** 2 + fx[rows].imag ** 2, axis=0)
            syy[g] += np.sum(fy[rows].real ** 2 + fy[rows].imag ** 2, axis=0)
            sxy[g] += np.sum(np.conj(fx[rows]) * fy[rows], axis=0)
    norm = scale / counts[:, None]
    edges = [0, -1] if segment % 2 == 0 else [0]
    for arr in (sxx, syy, sxy):
        arr *= norm
        arr[:, edges] *= 0.5                # DC and Nyquist are not doubled (as scipy)
    freqs = np.arange(bins) * (fs / segment)
    return CrossSpectra(frequency=freqs, sxx=sxx, syy=syy, sxy=sxy, counts=counts,
                        segment=int(segment), step=int(step), window=window, fs=float(fs))
