"""The README's pictures of the desktop application: each tab at 1366x768, offscreen.

``make screenshots`` (or ``.venv/bin/python docs/screenshots.py``) runs the paper's wet experiment
(profiles/wet-beam-sim.toml, its simulated bench paced in real time) in the window twice, with
two excitation heights, and saves:

- docs/gui-screenshot-experiment.png: the Experiment tab while the first run acquires;
- docs/gui-screenshot-analysis.png: the Analysis tab once the first run is analysed;
- docs/gui-screenshot-runs.png: the Runs tab comparing the two runs.

Every wait is on a condition, with a generous limit; the layouts are settled before each picture.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SIZE = (1366, 768)
LIMIT_S = 600.0


def main() -> int:
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from PySide6.QtWidgets import QApplication

    from fsi_lab.gui.app import MainWindow, _configure_pyqtgraph, _wait_events, settle

    app = QApplication.instance() or QApplication(sys.argv[:1])
    _configure_pyqtgraph()
    docs = ROOT / "docs"
    os.chdir(ROOT)  # the profile shown as the README names it
    profile = Path("profiles") / "wet-beam-sim.toml"
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        window = MainWindow(out_dir=folder / "runs")
        window.resize(*SIZE)
        window.show()

        def wait(what: str, condition) -> None:
            deadline = time.monotonic() + LIMIT_S
            while not condition():
                if time.monotonic() > deadline:
                    raise SystemExit(f"screenshots: gave up waiting for {what}")
                _wait_events(app, 20)

        def picture(name: str) -> None:
            settle(window)
            path = docs / name
            if not window.grab().save(str(path)):
                raise SystemExit(f"screenshots: cannot write {path}")
            print(path.relative_to(ROOT))

        def run(height: float):
            window.designer.form.fields["height"].editor.setValue(height)
            name = window.designer.run_form.fields["name"].editor
            name.setText(f"wet beam, ramp derivative of {height:g} V*s")
            name.editingFinished.emit()
            wait("the safety check", lambda: window.session.current is not None
                 and window.run_control.start_button.isEnabled())
            assert window.run_control.start(), "the window refused to start the run"
            return window.run_control

        try:
            assert window.open_profile(profile), window.messages.messages
            # its simulated bench paced in real time, to be seen acquiring (an override, as
            # `fsi-lab run --set bench.fast=false` would give)
            window.session.set_overrides("screenshots", ["bench.fast=false"])
            control = run(height=0.01)
            wait("4 s of data", lambda: window.live.blocks >= 40 or not control.running)
            window.live.refresh(force=True)
            picture("gui-screenshot-experiment.png")
            wait("the end of the run", lambda: not control.running)
            first = control.outcome.path.resolve()
            wait("the analysis", lambda: window.analysis.results is not None
                 and window.analysis.results.path == first
                 and bool(window.analysis.results.analysis) and not window.busy())
            window.tabs.setCurrentWidget(window.analysis)
            window.analysis.filled()
            picture("gui-screenshot-analysis.png")
            window.tabs.setCurrentIndex(0)  # the Experiment tab
            control = run(height=0.014)
            wait("the second run", lambda: not control.running)
            second = control.outcome.path.resolve()
            wait("its analysis", lambda: second in window.runs.runs and not window.busy()
                 and bool(window.runs.runs[second].analysis) and not window.runs.pending)
            window.tabs.setCurrentWidget(window.runs)
            window.runs.set_checked([first, second])
            picture("gui-screenshot-runs.png")
        finally:
            if window.run_control.running:
                window.run_control.abort()
                wait("the abort", lambda: not window.run_control.running)
            wait("idle", lambda: not window.busy())
            window.dispose()
    return 0


if __name__ == "__main__":
    sys.exit(main())
