"""Bench panel: each instrument's identity, connection state, settings and interlocks, and a
safe-state button that always works.

During a run the panel follows the runner's state events; afterwards it shows the state the
runner read back from each instrument after the safe state (and the identities from the run
file). Between runs, "Check bench" opens each instrument through its plugin, reads identity,
settings, state and interlocks, puts it in its safe state and closes it again. "Safe state"
asks a running run to abort (the runner safes the bench, amplifier first); with no run, it opens
each instrument and calls its ``safe_state()`` in the runner's order. Both happen off the UI
thread.
"""

from __future__ import annotations

from typing import Any, Callable

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import (
    QFormLayout,
    QGroupBox,
    QLabel,
    QPushButton,
    QScrollArea,
    QVBoxLayout,
    QWidget,
)

from fsi_lab.bench_access import OPEN_ORDER, probe_bench, problems, safe_bench
from fsi_lab.events import StateChanged
from fsi_lab.gui.excitation_designer import changed_overrides
from fsi_lab.gui.figure import FlowLayout
from fsi_lab.gui.forms import ParamForm
from fsi_lab.gui.session import ProfileSession
from fsi_lab.gui.worker import TaskPool
from fsi_lab.profile import Profile
from fsi_lab.registry import Registry

LED_CLEAR = "background: #c8e6c9; color: #1b5e20; border-radius: 3px; padding: 1px 4px;"
LED_TRIPPED = "background: #d32f2f; color: white; border-radius: 3px; padding: 1px 4px;"
LED_UNKNOWN = "background: #e0e0e0; color: #616161; border-radius: 3px; padding: 1px 4px;"

RUN_STATES = {
    "configuring": "opening for the run",
    "armed": "in use by the run (output enabled)",
    "running": "in use by the run (output enabled)",
    "finalizing": "safe state requested by the run",
}


class InstrumentBox(QGroupBox):
    """One instrument role: plugin, address, identity, state, interlocks and settings form."""

    def __init__(self, role: str, profile: Profile, registry: Registry) -> None:
        config = profile.roles[role]
        super().__init__(f"{role}: {config.plugin}")
        self.role = role
        self.setObjectName(f"instrument:{role}")
        descriptor = registry.get("instrument", config.plugin)
        self.identity = QLabel("not read yet")
        self.identity.setWordWrap(True)
        self.identity.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.state = QLabel("not connected")
        self.state.setWordWrap(True)
        self.state.setObjectName(f"state:{role}")
        self.interlock_row = FlowLayout(spacing=4, line_spacing=3)  # wraps in a narrow column
        self.interlocks: dict[str, QLabel] = {}
        self.form = ParamForm(descriptor.params, config.settings, f"bench.{role}")
        self.base_settings = dict(config.settings)
        form = QFormLayout(self)
        form.setRowWrapPolicy(QFormLayout.RowWrapPolicy.WrapLongRows)  # narrow: value below
        address = QLabel(config.address or "(default)")
        address.setWordWrap(True)
        address.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        form.addRow("address", address)
        form.addRow("identity", self.identity)
        form.addRow("state", self.state)
        if role == "amplifier":
            holder = QWidget()
            holder.setLayout(self.interlock_row)
            self.interlock_row.setContentsMargins(0, 0, 0, 0)
            self.interlock_note = QLabel("not read yet")
            self.interlock_row.addWidget(self.interlock_note)
            form.addRow("interlocks", holder)
        form.addRow(self.form)

    def show_interlocks(self, interlocks: dict[str, bool]) -> None:
        """Indicators for every known interlock; red when tripped."""
        if self.role != "amplifier":
            return
        self.interlock_note.setVisible(False)
        for name, tripped in interlocks.items():
            led = self.interlocks.get(name)
            if led is None:
                led = QLabel(name.replace("_", " "))
                led.setObjectName(f"interlock:{name}")
                self.interlocks[name] = led
                self.interlock_row.addWidget(led)
            led.setStyleSheet(LED_TRIPPED if tripped else LED_CLEAR)
            led.setToolTip(f"{name}: {'TRIPPED' if tripped else 'clear'}")
        for name, led in self.interlocks.items():
            if name not in interlocks:
                led.setStyleSheet(LED_CLEAR)

    def show_state(self, state: dict[str, Any]) -> None:
        parts = []
        for key, value in state.items():
            if key == "interlocks":
                continue
            if isinstance(value, bool):
                value = "on" if value else "off"
            parts.append(f"{key.replace('_', ' ')}: {value}")
        self.state.setText(", ".join(parts) or "ok")
        error = state.get("error") or state.get("safe_state_error")
        self.state.setStyleSheet("color: #b00020;" if error else "")
        if "interlocks" in state and isinstance(state["interlocks"], dict):
            active = state["interlocks"]
            known = {name: bool(active.get(name, False)) for name in self.interlocks}
            known.update({name: bool(value) for name, value in active.items()})
            self.show_interlocks(known)


class BenchPanel(QWidget):
    """All instruments of the open profile, "Check bench" and the safe-state button.

    ``safe_requested`` is emitted when the safe-state button is pressed during a run (the main
    window aborts the run); otherwise the panel safes the bench itself.
    """

    safe_requested = Signal()
    message = Signal(str, str)  # level, text

    def __init__(self, session: ProfileSession, pool: TaskPool,
                 run_active: Callable[[], bool] = lambda: False,
                 parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.session = session
        self.pool = pool
        self.run_active = run_active
        self.boxes: dict[str, InstrumentBox] = {}
        self.last_report: dict[str, dict[str, Any]] = {}
        self.safe_button = QPushButton("SAFE STATE")
        self.safe_button.setObjectName("safe-state")
        self.safe_button.setToolTip("Amplifier output off and source at 0 V, now. During a run "
                                    "this aborts the run; the data so far is kept.")
        self.safe_button.setMinimumHeight(40)
        self.safe_button.setStyleSheet(
            "QPushButton { background: #c62828; color: white; font-weight: bold; }")
        self.safe_button.clicked.connect(self.safe_state)
        self.check_button = QPushButton("Check bench")
        self.check_button.setToolTip("Connect to each instrument, read identity, settings and "
                                     "interlocks, then leave it safe and closed.")
        self.check_button.clicked.connect(self.check)
        self.check_button.setEnabled(False)
        self.status = QLabel("Open a profile to see its bench.")
        self.status.setWordWrap(True)
        self.boxes_widget = QWidget()
        self.boxes_layout = QVBoxLayout(self.boxes_widget)
        self.boxes_layout.addStretch(1)
        scroll = QScrollArea()
        scroll.setWidgetResizable(True)
        scroll.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.setMinimumWidth(260)
        scroll.setWidget(self.boxes_widget)
        layout = QVBoxLayout(self)
        layout.addWidget(self.safe_button)
        layout.addWidget(self.check_button)
        layout.addWidget(self.status)
        layout.addWidget(scroll, 1)
        session.opened.connect(self._opened)

    # ------------------------------------------------------------------ profile
    def _opened(self, profile: Profile) -> None:
        for box in self.boxes.values():
            box.deleteLater()
        self.boxes.clear()
        for role in OPEN_ORDER:
            if role not in profile.roles:
                continue
            box = InstrumentBox(role, profile, self.session.registry)
            box.form.changed.connect(lambda b=box: self._settings_changed(b))
            self.boxes_layout.insertWidget(self.boxes_layout.count() - 1, box)
            self.boxes[role] = box
        self.check_button.setEnabled(bool(self.boxes))
        self.status.setText(f"{len(self.boxes)} instruments in {profile.path}"
                            if self.boxes else "This profile describes no bench.")

    def _settings_changed(self, box: InstrumentBox) -> None:
        self.session.set_overrides(
            f"bench.{box.role}",
            changed_overrides(box.form, box.base_settings, f"bench.{box.role}"))

    def forms_valid(self) -> bool:
        return all(box.form.is_valid() for box in self.boxes.values())

    # ------------------------------------------------------------------ actions
    def _profile(self) -> Profile | None:
        checked = self.session.current
        if checked is not None and checked.profile is not None:
            return checked.profile
        return self.session.base

    def check(self) -> None:
        profile = self._profile()
        if profile is None or self.run_active():
            return
        self.status.setText("checking the bench ...")
        self.check_button.setEnabled(False)
        self.pool.start(probe_bench, profile, self.session.registry,
                        on_done=lambda report: self._show_report(report, "checked"),
                        on_error=self._failed, name="check bench")

    def safe_state(self) -> None:
        """Safe the bench now: abort the run if one is active, else safe every instrument."""
        if self.run_active():
            self.status.setText("safe state: aborting the run ...")
            self.safe_requested.emit()
            return
        profile = self._profile()
        if profile is None:
            self.message.emit("WARNING", "No profile is open: there is no bench to put in its "
                                         "safe state.")
            return
        self.status.setText("putting the bench in its safe state ...")
        self.pool.start(safe_bench, profile, self.session.registry,
                        on_done=lambda report: self._show_report(report, "safe state"),
                        on_error=self._failed, name="safe state")

    def _show_report(self, report: dict[str, dict[str, Any]], what: str) -> None:
        self.last_report = report
        errors = [f"{role}: {text}" for role, text in problems(report).items()]
        for role, info in report.items():
            box = self.boxes.get(role)
            if box is None:
                continue
            if "identity" in info:
                box.identity.setText(info["identity"])
            if "interlocks" in info:
                box.show_interlocks(info["interlocks"])
            state = dict(info.get("state", {}))
            for key in ("error", "safe_state_error"):
                if key in info:
                    state[key] = info[key]
            box.show_state(state)
        self.check_button.setEnabled(bool(self.boxes))
        answer = "; ".join(errors) if errors else "all instruments answered"
        self.status.setText(f"{what}: {answer}")
        if errors:
            self.message.emit("ERROR", f"{what}: " + "; ".join(errors))

    def _failed(self, exc: BaseException, text: str) -> None:
        self.check_button.setEnabled(bool(self.boxes))
        self.status.setText(f"failed: {exc}")
        self.message.emit("ERROR", f"bench: {exc}")

    # ------------------------------------------------------------------ run events
    def on_state(self, event: StateChanged) -> None:
        text = RUN_STATES.get(event.state)
        if text is None:
            return
        for box in self.boxes.values():
            box.state.setText(text)
            box.state.setStyleSheet("")
        self.check_button.setEnabled(False)

    def on_run_finished(self, outcome: Any) -> None:
        """Show the states the runner read back after the safe state, and the identities."""
        for role, state in (outcome.final_states or {}).items():
            if role in self.boxes:
                self.boxes[role].show_state(state)
        self.check_button.setEnabled(bool(self.boxes))
        self.status.setText(f"run {outcome.exit_status}: instruments left in their safe state"
                            if outcome.final_states else f"run {outcome.exit_status}")

    def show_identities(self, instruments: dict[str, dict[str, Any]]) -> None:
        """Identities as the run file recorded them (the window passes them on once it has
        read the file: reading it here too could collide with the analysis writing it)."""
        for role, info in instruments.items():
            box = self.boxes.get(role)
            if box is not None and info.get("identity"):
                box.identity.setText(str(info["identity"]))
