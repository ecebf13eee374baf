"""The ``damping`` analysis plugin: damping ratio against amplitude, per component.

Declared here; the work, around :mod:`fsi_lab.dsp.damping`, is in :mod:`._damping`, imported
when the chain first runs it, so that listing the plugins and checking a profile do not load it.
"""

from __future__ import annotations

from fsi_lab.contract import AnalysisPlugin, Deferred
from fsi_lab.dsp.choices import DAMPING_METHODS as METHODS
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param
from fsi_lab.plugins.analysis.instantaneous import DECAY_ONLY, INSTANT_PARAMS
from fsi_lab.plugins.analysis.results import Components, DampingCurves, Integrated
from fsi_lab.presentation import SummaryText

PLUGIN = AnalysisPlugin(
    name="damping",
    params=(
        Param("method", "str", "", "decrement", choices=METHODS,
              help="decrement (successive-peak log decrement, unbiased), envelope-fit (linear + "
                   "quadratic envelope law), eq5 (paper, windowed regression), eq7 (paper, "
                   "cubic in t; biased on long decays)."),
        Param("span", "int", "", 2, minimum=1,
              help="Extrema per decrement (2 = one full period)."),
        Param("window", "int", "", 6, minimum=3, help="Extrema per regression window (eq5)."),
        Param("smooth_points", "int", "", 0, minimum=0,
              help="Centred moving average of the curve, points each side (paper: 5)."),
        *INSTANT_PARAMS,
        DECAY_ONLY,
    ),
    run=Deferred("fsi_lab.plugins.analysis._damping:run"),
    uses=(Components, Integrated),
    provides=DampingCurves,
    help="Damping ratio against displacement amplitude (m) per component, from the refined "
         "extrema; the untrusted record ends are left out. A component of hvd's bands has its "
         "identification's extrema, corrected for the band filter's smear (min_amplitude, "
         "offset and decay_only apply to the others).",
)


@hookimpl
def fsi_lab_analyses():
    return [PLUGIN]


@hookimpl
def fsi_lab_default_chain():
    return ["damping"]


@hookimpl
def fsi_lab_summary_lines(component):
    """The curves are drawn (fsi-lab gui), not written out."""
    return None if component is None else SummaryText(keys=("damping",))
