"""Integration in the frequency domain: velocity to displacement, acceleration to velocity.

The paper (Section 5.3) integrates the measured velocity and removes the zero-frequency content
in the frequency domain, so that the displacement oscillates about zero. Here:

1. both ends are extended by linear prediction (:func:`._signal.predict_pad`: a damped-
   exponential model with a constant level fitted to the first and last cycles, continued
   without a phase jump, a decay allowed to grow backwards by up to ``PAD_GROWTH``) to a fast
   FFT length, so the record does not wrap around with a jump and an offset stays an offset;
2. (no detrending in the time domain: a least-squares line through a free decay is not zero
   and removing it would distort the displacement);
3. the spectrum is divided by ``(i 2 pi f)^order`` and multiplied by a zero-phase high-pass:
   gain 0 up to ``highpass / 2``, 1 from ``highpass`` up, infinitely smooth between. The
   default ``highpass`` is half the lowest significant spectral peak of the record, so the
   modes pass unchanged and the zero-frequency and drift content is removed;
4. back to the time domain, cropped to the record.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import scipy.fft as sfft

from fsi_lab.dsp._signal import FFT_WORKERS, as_record, check_rate, fail, highpass_gain, predict_pad
from fsi_lab.dsp.spectrum import free_decay_peaks

#: Default high-pass corner as a fraction of the lowest significant spectral peak.
HIGHPASS_FRACTION = 0.5
#: Each end is extended by PAD_PERIODS periods of the high-pass corner.
PAD_PERIODS = 4.0
#: Largest growth of the predicted extension: a decay continued backwards in time grows, and
#: letting it (instead of mirroring) avoids an envelope kink at the record start, whose low
#: frequency content the high-pass would otherwise distort.
PAD_GROWTH = 100.0
#: Frequency bins the integrating high-pass is computed for at a time.
FACTOR_BLOCK = 1 << 16


def lowest_mode(x: np.ndarray, fs: float, func: str) -> tuple[float, np.ndarray]:
    """Lowest significant spectral peak (Hz) of a record, and all significant peaks (of its
    decays' averaged spectrum when it holds several: :func:`.spectrum.free_decay_peaks`)."""
    peaks = free_decay_peaks(x, fs, min_relative=0.01, smoothing=0.05)
    if peaks.frequencies.size == 0:
        raise fail(func, "found no spectral peak above the lowest resolvable frequency "
                         f"{2.0 * fs / x.size:.3g} Hz, so no high-pass corner can be chosen; "
                         "give highpass (Hz) explicitly")
    return float(peaks.frequencies.min()), peaks.frequencies


def integrate(x: Any, fs: float, *, order: int = 1, highpass: float | None = None) -> np.ndarray:
    """Integrate a record ``order`` times in the frequency domain, drift removed.

    Parameters
    ----------
    x
        Samples in unit U (e.g. velocity, m/s, or acceleration, m/s^2); 1-D, finite, not
        constant, not clipped, at least 64 samples.
    fs
        Sample rate, Hz.
    order
        1 (velocity -> displacement, acceleration -> velocity) or 2 (acceleration ->
        displacement).
    highpass
        High-pass corner, Hz: content below ``highpass / 2`` is removed, above ``highpass`` kept
        exactly. Default: half the lowest significant spectral peak of the record.

    Returns
    -------
    numpy.ndarray
        The integral, unit U s^order (m for a velocity in m/s), same length as ``x``, with zero
        mean content below the high-pass.

    Raises
    ------
    AnalysisError
        Bad sample rate, NaN/inf, constant, clipped or too short record, order not 1 or 2, a
        high-pass corner not in (0, fs/2), or no spectral peak to set the default corner.
    """
    func = "integrate"
    fs = check_rate(fs, func)
    x = as_record(x, func, min_samples=64)
    if isinstance(order, bool) or order not in (1, 2):
        raise fail(func, f"order = {order!r}; expected 1 or 2")
    f_lo, peaks = lowest_mode(x, fs, func)
    if highpass is None:
        highpass = HIGHPASS_FRACTION * f_lo
    highpass = float(highpass)
    if not math.isfinite(highpass) or not (0 < highpass < fs / 2):
        raise fail(func, f"highpass = {highpass!r} Hz; expected a corner between 0 and "
                         f"{fs / 2:g} Hz (Nyquist)")
    n = x.size
    y = x
    pad = min(int(math.ceil(PAD_PERIODS * fs / highpass)), 4 * n)
    m = sfft.next_fast_len(n + 2 * pad, real=True)
    yp = predict_pad(y, fs, peaks, pad, m - n - pad, PAD_GROWTH)
    spec = sfft.rfft(yp, workers=FFT_WORKERS)
    del yp
    # The integrating high-pass, applied a block of bins at a time (its temporaries stay
    # small; every bin gets the same numbers as from the whole spectrum at once).
    for lo in range(0, spec.size, FACTOR_BLOCK):
        f = np.arange(lo, min(spec.size, lo + FACTOR_BLOCK)) * (fs / m)
        gain = highpass_gain(f, highpass)
        if lo == 0:
            gain[0] = 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            factor = np.where(f > 0, gain / (2j * np.pi * np.where(f > 0, f, 1.0)) ** order, 0.0)
        spec[lo:lo + f.size] *= factor
    out = sfft.irfft(spec, n=m, workers=FFT_WORKERS, overwrite_x=True)
    return out[pad:pad + n].copy()
