"""The work of the ``integrate`` analysis plugin (declared in :mod:`.integrate`): an adapter around
:mod:`fsi_lab.dsp.integrate`."""

from __future__ import annotations

from typing import Any

from fsi_lab.contract import AnalysisContext
from fsi_lab.dsp.components import BandComponents
from fsi_lab.dsp.integrate import integrate
from fsi_lab.errors import AnalysisError
from fsi_lab.plugins.analysis._chain import (
    SI_UNITS,
    component_quantity,
    components,
    guarded,
    per_component,
    where,
)
from fsi_lab.plugins.analysis.results import Components, Integrated
from fsi_lab.units import voltage_hint

_ORDER = {("velocity", "displacement"): 1, ("acceleration", "velocity"): 1,
          ("acceleration", "displacement"): 2}


def run(context: AnalysisContext, params: dict[str, Any]) -> Integrated:
    ch = context.channel
    target = params["target"]
    quantity = component_quantity(context)
    if quantity == target:
        order = 0                                     # nothing to do: passed through
    elif (quantity, target) in _ORDER:
        order = _ORDER[(quantity, target)]
    else:
        raise AnalysisError(
            f"{where('integrate', context)}: cannot integrate a {ch.quantity!r} channel "
            f"({ch.unit}) to {target}; expected a velocity or acceleration channel (or "
            f"target = the channel's own quantity)" + voltage_hint(ch.quantity))
    comps = components(context, order)
    found = context.result(Components)
    bands = found.decomposition.integrated(order) if order and found is not None \
        and isinstance(found.decomposition, BandComponents) else None

    def work(c):
        if order == 0:
            return c.signal
        if bands is not None:                  # band by band: no high-pass needed
            return bands.components[c.index]
        with guarded("integrate", context):
            return integrate(c.signal, c.sample_rate, order=order, highpass=params["highpass_hz"])

    done, errors = per_component("integrate", context, comps, work)
    return Integrated(quantity=target, unit=SI_UNITS[target], sample_rate=float(ch.sample_rate),
                      signals=done, edge_masks={c.index: c.edge_mask for c in comps},
                      noise_floors={c.index: c.noise_floor for c in comps},
                      settles={c.index: c.settle for c in comps},
                      t0s={c.index: c.t0 for c in comps},
                      frequencies={c.index: c.frequency for c in comps},
                      order=order, from_quantity=ch.quantity, highpass_hz=params["highpass_hz"],
                      count=len(comps), start_s=comps[0].t0, errors=errors)
