"""Hilbert Vibration Decomposition (Feldman 2006, 2011) with time-varying frequency.

The record is split into quasi-harmonic components ``A_k(t) cos(theta_k(t))``, the largest
first. For each component, on the residual left by the previous ones:

1. analytic signal ``z = r + i H[r]`` (FFT);
2. instantaneous frequency ``omega(t) = d arg z / dt``, low-passed: the ripple that the smaller
   components put on ``omega`` sits at their frequency differences and is removed, leaving the
   frequency of the largest component, time-varying (not a constant carrier);
3. synchronous demodulation: ``b = LP[z e^{-i phi}]`` with ``phi = integral of omega`` - the
   in-phase and quadrature parts of the residual, low-passed with the same cut-off;
4. amplitude ``A = |b|``, phase ``theta = phi + arg b`` (phase correction), component
   ``A cos(theta)``, frequency ``d theta / dt``;
5. subtract and repeat.

Numerical choices (see the module constants):

- Filters act in the frequency domain with a zero-phase low-pass whose pass band is flat (slowly
  varying envelopes pass without bias) and whose transition is infinitely smooth (filter
  transients stay near the record ends).
- Record ends: each end is extended by linear prediction (an AR model fitted to the first and
  last cycles continues the oscillation without a phase jump), tapered to zero, to a fast FFT
  length. ``padding="mirror"`` uses even reflection instead. Samples closer to an end than
  ``EDGE_PERIODS / cutoff`` are marked in :attr:`HVDResult.edge_mask`.
- Speed: the decomposition runs on the band that holds the record's spectral peaks (up to
  ``BAND_FACTOR`` times the highest significant peak - or, when more components are asked for
  than there are significant peaks, the highest frequency where the spectrum stands above the
  noise and ``WEAK_CONTENT`` of its largest value - at least 10 samples per cycle of the band
  edge), obtained exactly by truncating the spectrum; the components are brought back to the
  full sample rate by interpolating their (smooth) envelopes and phases. Content above that band
  (noise, weak harmonics) does not influence the components and stays in the residual.
- Automatic cut-off, per component: half the smaller of the component's frequency and its
  distance to the nearest other spectral peak (Feldman's rule: below the difference of the
  component frequencies). Peaks closer than about 5 % are treated as one (a chirping component);
  give ``cutoff`` explicitly to separate closer components. The peaks of a record with several
  free decays (an impulse train) are those of its decays' averaged spectrum
  (:func:`.spectrum.free_decay_peaks`): the whole record's spectrum is a comb of lines
  1 / spacing apart around each mode, which would pass for close peaks and give tiny cut-offs.
- Crossing envelopes: HVD follows the largest component at each instant, so when two modes'
  envelopes cross (a short impulse makes a higher mode the larger at first, and it decays
  faster) a component switches from one mode to the other. :func:`.mode_switch.mode_switches`
  finds such components (:attr:`HVDResult.switches`); the plugin marks them with an error,
  which every later analysis of the chain reports instead of results. ``band`` (``band_hz``)
  decomposes a band-passed record (:func:`._signal.bandpass`), one mode at a time.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Sequence

import numba
import numpy as np
import scipy.fft as sfft

from fsi_lab.dsp._signal import (
    BAND_HIGH_STOP,
    BAND_LOW_STOP,
    FFT_WORKERS,
    as_record,
    bandpass,
    bandpass_smear,
    check_rate,
    check_samples_per_cycle,
    fail,
    lowpass_gain,
    mirror_pad,
    predict_pad,
    smooth_step,
)
from fsi_lab.dsp.choices import PADDINGS
from fsi_lab.dsp.mode_switch import mode_switches
from fsi_lab.dsp.spectrum import free_decay_peaks

#: Cut-off as a fraction of min(component frequency, distance to the nearest other peak).
CUTOFF_FRACTION = 0.5
#: Relative width of the low-pass transition band (gain 1 below fc (1 - w), 0 above fc (1 + w)).
TRANSITION = 0.5
#: Samples closer to an end than EDGE_PERIODS / cutoff seconds are marked untrusted.
EDGE_PERIODS = 1.0
#: Each end is padded by PAD_PERIODS / cutoff seconds (predicted or mirrored).
PAD_PERIODS = 3.0
#: Fewest samples per cycle HVD accepts for a component.
MIN_SAMPLES_PER_CYCLE = 4.0
#: Relative prominence of the spectral peaks considered by the automatic cut-off and the band.
PEAK_THRESHOLD = 0.01
#: Relative half-width of the spectral smoothing before the peak search: peaks closer than
#: about 5 % merge (a chirping component, e.g. a softening or hardening decay, is one peak).
PEAK_SMOOTHING = 0.05
#: The decomposition band is flat up to BAND_FACTOR x the highest significant peak.
BAND_FACTOR = 3.0
#: With more components asked for than significant peaks, the band also holds the spectrum
#: up to where it stands above this share of its largest value ...
WEAK_CONTENT = 1e-6
#: ... and above this many times its median (the noise floor of a record with a few modes).
NOISE_CONTENT = 10.0
#: A band (``band_hz``) must hold a spectral peak of the record at least this fraction of its
#: largest.
BAND_PEAK_THRESHOLD = 1e-3
#: Largest growth allowed to the predicted extension (a decay read backwards grows; letting a
#: fast-decaying small component grow past the dominant one would switch the tracked component).
PAD_GROWTH = 1.0


@dataclass(frozen=True)
class HVDResult:
    """Components of a Hilbert Vibration Decomposition, by decreasing amplitude.

    Attributes
    ----------
    components
        Waveforms, shape ``(K, N)``, unit of the input.
    envelopes
        Instantaneous amplitudes ``A_k(t) >= 0``, shape ``(K, N)``, unit of the input.
    frequencies
        Instantaneous frequencies, shape ``(K, N)``, Hz.
    residual
        The record minus all components, shape ``(N,)``.
    edge_mask
        ``True`` where a sample is too close to a record end to be trusted, shape ``(K, N)``.
    cutoffs
        Low-pass cut-off used for each component, Hz, shape ``(K,)``.
    sample_rate
        Hz.
    t0
        Time of the first sample relative to the channel's first sample, s (the ``hvd``
        plugin's ``start_s``; 0 for :func:`hvd`).
    switches
        Per component, None, or the two spectral peaks (Hz, the one it stays near longer
        first) it switches between (:func:`.mode_switch.mode_switches`: two modes' envelopes
        cross); empty when not checked.
    band
        The pass band ``(low, high)`` (Hz) the record was filtered to before the
        decomposition, or None.
    peaks
        The significant spectral peaks of the record decomposed, Hz, largest first (those of
        its decays' averaged spectrum for several decays), which set the automatic cut-offs.
    """

    components: np.ndarray
    envelopes: np.ndarray
    frequencies: np.ndarray
    residual: np.ndarray
    edge_mask: np.ndarray
    cutoffs: np.ndarray
    sample_rate: float
    t0: float = 0.0
    switches: tuple[tuple[float, float] | None, ...] = ()
    band: tuple[float, float] | None = None
    peaks: np.ndarray = dataclasses.field(default_factory=lambda: np.empty(0))

    @property
    def n_components(self) -> int:
        return self.components.shape[0]

    def settle(self, k: int) -> float:
        """Time (s) over which component ``k``'s filters smear a sudden change (an impulse):
        2 / cutoff, plus the band-pass's smear (:func:`._signal.bandpass_smear`) with a band.
        """
        return settle_time(float(self.cutoffs[k]), self.band)

    def mean_frequency(self, k: int) -> float:
        """Envelope-weighted mean instantaneous frequency of component ``k`` (trusted part), Hz."""
        good = ~self.edge_mask[k]
        if not good.any():
            good = np.ones_like(good)
        w = self.envelopes[k, good]
        return float(np.sum(w * self.frequencies[k, good]) / max(np.sum(w), 1e-300))


def settle_time(cutoff: float, band: tuple[float, float] | None) -> float:
    """2 / ``cutoff`` (Hz), plus :func:`._signal.bandpass_smear` of ``band``'s low edge (Hz)
    when given: s."""
    return 2.0 / cutoff + (bandpass_smear(band[0]) if band is not None else 0.0)


# ----------------------------------------------------------------------------- kernels
# The band-rate kernels run serially (their arrays are small after the band reduction, where
# waking a thread pool costs more than it saves); the full-rate reconstruction is parallel.
@numba.njit(cache=True)
def _inst_omega(z: np.ndarray, out: np.ndarray) -> None:
    """Instantaneous angular frequency, rad/sample: central phase difference of ``z``."""
    m = z.shape[0]
    for n in range(1, m - 1):
        p = z[n + 1] * np.conj(z[n - 1])
        out[n] = 0.5 * math.atan2(p.imag, p.real)
    p0 = z[1] * np.conj(z[0])
    out[0] = math.atan2(p0.imag, p0.real)
    p1 = z[m - 1] * np.conj(z[m - 2])
    out[m - 1] = math.atan2(p1.imag, p1.real)


@numba.njit(cache=True)
def _demodulate(z: np.ndarray, phi: np.ndarray, out: np.ndarray) -> None:
    """out = z * exp(-i phi)."""
    for n in range(z.shape[0]):
        c = math.cos(phi[n])
        s = math.sin(phi[n])
        zr = z[n].real
        zi = z[n].imag
        out[n] = complex(zr * c + zi * s, zi * c - zr * s)


@numba.njit(cache=True)
def _modulate_real(b: np.ndarray, phi: np.ndarray, out: np.ndarray) -> None:
    """out -= Re(b e^{i phi})."""
    for n in range(b.shape[0]):
        out[n] -= b[n].real * math.cos(phi[n]) - b[n].imag * math.sin(phi[n])


@numba.njit(cache=True, parallel=True)
def _reconstruct(bf: np.ndarray, theta: np.ndarray, slope: float, freq: np.ndarray,
                 start: float, step: float, comp: np.ndarray, env: np.ndarray,
                 inst: np.ndarray, residual: np.ndarray) -> None:
    """Full-rate component from band-rate quantities by cubic (4-point Lagrange) interpolation.

    Sample n of the record sits at band-rate position u = start + n * step. ``theta`` is the
    band-rate phase minus ``slope * j`` (smooth); bf the complex baseband; freq in Hz.
    """
    m = bf.shape[0]
    for n in numba.prange(comp.shape[0]):
        u = start + n * step
        j = int(math.floor(u))
        t = u - j
        if j < 1:
            j = 1
            t = u - 1.0
        if j > m - 3:
            j = m - 3
            t = u - j
        # Lagrange weights at nodes j-1, j, j+1, j+2.
        w0 = -t * (t - 1.0) * (t - 2.0) / 6.0
        w1 = (t + 1.0) * (t - 1.0) * (t - 2.0) / 2.0
        w2 = -(t + 1.0) * t * (t - 2.0) / 2.0
        w3 = (t + 1.0) * t * (t - 1.0) / 6.0
        br = (w0 * bf[j - 1].real + w1 * bf[j].real + w2 * bf[j + 1].real
              + w3 * bf[j + 2].real)
        bi = (w0 * bf[j - 1].imag + w1 * bf[j].imag + w2 * bf[j + 1].imag
              + w3 * bf[j + 2].imag)
        ph = (w0 * theta[j - 1] + w1 * theta[j] + w2 * theta[j + 1] + w3 * theta[j + 2]
              + slope * u)
        c = math.cos(ph)
        s = math.sin(ph)
        y = br * c - bi * s
        comp[n] = y
        env[n] = math.sqrt(br * br + bi * bi)
        inst[n] = w0 * freq[j - 1] + w1 * freq[j] + w2 * freq[j + 1] + w3 * freq[j + 2]
        residual[n] -= y


@numba.njit(cache=True)
def _band_frequency(om_f: np.ndarray, bf: np.ndarray, scale: float, out: np.ndarray) -> None:
    """out = (omega_f + d arg(bf)/dn) * scale (central difference of the phase correction)."""
    m = bf.shape[0]
    for n in range(1, m - 1):
        q = bf[n + 1] * np.conj(bf[n - 1])
        out[n] = (om_f[n] + 0.5 * math.atan2(q.imag, q.real)) * scale
    out[0] = out[1]
    out[m - 1] = out[m - 2]


# ----------------------------------------------------------------------------- helpers
def _significant_peaks(x: np.ndarray, fs: float, func: str) -> np.ndarray:
    """Frequencies (Hz) of the record's significant spectral peaks, largest first; for a
    record with several free decays, those of its decays' averaged spectrum
    (:func:`.spectrum.free_decay_peaks`: an impulse train's comb of lines merges into one peak
    per mode)."""
    peaks = free_decay_peaks(x, fs, min_relative=PEAK_THRESHOLD, smoothing=PEAK_SMOOTHING)
    if peaks.frequencies.size == 0:
        fmin = 2.0 * fs / x.size
        raise fail(func, "found no spectral peak to decompose (no oscillation above the lowest "
                         f"resolvable frequency {fmin:.3g} Hz in a record of {x.size / fs:.4g} s)")
    return peaks.frequencies


def _content_top(spec: np.ndarray, freqs: np.ndarray) -> float:
    """The highest frequency (Hz) at which the amplitude spectrum ``spec`` (of the padded
    record, at ``freqs``) stands above both :data:`WEAK_CONTENT` of its largest value and
    :data:`NOISE_CONTENT` times its median (the noise): where components beyond the
    significant peaks can be."""
    amp = np.abs(spec)
    level = max(WEAK_CONTENT * float(amp.max()), NOISE_CONTENT * float(np.median(amp)))
    above = np.flatnonzero(amp > level)
    return float(freqs[above[-1]]) if above.size else 0.0


def _check_band_peaks(x: np.ndarray, fs: float, band: tuple[float, float], func: str) -> None:
    """Raise unless ``band`` (Hz) suits the spectral peaks of ``x`` (the record before the
    band-pass): one of them (at least BAND_PEAK_THRESHOLD of the largest) must lie in it - a
    band around no mode would decompose the filter's transients - and none of the significant
    ones (PEAK_THRESHOLD) in its transitions (:func:`._signal.bandpass`), where a mode would
    pass attenuated by a factor that varies with frequency."""
    found = free_decay_peaks(x, fs, min_relative=BAND_PEAK_THRESHOLD, smoothing=PEAK_SMOOTHING)
    f = found.frequencies
    low, high = band
    where = f"band_hz [{low:g}, {high:g}] Hz"
    if not np.any((f >= low) & (f <= high)):
        listed = ", ".join(f"{v:.4g}" for v in np.sort(f)) or "none"
        raise fail(func, f"{where} holds no spectral peak of the record (its peaks are at "
                         f"{listed} Hz); expected a band around one of them")
    big = f[found.amplitudes >= PEAK_THRESHOLD * float(np.max(found.amplitudes))]
    edges = ((BAND_LOW_STOP * low, low), (high, BAND_HIGH_STOP * high))
    for lo, hi in edges:
        inside = big[(big > lo) & (big < hi)]
        if inside.size:
            raise fail(func, f"{where}: the record's spectral peak at {inside[0]:.4g} Hz lies in "
                             f"the band's transition ({lo:.4g} to {hi:.4g} Hz), where it would "
                             "pass partly attenuated; expected every mode inside the band or "
                             f"outside {BAND_LOW_STOP:g} x low to {BAND_HIGH_STOP:g} x high")


def _check_band(band: Any, fs: float, func: str) -> tuple[float, float] | None:
    """``band`` as ``(low, high)`` Hz with ``0 < low < high < fs / 2``, or None; raises an
    AnalysisError naming ``func`` otherwise."""
    if band is None:
        return None
    try:
        values = [float(v) for v in band]
    except (TypeError, ValueError):
        values = []
    if len(values) != 2 or not all(math.isfinite(v) for v in values) \
            or not 0.0 < values[0] < values[1] < 0.5 * fs:
        raise fail(func, f"band_hz = {band!r} is not usable; expected [low, high] in Hz with "
                         f"0 < low < high < {0.5 * fs:g} Hz (the Nyquist frequency)")
    return values[0], values[1]


def band_around(f: float, peaks: np.ndarray) -> tuple[float, float] | None:
    """A ``band_hz`` (Hz, two significant digits) that keeps the spectral peak ``f`` (Hz) and
    stops every other of ``peaks`` (:func:`._signal.bandpass`: nothing below BAND_LOW_STOP x
    low or above BAND_HIGH_STOP x high), with ``f`` at least 20 % inside each edge; None when
    the other peaks are too close for one."""
    others = peaks[np.abs(peaks - f) > PEAK_SMOOTHING * f]
    below, above = others[others < f], others[others > f]
    low = f / 1.5
    high = 1.5 * f
    if below.size:
        low = max(low, 1.05 * float(below.max()) / BAND_LOW_STOP)
    if above.size:
        high = min(high, float(above.min()) / BAND_HIGH_STOP / 1.05)

    def digits(v: float) -> float:
        return 10.0 ** (math.floor(math.log10(v)) - 1)

    low = math.ceil(low / digits(low)) * digits(low)
    high = math.floor(high / digits(high)) * digits(high)
    if not (1.2 * low <= f <= high / 1.2):
        return None
    return float(f"{low:.2g}"), float(f"{high:.2g}")


def _cutoff_for(f_k: float, peaks: np.ndarray) -> float:
    """Automatic cut-off for a component at ``f_k`` Hz among the record's ``peaks``."""
    others = peaks[np.abs(peaks - f_k) > PEAK_SMOOTHING * f_k]
    gap = float(np.min(np.abs(others - f_k))) if others.size else f_k
    return CUTOFF_FRACTION * min(f_k, gap)


def _analytic(spec: np.ndarray, m: int, out_len: int, band_gain: np.ndarray | None
              ) -> np.ndarray:
    """Analytic signal of length ``out_len`` from the rfft ``spec`` of a real length-m signal.

    With ``out_len < m`` the spectrum is truncated (``band_gain`` tapers its kept bins), which
    resamples the band-limited analytic signal exactly at rate ``fs * out_len / m``.
    """
    zs = np.zeros(out_len, dtype=np.complex128)
    kept = min(spec.size, (out_len + 1) // 2) if out_len < m else spec.size
    zs[0] = spec[0]
    if out_len < m:
        zs[1:kept] = 2.0 * spec[1:kept] * band_gain[1:kept]
    else:
        half = (m + 1) // 2
        zs[1:half] = 2.0 * spec[1:half]
        if m % 2 == 0:
            zs[m // 2] = spec[m // 2]
    z = sfft.ifft(zs, workers=FFT_WORKERS, overwrite_x=True)
    if out_len < m:
        z *= out_len / m
    return z


# ----------------------------------------------------------------------------- main
def hvd(x: Any, fs: float, n_components: int = 2, cutoff: float | Sequence[float] | None = None,
        *, padding: str = "predict", band: Sequence[float] | None = None) -> HVDResult:
    """Hilbert Vibration Decomposition of a real record.

    Parameters
    ----------
    x
        Samples of the record, any unit U (1-D, finite, not constant, not clipped).
    fs
        Sample rate, Hz.
    n_components
        Number of components to extract, >= 1 (no upper limit).
    cutoff
        Low-pass cut-off, Hz, of the instantaneous-frequency and demodulation filters: one value
        for all components, one per component, or None (automatic: for each component, half the
        smaller of its frequency and its distance to the nearest other spectral peak). It must
        stay below the difference between the component frequencies.
    padding
        ``"predict"`` (default: linear-prediction extension of both ends) or ``"mirror"``.
    band
        ``[low, high]``, Hz, ``0 < low < high < fs / 2``: decompose the record band-passed to
        it (:func:`._signal.bandpass`: gain exactly 1 from low to high, 0 below low / 2 and
        above 1.5 high, zero phase), so one mode can be analysed on its own; None (default):
        the whole record. The content outside the band stays in the residual.

    Returns
    -------
    HVDResult
        Components, envelopes (U), instantaneous frequencies (Hz), residual, edge mask,
        cut-offs and mode switches (:func:`.mode_switch.mode_switches`); components sorted by
        decreasing RMS envelope over their trusted samples.

    Raises
    ------
    AnalysisError
        NaN/inf, constant or clipped record, bad sample rate, ``n_components`` < 1, a cut-off
        that is not positive or not below the Nyquist frequency, a band that is not
        ``0 < low < high < fs / 2`` or holds no spectral peak, one of the ``n_components``
        largest spectral peaks with fewer than 4 samples per cycle, or a record too short for
        the cut-off (no trusted sample left).

    Notes
    -----
    Components are extracted in order of decreasing instantaneous amplitude; when two
    envelopes cross, a component can switch from one mode to the other mid-record
    (:attr:`HVDResult.switches` tells; ``band`` around one mode avoids it).
    """
    func = "hvd"
    fs = check_rate(fs, func)
    x = as_record(x, func, min_samples=32)
    if isinstance(n_components, bool) or not isinstance(n_components, (int, np.integer)) \
            or n_components < 1:
        raise fail(func, f"n_components = {n_components!r}; expected an integer >= 1")
    if padding not in PADDINGS:
        raise fail(func, f"padding = {padding!r}; expected one of {', '.join(PADDINGS)}")
    band_t = _check_band(band, fs, func)
    raw = x
    if band_t is not None:
        _check_band_peaks(raw, fs, band_t, func)
        x = bandpass(raw, fs, *band_t)
    n = x.size
    k_total = int(n_components)

    peaks = _significant_peaks(x, fs, func)
    for f_p in peaks[:k_total]:          # the largest peaks: the components asked for
        check_samples_per_cycle(f_p, fs, func, MIN_SAMPLES_PER_CYCLE, "spectral peak")

    given = None
    if cutoff is not None:
        given = np.atleast_1d(np.asarray(cutoff, dtype=np.float64))
        if given.ndim != 1 or given.size not in (1, k_total):
            raise fail(func, f"cutoff has {given.size} values for {k_total} components; give "
                             "one value, one per component, or None (automatic)")
        if not np.all(np.isfinite(given)) or np.any(given <= 0) \
                or np.any(given * (1 + TRANSITION) >= fs / 2):
            raise fail(func, f"cutoff {given.tolist()} Hz is not usable; expected values > 0 "
                             f"and below {fs / 2 / (1 + TRANSITION):.4g} Hz (Nyquist / "
                             f"{1 + TRANSITION:g})")
        given = np.broadcast_to(given, (k_total,)).copy()

    auto = [_cutoff_for(f, peaks) for f in peaks]
    fc_min = float(given.min()) if given is not None else min(auto)
    fc_max = float(given.max()) if given is not None else max(auto)
    edge = int(math.ceil(EDGE_PERIODS * fs / fc_min))
    if n <= 2 * edge + 8:
        raise fail(func, f"record of {n} samples ({n / fs:.4g} s) is too short for a cut-off of "
                         f"{fc_min:.4g} Hz: {edge} samples at each end are not trusted; need "
                         f"more than {2 * edge + 8} samples (a longer record or a higher cut-off)")

    # Padded length (fast for the real FFT) and the band actually decomposed.
    pad = min(int(math.ceil(PAD_PERIODS * fs / fc_min)), 4 * n)
    m = sfft.next_fast_len(n + 2 * pad, real=True)
    left = pad
    right = m - n - pad
    xp = mirror_pad(x, left, right) if padding == "mirror" else \
        predict_pad(x, fs, peaks, left, right, PAD_GROWTH, modes=k_total)
    spec = sfft.rfft(xp, workers=FFT_WORKERS)
    del xp
    freqs_full = np.arange(spec.size) * (fs / m)
    top = float(peaks.max())
    if k_total > peaks.size:        # components below the peak threshold: wherever content is
        top = max(top, _content_top(spec, freqs_full))
    f_pass = max(BAND_FACTOR * top, 2.0 * fc_max)
    f_stop = 1.25 * f_pass
    m_b = sfft.next_fast_len(int(math.ceil(2.0 * 1.1 * f_stop * m / fs)) + 8)
    if m_b < m and f_stop < 0.45 * fs:
        band_gain = 1.0 - smooth_step((freqs_full - f_pass) / (f_stop - f_pass))
    else:
        m_b = m
        band_gain = None
    fs_b = fs * m_b / m                     # sample rate of the band signal, Hz
    start = left * m_b / m                  # band-rate position of the first record sample
    step = m_b / m
    lo_b = int(math.floor(start))
    hi_b = int(math.ceil(start + n * step))

    z = _analytic(spec, m, m_b, band_gain)
    r_b = z.real.copy()                     # band residual
    freqs_r = np.arange(m_b // 2 + 1) * (fs_b / m_b)
    freqs_c = sfft.fftfreq(m_b, d=1.0 / fs_b)

    comps = np.empty((k_total, n))
    envs = np.empty((k_total, n))
    inst = np.empty((k_total, n))
    cutoffs = np.empty(k_total)
    mask = np.zeros((k_total, n), dtype=bool)
    residual = raw.copy()
    omega = np.empty(m_b)
    b = np.empty(m_b, dtype=np.complex128)
    fband = np.empty(m_b)
    to_hz = fs_b / (2.0 * math.pi)
    assigned: set[int] = set()
    for k in range(k_total):
        if k > 0:
            z = _analytic(sfft.rfft(r_b, workers=FFT_WORKERS), m_b, m_b, None)
        _inst_omega(z, omega)
        if given is not None:
            fc = float(given[k])
        else:
            # The frequency that dominates the residual: median of the raw instantaneous
            # frequency where the residual is large (at least 30 % of its largest magnitude;
            # smaller components only add a ripple), snapped to the nearest spectral peak of
            # the record (or kept if no peak is within 25 %: a component below the peak
            # threshold).
            # (After the first component, 5 % at each end are left out: earlier components
            # leave their largest errors there.)
            inner = 0 if k == 0 else (hi_b - lo_b) // 20
            stride = max(1, (hi_b - lo_b) // 20000)
            sel = slice(lo_b + inner, hi_b - inner, stride)
            mag = np.abs(z[sel])
            f_res = abs(float(np.median(omega[sel][mag >= 0.3 * mag.max()]))) * to_hz
            near = int(np.argmin(np.abs(peaks - f_res)))
            free = [i for i in range(peaks.size) if i not in assigned]
            if abs(peaks[near] - f_res) <= 0.25 * f_res:
                assigned.add(near)
                fc = _cutoff_for(float(peaks[near]), peaks)
            elif free:
                # No peak near: the residual is not dominated by one component (its phase
                # wanders); take the largest spectral peak not yet extracted.
                assigned.add(free[0])
                fc = _cutoff_for(float(peaks[free[0]]), peaks)
            else:                                    # a component below the peak threshold
                fc = _cutoff_for(f_res, np.append(peaks, f_res))
        cutoffs[k] = fc
        # Low-passed instantaneous frequency and its phase.
        om_f = sfft.irfft(sfft.rfft(omega, workers=FFT_WORKERS)
                          * lowpass_gain(freqs_r, fc, TRANSITION), n=m_b, workers=FFT_WORKERS)
        phi = np.cumsum(om_f)
        # Synchronous demodulation: in-phase and quadrature parts, low-passed.
        _demodulate(z, phi, b)
        bs = sfft.fft(b, workers=FFT_WORKERS)
        bs *= lowpass_gain(freqs_c, fc, TRANSITION)
        bf = sfft.ifft(bs, workers=FFT_WORKERS, overwrite_x=True)
        # Subtract from the band residual; frequency with the phase correction.
        _modulate_real(bf, phi, r_b)
        _band_frequency(om_f, bf, to_hz, fband)
        slope = float(np.mean(om_f))
        theta = phi - slope * np.arange(m_b)
        _reconstruct(bf, theta, slope, fband, start, step, comps[k], envs[k], inst[k], residual)
        e = min(int(math.ceil(EDGE_PERIODS * fs / fc)), n // 2)
        mask[k, :e] = True
        mask[k, n - e:] = True

    rms = np.array([np.sqrt(np.mean(envs[k][~mask[k]] ** 2)) if (~mask[k]).any() else 0.0
                    for k in range(k_total)])
    order = np.argsort(-rms, kind="stable")
    if np.any(order != np.arange(k_total)):          # (a copy only when needed)
        comps, envs, inst, mask, cutoffs = (a[order] for a in (comps, envs, inst, mask, cutoffs))
    settles = np.array([settle_time(float(c), band_t) for c in cutoffs])
    switches = mode_switches(x, fs, envs, inst, mask, cutoffs, settles, peaks)
    return HVDResult(components=comps, envelopes=envs, frequencies=inst, residual=residual,
                     edge_mask=mask, cutoffs=cutoffs, sample_rate=fs, switches=switches,
                     band=band_t, peaks=peaks)
