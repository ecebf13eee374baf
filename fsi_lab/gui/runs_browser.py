"""Runs browser: open run files (several at once), compare them side by side, export.

Files are read off the UI thread; a file that is not a readable fsi-lab run file is reported
(``failed``) and the others stay open. The comparison overlays the curves the plugins register
for it (:class:`fsi_lab.presentation.ComparisonCurve`, through the ``fsi_lab_addviews`` hook) of
the ticked runs and lists their identified values (the columns the plugins register, and the plain
values of any analysis); figures export as PNG or SVG, the values and the curves as CSV.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import (
    QComboBox,
    QFileDialog,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QPushButton,
    QSplitter,
    QTableWidget,
    QTableWidgetItem,
    QTreeWidget,
    QTreeWidgetItem,
    QVBoxLayout,
    QWidget,
)

from fsi_lab.errors import FsiLabError
from fsi_lab.gui.analysis.datasets import finite_pairs, per_component, summary_series, value_columns
from fsi_lab.gui.analysis.plotting import COLOURS, robust_range, set_bottom_label
from fsi_lab.gui.export import export_figure, write_csv
from fsi_lab.gui.figure import Figure, FlowLayout, Legend, scrolled
from fsi_lab.gui.results import RunResults, load_results
from fsi_lab.gui.worker import TaskPool
from fsi_lab.presentation import ComparisonCurve, SummaryColumn
from fsi_lab.registry import Registry

#: Markers of the runs compared (run r in ``SYMBOLS[r % len(SYMBOLS)]``); every curve of the
#: comparison (a component of a run) has a colour of its own.
SYMBOLS = ("o", "t", "s", "d", "+", "x")
#: Components of a run compared at most.
MAX_COMPARED_COMPONENTS = 6
#: Initial width of the list of open runs, in pixels.
LIST_WIDTH = 240
#: Columns of the CSV of identified values before the values, and after them.
RUN_COLUMNS = ("run", "file", "exit_status", "start_time", "channel", "component")
END_COLUMNS = ("errors",)
CURVE_COLUMNS = ("run", "file", "channel", "component", "curve", "x_name", "x_axis", "x", "y_name",
                 "y")


def curves_of(results: RunResults, channel: str, curves: list[ComparisonCurve]
              ) -> dict[str, list[tuple[np.ndarray, np.ndarray]]]:
    """The points of each compared curve per component, from the datasets or the summary."""
    out: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    for curve in curves:
        result = results.result(channel, curve.analysis)
        pairs = []
        if result is not None and result.ok:
            pairs = finite_pairs(zip(per_component(result, curve.x),
                                     per_component(result, curve.y)))
        if not pairs and curve.summary:
            pairs = summary_series(results, channel, *curve.summary)
        out[curve.name] = pairs
    return out


def csv_columns(columns: list[SummaryColumn]) -> tuple[str, ...]:
    """CSV columns of the identified values: each value, and its 95 % interval's bounds."""
    out = list(RUN_COLUMNS)
    for column in columns:
        out.append(column.name)
        if column.interval:
            out += [f"{column.name}_ci95_low", f"{column.name}_ci95_high"]
    return tuple(out) + END_COLUMNS


class RunsBrowser(QWidget):
    """The open runs, their comparison and the exports.

    Signals: ``loaded(RunResults)`` whenever a file has been (re)read, ``selected(RunResults)``
    when the experimenter picks a run, ``failed(path, message)`` when a file cannot be read.
    """

    loaded = Signal(object)
    selected = Signal(object)
    failed = Signal(object, str)

    def __init__(self, registry: Registry, pool: TaskPool, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.registry = registry
        self.pool = pool
        self.runs: dict[Path, RunResults] = {}  # in the order the files were opened
        self._order: list[Path] = []
        self.pending: set[Path] = set()
        self._again: set[Path] = set()
        self._stale = False
        self.list = QTreeWidget()
        self.list.setObjectName("runs-list")
        self.list.setHeaderLabels(["run", "status", "start", "file"])
        self.list.itemChanged.connect(self._ticked)
        self.list.itemDoubleClicked.connect(self._picked)
        self.channel = QComboBox()
        self.channel.currentIndexChanged.connect(self.compare)
        open_button = QPushButton("Open runs ...")
        open_button.clicked.connect(self._open_dialog)
        close_button = QPushButton("Close selected")
        close_button.clicked.connect(self._close_selected)
        show_button = QPushButton("Show analysis")
        show_button.clicked.connect(lambda: self._picked(self.list.currentItem()))
        fig_button = QPushButton("Export figure ...")
        fig_button.clicked.connect(self._export_figure_dialog)
        csv_button = QPushButton("Export CSV ...")
        csv_button.clicked.connect(self._export_csv_dialog)
        self.graphics = Figure()
        self.graphics.setObjectName("compare-plots")
        self.legend = Legend()
        self.legend.setVisible(False)
        self.table = QTableWidget()
        self.table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.note = QLabel("Open run files and tick them to compare them.")
        self.note.setWordWrap(True)

        buttons = QWidget()
        flow = FlowLayout(buttons, spacing=6, line_spacing=4)  # wrap in a narrow list
        for button in (open_button, close_button, show_button):
            flow.addWidget(button)
        left = QWidget()
        left_layout = QVBoxLayout(left)
        left_layout.setContentsMargins(0, 0, 0, 0)
        left_layout.addWidget(buttons)
        left_layout.addWidget(self.list, 1)
        exports = QHBoxLayout()
        exports.addWidget(QLabel("Channel"))
        exports.addWidget(self.channel, 1)
        exports.addWidget(fig_button)
        exports.addWidget(csv_button)
        right = QWidget()
        right_layout = QVBoxLayout(right)
        right_layout.addLayout(exports)
        right_layout.addWidget(self.note)
        right_layout.addWidget(self.legend)
        right_layout.addWidget(scrolled(self.graphics), 3)
        right_layout.addWidget(self.table, 1)
        splitter = QSplitter(Qt.Orientation.Horizontal)
        splitter.addWidget(left)
        splitter.addWidget(right)
        splitter.setStretchFactor(0, 0)
        splitter.setStretchFactor(1, 1)
        splitter.setSizes([LIST_WIDTH, 4 * LIST_WIDTH])  # the comparison gets the room
        layout = QVBoxLayout(self)
        layout.addWidget(splitter)

    # ------------------------------------------------------------------ opening
    def open(self, paths: list[str | Path]) -> None:
        """Read each file off the UI thread; ``loaded`` or ``failed`` follows for each."""
        for path in paths:
            path = Path(path).resolve()
            if path not in self._order:
                self._order.append(path)
            if path in self.pending:  # read again once the current reading is done
                self._again.add(path)
                continue
            self.pending.add(path)
            self.pool.start(load_results, path,
                            on_done=self._loaded,
                            on_error=lambda exc, text, p=path: self._failed(p, exc),
                            name=f"read {path.name}")

    reload = open

    def _read_again(self, path: Path) -> bool:
        if path in self._again:
            self._again.discard(path)
            self.open([path])
            return True
        return False

    def _loaded(self, results: RunResults) -> None:
        path = results.path.resolve()
        self.pending.discard(path)
        if self._read_again(path):
            return
        self.runs[path] = results
        # listed in the order opened, whichever file was read first
        rank = {p: i for i, p in enumerate(self._order)}
        self.runs = dict(sorted(self.runs.items(), key=lambda item: rank.get(item[0], 0)))
        self._refresh_list(path)
        self.compare()
        self.loaded.emit(results)

    def _failed(self, path: Path, exc: BaseException) -> None:
        self.pending.discard(path)
        if self._read_again(path):
            return
        message = str(exc) if isinstance(exc, FsiLabError) else (
            f"{path}: cannot be read as a run file ({type(exc).__name__}: {exc})")
        self.failed.emit(path, message)

    def _open_dialog(self) -> None:
        files, _ = QFileDialog.getOpenFileNames(self, "Open run files", "",
                                                "Run files (*.h5 *.hdf5);;All files (*)")
        if files:
            self.open(files)

    def close_run(self, path: Path) -> None:
        self.runs.pop(Path(path).resolve(), None)
        self._refresh_list()
        self.compare()

    def _close_selected(self) -> None:
        for item in self.list.selectedItems():
            self.runs.pop(item.data(0, Qt.ItemDataRole.UserRole), None)
        self._refresh_list()
        self.compare()

    def _refresh_list(self, tick: Path | None = None) -> None:
        ticked = {p for p in self.checked_paths()}
        if tick is not None:
            ticked.add(tick)
        self.list.blockSignals(True)
        self.list.clear()
        for path, results in self.runs.items():
            item = QTreeWidgetItem([results.name, results.exit_status,
                                    str(results.attrs.get("start_time", ""))[:19], path.name])
            item.setData(0, Qt.ItemDataRole.UserRole, path)
            item.setFlags(item.flags() | Qt.ItemFlag.ItemIsUserCheckable)
            item.setCheckState(0, Qt.CheckState.Checked if path in ticked
                               else Qt.CheckState.Unchecked)
            item.setToolTip(0, str(path))
            self.list.addTopLevelItem(item)
        self.list.blockSignals(False)
        for column in range(4):
            self.list.resizeColumnToContents(column)
        channels: list[str] = []
        for results in self.runs.values():
            for name in results.analysed_channels():
                if name not in channels:
                    channels.append(name)
        current = self.channel.currentData()
        self.channel.blockSignals(True)
        self.channel.clear()
        for name in channels:
            self.channel.addItem(name, name)
        if current in channels:
            self.channel.setCurrentIndex(channels.index(current))
        self.channel.blockSignals(False)

    def _ticked(self, *args) -> None:
        self.compare()

    def _picked(self, item: QTreeWidgetItem | None) -> None:
        if item is None:
            return
        results = self.runs.get(item.data(0, Qt.ItemDataRole.UserRole))
        if results is not None:
            self.selected.emit(results)

    def checked_paths(self) -> list[Path]:
        paths = []
        for i in range(self.list.topLevelItemCount()):
            item = self.list.topLevelItem(i)
            if item.checkState(0) == Qt.CheckState.Checked:
                paths.append(item.data(0, Qt.ItemDataRole.UserRole))
        return paths

    def set_checked(self, paths: list[Path]) -> None:
        wanted = {Path(p).resolve() for p in paths}
        self.list.blockSignals(True)
        for i in range(self.list.topLevelItemCount()):
            item = self.list.topLevelItem(i)
            item.setCheckState(0, Qt.CheckState.Checked
                               if item.data(0, Qt.ItemDataRole.UserRole) in wanted
                               else Qt.CheckState.Unchecked)
        self.list.blockSignals(False)
        self.compare()

    # ------------------------------------------------------------------ comparison
    def _compared(self) -> list[RunResults]:
        return [self.runs[p] for p in self.checked_paths() if p in self.runs]

    def _channel_of(self, results: RunResults) -> str | None:
        channel = self.channel.currentData()
        channels = results.analysed_channels()
        if channel in channels:
            return channel
        return channels[0] if channels else None

    def showEvent(self, event) -> None:
        super().showEvent(event)
        if self._stale:
            self.compare(force=True)

    def compare(self, *args, force: bool = False) -> None:
        """Overlay the ticked runs' curves and list their identified values (drawn when the
        browser is on screen; until then only marked as out of date)."""
        if not (force or self.isVisible()):
            self._stale = True
            return
        self._stale = False
        self.graphics.clear()
        runs = self._compared()
        plots = {}
        curves = self.registry.views().curves
        compared = [(results, channel) for results in runs
                    if (channel := self._channel_of(results)) is not None]
        for col, curve in enumerate(curves):
            plot = self.graphics.addPlot(row=0, col=col)
            set_bottom_label(plot, self._x_label(curve, compared), curve.x_unit)
            plot.setLabel("left", curve.y_label, units=curve.y_unit)
            plot.setTitle(curve.name.replace("_", " "))
            plot.showGrid(x=True, y=True, alpha=0.2)
            plots[curve.name] = plot
        drawn = 0
        entries = []
        shown: dict[str, list[np.ndarray]] = {name: [] for name in plots}
        series = 0  # a colour for every component of every run
        names = [results.name for results in runs]
        for r, results in enumerate(runs):
            channel = self._channel_of(results)
            if channel is None:
                continue
            symbol = SYMBOLS[r % len(SYMBOLS)]
            points = curves_of(results, channel, curves)
            count = min(MAX_COMPARED_COMPONENTS, max((len(p) for p in points.values()),
                                                     default=0))
            for k in range(count):
                colour = COLOURS[(series + k) % len(COLOURS)]
                label = f"{self._label(results, names)}, component {k}"
                entries.append((label, Legend.look(symbol=symbol, symbol_colour=colour)))
                for name, pairs in points.items():
                    if k >= len(pairs):
                        continue
                    x, y = pairs[k]
                    line = x.size > 400
                    plots[name].plot(x, y, pen=pg.mkPen(colour, width=1.2) if line else None,
                                     symbol=None if line else symbol, symbolSize=6,
                                     symbolBrush=colour, symbolPen=None, name=label)
                    shown[name].append(y)
                    drawn += 1
            series += count
        for name, values in shown.items():
            robust_range(plots[name], values)  # the bulk; outliers are a zoom-out away
        self.legend.show_entries(entries if drawn else [])
        self.graphics.fit_minimum()
        self._fill_table(runs)
        if not runs:
            self.note.setText("Open run files and tick them to compare them.")
        elif not drawn:
            names = ", ".join(curve.name.replace("_", " ") for curve in curves) or "none"
            self.note.setText(f"The ticked runs hold none of the curves compared ({names}): "
                              "not computed.")
        else:
            self.note.setText(f"{len(runs)} run(s) compared")

    @staticmethod
    def _x_label(curve: ComparisonCurve, compared: list[tuple[RunResults, str]]) -> str:
        """The curve's x label for the runs compared (its plugin's ``x_label_for``), else, or
        when that fails, its ``x_label``."""
        if curve.x_label_for is None or not compared:
            return curve.x_label
        try:
            return str(curve.x_label_for(compared))
        except Exception:  # noqa: BLE001 - a plugin's label must not take the comparison down
            return curve.x_label

    @staticmethod
    def _label(results: RunResults, names: list[str]) -> str:
        """The run's name, with its start time (or file) when another compared run shares it."""
        if names.count(results.name) < 2:
            return results.name
        started = str(results.attrs.get("start_time", ""))
        return f"{results.name} ({started[11:19] if len(started) >= 19 else results.path.name})"

    def value_columns(self, runs: list[RunResults]) -> list[SummaryColumn]:
        """The columns of identified values of ``runs`` (each channel), each once."""
        out: dict[str, SummaryColumn] = {}
        for results in runs:
            for column in value_columns(results, results.analysed_channels(), self.registry):
                out.setdefault(column.name, column)
        return list(out.values())

    def summary_rows(self, runs: list[RunResults] | None = None,
                     columns: list[SummaryColumn] | None = None) -> list[dict[str, Any]]:
        """One row per run, channel and component (a run without components gives one row)."""
        runs = runs if runs is not None else self._compared()
        columns = columns if columns is not None else self.value_columns(runs)
        out = []
        for results in runs:
            base = {"run": results.name, "file": str(results.path),
                    "exit_status": results.exit_status,
                    "start_time": results.attrs.get("start_time", "")}
            channels = results.analysed_channels() or [""]
            for channel in channels:
                errors = "; ".join(f"{r.plugin}: {r.error}"
                                   for r in results.analysis.get(channel, {}).values() if not r.ok)
                components = results.components(channel) if channel else []
                for component in components or [{}]:
                    row = {**base, "channel": channel, "component": component.get("index"),
                           "errors": errors}
                    for column in columns:
                        row[column.name] = column.value(component)
                        if column.interval:
                            row[f"{column.name}_ci95_low"], row[f"{column.name}_ci95_high"] = \
                                column.bounds(component)
                    out.append(row)
        return out

    def _fill_table(self, runs: list[RunResults]) -> None:
        values = self.value_columns(runs)
        rows = self.summary_rows(runs, values)
        columns = ("run", "exit_status", "channel", "component",
                   *(column.name for column in values), "errors")
        self.table.clear()
        self.table.setColumnCount(len(columns))
        self.table.setHorizontalHeaderLabels(list(columns))
        self.table.setRowCount(len(rows))
        for r, row in enumerate(rows):
            for c, key in enumerate(columns):
                value = row.get(key)
                text = f"{value:.5g}" if isinstance(value, float) else (
                    "" if value is None else str(value))
                self.table.setItem(r, c, QTableWidgetItem(text))
        self.table.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)

    # ------------------------------------------------------------------ exports
    def export_figure(self, path: str | Path) -> Path:
        """The comparison plots as PNG or SVG (by the suffix)."""
        if self._stale:
            self.compare(force=True)
        return export_figure(self.graphics, path)

    def export_csv(self, path: str | Path) -> Path:
        """The identified values of the ticked runs, one row per component."""
        if self._stale:
            self.compare(force=True)
        runs = self._compared()
        columns = self.value_columns(runs)
        return write_csv(path, csv_columns(columns), self.summary_rows(runs, columns))

    def export_curves_csv(self, path: str | Path) -> Path:
        """Every point of the ticked runs' compared curves (long format); ``x_axis`` says what
        each run's ``x`` holds (the curve's ``x_label_for`` that run alone)."""
        rows = []
        curves = self.registry.views().curves
        labels = {c.name: (c.x_name, c.y_name) for c in curves}
        by_name = {c.name: c for c in curves}
        for results in self._compared():
            channel = self._channel_of(results)
            if channel is None:
                continue
            for name, pairs in curves_of(results, channel, curves).items():
                # what x holds in this run's own words (the modal or the measured amplitude)
                axis = self._x_label(by_name[name], [(results, channel)])
                for k, (x, y) in enumerate(pairs):
                    for xv, yv in zip(x, y):
                        rows.append({"run": results.name, "file": str(results.path),
                                     "channel": channel, "component": k + 1, "curve": name,
                                     "x_name": labels[name][0], "x_axis": axis, "x": float(xv),
                                     "y_name": labels[name][1], "y": float(yv)})
        return write_csv(path, CURVE_COLUMNS, rows)

    def _export_figure_dialog(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Export figure", "comparison.png",
                                              "PNG image (*.png);;SVG drawing (*.svg)")
        if path:
            try:
                self.export_figure(path)
            except (OSError, ValueError) as exc:
                self.failed.emit(Path(path), f"export failed: {exc}")

    def _export_csv_dialog(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Export results", "results.csv",
                                              "CSV (*.csv)")
        if path:
            try:
                self.export_csv(path)
                curves = Path(path).with_name(Path(path).stem + "-curves.csv")
                self.export_curves_csv(curves)
            except OSError as exc:
                self.failed.emit(Path(path), f"export failed: {exc}")
