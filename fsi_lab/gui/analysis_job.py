"""The analysis chain of a run file, run as ``fsi-lab analyze RUN.h5 --set ... --json`` in a
child process.

The chain is CPU-bound compiled code that holds Python's global interpreter lock while it
works; in a thread of the GUI's own process it would freeze the window for hundreds of
milliseconds at a time. In a child process the window stays responsive, and the GUI runs exactly
what an experimenter would type: the same command, the same plugins, the same run file.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from PySide6.QtCore import QObject, QProcess, QTimer, Signal


class AnalysisJob(QObject):
    """One ``fsi-lab analyze`` process; ``succeeded(path, summary)`` or ``failed(path, text)``."""

    succeeded = Signal(object, object)
    failed = Signal(object, str)
    MAX_ATTEMPTS = 3

    def __init__(self, path: str | Path, overrides: list[str] = (),
                 parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.path = Path(path)
        self.overrides = list(overrides)
        self.process = QProcess(self)
        self.process.finished.connect(self._finished)
        self.process.errorOccurred.connect(self._error)
        self._reported = False
        self.attempts = 0

    def arguments(self) -> list[str]:
        args = ["-m", "fsi_lab.cli", "analyze", str(self.path), "--json", "--quiet"]
        for item in self.overrides:
            args += ["--set", item]
        return args

    def start(self) -> None:
        self.process.start(sys.executable, self.arguments())

    @property
    def running(self) -> bool:
        return self.process.state() != QProcess.ProcessState.NotRunning

    def wait(self, timeout_ms: int = 30000) -> bool:
        """Block until the process ends; kill it after ``timeout_ms`` (closing the window)."""
        if not self.running:
            return True
        if self.process.waitForFinished(timeout_ms):
            return True
        self.process.kill()
        return self.process.waitForFinished(5000)

    def _finished(self, code: int, status: QProcess.ExitStatus) -> None:
        out = bytes(self.process.readAllStandardOutput()).decode(errors="replace")
        err = bytes(self.process.readAllStandardError()).decode(errors="replace")
        try:
            answer = json.loads(out) if out.strip() else {}
        except ValueError:
            answer = {}
        # Exit 2 with a summary: nothing was identified, but what was computed (the spectrum)
        # is stored and shown, with each refusal in its view.
        summary = "channels" in answer and code in (0, 2)
        if (status == QProcess.ExitStatus.NormalExit and "error" not in answer
                and (code == 0 or summary)):
            self._report(self.succeeded, self.path, answer)
            return
        message = answer.get("error") or _last_lines(err) or f"fsi-lab analyze ended with {code}"
        if "unable to lock file" in message and self.attempts < self.MAX_ATTEMPTS:
            # another program is reading the file this very moment: try again shortly
            self.attempts += 1
            QTimer.singleShot(500 * self.attempts, self.start)
            return
        self._report(self.failed, self.path, message)

    def _error(self, error: QProcess.ProcessError) -> None:
        if error == QProcess.ProcessError.FailedToStart:
            self._report(self.failed, self.path,
                         f"cannot start {sys.executable} -m fsi_lab.cli analyze")

    def _report(self, signal, *args) -> None:
        if not self._reported:
            self._reported = True
            signal.emit(*args)


def _last_lines(text: str, count: int = 3) -> str:
    lines = [line.removeprefix("fsi-lab: error: ") for line in text.strip().splitlines()
             if line.strip() and not line.startswith("[warning]")]
    return " ".join(lines[-count:])
