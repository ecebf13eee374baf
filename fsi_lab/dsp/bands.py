"""One zero-phase band per mode: a partition of unity of the spectrum.

:class:`ModeBands` splits a record into one band per mode, plus what lies below the lowest
mode and above the highest. Two neighbouring bands meet at the geometric mean of their modes,
across a transition that covers :data:`TRANSITION_SHARE` of the gap between them (in
log-frequency) and is infinitely smooth (:func:`._signal.smooth_step`: the band filters'
impulse responses die out faster than any power of time). The gains of all bands add up to
exactly one at every frequency, so the band signals add up to the record: nothing is lost and
nothing counted twice. A band cannot follow another mode: a component made this way never
switches modes (unlike HVD, which follows whichever mode is the larger).

:func:`split` filters a window of a record (one free decay) after extending both its ends by
prediction (:func:`._signal.ar_extend` fitted to the first and last
:data:`PAD_FIT_CYCLES` cycles), so the filters see a continuation of the decay rather than a
jump; what the filters still smear at the window's start is small, and the identification
(:mod:`.identify`) corrects it by putting its own model decay through the same steps.

:func:`reduce_rate` brings a record sampled far above its highest band to the rate the bands
need (:func:`reduction_factor`), with the same band signals.

:meth:`ModeBands.correlation` gives the correlation of white noise after a band's filter as a
function of the time lag: the errors of extrema measured on the band signal are correlated
like it (:func:`.laws.fit_law` whitens them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.fft as sfft
from scipy.integrate import trapezoid as _trapezoid

from fsi_lab.dsp._signal import FFT_WORKERS, ar_extend, fail, smooth_step

#: Share of the log-frequency gap between two modes taken by the transition between their
#: bands (the rest is flat: gain 1 around each mode).
TRANSITION_SHARE = 0.6
#: The lowest band is flat from LOW_PASS x its mode's frequency up, zero below LOW_STOP x it.
LOW_STOP, LOW_PASS = 0.25, 0.6
#: The highest band is flat up to HIGH_PASS x its mode's frequency, zero from HIGH_STOP x it
#: (or from 0.95 x the Nyquist frequency when that is lower).
HIGH_PASS, HIGH_STOP = 2.4, 3.6
#: Cycles of the lowest mode that the end predictions are fitted to.
PAD_FIT_CYCLES = 1.5
#: Periods of the lowest band edge by which each window end is extended.
PAD_PERIODS = 4.0
#: A band filter's reach ends where its impulse response stays below this share of its peak.
REACH_LEVEL = 0.01
#: :func:`reduction_factor`: a record is worth reducing when it keeps at least this many samples
#: per cycle of the highest band's stop edge (above which every band passes nothing).
REDUCED_SAMPLES_PER_CYCLE = 32.0
#: :func:`reduce_rate`'s low-pass falls from 1 to 0 between these shares of the reduced
#: Nyquist frequency (infinitely smooth, so its impulse response dies out within a few samples).
REDUCE_PASS, REDUCE_STOP = 0.5, 0.8
#: Samples of the reduced rate by which :func:`reduce_rate` extends each end by prediction.
REDUCE_PAD = 512


@dataclass(frozen=True)
class ModeBands:
    """Band filters around modes at ``centres`` (Hz, increasing).

    Attributes
    ----------
    centres
        Frequency of each mode, Hz, increasing.
    transitions
        ``(K + 1, 2)`` array of transition bands in Hz: row 0 is the rise of the lowest band,
        row K the fall of the highest, row k (0 < k < K) the transition from band k - 1 to
        band k.
    """

    centres: np.ndarray
    transitions: np.ndarray

    @classmethod
    def around(cls, centres, fs: float) -> "ModeBands":
        """Bands around the mode frequencies ``centres`` (Hz) for a record sampled at ``fs``
        (Hz)."""
        f = np.sort(np.asarray(centres, dtype=np.float64))
        nyq = 0.5 * float(fs)
        if f.size == 0 or not np.all(np.isfinite(f)) or f[0] <= 0 or f[-1] >= 0.95 * nyq:
            raise fail("ModeBands", f"mode frequencies {f.tolist()} Hz: expected at least one, "
                                    f"all > 0 and below 0.95 x the Nyquist frequency {nyq:g} Hz")
        if np.any(np.diff(f) <= 0):
            raise fail("ModeBands", f"mode frequencies {f.tolist()} Hz are not distinct")
        rows = [(LOW_STOP * f[0], LOW_PASS * f[0])]
        for lo, hi in zip(f[:-1], f[1:]):
            mid = 0.5 * (math.log(lo) + math.log(hi))
            half = 0.5 * TRANSITION_SHARE * (math.log(hi) - math.log(lo))
            rows.append((math.exp(mid - half), math.exp(mid + half)))
        top_stop = min(HIGH_STOP * f[-1], 0.95 * nyq)
        top_pass = min(HIGH_PASS * f[-1], top_stop / (HIGH_STOP / HIGH_PASS))
        top_pass = max(top_pass, f[-1] * (1.0 + 0.5 * (top_stop / f[-1] - 1.0)))
        rows.append((top_pass, top_stop))
        return cls(f, np.array(rows))

    @property
    def count(self) -> int:
        """Number of mode bands."""
        return int(self.centres.size)

    def gain(self, k: int, freqs: np.ndarray) -> np.ndarray:
        """Gain of band ``k`` at ``freqs`` (Hz, any sign): 1 in its flat part, 0 outside."""
        f = np.abs(np.asarray(freqs, dtype=np.float64))
        with np.errstate(divide="ignore"):
            lf = np.log(np.maximum(f, 1e-300))
        lo, hi = self.transitions[k], self.transitions[k + 1]
        rise = smooth_step((lf - math.log(lo[0])) / (math.log(lo[1]) - math.log(lo[0])))
        fall = 1.0 - smooth_step((lf - math.log(hi[0])) / (math.log(hi[1]) - math.log(hi[0])))
        return rise * fall

    def flat(self, k: int) -> tuple[float, float]:
        """The flat part of band ``k`` (gain exactly 1), Hz."""
        return float(self.transitions[k, 1]), float(self.transitions[k + 1, 0])

    def noise_fraction(self, k: int, fs: float, integrate: bool = False) -> float:
        """Fraction of the power of white noise (sampled at ``fs`` Hz) that band ``k`` passes
        (with ``integrate``, divided by ``(2 pi f)^2`` as :func:`split` does, in s^2): the
        noise RMS after the band is ``sqrt`` of it times the RMS before."""
        grid, g2 = self._power(k, integrate)
        return float(_trapezoid(g2, grid) / (0.5 * float(fs)))

    def mean_square_frequency(self, k: int, integrate: bool = False) -> float:
        """Mean of ``(2 pi f)^2`` (rad^2/s^2) over the power of white noise after band ``k``:
        the variance of the noise's time derivative over that of the noise."""
        grid, g2 = self._power(k, integrate)
        return float(_trapezoid(g2 * (2.0 * math.pi * grid) ** 2, grid) / _trapezoid(g2, grid))

    def _power(self, k: int, integrate: bool) -> tuple[np.ndarray, np.ndarray]:
        grid = np.linspace(self.transitions[k, 0], self.transitions[k + 1, 1], 4096)
        g2 = self.gain(k, grid) ** 2
        if integrate:
            g2 = g2 / (2.0 * math.pi * grid) ** 2
        return grid, g2

    def reach(self, k: int, level: float = REACH_LEVEL) -> float:
        """How far (s) band ``k``'s filter reaches: the lag beyond which its impulse response
        stays below ``level`` of its peak. A band signal's value depends on the input within
        this lag of it (and on nothing further within ``level``)."""
        lo, hi = float(self.transitions[k, 0]), float(self.transitions[k + 1, 1])
        df = lo / 64.0                                       # lags up to 32 / lo s
        grid = np.arange(int(math.ceil(hi / df)) + 1) * df
        size = sfft.next_fast_len(max(2 * grid.size, int(8.0 * hi / df)))
        spec = np.zeros(size // 2 + 1)
        spec[:grid.size] = self.gain(k, grid)
        h = np.abs(sfft.irfft(spec, n=size)[:size // 2])
        above = np.flatnonzero(h > level * h[0])
        return float(above[-1] + 1) / (size * df)

    def correlation(self, k: int) -> Callable[[np.ndarray], np.ndarray]:
        """Correlation of white noise after band ``k``'s filter as a function of the lag (s):
        the cosine transform of the squared gain, tabulated by FFT."""
        lo, hi = float(self.transitions[k, 0]), float(self.transitions[k + 1, 1])
        df = (hi - lo) / 2048.0
        grid = np.arange(int(math.ceil(hi / df)) + 1) * df
        g2 = self.gain(k, grid) ** 2
        size = sfft.next_fast_len(int(32.0 * hi / df))      # lag step <= 1 / (16 hi)
        spec = np.zeros(size // 2 + 1)
        spec[:g2.size] = g2
        table = sfft.irfft(spec, n=size)
        table /= table[0]
        lags = np.arange(size // 2) / (size * df)

        def rho(lag: np.ndarray) -> np.ndarray:
            return np.interp(np.abs(lag), lags, table[:size // 2], right=0.0)

        return rho


def extend(x: np.ndarray, fs: float, lowest: float, highest: float, modes: int, pad: int
           ) -> np.ndarray:
    """``x`` with ``pad`` predicted samples before and after it, tapered to zero.

    The prediction (:func:`._signal.ar_extend`, ``2 modes + 2`` poles) is fitted to the first
    and last :data:`PAD_FIT_CYCLES` cycles of the ``lowest`` frequency (Hz) present, at about
    8 points per cycle of the ``highest``; over the outer part of each extension it is tapered
    smoothly to zero so the padded window wraps around without a jump.
    """
    if pad <= 0:
        return x.copy()
    stride = max(1, int(fs / (8.0 * highest)))
    order = 2 * modes + 2
    fit = int(min(x.size // 2, max(3 * order * stride, PAD_FIT_CYCLES * fs / lowest)))
    def predicted(stretch: np.ndarray) -> np.ndarray:
        # A stretch with no signal (a silent start, a tail sunk to zero) predicts silence.
        if fit < 2 * order * stride + 4 or not np.any(stretch != stretch[-1]):
            return np.full(pad, float(stretch[-1]))
        return ar_extend(stretch, pad, order, stride, fit, 1e3, None, 0.0)

    head = predicted(x[:fit][::-1].copy())[::-1]
    tail = predicted(x[-fit:].copy())
    taper = np.ones(pad)
    fade = min(pad, int(2.0 * fs / lowest))
    taper[:pad - fade] = 0.0
    taper[pad - fade:] = smooth_step(np.linspace(0.0, 1.0, fade))
    return np.concatenate((head * taper, x, tail * taper[::-1]))


def reduction_factor(bands: ModeBands, fs: float) -> int:
    """By how much a record sampled at ``fs`` (Hz) can be reduced for ``bands``: the largest
    integer that keeps :data:`REDUCED_SAMPLES_PER_CYCLE` samples per cycle of the highest
    band's stop edge (1 when the record is not that oversampled)."""
    top = float(bands.transitions[-1, 1])
    return max(1, int(float(fs) // (REDUCED_SAMPLES_PER_CYCLE * top)))


def reduce_rate(x: np.ndarray, fs: float, factor: int, bands: ModeBands) -> np.ndarray:
    """A record at ``fs / factor`` Hz that every band of ``bands`` sees as it sees ``x``.

    ``x`` (sampled at ``fs`` Hz) is extended at both ends by prediction (:func:`extend`, as
    :func:`split` does), low-passed with a zero-phase filter that is flat up to
    :data:`REDUCE_PASS` of the reduced Nyquist frequency (keep ``factor`` at most
    :func:`reduction_factor`: the bands then lie inside the flat part), and sampled every
    ``factor``-th sample from the first. A record sampled far above its modes costs the
    band filters ``factor`` times less this way, for the same band signals.

    Parameters
    ----------
    x
        Samples (1-D, any unit U).
    fs
        Sample rate of ``x``, Hz.
    factor
        Reduction, an integer >= 1 (1 returns a copy of ``x``).
    bands
        The band filters the reduced record is for.

    Returns
    -------
    numpy.ndarray
        ``ceil(len(x) / factor)`` samples (U); sample ``j`` is at the time of ``x[j * factor]``.

    Examples
    --------
    A 20 Hz decay sampled at 20 kHz, brought to the rate its band needs:

    >>> import numpy as np
    >>> from fsi_lab.dsp.bands import ModeBands, reduce_rate, reduction_factor
    >>> fs = 20000.0
    >>> t = np.arange(int(2 * fs)) / fs
    >>> x = np.exp(-2.0 * t) * np.cos(2 * np.pi * 20.0 * t)
    >>> bands = ModeBands.around([20.0], fs)
    >>> q = reduction_factor(bands, fs)
    >>> y = reduce_rate(x, fs, q, bands)
    >>> print(q, y.size, bool(np.max(np.abs(y - x[::q])) < 1e-8))
    8 5000 True
    """
    x = np.asarray(x, dtype=np.float64)
    factor = int(factor)
    if factor < 1:
        raise fail("reduce_rate", f"factor = {factor}; expected an integer >= 1")
    if factor == 1:
        return x.copy()
    level = float(np.mean(x))
    pad = REDUCE_PAD * factor
    xp = extend(x - level, fs, float(bands.centres[0]), float(bands.centres[-1]), bands.count,
                pad)
    m_out = sfft.next_fast_len(-(-xp.size // factor), real=True)
    spec = sfft.rfft(xp, n=m_out * factor, workers=FFT_WORKERS)[:m_out // 2 + 1]
    del xp
    share = np.arange(spec.size) / (0.5 * m_out)        # of the reduced Nyquist frequency
    spec *= 1.0 - smooth_step((share - REDUCE_PASS) / (REDUCE_STOP - REDUCE_PASS))
    y = sfft.irfft(spec, n=m_out, workers=FFT_WORKERS)
    first = pad // factor
    return y[first:first + -(-x.size // factor)] / factor + level


def split(x: np.ndarray, fs: float, bands: ModeBands, integrate: int = 0) -> np.ndarray:
    """Band signals of a window ``x`` of a record (samples at ``fs`` Hz), one row per band.

    Both ends are extended by prediction (:func:`extend`) before the zero-phase filters are
    applied; ``integrate`` (a count) divides each band by ``(i 2 pi f)^integrate`` on the way
    (an acceleration becomes a velocity with 1; the bands hold no zero frequency).

    Returns
    -------
    numpy.ndarray
        Shape ``(bands.count, len(x))``, unit of x (times s^integrate).
    """
    x = np.asarray(x, dtype=np.float64)
    lowest = float(bands.transitions[0, 1])
    pad = int(math.ceil(PAD_PERIODS * fs / lowest))
    xp = extend(x - float(np.mean(x)), fs, float(bands.centres[0]), float(bands.centres[-1]),
                bands.count, pad)
    m = sfft.next_fast_len(xp.size, real=True)
    spec = sfft.rfft(xp, n=m, workers=FFT_WORKERS)
    freqs = np.arange(spec.size) * (float(fs) / m)
    if integrate:
        with np.errstate(divide="ignore", invalid="ignore"):
            jw = 2j * math.pi * np.where(freqs > 0, freqs, 1.0)
            spec = np.where(freqs > 0, spec / jw ** int(integrate), 0.0)
    out = np.empty((bands.count, x.size))
    for k in range(bands.count):
        out[k] = sfft.irfft(spec * bands.gain(k, freqs), n=m, workers=FFT_WORKERS)[pad:pad + x.size]
    return out
