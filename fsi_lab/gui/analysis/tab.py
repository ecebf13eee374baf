"""AnalysisViews: the Analysis tab (views, channel selector, parameter panel, re-analysis)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtWidgets import (
    QComboBox,
    QHBoxLayout,
    QLabel,
    QScrollArea,
    QSplitter,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from fsi_lab.contract import failed_provider, for_want_of
from fsi_lab.gui.analysis.dataset_browser import DatasetBrowser
from fsi_lab.gui.analysis.datasets import chain_of
from fsi_lab.gui.analysis.generic_view import GenericView
from fsi_lab.gui.analysis.parameters import AnalysisParameters
from fsi_lab.gui.analysis.stepper import Stepper
from fsi_lab.gui.analysis.summary import SummaryView
from fsi_lab.gui.analysis.view import View
from fsi_lab.gui.analysis_job import AnalysisJob
from fsi_lab.gui.figure import scrolled
from fsi_lab.gui.results import RunResults
from fsi_lab.gui.worker import TaskPool
from fsi_lab.registry import Registry


def registered_views(registry: Registry, report) -> list[Any]:
    """The widgets of the views the plugins register (``fsi_lab_addviews``), in the order of
    their tabs; one that cannot be made is left out and ``report(text)`` says why."""
    views = []
    for descriptor in sorted(registry.views().views, key=lambda v: (v.order, v.title)):
        try:
            widget = descriptor.view()
            if not isinstance(widget, QWidget):
                raise TypeError(f"made a {type(widget).__name__}, not a QWidget")
        except Exception as exc:  # noqa: BLE001 - a broken view must not take the window down
            report(f"view {descriptor.title!r} left out: {type(exc).__name__}: {exc}")
            continue
        widget.title = descriptor.title
        widget.analyses = descriptor.analyses
        views.append(widget)
    return views


class AnalysisViews(QWidget):
    """The views of one run, a channel selector and the parameter panel.

    The tabs are the views the plugins register, then a generic view
    (:class:`~fsi_lab.gui.analysis.generic_view.GenericView`) for each analysis of the run
    shown that no registered view draws, then the Results and All datasets tabs.

    Signals: ``reanalysed(path)`` after an analysis was stored, ``analysis_failed(path)``,
    ``message(level, text)``.
    """

    reanalysed = Signal(object)
    analysis_failed = Signal(object)
    message = Signal(str, str)

    def __init__(self, registry: Registry, pool: TaskPool, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.registry = registry
        self.pool = pool
        self.results: RunResults | None = None
        self.job: AnalysisJob | None = None
        self.title = QLabel("No run open: runs appear here when they finish or when you open "
                            "a run file.")
        self.title.setObjectName("analysis-title")
        self.title.setWordWrap(True)
        self.channel = QComboBox()
        self.channel.setObjectName("analysis-channel")
        self.channel.currentIndexChanged.connect(self._redraw)
        self.state = QLabel("")
        self.state.setWordWrap(True)
        self.state.setVisible(False)
        self.problems: list[str] = []
        self.views: list[Any] = registered_views(registry, self.problems.append) + [
            SummaryView(registry), DatasetBrowser()]
        #: generic views, by analysis, made for the runs shown (kept, hidden when not needed)
        self.generic: dict[str, GenericView] = {}
        self.drawn_by_views = registry.views().drawn()
        self.tabs = QTabWidget()
        self.tabs.setObjectName("analysis-tabs")
        for view in self.views:
            self.tabs.addTab(scrolled(view), view.title)
        self._drawn: set[int] = set()  # views drawn for the run and channel shown
        # Draws the figures of the tab shown, then builds the parameter forms of a new run, a
        # slice per turn of the event loop, in that order.
        self.stepper = Stepper(self)
        for view in self.views:  # a view made of parts (the Overview) shares the stepper
            if hasattr(view, "stepper"):
                view.stepper = self.stepper
        self.tabs.currentChanged.connect(self._draw_current)
        # build the figures' plot items in idle time, one view per turn of the event loop
        self._prebuild = [v for v in self.views if hasattr(v, "prebuild")]
        self._prebuild_timer = QTimer(self)
        self._prebuild_timer.setSingleShot(True)
        self._prebuild_timer.timeout.connect(self._prebuild_next)
        self._prebuild_timer.start(200)
        self.parameters = AnalysisParameters(registry)
        self.parameters.rerun.connect(self.rerun)
        bar = QHBoxLayout()
        bar.addWidget(self.title, 1)
        bar.addWidget(QLabel("Channel"))
        bar.addWidget(self.channel)
        # in a scroll area: building the forms of a run does not resize the figures beside them
        parameters = QScrollArea()
        parameters.setWidgetResizable(True)
        parameters.setFrameShape(QScrollArea.Shape.NoFrame)
        parameters.setWidget(self.parameters)
        parameters.setMinimumWidth(250)
        parameters.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        splitter = QSplitter(Qt.Orientation.Horizontal)
        splitter.addWidget(self.tabs)
        splitter.addWidget(parameters)
        splitter.setStretchFactor(0, 4)
        splitter.setStretchFactor(1, 1)
        self.parameters.setMinimumWidth(240)
        layout = QVBoxLayout(self)
        layout.addLayout(bar)
        layout.addWidget(self.state)
        layout.addWidget(splitter, 1)

    def stop_drawing(self) -> None:
        """Cancel drawings scheduled for later turns of the event loop (closing)."""
        self._prebuild.clear()
        self._prebuild_timer.stop()
        self.stepper.cancel()

    def _prebuild_next(self) -> None:
        if self._prebuild and self.results is None:
            self._prebuild.pop(0).prebuild()
            self._prebuild_timer.start(0)

    def view(self, cls: type | str) -> Any:
        """The view of class ``cls``, or titled ``cls``."""
        if isinstance(cls, str):
            return next(v for v in self.views if v.title == cls)
        return next(v for v in self.views if isinstance(v, cls))

    def show_view(self, name: str) -> bool:
        """Show the tab titled ``name``, or else the first that draws the analysis ``name``
        (its own view, or its generic one); False when the run shown has none."""
        shown = [(index, view) for index, view in enumerate(self.views)
                 if self.tabs.isTabVisible(index)]
        found = next((index for index, view in shown if view.title == name), None)
        if found is None:
            found = next((index for index, view in shown
                          if name in getattr(view, "analyses", ())), None)
        if found is None:
            return False
        self.tabs.setCurrentIndex(found)
        return True

    def view_titles(self) -> list[str]:
        """Titles of the tabs shown for the run."""
        return [view.title for index, view in enumerate(self.views)
                if self.tabs.isTabVisible(index)]

    def _show_a_view_with_results(self, results: RunResults) -> None:
        """When the tab shown draws analyses the run does not have, the first tab that draws
        one it has (a run of a third-party analysis opens on its view, not on an empty
        Overview)."""
        present = {plugin for groups in results.analysis.values() for plugin in groups}
        current = self.views[self.tabs.currentIndex()] if self.tabs.currentIndex() >= 0 \
            else None
        if not present or current is None or set(getattr(current, "analyses", present)) & present:
            return
        for index, view in enumerate(self.views):
            if self.tabs.isTabVisible(index) and set(getattr(view, "analyses", ())) & present:
                self.tabs.blockSignals(True)
                self.tabs.setCurrentIndex(index)
                self.tabs.blockSignals(False)
                return

    def _generic_views(self, results: RunResults) -> None:
        """A generic view for each analysis of ``results`` that no registered view draws
        (before the Results tab), shown; those of other runs hidden."""
        wanted = [plugin for groups in results.analysis.values() for plugin in groups
                  if plugin not in self.drawn_by_views]
        wanted = list(dict.fromkeys(wanted))
        added = False
        for name in wanted:
            if name not in self.generic:
                view = self.generic[name] = GenericView(name)
                index = self.views.index(self.view(SummaryView))
                self.views.insert(index, view)
                self.tabs.insertTab(index, scrolled(view), view.title)
                added = True
        for name, view in self.generic.items():
            self.tabs.setTabVisible(self.views.index(view), name in wanted)
        if added:
            self._drawn.clear()

    def show_results(self, results: RunResults) -> None:
        """Show a run (already read off the UI thread).

        Only the title, channel and state are set now; the figures of the Overview are drawn
        one per turn of the event loop, then the parameter forms are built (see
        :attr:`pending` and :meth:`finish`)."""
        self.results = results
        self._generic_views(results)
        self._show_a_view_with_results(results)
        self.title.setText(" — ".join(_title_parts(results)))
        channels = results.analysed_channels() or [
            n for n, c in results.channels.items() if c.quantity in ("velocity", "displacement")
        ] or list(results.channels)
        current = self.channel.currentData()
        self.channel.blockSignals(True)
        self.channel.clear()
        for name in channels:
            self.channel.addItem(name, name)
        if current in channels:
            self.channel.setCurrentIndex(channels.index(current))
        self.channel.blockSignals(False)
        if not results.analysis:
            self.state.setText("not computed: this run file has no analysis results (exit "
                               f"status {results.exit_status}); set the parameters and re-run")
        else:
            errors = _failures(results)
            self.state.setText("failed: " + "; ".join(errors) if errors else "")
        self.state.setVisible(bool(self.state.text()))
        self.state.setStyleSheet("color: #b00020;" if results.analysis and
                                 self.state.text().startswith("failed") else "color: #555;")
        self._redraw()
        # the forms after the figures: the figures are what is looked at first
        self.stepper.cancel(self.parameters)
        self.stepper.add(self.parameters.loading(*chain_of(results, self.registry)),
                         self.parameters)

    @property
    def pending(self) -> bool:
        """Whether figures or the parameter forms of the run shown are still to be built."""
        return self.stepper.pending

    def finish(self) -> None:
        """Build at once what is still pending (tests, screenshots, exports)."""
        self.stepper.finish()

    def _redraw(self) -> None:
        """Views are drawn when shown: the current one now (its figures a slice per turn of
        the event loop), the others on their turn."""
        self._drawn.clear()
        for view in self.views:
            self.stepper.cancel(view)
        self._draw_current()

    def _draw_current(self, *args) -> None:
        self._draw(self.tabs.currentIndex())

    def _draw(self, index: int, now: bool = False) -> None:
        if self.results is None or index < 0 or index in self._drawn:
            return
        self._drawn.add(index)
        view, channel = self.views[index], self.channel.currentData() or ""
        if hasattr(view, "stepper") and not now:
            view.show_results(self.results, channel)  # queues its parts on the stepper
        elif isinstance(view, View) and not now:
            self.stepper.add(view.drawing(self.results, channel), view)
        else:
            view.show_results(self.results, channel)

    def filled(self) -> dict[str, bool]:
        """Whether each view shown for the run shows data (draws the views not drawn yet)."""
        for index in range(len(self.views)):
            self._draw(index, now=True)
        self.finish()
        return {view.title: view.filled for index, view in enumerate(self.views)
                if self.tabs.isTabVisible(index)}

    # ------------------------------------------------------------------ re-analysis
    @property
    def busy(self) -> bool:
        return self.job is not None

    def analyse(self, path: str | Path, overrides: list[str] = ()) -> bool:
        """Run the chain on ``path`` with ``overrides`` in a child process (``fsi-lab analyze``);
        ``reanalysed(path)`` or ``message`` follows. False if an analysis is already running."""
        if self.job is not None:
            return False
        self.job = AnalysisJob(path, list(overrides), self)
        self.job.succeeded.connect(self._job_done)
        self.job.failed.connect(self._job_failed)
        self.parameters.button.setEnabled(False)
        self.parameters.note.setText("analysing (fsi-lab analyze in a separate process) ...")
        self.job.start()
        return True

    def rerun(self, overrides: list[str]) -> None:
        if self.results is not None:
            self.analyse(self.results.path, overrides)

    def wait(self, timeout_ms: int = 30000) -> None:
        if self.job is not None:
            self.job.wait(timeout_ms)

    def _end_job(self) -> None:
        job, self.job = self.job, None
        if job is not None:
            job.deleteLater()
        self.parameters.button.setEnabled(True)

    def _job_done(self, path: Path, summary: object) -> None:
        self._end_job()
        self.parameters.note.setText("analysis stored in the run file")
        self.reanalysed.emit(path)

    def _job_failed(self, path: Path, message: str) -> None:
        self._end_job()
        self.parameters.note.setText(f"failed: {message}")
        self.message.emit("ERROR", f"analysis of {Path(path).name} failed: {message}")
        self.analysis_failed.emit(path)


def _failures(results: RunResults) -> list[str]:
    """Each failed analysis of the run, ``PLUGIN on CHANNEL: why``; those that failed only
    for want of the result of one that failed before them on the channel are named together
    after it, as ``fsi-lab analyze`` prints them, rather than repeating its message."""
    failed = [r for groups in results.analysis.values() for r in groups.values() if not r.ok]
    own = {(r.channel, r.plugin) for r in failed}
    wanting: dict[tuple[str, str], list[str]] = {}
    lines = []
    for r in failed:
        provider = failed_provider(r.error)
        if provider is not None and (r.channel, provider) in own:
            wanting.setdefault((r.channel, provider), []).append(r.plugin)
        else:
            lines.append(f"{r.plugin} on {r.channel}: {r.error}")
    lines.extend(f"{', '.join(plugins)} on {channel}: {for_want_of(provider)}"
                 for (channel, provider), plugins in wanting.items())
    return lines


def _title_parts(results: RunResults) -> list[str]:
    """The run's name (and its file's, when another), its status and when it started; for
    imported data, the file it was imported from and when (a CSV holds no start time)."""
    parts = [f"<b>{results.name}</b>"]
    if results.path.name != results.name:
        parts.append(results.path.name)
    parts.append(results.exit_status)
    started = str(results.attrs.get("start_time", ""))[:19].replace("T", " ")
    if results.attrs.get("kind") == "imported":
        source = Path(str(results.attrs.get("source_file", ""))).name
        parts.append(f"imported{f' from {source}' if source else ''}"
                     f"{f' at {started} UTC' if started else ''}")
    elif started:
        parts.append(f"started {started} UTC")
    return parts
