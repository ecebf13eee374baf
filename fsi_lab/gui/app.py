"""The main window of ``fsi-lab gui`` and its entry point.

Layout: the bench panel (with the safe-state button) docked on the left, the log docked at the
bottom, and four tabs: Experiment (excitation designer, run control, live plots), Analysis (the
views of the current run and its parameters), Runs (open run files, compare, export) and
Sequence (a plan's runs, stop and resume, their aggregation as they complete).
Messages (a file that cannot be read, an instrument lost, a refused run) appear in a bar above
the tabs and in the log; the application keeps running.
"""

from __future__ import annotations

import gc
import os
import signal
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import pyqtgraph as pg
from PySide6.QtCore import QCoreApplication, QEvent, QEventLoop, Qt, QTimer, qInstallMessageHandler
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import (
    QApplication,
    QDockWidget,
    QFileDialog,
    QFrame,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QMainWindow,
    QPushButton,
    QScrollArea,
    QSplitter,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from fsi_lab.events import LogRecord
from fsi_lab.gui.analysis.tab import AnalysisViews
from fsi_lab.gui.bench_panel import BenchPanel
from fsi_lab.gui.display import window_problem
from fsi_lab.gui.excitation_designer import ExcitationDesigner
from fsi_lab.gui.figure import Figure
from fsi_lab.gui.live_plots import LivePlots
from fsi_lab.gui.results import RunResults
from fsi_lab.gui.run_control import LogPanel, RunControl
from fsi_lab.gui.runs_browser import RunsBrowser
from fsi_lab.gui.sequence_tab import SequenceTab
from fsi_lab.gui.session import ProfileSession
from fsi_lab.gui.worker import EventForwarder, TaskPool
from fsi_lab.registry import Registry, load_registry

RUN_SUFFIXES = (".h5", ".hdf5", ".hdf")
#: Initial width of the left column (bench, and the log under it) and height of the log, in
#: pixels (both can be dragged).
BENCH_DOCK_WIDTH = 300
LOG_DOCK_HEIGHT = 190
#: The window's size when the screen has room for it; a smaller screen gets a window that fits.
PREFERRED_SIZE = (1680, 1050)
#: The size ``--screenshot`` renders at unless ``--size`` says otherwise: a common laptop screen.
SCREENSHOT_SIZE = (1366, 768)
BAR_STYLES = {
    "ERROR": "background: #fde7ea; color: #b00020; border: 1px solid #f3b6bf;",
    "WARNING": "background: #fff4e0; color: #8a4b00; border: 1px solid #f5cf8f;",
    "INFO": "background: #e8f1fb; color: #0d47a1; border: 1px solid #b5cdef;",
}


class MessageBar(QFrame):
    """The latest message for the experimenter, dismissable; every message is kept."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("message-bar")
        self.messages: list[tuple[str, str]] = []
        self.text = QLabel()
        self.text.setWordWrap(True)
        self.text.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        close = QPushButton("Dismiss")
        close.clicked.connect(self.hide)
        layout = QHBoxLayout(self)
        layout.setContentsMargins(8, 4, 8, 4)
        layout.addWidget(self.text, 1)
        layout.addWidget(close)
        self.hide()

    def show_message(self, level: str, text: str) -> None:
        self.messages.append((level, text))
        self.setStyleSheet(f"#message-bar {{ {BAR_STYLES.get(level, BAR_STYLES['INFO'])} }}")
        self.text.setText(f"<b>{level.lower()}</b>: {text}")
        self.show()


class MainWindow(QMainWindow):
    """The fsi-lab desktop: experiment, analysis and runs, on the core's runner and events."""

    def __init__(self, registry: Registry | None = None, out_dir: str | Path = "runs",
                 parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("fsi-lab")
        self.registry = registry if registry is not None else load_registry()
        self.pool = TaskPool(self)
        self.forwarder = EventForwarder(self)
        self.session = ProfileSession(self.registry, self.pool, self)
        self._closing = False
        self._run_profile: Any = None
        self._show_when_loaded: set[Path] = set()
        self._front_when_loaded: set[Path] = set()  # shown on the Analysis tab once loaded
        self.last_run: Path | None = None

        self.messages = MessageBar()
        self.log = LogPanel()
        self.designer = ExcitationDesigner(self.session)
        self.run_control = RunControl(self.session, self.forwarder, ready=self._forms_valid,
                                      out_dir=out_dir)
        self.bench = BenchPanel(self.session, self.pool,
                                run_active=lambda: self.run_control.running)
        self.live = LivePlots()
        self.analysis = AnalysisViews(self.registry, self.pool)
        self.runs = RunsBrowser(self.registry, self.pool)
        self.sequence = SequenceTab(self.registry)
        self._build_layout()
        self._build_menu()
        self._connect()
        self.registry.check_hooks()
        for record in self.registry.records:
            if record.warning():
                self.log.add(LogRecord("WARNING", record.warning()))
        for problem in self.analysis.problems:
            self.log.add(LogRecord("WARNING", problem))

    # ------------------------------------------------------------------ layout
    def _build_layout(self) -> None:
        run_box = QGroupBox("Run")
        QVBoxLayout(run_box).addWidget(self.run_control)
        design = QWidget()
        column = QVBoxLayout(design)
        column.addWidget(self.designer)
        column.addWidget(run_box)
        column.addStretch(1)
        scroll = QScrollArea()
        scroll.setWidgetResizable(True)
        scroll.setWidget(design)
        scroll.setMinimumWidth(340)
        experiment = QSplitter(Qt.Orientation.Horizontal)
        experiment.addWidget(scroll)
        experiment.addWidget(self.live)
        experiment.setStretchFactor(0, 1)
        experiment.setStretchFactor(1, 3)
        self.tabs = QTabWidget()
        self.tabs.setObjectName("main-tabs")
        self.tabs.addTab(experiment, "Experiment")
        self.tabs.addTab(self.analysis, "Analysis")
        self.tabs.addTab(self.runs, "Runs")
        self.tabs.addTab(self.sequence, "Sequence")
        central = QWidget()
        layout = QVBoxLayout(central)
        layout.setContentsMargins(4, 4, 4, 4)
        layout.addWidget(self.messages)
        layout.addWidget(self.tabs, 1)
        self.setCentralWidget(central)

        bench_dock = QDockWidget("Bench", self)
        bench_dock.setObjectName("bench-dock")
        bench_dock.setWidget(self.bench)
        bench_dock.setFeatures(QDockWidget.DockWidgetFeature.DockWidgetMovable
                               | QDockWidget.DockWidgetFeature.DockWidgetFloatable)
        self.addDockWidget(Qt.DockWidgetArea.LeftDockWidgetArea, bench_dock)
        log_dock = QDockWidget("Log", self)
        log_dock.setObjectName("log-dock")
        log_dock.setWidget(self.log)
        # the log under the bench, in the left column: the figures get the window's full height
        self.addDockWidget(Qt.DockWidgetArea.LeftDockWidgetArea, log_dock)
        self.splitDockWidget(bench_dock, log_dock, Qt.Orientation.Vertical)
        self.resizeDocks([bench_dock], [BENCH_DOCK_WIDTH], Qt.Orientation.Horizontal)
        self.resizeDocks([log_dock], [LOG_DOCK_HEIGHT], Qt.Orientation.Vertical)
        self.status_label = QLabel(f"{sum(len(v) for v in self.registry.descriptors.values())} "
                                   "plugins loaded")
        self.statusBar().addPermanentWidget(self.status_label)

    def _build_menu(self) -> None:
        menu = self.menuBar().addMenu("&File")
        for text, shortcut, slot in (
                ("Open &profile ...", QKeySequence.StandardKey.Open, self._open_profile_dialog),
                ("Open &runs ...", None, self.runs._open_dialog),
                ("&Quit", QKeySequence.StandardKey.Quit, self.close)):
            action = QAction(text, self)
            if shortcut is not None:
                action.setShortcut(shortcut)
            action.triggered.connect(slot)
            menu.addAction(action)
        bench = self.menuBar().addMenu("&Bench")
        safe = QAction("&Safe state", self)
        safe.setShortcut(QKeySequence("Ctrl+Shift+S"))
        safe.triggered.connect(self.bench.safe_state)
        bench.addAction(safe)

    def _connect(self) -> None:
        f = self.forwarder
        f.data.connect(self.live.on_block)
        f.log.connect(self.log.add)
        f.state.connect(self.bench.on_state)
        self.session.open_failed.connect(lambda text: self.notify("ERROR", text))
        self.session.checked.connect(self._checked)
        self.run_control.started.connect(self._run_started)
        self.run_control.finished.connect(self._run_finished)
        self.run_control.refused.connect(lambda text: self.notify("ERROR", f"run refused: {text}"))
        self.bench.safe_requested.connect(self.run_control.abort)
        self.bench.message.connect(self.notify)
        self.runs.loaded.connect(self._run_loaded)
        self.runs.selected.connect(self._show_run)
        self.runs.failed.connect(self._run_failed)
        self.analysis.message.connect(self.notify)
        self.sequence.message.connect(self.notify)
        self.analysis.reanalysed.connect(self._reanalysed)
        self.analysis.analysis_failed.connect(lambda path: self.open_runs([path], show=True))

    # ------------------------------------------------------------------ messages
    def notify(self, level: str, text: str) -> None:
        """Show a message in the bar and the log; never modal, never fatal."""
        self.messages.show_message(level, text)
        self.log.add(LogRecord(level, text))
        self.statusBar().showMessage(text.splitlines()[0][:200], 10000)

    def _checked(self, checked: Any) -> None:
        self.run_control.update_buttons()
        profile = checked.profile
        if profile is not None and profile.channels and not self.run_control.running:
            # lay out the live plots now: building them at Start would pause the window
            self.live.configure({name: c.unit for name, c in profile.channels.items()},
                                profile.run["sample_rate"])

    def _forms_valid(self) -> bool:
        return self.designer.forms_valid() and self.bench.forms_valid()

    # ------------------------------------------------------------------ opening
    def open_paths(self, paths: list[str | Path]) -> None:
        """Open profiles (TOML) and run files (HDF5) given on the command line. The first run
        file is shown in the Analysis tab, which comes to the front unless a profile was given
        too (then the Experiment tab stays); the others are listed in the Runs tab. A folder
        gives its run files; a sequence's folder, or its record (``sequence.h5``, which a glob
        of the folder catches), also its record in the Sequence tab."""
        from fsi_lab.seqfile import SEQUENCE_FILE, is_sequence_record

        runs, profiles = [], 0
        for path in paths:
            path = Path(path)
            if path.is_dir():
                found = sorted(p for p in path.glob("*.h5") if not is_sequence_record(p))
                if (path / SEQUENCE_FILE).is_file():
                    self._show_sequence(path)
                elif not found:
                    self.notify("ERROR", f"{path}: a folder with no run file (*.h5) in it; "
                                         "expected a profile (.toml), run files (.h5) or the "
                                         "folder of a sequence")
                runs.extend(found)
            elif is_sequence_record(path):
                self._show_sequence(path.parent)
            elif path.suffix.lower() in RUN_SUFFIXES or self._looks_like_hdf5(path):
                runs.append(path)
            else:
                profiles += 1
                self.open_profile(path)
        if runs:
            if not profiles:
                self._front_when_loaded.add(Path(runs[0]).resolve())
            self.open_runs(runs[:1], show=True)
            self.open_runs(runs[1:], show=False)

    def _show_sequence(self, folder: Path) -> None:
        """The sequence recorded in ``folder`` in the Sequence tab (its runs are opened as
        run files)."""
        self.sequence.out_dir.setText(str(folder))
        if not self.sequence.refresh(force=True):
            self.notify("ERROR", f"{folder}: its sequence record cannot be read")
            return
        self.notify("INFO", f"{folder}: a sequence's folder: its record is in the Sequence "
                            "tab, its runs in the Runs tab")

    @staticmethod
    def _looks_like_hdf5(path: Path) -> bool:
        try:
            with path.open("rb") as handle:
                return handle.read(8) == b"\x89HDF\r\n\x1a\n"
        except OSError:
            return False

    def open_profile(self, path: str | Path) -> bool:
        ok = self.session.open(path)
        if ok:
            self.setWindowTitle(f"fsi-lab — {Path(path).name}")
            self.tabs.setCurrentIndex(0)
        return ok

    def open_runs(self, paths: list[str | Path], show: bool = True) -> None:
        resolved = [Path(p).resolve() for p in paths]
        if show:
            self._show_when_loaded.update(resolved)
        self.runs.open(resolved)

    def _open_profile_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Open profile", "",
                                              "Profiles (*.toml);;All files (*)")
        if path:
            self.open_profile(path)

    # ------------------------------------------------------------------ runs
    def _run_started(self, profile: Any) -> None:
        self._run_profile = profile
        self.live.configure({name: c.unit for name, c in profile.channels.items()},
                            profile.run["sample_rate"])
        self.messages.hide()
        self.tabs.setCurrentIndex(0)

    def _run_finished(self, outcome: Any) -> None:
        self.bench.on_run_finished(outcome)
        kept = f" The data acquired so far is kept in {outcome.path}." if outcome.path else ""
        if outcome.exit_status == "failed" and outcome.path is None and not outcome.final_states:
            # the run process died before it could make the bench safe: do it from here
            self.notify("ERROR", f"run failed: {outcome.error}. Putting the bench in its safe "
                                 "state now.")
            self.bench.safe_state()
        elif outcome.exit_status == "failed":
            self.notify("ERROR", f"run failed: {outcome.error}. The bench was put in its safe "
                                 f"state.{kept}")
        elif outcome.exit_status == "aborted":
            self.notify("WARNING", f"run aborted ({outcome.error}); the bench is in its safe "
                                   f"state.{kept}")
        elif getattr(outcome, "stopped_early", False):
            self.notify("INFO", f"run stopped early: the bench is in its safe state and the "
                                f"shortened record is a completed run ({outcome.path}).")
        if outcome.path is not None:
            self.last_run = Path(outcome.path).resolve()
            chain = self._run_profile.analysis["chain"] if self._run_profile else []
            if outcome.exit_status == "completed" and chain and not self._closing \
                    and self.analysis.analyse(outcome.path):  # it applies the run's overrides
                # the file is read once the analysis has written to it (HDF5 files are locked
                # while a process writes them)
                self.run_control.state_label.setText(
                    f"{self.run_control.status_text}; analysing ...")
            else:
                self.open_runs([outcome.path], show=True)
        if self._closing:
            QTimer.singleShot(0, self.close)

    def _run_loaded(self, results: RunResults) -> None:
        path = results.path.resolve()
        if path == self.last_run:
            self.bench.show_identities(results.instruments)
        if path in self._show_when_loaded:
            self._show_when_loaded.discard(path)
            self._show_run(results)
            if path in self._front_when_loaded or (
                    path == self.last_run and results.exit_status == "completed"
                    and results.analysis):
                self.tabs.setCurrentWidget(self.analysis)
        self._front_when_loaded.discard(path)

    def _run_failed(self, path: Path, text: str) -> None:
        self._show_when_loaded.discard(Path(path).resolve())
        self._front_when_loaded.discard(Path(path).resolve())
        self.notify("ERROR", text)

    def _show_run(self, results: RunResults) -> None:
        self.analysis.show_results(results)

    def _reanalysed(self, path: Path) -> None:
        if Path(path).resolve() == self.last_run and self.run_control.state == "completed":
            self.run_control.state_label.setText(f"{self.run_control.status_text}; analysed")
        self.open_runs([path], show=True)

    # ------------------------------------------------------------------ closing
    def busy(self) -> bool:
        return self.run_control.running or self.pool.busy or self.analysis.busy

    def closeEvent(self, event) -> None:
        if self.run_control.running:
            # Never leave a bench driving: abort, and close once the runner has made it safe.
            self._closing = True
            self.run_control.abort()
            self.notify("WARNING", "closing: aborting the run first (safe state) ...")
            event.ignore()
            return
        self.sequence.wait()  # a sequence still going ends its run safely first
        self.live.timer.stop()
        self.analysis.stop_drawing()
        self.analysis.wait()
        self.pool.wait_all()
        super().closeEvent(event)

    def dispose(self) -> None:
        """Close the window (it must not be running a run) and delete it, in order: timers and
        drawings stopped, threads finished, then every figure's items (linked axes first, then
        the scene), then the widgets. Nothing is left to signal a deleted plot item."""
        self.close()
        for figure in self.findChildren(pg.GraphicsView):
            if isinstance(figure, Figure):
                figure.release()
            else:
                figure.close()  # pyqtgraph clears its scene
        self.deleteLater()
        QCoreApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete)


def freeze_startup_objects() -> None:
    """Keep the objects built so far (the window, its plots, the plugins) out of the garbage
    collector's full passes, which would otherwise pause the UI thread now and then. For the
    application's own process only: frozen objects are never collected."""
    gc.collect()
    gc.freeze()


#: Qt messages that say nothing to a user, left out of stderr: the offscreen platform (used by
#: ``--screenshot``) cannot pass size hints to a window system it does not have.
QUIET_QT_MESSAGES = frozenset({"This plugin does not support propagateSizeHints()"})


def quiet_qt_messages() -> Callable[[], None]:
    """Leave the :data:`QUIET_QT_MESSAGES` out of Qt's messages; every other message goes
    where it went before (Qt's handler, or the one installed before). Returns a function that
    puts the previous handler back."""
    previous = None

    def handler(mode, context, message) -> None:
        if message in QUIET_QT_MESSAGES:
            return
        if previous is not None:
            previous(mode, context, message)
        else:
            print(message, file=sys.stderr, flush=True)

    previous = qInstallMessageHandler(handler)
    return lambda: qInstallMessageHandler(previous)


def _configure_pyqtgraph() -> None:
    pg.setConfigOptions(background="w", foreground="k", antialias=True)


def _wait_events(app: QApplication, ms: int) -> None:
    """Run the event loop for up to ``ms`` milliseconds (it wakes for every event)."""
    loop = QEventLoop()
    QTimer.singleShot(ms, loop.quit)
    loop.exec()


def wait_until_idle(window: MainWindow, timeout_s: float = 120.0,
                    stop: Callable[[], bool] = lambda: False) -> bool:
    """Process events until nothing is loading or checking (for screenshots), or ``stop()``
    holds (False then)."""
    deadline = time.monotonic() + timeout_s
    app = QApplication.instance()
    while time.monotonic() < deadline and not stop():
        pending = window.runs.pending or window._show_when_loaded
        checking = window.session.loaded and window.session.current is None
        if not window.busy() and not pending and not checking:
            app.processEvents()
            return True
        _wait_events(app, 20)
    return False


def figure_geometry(window: QWidget) -> list[tuple]:
    """Where every figure on screen and each of its plots are (to tell when layouts settle)."""
    out = []
    for view in window.findChildren(pg.GraphicsView):
        if not view.isVisible():
            continue
        origin = view.mapTo(window, view.rect().topLeft())
        out.append((origin.x(), origin.y(), view.width(), view.height()))
        scene = view.scene()
        for item in scene.items() if scene is not None else ():
            if isinstance(item, pg.PlotItem) and item.isVisible():
                out.append(item.geometry().getRect())
    return out


def settle(window: QWidget, passes: int = 500) -> bool:
    """Deliver pending layout, resize and paint events until no figure moves any more (two
    passes in a row leave every figure and plot where it was); False if they never settle."""
    app = QApplication.instance()
    last, stable = None, 0
    for _ in range(passes):
        QCoreApplication.sendPostedEvents()
        app.processEvents()
        now = figure_geometry(window)
        stable = stable + 1 if now == last else 0
        if stable >= 2:
            return True
        last = now
    return False


def take_screenshot(window: MainWindow, path: Path) -> bool:
    """Render the whole window into ``path`` (PNG), once its layouts have settled: the same
    file gives the same picture."""
    if window.analysis.results is not None:
        window.tabs.setCurrentWidget(window.analysis)
        window.analysis.filled()  # every view drawn now
    settle(window)
    path.parent.mkdir(parents=True, exist_ok=True)
    return window.grab().save(str(path))


def _dispose(window: MainWindow) -> None:
    """Delete the window before the interpreter exits (pyqtgraph items must go first)."""
    window.dispose()
    QApplication.instance().processEvents()


#: Exit code of a window closed by Ctrl+C or SIGTERM (as every fsi-lab command's).
EXIT_INTERRUPTED = 130
#: Said on stderr once the window is open and handles Ctrl+C and SIGTERM.
READY = "fsi-lab gui: window open (Ctrl+C or SIGTERM closes it, as its close button does)"
#: How often Python gets to run a signal handler while Qt's event loop holds the thread, ms.
SIGNAL_POLL_MS = 200


class EndOnSignal:
    """Ctrl+C and SIGTERM close the window as its close button does: a run in progress is
    aborted first and the window closes once the bench is in its safe state; a sequence's run
    ends safely. Qt's event loop holds the thread, so a timer lets Python run the handler.
    ``noted``: signals received while the window was being built, acted on at once."""

    def __init__(self, window: MainWindow, noted: Sequence[int] = (), *,
                 interactive: bool = True) -> None:
        self.window = window
        self.received: int | None = None
        self._timer = QTimer()
        self._timer.timeout.connect(lambda: None)
        self._timer.start(SIGNAL_POLL_MS)
        self._previous = {signum: signal.signal(signum, self._close)
                          for signum in (signal.SIGINT, signal.SIGTERM)}
        if noted:
            self._close(noted[0], None)
        elif interactive:
            print(READY, file=sys.stderr, flush=True)

    def _close(self, signum, frame) -> None:
        name = signal.Signals(signum).name
        if self.received is not None:  # the window is closing: say what it waits for
            print(f"fsi-lab gui: {name} received: still closing"
                  + (" (the run is being brought to its safe state)"
                     if self.window.run_control.running else ""), file=sys.stderr, flush=True)
            return
        self.received = signum
        print(f"fsi-lab gui: {name} received: closing"
              + (" (aborting the run to its safe state first)"
                 if self.window.run_control.running else ""), file=sys.stderr, flush=True)
        self.window.notify("WARNING", f"{name} received: closing")
        QTimer.singleShot(0, self.window.close)

    def restore(self) -> None:
        self._timer.stop()
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)


def fitting_size(app: QApplication) -> tuple[int, int]:
    """:data:`PREFERRED_SIZE`, or less where the screen's free area is smaller."""
    screen = app.primaryScreen()
    if screen is None:
        return PREFERRED_SIZE
    free = screen.availableGeometry()
    return min(PREFERRED_SIZE[0], free.width()), min(PREFERRED_SIZE[1], free.height())


def main(args: Any) -> int:
    """``fsi-lab gui [PROFILE | RUN.h5 ...] [--screenshot OUT.png] [--size WxH] [--view
    NAME]``."""
    restore = quiet_qt_messages()
    try:
        return _main(args)
    finally:
        restore()


def _main(args: Any) -> int:
    screenshot = getattr(args, "screenshot", None)
    if QApplication.instance() is None:
        if screenshot is not None:
            # a picture needs no display: Qt draws it offscreen (unless told otherwise)
            os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
        else:
            problem = window_problem()
            if problem is not None:  # Qt would abort the process; say why instead
                print(f"fsi-lab gui: {problem}", file=sys.stderr)
                return 2
    app = QApplication.instance() or QApplication(sys.argv[:1])
    app.setApplicationName("fsi-lab")
    _configure_pyqtgraph()
    paths = list(getattr(args, "paths", None) or [])
    window = MainWindow(out_dir=getattr(args, "out", None) or "runs")
    size = getattr(args, "size", None) or (SCREENSHOT_SIZE if screenshot is not None
                                           else fitting_size(app))
    window.resize(*size)
    window.show()
    freeze_startup_objects()
    held = getattr(args, "signals", None)
    ending = EndOnSignal(window, held.pending if held is not None else (),
                         interactive=screenshot is None)
    window.open_paths(paths)
    view = getattr(args, "view", None)
    idle = True
    if view is not None:  # the run files' tabs exist once they are loaded
        idle = wait_until_idle(window, stop=lambda: ending.received is not None)
        if not window.analysis.show_view(view):
            window.notify("ERROR", f"--view {view}: no view of that title or drawing that "
                                   "analysis for the run shown; its views: "
                                   f"{', '.join(window.analysis.view_titles()) or 'none'}")
    if screenshot is None:
        code = app.exec()
        ending.restore()
        _dispose(window)
        return EXIT_INTERRUPTED if ending.received else code
    idle = idle and wait_until_idle(window, stop=lambda: ending.received is not None)
    ending.restore()
    if ending.received:
        _dispose(window)
        return EXIT_INTERRUPTED
    saved = take_screenshot(window, Path(screenshot))
    errors = [text for level, text in window.messages.messages if level == "ERROR"]
    _dispose(window)
    for text in errors:
        print(f"fsi-lab gui: {text}", file=sys.stderr)
    if not saved:
        print(f"fsi-lab gui: could not write {screenshot}", file=sys.stderr)
        return 1
    if not idle:
        print("fsi-lab gui: timed out waiting for the run files to load", file=sys.stderr)
        return 1
    return 2 if errors else 0
