"""The ``integrate`` analysis plugin: velocity to displacement, acceleration to velocity.

Declared here; the work, around :mod:`fsi_lab.dsp.integrate`, is in :mod:`._integrate`, imported
when the chain first runs it, so that listing the plugins and checking a profile do not load it.
"""

from __future__ import annotations

from fsi_lab.contract import AnalysisPlugin, Deferred
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param
from fsi_lab.plugins.analysis.results import Components, Integrated
from fsi_lab.presentation import SummaryText

PLUGIN = AnalysisPlugin(
    name="integrate",
    params=(
        Param("target", "str", "", "displacement", choices=("displacement", "velocity"),
              help="Quantity wanted: displacement (from velocity or acceleration) or velocity "
                   "(from acceleration)."),
        Param("highpass_hz", "float", "Hz", None, minimum=0.0, exclusive_minimum=True,
              help="High-pass corner: content below half of it is removed; unset = half the "
                   "lowest spectral peak of the record."),
    ),
    run=Deferred("fsi_lab.plugins.analysis._integrate:run"),
    uses=(Components,),
    provides=Integrated,
    help="Integrates velocity to displacement (or acceleration to velocity/displacement) in "
         "the frequency domain with the zero-frequency and drift content removed, per HVD "
         "component when hvd ran earlier.",
)


@hookimpl
def fsi_lab_analyses():
    return [PLUGIN]


@hookimpl
def fsi_lab_default_chain():
    return ["integrate"]


@hookimpl
def fsi_lab_summary_lines(component):
    """The peaks of the integrated signals stay in the JSON summary."""
    if component is None:
        return None
    return SummaryText(keys=("displacement_peak", "velocity_peak", "integrate"))
