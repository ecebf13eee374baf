"""Figures against amplitude: backbone and damping ratio vs displacement and velocity amplitude."""

from __future__ import annotations

from typing import Iterator

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QWidget

from fsi_lab.gui.analysis.datasets import finite_pairs, per_component, summary_series
from fsi_lab.gui.analysis.plotting import (
    COLOURS,
    MAX_COMPONENTS_DRAWN,
    draw_line,
    draw_points,
    robust_range,
)
from fsi_lab.gui.analysis.view import View
from fsi_lab.gui.results import RunResults
from fsi_lab.plugins.analysis.views.names import (
    DISPLACEMENT_AMPLITUDE,
    FREQUENCY,
    VELOCITY_AMPLITUDE,
    VELOCITY_FREQUENCY,
    ZETA,
)


class _AmplitudeView(View):
    """Two plots of a quantity against displacement and velocity amplitude."""

    #: the dataset drawn against displacement amplitude, and the one against velocity
    #: amplitude (the same when empty)
    y_name = ""
    velocity_y_name = ""
    summary_velocity_section = ""
    y_label = ""
    y_units: str | None = None
    #: where the curves are read from a run whose datasets lack them
    summary_section = ""
    summary_y = ""
    #: the modal-model datasets of the model's curve: amplitudes against displacement and
    #: velocity ("" where modal-model does not compute it) and the quantity drawn
    model_x = ""
    model_velocity_x = ""
    model_y = ""

    def __init__(self, compact: bool = False, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.compact = compact
        self.cells = ((0, 0),) if compact else ((0, 0), (0, 1))

    def draw(self, results: RunResults, channel: str) -> Iterator[None]:
        result = results.result(channel, self.plugins[0])
        ok = result is not None and result.ok
        y = per_component(result, self.y_name) if ok else []
        y_v = per_component(result, self.velocity_y_name or self.y_name) if ok else []
        disp = per_component(result, DISPLACEMENT_AMPLITUDE) if y else []
        vel = per_component(result, VELOCITY_AMPLITUDE) if y_v else []
        pairs_d = finite_pairs(zip(disp, y))
        pairs_v = finite_pairs(zip(vel, y_v))
        if not pairs_d and ok:
            pairs_d = summary_series(results, channel, self.summary_section, "amplitude",
                                     self.summary_y)
        if not pairs_v and ok and self.summary_velocity_section:
            pairs_v = summary_series(results, channel, self.summary_velocity_section,
                                     "amplitude", self.summary_y)
        if not pairs_d and not pairs_v:
            return False
        left = self.add_plot(0, 0, self.y_label, "displacement amplitude", self.y_units, "m")
        yield
        for k, (a, b) in enumerate(pairs_d[:MAX_COMPONENTS_DRAWN]):
            self._series(left, a, b, k)
            yield
        robust_range(left, [b for _, b in pairs_d])
        right = None
        if not self.compact:
            right = self.add_plot(0, 1, self.y_label, "velocity amplitude", self.y_units, "m/s")
            yield
            for k, (a, b) in enumerate(pairs_v[:MAX_COMPONENTS_DRAWN]):
                self._series(right, a, b, k)
                yield
            robust_range(right, [b for _, b in pairs_v])
            if not pairs_v:
                right.setTitle("velocity amplitude: not computed")
        yield from self.overlay_model(results, channel, left, right)
        self.set_note(f"{self.title} of {channel}, {len(pairs_d or pairs_v)} component(s)")
        return True

    def _series(self, plot: pg.PlotItem, a: np.ndarray, b: np.ndarray, k: int) -> None:
        colour = COLOURS[k % len(COLOURS)]
        if a.size > 400:
            draw_line(plot, a, b, colour, f"component {k}", 1.4)
        else:
            draw_points(plot, a, b, colour, f"component {k}", 5)

    def overlay_model(self, results, channel, left, right) -> Iterator[None]:
        """The modal model's curve (dashed) over the measured one, where it computed it."""
        model = results.result(channel, "modal-model")
        if model is None or not model.ok:
            return
        y = per_component(model, self.model_y)
        for plot, name in ((left, self.model_x), (right, self.model_velocity_x)):
            if plot is None or not name:
                continue
            for k, (a, b) in enumerate(finite_pairs(zip(per_component(model, name), y))):
                order = np.argsort(a)
                draw_line(plot, a[order], b[order], "#000000",
                          "modal model" if k == 0 else None, 1.6, Qt.PenStyle.DashLine)
                yield


class BackboneView(_AmplitudeView):
    title = "Backbone"
    plugins = ("backbone",)
    y_name = FREQUENCY
    velocity_y_name = VELOCITY_FREQUENCY
    summary_velocity_section = "backbone_velocity"
    y_label = "frequency"
    y_units = "Hz"
    summary_section = "backbone"
    summary_y = "frequency_hz"
    model_x = "backbone_amplitude_model"
    model_y = "backbone_frequency_model"


class DampingView(_AmplitudeView):
    title = "Damping"
    plugins = ("damping",)
    y_name = ZETA
    y_label = "damping ratio ζ"
    summary_section = "damping"
    summary_y = "zeta"
    model_x = "damping_amplitude_model"
    model_velocity_x = "damping_velocity_amplitude_model"
    model_y = "damping_zeta_model"
