"""The bridge between the core's threads and the UI thread.

The core emits its events from the thread that runs the experiment; :class:`EventForwarder`
hands each one to the UI thread through a queued connection and re-emits it there as a Qt
signal, so every receiver (widget method or plain function) runs on the UI thread.
:class:`Task` runs any callable on a :class:`QThread` of its own and reports its result or its
exception the same way; :class:`TaskPool` keeps tasks alive until they finish and lets the window
wait for them when it closes. Nothing here blocks the UI thread.
"""

from __future__ import annotations

import traceback
from typing import Any, Callable

from PySide6.QtCore import QObject, Qt, QThread, Signal, Slot

from fsi_lab.events import DataBlock, LogRecord, Progress, StateChanged


class EventForwarder(QObject):
    """A subscriber of :class:`fsi_lab.events.EventBus` that turns events into Qt signals.

    Create it on the UI thread; call it (``bus.subscribe(forwarder)``) from any thread. Each
    public signal carries the event object unchanged and is emitted on the UI thread.
    """

    state = Signal(object)
    progress = Signal(object)
    data = Signal(object)
    log = Signal(object)
    _incoming = Signal(object)

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._incoming.connect(self._dispatch, Qt.ConnectionType.QueuedConnection)

    def __call__(self, event: Any) -> None:
        """Called by the event bus on the run's thread: queue the event for the UI thread."""
        self._incoming.emit(event)

    @Slot(object)
    def _dispatch(self, event: Any) -> None:
        if isinstance(event, DataBlock):
            self.data.emit(event)
        elif isinstance(event, Progress):
            self.progress.emit(event)
        elif isinstance(event, StateChanged):
            self.state.emit(event)
        elif isinstance(event, LogRecord):
            self.log.emit(event)


class Task(QThread):
    """Runs ``func(*args)`` on a thread of its own.

    Signals, emitted on the UI thread: ``succeeded(result)`` or ``failed(exception, text)``
    (``text`` is the formatted traceback), then ``done()``.
    """

    succeeded = Signal(object)
    failed = Signal(object, str)
    done = Signal()
    _result = Signal(object)
    _error = Signal(object, str)

    def __init__(self, func: Callable[..., Any], *args: Any, name: str = "") -> None:
        super().__init__()
        self._func = func
        self._args = args
        self.name = name or getattr(func, "__name__", "task")
        self.setObjectName(self.name)
        queued = Qt.ConnectionType.QueuedConnection
        self._result.connect(self.succeeded, queued)
        self._error.connect(self.failed, queued)
        self.finished.connect(self.done, queued)

    def run(self) -> None:  # runs on the task's thread
        try:
            result = self._func(*self._args)
        except BaseException as exc:  # noqa: BLE001 - reported to the UI, never raised there
            self._error.emit(exc, traceback.format_exc())
            return
        self._result.emit(result)


class TaskPool(QObject):
    """Starts :class:`Task` objects and holds them until they have finished."""

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._tasks: set[Task] = set()

    def start(self, func: Callable[..., Any], *args: Any,
              on_done: Callable[[Any], None] | None = None,
              on_error: Callable[[BaseException, str], None] | None = None,
              name: str = "") -> Task:
        """Run ``func(*args)`` off the UI thread; the callbacks run on the UI thread."""
        task = Task(func, *args, name=name)
        if on_done is not None:
            task.succeeded.connect(on_done)
        if on_error is not None:
            task.failed.connect(on_error)
        task.done.connect(lambda t=task: self._forget(t))
        self._tasks.add(task)
        task.start()
        return task

    def _forget(self, task: Task) -> None:
        if task in self._tasks:
            self._tasks.discard(task)
            task.wait()  # already finished: returns at once
            task.deleteLater()

    @property
    def busy(self) -> bool:
        return bool(self._tasks)

    def running(self) -> list[str]:
        return sorted(t.name for t in self._tasks)

    def wait_all(self, timeout_ms: int = 30000) -> bool:
        """Block until every task has finished (used only when the window closes)."""
        ok = True
        for task in list(self._tasks):
            ok = task.wait(timeout_ms) and ok
        return ok
