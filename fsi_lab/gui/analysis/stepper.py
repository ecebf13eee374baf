"""Stepper: runs drawings a slice per turn of the event loop, so the window keeps answering."""

from __future__ import annotations

import time
from typing import Any, Iterator

from PySide6.QtCore import QObject, QTimer

#: Pause (ms) between two slices of a drawing spread over turns of the event loop, and the
#: longest a slice may go on before it hands the event loop back.
PAUSE_MS = 8
SLICE_S = 0.008


class Stepper(QObject):
    """Runs drawings (generators from :meth:`~fsi_lab.gui.analysis.view.View.drawing`) a slice
    at a time, one slice per turn of the event loop, so that the window keeps answering while
    figures are built. A drawing that completes ends its slice: its figure is painted before
    the next one starts."""

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._queue: list[tuple[Iterator[Any], Any]] = []
        #: The clock slices are measured with (seconds; replaceable, e.g. by a test's).
        self.clock = time.perf_counter
        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(PAUSE_MS)
        self._timer.timeout.connect(self.step)

    @property
    def pending(self) -> bool:
        return bool(self._queue)

    def add(self, drawing: Iterator[Any], owner: Any = None) -> None:
        """Queue ``drawing``; ``owner`` names who may :meth:`cancel` it."""
        self._queue.append((drawing, owner))
        if not self._timer.isActive():
            self._timer.start()

    def pending_for(self, owner: Any) -> bool:
        return any(o is owner for _, o in self._queue)

    def cancel(self, owner: Any = None) -> None:
        """Drop the queued drawings of ``owner`` (all with None)."""
        dropped = [d for d, o in self._queue if owner is None or o is owner]
        self._queue = [(d, o) for d, o in self._queue if not (owner is None or o is owner)]
        if not self._queue:
            self._timer.stop()
        for drawing in dropped:
            drawing.close()  # its figure is painted again (as far as it got)

    def step(self, deadline: float | None = None) -> None:
        """One slice: steps of the first drawing until ``SLICE_S`` is used or it completes."""
        if deadline is None:
            deadline = self.clock() + SLICE_S
        try:
            while self._queue:
                try:
                    next(self._queue[0][0])
                except StopIteration:
                    self._queue.pop(0)
                    break
                except Exception:
                    self._queue.pop(0)  # reported by Qt's handler; the others go on
                    raise
                if self.clock() >= deadline:
                    break
        finally:
            if self._queue and deadline != float("inf"):
                self._timer.start()

    def finish(self) -> None:
        """Complete every drawing at once (tests, screenshots, exports)."""
        self._timer.stop()
        while self._queue:
            self.step(deadline=float("inf"))
        self._timer.stop()
