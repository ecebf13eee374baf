"""The ``equivalent-damping`` analysis plugin: C_i and C_f from the damping of each component.

Declared here; the work, around :mod:`fsi_lab.dsp.equivalent_damping`, is in
:mod:`._equivalent_damping`, imported when the chain first runs it, so that listing the plugins
and checking a profile do not load it.
"""

from __future__ import annotations

from fsi_lab.contract import AnalysisPlugin, Deferred
from fsi_lab.dsp.choices import WEIGHTINGS
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param
from fsi_lab.plugins.analysis.results import (
    Components,
    DampingCoefficients,
    DampingCurves,
    Integrated,
)

METHODS = ("law", "regression", "envelope")


PLUGIN = AnalysisPlugin(
    name="equivalent-damping",
    params=(
        Param("method", "str", "", "law", choices=METHODS,
              help="law (default): the linear + quadratic damping law fitted to every extremum "
                   "of every free decay by hvd's bands decomposition, from the first cycle on, "
                   "compared with viscous and viscous + Coulomb damping (preferred_law); "
                   "regression: the paper's first-order fit of C_q = 2 zeta (mu+M) 2 pi f "
                   "against displacement amplitude (uses the chain's damping curves); "
                   "envelope: the averaged envelope law's closed form fitted to the peaks."),
        Param("weighting", "str", "", "amplitude", choices=WEIGHTINGS,
              help="regression weights: amplitude (W^2, inverse noise variance) or uniform "
                   "(ordinary least squares)."),
        Param("confidence", "float", "", 0.95, minimum=0.5, maximum=0.999,
              help="Level of the confidence intervals (t-distribution)."),
        Param("modal_scale", "float", "", None,
              help="W_n(x_meas) (Eq. 15 normalisation) to express amplitudes in the modal "
                   "coordinate; unset = from the beam model when the run has a specimen, else "
                   "1 (amplitudes as measured)."),
        Param("mode", "int", "", None, minimum=1,
              help="Mode number for the modal conversion; unset = nearest calculated natural "
                   "frequency."),
    ),
    run=Deferred("fsi_lab.plugins.analysis._equivalent_damping:run"),
    uses=(Components, Integrated, DampingCurves),
    provides=DampingCoefficients,
    help="Linear (C_i, kg/(m s)) and quadratic (C_f, kg/m^2) damping per length from the "
         "damping curve by harmonic balance (Eqs. 24-25), with R^2 and 95 % intervals; needs "
         "mu + M from --mass-per-length or the profile's [specimen].",
)


@hookimpl
def fsi_lab_analyses():
    return [PLUGIN]
