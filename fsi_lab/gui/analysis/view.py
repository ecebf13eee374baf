"""View: the base of every analysis figure, drawn step by step into plots kept between drawings."""

from __future__ import annotations

import inspect
from typing import Iterator

import pyqtgraph as pg
from PySide6.QtWidgets import QLabel, QSizePolicy, QVBoxLayout, QWidget

from fsi_lab.gui.figure import Figure, Legend
from fsi_lab.gui.results import RunResults


class View(QWidget):
    """One figure of the analysis; ``filled`` tells whether it shows data."""

    title = ""
    plugins: tuple[str, ...] = ()
    #: Plot cells (row, column) the view usually draws, built ahead of time by :meth:`prebuild`.
    cells: tuple[tuple[int, int], ...] = ((0, 0),)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.filled = False
        self.note = QLabel()
        self.note.setWordWrap(True)
        self.note.setObjectName("view-note")
        # Two lines are reserved whatever the note says, so that a new note does not resize
        # the figures below it (which would repaint every figure of the Overview).
        self.note.setMinimumHeight(2 * self.note.fontMetrics().lineSpacing() + 2)
        self.legend = Legend()
        self.legend.setVisible(False)
        self.graphics = Figure()
        # The figure takes the space it is given, whatever its plots hint, down to the minimum
        # of the plots it shows (the view sits in a scroll area): a drawing does not change
        # the layout around it unless the figure would otherwise be squashed.
        self.graphics.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Ignored)
        # Plot items are costly to build: they are kept between drawings and emptied.
        self._plots: dict[tuple[int, int], pg.PlotItem] = {}
        self._used: set[tuple[int, int]] = set()
        self.column = QVBoxLayout(self)
        self.column.setContentsMargins(2, 2, 2, 2)
        self.column.addWidget(self.note)
        self.column.addWidget(self.legend)
        self.column.addWidget(self.graphics, 1)

    def clear(self) -> None:
        for plot in self._plots.values():
            plot.clear()
            plot.setTitle(None)
            plot.setLogMode(False, False)
            plot.enableAutoRange()
            plot.setXLink(None)
        self._used.clear()
        self.filled = False

    def prebuild(self) -> None:
        """Build the usual plot items now (idle time), hidden until a drawing uses them."""
        for row, col in self.cells:
            self.add_plot(row, col, "", "")
        self._used.clear()
        self._prune()

    def _prune(self) -> None:
        """Hide the plots the last drawing did not use (kept for the next), list the curves
        of those it used in the legend, and size the figure for them."""
        for key, item in self._plots.items():
            item.setVisible(key in self._used)
        self.legend.show_items(curve for key in sorted(self._used)
                               for curve in self._plots[key].listDataItems())
        self.graphics.fit_minimum()

    def show_results(self, results: RunResults, channel: str) -> None:
        """Draw the view at once."""
        for _ in self.drawing(results, channel):
            pass

    def drawing(self, results: RunResults, channel: str) -> Iterator[None]:
        """Draw the view step by step: each ``next()`` does a little of the work (a curve, a
        plot), so that a :class:`~fsi_lab.gui.analysis.stepper.Stepper` can spread the drawing
        over turns of the event loop. The figure is painted once, when the drawing is complete;
        ``filled`` is set then."""
        self.clear()
        self.graphics.setUpdatesEnabled(False)
        try:
            try:
                outcome = self.draw(results, channel)
                if inspect.isgenerator(outcome):
                    outcome = yield from outcome
                self.filled = bool(outcome)
            except Exception as exc:  # noqa: BLE001 - an odd dataset must not take the window down
                self.clear()
                self._prune()
                self._set_note(f"cannot draw this view: {type(exc).__name__}: {exc}",
                               "color: #b00020;")
                return
            if not self.filled:
                self.clear()
            self._prune()
            if not self.filled:
                self._set_note(self.missing(results, channel), "color: #666;")
        finally:
            self.graphics.setUpdatesEnabled(True)

    def missing(self, results: RunResults, channel: str) -> str:
        """Why nothing is drawn: failed with its message, or not computed."""
        for plugin in self.plugins:
            result = results.result(channel, plugin)
            if result is not None and not result.ok:
                return f"{plugin} failed on {channel}: {result.error}"
        names = " / ".join(self.plugins)
        return f"not computed: this run has no {names} results for channel {channel}"

    def draw(self, results: RunResults, channel: str) -> bool | Iterator[None]:
        """Draw the view; True if it shows data. A generator (``yield`` between steps,
        ``return`` the verdict) can be drawn a step at a time. Each figure overrides it; the
        bare view has no figure and shows nothing."""
        return False

    def add_plot(self, row: int, col: int, left: str, bottom: str, left_units: str | None = None,
                 bottom_units: str | None = None, colspan: int = 1) -> pg.PlotItem:
        key = (row, col)
        plot = self._plots.get(key)
        if plot is None:
            plot = self._plots[key] = self.graphics.addPlot(row=row, col=col, colspan=colspan)
        plot.setVisible(True)
        self._used.add(key)
        plot.setLabel("left", left, units=left_units)
        plot.setLabel("bottom", bottom, units=bottom_units)
        return plot

    def set_note(self, text: str) -> None:
        self._set_note(text, "")

    def _set_note(self, text: str, style: str) -> None:
        # unchanged text and style are not set again: each would ask for a new layout
        if self.note.text() != text:
            self.note.setText(text)
        if self.note.styleSheet() != style:
            self.note.setStyleSheet(style)
