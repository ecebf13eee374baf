"""Forms generated from parameter schemas: widgets, tooltips, and refusal of bad values."""

from conftest import UI_TIMEOUT_MS
from PySide6.QtCore import QEvent, Qt
from PySide6.QtGui import QFocusEvent
from PySide6.QtWidgets import (
    QApplication,
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QLineEdit,
    QSpinBox,
)

from fsi_lab.gui.forms import ParamForm
from fsi_lab.params import Param

SCHEMA = (
    Param("amplitude", "float", "V", 0.5, minimum=-10.0, maximum=10.0, help="Peak drive."),
    Param("width", "float", "s", 0.02, minimum=0.0, exclusive_minimum=True, help="Pulse width."),
    Param("components", "int", "", 2, minimum=1, help="How many."),
    Param("window", "str", "", "hann", choices=("hann", "boxcar"), help="Window."),
    Param("detrend", "bool", "", True, help="Remove the mean."),
    Param("cutoff", "float", "Hz", None, minimum=0.0, help="Automatic when unset."),
    Param("levels", "floats", "V", [1.0, 2.0], minimum=0.0, help="Levels."),
)


def test_one_widget_per_parameter_with_unit_and_help(qtbot):
    from fsi_lab.gui.forms import ListEdit

    form = ParamForm(SCHEMA, {}, "excitation")
    qtbot.addWidget(form)
    kinds = {name: type(form.editor(name)) for name in form.fields}
    assert issubclass(kinds["amplitude"], QDoubleSpinBox)
    assert issubclass(kinds["components"], QSpinBox)
    assert kinds["window"] is QComboBox and kinds["detrend"] is QCheckBox
    assert kinds["levels"] is ListEdit
    assert form.editor("amplitude").suffix() == " V"
    tip = form.editor("amplitude").toolTip()
    assert "Peak drive." in tip and "<= 10 V" in tip and ">= -10 V" in tip
    assert form.values() == {"amplitude": 0.5, "width": 0.02, "components": 2, "window": "hann",
                             "detrend": True, "cutoff": None, "levels": [1.0, 2.0]}
    assert form.is_valid()


def test_out_of_bounds_value_is_refused_and_shown(qtbot):
    form = ParamForm(SCHEMA, {"amplitude": 1.0}, "excitation")
    qtbot.addWidget(form)
    form.show()
    field = form.fields["amplitude"]
    field.editor.setValue(20.0)          # as if typed
    assert not form.is_valid()
    assert "out of bounds" in field.error and "excitation.amplitude" in field.error
    assert field.message.isVisible() and "refused" in field.message.text()
    assert form.values()["amplitude"] == 1.0        # the last accepted value is kept
    assert form.overrides("excitation") == [o for o in form.overrides("excitation")
                                            if "amplitude=20" not in o]
    field.editor.setValue(-3.0)
    assert form.is_valid() and not field.message.isVisible()
    assert form.values()["amplitude"] == -3.0


def test_exclusive_minimum_and_integers(qtbot):
    form = ParamForm(SCHEMA, {}, "x")
    qtbot.addWidget(form)
    form.fields["width"].editor.setValue(0.0)
    assert "width" in form.errors()
    form.fields["components"].editor.setValue(0)
    assert "components" in form.errors()
    form.fields["width"].editor.setValue(0.5)
    form.fields["components"].editor.setValue(4)
    assert form.is_valid() and form.values()["components"] == 4


def test_step_arrows_stay_within_bounds(qtbot):
    form = ParamForm(SCHEMA, {"amplitude": 9.9}, "x")
    qtbot.addWidget(form)
    spin = form.editor("amplitude")
    spin.setSingleStep(1.0)
    spin.stepBy(5)
    assert spin.value() == 10.0 and form.is_valid()


def test_optional_parameter_auto_and_lists(qtbot):
    form = ParamForm(SCHEMA, {"cutoff": 5.0}, "analysis.hvd")
    qtbot.addWidget(form)
    field = form.fields["cutoff"]
    assert field.auto is not None and not field.auto.isChecked()
    assert form.values()["cutoff"] == 5.0
    field.auto.setChecked(True)
    assert form.values()["cutoff"] is None
    assert "analysis.hvd.cutoff=auto" in form.overrides("analysis.hvd")
    levels = form.fields["levels"]
    levels.editor.setText("1, -2")
    levels.editor.editingFinished.emit()
    assert "levels" in form.errors() and form.values()["levels"] == [1.0, 2.0]
    levels.editor.setText("0.5, 3")
    levels.editor.editingFinished.emit()
    assert form.is_valid() and form.values()["levels"] == [0.5, 3.0]


def test_an_unset_optional_number_reads_auto(qtbot):
    # as a signal source's sample rate: unset means "the run's sample rate", and no number
    # (such as its lower bound, 1e-06 Hz) is shown for it
    schema = (Param("sample_rate", "float", "Hz", None, minimum=1e-6, maximum=160e6),
              Param("points", "int", "", None, minimum=8))
    form = ParamForm(schema, {}, "bench.source")
    qtbot.addWidget(form)
    rate, points = form.fields["sample_rate"], form.fields["points"]
    for field in (rate, points):
        assert field.auto.isChecked() and not field.editor.isEnabled()
        assert field.editor.text() == "auto" and field.value is None and not field.error
    rate.auto.setChecked(False)                  # a number to start from, within the bounds
    assert rate.editor.isEnabled() and rate.editor.text() == "1e-06 Hz"
    assert rate.value == 1e-6 and not rate.error
    rate.editor.setValue(10000.0)
    assert form.values()["sample_rate"] == 10000.0
    rate.auto.setChecked(True)
    assert rate.editor.text() == "auto" and form.values()["sample_rate"] is None
    assert "bench.source.sample_rate=auto" in form.overrides("bench.source")
    points.auto.setChecked(False)
    assert points.editor.text() == "8" and points.value == 8


def test_choices_and_missing_required(qtbot):
    schema = (Param("mode", "str", "", "a", choices=("a", "b")),
              Param("gain", "float", "V/V", help="Required."))
    form = ParamForm(schema, {}, "bench.amplifier")
    qtbot.addWidget(form)
    assert "gain" in form.errors() and "missing" in form.errors()["gain"]
    form.fields["gain"].editor.setValue(2.0)
    form.fields["mode"].editor.setCurrentIndex(1)
    assert form.is_valid() and form.values() == {"mode": "b", "gain": 2.0}
    assert form.overrides("bench.amplifier") == ["bench.amplifier.mode=b",
                                                 "bench.amplifier.gain=2.0"]


def test_a_list_wraps_to_show_every_item_and_is_edited_as_a_line(qtbot):
    """A list's editor shows every item, on as many lines as its width needs (a line edit
    showed the part that fit); it is edited as a line edit is: Enter, or leaving it after a
    change, commits the list, and leaving it unchanged commits nothing."""
    chain = ["hvd", "instantaneous", "backbone", "damping", "equivalent-damping", "modal-model"]
    form = ParamForm((Param("chain", "strs", "", [], help="Analyses."),), {"chain": chain},
                     "analysis")
    qtbot.addWidget(form)
    form.resize(220, 200)
    form.show()
    qtbot.waitExposed(form)
    editor = form.editor("chain")
    one_line = QLineEdit().sizeHint().height()
    assert editor.text() == ", ".join(chain)             # wraps after a comma
    qtbot.waitUntil(lambda: editor.height() > 2 * one_line, timeout=UI_TIMEOUT_MS)
    assert editor.document().lineCount() > 2
    assert editor.verticalScrollBar().maximum() == 0     # every line in view

    committed = []
    form.changed.connect(lambda: committed.append(form.values()["chain"]))
    editor.selectAll()
    qtbot.keyClicks(editor, "hvd, backbone")
    assert committed == []                               # typing is not committing
    qtbot.keyClick(editor, Qt.Key.Key_Return)
    assert committed == [["hvd", "backbone"]] and editor.text() == "hvd, backbone"
    qtbot.waitUntil(lambda: editor.height() == one_line, timeout=UI_TIMEOUT_MS)

    def leave():
        QApplication.sendEvent(editor, QFocusEvent(QEvent.Type.FocusOut))

    leave()
    assert len(committed) == 1                           # nothing changed since Enter
    qtbot.keyClicks(editor, ", damping")
    leave()
    assert committed[-1] == ["hvd", "backbone", "damping"] and len(committed) == 2
