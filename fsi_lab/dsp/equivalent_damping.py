"""Linear and quadratic damping coefficients by harmonic balance (the paper's Eqs. 24-25).

For ``(mu + M) q'' + (C_i + C_f |q'|) q' + k q = 0`` the harmonic balance gives the equivalent
viscous coefficient ``C_q = C_i + 8 C_f omega W / (3 pi)`` (Eq. 24) at displacement amplitude
W, while a measured damping ratio zeta at frequency f gives ``C_q = 2 zeta (mu + M) 2 pi f``
(Eq. 25). A first-order least-squares fit of C_q against ``8 omega W / (3 pi)`` (omega taken
point by point) gives C_i (intercept) and C_f (slope), with R^2 and t-distribution confidence
intervals.

Amplitude convention
--------------------
The coefficients belong to the coordinate in which W is measured. By default W is the
displacement amplitude at the measuring point (``modal_scale = 1``). For the modal coordinate
q_n of Eq. 20 (``w(x, t) = sum W_n(x) q_n(t)`` with the mode shapes of Eq. 15, normalised so
that ``int_0^L W_n^2 dx = L``, |W_n(L)| = 2), pass ``modal_scale = W_n(x_meas)``: then
``W_modal = W / modal_scale``. zeta, and hence C_q, do not depend on the coordinate; C_f scales
with ``modal_scale`` and C_i does not. The identified C_i and C_f can then be put straight back
into Eq. 20.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.stats as sstats

from fsi_lab.dsp._signal import fail
from fsi_lab.dsp.choices import WEIGHTINGS


@dataclass(frozen=True)
class EquivalentDamping:
    """Result of the C_q = C_i + (8 C_f omega / (3 pi)) W fit.

    Attributes
    ----------
    c_i
        Linear (material) damping per length, kg/(m s) (= N s/m^2).
    c_f
        Quadratic (fluid) damping per length, kg/m^2.
    r2
        Coefficient of determination of the fit (0..1; weighted like the fit).
    c_i_ci95, c_f_ci95
        Confidence intervals (level ``confidence``, default 95 %), from the t-distribution.
    c_i_se, c_f_se
        Standard errors.
    amplitude
        W used in the fit (after ``modal_scale``), m.
    c_q
        Equivalent damping per point, kg/(m s).
    regressor
        ``8 omega W / (3 pi)`` per point, m/s.
    n
        Number of points.
    confidence
        Level of the intervals.
    """

    c_i: float
    c_f: float
    r2: float
    c_i_ci95: tuple[float, float]
    c_f_ci95: tuple[float, float]
    c_i_se: float
    c_f_se: float
    amplitude: np.ndarray
    c_q: np.ndarray
    regressor: np.ndarray
    n: int
    confidence: float

    def as_summary(self) -> dict[str, Any]:
        """JSON-ready ``{"c_i", "c_f", "r2", "c_i_ci95", "c_f_ci95", ...}``."""
        return {"c_i": self.c_i, "c_f": self.c_f, "r2": self.r2,
                "c_i_ci95": list(self.c_i_ci95), "c_f_ci95": list(self.c_f_ci95),
                "c_i_se": self.c_i_se, "c_f_se": self.c_f_se, "points": self.n}


def equivalent_coefficient(zeta: Any, frequency: Any, mass_per_length: float) -> np.ndarray:
    """Eq. 25: ``C_q = 2 zeta (mu + M) 2 pi f``, kg/(m s), from zeta and f (Hz)."""
    return 2.0 * np.asarray(zeta, dtype=np.float64) * mass_per_length * 2.0 * math.pi \
        * np.asarray(frequency, dtype=np.float64)


def equivalent_damping(amplitude: Any, zeta: Any, frequency: Any, mass_per_length: float, *,
                       modal_scale: float = 1.0, confidence: float = 0.95,
                       weighting: str = "amplitude") -> EquivalentDamping:
    """Fit C_i and C_f to a damping curve (Eqs. 24-25).

    Parameters
    ----------
    amplitude
        Displacement amplitude W at each point, m (at the measuring point; see ``modal_scale``).
    zeta
        Damping ratio at each point.
    frequency
        Instantaneous frequency at each point, Hz.
    mass_per_length
        mu + M, kg/m (beam mass per length plus added fluid mass).
    modal_scale
        W_n(x_meas) of the mode in the normalisation of Eq. 15 to fit in the modal coordinate
        of Eq. 20 (W_modal = W / modal_scale); 1 (default) keeps the measured amplitude.
    confidence
        Level of the confidence intervals (0..1).
    weighting
        ``"amplitude"`` (default): weighted least squares with weights W^2. Additive measurement
        noise of RMS sigma puts an error of about sigma / W on ln A, hence on each decrement
        and on C_q, so the small-amplitude end of a decay is much noisier than its start;
        weighting by W^2 (inverse variance) keeps the tail from dominating. ``"uniform"``:
        ordinary least squares as in the paper.

    Returns
    -------
    EquivalentDamping

    Raises
    ------
    AnalysisError
        Arrays of different lengths, NaN/inf, non-positive amplitude, frequency, mass or scale,
        fewer than 3 points, or amplitudes that do not vary (the slope is undetermined).
    """
    func = "equivalent_damping"
    w = np.asarray(amplitude, dtype=np.float64)
    z = np.asarray(zeta, dtype=np.float64)
    f = np.asarray(frequency, dtype=np.float64)
    if w.ndim != 1 or z.shape != w.shape or f.shape != w.shape:
        raise fail(func, f"amplitude {w.shape}, zeta {z.shape} and frequency {f.shape} must be "
                         "1-D arrays of the same length")
    if w.size < 3:
        raise fail(func, f"{w.size} point(s) given; the linear fit with confidence intervals "
                         "needs at least 3 damping points (a longer decay or fewer points "
                         "dropped)")
    if not (np.all(np.isfinite(w)) and np.all(np.isfinite(z)) and np.all(np.isfinite(f))):
        raise fail(func, "amplitude, zeta or frequency contain NaN or inf")
    for name, value in (("mass_per_length", mass_per_length), ("modal_scale", modal_scale)):
        if not isinstance(value, (int, float)) or isinstance(value, bool) \
                or not math.isfinite(value) or value == 0 or (name == "mass_per_length"
                                                               and value < 0):
            raise fail(func, f"{name} = {value!r}; expected a finite number"
                             + (" > 0 kg/m" if name == "mass_per_length" else " != 0"))
    if np.any(w <= 0) or np.any(f <= 0):
        raise fail(func, "amplitudes and frequencies must be > 0")
    if not (0.0 < confidence < 1.0):
        raise fail(func, f"confidence = {confidence!r}; expected a level in (0, 1)")
    wm = w / abs(float(modal_scale))
    cq = equivalent_coefficient(z, f, float(mass_per_length))
    u = 8.0 * 2.0 * math.pi * f * wm / (3.0 * math.pi)
    if weighting not in WEIGHTINGS:
        raise fail(func, f"weighting = {weighting!r}; expected one of {', '.join(WEIGHTINGS)}")
    wt = wm * wm if weighting == "amplitude" else np.ones_like(wm)
    wt = wt / wt.mean()
    n = u.size
    sw = float(wt.sum())
    um = float(wt @ u) / sw
    cm = float(wt @ cq) / sw
    sxx = float(wt @ (u - um) ** 2)
    if sxx <= 1e-24 * max(float(wt @ (u * u)), 1e-300):
        raise fail(func, "the amplitudes do not vary, so C_f (the slope) is undetermined; "
                         "the fit needs a decay over a range of amplitudes")
    slope = float(wt @ ((u - um) * (cq - cm))) / sxx
    icpt = cm - slope * um
    resid = cq - (icpt + slope * u)
    sse = float(wt @ (resid * resid))
    sst = float(wt @ (cq - cm) ** 2)
    r2 = 1.0 - sse / sst if sst > 0 else 1.0
    dof = n - 2
    s2 = sse / dof if dof > 0 else 0.0
    se_slope = math.sqrt(s2 / sxx)
    se_icpt = math.sqrt(s2 * (1.0 / sw + um * um / sxx))
    q = float(sstats.t.ppf(0.5 + 0.5 * confidence, dof)) if dof > 0 else float("inf")
    return EquivalentDamping(
        c_i=icpt, c_f=slope, r2=float(r2),
        c_i_ci95=(icpt - q * se_icpt, icpt + q * se_icpt),
        c_f_ci95=(slope - q * se_slope, slope + q * se_slope),
        c_i_se=se_icpt, c_f_se=se_slope, amplitude=wm, c_q=cq, regressor=u, n=n,
        confidence=float(confidence))


def equivalent_damping_from_envelope(a: float, b: float, a_se: float, b_se: float, dof: int,
                                     frequency: Any, mass_per_length: float, *,
                                     modal_scale: float = 1.0, confidence: float = 0.95
                                     ) -> tuple[float, float, tuple[float, float],
                                                tuple[float, float]]:
    """C_i and C_f from a fitted envelope law ``dA/dt = -a A - b A^2`` (damping "envelope-fit").

    For ``m q'' + (C_i + C_f |q'|) q' + k q = 0``: ``a = C_i / (2 m)`` and
    ``b = 4 C_f omega / (3 pi m)``, so ``C_i = 2 m a`` and ``C_f = 3 pi m b / (4 omega)`` with
    omega the mean angular frequency of ``frequency`` (Hz). ``b`` is per unit of the measured
    amplitude; ``modal_scale`` converts to the modal coordinate as in
    :func:`equivalent_damping` (C_f scales with it).

    Returns
    -------
    c_i, c_f, c_i_ci, c_f_ci
        kg/(m s), kg/m^2 and their confidence intervals (t-distribution, ``dof`` degrees of
        freedom, level ``confidence``).
    """
    func = "equivalent_damping_from_envelope"
    f = np.asarray(frequency, dtype=np.float64)
    if f.size == 0 or not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise fail(func, "frequencies must be finite and > 0 Hz")
    if not (mass_per_length > 0 and math.isfinite(mass_per_length)):
        raise fail(func, f"mass_per_length = {mass_per_length!r}; expected a finite number > 0")
    omega = 2.0 * math.pi * float(f.mean())
    m = float(mass_per_length)
    k_f = 3.0 * math.pi * m * abs(float(modal_scale)) / (4.0 * omega)
    c_i = 2.0 * m * a
    c_f = k_f * b
    q = float(sstats.t.ppf(0.5 + 0.5 * confidence, max(1, int(dof))))
    return (c_i, c_f, (c_i - q * 2.0 * m * a_se, c_i + q * 2.0 * m * a_se),
            (c_f - q * k_f * b_se, c_f + q * k_f * b_se))
