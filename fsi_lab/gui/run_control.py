"""Run control: start a run, stop it early or abort it, follow its progress, exit status and log.

A run is :meth:`fsi_lab.runner.Runner.run` in a child process followed by a worker thread
(:mod:`fsi_lab.gui.run_process` says why); its events reach the UI through
:class:`~fsi_lab.gui.worker.EventForwarder`. Abort makes the child call :meth:`Runner.abort`: the
runner puts the bench in its safe state (amplifier first), keeps the data acquired so far and
records the exit status in the run file. Stop (enabled only while the excitation and the
acquisition are running) makes the child call :meth:`Runner.stop`: the acquisition ends after
the block in hand, the bench goes to the same safe state, and the shortened record is a
completed run marked ``stopped_early`` ("completed (stopped early)"), analysed like any other.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QFont
from PySide6.QtWidgets import (
    QComboBox,
    QFileDialog,
    QGridLayout,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QPlainTextEdit,
    QProgressBar,
    QPushButton,
    QToolButton,
    QVBoxLayout,
    QWidget,
)

from fsi_lab.events import LogRecord, Progress, StateChanged
from fsi_lab.gui.run_process import RunProcess
from fsi_lab.gui.session import ProfileSession
from fsi_lab.gui.worker import EventForwarder, Task
from fsi_lab.runner import RunOutcome

LEVELS = {"DEBUG": 10, "INFO": 20, "WARNING": 30, "ERROR": 40}
STATUS_STYLE = {
    "completed": "color: #1b5e20; font-weight: bold;",
    "aborted": "color: #e65100; font-weight: bold;",
    "failed": "color: #b00020; font-weight: bold;",
}


class LogPanel(QWidget):
    """The run's log records, filtered by level, bounded in length."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.text = QPlainTextEdit()
        self.text.setReadOnly(True)
        self.text.setMaximumBlockCount(5000)
        self.text.setObjectName("log")
        self.text.setFont(QFont("monospace", 9))
        self.level = QComboBox()
        self.level.addItems(list(LEVELS))
        self.level.setCurrentText("INFO")
        self.records: list[LogRecord] = []
        clear = QPushButton("Clear")
        clear.clicked.connect(self.text.clear)
        bar = QHBoxLayout()
        bar.addWidget(QLabel("Log level"))
        bar.addWidget(self.level)
        bar.addStretch(1)
        bar.addWidget(clear)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addLayout(bar)
        layout.addWidget(self.text, 1)

    def add(self, record: LogRecord) -> None:
        self.records.append(record)
        del self.records[:-5000]
        if LEVELS.get(record.level, 20) >= LEVELS[self.level.currentText()]:
            self.text.appendPlainText(f"[{record.level.lower()}] {record.message}")

    def contents(self) -> str:
        return self.text.toPlainText()


class RunControl(QWidget):
    """Start, stop and abort buttons, the output folder, state, progress and exit status.

    ``ready`` is asked before Start is enabled (the forms hold only accepted values). Signals:
    ``started(profile)``, ``finished(RunOutcome)``, ``refused(message)`` when the run could not
    start (for example the safety check refused it at the last moment).
    """

    started = Signal(object)
    finished = Signal(object)
    refused = Signal(str)

    def __init__(self, session: ProfileSession, forwarder: EventForwarder,
                 ready: Callable[[], bool] = lambda: True, out_dir: str | Path = "runs",
                 parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.session = session
        self.forwarder = forwarder
        self.ready = ready
        self.run_process: RunProcess | None = None
        self.task: Task | None = None
        self.outcome: RunOutcome | None = None
        self.state = "idle"

        self.start_button = QPushButton("Start")
        self.start_button.setObjectName("start")
        self.start_button.setToolTip("Enabled once the safety check has passed.")
        self.start_button.setStyleSheet("QPushButton:enabled { font-weight: bold; }")
        self.abort_button = QPushButton("Abort")
        self.abort_button.setObjectName("abort")
        self.abort_button.setToolTip("Stop now: the bench goes to its safe state and the data "
                                     "acquired so far is kept.")
        self.abort_button.setStyleSheet(
            "QPushButton:enabled { color: #b00020; font-weight: bold; }")
        self.stop_button = QPushButton("Stop")
        self.stop_button.setObjectName("stop")
        self.stop_button.setToolTip("End the acquisition after the current block: the bench "
                                    "goes to its safe state, the shortened record is kept as a "
                                    "completed run (stopped early) and analysed.")
        self.stop_button.setStyleSheet("QPushButton:enabled { font-weight: bold; }")
        self._stopping = False
        self.start_button.clicked.connect(self.start)
        self.stop_button.clicked.connect(self.stop)
        self.abort_button.clicked.connect(self.abort)
        self.out_dir = QLineEdit(str(out_dir))
        self.out_dir.setObjectName("out-dir")
        browse = QToolButton()
        browse.setText("...")
        browse.clicked.connect(self._browse)
        self.state_label = QLabel("idle")
        self.state_label.setObjectName("run-state")
        self.progress = QProgressBar()
        self.progress.setRange(0, 1000)
        self.progress.setFormat("%p%")
        self.progress_text = QLabel("")
        self.exit_label = QLabel("")
        self.exit_label.setObjectName("exit-status")
        self.exit_label.setWordWrap(True)
        self.file_label = QLabel("")
        self.file_label.setWordWrap(True)
        self.file_label.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)

        grid = QGridLayout(self)
        grid.addWidget(self.start_button, 0, 0)
        buttons = QHBoxLayout()
        buttons.addWidget(self.stop_button)
        buttons.addWidget(self.abort_button)
        grid.addLayout(buttons, 0, 1)
        folder = QHBoxLayout()
        folder.addWidget(QLabel("Run files in"))
        folder.addWidget(self.out_dir, 1)
        folder.addWidget(browse)
        grid.addLayout(folder, 1, 0, 1, 2)
        grid.addWidget(QLabel("State"), 2, 0)
        grid.addWidget(self.state_label, 2, 1)
        grid.addWidget(self.progress, 3, 0, 1, 2)
        grid.addWidget(self.progress_text, 4, 0, 1, 2)
        grid.addWidget(QLabel("Exit status"), 5, 0)
        grid.addWidget(self.exit_label, 5, 1)
        grid.addWidget(self.file_label, 6, 0, 1, 2)

        forwarder.state.connect(self._on_state)
        forwarder.progress.connect(self._on_progress)
        session.checking.connect(self.update_buttons)
        session.checked.connect(self.update_buttons)
        self.update_buttons()

    # ------------------------------------------------------------------ buttons
    @property
    def running(self) -> bool:
        return self.task is not None

    def can_start(self) -> bool:
        checked = self.session.current
        return (not self.running and checked is not None and checked.ok and self.ready())

    def can_stop(self) -> bool:
        """Stop is offered only while the excitation and the acquisition are running."""
        return self.running and self.state == "running" and not self._stopping

    def update_buttons(self, *args) -> None:
        self.start_button.setEnabled(self.can_start())
        self.stop_button.setEnabled(self.can_stop())
        self.abort_button.setEnabled(self.running)

    def _browse(self) -> None:
        folder = QFileDialog.getExistingDirectory(self, "Folder for run files", self.out_dir.text())
        if folder:
            self.out_dir.setText(folder)

    # ------------------------------------------------------------------ run
    def start(self) -> bool:
        """Start a run with the checked profile; False if Start is not allowed now."""
        if not self.can_start():
            return False
        profile = self.session.current.profile
        # The analysis runs afterwards as fsi-lab analyze (see fsi_lab.gui.analysis_job).
        self.run_process = RunProcess(profile.text, profile.path, list(profile.overrides),
                                      Path(self.out_dir.text()), self.forwarder)
        self.outcome = None
        self._stopping = False
        self.exit_label.setText("")
        self.exit_label.setStyleSheet("")
        self.file_label.setText("")
        self.progress.setValue(0)
        self.state = "starting"
        self.state_label.setText("starting")
        self.task = Task(self.run_process.follow, name="run")
        self.task.succeeded.connect(self._on_outcome)
        self.task.failed.connect(self._on_error)
        self.task.done.connect(self._on_done)
        self.task.start()
        self.update_buttons()
        self.started.emit(profile)
        return True

    def stop(self) -> bool:
        """Ask the runner to end the acquisition after the current block and keep the record
        as a completed run (stopped early); False if Stop is not possible now."""
        if self.run_process is None or not self.can_stop():
            return False
        self._stopping = True
        self.run_process.stop()
        self.state_label.setText("stopping after the current block ...")
        self.update_buttons()
        return True

    def abort(self) -> None:
        """Ask the runner to stop now (safe state first, data kept)."""
        if self.run_process is not None and self.running:
            self.run_process.abort()
            self.state_label.setText("aborting ...")

    def wait(self, timeout_ms: int = 30000) -> bool:
        """Block until the run's thread has ended (only for closing the window)."""
        return self.task.wait(timeout_ms) if self.task is not None else True

    def _on_state(self, event: StateChanged) -> None:
        self.state = event.state
        if not (self._stopping and event.state == "running"):
            self.state_label.setText(event.state + (f": {event.detail}" if event.detail else ""))
        self.update_buttons()

    @property
    def status_text(self) -> str:
        """The exit status as shown: "completed (stopped early)" for a run stopped early."""
        if self.outcome is None:
            return ""
        status = self.outcome.exit_status
        if status == "completed" and getattr(self.outcome, "stopped_early", False):
            return "completed (stopped early)"
        return status

    def _on_progress(self, event: Progress) -> None:
        self.progress.setValue(int(round(1000 * max(0.0, min(1.0, event.fraction)))))
        self.progress_text.setText(f"{event.stage}: {event.message}" if event.message
                                   else event.stage)

    def _on_outcome(self, outcome: RunOutcome) -> None:
        self.outcome = outcome
        status = outcome.exit_status
        self.exit_label.setText(self.status_text + (f": {outcome.error}" if outcome.error else ""))
        self.exit_label.setStyleSheet(STATUS_STYLE.get(status, ""))
        if outcome.path is not None:
            self.file_label.setText(f"run file: {outcome.path}")
        self.state = status
        self.state_label.setText(self.status_text)

    def _on_error(self, exc: BaseException, text: str) -> None:
        self.state = "refused"
        self.state_label.setText("not started")
        self.exit_label.setText(str(exc))
        self.exit_label.setStyleSheet(STATUS_STYLE["failed"])
        self.refused.emit(str(exc) or type(exc).__name__)

    def _on_done(self) -> None:
        task, self.task = self.task, None
        if task is not None:
            task.wait()
            task.deleteLater()
        self.update_buttons()
        if self.outcome is not None:
            self.finished.emit(self.outcome)
