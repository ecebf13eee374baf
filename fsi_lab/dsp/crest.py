"""The crests of a free decay: a third harmonic in phase with the mode, as a compressing
measuring chain makes it.

A vibrometer's decoder or an amplifier near the end of its range reads the largest cycles a
few per cent low. Their envelope then falls too slowly at first, and the quadratic damping
law takes that for too little fluid damping: C_f comes out low, with an interval that does
not warn. The waveform shows it: a memoryless compression ``y (1 - c (y / A)^2)`` of a cycle
``A cos(psi)`` flattens its crest, adding ``-c A / 4 cos(3 psi)``, in phase with the cycle and
growing as ``A^3``, while its zero crossings stay where they were.

The beam's own mechanisms make little of it:

- damping's harmonics (linear, quadratic, Coulomb) lie in quadrature, odd about the crest, to
  first order; a quadratic law's decay adds an in-phase share of second order (-0.2 % at a
  damping ratio of 0.1);
- a cubic stiffness ``k3 x^3`` adds an in-phase third harmonic of ``rho dw/w`` of the cycle,
  ``rho`` = 1/12 for a displacement, -1/4 for a velocity, 3/4 for an acceleration (harmonic
  balance, to first order in the shift ``dw/w`` its backbone shows).

:func:`half_cycle_harmonics` fits each half cycle between two zero crossings of the mode with
the crest-centred cosines ``cos psi, cos 3 psi`` beside an odd term, an offset (a slow drift)
and a stretch (a crossing moved by noise or a filter), under an envelope with the rate and
curvature of its neighbours' fall; :func:`pooled_crest` takes the in-phase ratio as growing as
the square of the amplitude over the decays' larger half cycles and takes the stiffness's
share off, found from the same crossings' half periods. :func:`.identify.identify` measures
the fitted model of the record the same way and warns of what the record holds beyond it,
half cycle by half cycle (``pooled_crest(..., reference=...)``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from fsi_lab.dsp._signal import as_record, check_rate, fail

#: Half cycles whose fundamental is at least this share of the largest one are used (the
#: harmonic grows as the amplitude cubed: the small ones carry almost nothing of it).
TOP_SHARE = 0.1
#: Fewest samples per half cycle: its four terms need them, with some to spare.
MIN_SAMPLES = 8
#: Fewest half cycles to estimate the ratio and its scatter from.
MIN_HALF_CYCLES = 6
#: The in-phase third harmonic of a cubic stiffness, over the relative frequency shift, by the
#: quantity measured (harmonic balance; each derivative multiplies the harmonic by -3).
STIFFNESS_HARMONIC = {"displacement": 1.0 / 12.0, "velocity": -0.25, "acceleration": 0.75}
#: Columns of :func:`half_cycle_harmonics`' rows.
ROW_WIDTH = 7


@dataclass(frozen=True)
class CrestHarmonic:
    """The in-phase third harmonic of a mode's largest half cycles.

    Attributes
    ----------
    ratio
        What neither damping nor the stiffness explains: third harmonic over fundamental at the
        largest half cycle used, in phase (negative: flattened crests, as a compressing chain
        gives; about -c/4 for a chain reading that cycle ``3 c / 4`` low).
    stderr
        Its standard error (from the half cycles' scatter about the ``A^2`` law and the
        stiffness share's).
    measured
        The ratio before the stiffness's share is taken off.
    noise_stderr
        ``measured``'s standard error were the record's noise white, at the level the half
        cycles' residuals show (a floor for the scatter's, which a few half cycles estimate
        roughly).
    stiffness
        That share: ``rho`` times the relative frequency shift at the largest half cycle.
    half_cycles
        Half cycles used.
    amplitude
        The largest half cycle's fundamental, unit of the record.
    """

    ratio: float
    stderr: float
    measured: float
    noise_stderr: float
    stiffness: float
    half_cycles: int
    amplitude: float


def _half_cycle(x: np.ndarray, fs: float, t0: float, t1: float, rate: float,
                offset: float | None, bend: float = 0.0) -> tuple[float, ...]:
    """Fundamental, in-phase third harmonic, offset, residual sum of squares, its degrees of
    freedom and the harmonic's variance per unit noise variance of the half cycle between
    crossings ``t0`` and ``t1`` (s), its envelope's logarithm falling at ``rate`` (1/s) and
    curving by ``bend`` (1/s^2; a quadratic damping's rate falls with the amplitude: its edges
    stand higher than an exponential's, which reads as a flattened crest), the offset fitted
    (None: the last three then NaN) or given."""
    i0 = max(int(math.ceil(t0 * fs)), 0)
    i1 = min(int(math.floor(t1 * fs)), x.size - 1)
    t = np.arange(i0, i1 + 1) / fs
    psi = np.pi * ((t - t0) / (t1 - t0) - 0.5)
    tau = t - 0.5 * (t0 + t1)
    envelope = np.exp(-rate * tau + 0.5 * bend * tau * tau)
    # (the fifth harmonic and a second odd term left out: a half cycle of ten samples, a
    # 90 Hz mode at 2 kHz, then measures the third with 0.6 times the error)
    columns = [envelope * np.cos(psi), envelope * np.cos(3 * psi), envelope * np.sin(2 * psi)]
    y = x[i0:i1 + 1]
    if offset is None:
        columns.append(np.ones_like(t))
    else:
        # A crossing that noise or a filter moved stretches the cosine's half cycle, which
        # reads as a third harmonic: the stretch is fitted too (its offset is known now).
        columns.append(envelope * psi * np.sin(psi))
        y = y - offset
    basis = np.stack(columns, 1)
    coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
    if offset is None:
        return float(coef[0]), float(coef[1]), float(coef[-1]), math.nan, math.nan, math.nan
    resid = y - basis @ coef
    unit = np.linalg.pinv(basis.T @ basis)[1, 1]
    return (float(coef[0]), float(coef[1]), offset, float(resid @ resid),
            float(y.size - basis.shape[1]), float(unit))


def _samples(fs: float, t0: float, t1: float, size: int) -> int:
    """Samples of a record of ``size`` between times ``t0`` and ``t1`` (s)."""
    return min(int(math.floor(t1 * fs)), size - 1) - max(int(math.ceil(t0 * fs)), 0) + 1


def _log_slopes(fundamental: np.ndarray, mid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rate (1/s) and curvature (1/s^2) of the envelope's logarithm at each of three or more
    half cycles, from its neighbours' fundamentals (second-order differences, one-sided at
    the ends)."""
    rate = -np.gradient(np.log(np.abs(fundamental)), mid, edge_order=2)
    return rate, -np.gradient(rate, mid, edge_order=2)


def _slope(u: np.ndarray, y: np.ndarray, intercept: bool,
           weight: np.ndarray | None = None) -> tuple[float, float, float]:
    """Least squares ``y = [b +] s u``, each point weighted by ``weight`` (the inverse of its
    variance, up to a factor): (s, its standard error, b or 0)."""
    cols = [np.ones_like(u), u] if intercept else [u]
    basis = np.stack(cols, 1)
    if weight is not None:
        root = np.sqrt(weight)
        basis, y = basis * root[:, None], y * root
    coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
    dof = y.size - basis.shape[1]
    resid = y - basis @ coef
    cov = np.linalg.pinv(basis.T @ basis) * float(resid @ resid) / max(dof, 1)
    return float(coef[-1]), math.sqrt(max(float(cov[-1, -1]), 0.0)), \
        float(coef[0]) if intercept else 0.0


def half_cycle_harmonics(x: np.ndarray, fs: float, crossings: np.ndarray) -> np.ndarray:
    """Fundamental and in-phase third harmonic of each half cycle of one decay.

    Each half cycle is fitted with an offset (a slow drift, an offset of the record), first
    without an envelope, then with the rate and curvature of its fundamentals' fall; the
    offsets, which a half cycle cannot tell well from its cosines, are then smoothed over
    neighbours (1, 2, 1: the fundamental's share alternates in sign and cancels) and taken as
    known.

    Parameters
    ----------
    x
        Samples of the record (unit U), 1-D, at ``fs`` Hz.
    fs
        Sample rate, Hz.
    crossings
        The decay's zero-crossing times, s from ``x``'s first sample, increasing.

    Returns
    -------
    numpy.ndarray
        ``(n, 7)``: mid time (s), fundamental (U, signed), in-phase third harmonic (U),
        frequency ``1 / (2 half period)`` (Hz), the fit's residual sum of squares (U^2) and
        degrees of freedom, and the harmonic's variance per unit noise variance, of each half
        cycle with :data:`MIN_SAMPLES` samples or more; empty when fewer than 3 are.
    """
    x = np.asarray(x, dtype=np.float64)
    crossings = np.asarray(crossings, dtype=np.float64)
    spans = [(a, b) for a, b in zip(crossings[:-1], crossings[1:])
             if _samples(fs, a, b, x.size) >= MIN_SAMPLES]
    if len(spans) < 3:
        return np.empty((0, ROW_WIDTH))
    mid = np.array([0.5 * (a + b) for a, b in spans])
    first = np.array([_half_cycle(x, fs, a, b, 0.0, None) for a, b in spans])
    if np.any(first[:, 0] == 0.0):
        return np.empty((0, ROW_WIDTH))
    rate, bend = _log_slopes(first[:, 0], mid)
    second = np.array([_half_cycle(x, fs, a, b, r, None, g)
                       for (a, b), r, g in zip(spans, rate, bend)])
    rate, bend = _log_slopes(second[:, 0], mid)
    padded = np.concatenate((second[:1, 2], second[:, 2], second[-1:, 2]))
    smooth = 0.25 * padded[:-2] + 0.5 * padded[1:-1] + 0.25 * padded[2:]
    rows = []
    for (a, b), m, r, d, g in zip(spans, mid, rate, smooth, bend):
        a1, a3, _, rss, dof, unit = _half_cycle(x, fs, a, b, r, d, g)
        rows.append((m, a1, a3, 0.5 / (b - a), rss, dof, unit))
    return np.array(rows).reshape(-1, ROW_WIDTH)


def crest_harmonic(x: Any, fs: float, crossings: Sequence[Any], *,
                   quantity: str = "velocity") -> CrestHarmonic | None:
    """In-phase third harmonic of a mode's largest half cycles, beyond its stiffness's share.

    Parameters
    ----------
    x
        Samples of one mode (velocity, U/s, displacement, U, or acceleration, U/s^2), at
        ``fs``: another mode's oscillation projects onto the half cycles (take its band off
        first, as :func:`.identify.identify` does).
    fs
        Sample rate, Hz.
    crossings
        One array per free decay: the mode's zero-crossing times, s from ``x``'s first sample,
        increasing (those of its band signal: a chain's compression does not move them).
    quantity
        ``"velocity"``, ``"displacement"`` or ``"acceleration"``: sets the stiffness's share.

    Returns
    -------
    CrestHarmonic or None
        None when fewer than :data:`MIN_HALF_CYCLES` half cycles of :data:`MIN_SAMPLES`
        samples or more stand above :data:`TOP_SHARE` of the largest.

    Raises
    ------
    AnalysisError
        Bad sample rate, NaN/inf in the record, an unknown quantity.

    Examples
    --------
    A 20 Hz decay read through a chain that compresses a value of 1 by 5 %: its largest
    whole half cycle (0.92) carries -0.05 * 0.92^2 / 4 of a third harmonic, over a
    fundamental read 3 % low:

    >>> import numpy as np
    >>> from fsi_lab.dsp.crest import crest_harmonic
    >>> from fsi_lab.dsp.instantaneous import half_cycles
    >>> fs = 5000.0
    >>> t = np.arange(int(2 * fs)) / fs
    >>> v = np.exp(-2.0 * t) * np.cos(2 * np.pi * 20.0 * t)
    >>> read = v * (1 - 0.05 * v ** 2)
    >>> found = crest_harmonic(read, fs, [half_cycles(v, fs, 20.0).crossings])
    >>> print(f"{found.ratio:+.4f} +- {found.stderr:.4f}")
    -0.0114 +- 0.0000
    """
    func = "crest_harmonic"
    fs = check_rate(fs, func)
    x = as_record(x, func, min_samples=16, check_clipping=False, allow_constant=True)
    if quantity not in STIFFNESS_HARMONIC:
        raise fail(func, f"quantity = {quantity!r}; expected one of "
                         f"{', '.join(STIFFNESS_HARMONIC)}")
    _check_crossings(crossings)
    return pooled_crest([half_cycle_harmonics(x, fs, c) for c in crossings if np.size(c) >= 4],
                        quantity)


def pooled_crest(rows: Sequence[np.ndarray], quantity: str = "velocity",
                 reference: Sequence[np.ndarray] | None = None) -> CrestHarmonic | None:
    """:func:`crest_harmonic` from the rows of :func:`half_cycle_harmonics` of each decay:
    the half cycles above :data:`TOP_SHARE` of the largest, the in-phase ratio growing as the
    amplitude squared, the stiffness's share from their half periods (weighted as the square
    of the amplitude). None when fewer than :data:`MIN_HALF_CYCLES` are left.

    With ``reference`` (rows of the same decays, in the same order, from a record that holds
    everything but what is looked for: the fitted model of the record), each half cycle's
    harmonic and frequency are taken less those of the reference's half cycle it falls on
    (the nearest in time, within a quarter of a half period, of the same sign and within a
    factor of two; half cycles without one are left out): what both hold (a damping law's
    in-phase share, a band filter's smear of the first crossings, an acceleration's half
    periods, which its damping's phase moves with the amplitude) then cancels half cycle by
    half cycle instead of on the average, and the scatter left about the ``A^2`` law is the
    record's noise.
    """
    if reference is not None:
        rows = [_excess(r, m) for r, m in zip(rows, reference)]
    rows = [r for r in rows if r.size]
    if not rows:
        return None
    h = np.concatenate(rows)
    top = float(np.max(np.abs(h[:, 1])))
    h = h[np.abs(h[:, 1]) >= TOP_SHARE * top]
    if h.shape[0] < MIN_HALF_CYCLES:
        return None
    a1, a3, freq = h[:, 1], h[:, 2], h[:, 3]
    square = (a1 / top) ** 2
    u = a1 * square
    measured, measured_se, _ = _slope(u, a3, intercept=False)
    noise_var = float(np.sum(h[:, 4]) / max(float(np.sum(h[:, 5])), 1.0))
    noise_se = math.sqrt(noise_var * float(np.sum(u * u * h[:, 6]))) / float(np.sum(u * u))
    # (a half period's crossings move with the noise over the half cycle's slope: its
    # frequency's variance grows as 1 / A^2)
    shift, shift_se, f_lin = _slope(square, freq, intercept=True, weight=square)
    rho = STIFFNESS_HARMONIC[quantity]
    stiffness = rho * shift / f_lin
    stderr = math.hypot(measured_se, rho * shift_se / f_lin)
    return CrestHarmonic(ratio=measured - stiffness, stderr=stderr, measured=measured,
                         noise_stderr=noise_se, stiffness=stiffness,
                         half_cycles=int(h.shape[0]), amplitude=top)


def _excess(rows: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``rows`` of one decay less ``reference``'s: each half cycle's third harmonic less its
    fundamental times the harmonic ratio of the reference's half cycle nearest in time (within
    a quarter of its half period, of the same sign and within a factor of two), its frequency
    less that half cycle's plus the reference's mean (a frequency still, for the stiffness's
    share); half cycles without such a partner are left out."""
    if not rows.size or not reference.size:
        return np.empty((0, ROW_WIDTH))
    partner = reference[np.argmin(np.abs(reference[None, :, 0] - rows[:, None, 0]), axis=1)]
    # (of the same sign and within a factor of two: a reference that left the decay out,
    # a fit gone astray, pairs with nothing)
    share = partner[:, 1] / rows[:, 1]
    paired = (np.abs(partner[:, 0] - rows[:, 0]) < 0.125 / rows[:, 3]) \
        & (share > 0.5) & (share < 2.0)
    out = rows[paired].copy()
    partner = partner[paired]
    out[:, 2] -= out[:, 1] * partner[:, 2] / partner[:, 1]
    out[:, 3] += float(np.mean(reference[:, 3])) - partner[:, 3]
    return out


def _check_crossings(crossings: Sequence[Any]) -> None:
    """Each decay's crossings: finite, increasing times, s."""
    for c in crossings:
        c = np.asarray(c, dtype=np.float64)
        if c.ndim != 1 or not np.all(np.isfinite(c)) or np.any(np.diff(c) <= 0):
            raise fail("crest_harmonic", "crossings must be one array of finite, increasing "
                                         "times (s) per decay: the mode's zero crossings")

