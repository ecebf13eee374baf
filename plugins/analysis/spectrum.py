"""The ``spectrum`` analysis plugin: an adapter around :mod:`fsi_lab.dsp.spectrum`."""

from __future__ import annotations

from typing import Any

import numpy as np

from fsi_lab.contract import AnalysisContext, AnalysisPlugin, AnalysisResult
from fsi_lab.dsp.spectrum import WINDOWS, amplitude_spectrum, find_peaks_interpolated
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param
from fsi_lab.plugins.analysis._chain import guarded, jsonable


def _run(context: AnalysisContext, params: dict[str, Any]) -> AnalysisResult:
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


PLUGIN = AnalysisPlugin(
    name="spectrum",
    params=(
        Param("window", "str", "", "decay", choices=WINDOWS,
              help="Window: decay (default: flat, then half-Hann - keeps the early part of a "
                   "free decay and fast-decaying modes), hann (steady or random records), "
                   "blackmanharris, flattop (accurate amplitudes), boxcar."),
        Param("min_relative", "float", "", 0.02, minimum=0.0, maximum=1.0,
              exclusive_minimum=True,
              help="Report peaks whose prominence is at least this fraction of the largest."),
        Param("max_peaks", "int", "", 8, minimum=1, help="Report at most this many peaks."),
        Param("smoothing", "float", "", 0.0, minimum=0.0, maximum=0.5,
              help="Relative half-width of a spectral RMS average before the peak search "
                   "(0.02 = +-2 %), for noisy or chirped spectra."),
    ),
    run=_run,
    help="Single-sided amplitude spectrum of the channel with interpolated peak frequencies "
         "(the paper's Figs. 5, 9, 11).",
)


@hookimpl
def fsi_lab_analyses():
    return [PLUGIN]
