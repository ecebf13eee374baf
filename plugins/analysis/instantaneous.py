"""The ``instantaneous`` analysis plugin: zero-crossing frequency and extremum amplitude.

Declared here, with the parameters the plugins that measure extrema share (backbone, damping);
the work, around :mod:`fsi_lab.dsp.instantaneous`, is in :mod:`._instantaneous`, imported when
the chain first runs it, so that listing the plugins and checking a profile do not load it.
"""

from __future__ import annotations

from fsi_lab.contract import AnalysisPlugin, Deferred
from fsi_lab.dsp.choices import OFFSETS
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param
from fsi_lab.plugins.analysis.results import Components, InstantaneousCurves, Integrated
from fsi_lab.presentation import SummaryText

#: Parameters shared by the plugins that measure extrema (backbone, damping).
INSTANT_PARAMS = (
    Param("min_amplitude", "float", "", None, minimum=0.0, maximum=1.0,
          help="Drop cycles below this fraction of the largest amplitude; unset = below 10x "
               "the noise RMS estimated from the spectrum."),
    Param("offset", "str", "", "cycles", choices=OFFSETS,
          help="Offset removed before the zero crossings: from successive extrema (cycles), "
               "the mean, or none."),
)


#: Shared by backbone and damping: leave out the points before the largest amplitude.
DECAY_ONLY = Param("decay_only", "bool", "", True,
                   help="Use only the free decay: points from the largest amplitude on (before "
                        "it the excitation still feeds the mode).")


PLUGIN = AnalysisPlugin(
    name="instantaneous",
    params=(
        Param("smooth_points", "int", "", 0, minimum=0,
              help="Centred moving average, points each side (the paper uses 5; 0 = none)."),
        *INSTANT_PARAMS,
    ),
    run=Deferred("fsi_lab.plugins.analysis._instantaneous:run"),
    uses=(Components, Integrated),
    provides=InstantaneousCurves,
    help="Instantaneous frequency f = 1/(t[i+1] - t[i-1]) from interpolated zero crossings "
         "(offset removed first) and instantaneous amplitude at refined extrema, per component, "
         "on the displacement when the channel gives one.",
)


@hookimpl
def fsi_lab_analyses():
    return [PLUGIN]


@hookimpl
def fsi_lab_default_chain():
    return ["instantaneous"]


@hookimpl
def fsi_lab_summary_lines(component):
    """The weighted mean frequency stays in the JSON summary."""
    return None if component is None else SummaryText(keys=("instantaneous",))
