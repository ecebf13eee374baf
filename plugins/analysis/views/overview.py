"""The Overview tab: the paper's four figures side by side, drawn a slice per event-loop turn."""

from __future__ import annotations

from typing import Iterator

from PySide6.QtWidgets import QGridLayout, QWidget

from fsi_lab.gui.analysis.stepper import Stepper
from fsi_lab.gui.analysis.view import View
from fsi_lab.gui.results import RunResults
from fsi_lab.plugins.analysis.views.amplitude_views import BackboneView
from fsi_lab.plugins.analysis.views.equivalent_damping_view import EquivalentDampingView
from fsi_lab.plugins.analysis.views.time_views import FrequencyView, HVDView

#: Smallest plot of an Overview figure (axes included), in pixels.
OVERVIEW_MIN_PLOT = (240, 140)


class OverviewView(QWidget):
    """The paper's figures side by side: HVD component with its envelope, instantaneous
    frequency, backbone and the C_q fit."""

    title = "Overview"

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.parts = [HVDView(max_components=1, record=False), FrequencyView(),
                      BackboneView(compact=True), EquivalentDampingView(compact=True)]
        grid = QGridLayout(self)
        grid.setContentsMargins(0, 0, 0, 0)
        grid.setSpacing(4)
        for i, part in enumerate(self.parts):
            part.graphics.min_plot = OVERVIEW_MIN_PLOT  # four figures on a laptop screen
            grid.addWidget(part, i // 2, i % 2)
        for k in range(2):  # four equal quarters, whatever each figure holds
            grid.setRowStretch(k, 1)
            grid.setColumnStretch(k, 1)
        self.filled = False
        #: Draws the parts; the analysis panel gives its own, shared with its other work.
        self.stepper = Stepper(self)  # owned by the view: it dies with it

    def show_results(self, results: RunResults, channel: str) -> None:
        """Draw the four parts a slice per turn of the event loop, from the next one on, so
        that the window keeps answering (and paints each figure) while they are built."""
        self.stepper.cancel(self)
        self.filled = False
        for part in self.parts:
            self.stepper.add(self._part(part, results, channel), self)

    def _part(self, part: View, results: RunResults, channel: str) -> Iterator[None]:
        yield from part.drawing(results, channel)
        self.filled = any(p.filled for p in self.parts)

    @property
    def pending(self) -> bool:
        return self.stepper.pending_for(self)

    def cancel(self) -> None:
        self.stepper.cancel(self)

    def prebuild(self) -> None:
        for part in self.parts:
            part.prebuild()

    def finish(self) -> None:
        """Draw what is still pending at once (tests, screenshots, exports)."""
        self.stepper.finish()
