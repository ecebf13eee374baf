"""The work of the ``spectrum`` analysis plugin (declared in :mod:`.spectrum`): an adapter around
:mod:`fsi_lab.dsp.spectrum`."""

from __future__ import annotations

from typing import Any

import numpy as np

from fsi_lab.contract import AnalysisContext, AnalysisResult
from fsi_lab.dsp.spectrum import amplitude_spectrum, find_peaks_interpolated
from fsi_lab.plugins.analysis._chain import guarded, jsonable


def run(context: AnalysisContext, params: dict[str, Any]) -> AnalysisResult:
    ch = context.channel
    with guarded("spectrum", context):
        f, a = amplitude_spectrum(ch.data, ch.sample_rate, window=params["window"])
        peaks = find_peaks_interpolated(f, a, min_relative=params["min_relative"],
                                        max_peaks=params["max_peaks"],
                                        smoothing=params["smoothing"], fmin=f[1])
    order = np.argsort(peaks.frequencies)
    pf = peaks.frequencies[order]
    pa = peaks.amplitudes[order]
    return AnalysisResult(
        datasets={"frequency": f, "amplitude": a, "peak_frequencies": pf,
                  "peak_amplitudes": pa},
        units={"frequency": "Hz", "amplitude": ch.unit, "peak_frequencies": "Hz",
               "peak_amplitudes": ch.unit},
        attrs={"window": params["window"], "resolution_hz": float(f[1] - f[0])},
        summary={"spectrum_peaks_hz": jsonable(pf), "spectrum_peak_amplitudes": jsonable(pa)},
        values=peaks)
