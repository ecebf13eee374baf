"""Frequency response functions under random excitation (the paper's Section 5.2, Fig. 17).

``H1 = S_xy / S_xx`` (unbiased by output noise) and ``H2 = S_yy / S_yx`` (unbiased by input
noise) from Welch-averaged auto and cross spectra of the reference x (base acceleration) and
the response y (tip velocity), with the coherence ``|S_xy|^2 / (S_xx S_yy)``. Natural
frequencies are the peaks of ``|H1|`` refined by a parabola through the log magnitudes of the
three bins around each; the damping ratio of each is estimated by the half-power bandwidth,
``zeta = (f_b - f_a) / (2 f_n)`` where ``|H1|`` falls to ``|H1(f_n)| / sqrt(2)`` (crossings
interpolated linearly in the magnitude).

For a velocity response over an acceleration (or force) input of a lightly damped mode the
half-power points bracket the peak exactly at ``f_n (sqrt(1 + zeta^2) -+ zeta)``; for other
pairings the estimate is correct to first order in zeta.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.signal as ssig

from fsi_lab.dsp._signal import as_record, check_rate, fail
from fsi_lab.dsp.spectrum import find_peaks_interpolated


@dataclass(frozen=True)
class FRF:
    """Frequency response estimates.

    Attributes
    ----------
    frequency
        Hz, from 0 to fs/2.
    h1, h2
        Complex FRF estimates, unit of y per unit of x.
    coherence
        0..1.
    natural_frequencies
        Interpolated peak frequencies of |H1|, Hz, ascending.
    damping_ratios
        Half-power damping ratio of each peak (NaN where a half-power point is not found).
    peak_magnitudes
        |H1| at each peak.
    """

    frequency: np.ndarray
    h1: np.ndarray
    h2: np.ndarray
    coherence: np.ndarray
    natural_frequencies: np.ndarray
    damping_ratios: np.ndarray
    peak_magnitudes: np.ndarray


def half_power_damping(freqs: np.ndarray, mag: np.ndarray, f_peak: float) -> float:
    """Half-power damping ratio of the peak of ``mag`` at ``f_peak`` (Hz); NaN if the
    magnitude does not fall below peak/sqrt(2) on both sides before rising again."""
    k = int(np.argmin(np.abs(freqs - f_peak)))
    lo = max(k - 1, 0)
    hi = min(k + 2, mag.size)
    k = lo + int(np.argmax(mag[lo:hi]))
    level = mag[k] / math.sqrt(2.0)
    i = k
    while i > 0 and mag[i] > level:
        if mag[i - 1] > mag[i] * 1.0000001 and i < k:
            return float("nan")              # another peak before the half-power point
        i -= 1
    j = k
    while j < mag.size - 1 and mag[j] > level:
        if mag[j + 1] > mag[j] * 1.0000001 and j > k:
            return float("nan")
        j += 1
    if mag[i] > level or mag[j] > level:
        return float("nan")
    fa = freqs[i] + (level - mag[i]) * (freqs[i + 1] - freqs[i]) / (mag[i + 1] - mag[i])
    fb = freqs[j - 1] + (level - mag[j - 1]) * (freqs[j] - freqs[j - 1]) / (mag[j] - mag[j - 1])
    fn = freqs[k]
    return float((fb - fa) / (2.0 * fn))


def frf(x: Any, y: Any, fs: float, *, segment: int | None = None, overlap: float = 0.5,
        window: str = "hann", min_relative: float = 0.05, max_peaks: int | None = None,
        min_coherence: float = 0.0) -> FRF:
    """H1, H2 and coherence by Welch averaging, natural frequencies and half-power damping.

    Parameters
    ----------
    x
        Reference (input) record, e.g. base acceleration, unit X.
    y
        Response record of the same length, e.g. tip velocity, unit Y.
    fs
        Sample rate, Hz.
    segment
        Samples per Welch segment (frequency resolution fs / segment). Default: the record
        split into about 16 segments at 50 % overlap, at most 2^16 samples.
    overlap
        Fraction of overlap between segments, 0 <= overlap < 1.
    window
        Window name for :func:`scipy.signal.get_window`.
    min_relative
        Peaks of |H1| with a prominence below this fraction of the largest are ignored.
    max_peaks
        Keep at most this many natural frequencies (the largest peaks).
    min_coherence
        Ignore peaks where the coherence is below this value (0..1).

    Returns
    -------
    FRF

    Raises
    ------
    AnalysisError
        Records of different lengths, NaN/inf, constant records, bad sample rate, a segment
        shorter than 16 samples or longer than the record, fewer than 2 segments to average, or
        an overlap outside [0, 1).
    """
    func = "frf"
    fs = check_rate(fs, func)
    xa = as_record(x, func, min_samples=64, name="reference record", check_clipping=True)
    ya = as_record(y, func, min_samples=64, name="response record", check_clipping=True)
    if xa.size != ya.size:
        raise fail(func, f"reference ({xa.size} samples) and response ({ya.size} samples) "
                         "have different lengths; expected two records of the same length")
    if not (0.0 <= overlap < 1.0):
        raise fail(func, f"overlap = {overlap!r}; expected a fraction in [0, 1)")
    n = xa.size
    if segment is None:
        segment = int(min(2 ** 16, max(64, n // 8)))
    if isinstance(segment, bool) or not isinstance(segment, (int, np.integer)) \
            or not (16 <= segment <= n):
        raise fail(func, f"segment = {segment!r} samples; expected an integer between 16 and "
                         f"the record length {n}")
    step = max(1, int(round(segment * (1.0 - overlap))))
    n_avg = 1 + (n - segment) // step
    if n_avg < 2:
        raise fail(func, f"only {n_avg} segment of {segment} samples fits in {n} samples; "
                         "averaging needs at least 2 - a longer record or a shorter segment")
    noverlap = segment - step
    kw = dict(fs=fs, window=window, nperseg=segment, noverlap=noverlap, detrend="constant")
    f, sxx = ssig.welch(xa, **kw)
    _, syy = ssig.welch(ya, **kw)
    _, sxy = ssig.csd(xa, ya, **kw)
    tiny = 1e-300
    h1 = sxy / np.maximum(sxx, tiny)
    h2 = syy / np.where(np.abs(sxy) > tiny, np.conj(sxy), tiny)
    coh = np.abs(sxy) ** 2 / np.maximum(sxx * syy, tiny)
    mag = np.abs(h1)
    mag[0] = 0.0                              # the DC bin carries no resonance
    peaks = find_peaks_interpolated(f, mag, min_relative=min_relative, max_peaks=None,
                                    fmin=f[1], _func=func)
    fn = peaks.frequencies
    amp = peaks.amplitudes
    if min_coherence > 0 and fn.size:
        ok = np.interp(fn, f, coh) >= min_coherence
        fn, amp = fn[ok], amp[ok]
    if max_peaks is not None:
        fn, amp = fn[:max_peaks], amp[:max_peaks]
    order = np.argsort(fn)
    fn, amp = fn[order], amp[order]
    zeta = np.array([half_power_damping(f, mag, fk) for fk in fn])
    return FRF(frequency=f, h1=h1, h2=h2, coherence=np.clip(coh, 0.0, 1.0),
               natural_frequencies=fn, damping_ratios=zeta, peak_magnitudes=amp)
