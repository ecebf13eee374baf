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

from fsi_lab.plugins.analysis._signal import fail


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


WEIGHTINGS = ("amplitude", "uniform")


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


# ----------------------------------------------------------------------------- plugin
from fsi_lab.contract import AnalysisContext, AnalysisPlugin, AnalysisResult  # noqa: E402
from fsi_lab.errors import AnalysisError  # noqa: E402
from fsi_lab.hookspecs import hookimpl  # noqa: E402
from fsi_lab.params import Param  # noqa: E402
from fsi_lab.plugins.analysis._chain import (  # noqa: E402
    decay_summary, displacement_components, error_entries, guarded, jsonable, per_component,
    where,
)

METHODS = ("regression", "envelope")


def specimen_mass_per_length(specimen: Any) -> float:
    """mu + M = rho width thickness + rho_f pi (width / 2)^2 (Eq. 10), kg/m."""
    fluid = getattr(specimen, "fluid_density", None)
    if fluid is None:
        from fsi_lab.specimen import FLUID_DENSITY
        fluid = FLUID_DENSITY[specimen.fluid]
    return float(specimen.density * specimen.width * specimen.thickness
                 + fluid * math.pi * (specimen.width / 2.0) ** 2)


def modal_scale_from_beam(specimen: Any, frequency_hz: float, mode: int | None = None
                          ) -> tuple[float, int] | None:
    """Hook point for the modal conversion: ``W_n(x_meas)`` of the beam model, or None.

    Uses :mod:`fsi_lab.beam` when it is importable and offers ``BeamModel.from_specimen``,
    ``natural_frequencies_hz`` and ``mode_shape(x, n)`` (Eq. 15, normalised so that
    ``int W_n^2 = L``). The mode is ``mode`` (1-based) if given, else the one whose calculated
    natural frequency is nearest (in ratio) to ``frequency_hz`` - the shaker's suspension shifts
    the measured modes by up to about 15 %, far less than the spacing of the beam's modes.
    Returns ``(|W_n(x_meas)|, n)``, or None when no beam model is available or the mode shape
    vanishes at the measuring point (a node: the mode cannot be measured there).
    """
    try:
        from fsi_lab import beam
        model_cls = beam.BeamModel
        n_modes = max(8, int(mode or 0))
        model = model_cls.from_specimen(specimen, modes=n_modes)
        if mode is None:
            fn = np.asarray(model.natural_frequencies_hz, dtype=np.float64)
            mode = 1 + int(np.argmin(np.abs(np.log(fn / float(frequency_hz)))))
        value = abs(float(np.asarray(model.mode_shape(specimen.measurement_point, mode))))
    except Exception:  # noqa: BLE001 - no usable beam model: amplitudes stay as measured
        return None
    if not math.isfinite(value) or value < 1e-6:
        return None
    return value, int(mode)


def _run(context: AnalysisContext, params: dict[str, Any]) -> AnalysisResult:
    plugin = "equivalent-damping"
    if context.mass_per_length is not None:
        mass = float(context.mass_per_length)
        mass_source = "given (--mass-per-length)"
    elif context.specimen is not None:
        mass = specimen_mass_per_length(context.specimen)
        mass_source = "specimen: rho width thickness + rho_f pi (width/2)^2"
    else:
        raise AnalysisError(
            f"{where(plugin, context)}: needs mu + M, the mass per length of beam plus added "
            "fluid mass: pass --mass-per-length KG_PER_M or give the profile a [specimen]")
    with guarded(plugin, context):
        disp = displacement_components(context, plugin)
    from fsi_lab.plugins.analysis.damping import curve_for, damping_from_peaks, trusted_peaks

    prior = context.results.get("damping")
    prior_curves = prior.values if prior is not None and isinstance(prior.values, dict) else {}
    defaults = {"method": "decrement", "span": 2, "window": 6, "smooth_points": 0,
                "offset": "cycles", "min_amplitude": None, "decay_only": True}
    conventions: dict[int, str] = {}

    def scale_for(k: int, f_hz: float) -> float:
        given = params["modal_scale"]
        if given is not None:
            conventions[k] = f"modal (modal_scale = {given:g} given)"
            return float(given)
        if context.specimen is not None:
            found = modal_scale_from_beam(context.specimen, f_hz, params["mode"])
            if found is not None:
                conventions[k] = (f"modal: q_{found[1]} = w(x_meas) / W_{found[1]}(x_meas), "
                                  f"W_{found[1]}(x_meas) = {found[0]:.6g} (Eq. 15, "
                                  "int W^2 = L)")
                return found[0]
            conventions[k] = "measured (no beam model available for the modal conversion)"
            return 1.0
        conventions[k] = "measured (displacement amplitude at the measuring point)"
        return 1.0

    def work(c):
        with guarded(plugin, context):
            if params["method"] == "envelope":
                t, a, f, decay, decays = trusted_peaks(c, defaults)
                curve = damping_from_peaks(t, a, f, method="envelope-fit", decay=decay)
                p = curve.params
                scale = scale_for(c.index, float(np.mean(curve.frequency)))
                c_i, c_f, ci_i, ci_f = equivalent_damping_from_envelope(
                    p["a"], p["b"], p["a_se"], p["b_se"], int(p["dof"]), curve.frequency,
                    mass, modal_scale=scale, confidence=params["confidence"])
                resid = a - curve.amplitude
                r2 = 1.0 - float(resid @ resid) / float(np.sum((a - a.mean()) ** 2))
                cq = equivalent_coefficient(curve.zeta, curve.frequency, mass)
                return {"c_i": c_i, "c_f": c_f, "r2": r2, "c_i_ci95": list(ci_i),
                        "c_f_ci95": list(ci_f), "points": int(t.size),
                        **decay_summary(decays, c.t0),
                        "amplitude": curve.amplitude / scale, "c_q": cq}
            curve = prior_curves.get(c.index) or curve_for(c, defaults)
            scale = scale_for(c.index, float(np.mean(curve.frequency)))
            res = equivalent_damping(curve.amplitude, curve.zeta, curve.frequency, mass,
                                     modal_scale=scale, confidence=params["confidence"],
                                     weighting=params["weighting"])
            return {**res.as_summary(), **decay_summary(curve.decays, c.t0),
                    "amplitude": res.amplitude, "c_q": res.c_q,
                    "damping_method": curve.method}

    done, errors = per_component(plugin, context, disp, work)
    entries = []
    for k, r in done.items():
        summary = {key: jsonable(v) for key, v in r.items() if key not in ("amplitude", "c_q")}
        summary.update(mass_per_length=mass, method=params["method"],
                       amplitude_convention=conventions.get(k, "measured"))
        entries.append({"index": k, "equivalent_damping": summary})
    err_entries, err_attrs = error_entries(errors, "equivalent_damping")
    from fsi_lab.plugins.analysis._chain import stack_rows
    count = len(disp)
    attrs = {"mass_per_length": mass, "mass_per_length_source": mass_source,
             "method": params["method"], "weighting": params["weighting"],
             "confidence": params["confidence"],
             "amplitude_convention": "; ".join(f"component {k}: {v}"
                                               for k, v in sorted(conventions.items())),
             **err_attrs}
    for k, r in done.items():
        for key in ("c_i", "c_f", "r2"):
            attrs[f"component_{k}_{key}"] = float(r[key])
    return AnalysisResult(
        datasets={"amplitude": stack_rows({k: r["amplitude"] for k, r in done.items()}, count),
                  "c_q": stack_rows({k: r["c_q"] for k, r in done.items()}, count)},
        units={"amplitude": "m", "c_q": "kg/(m s)"},
        attrs=attrs, summary={"components": entries + err_entries}, values=done)


PLUGIN = AnalysisPlugin(
    name="equivalent-damping",
    params=(
        Param("method", "str", "", "regression", choices=METHODS,
              help="regression: the paper's first-order fit of C_q = 2 zeta (mu+M) 2 pi f "
                   "against displacement amplitude (uses the chain's damping curves); "
                   "envelope: direct fit of the linear + quadratic envelope law to the peaks."),
        Param("weighting", "str", "", "amplitude", choices=WEIGHTINGS,
              help="regression weights: amplitude (W^2, inverse noise variance) or uniform "
                   "(ordinary least squares)."),
        Param("confidence", "float", "", 0.95, minimum=0.5, maximum=0.999,
              help="Level of the confidence intervals (t-distribution)."),
        Param("modal_scale", "float", "", None,
              help="W_n(x_meas) (Eq. 15 normalisation) to express amplitudes in the modal "
                   "coordinate; unset = from the beam model when the run has a specimen, else "
                   "1 (amplitudes as measured)."),
        Param("mode", "int", "", None, minimum=1,
              help="Mode number for the modal conversion; unset = nearest calculated natural "
                   "frequency."),
    ),
    run=_run,
    help="Linear (C_i, kg/(m s)) and quadratic (C_f, kg/m^2) damping per length from the "
         "damping curve by harmonic balance (Eqs. 24-25), with R^2 and 95 % intervals; needs "
         "mu + M from --mass-per-length or the profile's [specimen].",
)


@hookimpl
def fsi_lab_analyses():
    return [PLUGIN]
