"""The work of the ``instantaneous`` analysis plugin (declared in :mod:`.instantaneous`): an
adapter around :mod:`fsi_lab.dsp.instantaneous`."""

from __future__ import annotations

from typing import Any

import numpy as np

from fsi_lab.contract import AnalysisContext, AnalysisResult
from fsi_lab.dsp.instantaneous import instantaneous
from fsi_lab.errors import AnalysisError
from fsi_lab.plugins.analysis._chain import (
    components,
    displacement_components,
    error_entries,
    guarded,
    per_component,
    stack_rows,
)


def analysed_components(context: AnalysisContext, plugin: str):
    """Displacement components when the channel can give them, else the components as they
    are (a voltage channel is analysed in volts)."""
    try:
        return displacement_components(context, plugin)
    except AnalysisError:
        if context.channel.quantity in ("velocity", "acceleration", "displacement"):
            raise
        return components(context)


def run(context: AnalysisContext, params: dict[str, Any]) -> AnalysisResult:
    with guarded("instantaneous", context):
        comps = analysed_components(context, "instantaneous")

    def work(c):
        with guarded("instantaneous", context):
            return instantaneous(c.signal, c.sample_rate, offset=params["offset"],
                                 smooth=params["smooth_points"],
                                 min_amplitude=params["min_amplitude"],
                                 noise_floor=c.noise_floor, frequency_hint=c.frequency)

    done, errors = per_component("instantaneous", context, comps, work)
    unit = comps[0].unit
    count = len(comps)
    # (the amplitude^2-weighted mean leans on the largest cycles; the headline natural
    # frequency is hvd's small-amplitude limit)
    entries = [{"index": k, "instantaneous": {
        "weighted_mean_frequency_hz": float(np.sum(r.amplitude ** 2 * r.frequency)
                                            / np.sum(r.amplitude ** 2))}}
               for k, r in done.items()]
    err_entries, err_attrs = error_entries(errors, "instantaneous")
    t0 = {c.index: c.t0 for c in comps}
    rows = {name: stack_rows({k: getattr(r, name) + (t0[k] if name.endswith("times") else 0.0)
                              for k, r in done.items()}, count)
            for name in ("frequency_times", "frequency", "amplitude", "peak_times",
                         "peak_values")}
    return AnalysisResult(
        datasets=rows,
        units={"frequency_times": "s", "frequency": "Hz", "amplitude": unit,
               "peak_times": "s", "peak_values": unit},
        attrs={"quantity": comps[0].quantity,
               "offsets": [float(done[k].offset) if k in done else float("nan")
                           for k in range(count)],
               "rows": "one row per component, padded with NaN", **err_attrs},
        summary={"components": entries + err_entries}, values=done)
