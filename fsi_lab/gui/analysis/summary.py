"""The Results tab: identified values per component and the status of the channel's analyses."""

from __future__ import annotations

import pyqtgraph as pg
from PySide6.QtWidgets import (
    QHeaderView, QLabel, QTableWidget, QTableWidgetItem, QVBoxLayout, QWidget,
)

from fsi_lab.gui.analysis.datasets import format_ci, table_rows
from fsi_lab.gui.results import RunResults


class SummaryView(QWidget):
    """The identified values per component, the failures, and the status of every analysis."""

    title = "Results"

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
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

    COLUMNS = ("component", "frequency (Hz)", "C_i (kg/(m s))", "C_i 95 %", "C_f (kg/m²)",
               "C_f 95 %", "R²")

    def show_results(self, results: RunResults, channel: str) -> None:
        rows_ = table_rows(results, channel)
        self.table.clear()
        self.table.setColumnCount(len(self.COLUMNS))
        self.table.setHorizontalHeaderLabels(list(self.COLUMNS))
        self.table.setRowCount(len(rows_))
        for r, row in enumerate(rows_):
            for c, key in enumerate(("index", "frequency_hz", "c_i", "c_i_ci95", "c_f",
                                     "c_f_ci95", "r2")):
                value = row.get(key)
                if isinstance(value, float):
                    text = f"{value:.5g}"
                elif isinstance(value, (list, tuple)):
                    text = format_ci(value)
                else:
                    text = "" if value is None else str(value)
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
        self.filled = bool(rows_)
