"""The work of the ``backbone`` analysis plugin (declared in :mod:`.backbone`): an adapter around
:mod:`fsi_lab.dsp.backbone`."""

from __future__ import annotations

from typing import Any

import numpy as np

from fsi_lab.contract import AnalysisContext
from fsi_lab.dsp._signal import fail
from fsi_lab.dsp.backbone import Backbone
from fsi_lab.dsp.decays import FreeDecays, smooth_per_decay
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
    velocity_components,
)
from fsi_lab.plugins.analysis.results import Backbones


def decay_backbone(inst: Instantaneous, c: Component, smooth: int = 0,
                   decay_only: bool = True) -> Backbone:
    """Backbone of one component's :class:`.instantaneous.Instantaneous` analysis (made with
    ``smooth = 0``) without the points in untrusted record ends (the HVD edge mask and one
    period at each end) and, with ``decay_only``, outside its free decays; ``smooth`` is the
    moving average (points each side) applied within each decay. Times are from the channel's
    first sample."""
    freq, amp = inst.frequency, inst.amplitude
    times = inst.frequency_times
    if smooth:
        period = 1.0 / float(np.median(freq))
        _, split = decay_labels(times, c, period, amp, decay_only)
        regions = split.regions(times) if split is not None else np.zeros(times.size)
        freq = smooth_per_decay(freq, regions, smooth)
        amp = np.exp(smooth_per_decay(np.log(np.maximum(amp, 1e-300)), regions, smooth))
    period = 1.0 / float(np.median(freq))
    labels, decays = decay_labels(times, c, period, amp, decay_only)
    return _backbone_of(times, amp, freq, labels, decays, c.t0)


def identified_backbone(mode: ModeIdentification, c: Component, smooth: int = 0,
                        velocity: bool = False) -> Backbone:
    """Backbone of a component of the ``bands`` decomposition as its mode's identification
    measured it (:attr:`fsi_lab.dsp.identify.ModeIdentification.backbone`): the band's
    crossings and extrema in each free decay (:func:`._chain.identified_decays`), corrected for
    the band filter's smear of the first cycles, from the first, with displacement amplitudes
    (m), or with ``velocity`` velocity amplitudes (m/s, for a mode identified on a velocity).
    Read off the band signal itself, the largest cycles of a Duffing decay lay up to 1 % off
    harmonic balance. ``smooth`` as for :func:`decay_backbone`."""
    bb = mode.backbone
    freq = bb.frequency
    amp = bb.amplitude * (2.0 * np.pi * freq) if velocity else bb.amplitude
    labels, decays = identified_decays(mode, c, bb.times, amp)
    if smooth:
        regions = decays.regions(bb.times)
        freq = smooth_per_decay(freq, regions, smooth)
        amp = np.exp(smooth_per_decay(np.log(np.maximum(amp, 1e-300)), regions, smooth))
    return _backbone_of(bb.times, amp, freq, labels, decays, c.t0)


def _backbone_of(times: np.ndarray, amp: np.ndarray, freq: np.ndarray, labels: np.ndarray,
                 decays: FreeDecays | None, t0: float) -> Backbone:
    """The backbone of the points with a decay (``labels >= 0``), times moved by ``t0`` (s)."""
    keep = labels >= 0
    if keep.sum() < 2:
        raise fail("backbone", f"only {int(keep.sum())} period(s) away from the untrusted "
                               "record ends and inside a free decay; need at least 2 - a "
                               "longer record")
    return Backbone(times[keep] + t0, amp[keep], freq[keep], labels[keep], decays)


def trusted_backbone(c: Component, params: dict[str, Any], plugin: str,
                     context: AnalysisContext, velocity: bool = False) -> Backbone:
    """Backbone of one component as the ``backbone`` plugin gives it: its mode's when the
    identification has it (:func:`._chain.identified_mode`; :func:`identified_backbone`,
    velocity amplitudes with ``velocity``), otherwise the zero crossings and extrema of the
    component (:func:`decay_backbone`)."""
    decay_only = params.get("decay_only", True)
    mode = identified_mode(context, c, params)
    if mode is not None and (not velocity or mode.quantity == "velocity"):
        with guarded(plugin, context):
            return identified_backbone(mode, c, params["smooth_points"], velocity)
    with guarded(plugin, context):
        inst = instantaneous(c.signal, c.sample_rate, offset=params["offset"], smooth=0,
                             min_amplitude=params["min_amplitude"], noise_floor=c.noise_floor,
                             frequency_hint=c.frequency)
        return decay_backbone(inst, c, params["smooth_points"], decay_only)


def run(context: AnalysisContext, params: dict[str, Any]) -> Backbones:
    with guarded("backbone", context):
        disp = displacement_components(context, "backbone")
    done, errors = per_component("backbone", context, disp,
                                 lambda c: trusted_backbone(c, params, "backbone", context))
    vel = velocity_components(context)
    vdone: dict[int, Backbone] = {}
    if vel is not None:
        for c in vel:
            try:
                vdone[c.index] = trusted_backbone(c, params, "backbone", context,
                                                  velocity=True)
            except Exception:  # noqa: BLE001 - the velocity backbone is optional
                pass
    return Backbones(displacement=done, velocity=vdone, t0s={c.index: c.t0 for c in disp},
                     count=len(disp), errors=errors)
