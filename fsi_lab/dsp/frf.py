"""Frequency response functions under random excitation (the paper's Section 5.2, Fig. 17).

``H1 = S_xy / S_xx`` (unbiased by output noise) and ``H2 = S_yy / S_yx`` (unbiased by input
noise) from Welch-averaged auto and cross spectra of the reference x (base acceleration) and
the response y (tip velocity), with the coherence ``|S_xy|^2 / (S_xx S_yy)``. The peaks of
``|H1|`` are found on the spectrum (refined by a parabola through the log magnitudes of the
three bins around each); each peak's natural frequency and damping ratio come from a modal fit
that models the Welch estimate's leakage (:mod:`fsi_lab.dsp.modal_fit`), with 95 % intervals
from a jackknife over groups of segments.

The half-power damping ``zeta = (f_b - f_a) / (2 f_n)``, where ``|H1|`` falls to
``|H1(f_n)| / sqrt(2)`` (crossings interpolated linearly in the magnitude), is kept beside it:
it is right only when the half-power band spans several bins. With a resolution df, damping
ratios below about 2 df / f are not measurable that way (the band then measures the window:
3 to 25 times too wide), and each such peak carries a warning. For a velocity response over an
acceleration (or force) input of a lightly damped mode the half-power points bracket the peak
exactly at ``f_n (sqrt(1 + zeta^2) -+ zeta)``; for other pairings the estimate is correct to
first order in zeta.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.ndimage import median_filter

from fsi_lab.dsp._signal import as_record, check_rate, fail, true_runs
from fsi_lab.dsp.modal_fit import (
    DEFAULT_GROUPS,
    MIN_GROUPS,
    ModalFit,
    half_power_damping,
    modal_fit,
)
from fsi_lab.dsp.spectrum import cross_spectra, find_peaks_interpolated
from fsi_lab.sources import check_source, is_source

#: Bins where the reference's power (its median over EXCITED_BINS bins) falls below this
#: share of its largest hold no mode (40 dB: a random excitation band-limited to 200 Hz put
#: the shaker's base 80 to 105 dB down above 220 Hz, where |H1| of noise over noise peaked
#: twice as high as the beam's modes; the beam's 17 Hz mode lies 23 dB down, under the
#: shaker's 30 Hz resonance).
EXCITED_SHARE = 1e-4
EXCITED_BINS = 9


def _stretches(f: np.ndarray, inside: np.ndarray) -> str:
    """The stretches of ``f`` (Hz) where ``inside`` holds, in words ("from a to b Hz and
    from c to d Hz", the first three)."""
    spans = [f"from {f[lo]:.4g} to {f[hi - 1]:.4g} Hz" for lo, hi in zip(*true_runs(inside))]
    more = f" and {len(spans) - 3} more" if len(spans) > 3 else ""
    return " and ".join(spans[:3]) + more


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
        Undamped natural frequency of each peak's mode by the modal fit, Hz, ascending by
        peak (the peak's frequency where the fit failed, with a warning).
    natural_frequency_ci95
        Their 95 % intervals, Hz, shape (peaks, 2) (NaN where there is none).
    damping_ratios
        Damping ratio of each peak's mode by the modal fit (NaN where it failed).
    damping_ratio_ci95
        Their 95 % intervals, shape (peaks, 2).
    half_power_damping_ratios
        Half-power damping ratio of each peak (NaN where a half-power point is not found; not
        usable where the half-power band spans fewer than 4 bins, see the warnings).
    peak_frequencies
        Interpolated frequencies of the peaks of |H1|, Hz.
    peak_magnitudes
        |H1| at each peak.
    modes
        The modal fit of each peak.
    warnings
        Sentences, each naming its peak; empty when every check passed.
    """

    frequency: np.ndarray
    h1: np.ndarray
    h2: np.ndarray
    coherence: np.ndarray
    natural_frequencies: np.ndarray
    natural_frequency_ci95: np.ndarray
    damping_ratios: np.ndarray
    damping_ratio_ci95: np.ndarray
    half_power_damping_ratios: np.ndarray
    peak_frequencies: np.ndarray
    peak_magnitudes: np.ndarray
    modes: tuple[ModalFit, ...]
    warnings: tuple[str, ...]
    notes: tuple[str, ...] = ()

    @property
    def resolution(self) -> float:
        """Frequency step, Hz."""
        return float(self.frequency[1] - self.frequency[0])


def frf(x: Any, y: Any, fs: float, *, segment: int | None = None, overlap: float = 0.5,
        window: str = "hann", min_relative: float = 0.05, max_peaks: int | None = None,
        min_coherence: float = 0.0) -> FRF:
    """H1, H2 and coherence by Welch averaging; natural frequencies and damping ratios by a
    modal fit around each peak, with 95 % intervals; half-power damping beside them.

    Parameters
    ----------
    x
        Reference (input) record, e.g. base acceleration, unit X: an array, or a source read a
        chunk at a time (:class:`fsi_lab.sources.DatasetSource`; the same numbers to the bit).
    y
        Response record of the same length, e.g. tip velocity, unit Y (likewise).
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
        Peaks are sought only where the reference is excited: where its power (the median
        over :data:`EXCITED_BINS` bins) is at least :data:`EXCITED_SHARE` of its largest
        (a note then gives the range sought).
    max_peaks
        Keep at most this many natural frequencies (the largest peaks).
    min_coherence
        Ignore peaks where the coherence is below this value (0..1).

    Returns
    -------
    FRF

    Examples
    --------
    A 20 Hz mode with 1 % damping driven by white noise, at a resolution (0.49 Hz) coarser than
    its half-power band (0.4 Hz):

    >>> import numpy as np, scipy.signal as ssig
    >>> fs, wn = 500.0, 2 * np.pi * 20.0
    >>> mode = ssig.cont2discrete(([1.0], [1.0, 2 * 0.01 * wn, wn ** 2]), 1 / fs)
    >>> x = np.random.default_rng(1).standard_normal(2 ** 16)
    >>> y = ssig.lfilter(mode[0].ravel(), mode[1], x)
    >>> res = frf(x, y, fs, segment=1024)
    >>> k = int(np.argmax(res.peak_magnitudes))
    >>> round(float(res.natural_frequencies[k]), 1), round(float(res.damping_ratios[k]), 3)
    (20.0, 0.01)

    Raises
    ------
    AnalysisError
        Records of different lengths, NaN/inf, constant records, bad sample rate, a segment
        shorter than 16 samples or longer than the record, fewer than 2 segments to average, or
        an overlap outside [0, 1).
    """
    func = "frf"
    fs = check_rate(fs, func)
    if is_source(x) or is_source(y):  # read a chunk at a time, never held whole
        xa, ya = x, y
        nx = check_source(x, func, min_samples=64, name="reference record")
        ny = check_source(y, func, min_samples=64, name="response record")
    else:
        xa = as_record(x, func, min_samples=64, name="reference record", check_clipping=True)
        ya = as_record(y, func, min_samples=64, name="response record", check_clipping=True)
        nx, ny = xa.size, ya.size
    if nx != ny:
        raise fail(func, f"reference ({nx} samples) and response ({ny} samples) "
                         "have different lengths; expected two records of the same length")
    if not (0.0 <= overlap < 1.0):
        raise fail(func, f"overlap = {overlap!r}; expected a fraction in [0, 1)")
    n = nx
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
    groups = min(DEFAULT_GROUPS, n_avg) if n_avg >= MIN_GROUPS else 1
    spectra = cross_spectra(xa, ya, fs, segment=segment, step=step, window=window,
                            groups=groups, _func=func)
    f = spectra.frequency
    sxx, syy, sxy = spectra.total()
    tiny = 1e-300
    h1 = sxy / np.maximum(sxx, tiny)
    h2 = syy / np.where(np.abs(sxy) > tiny, np.conj(sxy), tiny)
    coh = np.abs(sxy) ** 2 / np.maximum(sxx * syy, tiny)
    mag = np.abs(h1)
    mag[0] = 0.0                              # the DC bin carries no resonance
    # Where the reference carries almost no power (outside the band an excitation covers),
    # H1 divides noise by noise: its peaks there are no modes, and may be its largest. The
    # reference's level is taken over EXCITED_BINS bins (a tone in it, or a narrow drop at a
    # mode as a shaker's force shows, does not move it).
    level = median_filter(sxx, size=EXCITED_BINS, mode="nearest")
    excited = (level >= EXCITED_SHARE * float(np.max(level[1:]))) & (f > 0)
    notes = []
    if not excited.any():
        raise fail(func, "the reference record carries no power at any frequency above 0 Hz; "
                         "expected the excitation's record (e.g. the base acceleration)")
    if not excited[1:].all():
        notes.append(f"modes are sought {_stretches(f, excited)}, where the reference's power "
                     f"is at least {EXCITED_SHARE:g} of its largest: outside what the "
                     "excitation covers, H1 divides noise by noise")
    # Unexcited bins are held at the lowest excited |H1|: no peak there, and none so large
    # that the peaks the excitation reaches fall below min_relative of it. A peak at the edge
    # of an excited stretch is that edge, not a peak of H1.
    found = find_peaks_interpolated(f, np.where(excited, mag, float(np.min(mag[excited]))),
                                    min_relative=min_relative, max_peaks=None, fmin=f[1],
                                    _func=func)
    k = np.clip(np.rint(found.frequencies / f[1]).astype(int), 1, f.size - 2)
    inside = excited[k] & excited[k - 1] & excited[k + 1]
    fp, amp = found.frequencies[inside], found.amplitudes[inside]
    if min_coherence > 0 and fp.size:
        ok = np.interp(fp, f, coh) >= min_coherence
        fp, amp = fp[ok], amp[ok]
    if max_peaks is not None:
        fp, amp = fp[:max_peaks], amp[:max_peaks]
    order = np.argsort(fp)
    fp, amp = fp[order], amp[order]
    hp = np.array([half_power_damping(f, mag, fk) for fk in fp])
    modes = []
    for i, fk in enumerate(fp):
        modes.append(modal_fit(f, spectra.sxy, spectra.sxx, float(fk), fs=fs, segment=segment,
                               window=window, syy=spectra.syy, counts=spectra.counts,
                               neighbours_hz=np.delete(fp, i), _func=func))
    warnings = [w for m in modes for w in m.warnings]
    fn = np.array([m.frequency_hz for m in modes])
    for i, m in enumerate(modes):
        if not math.isfinite(m.frequency_hz):
            fn[i] = fp[i]
            warnings.append(f"peak at {fp[i]:.4g} Hz: the modal fit failed; its natural "
                            "frequency is the peak's and it has no damping ratio")
    return FRF(frequency=f, h1=h1, h2=h2, coherence=np.clip(coh, 0.0, 1.0),
               natural_frequencies=fn,
               natural_frequency_ci95=np.array([m.frequency_ci95_hz for m in modes]
                                               ).reshape(-1, 2),
               damping_ratios=np.array([m.damping_ratio for m in modes]),
               damping_ratio_ci95=np.array([m.damping_ratio_ci95 for m in modes]).reshape(-1, 2),
               half_power_damping_ratios=hp, peak_frequencies=fp, peak_magnitudes=amp,
               modes=tuple(modes), warnings=tuple(warnings), notes=tuple(notes))
