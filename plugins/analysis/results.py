"""The typed results the built-in analyses hand each other, and what the run file keeps of them.

Each class is a :class:`fsi_lab.contract.Result` of one kind; an analysis declares the kinds it
``requires``, ``uses`` and ``provides`` (e.g. ``requires=(Components,)``) and reads them with
``context.result(Components)``. Each result's :meth:`~fsi_lab.contract.Result.record` gives the
datasets, attributes and summary the run file and ``fsi-lab analyze --json`` keep
(docs/run-format.md, docs/json-output.md).

=========================  ===============  ===================================================
kind                       class            provided by
=========================  ===============  ===================================================
``spectrum``               Spectrum         ``spectrum``
``components``             Components       ``hvd`` (bands or Feldman's HVD)
``integrated``             Integrated       ``integrate``
``instantaneous``          Instantaneous-   ``instantaneous``
                           Curves
``backbone``               Backbones        ``backbone``
``damping-curve``          DampingCurves    ``damping``
``damping-coefficients``   DampingCo-       ``equivalent-damping``
                           efficients
``modal-comparison``       ModalComparison  ``modal-model``
=========================  ===============  ===================================================

Per-component results hold the components that could not be worked on in ``errors`` (index ->
message); :attr:`Components.refused` holds those the decomposition itself refuses (a component
that switches between two modes), which every later analysis reports instead of numbers.

This module is light (numpy only): the descriptor modules name the kinds from it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from fsi_lab.contract import AnalysisResult, Result

if TYPE_CHECKING:
    from fsi_lab.dsp.backbone import Backbone
    from fsi_lab.dsp.components import BandComponents
    from fsi_lab.dsp.damping import DampingCurve
    from fsi_lab.dsp.decays import FreeDecays
    from fsi_lab.dsp.hvd import HVDResult
    from fsi_lab.dsp.identify import Identification
    from fsi_lab.dsp.instantaneous import Instantaneous
    from fsi_lab.dsp.spectrum import SpectralPeaks


# ----------------------------------------------------------------------------- stored form
def jsonable(values: Any) -> Any:
    """Python floats / lists with NaN and inf replaced by None."""
    if isinstance(values, np.ndarray):
        values = values.tolist()
    if isinstance(values, (list, tuple)):
        return [jsonable(v) for v in values]
    if isinstance(values, (np.floating, float)):
        v = float(values)
        return v if math.isfinite(v) else None
    if isinstance(values, np.integer):
        return int(values)
    return values


def stack_rows(rows: dict[int, np.ndarray], count: int) -> np.ndarray:
    """2-D array (count x max length) of 1-D rows by index, padded with NaN."""
    width = max((r.size for r in rows.values()), default=0)
    out = np.full((count, width), np.nan)
    for k, r in rows.items():
        out[k, :r.size] = r
    return out


def error_entries(errors: dict[int, str], key: str) -> tuple[list[dict], dict[str, str]]:
    """Summary entries (``{"index": k, key: {"error": message}}``) and attributes
    (``component_<k>_error``) recording per-component failures."""
    entries = [{"index": k, key: {"error": m}} for k, m in errors.items()]
    attrs = {f"component_{k}_error": m for k, m in errors.items()}
    return entries, attrs


def decay_summary(decays: FreeDecays | None, t0: float = 0.0) -> dict[str, Any]:
    """``decays`` (count), ``decay_starts_s`` and ``decay_ends_s`` (free parts, s from the
    channel's first sample given the component's ``t0``) for a summary entry; ``{}`` when the
    record was not split (``decay_only`` off)."""
    if decays is None:
        return {}
    return {"decays": decays.count, "decay_starts_s": jsonable(decays.starts + t0),
            "decay_ends_s": jsonable(decays.ends + t0)}


def decay_attrs(decays: dict[int, FreeDecays | None], t0s: dict[int, float]) -> dict[str, Any]:
    """Attributes ``component_<k>_decays``, ``component_<k>_decay_starts_s`` and
    ``component_<k>_decay_ends_s`` (s from the channel's first sample) of the split records."""
    return {f"component_{k}_{key}": value for k, d in sorted(decays.items())
            for key, value in decay_summary(d, t0s[k]).items()}


ROWS = "one row per component, padded with NaN"


# ----------------------------------------------------------------------------- spectrum
@dataclass
class Spectrum(Result):
    """Amplitude spectrum of a channel and its peaks (``spectrum``).

    Attributes
    ----------
    frequency
        Hz, from 0 to half the sample rate.
    amplitude
        In ``unit``: a steady sinusoid of amplitude A shows a peak of height A.
    peaks
        Interpolated peaks (:class:`fsi_lab.dsp.spectrum.SpectralPeaks`), by decreasing
        amplitude.
    unit
        Unit of the channel.
    window
        Window of the transform.
    """

    kind = "spectrum"

    frequency: np.ndarray
    amplitude: np.ndarray
    peaks: SpectralPeaks
    unit: str
    window: str

    @property
    def peak_frequencies(self) -> np.ndarray:
        """Peak frequencies, Hz, increasing."""
        return self.peaks.frequencies[np.argsort(self.peaks.frequencies)]

    @property
    def peak_amplitudes(self) -> np.ndarray:
        """Peak amplitudes, ``unit``, in the order of :attr:`peak_frequencies`."""
        return self.peaks.amplitudes[np.argsort(self.peaks.frequencies)]

    def record(self) -> AnalysisResult:
        pf, pa = self.peak_frequencies, self.peak_amplitudes
        return AnalysisResult(
            datasets={"frequency": self.frequency, "amplitude": self.amplitude,
                      "peak_frequencies": pf, "peak_amplitudes": pa},
            units={"frequency": "Hz", "amplitude": self.unit, "peak_frequencies": "Hz",
                   "peak_amplitudes": self.unit},
            attrs={"window": self.window,
                   "resolution_hz": float(self.frequency[1] - self.frequency[0])},
            summary={"spectrum_peaks_hz": jsonable(pf), "spectrum_peak_amplitudes": jsonable(pa),
                     "spectrum_peak_amplitude_unit": self.unit},
            values=self.peaks)


# ----------------------------------------------------------------------------- components
#: What ``edge_mask`` and the row order mean, per decomposition method.
_EDGE_MASK = {"bands": "1 outside the free part of every decay (excitation, build-ups): not used",
              "hvd": "1 where the sample is too close to a record end to be trusted (within 1 / "
                     "cutoff)"}
_ORDER = {"bands": "components by decreasing height of their peak in the free decays' "
                   "spectrum; row k = index k",
          "hvd": "components sorted by decreasing RMS envelope; row k = index k"}
#: Said of every component of Feldman's HVD.
HVD_FREQUENCY_WARNING = ("frequency_hz is HVD's envelope-weighted mean frequency, not the "
                         "small-amplitude natural frequency (method = 'bands' gives that)")


@dataclass
class Components(Result):
    """A channel decomposed into one component per mode (``components``).

    Attributes
    ----------
    decomposition
        :class:`fsi_lab.dsp.components.BandComponents` (method ``bands``, with the
        identification of every mode) or :class:`fsi_lab.dsp.hvd.HVDResult` (method ``hvd``;
        its ``t0`` is the start of the rows, s from the channel's first sample).
    method
        ``"bands"`` or ``"hvd"``.
    unit
        Unit of the components (m/s for an acceleration channel that ``bands`` integrated).
    channel_unit
        Unit of the channel (and of the residual).
    relative_to
        Name of the base acceleration channel whose motion was subtracted first, or None (the
        channel as measured).
    start_rule
        How the decomposed part of the record was chosen, in words.
    band_hz
        ``[low, high]`` the record was band-passed to, Hz, or None.
    padding
        Record-end extension of Feldman's HVD (``predict`` or ``mirror``), None for ``bands``.
    refused
        Components that must not be analysed, with the reason (one that switches between two
        modes): every later analysis reports the reason for them instead of numbers.
    """

    kind = "components"

    decomposition: BandComponents | HVDResult
    method: str = "bands"
    unit: str = ""
    channel_unit: str = ""
    relative_to: str | None = None
    start_rule: str = ""
    band_hz: list[float] | None = None
    padding: str | None = None
    refused: dict[int, str] = field(default_factory=dict)

    @property
    def identification(self) -> Identification | None:
        """The identification of every mode (method ``bands``), else None."""
        return getattr(self.decomposition, "identification", None)

    @property
    def count(self) -> int:
        """Number of components."""
        return int(self.decomposition.n_components)

    def record(self) -> AnalysisResult:
        res = self.decomposition
        common = {"method": self.method, "n_components": res.n_components,
                  "sample_rate": float(res.sample_rate),
                  "relative_to": self.relative_to or "none (the channel as measured)"}
        datasets = {"components": res.components, "envelopes": res.envelopes,
                    "frequencies": res.frequencies, "residual": res.residual,
                    "edge_mask": res.edge_mask.astype(np.uint8), "cutoffs": res.cutoffs}
        units = {"components": self.unit, "envelopes": self.unit, "frequencies": "Hz",
                 "residual": self.channel_unit, "edge_mask": "", "cutoffs": "Hz"}
        band = list(self.band_hz) if self.band_hz is not None else "none (the whole record)"
        if self.method == "bands":
            ident = res.identification
            comps = []
            for k, mode in enumerate(ident.modes):
                good = ~res.edge_mask[k]
                comps.append({
                    "index": k, "frequency_hz": mode.frequency_hz,
                    "frequency_ci95_hz": list(mode.frequency_ci),
                    "damped_frequency_hz": mode.damped_frequency_hz,
                    "spectral_peak_hz": mode.spectral_peak_hz, "band_hz": list(mode.band_hz),
                    "extrema": mode.extrema_count, "decays": len(mode.decays),
                    "hvd_peak_envelope": float(res.envelopes[k][good].max())
                    if good.any() else None,
                    "warnings": list(mode.warnings)})
            notes = list(ident.notes)
            return AnalysisResult(
                datasets={**datasets, "bands": np.array([list(m.band_hz) for m in ident.modes])},
                units={**units, "bands": "Hz"},
                attrs={**common, "start_s": 0.0, "start_rule": self.start_rule,
                       "edge_mask_meaning": _EDGE_MASK["bands"], "band_hz": band,
                       "order": _ORDER["bands"], "noise_rms": ident.noise_rms, "notes": notes},
                summary={"components": comps, **({"notes": notes} if notes else {})},
                values=res)
        comps = []
        for k in range(res.n_components):
            good = ~res.edge_mask[k]
            comps.append({"index": k, "frequency_hz": res.mean_frequency(k),
                          "cutoff_hz": float(res.cutoffs[k]),
                          "hvd_peak_envelope": float(res.envelopes[k][good].max())
                          if good.any() else None,
                          "warnings": [HVD_FREQUENCY_WARNING],
                          **({"hvd": {"error": self.refused[k]}} if k in self.refused else {})})
        # (rows start at start_s: sample j of a row is at t = start_s + j / sample_rate)
        return AnalysisResult(
            datasets=datasets, units=units,
            attrs={**common, "padding": self.padding, "start_s": res.t0,
                   "start_rule": self.start_rule, "edge_mask_meaning": _EDGE_MASK["hvd"],
                   "band_hz": band, "order": _ORDER["hvd"],
                   **error_entries(self.refused, "hvd")[1]},
            summary={"components": comps}, values=res)


# ----------------------------------------------------------------------------- integrate
@dataclass
class Integrated(Result):
    """The components (or the channel) integrated to displacement or velocity
    (``integrated``).

    Attributes
    ----------
    quantity
        ``"displacement"`` or ``"velocity"``.
    unit
        m or m/s.
    sample_rate
        Hz.
    signals
        Samples of each component worked on, by index.
    edge_masks, noise_floors, settles, t0s, frequencies
        Of each component by index, as the components had them (see
        :class:`fsi_lab.plugins.analysis._chain.Component`).
    order
        Integrations applied (0: the components were already of this quantity).
    from_quantity
        Quantity of the channel.
    highpass_hz
        High-pass corner given, Hz, or None (automatic).
    count
        Number of components.
    start_s
        Start of the rows, s from the channel's first sample.
    errors
        Components that could not be integrated, with the reason.
    """

    kind = "integrated"

    quantity: str
    unit: str
    sample_rate: float
    signals: dict[int, np.ndarray]
    edge_masks: dict[int, np.ndarray | None]
    noise_floors: dict[int, float | None] = field(default_factory=dict)
    settles: dict[int, float] = field(default_factory=dict)
    t0s: dict[int, float] = field(default_factory=dict)
    frequencies: dict[int, float | None] = field(default_factory=dict)
    order: int = 0
    from_quantity: str = ""
    highpass_hz: float | None = None
    count: int = 0
    start_s: float = 0.0
    errors: dict[int, str] = field(default_factory=dict)

    def record(self) -> AnalysisResult:
        entries = [{"index": k, f"{self.quantity}_peak": float(np.max(np.abs(s)))}
                   for k, s in self.signals.items()]
        err_entries, err_attrs = error_entries(self.errors, "integrate")
        return AnalysisResult(
            datasets={"signals": stack_rows(self.signals, self.count)},
            units={"signals": self.unit},
            attrs={"quantity": self.quantity, "order": self.order,
                   "from_quantity": self.from_quantity, "start_s": self.start_s,
                   "highpass_hz": self.highpass_hz if self.highpass_hz is not None
                   else "auto (half the lowest spectral peak)", **err_attrs},
            summary={"components": entries + err_entries}, values=self)


# ----------------------------------------------------------------------------- instantaneous
@dataclass
class InstantaneousCurves(Result):
    """Zero-crossing frequency and extremum amplitude of each component
    (``instantaneous``).

    Attributes
    ----------
    curves
        :class:`fsi_lab.dsp.instantaneous.Instantaneous` of each component worked on (times
        from the component's start).
    t0s
        Start of each component, s from the channel's first sample.
    quantity, unit
        Of the analysed signals (a displacement in m when the channel gives one).
    count
        Number of components.
    errors
        Components that could not be analysed, with the reason.
    """

    kind = "instantaneous"

    curves: dict[int, Instantaneous]
    t0s: dict[int, float]
    quantity: str
    unit: str
    count: int
    errors: dict[int, str] = field(default_factory=dict)

    def record(self) -> AnalysisResult:
        done = self.curves
        # (the amplitude^2-weighted mean leans on the largest cycles; the headline natural
        # frequency is hvd's small-amplitude limit)
        entries = [{"index": k, "instantaneous": {
            "weighted_mean_frequency_hz": float(np.sum(r.amplitude ** 2 * r.frequency)
                                                / np.sum(r.amplitude ** 2))}}
                   for k, r in done.items()]
        err_entries, err_attrs = error_entries(self.errors, "instantaneous")
        rows = {name: stack_rows({k: getattr(r, name) + (self.t0s[k] if name.endswith("times")
                                                         else 0.0)
                                  for k, r in done.items()}, self.count)
                for name in ("frequency_times", "frequency", "amplitude", "peak_times",
                             "peak_values")}
        return AnalysisResult(
            datasets=rows,
            units={"frequency_times": "s", "frequency": "Hz", "amplitude": self.unit,
                   "peak_times": "s", "peak_values": self.unit},
            attrs={"quantity": self.quantity,
                   "offsets": [float(done[k].offset) if k in done else float("nan")
                               for k in range(self.count)],
                   "rows": ROWS, **err_attrs},
            summary={"components": entries + err_entries}, values=done)


# ----------------------------------------------------------------------------- backbone
@dataclass
class Backbones(Result):
    """Backbone curves of each component (``backbone``).

    Attributes
    ----------
    displacement
        :class:`fsi_lab.dsp.backbone.Backbone` of each component worked on: frequency (Hz)
        against displacement amplitude (m); times from the channel's first sample.
    velocity
        The same against velocity amplitude (m/s), for the components that give it.
    t0s
        Start of each component, s from the channel's first sample.
    count
        Number of components.
    errors
        Components without a backbone, with the reason.
    """

    kind = "backbone"

    displacement: dict[int, Backbone]
    velocity: dict[int, Backbone]
    t0s: dict[int, float]
    count: int
    errors: dict[int, str] = field(default_factory=dict)

    def record(self) -> AnalysisResult:
        done, vdone, count = self.displacement, self.velocity, self.count
        entries = []
        for k, bb in done.items():
            e = {"index": k, "backbone": {"amplitude": jsonable(bb.amplitude),
                                          "frequency_hz": jsonable(bb.frequency),
                                          **decay_summary(bb.decays, self.t0s[k])}}
            if k in vdone:
                e["backbone_velocity"] = {"amplitude": jsonable(vdone[k].amplitude),
                                          "frequency_hz": jsonable(vdone[k].frequency)}
            entries.append(e)
        err_entries, err_attrs = error_entries(self.errors, "backbone")
        datasets = {"time": stack_rows({k: b.time for k, b in done.items()}, count),
                    "amplitude": stack_rows({k: b.amplitude for k, b in done.items()}, count),
                    "frequency": stack_rows({k: b.frequency for k, b in done.items()}, count),
                    "decay": stack_rows({k: b.decay.astype(np.float64)
                                         for k, b in done.items()}, count)}
        units = {"time": "s", "amplitude": "m", "frequency": "Hz", "decay": ""}
        if vdone:
            datasets["velocity_amplitude"] = stack_rows(
                {k: b.amplitude for k, b in vdone.items()}, count)
            datasets["velocity_frequency"] = stack_rows(
                {k: b.frequency for k, b in vdone.items()}, count)
            units.update(velocity_amplitude="m/s", velocity_frequency="Hz")
        return AnalysisResult(
            datasets=datasets, units=units,
            attrs={"rows": ROWS,
                   **decay_attrs({k: b.decays for k, b in done.items()}, self.t0s),
                   **err_attrs},
            summary={"components": entries + err_entries},
            values={"displacement": done, "velocity": vdone})


# ----------------------------------------------------------------------------- damping
@dataclass
class DampingCurves(Result):
    """Damping ratio against displacement amplitude of each component (``damping-curve``).

    Attributes
    ----------
    curves
        :class:`fsi_lab.dsp.damping.DampingCurve` of each component worked on (amplitude in m,
        times from the channel's first sample; ``decays`` the free decays found).
    method
        Estimator (:data:`fsi_lab.dsp.choices.DAMPING_METHODS`).
    t0s
        Start of each component, s from the channel's first sample.
    count
        Number of components.
    errors
        Components without a curve, with the reason.
    """

    kind = "damping-curve"

    curves: dict[int, DampingCurve]
    method: str
    t0s: dict[int, float]
    count: int
    errors: dict[int, str] = field(default_factory=dict)

    def record(self) -> AnalysisResult:
        done, count = self.curves, self.count
        entries = [{"index": k, "damping": {"amplitude": jsonable(d.amplitude),
                                            "zeta": jsonable(d.zeta), "method": d.method,
                                            **({"params": d.params} if d.params else {}),
                                            **decay_summary(d.decays, self.t0s[k])}}
                   for k, d in done.items()]
        err_entries, err_attrs = error_entries(self.errors, "damping")
        names = ("time", "amplitude", "zeta", "frequency", "decay_rate")
        datasets = {n: stack_rows({k: getattr(d, n) for k, d in done.items()}, count)
                    for n in names}
        datasets["velocity_amplitude"] = stack_rows(
            {k: 2.0 * math.pi * d.frequency * d.amplitude for k, d in done.items()}, count)
        datasets["decay"] = stack_rows({k: d.decay.astype(np.float64) for k, d in done.items()},
                                       count)
        return AnalysisResult(
            datasets=datasets,
            units={"time": "s", "amplitude": "m", "zeta": "", "frequency": "Hz",
                   "decay_rate": "1/s", "velocity_amplitude": "m/s", "decay": ""},
            attrs={"method": self.method,
                   "velocity_amplitude": "2 pi f times the displacement amplitude",
                   "rows": ROWS,
                   **decay_attrs({k: d.decays for k, d in done.items()}, self.t0s),
                   **err_attrs},
            summary={"components": entries + err_entries}, values=done)


@dataclass
class CoefficientFit:
    """C_i and C_f of one component.

    Attributes
    ----------
    c_i
        Linear damping per length, kg/(m s).
    c_f
        Quadratic damping per length, kg/m^2.
    amplitude
        Displacement amplitude of the measured C_q points, m (in the amplitude convention).
    c_q
        Equivalent damping coefficient C_q at those points, kg/(m s).
    details
        The other JSON items of the component's summary, in order: ``r2``, the 95 % intervals,
        ``preferred_law`` and the law comparison (method ``law``), the decays used...
    """

    c_i: float
    c_f: float
    amplitude: np.ndarray
    c_q: np.ndarray
    details: dict[str, Any] = field(default_factory=dict)

    @property
    def r2(self) -> float:
        """Coefficient of determination of the fit."""
        return float(self.details.get("r2", math.nan))

    @property
    def preferred_law(self) -> str | None:
        """The damping law the record prefers (method ``law``), else None."""
        return self.details.get("preferred_law")

    def summary(self) -> dict[str, Any]:
        """JSON items (without the arrays)."""
        return {"c_i": jsonable(self.c_i), "c_f": jsonable(self.c_f),
                **{key: jsonable(v) for key, v in self.details.items()}}


@dataclass
class DampingCoefficients(Result):
    """C_i and C_f of each component (``damping-coefficients``).

    Attributes
    ----------
    fits
        :class:`CoefficientFit` of each component worked on.
    mass_per_length
        mu + M used, kg/m, and ``mass_source`` where it comes from.
    method, weighting, confidence
        The fit's parameters.
    conventions
        Amplitude convention of each component's coefficients (measured or modal), in words.
    count
        Number of components.
    warning
        Said of every component (the method fell back to another), or None.
    errors
        Components without coefficients, with the reason.
    component_warnings
        Sentences said of one component's coefficients (a high-pass in the measuring chain
        seen in the record), by index.
    """

    kind = "damping-coefficients"

    fits: dict[int, CoefficientFit]
    mass_per_length: float
    mass_source: str
    method: str
    weighting: str
    confidence: float
    conventions: dict[int, str]
    count: int
    warning: str | None = None
    errors: dict[int, str] = field(default_factory=dict)
    component_warnings: dict[int, list[str]] = field(default_factory=dict)

    def record(self) -> AnalysisResult:
        done = self.fits
        entries = []
        for k, fit in done.items():
            summary = fit.summary()
            summary.update(mass_per_length=self.mass_per_length, method=self.method,
                           amplitude_convention=self.conventions.get(k, "measured"))
            entries.append({"index": k, "equivalent_damping": summary,
                            **({"warnings": list(self.component_warnings[k])}
                               if self.component_warnings.get(k) else {})})
        err_entries, err_attrs = error_entries(self.errors, "equivalent_damping")
        attrs = {"mass_per_length": self.mass_per_length,
                 "mass_per_length_source": self.mass_source, "method": self.method,
                 "weighting": self.weighting, "confidence": self.confidence,
                 "amplitude_convention": "; ".join(f"component {k}: {v}"
                                                   for k, v in sorted(self.conventions.items())),
                 **err_attrs}
        for k, fit in done.items():
            attrs[f"component_{k}_c_i"] = float(fit.c_i)
            attrs[f"component_{k}_c_f"] = float(fit.c_f)
            attrs[f"component_{k}_r2"] = fit.r2
            if fit.preferred_law is not None:
                attrs[f"component_{k}_preferred_law"] = fit.preferred_law
        summary_entries = entries + err_entries
        if self.warning:
            for entry in summary_entries:
                entry.setdefault("warnings", []).append(self.warning)
        return AnalysisResult(
            datasets={"amplitude": stack_rows({k: f.amplitude for k, f in done.items()},
                                              self.count),
                      "c_q": stack_rows({k: f.c_q for k, f in done.items()}, self.count)},
            units={"amplitude": "m", "c_q": "kg/(m s)"},
            attrs=attrs, summary={"components": summary_entries},
            values={k: {**f.summary(), "amplitude": f.amplitude, "c_q": f.c_q}
                    for k, f in done.items()})


# ----------------------------------------------------------------------------- modal model
#: Above this RMS (%) of the instantaneous frequencies' differences over the compared decay,
#: their mean (the modal model's frequency error) is warned as saying little.
FREQUENCY_SCATTER_PCT = 5.0


def _frequency_scatter(figures: dict[str, Any]) -> str | None:
    """A warning when the compared decay's instantaneous frequencies scatter too much for the
    modal model's frequency error to mean anything (a decay cut short by the record's end, as
    the last of an impulse train, or still forced where the comparison starts); else None."""
    rms = figures.get("frequency_rms_error_pct")
    if rms is None or not math.isfinite(rms) or rms <= FREQUENCY_SCATTER_PCT:
        return None
    return (f"the modal model's instantaneous frequencies differ from the measured ones by "
            f"{rms:.3g} % RMS over the decay compared ({figures['decay_start_s']:.3g} to "
            f"{figures['decay_end_s']:.3g} s: a decay cut short by the record's end, or still "
            f"forced where it starts): its frequency error of "
            f"{figures['frequency_error_pct']:+.2f} % says little")


@dataclass
class ModalComparison(Result):
    """The beam model run with the measured base motion, compared with the measurement
    (``modal-comparison``; the figures are described in :mod:`._modal_model`).

    Attributes
    ----------
    c_i, c_f
        Damping of the model, kg/(m s) and kg/m^2; ``c_source`` where they come from.
    model
        The damped :class:`fsi_lab.beam.BeamModel`.
    natural_frequencies_hz
        Its undamped natural frequencies, Hz.
    relative
        Whether the motion relative to the base was compared (else the absolute motion).
    oversampling
        Integration steps per sample.
    velocity_rms_error
        Error of the compared part of the signal.
    figures
        Error figures of each compared component, by index (JSON-ready items).
    model_components
        The model's decomposition, done as the measurement's.
    model_signal
        The model's output at the channel's sample times, unit of the channel.
    curves, units
        Datasets stored (velocity or signal, envelope, frequency, backbone and damping rows of
        both sides) and their units.
    projection, damping_method, start_s, sample_rate
        As used.
    count
        Number of measured components.
    errors
        Components that could not be compared, with the reason.
    """

    kind = "modal-comparison"

    c_i: float
    c_f: float
    c_source: str
    model: Any
    natural_frequencies_hz: list[float]
    relative: bool
    oversampling: int
    velocity_rms_error: float
    figures: dict[int, dict[str, Any]]
    model_components: Any
    model_signal: np.ndarray
    curves: dict[str, np.ndarray]
    units: dict[str, str]
    projection: str
    damping_method: str
    start_s: float
    sample_rate: float
    count: int
    errors: dict[int, str] = field(default_factory=dict)

    def record(self) -> AnalysisResult:
        top = {"c_i": self.c_i, "c_f": self.c_f, "c_source": self.c_source,
               "modes": self.model.modes, "projection": self.projection,
               "natural_frequencies_hz": [float(f) for f in self.natural_frequencies_hz],
               "coordinate": "relative" if self.relative else "absolute",
               "oversampling": self.oversampling, "velocity_rms_error": self.velocity_rms_error}
        entries = [{"index": k, "modal_model": {key: jsonable(v) for key, v in f.items()},
                    **({"warnings": [warning]} if (warning := _frequency_scatter(f)) else {})}
                   for k, f in self.figures.items()]
        err_entries, err_attrs = error_entries(self.errors, "modal_model")
        attrs: dict[str, Any] = {
            "c_i": self.c_i, "c_f": self.c_f, "c_source": self.c_source,
            "modes": self.model.modes, "projection": self.projection,
            "damping_method": self.damping_method,
            "coordinate": ("relative to the base (measured: hvd.relative_signal; model: its own "
                           "relative motion, Eq. 13)" if self.relative
                           else "absolute (as measured)"),
            "oversampling": self.oversampling, "start_s": self.start_s,
            "sample_rate": self.sample_rate, "velocity_rms_error": self.velocity_rms_error,
            "rows": "one row per measured component (index k), padded with NaN",
            "time_base": "velocity_* sample j at t = start_s + j / sample_rate from the "
                         "channel's first sample (the decomposed part of the record); "
                         "envelope_* at envelope_time",
            **err_attrs,
        }
        for k, f in self.figures.items():
            for key, v in f.items():
                if v is not None:
                    attrs[f"component_{k}_{key}"] = v
        return AnalysisResult(
            datasets=self.curves, units=self.units, attrs=attrs,
            summary={"modal_model": {key: jsonable(v) for key, v in top.items()},
                     "components": entries + err_entries},
            values={"model_hvd": self.model_components, "model_signal": self.model_signal,
                    "model": self.model, "figures": self.figures})
