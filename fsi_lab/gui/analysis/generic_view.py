"""The generic view: any analysis's datasets plotted with their units, and tabled with its values.

An analysis that no plugin gives a view of its own (the ``fsi_lab_addviews`` hook) gets a tab
drawn by :class:`GenericView`, which knows nothing of the analysis: each numeric dataset of
``/analysis/<channel>/<analysis>/`` is plotted (a 2-D one row by row, as the components it
holds) against the dataset its ``axis`` attribute names (``AnalysisResult.axes``), or against
its sample index; the table below lists every dataset (shape, units, range) and every scalar
value the analysis stored.
"""

from __future__ import annotations

from typing import Any, Iterator

import numpy as np
from PySide6.QtWidgets import QHeaderView, QTableWidget, QTableWidgetItem, QWidget

from fsi_lab.gui.analysis.datasets import rows
from fsi_lab.gui.analysis.plotting import COLOURS, MAX_COMPONENTS_DRAWN, draw_line, draw_points
from fsi_lab.gui.analysis.view import View
from fsi_lab.gui.results import PluginResult, RunResults
from fsi_lab.summary import format_value

#: Datasets plotted at most (the others are in the table).
MAX_PLOTS = 6
#: Samples below which a curve is drawn as points.
POINTS_BELOW = 60


def numeric(array: Any) -> np.ndarray | None:
    """``array`` as floats when it is a 1-D or 2-D numeric dataset (magnitudes of complex
    values), else None."""
    array = np.asarray(array)
    if array.ndim not in (1, 2) or array.size == 0:
        return None
    if array.dtype == bool:
        return array.astype(float)
    if not np.issubdtype(array.dtype, np.number):
        return None
    return np.abs(array).astype(float) if np.iscomplexobj(array) else array.astype(float)


def axis_of(result: PluginResult, name: str, size: int) -> tuple[str, np.ndarray | None]:
    """The dataset a dataset of ``size`` points per row is drawn against (its ``axis``
    attribute), when it is a 1-D dataset of that length (or has a row per component of it)."""
    axis = result.axes.get(name)
    if not axis or axis not in result.datasets:
        return "", None
    values = numeric(result.datasets[axis])
    if values is None or values.shape[-1] != size:
        return "", None
    return axis, values


class GenericView(View):
    """The datasets and values of one analysis, drawn without knowing it.

    Parameters
    ----------
    analysis
        Name of the analysis (the tab title).
    """

    cells = ((0, 0),)

    def __init__(self, analysis: str, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.analysis = analysis
        self.title = analysis
        self.plugins = self.analyses = (analysis,)
        self.table = QTableWidget()
        self.table.setObjectName("generic-values")
        self.table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.table.setColumnCount(3)
        self.table.setHorizontalHeaderLabels(["name", "value", "units"])
        self.table.setMaximumHeight(180)
        self.table.setVisible(False)
        self.column.addWidget(self.table)

    def clear(self) -> None:
        super().clear()
        self.table.setRowCount(0)
        self.table.setVisible(False)

    def draw(self, results: RunResults, channel: str) -> Iterator[None]:
        result = results.result(channel, self.analysis)
        if result is None or not result.ok:
            return False
        used_as_axes = {result.axes[n] for n in result.datasets if n in result.axes}
        drawn: list[str] = []
        for name, array in result.datasets.items():
            values = numeric(array)
            if values is None or name in used_as_axes or len(drawn) == MAX_PLOTS:
                continue
            yield from self._plot(result, name, values, len(drawn))
            drawn.append(name)
        self._fill_table(result)
        if not drawn and not self.table.rowCount():
            return False
        others = [n for n in result.datasets if n not in drawn and n not in used_as_axes]
        self.set_note(f"{self.analysis} on {channel}: "
                      + (f"{', '.join(drawn)} drawn" if drawn else "no dataset to draw")
                      + (f"; {', '.join(others)} in the table" if others else "")
                      + " (the analysis's own datasets and values, drawn by the generic view)")
        return True

    def _plot(self, result: PluginResult, name: str, values: np.ndarray, row: int
              ) -> Iterator[None]:
        size = values.shape[-1]
        axis, x = axis_of(result, name, size)
        plot = self.add_plot(row, 0, name, axis or "sample", result.units.get(name) or None,
                             (result.units.get(axis) or None) if axis else None)
        yield
        lines = rows(values)
        x_rows = rows(x) if x is not None else []
        for k, y in enumerate(lines[:MAX_COMPONENTS_DRAWN]):
            xk = x_rows[k] if len(x_rows) == len(lines) else (
                x_rows[0] if x_rows else np.arange(size, dtype=float))
            label = f"{name}, row {k}" if len(lines) > 1 else name
            colour = COLOURS[k % len(COLOURS)]
            keep = np.isfinite(xk) & np.isfinite(y)
            if keep.sum() < POINTS_BELOW:
                draw_points(plot, xk[keep], y[keep], colour, label, 5)
            else:
                draw_line(plot, xk, y, colour, label, 1.2)
            yield

    def _fill_table(self, result: PluginResult) -> None:
        entries = []
        for name, array in result.datasets.items():
            array = np.asarray(array)
            values = numeric(array)
            finite = values[np.isfinite(values)] if values is not None else np.array([])
            text = "x".join(map(str, array.shape)) or "scalar"
            if array.ndim == 0:
                text = format_value(array.item())
            elif finite.size:
                text += f": {format_value(finite.min())} to {format_value(finite.max())}"
            axis = result.axes.get(name)
            entries.append((name + (f" (against {axis})" if axis else ""), text,
                            result.units.get(name, "")))
        for name, value in result.attrs.items():
            if isinstance(value, (list, tuple)):
                value = ", ".join(format_value(v) for v in value[:8]) + (
                    ", ..." if len(value) > 8 else "")
            entries.append((name, format_value(value), ""))
        self.table.setRowCount(len(entries))
        for r, entry in enumerate(entries):
            for c, text in enumerate(entry):
                self.table.setItem(r, c, QTableWidgetItem(str(text)))
        self.table.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        self.table.horizontalHeader().setStretchLastSection(True)
        self.table.setVisible(bool(entries))
