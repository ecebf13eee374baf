"""The ``spectrum`` analysis plugin: the amplitude spectrum of a channel and its peaks.

Declared here; the work, around :mod:`fsi_lab.dsp.spectrum`, is in :mod:`._spectrum`, imported
when the chain first runs it, so that listing the plugins and checking a profile do not load it.
"""

from __future__ import annotations

from fsi_lab.contract import AnalysisPlugin, Deferred
from fsi_lab.dsp.choices import WINDOWS
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param
from fsi_lab.plugins.analysis.results import Spectrum
from fsi_lab.presentation import SummaryText

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
    run=Deferred("fsi_lab.plugins.analysis._spectrum:run"),
    provides=Spectrum,
    help="Single-sided amplitude spectrum of the channel with interpolated peak frequencies "
         "(the paper's Figs. 5, 9, 11).",
)


@hookimpl
def fsi_lab_analyses():
    return [PLUGIN]


@hookimpl
def fsi_lab_default_chain():
    return ["spectrum"]


@hookimpl
def fsi_lab_summary_lines(summary, component):
    """The channel's peaks on its line."""
    if component is not None:
        return None
    peaks = [p for p in summary.get("spectrum_peaks_hz") or [] if p is not None]
    return SummaryText(keys=("spectrum_peaks_hz", "spectrum_peak_amplitudes",
                             "spectrum_peak_amplitude_unit"),
                       inline=f": spectrum peaks {', '.join(f'{p:.2f}' for p in peaks[:6])} Hz"
                       if peaks else "")
