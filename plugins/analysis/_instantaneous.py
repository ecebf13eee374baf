"""The work of the ``instantaneous`` analysis plugin (declared in :mod:`.instantaneous`): an
adapter around :mod:`fsi_lab.dsp.instantaneous`."""

from __future__ import annotations

from typing import Any

from fsi_lab.contract import AnalysisContext
from fsi_lab.dsp.instantaneous import instantaneous
from fsi_lab.errors import AnalysisError
from fsi_lab.plugins.analysis._chain import (
    components,
    displacement_components,
    guarded,
    per_component,
)
from fsi_lab.plugins.analysis.results import InstantaneousCurves


def analysed_components(context: AnalysisContext, plugin: str):
    """Displacement components when the channel can give them, else the components as they
    are (a voltage channel is analysed in volts)."""
    try:
        return displacement_components(context, plugin)
    except AnalysisError:
        if context.channel.quantity in ("velocity", "acceleration", "displacement"):
            raise
        return components(context)


def run(context: AnalysisContext, params: dict[str, Any]) -> InstantaneousCurves:
    with guarded("instantaneous", context):
        comps = analysed_components(context, "instantaneous")

    def work(c):
        with guarded("instantaneous", context):
            return instantaneous(c.signal, c.sample_rate, offset=params["offset"],
                                 smooth=params["smooth_points"],
                                 min_amplitude=params["min_amplitude"],
                                 noise_floor=c.noise_floor, frequency_hint=c.frequency)

    done, errors = per_component("instantaneous", context, comps, work)
    return InstantaneousCurves(curves=done, t0s={c.index: c.t0 for c in comps},
                               quantity=comps[0].quantity, unit=comps[0].unit, count=len(comps),
                               errors=errors)
