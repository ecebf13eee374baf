"""The window's Qt objects are taken down in order: nothing signals a deleted plot item."""

import gc

import numpy as np
import pytest
from conftest import LOAD_TIMEOUT_MS, UI_TIMEOUT_MS, write_run

from fsi_lab.events import DataBlock
from fsi_lab.gui.app import MainWindow, _configure_pyqtgraph


@pytest.mark.parametrize("state", ["figures built while idle", "every figure drawn"])
def test_the_window_is_deleted_without_an_error(qtbot, registry, tmp_path, state):
    _configure_pyqtgraph()
    window = MainWindow(registry=registry, out_dir=tmp_path / "runs")
    window.resize(1366, 768)
    window.show()
    qtbot.waitExposed(window)
    disposed = False
    try:
        # the analysis figures' plots are built in idle time, hidden until a run uses them
        qtbot.waitUntil(lambda: not window.analysis._prebuild, timeout=UI_TIMEOUT_MS)
        if state == "every figure drawn":
            runs = [write_run(tmp_path / "a.h5", name="run A"), write_run(tmp_path / "b.h5")]
            window.open_runs(runs)
            qtbot.waitUntil(lambda: len(window.runs.runs) == 2 and not window.busy()
                            and not window.runs.pending, timeout=LOAD_TIMEOUT_MS)
            filled = window.analysis.filled()
            assert filled["Overview"] and filled["HVD components"], filled
            window.tabs.setCurrentWidget(window.runs)
            window.runs.set_checked(runs)            # the comparison's plots
            window.live.configure({"a": "V", "b": "m/s"}, 1000.0)   # linked live plots
            window.live.on_block(DataBlock(0.0, 1000.0, {"a": np.ones(100),
                                                         "b": np.zeros(100)}))
            window.live.refresh(force=True)
        with qtbot.captureExceptions() as exceptions:
            window.close()
            window.dispose()
            disposed = True
            gc.collect()
        assert not exceptions, "".join(str(e[1]) for e in exceptions)
    finally:
        if not disposed:
            window.close()
            window.dispose()
