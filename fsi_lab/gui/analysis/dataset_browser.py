"""The All datasets tab: every dataset of every analysis of a channel, plotted when selected."""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QSplitter, QTreeWidget, QTreeWidgetItem, QVBoxLayout, QWidget

from fsi_lab.gui.analysis.datasets import rows
from fsi_lab.gui.analysis.plotting import COLOURS, MAX_COMPONENTS_DRAWN, draw_line
from fsi_lab.gui.results import RunResults


class DatasetBrowser(QWidget):
    """Every group and dataset under ``/analysis/<channel>``, any plugin; select one to plot it."""

    title = "All datasets"

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.filled = False
        self.results: RunResults | None = None
        self.channel = ""
        self.tree = QTreeWidget()
        self.tree.setHeaderLabels(["analysis / dataset", "shape", "units"])
        self.tree.itemSelectionChanged.connect(self._selected)
        self.plot = pg.PlotWidget()
        self.plot.showGrid(x=True, y=True, alpha=0.2)
        splitter = QSplitter()
        splitter.addWidget(self.tree)
        splitter.addWidget(self.plot)
        splitter.setStretchFactor(1, 2)
        layout = QVBoxLayout(self)
        layout.addWidget(splitter)

    def show_results(self, results: RunResults, channel: str) -> None:
        self.results, self.channel = results, channel
        self.tree.clear()
        self.plot.clear()
        for plugin, result in results.analysis.get(channel, {}).items():
            top = QTreeWidgetItem([f"{plugin} ({result.status})", "", ""])
            if result.error:
                top.setToolTip(0, result.error)
            for name, array in result.datasets.items():
                child = QTreeWidgetItem([name, "x".join(map(str, np.shape(array))),
                                         result.units.get(name, "")])
                child.setData(0, Qt.ItemDataRole.UserRole, (plugin, name))
                top.addChild(child)
            self.tree.addTopLevelItem(top)
            top.setExpanded(True)
        self.filled = self.tree.topLevelItemCount() > 0

    def _selected(self) -> None:
        items = self.tree.selectedItems()
        if not items or self.results is None:
            return
        key = items[0].data(0, Qt.ItemDataRole.UserRole)
        if not key:
            return
        plugin, name = key
        result = self.results.result(self.channel, plugin)
        array = np.asarray(result.datasets[name])
        self.plot.clear()
        self.plot.setTitle(f"{plugin}/{name}")
        if not np.issubdtype(array.dtype, np.number) and array.dtype != bool:
            return
        if np.iscomplexobj(array):
            array = np.abs(array)
        if array.ndim == 2 and array.shape[0] > array.shape[1]:
            array = array.T  # a plugin's own layout, points down the columns: draw the columns
        for k, row in enumerate(rows(array.astype(float))[:MAX_COMPONENTS_DRAWN]):
            draw_line(self.plot.getPlotItem(), np.arange(row.size), row, COLOURS[k % len(COLOURS)])
