"""Natural frequency and damping ratio of an FRF peak by a modal fit that models the leakage.

Why not the half-power band or a circle fit: both read the shape of the estimated FRF near its
peak, and a Welch estimate of the FRF is not the FRF. Averaged over segments of ``N`` samples
under a window ``w``, the expected cross spectrum over the auto spectrum of a (locally) white
input is the Fourier transform of the impulse response times the window's normalised
autocorrelation, the lag window ``rho(tau) = sum_n w[n] w[n + tau] / sum_n w[n]^2``::

    E[H1](theta_k) = sum_{tau=0}^{N-1} rho(tau) h[tau] exp(-i theta_k tau),  theta_k = 2 pi k / N

(Bendat & Piersol, Random Data, 4th ed., Sect. 8.5: the resolution bias). When the half-power
band 2 zeta f_n spans a few bins, the lag window cuts the impulse response short and the peak
is widened by the window's main lobe: the half-power estimate then measures the window, 3 to
25 times the true damping. A circle fit, which needs several points on the circle within the
half-power band, has none at such resolutions.

This module fits one mode's pole-residue model *through* the lag window instead: the impulse
response of a mode is ``h[tau] = c z^tau + conj(c) conj(z)^tau`` with the pole
``z = exp(s / fs)``, ``s = -zeta w_n + i w_n sqrt(1 - zeta^2)``, so the model of the estimate
is ``c G(z) + conj(c) G(conj z) + d0 + d1 (f - f_c)``, where ``G`` is the DFT of ``rho z^tau``
(one FFT of N points) and the complex background ``d0 + d1 (f - f_c)`` takes the other modes'
tails in the band. The residue and background are solved by linear least squares for each
``(f_n, zeta)`` (variable projection), which are found by a grid over zeta and then
:func:`scipy.optimize.least_squares`. Bins are weighted by the inverse of the standard error of
H1, ``|H1| sqrt((1 - coh^2) / coh^2)`` (Bendat & Piersol Eq. 9.90). This is a rational-fraction
fit (Richardson & Formenti 1982) of one mode, two poles, with the estimator's leakage in the
model; with ``segment=None`` (an FRF that is not a Welch estimate, e.g. computed from a model)
the plain rational fraction ``1 / (1 - z exp(-i theta))`` is used.

Intervals: the spectra of G groups of consecutive segments are left out one at a time and the
fit repeated (a jackknife over groups of segments, which carries the correlation between
neighbouring bins that a per-bin formula misses); the 95 % interval is the estimate
+- t(0.975, G - 1) jackknife standard errors, the damping ratio's on a log scale. With fewer than
:data:`MIN_GROUPS` groups the interval is the least-squares one, which assumes independent bins
and says so.

Assumptions: a linear, time-invariant structure; an input whose spectrum is flat to within a few
per cent over the window's main lobe (+-2 bins for Hann) near each peak; one mode per peak band
(the band is cut halfway to the neighbouring peaks).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.fft as sfft
import scipy.optimize as sopt
import scipy.signal as ssig
import scipy.stats as sstats

from fsi_lab.dsp._signal import FFT_WORKERS, fail

#: Fewest groups of segments for a jackknife interval.
MIN_GROUPS = 4
#: Groups of segments used by :func:`fsi_lab.dsp.frf.frf` when there are enough segments.
DEFAULT_GROUPS = 10
#: Half-power bandwidth, in bins, below which the half-power estimate is not usable (SCIENCE:
#: damping ratios below about 2 df / f are not measurable by half-power).
HALF_POWER_MIN_BINS = 4.0
#: A damping ratio whose 95 % interval is wider than this factor either side is not resolved.
RESOLVED_FACTOR = 1.5
#: Fewest bins in a peak's band.
MIN_BAND_BINS = 7
_ZETA_BOUNDS = (1e-6, 0.7)


@dataclass(frozen=True)
class ModalFit:
    """One mode fitted to an FRF peak.

    Attributes
    ----------
    frequency_hz
        Undamped natural frequency |s| / 2 pi, Hz (NaN when the fit failed).
    frequency_ci95_hz
        Its 95 % interval, Hz.
    damping_ratio
        Viscous damping ratio zeta (NaN when the fit failed).
    damping_ratio_ci95
        Its 95 % interval.
    peak_hz
        The peak of |H| the fit started from, Hz.
    band_hz
        The band fitted, Hz.
    bins_across
        Half-power bandwidth 2 zeta f_n over the resolution df (how many bins span it).
    interval
        How the intervals were obtained: ``"jackknife"`` (over groups of segments),
        ``"least-squares"`` or ``""`` (none).
    warnings
        Sentences, empty when every check passed.
    """

    frequency_hz: float
    frequency_ci95_hz: tuple[float, float]
    damping_ratio: float
    damping_ratio_ci95: tuple[float, float]
    peak_hz: float
    band_hz: tuple[float, float]
    bins_across: float
    interval: str
    warnings: tuple[str, ...]


@functools.lru_cache(maxsize=8)
def lag_window(window: str, segment: int) -> np.ndarray:
    """Normalised autocorrelation of a (periodic) window, ``rho(tau)`` for tau = 0..N-1.

    Parameters
    ----------
    window
        A name for :func:`scipy.signal.get_window`.
    segment
        Window length N, samples.

    Returns
    -------
    numpy.ndarray
        ``sum_n w[n] w[n + tau] / sum_n w[n]^2``, 1 at tau = 0 (read-only, cached).

    Examples
    --------
    >>> rho = lag_window("boxcar", 4)
    >>> [round(float(v), 6) for v in rho]
    [1.0, 0.75, 0.5, 0.25]
    """
    w = ssig.get_window(window, segment)
    spec = np.fft.rfft(w, 2 * segment)
    r = np.fft.irfft(spec.real ** 2 + spec.imag ** 2, 2 * segment)[:segment]
    r = r / r[0]
    r.setflags(write=False)
    return r


class _Model:
    """The leakage-aware one-mode model on a set of bins (see the module notes)."""

    def __init__(self, freqs: np.ndarray, bins: np.ndarray, fs: float, segment: int | None,
                 window: str):
        self.freqs = freqs[bins]
        self.bins = bins
        self.fs = fs
        self.segment = segment
        self.rho = lag_window(window, segment) if segment else None
        self.tau = np.arange(segment, dtype=np.float64) if segment else None
        centre = 0.5 * (self.freqs[0] + self.freqs[-1])
        half = max(0.5 * (self.freqs[-1] - self.freqs[0]), 1e-300)
        self.slope = (self.freqs - centre) / half
        self.theta = 2.0 * math.pi * self.freqs / fs

    def log_pole(self, fn: float, zeta: float) -> complex:
        """s / fs, the logarithm of the discrete pole z."""
        wn = 2.0 * math.pi * fn
        return complex(-zeta * wn, wn * math.sqrt(1.0 - zeta * zeta)) / self.fs

    def mode(self, fn: float, zeta: float) -> np.ndarray:
        """Two complex columns of one mode: its response to a real and an imaginary residue."""
        u = self.log_pole(fn, zeta)
        if self.rho is None:
            e = np.exp(-1j * self.theta)
            z = complex(np.exp(u))
            g1 = 1.0 / (1.0 - z * e)
            g2 = 1.0 / (1.0 - z.conjugate() * e)
        else:
            n = self.segment
            full = sfft.fft(self.rho * np.exp(u * self.tau), workers=FFT_WORKERS)
            g1 = full[self.bins]
            g2 = np.conj(full[(-self.bins) % n])
        return np.column_stack([g1 + g2, 1j * (g1 - g2)])

    def basis(self, p: np.ndarray) -> np.ndarray:
        """Complex columns of the modes ``p = [f_1, log zeta_1, f_2, ...]`` and the background
        ``d0 + d1 (f - f_c)``."""
        one = np.ones(self.freqs.size, dtype=np.complex128)
        cols = [self.mode(p[i], math.exp(p[i + 1])) for i in range(0, len(p), 2)]
        cols.append(np.column_stack([one, 1j * one, self.slope + 0j, 1j * self.slope]))
        return np.hstack(cols)


def _stack(a: np.ndarray) -> np.ndarray:
    return np.concatenate([a.real, a.imag], axis=0)


def _residual(basis: np.ndarray, h: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Weighted residual (real vector) of the best residues and background for a basis."""
    a = _stack(basis * weights[:, None])
    y = _stack(h * weights)
    coef, *_ = np.linalg.lstsq(a, y, rcond=None)
    return a @ coef - y


def _fit(model: _Model, h: np.ndarray, weights: np.ndarray, starts: list[tuple[float, float]],
         f_bounds: list[tuple[float, float]]) -> Any:
    """Least-squares fit of the modes from their starts (f, zeta); each mode's zeta is first
    chosen on a grid, the others held at their starts, then all are refined together."""
    def inside(z: float) -> float:
        # (a start from a half-power band as wide as the peak's frequency is no damping ratio
        # the model can take: its pole needs zeta < 1)
        return math.log(min(max(z, 2 * _ZETA_BOUNDS[0]), 0.5 * _ZETA_BOUNDS[1]))

    p = np.array([v for f, z in starts for v in (f, inside(z))], dtype=np.float64)
    for i in range(0, p.size, 2):
        best = None
        for z in [math.exp(p[i + 1])] + list(np.geomspace(1e-5, 0.3, 14)):
            q = p.copy()
            q[i + 1] = inside(z)
            r = _residual(model.basis(q), h, weights)
            cost = float(r @ r)
            if best is None or cost < best[0]:
                best = (cost, q[i + 1])
        p[i + 1] = best[1]
    lo = [v for b in f_bounds for v in (b[0], math.log(_ZETA_BOUNDS[0]))]
    hi = [v for b in f_bounds for v in (b[1], math.log(_ZETA_BOUNDS[1]))]
    p = np.clip(p, lo, hi)
    df = model.freqs[1] - model.freqs[0]
    return sopt.least_squares(lambda q: _residual(model.basis(q), h, weights), p,
                              bounds=(lo, hi), x_scale=[df, 1.0] * (p.size // 2),
                              xtol=1e-10, ftol=1e-12, max_nfev=100 * p.size)


def _one_step(model: _Model, cases: list[tuple[np.ndarray, np.ndarray]], p: np.ndarray
              ) -> np.ndarray:
    """Parameters of each (h, weights) case after one Gauss-Newton step from ``p``.

    The bases at ``p`` and its finite-difference neighbours are shared by every case (the
    one-step jackknife: each left-out replicate is one Newton step from the full fit).
    """
    df = model.freqs[1] - model.freqs[0]
    steps = np.array([1e-3 * df, 1e-4] * (p.size // 2))
    bases = [model.basis(p)]
    for j in range(p.size):
        q = p.copy()
        q[j] += steps[j]
        bases.append(model.basis(q))
    out = []
    for h, weights in cases:
        res = [_residual(b, h, weights) for b in bases]
        jac = np.column_stack([(r - res[0]) / steps[j] for j, r in enumerate(res[1:])])
        delta, *_ = np.linalg.lstsq(jac, -res[0], rcond=None)
        out.append(p + delta)
    return np.array(out)


def _weights(h: np.ndarray, coh: np.ndarray | None) -> np.ndarray:
    """Inverse standard error of H1 per bin, up to a constant (Bendat & Piersol Eq. 9.90)."""
    mag = np.maximum(np.abs(h), 1e-300 + 1e-12 * float(np.max(np.abs(h))))
    if coh is None:
        return 1.0 / mag
    c = np.clip(coh, 1e-6, 1.0)
    return np.sqrt(c / np.maximum(1.0 - c, 1e-4)) / mag


def _coherence(sxx: np.ndarray, syy: np.ndarray | None, sxy: np.ndarray) -> np.ndarray | None:
    if syy is None:
        return None
    return np.abs(sxy) ** 2 / np.maximum(sxx * syy, 1e-300)


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


def modal_fit(frequency: Any, sxy: Any, sxx: Any, f_peak: float, *, fs: float,
              segment: int | None = None, window: str = "hann", syy: Any = None,
              counts: Any = None, neighbours_hz: Any = (),
              band_hz: tuple[float, float] | None = None, _func: str = "modal_fit") -> ModalFit:
    """Fit one mode (natural frequency and damping ratio) to the FRF peak near ``f_peak``.

    Parameters
    ----------
    frequency
        Uniform frequency grid from 0 Hz, step fs / segment when ``segment`` is given.
    sxy, sxx
        Cross spectrum conj(X) Y and input auto spectrum on that grid, 1-D, or 2-D of shape
        (groups, bins) for groups of segments (their mean weighted by ``counts`` is the
        estimate; each is left out in turn for the jackknife interval). The FRF is
        ``sxy / sxx`` (H1), in the response's unit per input unit; for an FRF given directly,
        pass it as ``sxy`` with ``sxx`` = 1.
    f_peak
        Frequency of the peak of |H|, Hz.
    fs
        Sample rate, Hz.
    segment
        Samples per Welch segment of the estimate: its leakage is modelled (see the module
        notes). None for an FRF that is not a windowed estimate.
    window
        The segments' window (:func:`scipy.signal.get_window` name).
    syy
        Output auto spectrum, same shape as ``sxx``: the coherence weights the bins. Without
        it every bin has the same relative weight.
    counts
        Segments in each group (default: equal).
    neighbours_hz
        Frequencies of the other peaks, Hz: those inside this peak's band are fitted with it
        (their poles and residues are part of the model; only this peak's mode is returned).
    band_hz
        Limits the fitted band, Hz.

    Returns
    -------
    ModalFit
        NaN values with a warning saying why when the peak cannot be fitted.

    Raises
    ------
    AnalysisError
        Arrays of different shapes, a grid that is not uniform from 0, a peak outside it.

    Examples
    --------
    A mode at 10 Hz with 1 % damping, its FRF given directly (no Welch estimate):

    >>> import numpy as np
    >>> fs = 100.0
    >>> f = np.arange(0, 50.0, 0.05)
    >>> w, wn = 2 * np.pi * f, 2 * np.pi * 10.0
    >>> h = 1.0 / (wn ** 2 - w ** 2 + 2j * 0.01 * wn * w)
    >>> fit = modal_fit(f, h, np.ones_like(f), 10.0, fs=fs)
    >>> round(fit.frequency_hz, 2), round(fit.damping_ratio, 3)
    (10.0, 0.01)
    """
    f = np.asarray(frequency, dtype=np.float64)
    pxy = np.atleast_2d(np.asarray(sxy, dtype=np.complex128))
    pxx = np.atleast_2d(np.asarray(sxx, dtype=np.float64))
    pyy = None if syy is None else np.atleast_2d(np.asarray(syy, dtype=np.float64))
    if f.ndim != 1 or f.size < MIN_BAND_BINS or pxy.shape[-1] != f.size \
            or pxx.shape != pxy.shape or (pyy is not None and pyy.shape != pxy.shape):
        raise fail(_func, f"frequency {f.shape}, sxy {pxy.shape}, sxx {pxx.shape} must be a grid "
                          f"of at least {MIN_BAND_BINS} bins and spectra on it of one shape")
    df = float(f[1] - f[0])
    if df <= 0 or abs(f[0]) > 1e-9 * df or np.max(np.abs(np.diff(f) - df)) > 1e-6 * df:
        raise fail(_func, "frequency must be a uniform grid starting at 0 Hz")
    if segment is not None and abs(df * segment - fs) > 1e-6 * fs:
        raise fail(_func, f"the grid step {df:g} Hz is not fs / segment = {fs / segment:g} Hz")
    if not (f[1] <= f_peak <= f[-2]):
        raise fail(_func, f"peak {f_peak:g} Hz is outside the grid's inner bins "
                          f"({f[1]:g} to {f[-2]:g} Hz)")
    groups = pxy.shape[0]
    w_groups = np.ones(groups) if counts is None else np.asarray(counts, dtype=np.float64)

    def spectra(leave_out: int | None = None, cols=slice(None)):
        wg = w_groups.copy()
        if leave_out is not None:
            wg[leave_out] = 0.0
        wg /= wg.sum()
        yy = None if pyy is None else wg @ pyy[:, cols]
        return wg @ pxy[:, cols], wg @ pxx[:, cols], yy

    txy, txx, tyy = spectra()
    h = txy / np.where(txx > 0, txx, 1e-300)
    mag = np.abs(h)
    k = int(round(f_peak / df))
    lo_k, hi_k = max(k - 1, 1), min(k + 2, f.size - 1)
    k = lo_k + int(np.argmax(mag[lo_k:hi_k]))
    peak = float(f_peak)
    nan2 = (math.nan, math.nan)

    def failed(reason: str, band=nan2) -> ModalFit:
        return ModalFit(math.nan, nan2, math.nan, nan2, peak, band, math.nan, "",
                        (f"peak at {peak:.4g} Hz: {reason}",))

    # The band: +-4 half-power half-widths (at least +-6 bins), within band_hz.
    zeta_hp = half_power_damping(f, mag, float(f[k]))
    half = max(zeta_hp * f[k] if math.isfinite(zeta_hp) else df, df)
    width = max(6, int(math.ceil(4.0 * half / df)))
    lo = max(1, k - width)
    hi = min(f.size - 2, k + width)
    if band_hz is not None:
        lo = max(lo, int(math.ceil(band_hz[0] / df)))
        hi = min(hi, int(math.floor(band_hz[1] / df)))
    # Peaks of neighbouring modes near the band (their leakage reaches into it) are fitted
    # with it, the band widened to hold their peaks.
    reach = (hi - lo) * df
    others = sorted(float(v) for v in neighbours_hz
                    if f[lo] - reach <= v <= f[hi] + reach and abs(v - f[k]) > 1.5 * df)
    if others:
        lo = max(1, min(lo, int(math.floor(others[0] / df)) - 3))
        hi = min(f.size - 2, max(hi, int(math.ceil(others[-1] / df)) + 3))
        if band_hz is not None:
            lo = max(lo, int(math.ceil(band_hz[0] / df)))
            hi = min(hi, int(math.floor(band_hz[1] / df)))
        others = [v for v in others if f[lo] <= v <= f[hi]]
    band = (float(f[lo]), float(f[hi]))
    if hi - lo + 1 < MIN_BAND_BINS + 4 * len(others):
        return failed(f"only {hi - lo + 1} bins in the band (the fit needs "
                      f"{MIN_BAND_BINS + 4 * len(others)}): a finer resolution (a longer "
                      "segment) would resolve it", band)
    bins = np.arange(lo, hi + 1)
    model = _Model(f, bins, fs, segment, window)
    centres = [float(f[k])] + others
    f_bounds = []
    for i in range(len(centres)):
        below = [c for c in centres if c < centres[i]]
        above = [c for c in centres if c > centres[i]]
        f_bounds.append((0.5 * (max(below) + centres[i]) if below else float(f[lo]),
                         0.5 * (min(above) + centres[i]) if above else float(f[hi])))
    starts = [(float(f[k]), zeta_hp if math.isfinite(zeta_hp) else 2.0 * df / f[k])]
    starts += [(c, 2.0 * df / c) for c in others]

    def case(leave_out=None):
        sxy_g, sxx_g, syy_g = spectra(leave_out, bins)
        hg = sxy_g / np.where(sxx_g > 0, sxx_g, 1e-300)
        return hg, _weights(hg, _coherence(sxx_g, syy_g, sxy_g))

    res = _fit(model, *case(), starts, f_bounds)
    p = res.x
    fn, zeta = float(p[0]), float(math.exp(p[1]))
    warnings = []
    if zeta >= 0.99 * _ZETA_BOUNDS[1] or fn <= f_bounds[0][0] + 1e-6 * df \
            or fn >= f_bounds[0][1] - 1e-6 * df:
        return failed(f"the modal fit ran to the edge of its search (f_n {fn:.4g} Hz, zeta "
                      f"{zeta:.3g}): no single mode describes this peak", band)
    if zeta <= 1.01 * _ZETA_BOUNDS[0]:
        # The peak is narrower than anything the leakage model can tell apart from zero
        # damping: its frequency stands, its damping ratio is not measurable here.
        text = (f"peak at {fn:.4g} Hz: the damping ratio is not resolved at the resolution "
                f"{df:.3g} Hz (the fit runs to zeta -> 0: the peak is narrower than a bin)")
        if segment:
            text += f"; longer segments (at least {4 * segment} samples) may resolve it"
        return ModalFit(fn, nan2, math.nan, nan2, peak, band, math.nan, "", (text,))
    interval = ""
    f_ci = z_ci = nan2
    se = np.array([math.nan, math.nan])
    q = math.nan
    if groups >= MIN_GROUPS:
        reps = _one_step(model, [case(g) for g in range(groups)], p)[:, :2]
        if np.all(np.isfinite(reps)):
            se = np.sqrt((groups - 1) / groups * np.sum((reps - reps.mean(axis=0)) ** 2, axis=0))
            q = float(sstats.t.ppf(0.975, groups - 1))
            interval = "jackknife"
    else:
        dof = max(res.fun.size - p.size - 2 * len(starts) - 4, 1)
        s2 = float(res.fun @ res.fun) / dof
        try:
            cov = np.linalg.inv(res.jac.T @ res.jac) * s2
            se = np.sqrt(np.maximum(np.diag(cov)[:2], 0.0))
            q = float(sstats.t.ppf(0.975, dof))
            interval = "least-squares"
            warnings.append(f"peak at {fn:.4g} Hz: {groups} group(s) of segments, too few for "
                            f"a jackknife ({MIN_GROUPS} needed): the intervals are the least-"
                            "squares ones, which take neighbouring bins as independent and are "
                            "too narrow for a windowed estimate")
        except np.linalg.LinAlgError:
            pass
    if interval:
        f_ci = (fn - q * se[0], fn + q * se[0])
        spread = q * float(se[1])       # (of log zeta: beyond 700 its exp overflows)
        z_ci = (zeta * math.exp(-spread), zeta * math.exp(spread)) if spread < 700.0 \
            else (0.0, math.inf)
    else:
        warnings.append(f"peak at {fn:.4g} Hz: no interval could be computed")
    bins_across = 2.0 * zeta * fn / df
    if bins_across < HALF_POWER_MIN_BINS:
        need = 2 ** int(math.ceil(math.log2(HALF_POWER_MIN_BINS * fs / (2.0 * zeta * fn))))
        text = (f"peak at {fn:.4g} Hz: the resolution {df:.3g} Hz puts {bins_across:.3g} bins "
                f"across the half-power band of a damping ratio {zeta:.3g}, fewer than "
                f"{HALF_POWER_MIN_BINS:g}: the half-power estimate is not usable there; the "
                "modal fit's value rests on the model of the window's leakage")
        if segment:
            text += f" (segments of {need} samples or more would resolve the band)"
        warnings.append(text)
    if interval and not z_ci[1] / zeta <= RESOLVED_FACTOR:
        warnings.append(f"peak at {fn:.4g} Hz: the damping ratio is not resolved (95 %: "
                        f"{z_ci[0]:.3g} to {z_ci[1]:.3g})")
    coh = _coherence(txx, tyy, txy)
    if coh is not None and coh[k] < 0.5:
        warnings.append(f"peak at {fn:.4g} Hz: coherence {coh[k]:.2f} at the peak: the response "
                        "there is mostly not explained by the reference (noise, another input "
                        "or a nonlinearity)")
    return ModalFit(fn, f_ci, zeta, z_ci, peak, band, bins_across, interval, tuple(warnings))
