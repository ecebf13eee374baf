"""What the analysis plugins share: components of a channel, errors, JSON helpers.

Conventions of the chain (documented for plugin users in each plugin's help):

- Results pass between the plugins as typed objects (:mod:`.results`): each plugin declares
  the kinds it requires, uses and provides, and reads them with ``context.result(kind)``.
- Components are numbered from 0 (``"index"`` in the summary, row of the 2-D HVD datasets).
  When ``hvd`` ran earlier on the channel its components (:class:`.results.Components`) are
  analysed one by one; otherwise the whole channel is component 0.
- Amplitudes in summaries are in metres of displacement (``integrate`` output when it ran,
  else the channel integrated on the fly, or the channel itself if it is a displacement).
- A failure on one component is recorded (``summary`` entry ``"error"`` and attribute
  ``component_<k>_error``, from the typed result's ``errors``) and the others go on; the plugin
  fails only if every component does. A component ``hvd`` refuses
  (:attr:`.results.Components.refused`: one that switches between two modes whose envelopes
  cross) carries ``hvd``'s message through every later plugin instead of results.
- The channel's spectrum is computed once for the whole chain (``context.spectrum``, at a fast
  FFT length), and so is its noise level (:func:`channel_noise`).
- Cycles whose amplitude is below 10 x the noise left in a component are not measured (unless
  the plugin's ``min_amplitude`` is set): the white-noise RMS of the raw channel (from its
  spectrum above 3 x the dominant frequency), scaled to the component's band (an HVD component
  keeps its frequency +- 1.5 cut-off; a whole channel about 3 x its frequency) and divided by
  2 pi f per integration. An HVD component is band-limited, so its own spectrum shows no noise
  floor: the tail of a decay sunk into noise would otherwise be measured as garbage. Nor are
  HVD-component cycles below ``HVD_RANGE`` (1e-3) of the record's largest envelope (the
  decomposition leaves a residue of about 1e-4 of it in every component).
- Backbone and damping points closer than one period to a record end, or inside HVD's
  untrusted edge, are left out, and so are those outside the free decays (``decay_only``:
  before a decay's largest amplitude the excitation is still feeding the mode - a forced
  build-up is no free decay). A record may hold several free decays (an impulse train): it is
  split from the amplitudes themselves (:mod:`._decays`), and estimates from pairs or windows
  of peaks are made within one decay, never across two.
"""

from __future__ import annotations

import math
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Callable, Iterator

import numpy as np

from fsi_lab.contract import AnalysisContext, RecordSpectrum, record_spectrum
from fsi_lab.dsp.components import BandComponents
from fsi_lab.dsp.decays import FreeDecays, split_decays
from fsi_lab.dsp.identify import ModeIdentification
from fsi_lab.dsp.spectrum import SpectralPeaks, find_peaks_interpolated, free_decay_peaks
from fsi_lab.errors import AnalysisError
from fsi_lab.plugins.analysis.results import (  # noqa: F401 - the plugins import them from here
    Components,
    Integrated,
    decay_attrs,
    decay_summary,
    error_entries,
    jsonable,
    stack_rows,
)
from fsi_lab.units import voltage_hint

#: Dynamic range of HVD components: cycles below this fraction of the largest envelope of the
#: record are decomposition residue (about 1e-4) rather than signal.
HVD_RANGE = 1e-3

#: Units of the displacement, velocity and acceleration quantities.
SI_UNITS = {"displacement": "m", "velocity": "m/s", "acceleration": "m/s^2"}


@dataclass
class Component:
    """One component of a channel.

    Attributes
    ----------
    index
        0-based component number.
    signal
        Samples, in ``unit``.
    quantity
        ``displacement``, ``velocity``, ``acceleration`` or ``voltage``.
    unit
        Unit of ``signal``.
    sample_rate
        Hz.
    edge_mask
        True where samples are not trusted (HVD record ends), or None.
    noise_floor
        Smallest cycle amplitude worth measuring (10 x the noise RMS in the component), in
        ``unit``, or None to let the analysis estimate it.
    settle
        Time (s) over which the component's filters smear a sudden change (HVD: 2 / cutoff,
        plus the band-pass's smear with ``band_hz``): a free decay is taken to start that long
        after the largest amplitude.
    t0
        Time of the first sample relative to the channel's first sample, s (HVD ``start_s``).
    frequency
        Approximate frequency of the component, Hz (None if unknown).
    """

    index: int
    signal: np.ndarray
    quantity: str
    unit: str
    sample_rate: float
    edge_mask: np.ndarray | None = None
    noise_floor: float | None = None
    settle: float = 0.0
    t0: float = 0.0
    frequency: float | None = None


#: Signals per component handed down the chain: the ``integrate`` plugin's typed result.
ComponentSignals = Integrated


def where(plugin: str, context: AnalysisContext) -> str:
    return f"{plugin} on channel {context.channel.name!r}"


@contextmanager
def guarded(plugin: str, context: AnalysisContext) -> Iterator[None]:
    """Prefix AnalysisErrors with the plugin and channel names."""
    try:
        yield
    except AnalysisError as exc:
        text = str(exc)
        prefix = where(plugin, context)
        raise AnalysisError(text if text.startswith(prefix) else f"{prefix}: {text}") from None


def channel_noise(context: AnalysisContext) -> tuple[float, float]:
    """White-noise RMS of the raw channel and its dominant frequency.

    Computed once per channel for the whole chain (every plugin of the chain asks), from the
    channel's shared spectra (``context.spectrum``).

    Parameters
    ----------
    context
        The analysis context; its channel's samples are used.

    Returns
    -------
    tuple of float
        The RMS (unit of the channel) of the white noise, from the channel's Hann spectrum
        above 3 x the dominant frequency (as :func:`fsi_lab.dsp.instantaneous.noise_rms`), and
        that dominant frequency (the largest peak of its ``decay``-window spectrum), Hz;
        ``(0.0, 0.0)`` when the spectrum shows no peak.
    """
    assert context.shared is not None
    return context.shared.once("channel_noise", lambda: _channel_noise(context))


def _channel_noise(context: AnalysisContext) -> tuple[float, float]:
    try:
        decay = context.spectrum("decay")
        peaks = find_peaks_interpolated(decay.frequency, decay.amplitude, min_relative=0.05,
                                        max_peaks=1, smoothing=0.05, _func="spectral_peaks")
    except AnalysisError:
        return 0.0, 0.0
    if peaks.frequencies.size == 0:
        return 0.0, 0.0
    f_dom = float(peaks.frequencies[0])
    return noise_from_spectrum(context.spectrum("hann"), f_dom), f_dom


def noise_from_spectrum(spectrum: RecordSpectrum, f_dom: float) -> float:
    """RMS of the white noise in a record, from the median of its Hann amplitude spectrum
    above 3 ``f_dom`` (Hz), as :func:`fsi_lab.dsp.instantaneous.noise_rms` finds it: a
    Rayleigh-distributed bin's median is ``sigma sqrt(ln 2) sqrt(sum w^2)`` before the
    amplitude scaling ``2 / sum w``. 0 when fewer than 8 bins lie above."""
    n = spectrum.samples
    w = np.hanning(n)
    k0 = int(np.ceil(3.0 * f_dom * spectrum.nfft / spectrum.sample_rate))
    if k0 >= spectrum.amplitude.size - 8:
        return 0.0
    med = float(np.median(spectrum.amplitude[k0:])) * 0.5 * float(w.sum())
    return med / (math.sqrt(math.log(2.0)) * math.sqrt(float(np.sum(w * w))))


def free_decay_peaks_of(context: AnalysisContext, x: np.ndarray | None = None,
                        min_relative: float = 0.01, smoothing: float = 0.05) -> SpectralPeaks:
    """:func:`fsi_lab.dsp.spectrum.free_decay_peaks` of the channel (or of ``x``, samples of
    another record at the channel's rate), from the channel's shared ``decay`` spectrum (or
    ``x``'s own, at a fast length): the peaks of the whole record for one free decay, of its
    decays' averaged spectrum for several (an impulse train)."""
    fs = float(context.channel.sample_rate)
    if x is None:
        x = np.asarray(context.channel.data, dtype=np.float64)
        spectrum = context.spectrum("decay")
    else:
        spectrum = record_spectrum(x, fs, "decay")
    return free_decay_peaks(x, fs, min_relative=min_relative, smoothing=smoothing,
                            spectrum=(spectrum.frequency, spectrum.amplitude))


def _floor(sigma: float, fs: float, f_k: float, band: float, order: int) -> float | None:
    """10 x the noise RMS left in a component at f_k (Hz) whose noise band is ``band`` Hz wide,
    after ``order`` integrations (each divides by 2 pi f_k)."""
    if sigma <= 0 or f_k <= 0:
        return None
    return 10.0 * sigma * math.sqrt(min(1.0, band / (0.5 * fs))) / (2 * math.pi * f_k) ** order


def components(context: AnalysisContext, order: int = 0) -> list[Component]:
    """The channel's components: HVD's if it ran earlier in the chain (the ``components``
    result), else the channel.

    ``order`` (integrations the caller will apply) only scales the noise floors. Raises
    AnalysisError when HVD failed earlier in the chain: the whole channel is no stand-in for
    the components the chain asked for.
    """
    found = context.result(Components)     # (raises when hvd failed earlier)
    ch = context.channel
    fs = float(ch.sample_rate)
    sigma, f_dom = channel_noise(context)
    if found is not None and isinstance(found.decomposition, BandComponents):
        return _band_components(found.decomposition, ch, order)
    if found is not None:
        res = found.decomposition
        out = []
        largest = float(np.max(res.envelopes[~res.edge_mask])) if (~res.edge_mask).any() \
            else float(np.max(res.envelopes))
        for k in range(res.components.shape[0]):
            f_k = res.mean_frequency(k)
            # The demodulation keeps f_k +- 1.5 cutoff.
            floor = _floor(sigma, fs, f_k, 3.0 * float(res.cutoffs[k]), order) or 0.0
            # The decomposition leaves a residue of about 1e-4 of the largest component in
            # the others: cycles below 10 x that are not measured either.
            floor = max(floor, HVD_RANGE * largest / (2 * math.pi * f_k) ** order) \
                if f_k > 0 else floor
            out.append(Component(k, res.components[k], ch.quantity, ch.unit, res.sample_rate,
                                 res.edge_mask[k], floor, res.settle(k),
                                 float(getattr(res, "t0", 0.0)), f_k if f_k > 0 else None))
        return out
    # A cycle-by-cycle measurement feels the noise near the oscillation: about 3 f wide.
    floor = _floor(sigma, fs, f_dom, 3.0 * f_dom, order)
    return [Component(0, np.asarray(ch.data, dtype=np.float64), ch.quantity, ch.unit, fs, None,
                      floor, frequency=f_dom if f_dom > 0 else None)]


def _band_components(res: BandComponents, ch: Any, order: int) -> list[Component]:
    """Components of the ``bands`` decomposition: no settling time (each decay is filtered on
    its own), the noise floor of the identification scaled by ``order`` integrations."""
    ident = res.identification
    quantity, unit = ("velocity", "m/s") if res.integrate else (ch.quantity, ch.unit)
    out = []
    for k, mode in enumerate(ident.modes):
        f_k = mode.frequency_hz
        floor = mode.noise_floor / (2 * math.pi * f_k) ** order
        out.append(Component(k, res.components[k], quantity, unit, res.sample_rate,
                             res.edge_mask[k], floor, 0.0, 0.0, f_k))
    return out


def identified_mode(context: AnalysisContext, c: Component, params: dict[str, Any]
                    ) -> ModeIdentification | None:
    """The identification of the mode of ``c``, a component of the ``bands`` decomposition,
    when its backbone and damping curve are taken from it: the zero-crossing analysis at its
    defaults in ``params`` (no ``min_amplitude``, offset ``cycles``, ``decay_only``). Else
    None: the curves are measured on the component's signal."""
    found = context.result(Components)
    ident = found.identification if found is not None else None
    if ident is None or params.get("min_amplitude") is not None \
            or params.get("offset", "cycles") != "cycles" \
            or not params.get("decay_only", True) or not 0 <= c.index < len(ident.modes):
        return None
    return ident.modes[c.index]


def identified_decays(mode: ModeIdentification, c: Component, times: np.ndarray,
                      amplitude: np.ndarray) -> tuple[np.ndarray, FreeDecays]:
    """Free decay of each of an identified mode's points (``times``, s from the component's
    start, with their ``amplitude``) and the free decays, as :func:`decay_labels` gives them
    for a component's own points: each free decay identify measured
    (:attr:`fsi_lab.dsp.identify.ModeIdentification.measured_decays`) split again where its
    extrema rise as after a new excitation (identify splits the record where its largest
    swings rise twice over; a small impulse into a decay still ringing can rise less there than
    in the mode's extrema), but with no margin at the record's ends: identify's extrema are
    corrected for the band filter's smear there."""
    spans = sorted((float(d.times[0]), float(d.times[-1])) for d in mode.measured_decays
                   if d.times.size)
    labels = np.full(times.size, -1, dtype=np.int64)
    later = 4.0 / c.frequency if c.frequency else 0.0
    parts, count = [], 0
    for lo, hi in spans:
        inside = np.flatnonzero((times >= lo) & (times <= hi))
        if inside.size < 2:
            continue
        split = split_decays(times[inside], amplitude[inside], later_settle=later,
                             first_build_up=False, guard=2.0 * later)
        own = split.labels(times[inside])
        labels[inside] = np.where(own >= 0, own + count, -1)
        count += split.count
        parts.append((split, hi))
    bounds, region, first = [], [], 0
    for k, (split, hi) in enumerate(parts):
        bounds += split.bounds.tolist() + ([hi] if k < len(parts) - 1 else [])
        region += (split.region + first).tolist()
        first += split.bounds.size + 1

    def joined(name: str) -> np.ndarray:
        return np.concatenate([getattr(split, name) for split, _ in parts]) if parts \
            else np.empty(0)

    return labels, FreeDecays(peaks=joined("peaks"), starts=joined("starts"),
                              ends=joined("ends"), bounds=np.array(bounds, dtype=np.float64),
                              region=np.array(region, dtype=np.int64))


def displacement_components(context: AnalysisContext, plugin: str) -> list[Component]:
    """Components as displacement (m): from ``integrate`` if it ran (the ``integrated``
    result), else integrated here."""
    from fsi_lab.dsp.integrate import integrate

    context.result(Components)      # (a failed decomposition is the first reason to give)
    integ = context.result(Integrated)
    if integ is not None and integ.quantity == "displacement":
        return _integrated_components(integ)
    quantity = component_quantity(context)
    if quantity == "displacement":
        return components(context)
    found = context.result(Components)
    if quantity in ("velocity", "acceleration") and found is not None \
            and isinstance(found.decomposition, BandComponents):
        # Band by band: a band holds no zero frequency, so no high-pass is needed.
        comps = _band_components(
            found.decomposition.integrated(1 if quantity == "velocity" else 2),
            context.channel, 0)
        order = 1 if quantity == "velocity" else 2
        return [Component(c.index, c.signal, "displacement", "m", c.sample_rate, c.edge_mask,
                          c.noise_floor / (2 * math.pi * c.frequency) ** order, 0.0, 0.0,
                          c.frequency) for c in comps]
    if quantity not in ("velocity", "acceleration"):
        raise AnalysisError(
            f"{where(plugin, context)}: the channel measures {quantity!r} ({context.channel.unit})"
            "; displacement amplitudes need a calibrated displacement, velocity or acceleration "
            "channel" + voltage_hint(quantity))
    order = 1 if quantity == "velocity" else 2
    out = []
    for c in components(context, order):
        out.append(Component(c.index, integrate(c.signal, c.sample_rate, order=order),
                             "displacement", "m", c.sample_rate, c.edge_mask, c.noise_floor,
                             c.settle, c.t0, c.frequency))
    return out


def component_quantity(context: AnalysisContext) -> str:
    """What the channel's components measure: the channel's quantity, or a velocity when
    the ``bands`` decomposition integrated an acceleration band by band."""
    found = context.result(Components)
    if found is not None and isinstance(found.decomposition, BandComponents) \
            and found.decomposition.integrate:
        return "velocity"
    return context.channel.quantity


def velocity_components(context: AnalysisContext) -> list[Component] | None:
    """Components as velocity (m/s), or None when the channel is not a velocity or an
    acceleration (a displacement is not differentiated: it would amplify noise)."""
    from fsi_lab.dsp.integrate import integrate

    quantity = component_quantity(context)        # (raises first when hvd failed)
    if quantity == "velocity":
        return components(context)
    integ = context.result(Integrated)
    if integ is not None and integ.quantity == "velocity":
        return _integrated_components(integ)
    if quantity == "acceleration":
        return [Component(c.index, integrate(c.signal, c.sample_rate, order=1), "velocity",
                          "m/s", c.sample_rate, c.edge_mask, c.noise_floor, c.settle, c.t0,
                          c.frequency)
                for c in components(context, 1)]
    return None


def _integrated_components(v: Integrated) -> list[Component]:
    """The components of ``integrate``'s result."""
    return [Component(k, sig, v.quantity, v.unit, v.sample_rate, v.edge_masks.get(k),
                      v.noise_floors.get(k), v.settles.get(k, 0.0), v.t0s.get(k, 0.0),
                      v.frequencies.get(k)) for k, sig in sorted(v.signals.items())]


def refused_components(context: AnalysisContext) -> dict[int, str]:
    """The components that ``hvd`` (earlier in the chain) refuses, with its message
    (:attr:`.results.Components.refused`: one that switches between two modes,
    :func:`fsi_lab.dsp.mode_switch.mode_switches`)."""
    found = context.result(Components)
    return dict(found.refused) if found is not None else {}


def per_component(plugin: str, context: AnalysisContext, comps: list[Component],
                  work: Callable[[Component], Any]) -> tuple[dict[int, Any], dict[int, str]]:
    """Run ``work`` on each component; collect results and per-component error messages.

    A component that ``hvd`` refuses (:func:`refused_components`) is not worked on:
    its error is ``hvd``'s message, so every later plugin reports it rather than numbers.
    Raises AnalysisError (naming plugin, channel and every component's reason) when all fail.
    """
    done: dict[int, Any] = {}
    marked = refused_components(context)
    errors: dict[int, str] = dict(marked)
    for c in comps:
        if c.index in errors:
            continue
        try:
            done[c.index] = work(c)
        except AnalysisError as exc:
            errors[c.index] = str(exc)
    if not done:
        reasons = "; ".join(
            f"component {k}: " + ("refused by hvd (see its error for this component)"
                                  if k in marked else m)
            for k, m in sorted(errors.items()))
        raise AnalysisError(f"{where(plugin, context)}: {reasons}")
    return done, errors


def trusted_span(times: np.ndarray, comp: Component, period: float) -> np.ndarray:
    """Boolean mask of ``times`` (s) not in the component's untrusted edge and at least one
    ``period`` (s) from either record end."""
    n = comp.signal.size
    fs = comp.sample_rate
    ok = (times >= period) & (times <= (n - 1) / fs - period)
    if comp.edge_mask is not None and comp.edge_mask.any():
        idx = np.clip(np.rint(times * fs).astype(np.int64), 0, n - 1)
        ok &= ~comp.edge_mask[idx]
    return ok


def decay_labels(times: np.ndarray, comp: Component, period: float,
                 amplitude: np.ndarray | None = None, decay_only: bool = True
                 ) -> tuple[np.ndarray, FreeDecays | None]:
    """Free decay of each of ``times`` (s): its index, or -1 where the point is not used.

    Points in the untrusted span (:func:`trusted_span`) are -1. With ``amplitude`` and
    ``decay_only`` the record is split into its free decays (:func:`._decays.split_decays` on
    the trusted points: the component's ``settle`` after the first peak, the larger of it and
    the integration's smear after the later ones, twice that before each next build-up) and
    only their free parts are kept - a decay too short for those margins is no decay, and the
    decays are numbered 0..count-1 in time order; otherwise every trusted point is decay 0 and
    no split is returned.
    """
    ok = trusted_span(times, comp, period)
    labels = np.where(ok, 0, -1)
    if not (decay_only and amplitude is not None and ok.any()):
        return labels, None
    # A build-up inside the record is smeared by the HVD filters (settle) and by the high-pass
    # of the frequency-domain integration (2 / corner, the corner about half the component's
    # frequency) on both sides; the smear before it weighs on the small tail of the previous
    # decay, hence twice the settle time there.
    # An HVD component (settle > 0) starts at the first decay's peak: its first build-up is not
    # in the record. A whole channel whose first measured cycles come well after its start
    # was quiet (below the noise floor) before the first excitation.
    later = max(comp.settle, 4.0 / comp.frequency if comp.frequency else 0.0)
    first = times[ok][0]
    build_up = False if comp.settle > 0 else (True if first > 4.0 * period else None)
    decays = split_decays(times[ok], amplitude[ok], settle=comp.settle, later_settle=later,
                          first_build_up=build_up, guard=max(2.0 * later, period))
    labels = np.where(ok, decays.labels(times), -1)
    return labels, decays


def trusted_times(times: np.ndarray, comp: Component, period: float,
                  amplitude: np.ndarray | None = None, decay_only: bool = True) -> np.ndarray:
    """Boolean mask of ``times`` (s) not in the component's untrusted edge, at least one
    ``period`` (s) from either record end and - with ``amplitude`` and ``decay_only`` - inside
    a free decay: from a decay's largest amplitude plus the component's ``settle`` time (the
    free decay starts when the excitation has stopped feeding the mode - a forced build-up is no
    free vibration - and the HVD filters smear the onset over about 1 / cutoff) to just before
    the next build-up (:func:`decay_labels`)."""
    return decay_labels(times, comp, period, amplitude, decay_only)[0] >= 0
