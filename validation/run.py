"""Monte-Carlo trials of the validation matrix: fsi-lab's identification and a peer method.

For each case, ``trials`` noisy realisations are identified by :func:`fsi_lab.dsp.identify`
(the mode nearest the truth's frequency) and by the peer: the plain envelope-law fit on raw
peaks (the extrema of the record from its largest on, the closed form of the averaged law
``dA/dt = -a A - b A^2`` fitted by least squares, t-intervals). Reported per quantity: bias and
RMS error (% of the truth) and the coverage of the 95 % intervals. For a mode with a cubic
stiffness, the displacement backbone that the analysis chain reports is measured against
harmonic balance as well (:func:`chain_backbone`, :meth:`Row.backbone_bias`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.optimize as sopt
import scipy.stats as sstats

from validation.cases import Case, harmonic_balance_hz, trial

#: Amplitude bands (shares of the release's displacement) the backbone's bias is taken over.
BACKBONE_BANDS = (0.0, 0.1, 0.2, 0.4, 0.6, 0.8, 1.0)
#: Fewest backbone points (over the trials) for a band's bias to be taken.
BACKBONE_POINTS = 20


@dataclass
class Estimate:
    """One trial's numbers: value and 95 % interval of C_i, C_f and the frequency."""

    c_i: float = math.nan
    c_i_ci: tuple[float, float] = (math.nan, math.nan)
    c_f: float = math.nan
    c_f_ci: tuple[float, float] = (math.nan, math.nan)
    frequency: float = math.nan
    frequency_ci: tuple[float, float] = (math.nan, math.nan)
    law: str = ""
    warned: bool = False
    refused: str = ""
    #: The chain's displacement backbone, for a mode with a cubic stiffness: each point's
    #: amplitude as a share of the release's displacement, and its frequency's error from
    #: harmonic balance (%).
    backbone_share: np.ndarray | None = None
    backbone_error: np.ndarray | None = None


def fsi_lab_estimate(case: Case, x: np.ndarray) -> Estimate:
    """fsi-lab's identification of the case's first mode in ``x``."""
    from fsi_lab.dsp.identify import identify
    from fsi_lab.errors import AnalysisError

    try:
        found = identify(x, case.fs)
    except AnalysisError as exc:
        return Estimate(refused=str(exc))
    truth = case.truth.frequency
    mode = min(found.modes, key=lambda m: abs(math.log(m.frequency_hz / truth)))
    if abs(mode.frequency_hz / truth - 1.0) > 0.2:
        return Estimate(refused=f"no mode near {truth:g} Hz")
    m = case.mass
    # A dry-friction record is read as a user reads it: the law fsi-lab prefers gives C_i and
    # the friction force, or with the three-term law C_i and C_f (a coefficient the preferred
    # law has not is no number, counted as not covered). The quadratic law nests the viscous
    # one: a viscous record's C_i is its. Read by the preferred law, a trial is warned only
    # by the warnings on that law's own numbers (the others are on the quadratic law's).
    fit, warned = mode.quadratic, bool(mode.warnings)
    if case.law in ("coulomb", "quadratic_coulomb") and mode.laws.preferred != "quadratic":
        fit = mode.laws.fits[mode.laws.preferred]
        warned = any(w.startswith("the preferred law's ") for w in mode.warnings)
    second = "gamma" if case.law == "coulomb" else "beta"
    (a_lo, a_hi) = fit.interval("a")
    c_f, (b_lo, b_hi) = math.nan, (math.nan, math.nan)
    if second in fit.names:
        c_f, (b_lo, b_hi) = m * fit.value(second), fit.interval(second)
    return Estimate(c_i=2 * m * fit.value("a"), c_i_ci=(2 * m * a_lo, 2 * m * a_hi),
                    c_f=c_f, c_f_ci=(m * b_lo, m * b_hi),
                    frequency=mode.frequency_hz, frequency_ci=tuple(mode.frequency_ci),
                    law=mode.laws.preferred, warned=warned)


def _envelope(t: np.ndarray, a: float, b: float, a0: float) -> np.ndarray:
    # The peer's least squares may try coefficients for which the closed form's denominator
    # vanishes or overflows: the residual is then inf or NaN and the step is rejected, as
    # least_squares does, without numpy's warning in the matrix's output.
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if abs(a) < 1e-12:
            return a0 / (1.0 + b * a0 * t)
        e = np.exp(-a * t)
        return a * a0 * e / (a + b * a0 * (1.0 - e))


def peer_estimate(case: Case, x: np.ndarray) -> Estimate:
    """The plain envelope-law fit on raw peaks (see the module notes); velocity amplitudes:
    ``b = 4 beta / (3 pi)``, C_i = 2 m a, C_f = m beta."""
    ax = np.abs(x)
    # Half cycles between the sign changes of the record smoothed over a twentieth of a
    # period (noise would cut them up); the largest raw sample of each.
    width = max(1, int(case.fs / (20.0 * case.truth.frequency)))
    smooth = np.convolve(x, np.ones(width) / width, mode="same")
    cuts = np.flatnonzero(np.diff(np.signbit(smooth)))
    if cuts.size < 8:
        return Estimate(refused="too few half cycles")
    idx = np.array([lo + int(np.argmax(ax[lo:hi])) for lo, hi in zip(cuts[:-1], cuts[1:])
                    if hi > lo + 2])
    # Parabolic refinement of each extremum.
    i = idx[(idx > 0) & (idx < x.size - 1)]
    y0, y1, y2 = ax[i - 1], ax[i], ax[i + 1]
    den = y0 - 2 * y1 + y2
    shift = np.where(den != 0, 0.5 * (y0 - y2) / np.where(den != 0, den, 1.0), 0.0)
    amp = y1 - 0.25 * (y0 - y2) * shift
    t = (i + shift) / case.fs
    top = int(np.argmax(amp))
    noise = case.noise * float(np.max(ax))
    keep = np.arange(amp.size) >= top
    keep &= amp > 3.0 * noise
    t, amp = t[keep], amp[keep]
    if amp.size < 6:
        return Estimate(refused="too few peaks above the noise")
    tt = t - t[0]
    slope = -np.polyfit(tt, np.log(amp), 1)[0]
    try:
        res = sopt.least_squares(lambda p: _envelope(tt, p[0], p[1], p[2]) - amp,
                                 [max(slope, 1e-3) / 2, max(slope, 1e-3) / (2 * amp[0]), amp[0]],
                                 x_scale="jac")
    except ValueError as exc:
        return Estimate(refused=str(exc))
    dof = max(amp.size - 3, 1)
    s2 = float(res.fun @ res.fun) / dof
    cov = np.linalg.pinv(res.jac.T @ res.jac) * s2
    q = float(sstats.t.ppf(0.975, dof))
    a, b = float(res.x[0]), float(res.x[1])
    se_a, se_b = math.sqrt(max(cov[0, 0], 0)), math.sqrt(max(cov[1, 1], 0))
    m = case.mass
    k = 3.0 * math.pi / 4.0
    return Estimate(c_i=2 * m * a, c_i_ci=(2 * m * (a - q * se_a), 2 * m * (a + q * se_a)),
                    c_f=m * k * b, c_f_ci=(m * k * (b - q * se_b), m * k * (b + q * se_b)))


def chain_backbone(case: Case, x: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The displacement backbone (amplitudes m, frequencies Hz) of the case's first mode in the
    velocity record ``x`` as ``fsi-lab analyze`` reports it (the chain's ``hvd`` and
    ``backbone`` at their defaults), or None when the chain gives none near its frequency."""
    from fsi_lab.chain import run_chain
    from fsi_lab.contract import ChannelData
    from fsi_lab.params import validate
    from validation.bench import _registry

    registry = _registry()
    chain = ["hvd", "backbone"]
    params = {name: validate(registry.get("analysis", name).params, {}, f"analysis.{name}")
              for name in chain}
    channel = ChannelData("tip_velocity", x, case.fs, "velocity", "m/s")
    _, summary = run_chain({"tip_velocity": channel}, {"chain": chain}, params, registry)
    comps = [c for c in summary["tip_velocity"].get("components", [])
             if "backbone" in c and c.get("frequency_hz")]
    truth = case.truth.frequency
    if not comps:
        return None
    comp = min(comps, key=lambda c: abs(math.log(c["frequency_hz"] / truth)))
    if abs(comp["frequency_hz"] / truth - 1.0) > 0.2:
        return None
    return (np.asarray(comp["backbone"]["amplitude"], dtype=float),
            np.asarray(comp["backbone"]["frequency_hz"], dtype=float))


def run_trial(args: tuple[Case, int]) -> tuple[Estimate, Estimate]:
    case, seed = args
    x = trial(case, seed)
    if case.bench:
        from validation.bench import bench_estimate

        return bench_estimate(case, x), peer_estimate(case, x[0])
    ours = fsi_lab_estimate(case, x)
    if case.truth.alpha and not ours.refused and (bb := chain_backbone(case, x)) is not None:
        amplitude, frequency = bb
        ours.backbone_share = amplitude / case.truth.x0
        ours.backbone_error = 100.0 * (frequency / harmonic_balance_hz(case.truth, case.mass,
                                                                      amplitude) - 1.0)
    return ours, peer_estimate(case, x)


@dataclass
class Row:
    """Statistics of one case."""

    case: Case
    ours: list[Estimate]
    peer: list[Estimate]

    def stats(self, which: str, quantity: str) -> dict[str, float]:
        """Bias and RMS error (% of truth), coverage, over the trials that gave a number."""
        truth = {"c_i": self.case.truth.c_i, "c_f": self.case.second_truth,
                 "frequency": self.case.truth.frequency}[quantity]
        ests = [e for e in (self.ours if which == "ours" else self.peer) if not e.refused]
        values = np.array([getattr(e, quantity) for e in ests], dtype=float)
        lows = np.array([getattr(e, f"{quantity}_ci")[0] for e in ests], dtype=float)
        highs = np.array([getattr(e, f"{quantity}_ci")[1] for e in ests], dtype=float)
        if values.size == 0 or truth == 0:
            return {"bias": math.nan, "rms": math.nan, "coverage": math.nan}
        rel = values / truth - 1.0
        return {"bias": 100 * float(np.nanmean(rel)),
                "rms": 100 * float(np.sqrt(np.nanmean(rel ** 2))),
                "coverage": float(np.nanmean((lows <= truth) & (truth <= highs)))}

    def backbone_bias(self) -> float:
        """The backbone's largest bias from harmonic balance, %: the mean error of its points
        (pooled over the trials) in each amplitude band (:data:`BACKBONE_BANDS`, of at least
        :data:`BACKBONE_POINTS` points), the largest in size; NaN without a backbone."""
        got = [e for e in self.ours if e.backbone_error is not None]
        if not got:
            return math.nan
        share = np.concatenate([e.backbone_share for e in got])
        error = np.concatenate([e.backbone_error for e in got])
        worst = math.nan
        for lo, hi in zip(BACKBONE_BANDS[:-1], BACKBONE_BANDS[1:]):
            inside = (share >= lo) & (share < hi if hi < BACKBONE_BANDS[-1] else share <= hi)
            if inside.sum() >= BACKBONE_POINTS:
                mean = float(np.mean(error[inside]))
                worst = mean if math.isnan(worst) or abs(mean) > abs(worst) else worst
        return worst


def evaluate(cases: list[Case], trials: int, workers: int = 2,
             scheduler: str | None = None) -> list[Row]:
    """Run ``trials`` realisations of every case, through fsi-lab's executor: in ``workers``
    local processes of one BLAS and one numba thread each (1: in this process), or on the Dask
    scheduler at ``scheduler``."""
    from fsi_lab.executor import make_executor

    jobs = [(case, seed) for case in cases for seed in range(trials)]
    with make_executor(None if scheduler else workers, scheduler) as executor:
        done = executor.map(run_trial, jobs)
    failed = [r for r in done if not r.ok]
    if failed:
        case, seed = jobs[failed[0].index]
        raise RuntimeError(f"{len(failed)} trial(s) failed, the first {case.name} seed {seed}: "
                           f"{failed[0].error}")
    results = [r.value for r in done]
    rows = []
    for k, case in enumerate(cases):
        part = results[k * trials:(k + 1) * trials]
        rows.append(Row(case, [p[0] for p in part], [p[1] for p in part]))
    return rows
