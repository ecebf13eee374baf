"""The ``hvd`` analysis plugin: the decomposition of a channel into one component per mode.

Two methods: ``bands`` (default) adapts :mod:`fsi_lab.dsp.identify` and
:mod:`fsi_lab.dsp.components`; ``hvd`` adapts :mod:`fsi_lab.dsp.hvd` (the paper's method).
Declared here; the work is in :mod:`._hvd`, imported when the chain first runs it, so that
listing the plugins and checking a profile do not load it.
"""

from __future__ import annotations

from fsi_lab.contract import AnalysisPlugin, Deferred
from fsi_lab.dsp.choices import PADDINGS
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param
from fsi_lab.plugins.analysis.results import Components
from fsi_lab.presentation import SummaryText

METHODS = ("bands", "hvd")


PLUGIN = AnalysisPlugin(
    name="hvd",
    params=(
        Param("method", "str", "", "bands", choices=METHODS,
              help="bands (default): one component per mode, a zero-phase band around each "
                   "(they add up to the record, so a component never switches modes), each "
                   "free decay filtered on its own from its first cycle, with the "
                   "identification of every mode (natural frequency, damping laws); hvd: "
                   "Feldman's Hilbert Vibration Decomposition as in the paper (its filters "
                   "smear the first 2 / cutoff seconds of each decay)."),
        Param("components", "int", "", None, minimum=1, maximum=64,
              help="Number of components (the largest modes); unset or 'auto' = one per mode "
                   "with a free decay above the noise (hvd: per significant spectral peak)."),
        Param("cutoff_hz", "float", "Hz", None, minimum=0.0, exclusive_minimum=True,
              help="Low-pass cut-off of the frequency and demodulation filters; unset = "
                   "automatic (half the smaller of each component's frequency and its distance "
                   "to the nearest other spectral peak)."),
        Param("padding", "str", "", "predict", choices=PADDINGS,
              help="Record-end extension: linear prediction (default) or mirror image."),
        Param("start_s", "float", "s", None, minimum=0.0,
              help="Decompose from this time on: the free decay after the excitation (a forced "
                   "start disturbs its first cycles); unset = from the largest sample of the "
                   "first free decay (automatic: the record's largest sample when it holds one "
                   "decay, or with method 'bands' the end of a forced response that holds it, "
                   "which a note names), 0 = the whole record."),
        Param("band_hz", "floats", "Hz", None, minimum=0.0, exclusive_minimum=True,
              help="[low, high]: decompose the record band-passed to this band (gain 1 from "
                   "low to high, 0 below low/2 and above 1.5 high, zero phase), so one mode is "
                   "analysed on its own - e.g. when two modes' envelopes cross and a component "
                   "switches between them; 0 < low < high < Nyquist; unset = the whole record."),
        Param("relative", "str", "", "auto", choices=("auto", "yes", "no"),
              help="Subtract the base motion (integrated reference acceleration) first, so the "
                   "components are motion relative to the clamp as in the modal model; auto = "
                   "when the chain has a base acceleration reference."),
    ),
    run=Deferred("fsi_lab.plugins.analysis._hvd:run"),
    provides=Components,
    help="Decomposition into one component per mode (relative to the base when a reference "
         "acceleration is given), by decreasing amplitude: mode bands with the identification "
         "of each mode (default), or Feldman's Hilbert Vibration Decomposition. Later "
         "analyses of the chain work per component.",
)


@hookimpl
def fsi_lab_analyses():
    return [PLUGIN]


@hookimpl
def fsi_lab_default_chain():
    return ["hvd"]


@hookimpl
def fsi_lab_summary_lines(component):
    """The core shows each component's frequency; the identification's details stay in the
    JSON summary."""
    if component is None:
        return None
    return SummaryText(keys=("damped_frequency_hz", "spectral_peak_hz", "band_hz", "extrema",
                             "decays", "hvd_peak_envelope", "cutoff_hz", "hvd"))
