"""The work of the ``integrate`` analysis plugin (declared in :mod:`.integrate`): an adapter around
:mod:`fsi_lab.dsp.integrate`."""

from __future__ import annotations

from typing import Any

import numpy as np

from fsi_lab.contract import AnalysisContext, AnalysisResult
from fsi_lab.dsp.components import BandComponents
from fsi_lab.dsp.integrate import integrate
from fsi_lab.errors import AnalysisError
from fsi_lab.plugins.analysis._chain import (
    SI_UNITS,
    ComponentSignals,
    component_quantity,
    components,
    error_entries,
    guarded,
    per_component,
    stack_rows,
    where,
)

_ORDER = {("velocity", "displacement"): 1, ("acceleration", "velocity"): 1,
          ("acceleration", "displacement"): 2}


def run(context: AnalysisContext, params: dict[str, Any]) -> AnalysisResult:
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
            f"target = the channel's own quantity)")
    comps = components(context, order)
    hvd = context.results.get("hvd")
    bands = hvd.values.integrated(order) if order and hvd is not None \
        and isinstance(hvd.values, BandComponents) else None

    def work(c):
        if order == 0:
            return c.signal
        if bands is not None:                  # band by band: no high-pass needed
            return bands.components[c.index]
        with guarded("integrate", context):
            return integrate(c.signal, c.sample_rate, order=order, highpass=params["highpass_hz"])

    done, errors = per_component("integrate", context, comps, work)
    unit = SI_UNITS[target]
    entries = [{"index": k, f"{target}_peak": float(np.max(np.abs(s)))} for k, s in done.items()]
    err_entries, err_attrs = error_entries(errors, "integrate")
    values = ComponentSignals(quantity=target, unit=unit, sample_rate=float(ch.sample_rate),
                              signals=done,
                              edge_masks={c.index: c.edge_mask for c in comps},
                              noise_floors={c.index: c.noise_floor for c in comps},
                              settles={c.index: c.settle for c in comps},
                              t0s={c.index: c.t0 for c in comps},
                              frequencies={c.index: c.frequency for c in comps})
    return AnalysisResult(
        datasets={"signals": stack_rows(done, len(comps))},
        units={"signals": unit},
        attrs={"quantity": target, "order": order, "from_quantity": ch.quantity,
               "start_s": comps[0].t0,
               "highpass_hz": params["highpass_hz"] if params["highpass_hz"] is not None
               else "auto (half the lowest spectral peak)", **err_attrs},
        summary={"components": entries + err_entries}, values=values)
