"""The modal model figure: its signal, envelopes, backbone and damping against the measurement."""

from __future__ import annotations

from typing import Iterator

import numpy as np
from PySide6.QtCore import Qt

from fsi_lab.gui.analysis.datasets import channel_t0, finite_pairs, per_component
from fsi_lab.gui.analysis.plotting import COLOURS, active_span, draw_line, draw_points, robust_range
from fsi_lab.gui.analysis.view import View
from fsi_lab.gui.results import RunResults
from fsi_lab.plugins.analysis.views.labels import measured_amplitude


class ModalModelView(View):
    """The modal model (Eq. 20 with the identified C_i and C_f, driven by the measured base
    motion) against the measurement: the decomposed signals, envelopes, backbone and damping."""

    title = "Modal model"
    plugins = ("modal-model",)
    cells = ((0, 0), (1, 0), (2, 0), (2, 1))

    def draw(self, results: RunResults, channel: str) -> Iterator[None]:
        model = results.result(channel, "modal-model")
        if model is None or not model.ok or not model.datasets:
            return False
        data = results.channels.get(channel)
        rate = float(model.scalar("sample_rate") or (data.sample_rate if data else 1.0))
        t0 = channel_t0(results, channel) + float(model.scalar("start_s") or 0.0)
        unit = data.unit if data is not None else None
        drawn = False
        # modal-model names its time series velocity_* on a velocity channel and signal_* on
        # any other (they are in the channel's quantity)
        measured = model.get("velocity_measured", "signal_measured")
        simulated = model.get("velocity_model", "signal_model")
        top = None
        if measured is not None and simulated is not None:
            top = self.add_plot(0, 0, channel, "time", unit, "s", colspan=2)
            yield
            draw_line(top, t0 + np.arange(np.size(measured)) / rate, measured, "#9e9e9e",
                      "measured (decomposed record)", 1.0)
            yield
            draw_line(top, t0 + np.arange(np.size(simulated)) / rate, simulated, "#000000",
                      "modal model", 1.2, Qt.PenStyle.DashLine)
            yield
            drawn = True
        times = model.get("envelope_time")
        if times is not None:
            env = self.add_plot(1, 0, "envelope", "time", unit, "s", colspan=2)
            yield
            if top is not None:
                env.setXLink(top)
            t_env = channel_t0(results, channel) + np.asarray(times, float)
            for k, (m, s_) in enumerate(zip(per_component(model, "envelope_measured"),
                                            per_component(model, "envelope_model"))):
                colour = COLOURS[k % len(COLOURS)]
                if m.size == t_env.size:
                    draw_line(env, t_env, m, colour, f"measured {k}", 1.4)
                    yield
                if s_.size == t_env.size:
                    draw_line(env, t_env, s_, colour, f"model {k}", 1.4, Qt.PenStyle.DashLine)
                    yield
                if k == 0 and m.size == t_env.size:
                    span = active_span(t_env, m)
                    if span is not None:
                        env.setXRange(*span, padding=0)
            drawn = True
        for col, (x_name, y_name, label, units) in enumerate((
                ("backbone_amplitude", "backbone_frequency", "frequency", "Hz"),
                ("damping_amplitude", "damping_zeta", "damping ratio ζ", None))):
            meas = finite_pairs(zip(per_component(model, f"{x_name}_measured"),
                                    per_component(model, f"{y_name}_measured")))
            sim = finite_pairs(zip(per_component(model, f"{x_name}_model"),
                                   per_component(model, f"{y_name}_model")))
            if not meas and not sim:
                continue
            plot = self.add_plot(2, col, label, measured_amplitude(results), units, "m")
            yield
            for k, (a, b) in enumerate(meas):
                draw_points(plot, a, b, COLOURS[k % len(COLOURS)], f"measured {k}", 4)
                yield
            for k, (a, b) in enumerate(sim):
                order = np.argsort(a)
                draw_line(plot, a[order], b[order], COLOURS[k % len(COLOURS)], f"model {k}", 1.6,
                          Qt.PenStyle.DashLine)
                yield
            robust_range(plot, [b for _, b in meas + sim])
            drawn = True
        if drawn:
            c_i, c_f = model.scalar("c_i"), model.scalar("c_f")
            source = model.scalar("c_source")
            coefficients = (f" with C_i = {c_i:.4g} kg/(m s), C_f = {c_f:.4g} kg/m²"
                            if isinstance(c_i, (int, float)) and isinstance(c_f, (int, float))
                            else "")
            self.set_note(f"modal model (Eq. 20){coefficients}"
                          + (f" ({source})" if isinstance(source, str) else "")
                          + f" against the measurement of {channel}; dashed: model")
        return drawn
