"""The work of the ``spectrum`` analysis plugin (declared in :mod:`.spectrum`): an adapter around
:mod:`fsi_lab.dsp.spectrum`, on the channel's shared spectrum."""

from __future__ import annotations

from typing import Any

from fsi_lab.contract import AnalysisContext
from fsi_lab.dsp.spectrum import find_peaks_interpolated
from fsi_lab.plugins.analysis._chain import guarded
from fsi_lab.plugins.analysis.results import Spectrum


def run(context: AnalysisContext, params: dict[str, Any]) -> Spectrum:
    with guarded("spectrum", context):
        spectrum = context.spectrum(params["window"])   # computed once for the chain
        f, a = spectrum.frequency, spectrum.amplitude
        peaks = find_peaks_interpolated(f, a, min_relative=params["min_relative"],
                                        max_peaks=params["max_peaks"],
                                        smoothing=params["smoothing"], fmin=f[1])
    return Spectrum(frequency=f, amplitude=a, peaks=peaks, unit=context.channel.unit,
                    window=params["window"])
