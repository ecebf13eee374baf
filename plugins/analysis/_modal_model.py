"""Measured vs analytical model: the paper's Section 5.3 validation (Figs. 20 and 21), the work
of the ``modal-model`` analysis plugin (declared in :mod:`.modal_model`).

The beam model of Section 5 (:class:`fsi_lab.beam.BeamModel`, Eq. 20 with C_i and C_f) is driven
by the run's **measured** base acceleration (the ``[analysis] reference`` channel), and its
velocity at the measuring point goes through the same processing as the measurement:

1. simulation: :class:`fsi_lab.modal_integrator.ModalSimulator` at the record's sample rate (an
   integer multiple of it, with the acceleration held linear between samples as the integrator
   assumes, when the highest kept mode needs a smaller step), from rest at the reference's first
   sample; the output is then taken at the channel's own sample times (a vibrometer's signal
   delay makes its t0 differ from the reference's, as in :func:`._hvd.relative_signal`);
2. coordinate: when the measurement's HVD decomposed the motion relative to the base
   (``hvd.relative``), the model's relative velocity (Eq. 13, the modal model's own
   coordinate); otherwise its absolute velocity, as a vibrometer sees it. The measured signal
   compared is exactly what the measurement's HVD decomposed (its components plus residual).
   (Subtracting the measurement's base estimate from the model's absolute velocity instead was
   tried: the slow random walk of the integrated, noisy measured acceleration then spoils the
   model's decay tail more than the base estimate's own low-frequency error spoils the
   measurement's, on the simulated bench and in the tests alike.)
3. :func:`.hvd.hvd` from the measurement's start (``start_s``) with its number of components,
   its cut-offs, its padding and its band (``band_hz``); each measured component is paired
   with the model component of nearest mean frequency (within 25 %);
4. per pair: the HVD envelopes and instantaneous frequencies, then - on the displacement
   components (``integrate``'s for the measurement when it ran, integrated the same way for
   the model) - the zero-crossing backbone and damping curve of each component signal
   (:func:`component_curves`), with the same parameters on both sides. The model's components
   are cut from its output by the measurement's own filters, and measured on both sides alike
   their smear of the first cycles cancels; the ``backbone`` plugin reports a ``bands``
   component's backbone from its identification instead, the smear taken out.

C_i and C_f are this plugin's ``c_i`` / ``c_f`` when given, else the values the chain's
``equivalent-damping`` identified (in the modal coordinate of Eq. 20 when the run has a
specimen): those of the component of beam mode ``mode`` when given, else of the largest
component with a physical fit (finite, C_i >= 0, C_f >= 0).

Error figures (measured m, model s), over the free decay of each component: from the largest
measured envelope plus the HVD settling time (2 / cutoff) to where the measured envelope first
falls below the component's noise floor, HVD edges left out on both sides:

- ``envelope_rms_error`` = sqrt(mean((E_s - E_m)^2) / mean(E_m^2)) (dominated by the start);
- ``envelope_log_rms_error`` = sqrt(mean(ln(E_s / E_m)^2)) (every part of the decay alike);
- ``frequency_error_pct`` = 100 mean(f_s - f_m) / F_m of the HVD instantaneous frequencies,
  weighted by E_m (as the HVD's mean frequency is: the noisy tail counts little), over the
  component's measured frequency F_m (not over f_m sample by sample: a phase glitch that takes
  f_m through zero for a few samples would weigh without bound; samples where f_m is 50 % or
  more off F_m, or f_s off the model component's, phase glitches, are left out), and
  ``frequency_rms_error_pct`` its weighted RMS (:func:`frequency_errors`);
- ``backbone_error_pct`` = 100 mean((f_s(A) - f_m) / f_m) over the measured backbone points
  inside the decay span whose amplitude A lies within the model's (f_s(A) interpolated in
  ln A), weighted by A^2 (as ``equivalent-damping`` weights its fit: additive noise puts an
  error of about sigma / A on each point);
- ``damping_error_pct`` = 100 mean(zeta_s(A) - zeta_m) / mean(zeta_m) (bias) and
  ``damping_rms_error_pct`` = 100 sqrt(mean((zeta_s(A) - zeta_m)^2)) / mean(zeta_m) (includes
  the scatter of the measured curve), same points, same A^2 weights;
- ``velocity_rms_error`` (top level) = sqrt(mean((v_s - v_m)^2) / mean(v_m^2)), v the sum of
  the paired components of each side (the compared part of the signal: phase as well as
  envelope), over the decay span of the largest compared component.

Summary (``fsi-lab analyze --json``)
------------------------------------
Top level ``"modal_model"``:

``c_i``, ``c_f``
    Damping used, kg/(m s) and kg/m^2.
``c_source``
    Where they come from: ``"given"``, ``"equivalent-damping component K (mode N)"`` or both.
``modes``, ``projection``
    Modes kept in the model and the quadratic damping projection.
``natural_frequencies_hz``
    Calculated undamped natural frequencies of the model (Eq. 23), Hz.
``coordinate``
    ``"relative"`` (to the base) or ``"absolute"``.
``oversampling``
    Integration steps per sample.
``velocity_rms_error``
    See above (phase errors show here, e.g. a time shift between the channels).

Per component ``{"index": k, "modal_model": {...}}`` (merged by index):

``c_i``, ``c_f``
    As above.
``mode``
    Beam mode of the component (nearest calculated natural frequency).
``model_index``
    Row of the model's HVD paired with the component.
``natural_frequency_hz``, ``measured_frequency_hz``, ``model_frequency_hz``
    Calculated natural frequency of that mode; envelope-weighted mean HVD frequencies, Hz.
``decay_start_s``, ``decay_end_s``
    Span of the comparison, s from the channel's first sample.
``envelope_rms_error``, ``envelope_log_rms_error``, ``frequency_error_pct``,
``frequency_rms_error_pct``, ``backbone_error_pct``, ``damping_error_pct``,
``damping_rms_error_pct``
    See above (None when the overlap is too small to measure them).
``curves_error``
    Why the backbone and damping figures are None (too few cycles to measure the curves).
``error``
    Instead of the figures, when the component could not be compared.

Component switching (SCIENCE.md: where two envelopes cross, an HVD component can jump to the
other mode for a while) happens in the model's decomposition as in the measurement's, not
necessarily at the same time; such episodes show up in the errors as they would between two
measurements.

Datasets (``/analysis/<channel>/modal-model``; rows are measured component indices, padded
with NaN): ``velocity_measured``, ``velocity_model`` (the decomposed signals from ``start_s``
on, unit of the channel; ``signal_*`` for a displacement or acceleration channel);
``envelope_time`` (s) and ``envelope_measured``, ``envelope_model``,
``envelope_error`` ((E_s - E_m) / E_m inside the decay span), ``frequency_measured``,
``frequency_model`` (HVD, Hz), decimated to about 20 points per cycle of the fastest cut-off;
``backbone_{amplitude,frequency}_{measured,model}`` (m, Hz); ``damping_{amplitude,zeta,
velocity_amplitude}_{measured,model}`` (m, -, m/s).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from fsi_lab.contract import AnalysisContext, ChannelData
from fsi_lab.dsp.components import BandComponents
from fsi_lab.errors import AnalysisError
from fsi_lab.plugins.analysis._chain import (
    HVD_RANGE,
    SI_UNITS,
    components,
    displacement_components,
    guarded,
    per_component,
    stack_rows,
    where,
)
from fsi_lab.plugins.analysis.modal_model import PLUGIN_NAME
from fsi_lab.plugins.analysis.results import Components, DampingCoefficients, ModalComparison

#: A model component is paired with a measured one when their mean frequencies differ by less.
MATCH_TOLERANCE = 0.25
#: A measured instantaneous frequency this far (relative) from its component's is a phase
#: glitch, left out of the frequency error (:func:`frequency_errors`).
FREQUENCY_GLITCH = 0.5
#: Stored envelope and frequency rows: about this many points per cycle of the fastest cut-off.
POINTS_PER_CUTOFF_CYCLE = 20
MAX_OVERSAMPLING = 64
#: Model output for each channel quantity: (relative, absolute).
_OUTPUTS = {"velocity": ("velocity", "absolute_velocity"),
            "displacement": ("displacement", "absolute_displacement"),
            "acceleration": ("acceleration", "absolute_acceleration")}


# ----------------------------------------------------------------------------- helpers
def _shift(y: np.ndarray, s: float) -> np.ndarray:
    """``y`` taken at positions ``k + s`` (samples): exact for an integer ``s``, cubic
    (4-point Lagrange) otherwise; zero before the first sample (rest), the last value after."""
    n = y.size
    whole = math.floor(s)
    frac = s - whole
    if abs(frac) < 1e-9 or abs(frac - 1.0) < 1e-9:
        whole = int(round(s))
        frac = 0.0
    pad = 2
    ext = np.concatenate((np.zeros(pad + max(0, -whole)), y,
                          np.full(pad + max(0, whole) + 2, y[-1])))
    base = np.arange(n) + whole + pad + max(0, -whole)
    if frac == 0.0:
        return ext[base].copy()
    t = frac
    w0 = -t * (t - 1.0) * (t - 2.0) / 6.0
    w1 = (t + 1.0) * (t - 1.0) * (t - 2.0) / 2.0
    w2 = -(t + 1.0) * t * (t - 2.0) / 2.0
    w3 = (t + 1.0) * t * (t - 1.0) / 6.0
    return w0 * ext[base - 1] + w1 * ext[base] + w2 * ext[base + 1] + w3 * ext[base + 2]


def simulate_at_rate(model: Any, acceleration: np.ndarray, sample_rate: float, point: float,
                     output: str) -> tuple[np.ndarray, int]:
    """The model's ``output`` at ``point`` (m) for the sampled base acceleration, from rest.

    Integrates at the smallest integer multiple of ``sample_rate`` that resolves every kept
    mode, the acceleration linear between samples (the integrator's own assumption, so
    oversampling changes only the step). Returns the output at the sample times and the factor.
    """
    from fsi_lab.errors import ParameterError
    from fsi_lab.modal_integrator import ModalSimulator, check_step

    factor = 1
    while True:
        try:
            check_step(model, sample_rate * factor)
            break
        except ParameterError:
            factor += 1
            if factor > MAX_OVERSAMPLING:
                raise
    acc = np.ascontiguousarray(acceleration, dtype=np.float64)
    if factor > 1:
        fine = np.arange((acc.size - 1) * factor + 1) / factor
        acc = np.interp(fine, np.arange(acc.size), acc)
    sim = ModalSimulator(model, sample_rate * factor, [point], outputs=(output,))
    out = sim.advance(acc)[output][::factor, 0]
    return np.ascontiguousarray(out), factor


def mode_of(frequency_hz: float, natural_hz: np.ndarray) -> int:
    """1-based beam mode whose calculated natural frequency is nearest (in ratio)."""
    if not frequency_hz or frequency_hz <= 0:
        return 1
    return 1 + int(np.argmin(np.abs(np.log(natural_hz / frequency_hz))))


def _interp_log(x_new: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """y(x) interpolated in ln x at ``x_new``; NaN outside the range of ``x``."""
    ok = np.isfinite(x) & np.isfinite(y) & (x > 0)
    x, y = x[ok], y[ok]
    out = np.full(x_new.shape, np.nan)
    if x.size < 2:
        return out
    order = np.argsort(x)
    lx, y = np.log(x[order]), y[order]
    inside = (x_new >= x[order][0]) & (x_new <= x[order][-1]) & (x_new > 0)
    out[inside] = np.interp(np.log(x_new[inside]), lx, y)
    return out


def _num(value: float) -> float | None:
    return float(value) if value is not None and math.isfinite(value) else None


def _pick_damping(context: AnalysisContext, params: dict[str, Any], freqs: dict[int, float],
                  natural: np.ndarray) -> tuple[float, float, str]:
    """C_i, C_f and where they come from (see the module notes)."""
    given_i, given_f = params["c_i"], params["c_f"]
    if given_i is not None and given_f is not None:
        return float(given_i), float(given_f), "given"
    found = context.result(DampingCoefficients)
    fits = found.fits if found is not None else {}
    wanted = params["mode"]
    chosen = None
    for k in sorted(fits):
        ci, cf = fits[k].c_i, fits[k].c_f
        mode = mode_of(freqs.get(k, 0.0), natural)
        if wanted is not None:
            if mode == wanted:
                chosen = (k, mode, ci, cf)
                break
        elif math.isfinite(ci) and math.isfinite(cf) and ci >= 0 and cf >= 0:
            chosen = (k, mode, ci, cf)
            break
    missing = " and ".join(n for n, v in (("c_i", given_i), ("c_f", given_f)) if v is None)
    if chosen is None:
        if not fits:
            raise AnalysisError(
                f"{where(PLUGIN_NAME, context)}: needs C_i and C_f: run equivalent-damping "
                f"earlier in the chain on this channel, or give {PLUGIN_NAME}.{missing}")
        have = ", ".join(f"component {k} (mode {mode_of(freqs.get(k, 0.0), natural)}: C_i = "
                         f"{fits[k].c_i:.4g}, C_f = {fits[k].c_f:.4g})" for k in sorted(fits))
        what = (f"no component of mode {wanted}" if wanted is not None
                else "no physical fit (C_i >= 0 and C_f >= 0)")
        raise AnalysisError(
            f"{where(PLUGIN_NAME, context)}: equivalent-damping gave {what}: {have}; give "
            f"{PLUGIN_NAME}.{missing}" + (" or another mode" if wanted is not None else ""))
    k, mode, ci, cf = chosen
    if not (math.isfinite(ci) and math.isfinite(cf) and ci >= 0 and cf >= 0):
        raise AnalysisError(
            f"{where(PLUGIN_NAME, context)}: equivalent-damping's fit for component {k} (mode "
            f"{mode}) is not physical (C_i = {ci:.4g}, C_f = {cf:.4g}); give {PLUGIN_NAME}."
            f"{missing} or another mode")
    source = f"equivalent-damping component {k} (mode {mode})"
    c_i = float(given_i) if given_i is not None else ci
    c_f = float(given_f) if given_f is not None else cf
    if given_i is not None or given_f is not None:
        source = f"{'c_i' if given_i is not None else 'c_f'} given, the other from {source}"
    return c_i, c_f, source


def component_curves(c: Any, smooth: int, method: str) -> tuple[Any, Any]:
    """Backbone and damping curve of one displacement component's signal, as the ``damping``
    plugin computes its curve and the ``backbone`` plugin the backbone of a component that is
    not a ``bands`` one (:func:`._backbone.decay_backbone`, :func:`._damping.decay_peaks` with
    their defaults and ``smooth`` / ``method``), from a single zero-crossing analysis:
    untrusted record ends and the points outside the free decays left out. Times are from the
    channel's first sample."""
    from fsi_lab.dsp.damping import damping_from_peaks
    from fsi_lab.dsp.instantaneous import instantaneous
    from fsi_lab.plugins.analysis._backbone import decay_backbone
    from fsi_lab.plugins.analysis._damping import decay_peaks

    inst = instantaneous(c.signal, c.sample_rate, offset="cycles", smooth=0,
                         min_amplitude=None, noise_floor=c.noise_floor,
                         frequency_hint=c.frequency)
    bb = decay_backbone(inst, c, smooth)
    t, a, f, decay, _ = decay_peaks(inst, c)
    curve = damping_from_peaks(t, a, f, method=method, span=2, window=6, smooth=smooth,
                               decay=decay)
    return bb, curve


def frequency_errors(measured_hz: np.ndarray, model_hz: np.ndarray, envelope: np.ndarray,
                     reference_hz: float, model_reference_hz: float) -> tuple[float, float]:
    """The model's instantaneous frequency error over a compared decay, percent: the mean and
    the RMS of ``model_hz - measured_hz`` (Hz, sample by sample) weighted by the measured
    ``envelope``, over the component's measured frequency ``reference_hz``. Samples whose
    measured frequency is off ``reference_hz``, or whose model frequency is off the model
    component's ``model_reference_hz``, by :data:`FREQUENCY_GLITCH` or more are left out: no
    oscillation of one mode does that, a phase glitch of its decomposition does (where
    another mode or the excitation's transient crosses it, on either side), and a few of
    them would outweigh the rest. Returns ``(mean, rms)``; NaN when no sample is left."""
    kept = (np.abs(measured_hz - reference_hz) < FREQUENCY_GLITCH * reference_hz) & (
        np.abs(model_hz - model_reference_hz) < FREQUENCY_GLITCH * model_reference_hz)
    if not kept.any() or float(np.sum(envelope[kept])) <= 0.0:
        return math.nan, math.nan
    weight = envelope[kept] / float(np.sum(envelope[kept]))
    rel = (model_hz[kept] - measured_hz[kept]) / reference_hz
    return 100.0 * float(weight @ rel), 100.0 * math.sqrt(float(weight @ rel ** 2))


def curve_errors(bb_m: Any, bb_s: Any, dc_m: Any, dc_s: Any, t_lo: float, t_hi: float
                 ) -> dict[str, float | None]:
    """``backbone_error_pct``, ``damping_error_pct`` and ``damping_rms_error_pct`` (see the
    module notes) of measured (``_m``) against model (``_s``) curves, over the measured points
    between ``t_lo`` and ``t_hi`` (s) whose amplitude lies within the model curve's."""
    out: dict[str, float | None] = {}
    f_at = _interp_log(bb_m.amplitude, bb_s.amplitude, bb_s.frequency)
    inside = np.isfinite(f_at) & (bb_m.time >= t_lo) & (bb_m.time <= t_hi)
    if inside.sum() >= 2:
        w = bb_m.amplitude[inside] ** 2
        rel = (f_at[inside] - bb_m.frequency[inside]) / bb_m.frequency[inside]
        out["backbone_error_pct"] = 100.0 * float(w @ rel) / float(np.sum(w))
    else:
        out["backbone_error_pct"] = None
    z_at = _interp_log(dc_m.amplitude, dc_s.amplitude, dc_s.zeta)
    inside = np.isfinite(z_at) & (dc_m.time >= t_lo) & (dc_m.time <= t_hi)
    w = dc_m.amplitude[inside] ** 2
    w = w / max(float(np.sum(w)), 1e-300)
    scale = float(w @ dc_m.zeta[inside]) if inside.sum() >= 2 else 0.0
    if inside.sum() >= 2 and scale > 0:
        diff = z_at[inside] - dc_m.zeta[inside]
        out["damping_error_pct"] = 100.0 * float(w @ diff) / scale
        out["damping_rms_error_pct"] = 100.0 * math.sqrt(float(w @ diff ** 2)) / scale
    else:
        out["damping_error_pct"] = out["damping_rms_error_pct"] = None
    return out


def _check_inputs(context: AnalysisContext) -> ChannelData:
    """The reference channel, after checking the specimen, reference and units."""
    ch = context.channel
    here = where(PLUGIN_NAME, context)
    if context.specimen is None:
        raise AnalysisError(
            f"{here}: needs the beam to model: give the profile a [specimen] section (length, "
            "width, thickness, youngs_modulus, density, fluid, measurement_point)")
    name = context.reference
    if not name:
        raise AnalysisError(
            f"{here}: needs the measured base acceleration to drive the model: set the "
            "profile's [analysis] reference = \"<base acceleration channel>\"")
    ref = context.channels.get(name)
    if ref is None:
        raise AnalysisError(
            f"{here}: reference channel {name!r} is not in the run; channels are "
            f"{', '.join(context.channels) or 'none'}; set [analysis] reference to the base "
            "acceleration channel")
    if ref.quantity != "acceleration" or ref.unit != SI_UNITS["acceleration"]:
        raise AnalysisError(
            f"{here}: reference channel {name!r} measures {ref.quantity!r} in {ref.unit!r}; "
            "expected the base acceleration in m/s^2")
    if ch.quantity not in _OUTPUTS or ch.unit != SI_UNITS[ch.quantity]:
        raise AnalysisError(
            f"{here}: the channel measures {ch.quantity!r} in {ch.unit!r}; the model gives "
            "displacement (m), velocity (m/s) or acceleration (m/s^2) at the measuring point")
    if abs(float(ref.sample_rate) - float(ch.sample_rate)) > 1e-9 * float(ch.sample_rate) \
            or ref.data.size != ch.data.size:
        raise AnalysisError(
            f"{here}: reference {name!r} ({ref.data.size} samples at {ref.sample_rate:g} Hz) "
            f"does not match the channel ({ch.data.size} samples at {ch.sample_rate:g} Hz)")
    if not np.all(np.isfinite(ref.data)):
        raise AnalysisError(f"{here}: reference {name!r} contains NaN or infinite samples")
    return ref


# ----------------------------------------------------------------------------- plugin
def run(context: AnalysisContext, params: dict[str, Any]) -> ModalComparison:
    from fsi_lab.dsp.hvd import hvd
    from fsi_lab.errors import ParameterError
    from fsi_lab.modelling import beam_model

    ch = context.channel
    here = where(PLUGIN_NAME, context)
    ref = _check_inputs(context)
    measured = context.result(Components)
    res_m = measured.decomposition
    fs = float(ch.sample_rate)
    k_total = res_m.n_components
    i0 = int(round(float(res_m.t0) * fs))
    relative = measured.relative_to is not None
    padding = measured.padding or "predict"

    try:
        model = beam_model(context.specimen, {"modes": params["modes"], "c_i": 0.0, "c_f": 0.0,
                                              "damping_ratios": None, "rayleigh": False,
                                              "projection": params["projection"]})
    except ParameterError as exc:
        raise AnalysisError(f"{here}: the beam model cannot be built: {exc}") from None
    natural = model.natural_frequencies_hz
    freqs_m = {k: res_m.mean_frequency(k) for k in range(k_total)}
    c_i, c_f, c_source = _pick_damping(context, params, freqs_m, natural)
    from fsi_lab.beam import Damping
    try:
        model = model.with_damping(Damping(c_i=c_i, c_f=c_f, projection=params["projection"]))
    except ParameterError as exc:
        raise AnalysisError(f"{here}: {exc}") from None

    # -- simulate, then take the output at the channel's sample times
    output = _OUTPUTS[ch.quantity][0 if relative else 1]
    point = float(context.specimen.measurement_point)
    try:
        y_ref, factor = simulate_at_rate(model, ref.data, fs, point, output)
    except ParameterError as exc:
        raise AnalysisError(f"{here}: the model cannot be integrated: {exc}") from None
    y_s = _shift(y_ref, (float(ch.t0) - float(ref.t0)) * fs)
    # What the measurement's HVD decomposed (relative to the base when it was), from start_s.
    y_m = res_m.components.sum(axis=0) + res_m.residual

    # -- the measurement's decomposition on the model
    with guarded(PLUGIN_NAME, context):
        if isinstance(res_m, BandComponents):
            res_s = res_m.redo(y_s)
        else:
            res_s = hvd(y_s[i0:], fs, k_total, res_m.cutoffs, padding=padding,
                        band=getattr(res_m, "band", None))
            res_s = dataclasses.replace(res_s, t0=float(res_m.t0))
    model_ch = ChannelData(name=ch.name, data=y_s, sample_rate=fs, quantity=ch.quantity,
                           unit=ch.unit, t0=ch.t0)
    model_ctx = AnalysisContext(channel=model_ch, channels={ch.name: model_ch}, results={},
                                provided={Components.kind: Components(res_s)},
                                specimen=context.specimen, reference=None)
    freqs_s = np.array([res_s.mean_frequency(j) for j in range(k_total)])

    smooth, method = params["smooth_points"], params["damping_method"]
    with guarded(PLUGIN_NAME, context):
        comps_m = {c.index: c for c in components(context)}
        disp_m = {c.index: c for c in displacement_components(context, PLUGIN_NAME)}
    disp_s: dict[int, Any] = {}
    curves_s: dict[int, tuple] = {}

    def model_curves(j: int):
        if j not in curves_s:
            if not disp_s:
                with guarded(PLUGIN_NAME, context):
                    disp_s.update({c.index: c for c in
                                   displacement_components(model_ctx, PLUGIN_NAME)})
            c = disp_s[j]
            with guarded(PLUGIN_NAME, context):
                curves_s[j] = component_curves(c, smooth, method)
        return curves_s[j]

    largest = float(np.max(res_m.envelopes[~res_m.edge_mask])) if (~res_m.edge_mask).any() \
        else float(np.max(res_m.envelopes))
    spans: dict[int, tuple[int, int]] = {}

    def work(c):
        k = c.index
        f_m = freqs_m[k]
        if not f_m > 0:
            raise AnalysisError(f"{here}: component {k} has no frequency to pair it with")
        j = int(np.argmin(np.abs(np.log(np.maximum(freqs_s, 1e-300) / f_m))))
        if abs(freqs_s[j] / f_m - 1.0) > MATCH_TOLERANCE:
            raise AnalysisError(
                f"{here}: no model component near the measured {f_m:.4g} Hz (model components "
                f"at {', '.join(f'{f:.4g}' for f in freqs_s)} Hz); the model misses this mode - "
                "more modes, or check the specimen")
        e_m, e_s = res_m.envelopes[k], res_s.envelopes[j]
        fr_m, fr_s = res_m.frequencies[k], res_s.frequencies[j]
        ok = ~(res_m.edge_mask[k] | res_s.edge_mask[j])
        if ok.sum() < 8:
            raise AnalysisError(f"{here}: component {k}: no trusted samples to compare")
        idx = np.flatnonzero(ok)
        start = int(idx[np.argmax(e_m[idx])]) + int(round(res_m.settle(k) * fs))
        floor = max(c.noise_floor or 0.0, HVD_RANGE * largest)
        below = np.flatnonzero((e_m < floor) & (np.arange(e_m.size) >= start))
        end = int(below[0]) if below.size else e_m.size
        win = ok.copy()
        win[:start] = False
        win[end:] = False
        if win.sum() < 8:
            raise AnalysisError(
                f"{here}: component {k}: the free decay above the noise floor is too short to "
                "compare (fewer than 8 trusted samples)")
        spans[k] = (start, end)
        em, es = e_m[win], e_s[win]
        env_rms = math.sqrt(float(np.mean((es - em) ** 2)) / float(np.mean(em ** 2)))
        with np.errstate(divide="ignore", invalid="ignore"):
            lr = np.log(es / em)
        env_log = math.sqrt(float(np.mean(lr ** 2))) if np.all(np.isfinite(lr)) else math.inf
        mean_f, rms_f = frequency_errors(fr_m[win], fr_s[win], em, f_m, float(freqs_s[j]))
        figures = {"c_i": c_i, "c_f": c_f, "mode": mode_of(f_m, natural), "model_index": j,
                   "natural_frequency_hz": float(natural[mode_of(f_m, natural) - 1]),
                   "measured_frequency_hz": f_m, "model_frequency_hz": float(freqs_s[j]),
                   "decay_start_s": (i0 + start) / fs, "decay_end_s": (i0 + end - 1) / fs,
                   "envelope_rms_error": env_rms, "envelope_log_rms_error": env_log,
                   "frequency_error_pct": mean_f, "frequency_rms_error_pct": rms_f}
        # Backbone and damping curves, the same processing on both sides; if they cannot be
        # measured (too few cycles), the envelope and frequency figures still stand.
        try:
            with guarded(PLUGIN_NAME, context):
                bb_m, dc_m = component_curves(disp_m[k], smooth, method)
            bb_s, dc_s = model_curves(j)
        except AnalysisError as exc:
            figures.update(backbone_error_pct=None, damping_error_pct=None,
                           damping_rms_error_pct=None, curves_error=str(exc))
            return {"figures": figures, "j": j, "backbone": None, "damping": None}
        figures.update(curve_errors(bb_m, bb_s, dc_m, dc_s, figures["decay_start_s"],
                                    figures["decay_end_s"]))
        return {"figures": figures, "j": j, "backbone": (bb_m, bb_s), "damping": (dc_m, dc_s)}

    done, errors = per_component(PLUGIN_NAME, context, [comps_m[k] for k in sorted(comps_m)],
                                 work)

    # -- datasets
    count = k_total
    stride = max(1, int(fs / (POINTS_PER_CUTOFF_CYCLE * float(np.max(res_m.cutoffs)))))
    m_len = res_m.envelopes.shape[1]
    sel = np.arange(0, m_len, stride)
    env_err = np.full((count, sel.size), np.nan)
    rows: dict[str, dict[int, np.ndarray]] = {
        name: {} for name in ("envelope_measured", "envelope_model", "frequency_measured",
                              "frequency_model")}
    for k, r in done.items():
        j = r["j"]
        rows["envelope_measured"][k] = res_m.envelopes[k, sel]
        rows["envelope_model"][k] = res_s.envelopes[j, sel]
        rows["frequency_measured"][k] = res_m.frequencies[k, sel]
        rows["frequency_model"][k] = res_s.frequencies[j, sel]
        a, b = spans[k]
        inside = (sel >= a) & (sel < b)
        env_err[k, inside] = res_s.envelopes[j, sel[inside]] / res_m.envelopes[k, sel[inside]] \
            - 1.0
    datasets: dict[str, np.ndarray] = {
        "velocity_measured": np.asarray(y_m, dtype=np.float64),
        "velocity_model": y_s[i0:],
        "envelope_time": (i0 + sel) / fs,
        "envelope_error": env_err,
        **{name: stack_rows(r, count) for name, r in rows.items()},
    }
    units = {"velocity_measured": ch.unit, "velocity_model": ch.unit, "envelope_time": "s",
             "envelope_error": "", "envelope_measured": ch.unit, "envelope_model": ch.unit,
             "frequency_measured": "Hz", "frequency_model": "Hz"}
    curves = {k: r for k, r in done.items() if r["backbone"] is not None}
    for side, i in (("measured", 0), ("model", 1)):
        datasets[f"backbone_amplitude_{side}"] = stack_rows(
            {k: r["backbone"][i].amplitude for k, r in curves.items()}, count)
        datasets[f"backbone_frequency_{side}"] = stack_rows(
            {k: r["backbone"][i].frequency for k, r in curves.items()}, count)
        datasets[f"damping_amplitude_{side}"] = stack_rows(
            {k: r["damping"][i].amplitude for k, r in curves.items()}, count)
        datasets[f"damping_zeta_{side}"] = stack_rows(
            {k: r["damping"][i].zeta for k, r in curves.items()}, count)
        datasets[f"damping_velocity_amplitude_{side}"] = stack_rows(
            {k: 2.0 * math.pi * r["damping"][i].frequency * r["damping"][i].amplitude
             for k, r in curves.items()}, count)
        units.update({f"backbone_amplitude_{side}": "m", f"backbone_frequency_{side}": "Hz",
                      f"damping_amplitude_{side}": "m", f"damping_zeta_{side}": "",
                      f"damping_velocity_amplitude_{side}": "m/s"})
    if ch.quantity != "velocity":       # the time series are in the channel's quantity
        for key in ("velocity_measured", "velocity_model"):
            datasets[key.replace("velocity", "signal")] = datasets.pop(key)
            units[key.replace("velocity", "signal")] = units.pop(key)

    # -- error of the compared part of the signal (the sum of the paired components of each
    # side) over the decay of the largest compared component
    k_big = min(done) if done else 0
    a, b = spans.get(k_big, (0, m_len))
    vm = res_m.components[sorted(done), a:b].sum(axis=0)
    vs = res_s.components[sorted({r["j"] for r in done.values()}), a:b].sum(axis=0)
    v_err = math.sqrt(float(np.mean((vs - vm) ** 2)) / float(np.mean(vm ** 2))) \
        if vm.size and np.any(vm) else math.nan

    return ModalComparison(
        c_i=c_i, c_f=c_f, c_source=c_source, model=model, natural_frequencies_hz=list(natural),
        relative=relative, oversampling=factor, velocity_rms_error=v_err,
        figures={k: r["figures"] for k, r in done.items()}, model_components=res_s,
        model_signal=y_s, curves=datasets, units=units, projection=params["projection"],
        damping_method=params["damping_method"], start_s=float(res_m.t0), sample_rate=fs,
        count=count, errors=errors)
