"""Excitation designer: choose any excitation plugin, set its parameters, see the waveform and
the safety verdict before Start is possible.

The plugin list is the registry's (third-party plugins included); the form is generated from the
chosen plugin's schema; the preview is the waveform :func:`fsi_lab.preflight.check_safety`
generates, and the verdict is its :class:`~fsi_lab.safety.SafetyReport`, both computed off the
UI thread by :class:`~fsi_lab.gui.session.ProfileSession`.
"""

from __future__ import annotations

from typing import Any

import pyqtgraph as pg
from PySide6.QtCore import Qt
from PySide6.QtWidgets import (
    QComboBox,
    QFormLayout,
    QGroupBox,
    QLabel,
    QSizePolicy,
    QVBoxLayout,
    QWidget,
)

from fsi_lab.gui.forms import ParamForm
from fsi_lab.gui.session import Checked, ProfileSession
from fsi_lab.profile import RUN_PARAMS, Profile

OK_STYLE = "background: #e3f4e1; color: #1b5e20; padding: 4px; border-radius: 3px;"
BAD_STYLE = "background: #fde7ea; color: #b00020; padding: 4px; border-radius: 3px;"
WAIT_STYLE = "background: #f1f1f1; color: #555; padding: 4px; border-radius: 3px;"


def changed_overrides(form: ParamForm, base: dict[str, Any], section: str,
                      everything: bool = False) -> list[str]:
    """Overrides for the values of ``form`` that differ from ``base`` (all with ``everything``)."""
    items = []
    for name, field in form.fields.items():
        if field.value is None and field.param.required:
            continue
        if everything or name not in base or base[name] != field.value:
            items.append(field.override(section))
    return items


class ExcitationDesigner(QWidget):
    """Plugin choice, parameter form, safety verdict, waveform preview and record settings."""

    def __init__(self, session: ProfileSession, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.session = session
        self.registry = session.registry
        self.form: ParamForm | None = None
        self.run_form: ParamForm | None = None

        self.plugin = QComboBox()
        self.plugin.setObjectName("excitation-plugin")
        for name in self.registry.names("excitation"):
            descriptor = self.registry.get("excitation", name)
            self.plugin.addItem(name, name)
            self.plugin.setItemData(self.plugin.count() - 1, descriptor.help,
                                    Qt.ItemDataRole.ToolTipRole)
        self.plugin.currentIndexChanged.connect(self._plugin_changed)
        self.plugin_help = QLabel()
        self.plugin_help.setWordWrap(True)
        self.plugin_help.setStyleSheet("color: #555;")

        self.form_box = QGroupBox("Excitation parameters")
        self.form_layout = QVBoxLayout(self.form_box)
        self.run_box = QGroupBox("Record")
        self.run_layout = QVBoxLayout(self.run_box)

        self.preview = pg.PlotWidget()
        self.preview.setObjectName("excitation-preview")
        self.preview.setLabel("left", "drive", units="V")
        self.preview.setLabel("bottom", "time", units="s")
        self.preview.showGrid(x=True, y=True, alpha=0.2)
        self.preview.setMinimumHeight(150)
        self.preview.setMaximumHeight(220)
        self.preview.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Preferred)
        self.preview_curve = self.preview.plot(pen=pg.mkPen("#1f77b4", width=1.5))

        self.verdict = QLabel("Open a profile to design an excitation.")
        self.verdict.setObjectName("safety-verdict")
        self.verdict.setWordWrap(True)
        self.verdict.setStyleSheet(WAIT_STYLE)
        self.verdict.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)

        top = QFormLayout()
        top.addRow("Excitation plugin", self.plugin)
        layout = QVBoxLayout(self)
        layout.addLayout(top)
        layout.addWidget(self.plugin_help)
        layout.addWidget(self.form_box)
        # the verdict and the waveform right under the parameters that make them: on a
        # 1366x768 screen they are in view with them, the record's settings and the run below
        layout.addWidget(QLabel("Safety check"))
        layout.addWidget(self.verdict)
        layout.addWidget(QLabel("Waveform sent to the source"))
        layout.addWidget(self.preview)
        layout.addWidget(self.run_box)
        self.setEnabled(False)

        session.opened.connect(self._opened)
        session.checking.connect(self._checking)
        session.checked.connect(self._checked)

    # ------------------------------------------------------------------ profile
    def _opened(self, profile: Profile) -> None:
        self.setEnabled(profile.can_run)
        if self.run_form is not None:
            self.run_form.deleteLater()
        self.run_form = ParamForm(RUN_PARAMS, profile.run, "run")
        self.run_form.changed.connect(self._run_changed)
        self.run_layout.addWidget(self.run_form)
        self.plugin.blockSignals(True)
        index = self.plugin.findData(profile.excitation_plugin)
        self.plugin.setCurrentIndex(max(index, 0))
        self.plugin.blockSignals(False)
        self._build_form(profile.excitation_plugin, profile.excitation)

    def _plugin_changed(self) -> None:
        name = self.plugin.currentData()
        base = self.session.base
        values = base.excitation if base is not None and name == base.excitation_plugin else {}
        self.session.set_excitation_plugin(name)
        self._build_form(name, values)

    def _build_form(self, name: str | None, values: dict[str, Any]) -> None:
        if self.form is not None:
            self.form.deleteLater()
            self.form = None
        if not name:
            return
        descriptor = self.registry.get("excitation", name)
        self.plugin_help.setText(descriptor.help)
        self.form = ParamForm(descriptor.params, values, "excitation")
        self.form.setObjectName("excitation-form")
        self.form.changed.connect(self._form_changed)
        self.form_layout.addWidget(self.form)
        self._form_changed()

    def _form_changed(self) -> None:
        base = self.session.base
        same = base is not None and self.plugin.currentData() == base.excitation_plugin
        overrides = changed_overrides(self.form, base.excitation if same else {}, "excitation",
                                      everything=not same)
        if not self.form.is_valid():
            self._show_refused(self.form.errors())
        self.session.set_overrides("excitation", overrides)

    def _run_changed(self) -> None:
        if not self.run_form.is_valid():
            self._show_refused(self.run_form.errors())
        self.session.set_overrides(
            "run", changed_overrides(self.run_form, self.session.base.run, "run"))

    def _show_refused(self, errors: dict[str, str]) -> None:
        self.verdict.setStyleSheet(BAD_STYLE)
        self.verdict.setText("<br>".join(errors.values()))

    def forms_valid(self) -> bool:
        return all(f is None or f.is_valid() for f in (self.form, self.run_form))

    # ------------------------------------------------------------------ verdict
    def _checking(self) -> None:
        if self.forms_valid():
            self.verdict.setStyleSheet(WAIT_STYLE)
            self.verdict.setText("checking ...")

    def _checked(self, result: Checked) -> None:
        if result.preview is not None:
            t, y = result.preview
            self.preview_curve.setData(t, y)
        else:
            self.preview_curve.setData([], [])
        if not self.forms_valid():
            self._show_refused({**(self.form.errors() if self.form else {}),
                                **(self.run_form.errors() if self.run_form else {})})
            return
        if result.error:
            self.verdict.setStyleSheet(BAD_STYLE)
            self.verdict.setText(result.error)
            return
        r = result.report
        figures = (f"peak drive {r.peak_drive_v:.4g} V (limit {r.max_drive_v:g} V) · "
                   f"gain {r.gain:g} (limit {r.max_gain:g}) · predicted stroke "
                   f"{r.predicted_stroke_mm:.3g} mm (limit {r.max_stroke_mm:g} mm)")
        if r.ok:
            self.verdict.setStyleSheet(OK_STYLE)
            self.verdict.setText(f"<b>safe to start</b>: {figures}")
        else:
            self.verdict.setStyleSheet(BAD_STYLE)
            self.verdict.setText("<b>refused</b>: " + "<br>".join(r.problems) + f"<br>{figures}")
