"""The Results tab: identified values per component and the status of the channel's analyses."""

from __future__ import annotations

import pyqtgraph as pg
from PySide6.QtWidgets import (
    QHeaderView,
    QLabel,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from fsi_lab.gui.analysis.datasets import format_ci, value_columns
from fsi_lab.gui.results import RunResults
from fsi_lab.presentation import SummaryColumn
from fsi_lab.registry import Registry
from fsi_lab.summary import format_value


def interval_label(column: SummaryColumn) -> str:
    """Header of a column's 95 % interval: its label without the unit, then ``95 %``."""
    return f"{column.label.split(' (')[0]} 95 %"


class SummaryView(QWidget):
    """The identified values per component (the columns the plugins register, then every plain
    value of the summary no plugin shows in its own way), the failures, and the status of
    every analysis."""

    title = "Results"

    def __init__(self, registry: Registry, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.registry = registry
        self.filled = False
        self.table = QTableWidget()
        self.table.setObjectName("results-table")
        self.table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.status = QTableWidget()
        self.status.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        layout = QVBoxLayout(self)
        layout.addWidget(QLabel("Identified values"))
        layout.addWidget(self.table, 2)
        layout.addWidget(QLabel("Analyses of this channel"))
        layout.addWidget(self.status, 1)

    def show_results(self, results: RunResults, channel: str) -> None:
        components = results.components(channel)
        columns = value_columns(results, [channel], self.registry)
        headers = ["component"]
        for column in columns:
            headers.append(column.label)
            if column.interval:
                headers.append(interval_label(column))
        self.table.clear()
        self.table.setColumnCount(len(headers))
        self.table.setHorizontalHeaderLabels(headers)
        self.table.setRowCount(len(components))
        for r, component in enumerate(components):
            cells = [component.get("index")]
            for column in columns:
                cells.append(column.value(component))
                if column.interval:
                    bounds = column.bounds(component)
                    cells.append(list(bounds) if None not in bounds else None)
            for c, value in enumerate(cells):
                text = format_ci(value) if isinstance(value, list) else (
                    "" if value is None else format_value(value) if not isinstance(value, float)
                    else f"{value:.5g}")
                self.table.setItem(r, c, QTableWidgetItem(text))
        self.table.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        groups = results.analysis.get(channel, {})
        self.status.clear()
        self.status.setColumnCount(3)
        self.status.setHorizontalHeaderLabels(["analysis", "status", "message / parameters"])
        self.status.setRowCount(len(groups))
        for r, (plugin, result) in enumerate(groups.items()):
            self.status.setItem(r, 0, QTableWidgetItem(plugin))
            item = QTableWidgetItem(result.status)
            if not result.ok:
                item.setForeground(pg.mkColor("#b00020"))
            self.status.setItem(r, 1, item)
            detail = result.error or ", ".join(f"{k}={v}" for k, v in result.params.items())
            self.status.setItem(r, 2, QTableWidgetItem(detail))
        self.status.horizontalHeader().setStretchLastSection(True)
        self.filled = bool(components)
