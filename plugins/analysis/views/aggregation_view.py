"""The Sequence tab's figure of a sequence's aggregation: the backbone, damping and C_q curves
of every completed run on one amplitude axis, with their medians and the fitted C_q line.

The aggregation is the record's ``aggregate`` (:mod:`fsi_lab.aggregate`, layout in
docs/sequence-format.md, "Aggregation"): its curves are named after the analyses that give
them (hvd's modes, their backbone and damping), so the figure is registered with those
analyses' views, through ``fsi_lab_addviews``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pyqtgraph as pg
from PySide6.QtWidgets import QVBoxLayout, QWidget

from fsi_lab.aggregate import main_mode
from fsi_lab.gui.analysis.plotting import set_bottom_label
from fsi_lab.gui.figure import Figure
from fsi_lab.plugins.analysis.views.labels import aggregate_amplitude

#: Colours of the runs' points, by run.
PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
           "#7f7f7f", "#bcbd22", "#17becf")
#: The plots: (key, title, left label).
PLOTS = (("backbone", "backbone", "frequency (Hz)"),
         ("damping", "damping", "damping ratio"),
         ("c_q", "C_q and its fit", "C_q (kg/(m s))"))


class AggregationCurvesView(QWidget):
    """The aggregation's mode with the most extrema: each run's backbone, damping ratio and
    C_q against amplitude (m, log axis: the displacement at the measuring point, or the modal
    amplitude the mode's C_i and C_f belong to), points coloured by run; the medians on the
    common amplitude axis (black) and the fitted C_q line (dashed red)."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.figure = Figure()
        self.plots: dict[str, pg.PlotItem] = {}
        for col, (key, title, y_label) in enumerate(PLOTS):
            plot = self.figure.addPlot(row=0, col=col)
            set_bottom_label(plot, "amplitude", "m")
            plot.setLabel("left", y_label)
            plot.setLogMode(x=True, y=False)
            plot.showGrid(x=True, y=True, alpha=0.3)
            plot.setTitle(title)
            self.plots[key] = plot
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.figure)

    def draw(self, aggregate: dict[str, Any] | None) -> bool:
        """Draw the aggregation's mode with the most extrema; True when there was one."""
        mode = main_mode(aggregate)
        amplitude = aggregate_amplitude(mode) if mode is not None else "amplitude"
        for plot in self.plots.values():
            plot.clear()
            set_bottom_label(plot, amplitude, "m")
        if mode is None:
            return False
        curves, axis = mode["curves"], mode["axis"]
        for key, curve, y in (("backbone", "backbone", "frequency_hz"),
                              ("damping", "damping", "zeta"), ("c_q", "damping", "c_q")):
            x = np.asarray(curves[curve]["amplitude_m"], dtype=float)
            values = np.asarray(curves[curve][y], dtype=float)
            runs = np.asarray(curves[curve]["run"], dtype=int)
            keep = (x > 0) & np.isfinite(values)
            for run in np.unique(runs[keep]):
                sel = keep & (runs == run)
                self.plots[key].plot(x[sel], values[sel], pen=None, symbol="o", symbolSize=4,
                                     symbolPen=None,
                                     symbolBrush=PALETTE[int(run) % len(PALETTE)])
        centres = np.asarray(axis["amplitude_m"], dtype=float)
        for key, name in (("backbone", "backbone_frequency_hz"), ("c_q", "c_q")):
            medians = _floats(axis[name])
            ok = np.isfinite(medians)
            if ok.any():
                self.plots[key].plot(centres[ok], medians[ok], pen=pg.mkPen("k", width=2))
        fit = _floats(axis["c_q_fit"])
        if np.isfinite(fit).any():
            self.plots["c_q"].plot(centres, fit, pen=pg.mkPen(
                "r", width=2, style=pg.QtCore.Qt.PenStyle.DashLine))
        return True

    def points(self, key: str) -> int:
        """Points drawn in plot ``key`` (for tests)."""
        return sum(len(item.xData) for item in self.plots[key].listDataItems()
                   if item.xData is not None)


def _floats(values) -> np.ndarray:
    """A JSON list of numbers and nulls as floats (null: NaN)."""
    return np.array([math.nan if v is None else v for v in values], dtype=float)
