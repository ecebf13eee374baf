"""Every view of the window, drawn at a laptop's and a desktop's screen size, keeps every plot
readable: no plot area collapses, whatever the window holds."""

import numpy as np
import pytest
from conftest import (
    CHECK_TIMEOUT_MS,
    LOAD_TIMEOUT_MS,
    ROOT,
    UI_TIMEOUT_MS,
    assert_readable,
    wait_checked,
    write_run,
)

from fsi_lab.events import DataBlock
from fsi_lab.gui.app import settle

SIZES = [(1366, 768), (1920, 1080)]


@pytest.mark.parametrize("size", SIZES, ids=[f"{w}x{h}" for w, h in SIZES])
def test_every_view_keeps_its_plots_readable(qtbot, make_window, registry, tmp_path,
                                             sim_profile, size):
    window = make_window(registry)
    window.resize(*size)
    qtbot.waitUntil(lambda: window.size().toTuple() == size, timeout=CHECK_TIMEOUT_MS)
    # the analysis figures are built in idle time, their plots hidden until a run is drawn
    qtbot.waitUntil(lambda: not window.analysis._prebuild, timeout=UI_TIMEOUT_MS)

    # Experiment: the waveform preview and the live plots of a profile's channels (more than
    # fit the height: they scroll), with data
    assert window.open_profile(sim_profile(duration=1.0))
    wait_checked(qtbot, window)
    units = {f"channel_{k}": "V" for k in range(8)}
    window.live.configure(units, 2000.0)
    for i in range(5):
        window.live.on_block(DataBlock(0.1 * i, 2000.0, {n: np.sin(np.arange(200) + i)
                                                         for n in units}))
    window.live.refresh(force=True)
    areas = assert_readable(window, "experiment")
    assert len(areas) == 2 * len(units) + 1          # time and spectrum per channel, preview

    # Analysis: each view of a run file opened as from the command line, which brings the
    # Analysis tab to the front at once (its figures' plots still hidden), six HVD components
    runs = [write_run(tmp_path / "a.h5", name="run A", c_i=0.6, hvd_components=6),
            write_run(tmp_path / "b.h5", name="run B", c_i=0.7)]
    window.open_paths(runs[:1])
    qtbot.waitUntil(lambda: window.analysis.results is not None and not window.busy()
                    and not window.analysis.pending, timeout=LOAD_TIMEOUT_MS)
    assert window.tabs.currentWidget() is window.analysis
    assert_readable(window, "the Overview as it first appears")
    filled = window.analysis.filled()
    for index, view in enumerate(window.analysis.views):
        window.analysis.tabs.setCurrentIndex(index)
        if view.title == "All datasets":             # its plot shows a selected dataset
            tree = view.tree
            tree.setCurrentItem(tree.topLevelItem(0).child(0))
        if filled[view.title] and view.title != "Results":
            assert_readable(window, f"analysis view {view.title!r}")

    # Runs: two runs compared
    window.open_runs(runs[1:], show=False)
    qtbot.waitUntil(lambda: len(window.runs.runs) == 2 and not window.runs.pending,
                    timeout=LOAD_TIMEOUT_MS)
    window.tabs.setCurrentWidget(window.runs)
    window.runs.set_checked(runs)
    assert len(assert_readable(window, "runs")) == 3


def test_the_window_fits_a_1366x768_screen(qtbot, make_window, registry, sim_profile,
                                           tmp_path):
    window = make_window(registry)
    window.open_profile(sim_profile(duration=1.0))
    wait_checked(qtbot, window)
    window.open_runs([write_run(tmp_path / "a.h5")])
    qtbot.waitUntil(lambda: window.analysis.results is not None and not window.busy(),
                    timeout=LOAD_TIMEOUT_MS)
    window.analysis.filled()
    settle(window)
    # with a profile, a run and every figure built, the window may still be that small
    hint = window.minimumSizeHint()
    assert hint.width() <= 1366 and hint.height() <= 768, hint
    window.resize(1366, 768)
    qtbot.waitUntil(lambda: window.size().toTuple() == (1366, 768), timeout=CHECK_TIMEOUT_MS)


def test_the_excitation_s_waveform_and_its_labels_are_in_view_at_1366x768(qtbot, make_window,
                                                                         registry):
    """At 1366x768 the waveform preview of the demo profile ended below the visible part of
    the Experiment tab's column: its time axis label was cut off. The excitation's
    parameters, safety verdict and waveform, with every label, are in view without
    scrolling."""
    from PySide6.QtCore import QPoint, QRect
    from PySide6.QtWidgets import QLabel, QScrollArea

    window = make_window(registry)  # at 1366x768
    assert window.open_profile(ROOT / "profiles" / "wet-beam-sim.toml")
    wait_checked(qtbot, window)
    assert settle(window), "the layout did not settle"
    designer = window.designer
    scroll = designer.parentWidget()
    while not isinstance(scroll, QScrollArea):
        scroll = scroll.parentWidget()
    viewport = scroll.viewport()
    assert scroll.verticalScrollBar().value() == 0

    title = next(label for label in designer.findChildren(QLabel)
                 if label.text() == "Waveform sent to the source")
    preview = designer.preview
    bottom = preview.getPlotItem().getAxis("bottom")
    assert bottom.labelText == "time" and bottom.label.isVisible()
    for widget in (title, preview, designer.verdict, designer.form):
        where = QRect(widget.mapTo(viewport, QPoint(0, 0)), widget.size())
        assert widget.isVisible() and viewport.rect().contains(where), (
            f"{widget.objectName() or widget.text()!r} at {where} is not all within the "
            f"visible {viewport.size()}")


def test_a_figure_resized_while_its_plots_are_hidden_fills_out_when_they_show(qtbot):
    """The plots of a figure are hidden between drawings; a resize then (a tab coming to the
    front, a window resized) must not leave the figure's layout at its hidden size."""
    from fsi_lab.gui.figure import Figure

    figure = Figure()
    qtbot.addWidget(figure)
    plot = figure.addPlot(row=0, col=0)
    plot.plot([0, 1, 2], [1, 3, 2])
    plot.setVisible(False)
    figure.resize(600, 400)
    figure.show()
    qtbot.waitExposed(figure)
    plot.setVisible(True)
    qtbot.waitUntil(lambda: plot.geometry().width() > 500 and plot.geometry().height() > 300,
                    timeout=UI_TIMEOUT_MS)
    box = plot.getViewBox().sceneBoundingRect()
    assert box.width() > 400 and box.height() > 250, box


class _Screen:
    """A screen whose free area (the desktop less its panels) is ``width`` x ``height``."""

    def __init__(self, width, height):
        from PySide6.QtCore import QRect

        self.free = QRect(0, 0, width, height)

    def availableGeometry(self):
        return self.free


class _App:
    def __init__(self, screen):
        self.screen = screen

    def primaryScreen(self):
        return self.screen


@pytest.mark.parametrize("free, size", [((1600, 1000), (1600, 1000)),
                                        ((1366, 740), (1366, 740)),
                                        ((2560, 1400), (1680, 1050)),
                                        (None, (1680, 1050))])
def test_the_window_opens_within_a_smaller_screen(free, size):
    """Issue 14: the window opened at 1680x1050 and was cut off on a 1600x1000 screen; it
    opens at that size only where the screen's free area holds it."""
    from fsi_lab.gui.app import PREFERRED_SIZE, fitting_size

    assert PREFERRED_SIZE == (1680, 1050)
    assert fitting_size(_App(_Screen(*free) if free else None)) == size
