"""The work of the ``hvd`` analysis plugin (declared in :mod:`.hvd`): the decomposition of a
channel into one component per mode.

Two methods: ``bands`` (default) adapts :mod:`fsi_lab.dsp.identify` and
:mod:`fsi_lab.dsp.components`; ``hvd`` adapts :mod:`fsi_lab.dsp.hvd` (the paper's method).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from fsi_lab.contract import AnalysisContext
from fsi_lab.dsp.components import band_components
from fsi_lab.dsp.decays import QUIET_LEVEL, quiet_times
from fsi_lab.dsp.hvd import PEAK_SMOOTHING, PEAK_THRESHOLD, band_around, hvd
from fsi_lab.dsp.identify import identify
from fsi_lab.errors import AnalysisError
from fsi_lab.plugins.analysis._chain import channel_noise, free_decay_peaks_of, guarded, where
from fsi_lab.plugins.analysis.results import Components


def relative_signal(context: AnalysisContext, mode: str, plugin: str = "hvd"
                    ) -> tuple[np.ndarray, str | None]:
    """The channel, minus the base motion when asked (``mode`` "yes", or "auto" with a base
    acceleration reference): the beam's motion relative to its clamp, the coordinate of the
    modal model (Eq. 13). Returns the samples and the reference used (or None).

    The reference acceleration is integrated to the channel's quantity with
    :func:`.integrate.integrate`, high-passed at half the lowest spectral peak of the channel
    (so the base motion at the beam's modes is kept; from the channel's shared spectrum, as
    :func:`fsi_lab.dsp.integrate.lowest_mode` finds it).
    """
    from fsi_lab.dsp.integrate import integrate

    ch = context.channel
    data = np.asarray(ch.data, dtype=np.float64)
    ref_name = context.reference
    ref = context.channels.get(ref_name) if ref_name else None
    usable = (ref is not None and ref_name != ch.name and ref.quantity == "acceleration"
              and ch.quantity in ("displacement", "velocity", "acceleration"))
    if mode == "no" or (mode == "auto" and not usable):
        return data, None
    if not usable:
        raise AnalysisError(
            f"{where(plugin, context)}: relative = 'yes' needs a base acceleration reference "
            "channel (the profile's [analysis] reference) and a displacement, velocity or "
            f"acceleration channel; reference is {ref_name!r}")
    if abs(float(ref.sample_rate) - float(ch.sample_rate)) > 1e-9 * float(ch.sample_rate) \
            or ref.data.size != data.size:
        raise AnalysisError(
            f"{where(plugin, context)}: reference {ref_name!r} ({ref.data.size} samples at "
            f"{ref.sample_rate:g} Hz) does not match the channel ({data.size} samples at "
            f"{ch.sample_rate:g} Hz); cannot subtract the base motion")
    order = {"acceleration": 0, "velocity": 1, "displacement": 2}[ch.quantity]
    if order == 0:
        base = np.asarray(ref.data, dtype=np.float64)
    else:
        highpass = 0.5 * lowest_peak(context, plugin)
        try:
            base = integrate(ref.data, ch.sample_rate, order=order, highpass=highpass)
        except AnalysisError as exc:
            # (the reference's fault, not the channel's: a clipped or silent accelerometer)
            raise AnalysisError(
                f"{where(plugin, context)}: the base acceleration reference {ref_name!r} "
                f"cannot be integrated to subtract the base motion: {exc}; "
                "--set analysis.hvd.relative=no analyses the channel's absolute motion "
                "instead") from None
    # The channels may start at different times (a vibrometer's signal delay makes its t0
    # negative): take the base motion at the channel's own sample times.
    shift = float(ch.t0) - float(ref.t0)
    if shift:
        t = np.arange(data.size) / float(ch.sample_rate)
        base = np.interp(t + shift, t, base)
    return data - base, ref_name


def lowest_peak(context: AnalysisContext, plugin: str) -> float:
    """Lowest significant spectral peak of the channel, Hz (as
    :func:`fsi_lab.dsp.integrate.lowest_mode` finds it, from the shared spectrum)."""
    peaks = free_decay_peaks_of(context)
    if peaks.frequencies.size == 0:
        fs, n = float(context.channel.sample_rate), context.channel.data.size
        raise AnalysisError(f"{where(plugin, context)}: found no spectral peak above the lowest "
                            f"resolvable frequency {2.0 * fs / n:.3g} Hz, so no high-pass corner "
                            "can be chosen for the base motion")
    return float(peaks.frequencies.min())


def switch_message(context: AnalysisContext, k: int, pair: tuple[float, float],
                   peaks: np.ndarray) -> str:
    """The error recorded for component ``k`` that switches between the modes ``pair`` (Hz,
    :attr:`HVDResult.switches`): what happened, and the two ways out (an impulse width whose
    half-sine spectrum is zero on the higher mode; a ``band_hz`` around each mode, from the
    record's spectral ``peaks``, Hz)."""
    high = max(pair)
    bands = [(f, band_around(f, peaks)) for f in sorted(pair)] if peaks.size else []
    hint = "; ".join(f"[{b[0]:g}, {b[1]:g}] for the {f:.1f} Hz mode" for f, b in bands if b)
    return (f"{where('hvd', context)}: component {k} switches between the modes near "
            f"{pair[0]:.1f} Hz and {pair[1]:.1f} Hz (their envelopes cross, which HVD cannot "
            "separate: it follows the larger); its frequencies, damping and C_i / C_f would mix "
            "the two modes. Excite the higher mode less (e.g. impulse-train width "
            f"{1.5 / high:.2g} s puts a half-sine's first spectral zero on {high:.1f} Hz) or "
            "decompose one mode at a time with analysis.hvd.band_hz"
            + (f" (e.g. {hint})" if hint else ""))


#: Modes of the motion relative to the base are sought from this share of the channel's
#: lowest spectral peak up (the base's integration is high-passed at half of it).
RELATIVE_FLOOR = 0.8

#: The quantity :func:`fsi_lab.dsp.identify.identify` analyses for each channel quantity (a
#: voltage from an unknown sensor is taken as the coordinate itself).
_IDENTIFY_AS = {"velocity": "velocity", "displacement": "displacement",
                "acceleration": "acceleration", "voltage": "displacement"}


def run(context: AnalysisContext, params: dict[str, Any]) -> Components:
    if params["method"] == "bands":
        return _run_bands(context, params)
    return _run_hvd(context, params)


def _run_bands(context: AnalysisContext, params: dict[str, Any]) -> Components:
    """One component per mode: :func:`fsi_lab.dsp.identify.identify` and
    :func:`fsi_lab.dsp.components.band_components`."""
    ch = context.channel
    data, relative_to = relative_signal(context, params["relative"])
    fs = float(ch.sample_rate)
    quantity = _IDENTIFY_AS.get(ch.quantity, "displacement")
    starts = [] if params["start_s"] is None else [params["start_s"]]
    quiet = base_quiet(context)
    with guarded("hvd", context):
        # The base motion is integrated with a high-pass at half the channel's lowest
        # spectral peak (relative_signal): its transient after each excitation rings near
        # that corner in the relative motion alone, a decay the channel itself does not show.
        lowest = RELATIVE_FLOOR * lowest_peak(context, "hvd") \
            if relative_to and ch.quantity != "acceleration" else None
        ident = identify(data, fs, quantity=quantity,
                         components=params["components"] or "auto", band=params["band_hz"],
                         decay_starts=(starts + list(quiet)) or None,
                         reference=base_on_channel_clock(context), min_frequency=lowest)
        res = band_components(data, fs, ident, integrate=int(quantity == "acceleration"))
    return Components(
        decomposition=res, method="bands",
        unit=ch.unit if quantity != "acceleration" else "m/s", channel_unit=ch.unit,
        relative_to=relative_to,
        start_rule="each free decay from its largest sample, or from the end of a forced "
        "response that holds it (the channel's notes name each later start and why)"
        + ("" if params["start_s"] is None else f", not before {params['start_s']:g} s")
        + (f", and not before the base has calmed down ({QUIET_LEVEL:g} of its peak "
           f"envelope) at {', '.join(f'{s:.4g}' for s in quiet)} s" if len(quiet) else ""),
        band_hz=params["band_hz"])


def base_on_channel_clock(context: AnalysisContext) -> np.ndarray | None:
    """The base acceleration (the chain's reference) at the channel's sample times, or None
    without a usable reference."""
    ch = context.channel
    ref = context.channels.get(context.reference) if context.reference else None
    if ref is None or ref.name == ch.name or ref.quantity != "acceleration" \
            or ref.data.size != ch.data.size or not np.all(np.isfinite(ref.data)) \
            or abs(float(ref.sample_rate) - float(ch.sample_rate)) > 1e-9 * float(ch.sample_rate):
        return None
    data = np.asarray(ref.data, dtype=np.float64)
    shift = float(ch.t0) - float(ref.t0)
    if shift:
        t = np.arange(data.size) / float(ch.sample_rate)
        data = np.interp(t + shift, t, data)
    return data


def base_quiet(context: AnalysisContext) -> np.ndarray:
    """Times (s, on the channel's clock) at which the base acceleration (the chain's reference)
    has calmed down after each excitation (:func:`fsi_lab.dsp.decays.quiet_times`); empty
    without a usable reference."""
    ch = context.channel
    ref = context.channels.get(context.reference) if context.reference else None
    if ref is None or ref.name == ch.name or ref.quantity != "acceleration" \
            or ref.data.size < 64 or not np.all(np.isfinite(ref.data)):
        return np.empty(0)
    times = quiet_times(ref.data, float(ref.sample_rate))
    return times + (float(ref.t0) - float(ch.t0))


def _auto_components(context: AnalysisContext, data: np.ndarray) -> int:
    """Feldman's HVD with ``components`` unset: one per significant spectral peak of the free
    decays of ``data`` (the decomposed part of the channel; at most 7, his limit)."""
    peaks = free_decay_peaks_of(context, data, min_relative=PEAK_THRESHOLD,
                                smoothing=PEAK_SMOOTHING)
    return int(min(max(peaks.frequencies.size, 1), 7))


def _run_hvd(context: AnalysisContext, params: dict[str, Any]) -> Components:
    ch = context.channel
    data, relative_to = relative_signal(context, params["relative"])
    if params["start_s"] is None:
        # Automatic: the free decay starts where the excitation leaves the structure, at the
        # largest sample (0 for a record that starts with the decay); for several decays (an
        # impulse train) at the largest sample of the first one.
        from fsi_lab.dsp.decays import first_decay_peak
        sigma, f_dom = channel_noise(context)
        fs = float(ch.sample_rate)
        i0 = first_decay_peak(data, fs, 1.0 / f_dom, 10.0 * sigma) if f_dom > 0 \
            else int(np.argmax(np.abs(data)))
        start_rule = "auto: at the largest sample of the first free decay (end of the excitation)"
    else:
        i0 = int(round(params["start_s"] * float(ch.sample_rate)))
        start_rule = "given"
    if i0 >= data.size - 32:
        raise AnalysisError(f"{where('hvd', context)}: start_s = {i0 / ch.sample_rate:g} s leaves "
                            f"{max(data.size - i0, 0)} samples of a {data.size / ch.sample_rate:g}"
                            " s record; expected a start inside the record")
    with guarded("hvd", context):
        count = params["components"] or _auto_components(context, data[i0:])
        res = hvd(data[i0:], ch.sample_rate, count, params["cutoff_hz"],
                  padding=params["padding"], band=params["band_hz"])
    res = dataclasses.replace(res, t0=i0 / float(ch.sample_rate))
    refused = {k: switch_message(context, k, pair, res.peaks)
               for k, pair in enumerate(res.switches) if pair is not None}
    return Components(decomposition=res, method="hvd", unit=ch.unit, channel_unit=ch.unit,
                      relative_to=relative_to, start_rule=start_rule,
                      band_hz=list(res.band) if res.band is not None else None,
                      padding=params["padding"], refused=refused)
