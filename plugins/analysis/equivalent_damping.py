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
from fsi_lab.presentation import SummaryText
from fsi_lab.summary import coefficient_words, fluid_power_words, interval_words

METHODS = ("law", "regression", "envelope")


PLUGIN = AnalysisPlugin(
    name="equivalent-damping",
    params=(
        Param("method", "str", "", "law", choices=METHODS,
              help="law (default): the linear + quadratic damping law fitted to every extremum "
                   "of every free decay by hvd's bands decomposition, from the first cycle on, "
                   "compared with viscous, viscous + Coulomb and linear + quadratic + Coulomb "
                   "damping (preferred_law); "
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
        Param("highpass_hz", "float", "Hz", None, minimum=1e-3,
              help="Corner of a high-pass in the measuring chain (an AC coupling, a "
                   "decoder's high-pass; Butterworth of order highpass_order): each "
                   "component's amplitudes are divided by its gain at the component's "
                   "frequency, so C_f is multiplied by it; unset = none."),
        Param("highpass_order", "int", "", 1, minimum=1, maximum=8,
              help="Order of the measuring chain's high-pass (1: an RC AC coupling)."),
        Param("lowpass_hz", "float", "Hz", None, minimum=1e-3,
              help="Corner of a low-pass in the measuring chain (a decoder's or a DAQ's "
                   "anti-alias filter; Butterworth of order lowpass_order), taken out as "
                   "highpass_hz is; unset = none."),
        Param("lowpass_order", "int", "", 4, minimum=1, maximum=8,
              help="Order of the measuring chain's low-pass."),
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


@hookimpl
def fsi_lab_default_chain():
    return ["equivalent-damping"]


@hookimpl
def fsi_lab_summary_lines(component):
    """C_i, C_f, R^2, the preferred law and the power of the velocity the fluid term grows
    with (2 for the quadratic law) on the component's line; a coefficient whose interval
    contains 0 is said not to be resolved."""
    if component is None:
        return None
    eq = component.get("equivalent_damping")
    if not isinstance(eq, dict) or eq.get("c_i") is None:
        return SummaryText(keys=("equivalent_damping",))
    text = f": {coefficient_words(eq)}, R^2 = {eq['r2']:.3f}"
    if eq.get("preferred_law"):
        text += f", preferred law: {eq['preferred_law']}"
    if eq.get("fluid_power") is not None:
        # how far the record bears out the quadratic law's square of the velocity
        text += fluid_power_words(eq["fluid_power"], eq.get("fluid_power_ci95"))
    for name in ("c_i", "c_f"):
        bounds = eq.get(f"{name}_ci95")
        if bounds and None not in bounds and bounds[0] <= 0.0 <= bounds[1]:
            text += f"; {name[0].upper()}{name[1:]} is not resolved (its interval contains 0)"
    return SummaryText(keys=("equivalent_damping",), inline=text,
                       lines=_preferred_law_line(eq) + _measured_line(eq) + _chain_line(eq))


def _chain_line(eq: dict) -> tuple[str, ...]:
    """Where the measuring chain's filters were taken out of the amplitudes, by how much."""
    convention = str(eq.get("amplitude_convention", ""))
    _, said, rest = convention.partition("; amplitudes divided by the measuring chain's gain")
    if not said:
        return ()
    return (f"C_f with the amplitudes divided by the measuring chain's gain{rest}; the "
            "backbone's and damping curve's amplitudes are as measured",)


def _measured_line(eq: dict) -> tuple[str, ...]:
    """Where C_f belongs to the displacement measured, not to a mode's coordinate (no beam
    model: ``--mass-per-length``), how it becomes the modal C_f the paper and the modal
    model use (C_i is the same in both)."""
    if not str(eq.get("amplitude_convention", "")).startswith("measured"):
        return ()
    return ("C_f is per the amplitude measured at the sensor (no beam model); the modal C_f "
            "is W_n(x_meas) times it, the mode shape at the sensor (2 at a cantilever's tip): "
            "give the beam (--set specimen.*) or --set "
            "analysis.equivalent-damping.modal_scale=W",)


#: How the summary names each law whose coefficients it prints on a line of their own.
_LAW_WORDS = {"viscous": "viscous law", "coulomb": "viscous + Coulomb law",
              "quadratic_coulomb": "linear + quadratic + Coulomb law"}


def _preferred_law_line(eq: dict) -> tuple[str, ...]:
    """The coefficients of the preferred law when it is not the quadratic one (the numbers
    the record supports, beside the C_i and C_f that assume the quadratic law)."""
    law = (eq.get("laws") or {}).get(eq.get("preferred_law"))
    if eq.get("preferred_law") not in _LAW_WORDS or not isinstance(law, dict) \
            or law.get("c_i") is None:
        return ()
    text = (f"{_LAW_WORDS[eq['preferred_law']]} (preferred): C_i = {law['c_i']:.4g} kg/(m s) "
            f"{interval_words(law.get('c_i_ci95'))}")
    if law.get("c_f") is not None:
        text += f", C_f = {law['c_f']:.4g} kg/m^2 {interval_words(law.get('c_f_ci95'))}"
    if law.get("damping_ratio") is not None:
        bounds = law.get("damping_ratio_ci95")
        text += f", damping ratio {100.0 * law['damping_ratio']:.4g} %"
        if bounds:
            text += f" (95 %: {100.0 * bounds[0]:.4g} to {100.0 * bounds[1]:.4g} %)"
    if law.get("friction_force_per_length") is not None:
        text += (f", friction force = {law['friction_force_per_length']:.4g} N/m "
                 f"{interval_words(law.get('friction_force_per_length_ci95'))}")
    return (text.rstrip(),)
