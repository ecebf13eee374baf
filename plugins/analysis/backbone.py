"""The ``backbone`` analysis plugin: frequency against amplitude, per component.

Declared here; the work, around :mod:`fsi_lab.dsp.backbone`, is in :mod:`._backbone`, imported
when the chain first runs it, so that listing the plugins and checking a profile do not load it.
"""

from __future__ import annotations

from fsi_lab.contract import AnalysisPlugin, Deferred
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param
from fsi_lab.plugins.analysis.instantaneous import DECAY_ONLY, INSTANT_PARAMS
from fsi_lab.plugins.analysis.results import Backbones, Components, Integrated
from fsi_lab.presentation import SummaryText

PLUGIN = AnalysisPlugin(
    name="backbone",
    params=(
        Param("smooth_points", "int", "", 0, minimum=0,
              help="Centred moving average, points each side (the paper uses 5; 0 = none)."),
        *INSTANT_PARAMS,
        DECAY_ONLY,
    ),
    run=Deferred("fsi_lab.plugins.analysis._backbone:run"),
    uses=(Components, Integrated),
    provides=Backbones,
    help="Backbone curves: zero-crossing frequency against displacement amplitude (m) and "
         "against velocity amplitude (m/s), per component; the untrusted record ends are left "
         "out. A component of hvd's bands has its identification's crossings and extrema, "
         "corrected for the band filter's smear (min_amplitude, offset and decay_only apply to "
         "the others).",
)


@hookimpl
def fsi_lab_analyses():
    return [PLUGIN]


@hookimpl
def fsi_lab_default_chain():
    return ["backbone"]


@hookimpl
def fsi_lab_summary_lines(component):
    """The curves are drawn (fsi-lab gui), not written out."""
    return None if component is None else SummaryText(keys=("backbone", "backbone_velocity"))
