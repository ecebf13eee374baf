"""Forms generated from parameter schemas (:class:`fsi_lab.params.Param`).

One widget per parameter: a spin box with the unit as suffix for numbers, a combo box for
choices, a check box for booleans, a line edit for strings, and for lists an editor that wraps
and grows to show every item (an analysis chain is wider than a panel); an "auto" box for optional
parameters (default ``None``), whose editor then reads "auto" rather than a number the plugin
will not use. The help text and the accepted values are the tooltip. Every
edit is checked by the parameter's own :meth:`~fsi_lab.params.Param.check`: a refused value is
shown in red under the field with the schema's message, and the form keeps the last accepted
value, so nothing outside the bounds ever leaves the form.
"""

from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

from PySide6.QtCore import QSize, Qt, Signal
from PySide6.QtGui import QFontMetricsF, QTextOption
from PySide6.QtWidgets import (
    QAbstractSpinBox,
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QPlainTextEdit,
    QSizePolicy,
    QSpinBox,
    QVBoxLayout,
    QWidget,
)

from fsi_lab.errors import ParameterError
from fsi_lab.params import Param

#: Typed numbers are accepted up to this magnitude by the spin box; the schema decides the rest.
WIDE = 1e300
INT_WIDE = 2**31 - 1
ERROR_STYLE = "color: #b00020;"
#: What the editor of an optional parameter left unset reads.
AUTO_TEXT = "auto"
FIELD_ERROR_STYLE = "background: #fde7ea;"


def value_text(param: Param, value: Any) -> str:
    """``value`` as the text ``--set`` (and :meth:`Param.parse`) reads back."""
    if value is None:
        return "auto"
    if param.type == "bool":
        return "true" if value else "false"
    if param.type in ("floats", "strs"):
        return ",".join(repr(float(v)) if param.type == "floats" else str(v) for v in value)
    if param.type == "float":
        return repr(float(value))
    return str(value)


def tooltip(param: Param) -> str:
    unit = f" [{param.unit}]" if param.unit else ""
    lines = [f"<b>{param.name}</b>{unit}"]
    if param.help:
        lines.append(param.help)
    lines.append(f"Accepted: {param.describe()}")
    if not param.required:
        lines.append(f"Default: {value_text(param, param.default)}")
    return "<br>".join(lines)


class _DoubleSpin(QDoubleSpinBox):
    """A spin box that shows numbers compactly (``%g``) and steps within the bounds."""

    def __init__(self, param: Param) -> None:
        super().__init__()
        self._param = param
        self.setDecimals(15)
        self.setRange(-WIDE, WIDE)
        self.setKeyboardTracking(False)
        self.setStepType(QAbstractSpinBox.StepType.AdaptiveDecimalStepType)
        if param.unit:
            self.setSuffix(f" {param.unit}")

    def textFromValue(self, value: float) -> str:
        return f"{value:.10g}"

    def valueFromText(self, text: str) -> float:
        text = text.removesuffix(self.suffix()).strip()
        try:
            return float(text)
        except ValueError:
            return self.value()

    def validate(self, text: str, pos: int):
        from PySide6.QtGui import QValidator

        body = text.removesuffix(self.suffix()).strip()
        if body in ("", "-", "+", ".", "-.", "+.") or body.lower().endswith(("e", "e-", "e+")):
            return QValidator.State.Intermediate, text, pos
        try:
            float(body)
        except ValueError:
            return QValidator.State.Invalid, text, pos
        return QValidator.State.Acceptable, text, pos

    def stepBy(self, steps: int) -> None:
        super().stepBy(steps)
        lo, hi = self._param.minimum, self._param.maximum
        if hi is not None and self.value() > hi:
            self.setValue(hi)
        if lo is not None and self.value() < lo:
            self.setValue(lo)

    def sizeHint(self):
        # the spin box's wide range must not make the box wide
        hint = super().sizeHint()
        hint.setWidth(min(hint.width(), 160))
        return hint

    minimumSizeHint = sizeHint


class _IntSpin(QSpinBox):
    def __init__(self, param: Param) -> None:
        super().__init__()
        self._param = param
        self.setRange(-INT_WIDE, INT_WIDE)
        self.setKeyboardTracking(False)
        if param.unit:
            self.setSuffix(f" {param.unit}")

    def stepBy(self, steps: int) -> None:
        super().stepBy(steps)
        lo, hi = self._param.minimum, self._param.maximum
        if hi is not None and self.value() > hi:
            self.setValue(int(hi))
        if lo is not None and self.value() < lo:
            self.setValue(int(math.ceil(lo)))

    def sizeHint(self):
        hint = super().sizeHint()
        hint.setWidth(min(hint.width(), 160))
        return hint

    minimumSizeHint = sizeHint


class ListEdit(QPlainTextEdit):
    """The editor of a list (comma-separated items): it wraps at its width and grows to show
    the whole value, which a line edit cuts; used as one, Enter or leaving it after a change
    ends the edit (``editingFinished``)."""

    editingFinished = Signal()

    def __init__(self) -> None:
        super().__init__()
        self.setLineWrapMode(QPlainTextEdit.LineWrapMode.WidgetWidth)
        self.setWordWrapMode(QTextOption.WrapMode.WrapAtWordBoundaryOrAnywhere)
        self.setTabChangesFocus(True)
        self.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.setVerticalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Fixed)
        self.document().setDocumentMargin(2)
        #: the height of a line edit: a short list looks like any other field
        self._line_height = QLineEdit().sizeHint().height()
        self._dirty = False
        self.textChanged.connect(self._changed)
        self._fit()

    def text(self) -> str:
        # an item never holds a line break: one typed or pasted separates items
        return ",".join(self.toPlainText().splitlines())

    def setText(self, text: str) -> None:
        self.setPlainText(text)
        self._dirty = False
        self._fit()

    def _changed(self) -> None:
        self._dirty = True
        self._fit()

    def _fit(self) -> None:
        """As high as the wrapped text's lines (the text edit scrolls a line that is short of
        its height by a pixel)."""
        lines = max(1, self.document().lineCount())
        text = lines * QFontMetricsF(self.font()).lineSpacing() \
            + 2 * self.document().documentMargin() + 1
        margins = self.contentsMargins()
        self.setFixedHeight(max(self._line_height,
                                math.ceil(text) + margins.top() + margins.bottom()))

    def resizeEvent(self, event) -> None:
        super().resizeEvent(event)  # the text wrapped anew at the new width
        self._fit()

    def keyPressEvent(self, event) -> None:
        if event.key() in (Qt.Key.Key_Return, Qt.Key.Key_Enter):
            self._finish()
            return
        super().keyPressEvent(event)

    def focusOutEvent(self, event) -> None:
        super().focusOutEvent(event)
        if self._dirty:
            self._finish()

    def _finish(self) -> None:
        self._dirty = False
        self.editingFinished.emit()

    def sizeHint(self) -> QSize:
        # a line edit's width: the value wraps rather than widening its panel
        return QSize(17 * self.fontMetrics().horizontalAdvance("x"), self.height())

    def minimumSizeHint(self) -> QSize:
        return QSize(self.fontMetrics().horizontalAdvance("x" * 8), self.height())


class ParamField(QWidget):
    """The editor of one parameter, with its "auto" box and its error line.

    ``value`` is the last accepted value; ``error`` the message of the last refused edit (empty
    when the field holds what was typed).
    """

    changed = Signal()

    def __init__(self, param: Param, value: Any, where: str) -> None:
        super().__init__()
        self.param = param
        self.where = f"{where}.{param.name}" if where else param.name
        self.error = ""
        self.editor = self._make_editor()
        self.editor.setToolTip(tooltip(param))
        self.editor.setObjectName(f"field:{param.name}")
        self.auto: QCheckBox | None = None
        row = QHBoxLayout()
        row.setContentsMargins(0, 0, 0, 0)
        row.addWidget(self.editor, 1)
        if param.default is None:
            self.auto = QCheckBox("auto")
            self.auto.setToolTip("Leave unset: the plugin chooses (default).")
            self.auto.toggled.connect(self._auto_toggled)
            row.addWidget(self.auto)
            if isinstance(self.editor, (QDoubleSpinBox, QSpinBox)):
                # shown at the spin box's minimum, which no schema accepts as a value
                self.editor.setSpecialValueText(AUTO_TEXT)
        self.message = QLabel()
        self.message.setStyleSheet(ERROR_STYLE)
        self.message.setWordWrap(True)
        self.message.setVisible(False)
        self.message.setObjectName(f"error:{param.name}")
        column = QVBoxLayout(self)
        column.setContentsMargins(0, 0, 0, 0)
        column.setSpacing(1)
        column.addLayout(row)
        column.addWidget(self.message)
        self.value: Any = None
        self.set_value(value)
        self._connect()

    # ------------------------------------------------------------------ editors
    def _make_editor(self) -> QWidget:
        p = self.param
        if p.choices is not None and p.type not in ("strs", "floats"):
            box = QComboBox()
            for choice in p.choices:
                box.addItem(str(choice), choice)
            return box
        if p.type == "bool":
            return QCheckBox()
        if p.type == "float":
            return _DoubleSpin(p)
        if p.type == "int":
            return _IntSpin(p)
        if p.type in ("floats", "strs"):
            items = ListEdit()
            items.setPlaceholderText("comma-separated")
            return items
        return QLineEdit()

    def _connect(self) -> None:
        e = self.editor
        if isinstance(e, QComboBox):
            e.currentIndexChanged.connect(self._edited)
        elif isinstance(e, QCheckBox):
            e.toggled.connect(self._edited)
        elif isinstance(e, (QDoubleSpinBox, QSpinBox)):
            e.valueChanged.connect(self._edited)
        else:
            e.editingFinished.connect(self._edited)

    def _raw(self) -> Any:
        """What the editor holds, converted by the schema (raises ParameterError)."""
        e, p = self.editor, self.param
        if self.auto is not None and self.auto.isChecked():
            return None
        if isinstance(e, QComboBox):
            return p.check(e.currentData(), self.where)
        if isinstance(e, QCheckBox):
            return p.check(e.isChecked(), self.where)
        if isinstance(e, (QDoubleSpinBox, QSpinBox)):
            return p.check(e.value(), self.where)
        if p.type in ("floats", "strs"):
            return p.parse(e.text(), self.where)
        return p.check(e.text(), self.where)

    def _show(self, value: Any) -> None:
        e = self.editor
        e.blockSignals(True)
        try:
            if isinstance(e, QComboBox):
                index = e.findData(value)
                e.setCurrentIndex(max(index, 0))
            elif isinstance(e, QCheckBox):
                e.setChecked(bool(value))
            elif isinstance(e, QDoubleSpinBox):
                e.setValue(float(value) if value is not None else self._unset(e))
            elif isinstance(e, QSpinBox):
                e.setValue(int(value) if value is not None else int(self._unset(e)))
            elif self.param.type in ("floats", "strs"):
                # ", " between items: where a long list wraps
                e.setText("" if value is None else
                          ", ".join(value_text(self.param, [item]) for item in value))
            else:
                e.setText("" if value is None else str(value))
        finally:
            e.blockSignals(False)

    def _unset(self, editor: QAbstractSpinBox) -> float:
        """What a spin box shows for no value: "auto" (its minimum) when the parameter is
        optional, else a value within the bounds."""
        return editor.minimum() if self.auto is not None else self._placeholder()

    def _placeholder(self) -> float:
        lo, hi = self.param.minimum, self.param.maximum
        if lo is not None and (lo > 0 or (hi is not None and hi < 0)):
            return lo
        return 0.0 if hi is None or hi >= 0 else hi

    # ------------------------------------------------------------------ state
    def set_value(self, value: Any) -> None:
        """Show ``value`` (from a profile or a run file) and accept it if the schema does."""
        missing = value is None and self.param.required
        if self.auto is not None:
            self.auto.blockSignals(True)
            self.auto.setChecked(value is None)
            self.auto.blockSignals(False)
            self.editor.setEnabled(value is not None)
        self._show(value)
        if missing:
            self.value = None
            self._set_error(f"{self.where}: missing; expected {self.param.describe()}")
            return
        try:
            self.value = self.param.check(value, self.where) if value is not None else None
            self._set_error("")
        except ParameterError as exc:
            self.value = None
            self._set_error(str(exc))

    def _auto_toggled(self, checked: bool) -> None:
        e = self.editor
        e.setEnabled(not checked)
        if isinstance(e, (QDoubleSpinBox, QSpinBox)):
            e.blockSignals(True)
            if checked:
                e.setValue(e.minimum())                 # reads "auto"
            elif e.value() == e.minimum():
                e.setValue(type(e.value())(self._placeholder()))  # a value to start from
            e.blockSignals(False)
        self._edited()

    def _edited(self, *args: Any) -> None:
        try:
            self.value = self._raw()
            self._set_error("")
        except ParameterError as exc:
            self._set_error(f"refused: {exc}")
        self.changed.emit()

    def _set_error(self, message: str) -> None:
        self.error = message
        self.message.setText(message)
        self.message.setVisible(bool(message))
        self.editor.setStyleSheet(FIELD_ERROR_STYLE if message else "")

    def override(self, section: str) -> str:
        """``section.name=value`` for ``--set`` and :func:`fsi_lab.profile.apply_overrides`."""
        return f"{section}.{self.param.name}={value_text(self.param, self.value)}"


class ParamForm(QWidget):
    """A form for a whole schema; ``changed`` fires after any edit."""

    changed = Signal()

    def __init__(self, params: Sequence[Param], values: Mapping[str, Any] | None = None,
                 where: str = "", parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.params = tuple(params)
        self.where = where
        self.fields: dict[str, ParamField] = {}
        layout = QFormLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.setFieldGrowthPolicy(QFormLayout.FieldGrowthPolicy.AllNonFixedFieldsGrow)
        # in a narrow column the editor goes under its label rather than out of sight
        layout.setRowWrapPolicy(QFormLayout.RowWrapPolicy.WrapLongRows)
        values = dict(values or {})
        for param in self.params:
            value = values.get(param.name, None if param.required else param.default)
            field = ParamField(param, value, where)
            field.changed.connect(self.changed)
            label = QLabel(param.name.replace("_", " "))
            label.setToolTip(tooltip(param))
            layout.addRow(label, field)
            self.fields[param.name] = field
        if not self.params:
            layout.addRow(QLabel("(no parameters)"))

    def values(self) -> dict[str, Any]:
        """The last accepted value of every parameter."""
        return {name: field.value for name, field in self.fields.items()}

    def errors(self) -> dict[str, str]:
        return {name: f.error for name, f in self.fields.items() if f.error}

    def is_valid(self) -> bool:
        return not self.errors()

    def set_values(self, values: Mapping[str, Any]) -> None:
        for name, value in values.items():
            if name in self.fields:
                self.fields[name].set_value(value)
        self.changed.emit()

    def overrides(self, section: str) -> list[str]:
        """One ``section.name=value`` per accepted value."""
        return [f.override(section) for f in self.fields.values()
                if not (f.value is None and f.param.required)]

    def editor(self, name: str) -> QWidget:
        return self.fields[name].editor
