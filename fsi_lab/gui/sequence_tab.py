"""The Sequence tab: a campaign of runs from a plan, watched as it goes.

Open a plan (or build one: a base profile, one swept parameter, its values, repeats and the
settle time), choose the directory of its run files, and start it. The sequence runs as
``fsi-lab sequence PLAN --out DIR`` in a child process, exactly as on the command line: every
run checked before the first is driven, the bench safe between runs, the record
(``DIR/sequence.h5``) rewritten as it goes. The tab reads that record whenever it changes: each
run's status in the table, the progress bar (runs done of the plan's), and the aggregation of
the completed runs (C_i and C_f with their intervals, and the figures the plugins register for
it through ``fsi_lab_addviews``: fsi-lab's own draw every run's curves on one amplitude axis).

Stop sends the child SIGTERM: the run in progress ends as ``fsi-lab run`` ends it (safe state,
its file finalised) and the sequence is recorded as interrupted. Resume continues it with
``fsi-lab sequence --resume DIR``: the first run that did not complete, none repeated.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import pyqtgraph as pg
from PySide6.QtCore import QProcess, QTimer, Signal
from PySide6.QtWidgets import (
    QDialog,
    QDialogButtonBox,
    QDoubleSpinBox,
    QFileDialog,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QProgressBar,
    QPushButton,
    QSpinBox,
    QSplitter,
    QTableWidget,
    QTableWidgetItem,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from fsi_lab.registry import Registry

#: How often the record is looked at while the sequence runs, ms (it is read when it changed).
POLL_MS = 500
#: How long a stopped sequence may take to end its run safely before it is killed, ms.
STOP_GRACE_MS = 60000
COLUMNS = ("run", "step", "point", "status", "run file", "C_i kg/(m s)", "C_f kg/m^2")


def aggregation_figures(registry: Registry, report) -> list[QWidget]:
    """The widgets of the figures of a sequence's aggregation the plugins register
    (``fsi_lab_addviews``: ``views.add_aggregation_view``), in their order; one that cannot be
    made is left out and ``report(text)`` says why."""
    figures = []
    for descriptor in sorted(registry.views().aggregation_views,
                             key=lambda v: (v.order, v.title)):
        try:
            widget = descriptor.view()
            if not isinstance(widget, QWidget) or not callable(getattr(widget, "draw", None)):
                raise TypeError(f"made a {type(widget).__name__}, not a QWidget with "
                                "draw(aggregate)")
        except Exception as exc:  # noqa: BLE001 - a broken figure must not take the window down
            owner = registry.views().owners.get(("aggregation view", descriptor.title), "?")
            report(f"aggregation figure {descriptor.title!r} of plugin {owner} left out: "
                   f"{type(exc).__name__}: {exc}")
            continue
        widget.title = descriptor.title
        figures.append(widget)
    return figures


def plan_text(profile: str | Path, parameter: str, values: list[str], repeats: int = 1,
              settle_s: float = 0.0, name: str = "") -> str:
    """The TOML text of a plan of one sweep: ``parameter`` (a ``--set`` path) over ``values``
    (as written), each run ``repeats`` times, ``settle_s`` s between runs."""
    def toml_value(text: str) -> str:
        try:
            float(text)
            return text
        except ValueError:
            return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'

    lines = ["[plan]", f'profile = "{Path(profile).as_posix()}"']
    if name:
        lines.append(f'name = "{name}"')
    lines += [f"settle_s = {float(settle_s):g}", "", "[[step]]",
              f'name = "{parameter}"', f"repeats = {int(repeats)}", "[step.sweep]",
              f'"{parameter}" = [{", ".join(toml_value(v.strip()) for v in values)}]', ""]
    return "\n".join(lines)


class PlanBuilder(QDialog):
    """A plan of one sweep: base profile, parameter path, values, repeats, settle time."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("New sequence plan")
        self.profile = QLineEdit()
        browse = QPushButton("Browse ...")
        browse.clicked.connect(self._browse)
        row = QHBoxLayout()
        row.addWidget(self.profile, 1)
        row.addWidget(browse)
        self.parameter = QLineEdit("excitation.height")
        self.values = QLineEdit("0.005, 0.01, 0.015")
        self.repeats = QSpinBox()
        self.repeats.setRange(1, 1000)
        self.repeats.setValue(2)
        self.settle = QDoubleSpinBox()
        self.settle.setRange(0.0, 86400.0)
        self.settle.setSuffix(" s")
        form = QFormLayout(self)
        form.addRow("Base profile", row)
        form.addRow("Swept parameter", self.parameter)
        form.addRow("Values (comma separated)", self.values)
        form.addRow("Repeats of each value", self.repeats)
        form.addRow("Settle between runs", self.settle)
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Save
                                   | QDialogButtonBox.StandardButton.Cancel)
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        form.addRow(buttons)

    def _browse(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Base profile", "",
                                              "Profiles (*.toml);;All files (*)")
        if path:
            self.profile.setText(path)

    def text(self) -> str:
        values = [v for v in self.values.text().split(",") if v.strip()]
        return plan_text(self.profile.text(), self.parameter.text().strip(), values,
                         self.repeats.value(), self.settle.value())


class SequenceTab(QWidget):
    """Open or build a plan, run it, stop and resume it, and watch its runs and aggregation.

    Signals
    -------
    message(level, text)
        For the window's message bar.
    finished(exit_code)
        The sequence's process ended.
    """

    message = Signal(str, str)
    finished = Signal(int)

    def __init__(self, registry: Registry | None = None, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        if registry is None:
            from fsi_lab.registry import load_registry

            registry = load_registry()
        self.process: QProcess | None = None
        self.record = None
        self._mtime: float | None = None
        self._stderr = ""
        self.plan_path = QLineEdit()
        self.plan_path.setPlaceholderText("a sequence plan (.toml)")
        self.out_dir = QLineEdit()
        self.out_dir.setPlaceholderText("directory of the run files and sequence.h5")
        open_plan = QPushButton("Open plan ...")
        open_plan.clicked.connect(self._open_plan_dialog)
        new_plan = QPushButton("New plan ...")
        new_plan.clicked.connect(self._new_plan_dialog)
        choose = QPushButton("Directory ...")
        choose.clicked.connect(self._choose_out)
        self.start_button = QPushButton("Start")
        self.start_button.clicked.connect(self.start)
        self.stop_button = QPushButton("Stop")
        self.stop_button.clicked.connect(self.stop)
        self.resume_button = QPushButton("Resume")
        self.resume_button.clicked.connect(self.resume)
        self.status = QLabel("no sequence")
        self.status.setWordWrap(True)
        self.progress = QProgressBar()
        self.progress.setFormat("%v of %m runs")
        self.summary = QLabel("")
        self.summary.setWordWrap(True)
        self.table = QTableWidget(0, len(COLUMNS))
        self.table.setHorizontalHeaderLabels(COLUMNS)
        self.table.verticalHeader().setVisible(False)
        #: why a figure was left out or failed to draw (shown below the figures)
        self.notes: list[str] = []
        self.figures = aggregation_figures(registry, self.notes.append)
        self.figure_note = QLabel("")
        self.figure_note.setWordWrap(True)
        self.figure_note.setStyleSheet("color: #b00020;")
        if not self.figures:
            self.notes.append("no plugin draws a sequence's aggregation (fsi_lab_addviews: "
                              "views.add_aggregation_view)")
        self.figure_area = QTabWidget()
        for figure in self.figures:
            self.figure_area.addTab(figure, figure.title)
        self.figure_area.tabBar().setVisible(len(self.figures) > 1)
        self._show_notes()

        files = QHBoxLayout()
        files.addWidget(QLabel("Plan"))
        files.addWidget(self.plan_path, 2)
        files.addWidget(open_plan)
        files.addWidget(new_plan)
        files.addWidget(QLabel("Runs in"))
        files.addWidget(self.out_dir, 2)
        files.addWidget(choose)
        controls = QHBoxLayout()
        for button in (self.start_button, self.stop_button, self.resume_button):
            controls.addWidget(button)
        controls.addWidget(self.progress, 1)
        top = QWidget()
        column = QVBoxLayout(top)
        column.addLayout(files)
        column.addLayout(controls)
        column.addWidget(self.status)
        column.addWidget(self.summary)
        column.addWidget(self.table, 1)
        split = QSplitter()
        split.setOrientation(pg.QtCore.Qt.Orientation.Vertical)
        split.addWidget(top)
        bottom = QWidget()
        below = QVBoxLayout(bottom)
        below.setContentsMargins(0, 0, 0, 0)
        below.addWidget(self.figure_area, 1)
        below.addWidget(self.figure_note)
        split.addWidget(bottom)
        layout = QVBoxLayout(self)
        layout.addWidget(split)
        self.timer = QTimer(self)
        self.timer.setInterval(POLL_MS)
        self.timer.timeout.connect(self.refresh)
        self.plan_path.textChanged.connect(self._update_buttons)
        self.out_dir.textChanged.connect(self._update_buttons)
        self._update_buttons()

    # ------------------------------------------------------------------ plans
    @property
    def running(self) -> bool:
        return self.process is not None and self.process.state() != QProcess.ProcessState.NotRunning

    def open_plan(self, path: str | Path) -> bool:
        """Read the plan (its steps expanded; the runs are checked when it starts)."""
        from fsi_lab.errors import FsiLabError
        from fsi_lab.plan import load_plan

        try:
            plan = load_plan(path)
        except FsiLabError as exc:
            self.message.emit("ERROR", str(exc))
            return False
        self.plan_path.setText(str(path))
        if not self.out_dir.text():
            self.out_dir.setText(str(Path(path).with_suffix("")) + "-runs")
        self.status.setText(f"plan {Path(path).name}: {len(plan.runs)} runs"
                            + (f" ({plan.name})" if plan.name else ""))
        self.progress.setRange(0, len(plan.runs))
        self.progress.setValue(0)
        return True

    def build_plan(self, text: str, path: str | Path) -> bool:
        """Write the plan ``text`` to ``path`` and open it."""
        Path(path).write_text(text, encoding="utf-8")
        return self.open_plan(path)

    def _open_plan_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Open sequence plan", "",
                                              "Plans (*.toml);;All files (*)")
        if path:
            self.open_plan(path)

    def _new_plan_dialog(self) -> None:
        dialog = PlanBuilder(self)
        if dialog.exec() != QDialog.DialogCode.Accepted:
            return
        path, _ = QFileDialog.getSaveFileName(self, "Save the plan", "plan.toml",
                                              "Plans (*.toml)")
        if path:
            self.build_plan(dialog.text(), path)

    def _choose_out(self) -> None:
        path = QFileDialog.getExistingDirectory(self, "Directory of the run files")
        if path:
            self.out_dir.setText(path)

    # ------------------------------------------------------------------ the process
    def start(self) -> bool:
        """Start the plan into the directory (a new sequence)."""
        plan, out = self.plan_path.text().strip(), self.out_dir.text().strip()
        if not plan or not out or self.running:
            return False
        return self._launch(["sequence", plan, "--out", out, "-q"])

    def resume(self) -> bool:
        """Continue the sequence in the directory with its first run that did not complete."""
        out = self.out_dir.text().strip()
        if not out or self.running:
            return False
        return self._launch(["sequence", "--resume", out, "-q"])

    def stop(self) -> None:
        """End the sequence as Ctrl+C would (SIGTERM): the run in progress ends safely."""
        if self.running:
            self.status.setText(self.status.text() + "; stopping (the run in progress ends in "
                                                      "its safe state) ...")
            self.process.terminate()
            QTimer.singleShot(STOP_GRACE_MS, self._kill_if_running)

    def _kill_if_running(self) -> None:
        if self.running:
            self.message.emit("ERROR", "the sequence did not end after Stop: killed; check the "
                                       "bench (fsi-lab safe PROFILE)")
            self.process.kill()

    def _launch(self, args: list[str]) -> bool:
        process = QProcess(self)
        process.setProgram(sys.executable)
        process.setArguments(["-m", "fsi_lab.cli", *args])
        process.setProcessChannelMode(QProcess.ProcessChannelMode.SeparateChannels)
        process.readyReadStandardError.connect(self._read_stderr)
        process.finished.connect(self._finished)
        self.process = process
        self._stderr = ""
        self._mtime = None
        process.start()
        self.timer.start()
        self.status.setText(f"running: fsi-lab {' '.join(args[:-1])}")
        self._update_buttons()
        return True

    def _read_stderr(self) -> None:
        if self.process is not None:
            self._stderr += bytes(self.process.readAllStandardError()).decode(errors="replace")

    def _finished(self, code: int, _status=None) -> None:
        self._read_stderr()
        self.timer.stop()
        self.refresh(force=True)
        errors = [line.removeprefix("fsi-lab: error: ") for line in self._stderr.splitlines()
                  if line.startswith("fsi-lab: error: ")]
        if errors:
            self.message.emit("ERROR", errors[-1])
        elif code not in (0,):
            state = self.record.attrs.get("status") if self.record is not None else "?"
            why = self.record.attrs.get("error", "") if self.record is not None else ""
            self.message.emit("WARNING", f"the sequence ended {state} (exit code {code})"
                                         + (f": {why}" if why else ""))
        self._update_buttons()
        self.finished.emit(code)

    def wait(self, ms: int = STOP_GRACE_MS) -> None:
        """Stop a running sequence and wait for it to end (closing the window)."""
        if self.running:
            self.stop()
            if not self.process.waitForFinished(ms):
                self.process.kill()
                self.process.waitForFinished(ms)

    def _update_buttons(self) -> None:
        running = self.running
        have = bool(self.plan_path.text().strip()) and bool(self.out_dir.text().strip())
        self.start_button.setEnabled(have and not running)
        self.stop_button.setEnabled(running)
        self.resume_button.setEnabled(bool(self.out_dir.text().strip()) and not running)

    # ------------------------------------------------------------------ the record
    def refresh(self, force: bool = False) -> bool:
        """Read the record if it changed; True when it was read."""
        from fsi_lab.errors import FsiLabError
        from fsi_lab.seqfile import SEQUENCE_FILE, load_record

        path = Path(self.out_dir.text().strip() or ".") / SEQUENCE_FILE
        try:
            mtime = path.stat().st_mtime_ns
        except OSError:
            return False
        if mtime == self._mtime and not force:
            return False
        try:
            record = load_record(path.parent)
        except FsiLabError:  # being replaced: read it at the next look
            return False
        self._mtime = mtime
        self.show_record(record)
        return True

    def show_record(self, record) -> None:
        """The record's runs in the table and its aggregation in the plots."""
        self.record = record
        runs = record.runs
        done = sum(1 for e in runs if e["status"] in ("completed", "failed", "aborted",
                                                      "skipped"))
        self.progress.setRange(0, len(runs))
        self.progress.setValue(done)
        attrs = record.attrs
        text = f"{attrs['status']}: {record.counts()['completed']} of {len(runs)} runs completed"
        if attrs.get("error"):
            text += f" ({attrs['error']})"
        if attrs.get("stopped_early"):
            text += f"; {attrs['stopped_early']}"
        self.status.setText(text)
        self.table.setRowCount(len(runs))
        results = _run_results(record.aggregate)
        for row, entry in enumerate(runs):
            point = ", ".join(f"{k}={v}" for k, v in (entry.get("point") or {}).items())
            if entry.get("repeats", 1) > 1:
                point += f" ({entry['repeat']} of {entry['repeats']})"
            own = results.get(entry["index"], {})
            cells = (str(entry["index"]), str(entry["step"]), point, entry["status"],
                     entry["run_file"], _value(own, "c_i"), _value(own, "c_f"))
            for col, value in enumerate(cells):
                self.table.setItem(row, col, QTableWidgetItem(value))
        self.table.resizeColumnsToContents()
        self._draw(record.aggregate)

    def _draw(self, agg: dict[str, Any] | None) -> None:
        from fsi_lab.aggregate import main_mode

        mode = main_mode(agg)
        if mode is None:
            self.summary.setText("")
        else:
            lines = []
            for m in agg["modes"]:
                if "c_i" in m:
                    lines.append(f"{m['frequency_hz']:.4g} Hz ({m['runs']} runs): C_i = "
                                 f"{m['c_i']:.4g} kg/(m s) (95 %: {m['c_i_ci95'][0]:.4g} to "
                                 f"{m['c_i_ci95'][1]:.4g}), C_f = {m['c_f']:.4g} kg/m^2 (95 %: "
                                 f"{m['c_f_ci95'][0]:.4g} to {m['c_f_ci95'][1]:.4g})")
            self.summary.setText("aggregate: " + "; ".join(lines) + f" — plotted: "
                                 f"{mode['frequency_hz']:.4g} Hz" if lines else "")
        failed = []
        for figure in self.figures:
            try:
                figure.draw(agg)
            except Exception as exc:  # noqa: BLE001 - a plugin's figure must not take the tab down
                failed.append(f"cannot draw {figure.title!r}: {type(exc).__name__}: {exc}")
        self._show_notes(failed)

    def _show_notes(self, more: list[str] = ()) -> None:
        text = "; ".join([*self.notes, *more])
        self.figure_note.setText(text)
        self.figure_note.setVisible(bool(text))

def _run_results(agg: dict[str, Any] | None) -> dict[int, dict[str, Any]]:
    """Each run's own C_i and C_f of the aggregation's largest mode, by run index."""
    from fsi_lab.aggregate import main_mode

    mode = main_mode(agg)
    if mode is None:
        return {}
    indices = agg.get("sequence_runs") or []
    return {indices[r["run"]]: r for r in mode.get("per_run", []) if r["run"] < len(indices)}


def _value(entry: dict[str, Any], key: str) -> str:
    value = entry.get(key)
    return "" if value is None else f"{value:.4g}"

