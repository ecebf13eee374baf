"""The ``modal-model`` analysis plugin: the beam model driven by the measured base acceleration,
processed like the measurement and compared with it (the paper's Figs. 20 and 21).

Declared here; the method is described and done in :mod:`._modal_model`, imported when the
chain first runs it, so that listing the plugins and checking a profile do not load it.
"""

from __future__ import annotations

from fsi_lab.beam import PROJECTIONS
from fsi_lab.contract import AnalysisPlugin, Deferred
from fsi_lab.dsp.choices import DAMPING_METHODS
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param
from fsi_lab.plugins.analysis.results import (
    Components,
    DampingCoefficients,
    Integrated,
    ModalComparison,
)
from fsi_lab.presentation import SummaryText

PLUGIN_NAME = "modal-model"


PLUGIN = AnalysisPlugin(
    name=PLUGIN_NAME,
    params=(
        Param("c_i", "float", "kg/(m s)", None, minimum=0.0,
              help="Linear damping per length C_i for the model; unset = identified by "
                   "equivalent-damping earlier in the chain."),
        Param("c_f", "float", "kg/m^2", None, minimum=0.0,
              help="Quadratic fluid damping per length C_f for the model; unset = identified "
                   "by equivalent-damping earlier in the chain."),
        Param("mode", "int", "", None, minimum=1,
              help="Beam mode whose identified C_i and C_f are used (the component nearest its "
                   "natural frequency); unset = the largest component with C_i, C_f >= 0."),
        Param("modes", "int", "", 4, minimum=1, maximum=50,
              help="Number of beam modes kept in the model."),
        Param("projection", "str", "", "per-mode", choices=PROJECTIONS,
              help="Quadratic damping per mode (the paper's Eq. 20) or projected consistently "
                   "(Galerkin, couples the modes)."),
        Param("damping_method", "str", "", "decrement", choices=DAMPING_METHODS,
              help="Damping-curve estimator applied to measurement and model alike."),
        Param("smooth_points", "int", "", 0, minimum=0,
              help="Centred moving average of backbone and damping curves, points each side "
                   "(paper: 5; 0 = none)."),
    ),
    run=Deferred("fsi_lab.plugins.analysis._modal_model:run"),
    requires=(Components,),
    uses=(Integrated, DampingCoefficients),
    provides=ModalComparison,
    help="Runs the beam model (Eq. 20) with the measured base acceleration and the identified "
         "(or given) C_i and C_f, processes its output like the measurement (HVD, zero "
         "crossings, backbone, damping) and reports measured vs model with error figures "
         "(the paper's Figs. 20-21). Needs [specimen] and the [analysis] reference channel.",
)


@hookimpl
def fsi_lab_analyses():
    return [PLUGIN]


@hookimpl
def fsi_lab_summary_lines(summary, component):
    """Under each component, how the model compares with it. The model is one beam with one
    C_i and C_f for every component, taken from where ``c_source`` says (a component's own fit
    only for that component)."""
    if component is None:
        return SummaryText(keys=("modal_model",))
    model = component.get("modal_model")
    if not isinstance(model, dict) or model.get("envelope_rms_error") is None:
        return SummaryText(keys=("modal_model",))
    source = (summary.get("modal_model") or {}).get("c_source")
    origin = f" from {source}" if isinstance(source, str) and source else ""
    error = model.get("frequency_error_pct")
    # (None when every compared sample's instantaneous frequency was a glitch)
    frequency = f"{error:+.2f} %" if isinstance(error, (int, float)) else "not measured"
    return SummaryText(keys=("modal_model",), lines=(
        f"modal model (C_i = {model['c_i']:.4g} kg/(m s), C_f = {model['c_f']:.4g} kg/m^2"
        f"{origin}) vs "
        f"measurement: envelope RMS error {100 * model['envelope_rms_error']:.1f} %, "
        f"frequency error {frequency}",))
