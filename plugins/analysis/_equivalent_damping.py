"""The work of the ``equivalent-damping`` analysis plugin (declared in
:mod:`.equivalent_damping`): an adapter around :mod:`fsi_lab.dsp.equivalent_damping`."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from fsi_lab.contract import AnalysisContext
from fsi_lab.dsp.components import BandComponents
from fsi_lab.dsp.coupling import release_shift
from fsi_lab.dsp.damping import damping_decrement
from fsi_lab.dsp.equivalent_damping import (
    equivalent_coefficient,
    equivalent_damping,
    equivalent_damping_from_envelope,
)
from fsi_lab.errors import AnalysisError
from fsi_lab.params import validate
from fsi_lab.plugins.analysis._chain import (
    components,
    decay_summary,
    displacement_components,
    guarded,
    per_component,
    where,
)
from fsi_lab.plugins.analysis.damping import PLUGIN as DAMPING
from fsi_lab.plugins.analysis.results import (
    CoefficientFit,
    Components,
    DampingCoefficients,
    DampingCurves,
)
from fsi_lab.units import voltage_hint


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


def chain_gain(params: dict[str, Any], f_hz: float) -> tuple[float, str]:
    """The gain at ``f_hz`` (Hz) of the measuring chain's filters the parameters describe
    (``highpass_hz``, ``lowpass_hz``: Butterworth corners, Hz, of orders ``highpass_order``
    and ``lowpass_order``), and the words that say so (empty when there are none).

    A filter whose corner lies near a mode passes it with a gain G below 1: every amplitude
    of the mode is read G times its size, so C_f (damping per unit amplitude) would come out
    1/G times too large; the analysis divides the amplitudes by G."""
    gain, parts = 1.0, []
    for kind, corner, order in (("high-pass", params.get("highpass_hz"),
                                 params.get("highpass_order", 1)),
                                ("low-pass", params.get("lowpass_hz"),
                                 params.get("lowpass_order", 4))):
        if corner is None:
            continue
        ratio = float(corner) / f_hz if kind == "high-pass" else f_hz / float(corner)
        gain /= math.sqrt(1.0 + ratio ** (2 * int(order)))
        parts.append(f"{kind} at {float(corner):g} Hz, order {int(order)}")
    if not parts:
        return 1.0, ""
    return gain, (f"; amplitudes divided by the measuring chain's gain {gain:.4g} at "
                  f"{f_hz:.4g} Hz ({', '.join(parts)}, Butterworth)")


def amplitude_convention(context: AnalysisContext, params: dict[str, Any], f_hz: float
                         ) -> tuple[float, str]:
    """``modal_scale`` for a component at ``f_hz`` (Hz), times the measuring chain's gain
    there (:func:`chain_gain`), and the words that say which amplitude the coefficients
    belong to (see :mod:`fsi_lab.dsp.equivalent_damping`)."""
    scale, words = _coordinate(context, params, f_hz)
    gain, said = chain_gain(params, f_hz)
    return scale * gain, words + said


def _coordinate(context: AnalysisContext, params: dict[str, Any], f_hz: float
                ) -> tuple[float, str]:
    """``modal_scale`` for a component at ``f_hz`` (Hz) and the words that say which
    coordinate the coefficients belong to."""
    given = params["modal_scale"]
    if given is not None:
        return float(given), f"modal (modal_scale = {given:g} given)"
    if context.specimen is not None:
        found = modal_scale_from_beam(context.specimen, f_hz, params["mode"])
        if found is not None:
            return found[0], (f"modal: q_{found[1]} = w(x_meas) / W_{found[1]}(x_meas), "
                              f"W_{found[1]}(x_meas) = {found[0]:.6g} (Eq. 15, int W^2 = L)")
        return 1.0, "measured (no beam model available for the modal conversion)"
    return 1.0, "measured (displacement amplitude at the measuring point)"


#: A release whose mean displacement keeps less than this share of what it let go is read as
#: seen through a high-pass (:func:`fsi_lab.dsp.coupling.release_shift`; a DC-coupled one keeps
#: about all of it).
RELEASE_KEPT = 0.5
#: ... and the components whose C_f that high-pass would raise by more than this are warned.
COUPLING_BIAS = 0.005


def coupling_warnings(context: AnalysisContext, params: dict[str, Any]) -> dict[int, str]:
    """Per component, a sentence when the channel's record starts with a release whose mean
    displacement returns to where it started, as behind a high-pass in the measuring chain
    (:mod:`fsi_lab.dsp.coupling`), and that high-pass would raise the component's C_f by more
    than :data:`COUPLING_BIAS`. None is looked for when the chain's high-pass is given
    (``highpass_hz``), the channel is not a velocity, or the components are of the motion
    relative to a base (whose integration has a high-pass of its own)."""
    found = context.result(Components)
    ident = found.identification if found is not None else None
    ch = context.channel
    if ident is None or not ident.modes or params.get("highpass_hz") is not None \
            or found.relative_to or ch.quantity != "velocity":
        return {}
    lowest = min(m.frequency_hz for m in ident.modes)
    shift = release_shift(np.asarray(ch.data, dtype=np.float64), float(ch.sample_rate), lowest,
                          max(float(ident.noise_rms), 1e-300), free=ident.free_windows[0][1])
    if shift is None or shift.ratio >= RELEASE_KEPT:
        return {}
    out = {}
    for k, mode in enumerate(ident.modes):
        gain = shift.gain(mode.frequency_hz)
        if 1.0 / gain - 1.0 <= COUPLING_BIAS:
            continue
        out[k] = (
            f"the record's mean displacement returns to where it was before the release at "
            f"{shift.start / float(ch.sample_rate) + float(ch.t0):.4g} s (it keeps "
            f"{100 * shift.ratio:.0f} % of the displacement the release let go, where a "
            "DC-coupled record keeps all of it): a high-pass in the measuring chain does this "
            "(an AC-coupled channel, a sensor's or decoder's high-pass), here with a corner of "
            f"about {shift.corner_hz:.2g} Hz (first order), which reads this mode's amplitudes "
            f"up to {100 * (1 - gain):.1f} % low and C_f up to {100 * (1 / gain - 1):.1f} % high "
            "(C_i and the frequency are hardly affected); if the channel is AC-coupled, give "
            "its corner (--set analysis.equivalent-damping.highpass_hz=HZ, and highpass_order) "
            "and C_f is corrected; an excitation that leaves no net impulse, rather than a "
            "release, moves the mean as little")
    return out


def _law_entry(mode: Any, mass: float, scale: float, level: float) -> dict[str, Any]:
    """C_i, C_f and the law comparison of one identified mode (method ``law``)."""
    quad = mode.quadratic
    if not np.all(np.isfinite(quad.se)):
        # A fit driven where its model decay explodes pins nothing down (fsi_lab.dsp.laws).
        raise AnalysisError(
            f"component {mode.index} at {mode.frequency_hz:.4g} Hz: the linear + quadratic "
            "law does not determine C_i and C_f on this record (its fit diverges: the decay "
            "grows under it); no coefficients are reported")
    a, beta = quad.value("a"), quad.value("beta")
    (a_lo, a_hi), (b_lo, b_hi) = quad.interval("a", level), quad.interval("beta", level)
    r2 = mode.start_drift.get("joint_r2")
    if r2 is None:                   # (a mode fitted with its close neighbours has the joint fit's)
        amp = np.concatenate([d.amplitude for d in mode.decays])
        model = np.concatenate(quad.model)
        r2 = 1.0 - float(np.sum((amp - model) ** 2)) / max(
            float(np.sum((amp - amp.mean()) ** 2)), 1e-300)
    omega = 2.0 * math.pi * mode.frequency_hz
    laws = {name: _law_entry_of(fit, float(mode.laws.delta[name]), mass, scale, level,
                                name == mode.laws.preferred, omega)
            for name, fit in mode.laws.fits.items()}
    entry = {"c_i": 2.0 * mass * a, "c_f": mass * beta * scale,
             "c_i_ci95": [2.0 * mass * a_lo, 2.0 * mass * a_hi],
             "c_f_ci95": [mass * scale * b_lo, mass * scale * b_hi],
             "c_i_se": 2.0 * mass * float(quad.se[0]), "c_f_se": mass * scale * float(quad.se[1]),
             "r2": r2, "points": mode.extrema_count, "decays": len(mode.decays),
             "decay_starts_s": [float(d.times[0]) for d in mode.decays],
             "decay_ends_s": [float(d.times[-1]) for d in mode.decays],
             "preferred_law": mode.laws.preferred, "laws": laws}
    if "fluid_power" in mode.start_drift:
        entry["fluid_power"] = mode.start_drift["fluid_power"]
        entry["fluid_power_ci95"] = [mode.start_drift["fluid_power_low"],
                                     mode.start_drift["fluid_power_high"]]
    if "crest_ratio" in mode.start_drift:
        entry["crest_harmonic"] = mode.start_drift["crest_ratio"]
        entry["crest_harmonic_se"] = max(mode.start_drift["crest_se"],
                                         mode.start_drift["crest_noise_se"])
    if "gamma" in mode.laws.fits[mode.laws.preferred].names:
        friction = laws[mode.laws.preferred]
        entry["friction_force_per_length"] = friction["friction_force_per_length"]
        entry["friction_force_per_length_ci95"] = friction["friction_force_per_length_ci95"]
    return entry


def _off_the_law(entry: dict[str, Any], law: dict[str, Any], method: str) -> str:
    """A sentence when the C_i or C_f of ``method`` (``entry``) lies outside the 95 % interval
    of the damping-law fit to the same mode's extrema (``law``, :func:`_law_entry`), else ""."""
    off = [name for name, key in (("C_i", "c_i"), ("C_f", "c_f"))
           if not law[f"{key}_ci95"][0] <= entry[key] <= law[f"{key}_ci95"][1]]
    if not off:
        return ""
    words = " and ".join(f"{name} = {entry[key]:.4g} (the law fit's: {law[key]:.4g}, 95 %: "
                         f"{law[f'{key}_ci95'][0]:.4g} to {law[f'{key}_ci95'][1]:.4g})"
                         for name, key in (("C_i", "c_i"), ("C_f", "c_f")) if name in off)
    return (f"the {method} method gives {words}, outside the interval of the damping law "
            "fitted to the same extrema (method 'law', the one the validation matrix "
            "holds to its targets): a fit to damping ratios measured over whole periods leans "
            "where the damping changes within a period (a large fluid share), and its "
            "interval takes them as independent")


def _law_entry_of(fit: Any, delta_aicc: float, mass: float, scale: float, level: float,
                  preferred: bool, omega: float) -> dict[str, Any]:
    """One law's entry of ``laws``: its AICc gap, parameters and standard errors (measured
    coordinate), and for the ``preferred`` law the coefficients per length they stand for
    with their intervals: C_i (kg/(m s)) from ``a``, C_f (kg/m^2) from ``beta``, the friction
    force (N/m) from ``gamma`` (a friction force per unit mass in the measured coordinate).
    A preferred viscous law also gives its damping ratio ``a / omega`` (``omega``: the mode's
    small-amplitude natural frequency, rad/s), the one number that law stands for.
    Another law's fit describes nothing the record supports (its coefficients may well be
    negative): it is given for the comparison, not as coefficients to read."""
    entry: dict[str, Any] = {
        "delta_aicc": delta_aicc,
        **{p: float(v) for p, v in zip(fit.names, fit.params)},
        **{f"{p}_se": float(s) if math.isfinite(s) else None
           for p, s in zip(fit.names, fit.se)}}
    if not preferred:
        return entry
    # In the coordinate the coefficients belong to (the measured amplitude over ``scale``),
    # a quadratic term's coefficient is beta times the scale and a friction force per unit
    # mass gamma over it (x = scale q in x'' + ... + beta |x'| x' + gamma sgn(x') = 0).
    per_length = {"a": ("c_i", 2.0 * mass), "beta": ("c_f", mass * scale),
                  "gamma": ("friction_force_per_length", mass / scale)}
    for name in fit.names:
        key, factor = per_length[name]
        low, high = fit.interval(name, level)
        finite = math.isfinite(low) and math.isfinite(high)
        entry[key] = factor * fit.value(name)
        entry[f"{key}_ci95"] = [factor * low, factor * high] if finite else None
        if fit.law == "viscous":
            entry["damping_ratio"] = fit.value(name) / omega
            entry["damping_ratio_ci95"] = [low / omega, high / omega] if finite else None
    return entry


def _law_points(mode: Any, mass: float, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """Displacement amplitude (m, in the amplitude convention) and C_q (kg/(m s)) from each
    pair of successive extrema of the same sign (the measured points of the C_q plot)."""
    amps, cqs = [], []
    w = 2.0 * math.pi * mode.frequency_hz
    for d in mode.decays:
        if d.amplitude.size < 3:
            continue
        curve = damping_decrement(d.times, d.amplitude, mode.frequency_hz, span=2)
        disp = curve.amplitude / (w if mode.quantity == "velocity" else 1.0)
        amps.append(disp / scale)
        cqs.append(equivalent_coefficient(curve.zeta, curve.frequency, mass))
    if not amps:
        return np.empty(0), np.empty(0)
    return np.concatenate(amps), np.concatenate(cqs)


def _run_law(context: AnalysisContext, params: dict[str, Any], mass: float, mass_source: str
             ) -> DampingCoefficients:
    """Method ``law``: C_i and C_f from the linear + quadratic law fitted by the ``bands``
    decomposition (:mod:`fsi_lab.dsp.identify`), with the law the record prefers."""
    plugin = "equivalent-damping"
    with guarded(plugin, context):
        comps = components(context)            # (refuses when hvd failed earlier)
    found = context.result(Components)
    ident = found.identification if found is not None else None
    if ident is None:
        raise AnalysisError(
            f"{where(plugin, context)}: method 'law' uses the damping laws fitted by hvd "
            "(method 'bands') earlier in the chain on this channel; put hvd before it, or use "
            "method = 'regression'")
    if context.channel.quantity not in ("displacement", "velocity", "acceleration"):
        raise AnalysisError(
            f"{where(plugin, context)}: the channel measures {context.channel.quantity!r} "
            f"({context.channel.unit}); C_i and C_f need a calibrated displacement, velocity "
            "or acceleration channel" + voltage_hint(context.channel.quantity))
    conventions: dict[int, str] = {}

    def work(c):
        mode = ident.modes[c.index]
        scale, conventions[c.index] = amplitude_convention(context, params, mode.frequency_hz)
        entry = _law_entry(mode, mass, scale, params["confidence"])
        amplitude, c_q = _law_points(mode, mass, scale)
        return {**entry, "amplitude": amplitude, "c_q": c_q}

    done, errors = per_component(plugin, context, comps, work)
    return _result(done, errors, conventions, len(comps), mass, mass_source, params,
                   coupling=coupling_warnings(context, params))


def _result(done: dict[int, dict], errors: dict[int, str], conventions: dict[int, str],
            count: int, mass: float, mass_source: str, params: dict[str, Any],
            warning: str | None = None, coupling: dict[int, str] | None = None
            ) -> DampingCoefficients:
    """The plugin's result from per-component entries (the summary's items, with ``amplitude``
    and ``c_q`` arrays for the datasets); ``coupling``: per component, a warning of a
    high-pass in the measuring chain (:func:`coupling_warnings`)."""
    fits = {k: CoefficientFit(c_i=float(r["c_i"]), c_f=float(r["c_f"]),
                              amplitude=np.asarray(r["amplitude"], dtype=np.float64),
                              c_q=np.asarray(r["c_q"], dtype=np.float64),
                              details={key: v for key, v in r.items()
                                       if key not in ("c_i", "c_f", "amplitude", "c_q")})
            for k, r in done.items()}
    return DampingCoefficients(fits=fits, mass_per_length=mass, mass_source=mass_source,
                               method=params["method"], weighting=params["weighting"],
                               confidence=params["confidence"], conventions=conventions,
                               count=count, warning=warning, errors=errors,
                               component_warnings={k: [w] for k, w in (coupling or {}).items()
                                                   if k in fits})


def run(context: AnalysisContext, params: dict[str, Any]) -> DampingCoefficients:
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
    fallback = None
    if params["method"] == "law":
        found = context.result(Components)
        if found is None or isinstance(found.decomposition, BandComponents):
            return _run_law(context, params, mass, mass_source)
        # Feldman's HVD components carry no law fit: the paper's regression, said so.
        params = {**params, "method": "regression"}
        fallback = ("C_i and C_f from the paper's regression of C_q against amplitude: the "
                    "damping-law fit needs hvd's method 'bands'")
    with guarded(plugin, context):
        disp = displacement_components(context, plugin)
    from fsi_lab.dsp.damping import damping_from_peaks
    from fsi_lab.plugins.analysis._damping import curve_for, trusted_peaks

    prior = context.result(DampingCurves)
    prior_curves = prior.curves if prior is not None else {}
    # Without damping earlier in the chain, its curves as damping gives them by default.
    defaults = validate(DAMPING.params, {}, "analysis.damping")
    conventions: dict[int, str] = {}

    def scale_for(k: int, f_hz: float) -> float:
        scale, conventions[k] = amplitude_convention(context, params, f_hz)
        return scale

    found = context.result(Components)
    ident = found.identification if found is not None else None

    def work(c):
        # A bands component has the damping-law fit too: the method's numbers are held to it.
        entry = fitted(c)
        if ident is not None and c.index < len(ident.modes):
            mode = ident.modes[c.index]
            scale, _ = amplitude_convention(context, params, mode.frequency_hz)
            try:
                law = _law_entry(mode, mass, scale, params["confidence"])
            except AnalysisError:
                return entry            # (a law fit that pins nothing down holds nothing)
            if said := _off_the_law(entry, law, params["method"]):
                entry["warnings"] = [said]
        return entry

    def fitted(c):
        with guarded(plugin, context):
            if params["method"] == "envelope":
                t, a, f, decay, decays = trusted_peaks(c, defaults, context)
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
            curve = prior_curves.get(c.index) or curve_for(c, defaults, context)
            scale = scale_for(c.index, float(np.mean(curve.frequency)))
            res = equivalent_damping(curve.amplitude, curve.zeta, curve.frequency, mass,
                                     modal_scale=scale, confidence=params["confidence"],
                                     weighting=params["weighting"])
            return {**res.as_summary(), **decay_summary(curve.decays, c.t0),
                    "amplitude": res.amplitude, "c_q": res.c_q,
                    "damping_method": curve.method}

    done, errors = per_component(plugin, context, disp, work)
    return _result(done, errors, conventions, len(disp), mass, mass_source, params, fallback,
                   coupling=coupling_warnings(context, params))
