"""Free decays of several modes fitted together to a record's own samples.

The extrema of a mode are measured on its band of the record (:mod:`.identify`). When two
modes lie close together, each band also holds the other's first, strongly damped cycles: the
band filters smear them, and correcting the smear with a fitted model leans on that model
(on a 17 Hz mode beside a 22 Hz one, at 1 % noise, C_i came out 37 % high with intervals that
covered the truth in a quarter of the trials). Here the modes' decays are fitted to the record
itself: the sum of each mode's free decay, integrated from a start extremum with its damping
law (:func:`.laws.simulate_decay`), against the samples, by nonlinear least squares over every
span of the record that holds free decays. Nothing is filtered, so nothing is smeared; the
largest cycles, which carry the quadratic damping, count as fully as the rest. Each span
also gets an offset and a slope of its own: a record whose mean was taken off (a decay's
velocity has a mean of minus its start displacement over the record's length) or that drifts.
Each mode's cubic stiffness is fitted as well (``stiffness``), from its guess, or held at it.

The parameters' covariance is the least-squares one for white noise, widened where the
residuals say the noise is not white: the sandwich ``A^-1 J^T S J A^-1`` (``A = J^T J``,
``S`` the residuals' covariance) with ``S`` from an autoregressive model of the residuals,
its order chosen by AIC (prewhitening, Andrews & Monahan 1992): a record reduced in rate holds
noise that its low-pass has coloured, a base accelerometer's integrated noise grows at low
frequencies. Each variance is the larger of the two.

References
----------
D. W. K. Andrews and J. C. Monahan, "An improved heteroskedasticity and autocorrelation
consistent covariance matrix estimator", Econometrica 60 (1992), 953-966.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
import scipy.fft
import scipy.linalg
import scipy.optimize as sopt

from fsi_lab.dsp._signal import check_rate, fail
from fsi_lab.dsp.laws import LAWS, OUTPUTS, QUANTITIES, simulate_decay

#: Highest order of the autoregressive model of the residuals (:func:`_noise_spectrum`).
AR_ORDER = 12
#: Most evaluations of the residuals by the least squares.
MAX_EVALUATIONS = 60
#: Relative step of the forward differences (of each parameter's typical size).
DIFF_STEP = 1e-6
#: Evaluations over which the least squares' progress is judged (``target_rms``).
PROGRESS_WINDOW = 8
#: How far above ``target_rms`` (in RMS) the fit's projected end may stay before it stops.
HOPELESS_FACTOR = 10.0


class _Hopeless(Exception):
    """Raised inside the least squares to stop a fit that cannot reach ``target_rms``."""


@dataclass(frozen=True)
class DecayStart:
    """Where one free decay of a mode starts: an extremum of the fitted quantity.

    Attributes
    ----------
    span
        Index of the span (of ``spans``) the decay lies in.
    value
        Signed value of the extremum, U or U/s.
    time
        Its time from the record's first sample, s.
    """

    span: int
    value: float
    time: float


@dataclass(frozen=True)
class JointMode:
    """One mode's starting guess: its law, parameters, linear angular frequency, decays and
    cubic stiffness (all fitted but the law)."""

    law: str
    params: Sequence[float]
    w0: float                               # rad/s
    decays: Sequence[DecayStart]
    alpha: float = 0.0                      # cubic stiffness, 1/(U^2 s^2)


@dataclass(frozen=True)
class JointFit:
    """The modes fitted together.

    Attributes
    ----------
    params
        Per mode: the law's parameters (order of :data:`.laws.LAWS`).
    w0
        Per mode: the linear natural angular frequency, rad/s.
    alpha
        Per mode: the cubic stiffness per unit mass, 1/(U^2 s^2).
    cov
        Per mode: covariance of ``(params..., w0, alpha)``.
    starts, times
        Per mode: each decay's fitted start extremum (signed, U or U/s) and its time, s.
    residual_rms
        RMS of the record minus the fitted decays over the spans (of their block means, with
        ``average``), in the record's unit.
    r2
        The share of the record's variance over the spans (of the same values, each span less
        its mean) that the fit explains.
    samples, dof
        Samples (block means, with ``average``) fitted, and those less the parameters fitted
        (the modes', their decays' starts and the spans' offsets and slopes).
    widening
        Per mode: the factors (>= 1) the sandwich widened the standard errors of
        ``(params..., w0, alpha)`` by over the white-noise ones.
    converged
        Whether the least squares met its tolerance within :data:`MAX_EVALUATIONS`.
    evaluations
        How many times the least squares evaluated the residuals.
    """

    params: list[np.ndarray]
    w0: np.ndarray
    alpha: np.ndarray
    cov: list[np.ndarray]
    starts: list[np.ndarray]
    times: list[np.ndarray]
    residual_rms: float
    r2: float
    samples: int
    dof: int
    widening: list[np.ndarray]
    converged: bool
    evaluations: int


def fit_decays_jointly(x: np.ndarray, fs: float, spans: Sequence[tuple[int, int]],
                       modes: Sequence[JointMode], *, quantity: str = "velocity",
                       output: str | None = None, stiffness: bool = True,
                       average: int = 1, target_rms: float | None = None) -> JointFit:
    """Fit the free decays of several modes together to a record's samples.

    Parameters
    ----------
    x
        The record, U, U/s or U/s^2 as ``output``: what the modes' decays sum to (anything
        else already taken off).
    fs
        Sample rate, Hz.
    spans
        ``(first, stop)`` sample indices of the parts of ``x`` that hold free decays only.
    modes
        Each mode's law, starting parameters and decays (:class:`JointMode`).
    quantity
        The quantity the decays' starts are extrema of: ``"velocity"`` or
        ``"displacement"``.
    output
        The record's quantity (default ``quantity``): ``"displacement"``, ``"velocity"`` or
        ``"acceleration"``.
    stiffness
        Whether each mode's cubic stiffness is fitted (else held at its guess; its variance
        is then 0).
    average
        Samples per block: the record and the model are compared as means of blocks of this
        many samples (each span cut to whole blocks), the model computed at every sample
        and averaged alike, so that nothing is biased. The least squares of a record sampled
        far above its modes then works on as many values as one sampled a few times above
        them, with the same information on the decays (the model is still computed at every
        sample); the white noise of a block mean is that of a sample over the square root of
        ``average``.
    target_rms
        The residual RMS (of the values fitted: block means with ``average``; the record's
        unit) below which the fit is of use to the caller, or None. When the least squares'
        last :data:`PROGRESS_WINDOW` evaluations, carried on at their pace to the end of its
        budget (:data:`MAX_EVALUATIONS`), would still leave the residual RMS more than
        :data:`HOPELESS_FACTOR` times above it, the fit stops there (``converged`` False)
        instead of spending its budget on a record its model does not describe (on the wet
        bench's 48 and 94 Hz modes, 35 times above after its first step, each evaluation
        gaining 0.2 %: 60 evaluations, 1.5 s).

    Returns
    -------
    JointFit

    Raises
    ------
    AnalysisError
        No span, no mode, a decay outside the spans, an unknown law or quantity, or fewer
        samples than parameters.

    Examples
    --------
    Two close modes, 17 and 22 Hz, released together:

    >>> import numpy as np
    >>> from fsi_lab.dsp.laws import simulate_decay
    >>> from fsi_lab.dsp.joint_fit import DecayStart, JointMode, fit_decays_jointly
    >>> fs = 2000.0
    >>> t = np.arange(int(2 * fs)) / fs
    >>> w1, w2 = 2 * np.pi * 17.0, 2 * np.pi * 22.0
    >>> x = (simulate_decay("quadratic", [2.0, 200.0], w1, 0.1, 0.0, t)
    ...      + simulate_decay("quadratic", [3.0, 0.0], w2, 0.05, 0.0, t))
    >>> guess = [JointMode("quadratic", [2.5, 150.0], w1 * 1.002, [DecayStart(0, 0.09, 0.0)]),
    ...          JointMode("quadratic", [2.5, 10.0], w2, [DecayStart(0, 0.05, 0.001)])]
    >>> fit = fit_decays_jointly(x, fs, [(0, x.size)], guess)
    >>> print(np.round(fit.params[0], 3), round(fit.w0[0] / (2 * np.pi), 4))
    [  2. 200.] 17.0
    """
    func = "fit_decays_jointly"
    fs = check_rate(fs, func)
    x = np.asarray(x, dtype=np.float64)
    output = quantity if output is None else output
    if quantity not in QUANTITIES:
        raise fail(func, f"quantity = {quantity!r}; expected one of {', '.join(QUANTITIES)}")
    if output not in OUTPUTS:
        raise fail(func, f"output = {output!r}; expected one of {', '.join(OUTPUTS)}")
    if isinstance(average, bool) or not isinstance(average, (int, np.integer)) or average < 1:
        raise fail(func, f"average = {average!r}; expected a whole number of samples >= 1")
    average = int(average)
    spans = [(int(a), int(b)) for a, b in spans]
    if not spans or any(not 0 <= a < b <= x.size for a, b in spans):
        raise fail(func, f"spans = {spans!r}; expected (first, stop) sample indices with "
                         f"0 <= first < stop <= {x.size}")
    spans = [(a, a + (b - a) // average * average) for a, b in spans]
    if any(b <= a for a, b in spans):
        raise fail(func, f"a span shorter than average = {average} samples; expected at least "
                         "one block in each")
    if not modes:
        raise fail(func, "no mode given; expected at least one JointMode")
    for k, m in enumerate(modes):
        if m.law not in LAWS or len(m.params) != len(LAWS[m.law]):
            raise fail(func, f"mode {k}: law {m.law!r} with {len(m.params)} parameters; "
                             f"expected one of {', '.join(LAWS)} with its parameters")
        if not m.decays or any(not 0 <= d.span < len(spans) for d in m.decays):
            raise fail(func, f"mode {k}: each decay must name one of the {len(spans)} spans")
    def blocks(v: np.ndarray) -> np.ndarray:
        return v.reshape(-1, average).mean(axis=1) if average > 1 else v

    times = [np.arange(a, b) / fs for a, b in spans]
    data = np.concatenate([blocks(x[a:b]) for a, b in spans])
    offsets = np.cumsum([0] + [(b - a) // average for a, b in spans])
    counts = [len(LAWS[m.law]) + 1 + stiffness for m in modes]      # law, w0[, alpha]
    shared = int(sum(counts))
    decay_index = [(k, j) for k, m in enumerate(modes) for j in range(len(m.decays))]
    lines = shared + 2 * len(decay_index)         # each span's offset and slope from here
    centred = [blocks(t - 0.5 * (t[0] + t[-1])) for t in times]
    theta0 = np.array([v for m in modes
                       for v in (*m.params, m.w0, *([m.alpha] if stiffness else []))]
                      + [v for m in modes for d in m.decays for v in (d.value, d.time)]
                      + [0.0] * (2 * len(spans)), dtype=np.float64)
    if data.size <= theta0.size:
        raise fail(func, f"{data.size} samples for {theta0.size} parameters; expected more "
                         "samples than parameters")
    period = 2.0 * math.pi / min(m.w0 for m in modes)
    typical = np.concatenate(
        [np.r_[np.maximum(np.abs(np.asarray(m.params, dtype=float)),
                          1e-3 * math.pi * 2.0 / period), m.w0,
               *([_alpha_scale(m, quantity)] if stiffness else [])]
         for m in modes]
        + [np.r_[abs(d.value), period] for m in modes for d in m.decays]
        + [np.r_[1.0, 1.0 / max(t[-1] - t[0], 1.0 / fs)]
           * max(float(np.std(x[a:b])), 1e-300) for t, (a, b) in zip(times, spans)])
    first = np.cumsum([0] + counts)

    def one(theta: np.ndarray, k: int, j: int) -> np.ndarray:
        m = modes[k]
        p = theta[first[k]:first[k + 1]]
        i = shared + 2 * decay_index.index((k, j))
        d = m.decays[j]
        law, w0, alpha = (p[:-2], p[-2], p[-1]) if stiffness else (p[:-1], p[-1], m.alpha)
        return blocks(simulate_decay(m.law, law, float(w0), float(theta[i]),
                                     float(theta[i + 1]), times[d.span], alpha=float(alpha),
                                     quantity=quantity, output=output))

    def model(theta: np.ndarray) -> np.ndarray:
        out = np.zeros(data.size)
        for k, m in enumerate(modes):
            for j, d in enumerate(m.decays):
                out[offsets[d.span]:offsets[d.span + 1]] += one(theta, k, j)
        for s, t in enumerate(centred):
            out[offsets[s]:offsets[s + 1]] += theta[lines + 2 * s] + theta[lines + 2 * s + 1] * t
        return out

    best: dict[str, Any] = {"costs": [], "theta": theta0}
    enough = None if target_rms is None else float(target_rms) ** 2 * data.size

    def residuals(theta: np.ndarray) -> np.ndarray:
        resid = model(theta) - data
        cost = float(resid @ resid)
        costs = best["costs"]
        if not costs or cost < costs[-1]:
            best["theta"] = theta.copy()
            costs.append(cost)
        else:
            costs.append(costs[-1])
        if enough is not None and _hopeless(costs, enough):
            raise _Hopeless
        return resid

    def jacobian(theta: np.ndarray) -> np.ndarray:
        jac = np.zeros((data.size, theta.size))
        for k, m in enumerate(modes):
            base = [one(theta, k, j) for j in range(len(m.decays))]
            for c in range(first[k], first[k + 1]):
                step = DIFF_STEP * typical[c]
                moved = theta.copy()
                moved[c] += step
                for j, d in enumerate(m.decays):
                    sl = slice(offsets[d.span], offsets[d.span + 1])
                    jac[sl, c] += (one(moved, k, j) - base[j]) / step
            for j, d in enumerate(m.decays):
                sl = slice(offsets[d.span], offsets[d.span + 1])
                i = shared + 2 * decay_index.index((k, j))
                for c in (i, i + 1):
                    step = DIFF_STEP * typical[c]
                    moved = theta.copy()
                    moved[c] += step
                    jac[sl, c] = (one(moved, k, j) - base[j]) / step
        for s, t in enumerate(centred):
            jac[offsets[s]:offsets[s + 1], lines + 2 * s] = 1.0
            jac[offsets[s]:offsets[s + 1], lines + 2 * s + 1] = t
        return jac

    # A fit driven where the model decays explode overflows inside the solver and in its
    # covariance; it is then reported as not converged or with a non-finite covariance, which
    # the caller refuses.
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        try:
            sol = sopt.least_squares(residuals, theta0, jac=jacobian, x_scale=typical,
                                     method="trf", max_nfev=MAX_EVALUATIONS)
            theta, resid, converged = sol.x, sol.fun, bool(sol.status > 0)
        except _Hopeless:
            theta = best["theta"]
            resid, converged = model(theta) - data, False
        jac = jacobian(theta)
        white, hac = _covariances(jac, resid, [(b - a) // average for a, b in spans])
        var_white = np.diag(white)
        factor = np.sqrt(np.maximum(np.divide(np.diag(hac), var_white,
                                              out=np.ones_like(var_white),
                                              where=var_white > 0.0), 1.0))
        cov = white * np.outer(factor, factor)
    params, w0, alpha, covs, widen, starts, start_times = [], [], [], [], [], [], []
    for k, m in enumerate(modes):
        sl = slice(first[k], first[k + 1])
        # (params..., w0, alpha), alpha's variance 0 where it was held
        own = np.pad(theta[sl], (0, 0 if stiffness else 1), constant_values=m.alpha)
        params.append(own[:-2].copy())
        w0.append(float(own[-2]))
        alpha.append(float(own[-1]))
        covs.append(np.pad(cov[sl, sl], (0, 0 if stiffness else 1)))
        widen.append(np.pad(factor[sl], (0, 0 if stiffness else 1), constant_values=1.0))
        idx = [shared + 2 * decay_index.index((k, j)) for j in range(len(m.decays))]
        starts.append(theta[idx].copy())
        start_times.append(theta[np.array(idx) + 1].copy())
    spread = np.concatenate([data[a:b] - np.mean(data[a:b])
                             for a, b in zip(offsets[:-1], offsets[1:])])
    return JointFit(params=params, w0=np.array(w0), alpha=np.array(alpha), cov=covs,
                    starts=starts, times=start_times,
                    residual_rms=float(np.sqrt(np.mean(resid ** 2))),
                    r2=1.0 - float(resid @ resid) / max(float(spread @ spread), 1e-300),
                    samples=int(data.size),
                    dof=int(data.size - theta.size),
                    widening=widen, converged=converged,
                    evaluations=len(best["costs"]))


def _hopeless(costs: list[float], enough: float) -> bool:
    """Whether the least squares' best costs so far (sums of squares, one per evaluation),
    carried on at the pace of their last :data:`PROGRESS_WINDOW` evaluations to the end of the
    budget, stay above ``HOPELESS_FACTOR**2`` times ``enough`` (the cost of ``target_rms``)."""
    if len(costs) < PROGRESS_WINDOW or len(costs) >= MAX_EVALUATIONS:
        return False
    ratio = costs[-1] / max(costs[-PROGRESS_WINDOW], 1e-300)
    pace = ratio ** (1.0 / (PROGRESS_WINDOW - 1))
    projected = costs[-1] * pace ** (MAX_EVALUATIONS - len(costs))
    return projected > HOPELESS_FACTOR ** 2 * enough


def _alpha_scale(mode: JointMode, quantity: str) -> float:
    """A cubic stiffness's typical size for the fit's steps: its start, or one that moves the
    frequency by 1 % at the largest start amplitude."""
    largest = max(abs(d.value) for d in mode.decays)
    amplitude = largest / mode.w0 if quantity == "velocity" else largest
    return max(abs(mode.alpha), 0.01 * 8.0 / 3.0 * mode.w0 ** 2 / max(amplitude, 1e-300) ** 2)


def _covariances(jac: np.ndarray, resid: np.ndarray, sizes: Sequence[int]
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The white-noise covariance ``s^2 (J^T J)^-1`` and the sandwich
    ``A^-1 J^T S J A^-1`` of the parameters, ``S`` the residuals' covariance as an
    autoregressive model of them gives it (:func:`_noise_spectrum`), each span (given by
    their ``sizes``) on its own."""
    # In columns scaled to unit norm, scaled back at the end: the parameters' sizes span
    # twenty decades (a cubic stiffness against a damping rate), beyond what J^T J holds in
    # double precision.
    norms = np.linalg.norm(jac, axis=0)
    norms[norms == 0.0] = 1.0
    jac = jac / norms
    a_inv = np.linalg.pinv(jac.T @ jac)
    s2 = float(resid @ resid) / max(resid.size - jac.shape[1], 1)
    edges = np.cumsum([0, *sizes])
    middle = np.zeros_like(a_inv)
    spectrum = _noise_spectrum(resid, edges)
    for lo, hi in zip(edges[:-1], edges[1:]):
        n = scipy.fft.next_fast_len(2 * (hi - lo))
        density = spectrum(n)
        weight = np.full(density.size, 2.0)
        weight[0] = 1.0
        if n % 2 == 0:
            weight[-1] = 1.0
        jf = scipy.fft.rfft(jac[lo:hi], n, axis=0)
        middle += ((jf.conj() * (weight * density)[:, None]).T @ jf).real / n
    unscale = np.outer(norms, norms)
    return s2 * a_inv / unscale, a_inv @ middle @ a_inv / unscale


def _noise_spectrum(resid: np.ndarray, edges: np.ndarray):
    """The residuals' spectral density (per sample, U^2) as a function of the FFT length: an
    autoregressive model of order up to :data:`AR_ORDER` (chosen by AIC, fitted by
    Yule-Walker to the autocovariance pooled over the spans). A parametric estimate: one
    record's periodogram, however smoothed, scatters by tens of percent, and an interval
    that takes it at its word is too narrow as often as too wide."""
    gamma = np.zeros(AR_ORDER + 1)
    for lo, hi in zip(edges[:-1], edges[1:]):
        r = resid[lo:hi]
        keep = min(AR_ORDER + 1, r.size)
        gamma[:keep] += np.array([float(r[k:] @ r[:r.size - k]) for k in range(keep)])
    gamma /= max(resid.size, 1)
    best = (resid.size * math.log(max(gamma[0], 1e-300)), np.zeros(0), gamma[0])
    for order in range(1, AR_ORDER + 1):
        try:
            coef = scipy.linalg.solve_toeplitz(gamma[:order], gamma[1:order + 1])
        except np.linalg.LinAlgError:
            break
        innovation = float(gamma[0] - coef @ gamma[1:order + 1])
        if innovation <= 0.0:
            break
        aic = resid.size * math.log(innovation) + 2.0 * order
        if aic < best[0]:
            best = (aic, coef, innovation)
    _, coef, innovation = best

    def density(n: int) -> np.ndarray:
        poly = np.zeros(n)
        poly[0] = 1.0
        poly[1:coef.size + 1] = -coef
        return innovation / np.abs(scipy.fft.rfft(poly)) ** 2

    return density
