"""The work of the ``damping`` analysis plugin (declared in :mod:`.damping`): an adapter around
:mod:`fsi_lab.dsp.damping`."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from fsi_lab.contract import AnalysisContext
from fsi_lab.dsp.damping import DampingCurve, damping_from_peaks
from fsi_lab.dsp.identify import ModeIdentification
from fsi_lab.dsp.instantaneous import Instantaneous, instantaneous
from fsi_lab.plugins.analysis._chain import (
    Component,
    decay_labels,
    displacement_components,
    guarded,
    identified_decays,
    identified_mode,
    per_component,
)
from fsi_lab.plugins.analysis.results import DampingCurves


def decay_peaks(inst: Instantaneous, c: Component, decay_only: bool = True):
    """Extrema of a component's :class:`.instantaneous.Instantaneous` analysis without the
    untrusted record ends (the HVD edge mask and one period at each end) and, with
    ``decay_only``, outside its free decays: times (s from the channel's first sample),
    amplitudes, frequencies (Hz), the decay of each extremum and the free decays found (None
    without ``decay_only``; times from the component's start)."""
    period = 1.0 / float(np.median(inst.frequency))
    labels, decays = decay_labels(inst.peak_times, c, period, inst.peak_amplitudes, decay_only)
    keep = labels >= 0
    return (inst.peak_times[keep] + c.t0, inst.peak_amplitudes[keep],
            inst.peak_frequency[keep], labels[keep], decays)


def identified_peaks(mode: ModeIdentification, c: Component):
    """:func:`decay_peaks` of a component of the ``bands`` decomposition from its mode's
    identification: the extrema of each free decay (:func:`._chain.identified_decays`) as
    measured and corrected for the band filter's smear of the first cycles, from the first, as
    displacement amplitudes (m) at the backbone's frequency there. Read off the band signal
    itself, a release's first damping ratios alternated 10 to 15 % about the truth, and the
    curve began a period after the release."""
    measured = mode.measured_decays
    times = np.concatenate([d.times for d in measured]) if measured else np.empty(0)
    amp = np.concatenate([d.amplitude for d in measured]) if measured else np.empty(0)
    bb = mode.backbone
    freq = np.interp(times, bb.times, bb.frequency) if bb.times.size \
        else np.full(times.size, mode.damped_frequency_hz)
    if mode.quantity == "velocity":
        amp = amp / (2.0 * np.pi * freq)
    labels, decays = identified_decays(mode, c, times, amp)
    keep = labels >= 0
    return times[keep] + c.t0, amp[keep], freq[keep], labels[keep], decays


def trusted_peaks(c: Component, params: dict[str, Any],
                  context: AnalysisContext | None = None):
    """:func:`decay_peaks` of a component (its extrema measured with ``params``), or with the
    chain's ``context`` its mode's when the identification has it
    (:func:`._chain.identified_mode`, :func:`identified_peaks`)."""
    mode = identified_mode(context, c, params) if context is not None else None
    if mode is not None:
        return identified_peaks(mode, c)
    inst = instantaneous(c.signal, c.sample_rate, offset=params.get("offset", "cycles"),
                         min_amplitude=params.get("min_amplitude"), noise_floor=c.noise_floor,
                         frequency_hint=c.frequency)
    return decay_peaks(inst, c, params.get("decay_only", True))


def curve_for(c: Component, params: dict[str, Any],
              context: AnalysisContext | None = None) -> DampingCurve:
    """Damping curve of a component, decay by decay (``decays`` holds the split), from
    :func:`trusted_peaks`."""
    t, a, f, decay, decays = trusted_peaks(c, params, context)
    curve = damping_from_peaks(t, a, f, method=params["method"], span=params["span"],
                               window=params["window"], smooth=params["smooth_points"],
                               decay=decay)
    return dataclasses.replace(curve, decays=decays)


def run(context: AnalysisContext, params: dict[str, Any]) -> DampingCurves:
    with guarded("damping", context):
        disp = displacement_components(context, "damping")

    def work(c):
        with guarded("damping", context):
            return curve_for(c, params, context)

    done, errors = per_component("damping", context, disp, work)
    return DampingCurves(curves=done, method=params["method"],
                         t0s={c.index: c.t0 for c in disp}, count=len(disp), errors=errors)
