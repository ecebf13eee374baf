"""One damping law fitted to the free decays of several runs of the same mode.

Each run's identification (:func:`fsi_lab.dsp.identify.identify`) gives a mode's free decays as
the extrema its law fits use (:class:`~fsi_lab.dsp.identify.DecayExtrema`: times, values,
amplitudes corrected for the filters, the relative error of each), the correlation of their
errors (that of white noise through the mode's band filter) and the noise level. Here the
linear + quadratic law (and the viscous one, to say which the runs prefer) is fitted to the
union of those decays with :func:`fsi_lab.dsp.laws.fit_law`: common law parameters, one start
amplitude per decay, each decay's errors whitened as in its run, scaled by its run's noise.

Each run's own identification may have widened its intervals beyond what its extrema's
scatter says (a start of the decays that is not yet free, two halves that disagree):
``widening`` is that factor on its standard errors (the largest of ``a``'s and ``beta``'s, its
reported covariance over a plain refit of its decays). In the union, a run's errors are taken
``widening`` times larger: its decays weigh less, and the union's covariance is computed with
the noise variance the runs' residuals give at that scale (not the smaller one the weighted
residuals alone would give), so that a union of equally widened runs is widened as they are.

The runs may also disagree beyond their own intervals (the bench changed between runs, a run's
systematic error): the chi-square of the runs' own estimates about the union's, per degree of
freedom (Birge's ratio), scales the union's variance when it exceeds 1 (``spread_factor``).

Last, the identification's accuracy on records of known truth (:data:`fsi_lab.accuracy.
ACCURACY`: C_i 0.3 %, C_f 2 % of the value, as a 95 % half-width) is added to the interval in
quadrature: the union narrows the noise's part as more decays come, not the method's
systematic errors, which every run shares, so its interval is never narrower than those
(``accuracy_factor``).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.stats as sstats

from fsi_lab.accuracy import LAW_ACCURACY
from fsi_lab.dsp.identify import DecayExtrema
from fsi_lab.dsp.laws import (
    LawComparison,
    LawFit,
    PowerTest,
    Whitener,
    compare_laws,
    fit_law,
    fluid_power,
)
from fsi_lab.errors import AnalysisError

#: The laws fitted to the union: the quadratic one (C_i and C_f) and the viscous one, to say
#: whether the runs together call for the quadratic term.
UNION_LAWS = ("quadratic", "viscous")


@dataclass(frozen=True)
class RunDecays:
    """One run's free decays of a mode, as its identification found them.

    Attributes
    ----------
    decays
        The extrema of each free decay the run's fits used.
    correlation
        Correlation of the errors of two extrema against their time lag (s), or None.
    noise
        The run's noise level in the mode's band (any unit common to the runs, e.g. the
        identification's noise floor): each run's errors are scaled by it.
    w0
        The run's linear natural angular frequency, rad/s.
    alpha
        Its cubic stiffness per unit mass, 1/(U^2 s^2).
    quantity
        ``"velocity"`` or ``"displacement"``: what the extrema are extrema of.
    params, cov
        The run's own quadratic law ``(a, beta)`` and its covariance, as its identification
        reported them (widened where it found reasons to).
    widening
        How much wider the run's intervals are than its extrema's scatter alone makes them
        (>= 1, :func:`run_widening`).
    joint
        Whether the run's ``params`` come from its mode fitted together with a close mode to
        the record's samples, not from these extrema (:mod:`fsi_lab.dsp.joint_fit`).
    delta_aicc
        The run's own AICc of each law less the lowest (its identification's law comparison;
        empty when not known).
    """

    decays: Sequence[DecayExtrema]
    correlation: Callable[[np.ndarray], np.ndarray] | None
    noise: float
    w0: float
    alpha: float
    quantity: str
    params: np.ndarray
    cov: np.ndarray
    widening: float = 1.0
    joint: bool = False
    delta_aicc: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class UnionFit:
    """The law fitted to the union of several runs' decays.

    Attributes
    ----------
    fit
        The quadratic law's fit (its covariance as fitted).
    cov
        The covariance of ``(a, beta)``: at the runs' noise scale (``noise_factor``), widened
        by ``spread_factor``.
    comparison
        The union's fits of :data:`UNION_LAWS`, ranked by AICc.
    widenings
        Each run's ``widening`` (its weight in the union is its inverse square).
    noise_factor
        Factor on the fit's standard errors for the runs' noise scale (1 when no run was
        widened).
    spread_factor
        Factors on the standard errors of ``a`` and ``beta`` for the spread between runs.
    accuracy_factor
        Factors on them for the method's accuracy (:data:`fsi_lab.accuracy.LAW_ACCURACY`),
        added in quadrature to each variance (infinite where the fit's own variance is 0);
        the correlation of ``a`` and ``beta`` is kept.
    spread_chi2
        Chi-square per degree of freedom of the runs' own ``a`` and ``beta`` about the
        union's (NaN with one run).
    runs, decays, extrema
        What was fitted.
    w0, alpha
        The oscillator of the fit (medians of the runs').
    power
        The power of the velocity the quadratic law's fluid term grows with, tested on the
        union (:func:`fsi_lab.dsp.laws.fluid_power`; its standard error at the runs' noise
        scale, ``noise_factor``); None when C_f's interval includes 0, for a weighted mean,
        or when the test cannot be made.
    pooled
        ``"union"``, or ``"weighted mean"`` when a run's mode was fitted together with a close
        mode to its record's samples (:attr:`RunDecays.joint`): its extrema are smeared by the
        band filters, so ``a`` and ``beta`` are then the runs' own estimates averaged with
        their inverse covariances, and the laws are ranked by the sum of the runs' own AICc
        (each compared its laws on what its law was fitted to; the runs' records are
        independent), not by the union's fits of the smeared extrema.
    """

    fit: LawFit
    cov: np.ndarray
    comparison: LawComparison
    widenings: np.ndarray
    noise_factor: float
    spread_factor: np.ndarray
    spread_chi2: np.ndarray
    accuracy_factor: np.ndarray
    runs: int
    decays: int
    extrema: int
    w0: float
    alpha: float
    pooled: str = "union"
    power: PowerTest | None = None

    def value(self, name: str) -> float:
        """``a`` (1/s) or ``beta`` (1/U)."""
        return self.fit.value(name)

    def se(self, name: str) -> float:
        """Widened standard error of ``a`` or ``beta``."""
        i = self.fit.names.index(name)
        return math.sqrt(max(float(self.cov[i, i]), 0.0))

    def interval(self, name: str, level: float = 0.95) -> tuple[float, float]:
        """Widened confidence interval (t-distribution with the fit's degrees of freedom)."""
        q = float(sstats.t.ppf(0.5 + 0.5 * level, max(self.fit.dof, 1)))
        value, se = self.value(name), self.se(name)
        return value - q * se, value + q * se


def _whiteners(run: RunDecays, relative: float) -> list[Whitener]:
    """A whitener per decay of ``run``, its errors ``relative`` times the reference's."""
    out = []
    for d in run.decays:
        scale = np.ones(d.amplitude.size) if d.scale is None else np.asarray(d.scale)
        out.append(Whitener(np.asarray(d.times), np.sign(d.values), run.correlation,
                            scale * relative))
    return out


def run_widening(run: RunDecays) -> float:
    """How much wider ``run``'s reported intervals are than a plain refit of its decays
    makes them: the larger ratio of standard errors of ``a`` and ``beta`` (at least 1)."""
    plain = fit_law("quadratic", [d.amplitude for d in run.decays], run.w0, alpha=run.alpha,
                    quantity=run.quantity, whiteners=_whiteners(run, 1.0), start=run.params)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.sqrt(np.diag(run.cov) / np.diag(plain.cov))
    ratio = ratio[np.isfinite(ratio)]
    return max(1.0, float(ratio.max())) if ratio.size else 1.0


def fit_union(runs: Sequence[RunDecays]) -> UnionFit:
    """Fit the quadratic (and viscous) law to the union of the runs' decays (module notes).

    Raises
    ------
    AnalysisError
        No run, runs of different quantities, or a fit that fails (too few extrema).
    """
    runs = [run for run in runs if run.decays]
    if not runs:
        raise AnalysisError("aggregate: no free decay to fit")
    quantities = {run.quantity for run in runs}
    if len(quantities) != 1:
        raise AnalysisError(f"aggregate: the runs' decays are of {', '.join(sorted(quantities))}"
                            "; a law is fitted to extrema of one quantity")
    (quantity,) = quantities
    w0 = float(np.median([run.w0 for run in runs]))
    alpha = float(np.median([run.alpha for run in runs]))
    reference = float(np.median([run.noise for run in runs])) or 1.0
    amps, whiteners, widening = [], [], []
    for run in runs:
        amps.extend(np.asarray(d.amplitude) for d in run.decays)
        whiteners.extend(_whiteners(run, run.noise / reference * run.widening))
        widening.extend([run.widening] * len(run.decays))
    fits = {law: fit_law(law, amps, w0, alpha=alpha, quantity=quantity, whiteners=whiteners)
            for law in UNION_LAWS}
    quad = fits["quadratic"]
    # The weighted residuals' scatter is the noise over each run's widening: the union's
    # variance at the runs' own noise scale is the unweighted scatter's.
    weighted = [float(np.sum(w.apply(r) ** 2)) for w, r in zip(whiteners, quad.residuals)]
    total = sum(weighted)
    noise_factor = math.sqrt(sum(f * f * x for f, x in zip(widening, weighted)) / total) \
        if total > 0 else 1.0
    pooled = "union"
    comparison = compare_laws(list(fits.values()))
    if any(run.joint for run in runs):
        quad = _weighted_mean(quad, runs)
        noise_factor, pooled = 1.0, "weighted mean"
        comparison = _summed_comparison(fits, runs, comparison)
    chi2 = np.full(2, math.nan)
    spread_factor = np.ones(2)
    if len(runs) > 1:
        own = np.array([run.params for run in runs], dtype=np.float64)
        own_var = np.array([np.diag(run.cov) for run in runs], dtype=np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            z2 = (own - quad.params) ** 2 / own_var
        z2 = np.where(np.isfinite(z2), z2, 0.0)
        chi2 = z2.sum(axis=0) / (len(runs) - 1)
        spread_factor = np.sqrt(np.maximum(chi2, 1.0))
    factor = noise_factor * spread_factor
    cov = quad.cov * np.outer(factor, factor)
    # The method's accuracy as a standard error (its 95 % half-width over the t quantile the
    # interval uses), added to each variance; the correlation of a and beta is kept.
    q = float(sstats.t.ppf(0.975, max(quad.dof, 1)))
    floor = np.array([LAW_ACCURACY[name] * abs(float(v)) / q
                      for name, v in zip(quad.names, quad.params)])
    variance = np.diag(cov)
    with np.errstate(divide="ignore", invalid="ignore"):
        accuracy_factor = np.where(variance > 0, np.sqrt(1.0 + floor ** 2 / variance), 1.0)
    accuracy_factor = np.where(np.isfinite(accuracy_factor), accuracy_factor, 1.0)
    cov = cov * np.outer(accuracy_factor, accuracy_factor)
    exact = variance == 0.0  # (a noise-free union fitted exactly: its interval is the floor)
    cov[exact, exact] = floor[exact] ** 2
    accuracy_factor[exact & (floor > 0)] = math.inf
    power = None
    lower = quad.params[1] - q * math.sqrt(max(float(cov[1, 1]), 0.0))
    if pooled == "union" and lower > 0.0:
        try:
            power = fluid_power(quad, whiteners)
        except AnalysisError:
            power = None
        else:
            # (not by the spread between runs: runs over different amplitude ranges disagree
            # on a quadratic law because its power is wrong, which is what the test measures)
            power = dataclasses.replace(power, se=power.se * noise_factor)
    return UnionFit(fit=quad, cov=cov, comparison=comparison, power=power,
                    widenings=np.array([run.widening for run in runs]),
                    noise_factor=noise_factor, spread_factor=spread_factor, spread_chi2=chi2,
                    accuracy_factor=accuracy_factor,
                    runs=len(runs), decays=len(amps), extrema=int(sum(a.size for a in amps)),
                    w0=w0, alpha=alpha, pooled=pooled)


def _summed_comparison(fits: dict[str, LawFit], runs: Sequence[RunDecays],
                       union: LawComparison) -> LawComparison:
    """The laws of ``fits`` ranked by the sum over the runs of their own AICc (less each
    run's lowest: the same ranking), or ``union`` when a run does not give them all."""
    if not all(set(fits) <= set(run.delta_aicc) for run in runs):
        return union
    ranked = [dataclasses.replace(fit, aicc=sum(float(run.delta_aicc[law]) for run in runs))
              for law, fit in fits.items()]
    return compare_laws(ranked)


def _weighted_mean(quad: LawFit, runs: Sequence[RunDecays]) -> LawFit:
    """``quad`` with the runs' own ``(a, beta)`` averaged by their inverse covariances in
    place of its parameters, and the mean's covariance in place of its own."""
    precision = np.zeros((2, 2))
    weighted = np.zeros(2)
    for run in runs:
        inverse = np.linalg.pinv(np.asarray(run.cov, dtype=np.float64))
        precision += inverse
        weighted += inverse @ np.asarray(run.params, dtype=np.float64)
    cov = np.linalg.pinv(precision)
    return dataclasses.replace(quad, params=cov @ weighted, cov=cov)
