"""The profile being edited: the file's text plus the values changed in the forms.

The forms never build a profile themselves. Their edits become ``key.path=value`` overrides,
exactly what ``fsi-lab run --set`` takes, and :func:`fsi_lab.profile.parse_profile` validates the
result; :func:`fsi_lab.preflight.check_safety` then gives the waveform (the preview) and the
safety verdict. Both run off the UI thread, and a newer edit makes older answers stale. The run
file stores the profile text and the overrides, so a run started from the GUI can be redone
with ``fsi-lab run PROFILE --set ...``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from PySide6.QtCore import QObject, QTimer, Signal

from fsi_lab.errors import FsiLabError
from fsi_lab.gui.decimate import min_max_decimate
from fsi_lab.gui.worker import TaskPool
from fsi_lab.preflight import check_safety
from fsi_lab.profile import Profile, parse_profile
from fsi_lab.registry import Registry
from fsi_lab.safety import SafetyReport

PREVIEW_POINTS = 4000


@dataclass
class Checked:
    """The answer to one edit: the validated profile and its safety verdict, or the error."""

    generation: int
    profile: Profile | None = None
    report: SafetyReport | None = None
    preview: tuple[np.ndarray, np.ndarray] | None = None
    error: str = ""
    overrides: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.profile is not None and self.report is not None and self.report.ok


def check_profile(text: str, path: str, registry: Registry, overrides: list[str],
                  generation: int) -> Checked:
    """Validate, generate the waveform and assess it (runs on a worker thread)."""
    result = Checked(generation, overrides=list(overrides))
    try:
        profile = parse_profile(text, path, registry, overrides)
        result.profile = profile
        if not profile.can_run:
            result.error = f"{path}: describes no bench and excitation to run"
            return result
        waveform, rate, report = check_safety(profile, registry)
    except FsiLabError as exc:
        result.error = str(exc)
        return result
    except Exception as exc:  # noqa: BLE001 - a broken plugin must not take the GUI down
        result.error = f"{type(exc).__name__}: {exc}"
        return result
    result.report = report
    t = np.arange(waveform.size) / rate
    result.preview = min_max_decimate(t, waveform, PREVIEW_POINTS)
    return result


class ProfileSession(QObject):
    """The open profile, the forms' overrides by section, and the latest check.

    Signals: ``opened(Profile)`` when a profile file has been read and validated,
    ``open_failed(str)``, ``checking()`` when an edit starts a new check and ``checked(Checked)``
    with its answer (stale answers are dropped).
    """

    opened = Signal(object)
    open_failed = Signal(str)
    checking = Signal()
    checked = Signal(object)
    DEBOUNCE_MS = 120

    def __init__(self, registry: Registry, pool: TaskPool, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.registry = registry
        self.pool = pool
        self.path: str = ""
        self.base_text: str = ""
        self.text: str = ""
        self.base: Profile | None = None
        self.sections: dict[str, list[str]] = {}
        self.latest: Checked | None = None
        self._generation = 0
        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(self.DEBOUNCE_MS)
        self._timer.timeout.connect(self._start_check)

    # ------------------------------------------------------------------ opening
    def open(self, path: str | Path) -> bool:
        """Read and validate a profile file; ``opened`` or ``open_failed`` tells the outcome."""
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as exc:
            self.open_failed.emit(f"{path}: cannot read the profile ({exc.strerror})")
            return False
        except UnicodeDecodeError:
            self.open_failed.emit(f"{path}: not a text file; expected a TOML profile")
            return False
        try:
            profile = parse_profile(text, str(path), self.registry)
        except FsiLabError as exc:
            self.open_failed.emit(str(exc))
            return False
        self.path, self.base_text, self.text, self.base = str(path), text, text, profile
        self.sections.clear()
        self.latest = None
        self.opened.emit(profile)
        self.request_check()
        return True

    @property
    def loaded(self) -> bool:
        return self.base is not None

    # ------------------------------------------------------------------ edits
    def set_excitation_plugin(self, name: str) -> None:
        if self.base is None:
            return
        # The profile text stays verbatim; the switch is an override like the forms' values.
        self.set_overrides("excitation-plugin", [] if name == self.base.excitation_plugin
                           else [f"excitation.plugin={name}"])

    def set_overrides(self, section: str, overrides: list[str]) -> None:
        """Replace the overrides of one form (``section`` is a free label, e.g. ``run``)."""
        self.sections[section] = list(overrides)
        self.request_check()

    def overrides(self) -> list[str]:
        return [item for items in self.sections.values() for item in items]

    def request_check(self) -> None:
        if self.base is None:
            return
        self._generation += 1
        self.latest = None
        self.checking.emit()
        self._timer.start()

    def _start_check(self) -> None:
        generation = self._generation
        self.pool.start(check_profile, self.text, self.path, self.registry, self.overrides(),
                        generation, on_done=self._on_checked, name="check profile")

    def _on_checked(self, result: Checked) -> None:
        if result.generation != self._generation:
            return
        self.latest = result
        self.checked.emit(result)

    @property
    def current(self) -> Checked | None:
        """The check of the values now in the forms, or None while it runs."""
        return self.latest

    def value_of(self, section: str, name: str) -> Any:
        """The base profile's value of a parameter (``section`` run / excitation)."""
        if self.base is None:
            return None
        return {"run": self.base.run, "excitation": self.base.excitation}[section].get(name)
