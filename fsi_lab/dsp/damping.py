"""Damping ratio against amplitude from the extrema of a free decay.

The envelope is written as ``A(t) = A_0 exp(-zeta(t) 2 pi f(t) t)`` (the paper's Eq. 4), so
``zeta = -(d ln A / dt) / (2 pi f)`` with f the measured (damped) instantaneous frequency. Four
estimators:

``"decrement"`` (default, unbiased)
    Successive-peak logarithmic decrement over ``span`` extrema (default 2: one full period,
    between extrema of the same sign, so an offset cancels to first order):
    ``zeta_k = ln(A_k / A_{k+span}) / (2 pi f (t_{k+span} - t_k))``, at the logarithmic mean
    amplitude of the pair. On a linear + quadratic damping law this recovers the local decay
    rate ``a + b A`` to second order in the decrement.
``"envelope-fit"`` (unbiased for linear + quadratic damping)
    Least-squares fit of ln A to the closed-form envelope of ``dA/dt = -a A - b A^2``:
    ``A(t) = a A0 e^{-a t} / (a + b A0 (1 - e^{-a t}))``; then ``zeta = (a + b A) / (2 pi f)``.
``"eq5"`` (the paper's Eq. 5)
    Regression of ln A on ``2 pi f t`` over a sliding window of ``window`` extrema (time counted
    from the window start); the slope is ``-zeta``.
``"eq7"`` (the paper's Eq. 7)
    One cubic polynomial in t fitted to ln A over the whole decay,
    ``zeta(t) = (3 k1 t^2 + 2 k2 t + k3) / (2 pi f)``. Biased on long decays: a cubic cannot
    follow the envelope of quadratic damping over a 30-fold decay (c1 off by about +14 %, c2 by
    -24 %); offered for comparison with the paper.

All take the extrema (times, amplitudes) and the frequency at those times, as produced by
:func:`.instantaneous.instantaneous`; :func:`damping` runs that analysis on a record first.
:func:`damping_from_peaks` also takes the free decay of each peak (a record split by
:func:`.decays.split_decays`, e.g. an impulse train): no decrement, window, cubic or moving
average then spans two decays, and the envelope law is fitted to all decays at once with one
``a`` and ``b`` and a starting amplitude per decay (decays of fewer than ``MIN_FIT_PEAKS`` (3)
peaks left out of the fit: their start amplitude would absorb them).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.optimize as sopt

from fsi_lab.dsp._signal import fail
from fsi_lab.dsp.choices import DAMPING_METHODS as METHODS
from fsi_lab.dsp.decays import FreeDecays, decay_runs, smooth_per_decay
from fsi_lab.dsp.instantaneous import instantaneous
from fsi_lab.errors import AnalysisError


@dataclass(frozen=True)
class DampingCurve:
    """Damping ratio against amplitude, in time order.

    Attributes
    ----------
    time
        Time of each estimate, s.
    amplitude
        Amplitude at which the estimate holds, unit of the record.
    zeta
        Damping ratio (dimensionless).
    frequency
        Instantaneous frequency there, Hz.
    decay_rate
        ``zeta * 2 pi f = -d ln A / dt``, 1/s.
    method
        Estimator used.
    params
        Fitted parameters of ``"envelope-fit"`` (``a`` in 1/s, ``b`` in 1/(unit s), ``A0``) or
        ``"eq7"`` (``k1``, ``k2``, ``k3``, ``lnA0``); empty otherwise. With several decays,
        ``A0`` and the ``"eq7"`` parameters are those of the first decay.
    decay
        Index of the free decay of each estimate (all 0 for a single decay), or None.
    decays
        The free decays the peaks were taken from (:func:`.damping.curve_for`), or None.
    """

    time: np.ndarray
    amplitude: np.ndarray
    zeta: np.ndarray
    frequency: np.ndarray
    decay_rate: np.ndarray
    method: str
    params: dict[str, float] = field(default_factory=dict)
    decay: np.ndarray | None = None
    decays: FreeDecays | None = None


def _check(t: Any, amp: Any, freq: Any, func: str, need: int
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.asarray(t, dtype=np.float64)
    a = np.asarray(amp, dtype=np.float64)
    f = np.broadcast_to(np.asarray(freq, dtype=np.float64), t.shape).copy() \
        if np.ndim(freq) == 0 else np.asarray(freq, dtype=np.float64)
    if t.ndim != 1 or a.shape != t.shape or f.shape != t.shape:
        raise fail(func, f"times {t.shape}, amplitudes {a.shape} and frequencies {f.shape} must "
                         "be 1-D arrays of the same length")
    if t.size < need:
        raise fail(func, f"{t.size} peak(s) given; the method needs at least {need} peaks - "
                         "a longer decay, a lower min_amplitude or another method")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(a)) and np.all(np.isfinite(f))):
        raise fail(func, "peak times, amplitudes or frequencies contain NaN or inf")
    if np.any(a <= 0):
        raise fail(func, "peak amplitudes must be > 0 (give |extremum| values)")
    if np.any(f <= 0):
        raise fail(func, "frequencies must be > 0 Hz")
    if np.any(np.diff(t) <= 0):
        raise fail(func, "peak times must increase strictly")
    return t, np.abs(a), f


def _curve(t, amp, rate, f, method, params=None) -> DampingCurve:
    return DampingCurve(time=t, amplitude=amp, zeta=rate / (2.0 * math.pi * f), frequency=f,
                        decay_rate=rate, method=method, params=dict(params or {}))


def damping_decrement(t: Any, amp: Any, freq: Any, *, span: int = 2) -> DampingCurve:
    """Successive-peak logarithmic decrement (unbiased default).

    Parameters
    ----------
    t
        Extremum times, s, increasing.
    amp
        Extremum amplitudes (> 0), unit U.
    freq
        Instantaneous frequency at those times, Hz (array or one value).
    span
        Number of extrema between the two peaks of each decrement (2: one period).

    Returns
    -------
    DampingCurve
        One estimate per pair (k, k + span): time and amplitude at the midpoint (logarithmic
        mean amplitude), frequency averaged over the pair.
    """
    func = "damping (decrement)"
    if isinstance(span, bool) or not isinstance(span, (int, np.integer)) or span < 1:
        raise fail(func, f"span = {span!r}; expected an integer >= 1")
    t, a, f = _check(t, amp, freq, func, span + 2)
    la = np.log(a)
    d = la[:-span] - la[span:]
    dt = t[span:] - t[:-span]
    rate = d / dt
    # Logarithmic mean (exact mean amplitude of an exponential between the two peaks).
    with np.errstate(divide="ignore", invalid="ignore"):
        lmean = np.where(np.abs(d) > 1e-12, (a[:-span] - a[span:]) / d, a[:-span])
    fm = 0.5 * (f[:-span] + f[span:])
    return _curve(0.5 * (t[:-span] + t[span:]), lmean, rate, fm, "decrement")


def envelope_law(t: np.ndarray, a: float, b: float, a0: float) -> np.ndarray:
    """Envelope of dA/dt = -a A - b A^2 from A(0) = a0:
    ``a a0 e^{-a t} / (a + b a0 (1 - e^{-a t}))`` (``a0 / (1 + b a0 t)`` when a = 0)."""
    e = np.exp(-a * t)
    if abs(a) < 1e-12:
        return a0 / (1.0 + b * a0 * t)
    return a * a0 * e / (a + b * a0 * (1.0 - e))


def envelope_law_derivatives(t: np.ndarray, a: float, b: float, a0: Any) -> np.ndarray:
    """Derivatives of :func:`envelope_law` at times ``t`` (s) with respect to ``a`` (U s),
    ``b`` (U^2 s) and ``a0`` (dimensionless), as the columns of a ``(t.size, 3)`` array;
    ``a0`` (U) one value or one per time. Where the law takes its ``a = 0`` form, the
    derivative in ``a`` is its limit at ``a -> 0``."""
    t = np.asarray(t, dtype=np.float64)
    if abs(a) < 1e-12:
        g = 1.0 + b * a0 * t
        return np.stack((-a0 * (t + 0.5 * b * a0 * t * t) / (g * g), -a0 * a0 * t / (g * g),
                         1.0 / (g * g)), axis=1)
    u = a * t
    e = np.exp(-u)
    one_e = -np.expm1(-u)
    # 1 - e^-u - u without cancellation at small u (the derivative in a is of order a^2 / a^2).
    small = np.abs(u) < 1e-3
    us = np.where(small, u, 0.0)
    rest = np.where(small, -us * us * (0.5 - us * (1.0 / 6.0 - us * (1.0 / 24.0 - us / 120.0))),
                    one_e - u)
    d = a + b * a0 * one_e
    d2 = d * d
    da = a0 * e * (b * a0 * rest - a * u) / d2
    db = -a * a0 * a0 * e * one_e / d2
    d0 = a * a * e / d2
    return np.stack((da, db, d0), axis=1)


#: Fewest peaks of a free decay for the envelope-law fit to use it: each decay brings its own
#: start amplitude, so a decay of one peak says nothing of the decay rate and one of two peaks
#: (often the smear of the excitation) little.
MIN_FIT_PEAKS = 3


def damping_envelope_fit(t: Any, amp: Any, freq: Any, *, decay: Any = None) -> DampingCurve:
    """Fit the linear + quadratic damping envelope law to the peaks (unbiased for that law).

    ``A(t)`` is fitted to the peak amplitudes by least squares with ``a >= 0``, ``b >= 0``; the
    curve is then ``zeta = (a + b A) / (2 pi f)`` at every peak (A the fitted envelope).

    Parameters
    ----------
    t
        Extremum times, s, increasing.
    amp
        Extremum amplitudes (> 0), unit U.
    freq
        Instantaneous frequency at those times, Hz (array or one value).
    decay
        Optional free decay of each peak (an index constant over each decay): the law is fitted
        to every decay of at least :data:`MIN_FIT_PEAKS` peaks at once, with common ``a`` and
        ``b`` and a start amplitude per decay (time counted from each decay's first peak). The
        shorter decays are left out of the fit; their peaks get the law with ``a`` and ``b``
        fitted and their own start amplitude.

    Returns
    -------
    DampingCurve
        One estimate per peak. ``params`` holds ``a`` (1/s), ``b`` (1/(U s)), ``A0`` (U, of the
        first decay fitted), their standard errors ``a_se``, ``b_se`` and the degrees of
        freedom ``dof`` (peaks fitted minus parameters).

    Raises
    ------
    AnalysisError
        Bad peaks (shapes, NaN or inf, amplitudes or frequencies <= 0, times not increasing,
        fewer than 4 peaks), or no more peaks in the decays fitted than parameters (a, b and a
        start amplitude per decay).
    """
    func = "damping (envelope-fit)"
    t, amp_, f = _check(t, amp, freq, func, 4)
    runs = decay_runs(decay, t.size, func)
    fitted = [r for r in runs if r.stop - r.start >= MIN_FIT_PEAKS]
    points = sum(r.stop - r.start for r in fitted)
    if 2 + len(fitted) >= points:
        raise fail(func, f"{len(fitted)} of {len(runs)} free decays have {MIN_FIT_PEAKS} peaks or "
                         f"more ({points} peaks) for {2 + len(fitted)} parameters (a, b and a "
                         "start amplitude per decay); the fit needs more peaks than parameters "
                         "- longer decays, a lower min_amplitude or the decrement method")
    tt = t - t[np.concatenate([np.full(r.stop - r.start, r.start) for r in runs])]
    a, b, la0, se, dof = _fit_law(tt, amp_, fitted)
    env = np.empty_like(amp_)
    for r, la0_r in zip(fitted, la0):
        env[r] = envelope_law(tt[r], a, b, math.exp(la0_r))
    for r in runs:
        if r.stop - r.start < MIN_FIT_PEAKS:
            env[r] = envelope_law(tt[r], a, b, _start_amplitude(tt[r], amp_[r], a, b))
    return _curve(t, env, a + b * env, f, "envelope-fit",
                  {"a": float(a), "b": float(b), "A0": float(math.exp(la0[0])),
                   "a_se": float(se[0]), "b_se": float(se[1]), "dof": float(dof)})


def _fit_law(tt: np.ndarray, amp: np.ndarray, runs: list[slice]
             ) -> tuple[float, float, np.ndarray, np.ndarray, int]:
    """Least-squares fit of :func:`envelope_law` to the peaks ``amp`` (U) at times ``tt`` (s
    from each decay's first peak) of the decays ``runs``, common ``a`` and ``b``: returns
    a (1/s), b (1/(U s)), ln A0 of each run, the standard errors of a and b, and the degrees
    of freedom."""
    k = len(runs)
    tt = np.concatenate([tt[r] for r in runs])
    amp = np.concatenate([amp[r] for r in runs])
    which = np.repeat(np.arange(k), [r.stop - r.start for r in runs])
    first = np.concatenate(([0], np.cumsum([r.stop - r.start for r in runs])[:-1]))
    la = np.log(amp)
    # Start: straight line in ln A (b = 0), one intercept per decay. Residuals in amplitude (not
    # ln A): additive noise on the record gives peaks with equal absolute scatter, so this is
    # the efficient fit.
    dt = tt - (np.bincount(which, tt) / np.bincount(which))[which]
    dl = la - (np.bincount(which, la) / np.bincount(which))[which]
    slope = -float(dt @ dl) / max(float(dt @ dt), 1e-300)
    x0 = np.array([max(slope, 1e-6), 1e-6 / max(amp[0], 1e-300), *la[first]])
    scale = float(amp.max())

    def resid(p):
        return (envelope_law(tt, p[0], p[1], np.exp(p[2:][which])) - amp) / scale

    def jac(p):
        a0 = np.exp(p[2:][which])
        d = envelope_law_derivatives(tt, p[0], p[1], a0)
        out = np.zeros((tt.size, 2 + k))
        out[:, :2] = d[:, :2]
        out[np.arange(tt.size), 2 + which] = d[:, 2] * a0
        return out / scale

    res = sopt.least_squares(resid, x0, jac=jac,
                             bounds=([0.0, 0.0] + [-np.inf] * k, [np.inf] * (2 + k)),
                             x_scale="jac", xtol=1e-14, ftol=1e-14, gtol=1e-14, max_nfev=2000)
    dof = tt.size - 2 - k
    s2 = float(res.fun @ res.fun) / dof
    try:
        se = np.sqrt(np.maximum(np.diag(np.linalg.inv(res.jac.T @ res.jac) * s2), 0.0))
    except np.linalg.LinAlgError:
        se = np.full(2 + k, np.nan)
    return float(res.x[0]), float(res.x[1]), res.x[2:], se, dof


def _start_amplitude(tt: np.ndarray, amp: np.ndarray, a: float, b: float) -> float:
    """Start amplitude (U) of :func:`envelope_law` with ``a`` (1/s) and ``b`` (1/(U s)) given
    that fits the peaks ``amp`` (U) at ``tt`` (s) by least squares."""
    scale = float(amp.max())
    res = sopt.least_squares(lambda p: (envelope_law(tt, a, b, math.exp(p[0])) - amp) / scale,
                             [math.log(amp[0])], xtol=1e-14, ftol=1e-14, gtol=1e-14)
    return math.exp(float(res.x[0]))


def damping_eq5(t: Any, amp: Any, freq: Any, *, window: int = 6) -> DampingCurve:
    """The paper's Eq. 5 on a sliding window of ``window`` extrema.

    In each window, ln A is regressed on ``2 pi f(t) (t - t_start)``; ``-slope`` is zeta. The
    estimate is placed at the window's mean time, at the geometric mean amplitude.
    """
    func = "damping (eq5)"
    if isinstance(window, bool) or not isinstance(window, (int, np.integer)) or window < 3:
        raise fail(func, f"window = {window!r}; expected an integer >= 3 (peaks per window)")
    t, a, f = _check(t, amp, freq, func, window)
    la = np.log(a)
    n = t.size - window + 1
    idx = np.arange(window)[None, :] + np.arange(n)[:, None]
    tw = t[idx]
    xw = 2.0 * math.pi * f[idx] * (tw - tw[:, :1])
    yw = la[idx]
    xm = xw.mean(axis=1, keepdims=True)
    ym = yw.mean(axis=1, keepdims=True)
    slope = np.sum((xw - xm) * (yw - ym), axis=1) / np.sum((xw - xm) ** 2, axis=1)
    zeta = -slope
    fm = f[idx].mean(axis=1)
    return DampingCurve(time=tw.mean(axis=1), amplitude=np.exp(ym[:, 0]), zeta=zeta,
                        frequency=fm, decay_rate=zeta * 2.0 * math.pi * fm, method="eq5")


def damping_eq7(t: Any, amp: Any, freq: Any) -> DampingCurve:
    """The paper's Eq. 7: ln A = -(k1 t^3 + k2 t^2 + k3 t) + ln A0 over the whole decay.

    Biased on long decays (see the module notes); the curve is evaluated at every peak with the
    fitted (smooth) amplitude.
    """
    func = "damping (eq7)"
    t, a, f = _check(t, amp, freq, func, 5)
    t0 = t[0]
    tt = t - t0
    scale = tt[-1] if tt[-1] > 0 else 1.0
    u = tt / scale
    design = np.stack((u ** 3, u ** 2, u, np.ones_like(u)), axis=1)
    coef, *_ = np.linalg.lstsq(design, np.log(a), rcond=None)
    k1, k2, k3 = -coef[0] / scale ** 3, -coef[1] / scale ** 2, -coef[2] / scale
    rate = 3 * k1 * tt ** 2 + 2 * k2 * tt + k3
    fitted = np.exp(coef[3] - (k1 * tt ** 3 + k2 * tt ** 2 + k3 * tt))
    return _curve(t, fitted, rate, f, "eq7",
                  {"k1": float(k1), "k2": float(k2), "k3": float(k3), "lnA0": float(coef[3]),
                   "t0": float(t0)})


def _one_decay(t, amp, freq, method, span, window) -> DampingCurve:
    if method == "decrement":
        return damping_decrement(t, amp, freq, span=span)
    if method == "envelope-fit":
        return damping_envelope_fit(t, amp, freq)
    if method == "eq5":
        return damping_eq5(t, amp, freq, window=window)
    return damping_eq7(t, amp, freq)


def _concatenate(curves: list[tuple[int, DampingCurve]]) -> DampingCurve:
    """One curve from per-decay curves (in time order), ``decay`` set; parameters of the first."""
    names = ("time", "amplitude", "zeta", "frequency", "decay_rate")
    parts = {n: np.concatenate([getattr(c, n) for _, c in curves]) for n in names}
    decay = np.concatenate([np.full(c.time.size, k) for k, c in curves])
    return DampingCurve(**parts, method=curves[0][1].method, params=curves[0][1].params,
                        decay=decay)


def damping_from_peaks(t: Any, amp: Any, freq: Any, *, method: str = "decrement",
                       span: int = 2, window: int = 6, smooth: int = 0, decay: Any = None
                       ) -> DampingCurve:
    """Damping curve from extrema by one of :data:`METHODS` (see the module notes).

    ``smooth`` > 0 applies the paper's centred moving average (``smooth`` points each side) to
    zeta and ln(amplitude) of the resulting curve.

    ``decay`` (optional): the free decay of each peak, an index constant over each decay (from
    :meth:`.decays.FreeDecays.labels`). Each decay is then analysed on its own, a decay with
    too few peaks for the method is left out, the moving average stays within each decay, and
    the curves are concatenated in time order with ``decay`` set. The envelope law is fitted to
    all decays of at least :data:`MIN_FIT_PEAKS` peaks with common ``a`` and ``b`` and
    evaluated at every peak (:func:`damping_envelope_fit`). Raises AnalysisError when no decay
    has enough peaks (for the envelope law: fewer peaks than parameters).
    """
    if method not in METHODS:
        raise fail("damping", f"method = {method!r}; expected one of {', '.join(METHODS)}")
    runs = decay_runs(decay, np.size(t), "damping")
    if len(runs) == 1:
        curve = _one_decay(t, amp, freq, method, span, window)
        ids = np.asarray(decay)[:1] if decay is not None and np.size(decay) else np.zeros(1)
        curve = dataclasses.replace(curve, decay=np.full(curve.time.size, int(ids[0])))
    elif method == "envelope-fit":
        curve = damping_envelope_fit(t, amp, freq, decay=decay)
        curve = dataclasses.replace(curve, decay=np.asarray(decay, dtype=np.int64).copy())
    else:
        t_, a_, f_ = (np.asarray(v, dtype=np.float64) for v in (t, amp, freq))
        f_ = np.broadcast_to(f_, t_.shape)
        d_ = np.asarray(decay, dtype=np.int64)
        curves, refused = [], []
        for r in runs:
            try:
                curves.append((int(d_[r.start]),
                               _one_decay(t_[r], a_[r], f_[r], method, span, window)))
            except AnalysisError as exc:
                refused.append(str(exc))
        if not curves:
            raise fail("damping", f"no free decay has enough peaks ({len(runs)} decays): "
                                  f"{refused[0]}")
        curve = _concatenate(curves)
    if smooth:
        zeta = smooth_per_decay(curve.zeta, curve.decay, smooth)
        amp_s = np.exp(smooth_per_decay(np.log(curve.amplitude), curve.decay, smooth))
        curve = dataclasses.replace(curve, amplitude=amp_s, zeta=zeta,
                                    decay_rate=zeta * 2.0 * math.pi * curve.frequency)
    return curve


def damping(x: Any, fs: float, *, method: str = "decrement", span: int = 2, window: int = 6,
            smooth: int = 0, offset: Any = "cycles", min_amplitude: float | None = None
            ) -> DampingCurve:
    """Damping ratio against amplitude of a free decay (one component).

    Parameters
    ----------
    x
        Samples, unit U (displacement in m for the paper's damping curves), one quasi-harmonic
        decay.
    fs
        Sample rate, Hz.
    method
        One of ``"decrement"`` (default), ``"envelope-fit"``, ``"eq5"``, ``"eq7"``.
    span
        Extrema per decrement (``"decrement"``).
    window
        Extrema per regression window (``"eq5"``).
    smooth
        Moving average of the result, points each side (the paper: 5).
    offset, min_amplitude
        As for :func:`.instantaneous.instantaneous`.

    Returns
    -------
    DampingCurve
        Time (s), amplitude (U), zeta, frequency (Hz), decay rate (1/s).

    Raises
    ------
    AnalysisError
        Bad record (see :func:`.instantaneous.instantaneous`), unknown method, or fewer peaks
        than the method needs.
    """
    inst = instantaneous(x, fs, offset=offset, min_amplitude=min_amplitude)
    return damping_from_peaks(inst.peak_times, inst.peak_amplitudes, inst.peak_frequency,
                              method=method, span=span, window=window, smooth=smooth)
