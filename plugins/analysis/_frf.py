"""The work of the ``frf`` analysis plugin (declared in :mod:`.frf`): an adapter around
:mod:`fsi_lab.dsp.frf`; channels read from the run file are read a chunk at a time
(:func:`fsi_lab.sources.samples_of`), never held whole."""

from __future__ import annotations

from typing import Any

import numpy as np

from fsi_lab.contract import AnalysisContext, AnalysisResult
from fsi_lab.dsp.frf import frf
from fsi_lab.errors import AnalysisError
from fsi_lab.plugins.analysis._chain import guarded, jsonable, where
from fsi_lab.sources import samples_of


def run(context: AnalysisContext, params: dict[str, Any]) -> AnalysisResult:
    ch = context.channel
    ref_name = context.reference
    if not ref_name:
        raise AnalysisError(f"{where('frf', context)}: needs a reference channel (the base "
                            "acceleration): set reference = NAME in the profile's [analysis]")
    if ref_name not in context.channels:
        raise AnalysisError(f"{where('frf', context)}: reference channel {ref_name!r} is not in "
                            f"the run; channels are {', '.join(context.channels) or 'none'}")
    if ref_name == ch.name:
        raise AnalysisError(f"{where('frf', context)}: the channel is the reference itself; "
                            "analyse the response channel")
    ref = context.channels[ref_name]
    if abs(float(ref.sample_rate) - float(ch.sample_rate)) > 1e-9 * float(ch.sample_rate):
        raise AnalysisError(f"{where('frf', context)}: reference sampled at {ref.sample_rate:g} "
                            f"Hz, response at {ch.sample_rate:g} Hz; expected the same rate")
    with guarded("frf", context):
        res = frf(samples_of(ref), samples_of(ch), ch.sample_rate, segment=params["segment"],
                  overlap=params["overlap"], window=params["window"],
                  min_relative=params["min_relative"], max_peaks=params["max_peaks"],
                  min_coherence=params["min_coherence"])
    unit = f"{ch.unit}/({ref.unit})"
    return AnalysisResult(
        datasets={"frequency": res.frequency, "h1_magnitude": np.abs(res.h1),
                  "h1_phase": np.angle(res.h1), "h2_magnitude": np.abs(res.h2),
                  "h2_phase": np.angle(res.h2), "coherence": res.coherence,
                  "natural_frequencies": res.natural_frequencies,
                  "natural_frequency_ci95": res.natural_frequency_ci95,
                  "damping_ratios": res.damping_ratios,
                  "damping_ratio_ci95": res.damping_ratio_ci95,
                  "half_power_damping_ratios": res.half_power_damping_ratios,
                  "peak_frequencies": res.peak_frequencies},
        units={"frequency": "Hz", "h1_magnitude": unit, "h1_phase": "rad",
               "h2_magnitude": unit, "h2_phase": "rad", "coherence": "",
               "natural_frequencies": "Hz", "natural_frequency_ci95": "Hz",
               "damping_ratios": "", "damping_ratio_ci95": "", "half_power_damping_ratios": "",
               "peak_frequencies": "Hz"},
        attrs={"reference": ref_name, "resolution_hz": res.resolution,
               "window": params["window"]},
        summary={"frf": {"reference": ref_name,
                         "natural_frequencies_hz": jsonable(res.natural_frequencies),
                         "natural_frequency_ci95_hz": jsonable(res.natural_frequency_ci95),
                         "damping_ratios": jsonable(res.damping_ratios),
                         "damping_ratio_ci95": jsonable(res.damping_ratio_ci95),
                         "half_power_damping_ratios": jsonable(res.half_power_damping_ratios),
                         "peak_frequencies_hz": jsonable(res.peak_frequencies),
                         "resolution_hz": res.resolution,
                         "warnings": list(res.warnings), "notes": list(res.notes)}},
        values=res)
