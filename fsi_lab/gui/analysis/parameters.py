"""AnalysisParameters: the panel editing the analysis chain's parameters; asks for a re-run."""

from __future__ import annotations

from typing import Any, Iterator

from PySide6.QtCore import QTimer, Signal
from PySide6.QtWidgets import QComboBox, QGroupBox, QLabel, QPushButton, QVBoxLayout, QWidget

from fsi_lab.gui.forms import ParamForm
from fsi_lab.profile import ANALYSIS_PARAMS
from fsi_lab.registry import Registry


class AnalysisParameters(QGroupBox):
    """The chain (``[analysis]``) and a form per plugin of the chain, from the plugins' schemas.

    A valid change asks for a re-analysis (debounced); ``rerun`` carries the overrides.
    """

    rerun = Signal(list)

    def __init__(self, registry: Registry, parent: QWidget | None = None) -> None:
        super().__init__("Analysis parameters", parent)
        self.registry = registry
        self.chain_form: ParamForm | None = None
        self.forms: dict[str, ParamForm] = {}
        self.params: dict[str, dict] = {}
        self.chain_holder = QVBoxLayout()
        self.plugin = QComboBox()
        self.plugin.setObjectName("analysis-plugin")
        self.plugin.currentIndexChanged.connect(self._plugin_changed)
        self.holder = QVBoxLayout()
        self.button = QPushButton("Re-run analysis")
        self.button.setObjectName("rerun")
        self.button.clicked.connect(self.request)
        self.auto = QTimer(self)
        self.auto.setSingleShot(True)
        self.auto.setInterval(400)
        self.auto.timeout.connect(self.request)
        self.note = QLabel("")
        self.note.setWordWrap(True)
        installed = ", ".join(registry.names("analysis")) or "none"
        self.setToolTip(f"Installed analysis plugins: {installed}")
        layout = QVBoxLayout(self)
        layout.addLayout(self.chain_holder)
        layout.addWidget(QLabel("Plugin"))
        layout.addWidget(self.plugin)
        layout.addLayout(self.holder)
        layout.addStretch(1)
        layout.addWidget(self.button)
        layout.addWidget(self.note)
        self.setEnabled(False)

    def load(self, analysis: dict[str, Any], params: dict[str, dict]) -> None:
        """Forms for a run's chain and the parameters its plugins last ran with."""
        for _ in self.loading(analysis, params):
            pass

    def loading(self, analysis: dict[str, Any], params: dict[str, dict]) -> Iterator[None]:
        """:meth:`load` a form at a time (see :class:`~fsi_lab.gui.analysis.stepper.Stepper`);
        the panel is disabled until every form is there."""
        self.setEnabled(False)
        # the forms of the run shown before go, their values with them
        for form in self.forms.values():
            form.deleteLater()
        self.forms.clear()
        if self.chain_form is not None:
            self.chain_form.deleteLater()
        self.chain_form = ParamForm(ANALYSIS_PARAMS, analysis, "analysis")
        self.chain_form.changed.connect(self._chain_changed)
        self.chain_holder.addWidget(self.chain_form)
        self.params = {k: dict(v) for k, v in params.items()}
        yield
        yield from self._forms(list(analysis.get("chain") or []))
        self.setEnabled(True)

    def _build_forms(self, chain: list[str]) -> None:
        for _ in self._forms(chain):
            pass

    def _forms(self, chain: list[str]) -> Iterator[None]:
        """A form per plugin of ``chain`` (one per step), keeping the values edited so far."""
        current = self.plugin.currentData()
        for name, form in self.forms.items():
            self.params[name] = form.values()
            form.deleteLater()
        self.forms.clear()
        self.plugin.blockSignals(True)
        self.plugin.clear()
        self.plugin.blockSignals(False)
        unknown = []
        for name in chain:
            if name not in self.registry.descriptors["analysis"]:
                unknown.append(name)
                continue
            descriptor = self.registry.get("analysis", name)
            form = ParamForm(descriptor.params, self.params.get(name, {}), f"analysis.{name}")
            form.setVisible(False)
            form.setToolTip(descriptor.help)
            form.changed.connect(self._changed)
            self.holder.addWidget(form)
            self.forms[name] = form
            self.plugin.blockSignals(True)
            self.plugin.addItem(name, name)
            self.plugin.blockSignals(False)
            yield
        self.plugin.blockSignals(True)
        if current in self.forms:
            self.plugin.setCurrentIndex(list(self.forms).index(current))
        self.plugin.blockSignals(False)
        self._plugin_changed()
        self.note.setText(f"not installed here: {', '.join(unknown)}" if unknown else "")

    def _chain_changed(self) -> None:
        if self.chain_form.is_valid():
            self._build_forms(list(self.chain_form.values()["chain"] or []))
        self._changed()

    def _plugin_changed(self) -> None:
        current = self.plugin.currentData()
        for name, form in self.forms.items():
            form.setVisible(name == current)

    def valid(self) -> bool:
        forms = [self.chain_form, *self.forms.values()] if self.chain_form else []
        return all(form.is_valid() for form in forms)

    def _changed(self) -> None:
        if self.valid():
            self.auto.start()
        else:
            self.auto.stop()

    def overrides(self) -> list[str]:
        """Every value of every form (the run's profile may hold older values than its last
        analysis, so all are given), as ``fsi-lab analyze --set`` takes them."""
        items = []
        if self.chain_form is not None:
            for field in self.chain_form.fields.values():
                if field.param.name == "chain" or field.value:
                    items.append(field.override("analysis"))
        for name, form in self.forms.items():
            items.extend(form.overrides(f"analysis.{name}"))
        return items

    def request(self) -> None:
        self.auto.stop()
        if self.valid() and self.chain_form is not None:
            self.rerun.emit(self.overrides())
