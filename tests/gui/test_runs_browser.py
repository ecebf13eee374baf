"""Runs browser: several files at once, side-by-side comparison, PNG/SVG/CSV exports."""

import csv

import h5py
from conftest import LOAD_TIMEOUT_MS, with_specimen_and_convention, write_foreign, write_run


def test_compare_two_runs_and_export(qtbot, make_window, registry, tmp_path):
    window = make_window(registry)
    a = write_run(tmp_path / "a.h5", c_i=0.6, c_f=30.0, name="run A")
    b = write_run(tmp_path / "b.h5", c_i=0.7, c_f=36.0, name="run B")
    window.runs.open([a, b, write_foreign(tmp_path / "foreign.h5")])
    qtbot.waitUntil(lambda: len(window.runs.runs) == 2 and not window.runs.pending,
                    timeout=LOAD_TIMEOUT_MS)
    assert any("foreign.h5" in text for _, text in window.messages.messages)
    window.tabs.setCurrentWidget(window.runs)
    window.runs.set_checked([a, b])
    assert window.runs.note.text() == "2 run(s) compared"
    assert window.runs.table.rowCount() == 4          # 2 runs x 2 components
    backbone = window.runs.graphics.ci.getItem(0, 0)
    assert len(backbone.listDataItems()) == 4         # 2 runs x 2 components

    png = window.runs.export_figure(tmp_path / "out" / "compare.png")
    svg = window.runs.export_figure(tmp_path / "out" / "compare.svg")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 5000
    assert b"<svg" in svg.read_bytes()[:2000]
    rows = list(csv.DictReader(window.runs.export_csv(tmp_path / "out" / "results.csv").open()))
    rows.sort(key=lambda r: (r["run"], r["component"]))
    assert [(r["run"], r["component"]) for r in rows] == [
        ("run A", "0"), ("run A", "1"), ("run B", "0"), ("run B", "1")]
    assert float(rows[0]["c_i"]) == 0.6 and float(rows[2]["c_f"]) == 36.0
    assert float(rows[0]["c_i_ci95_low"]) == 0.5 and rows[1]["c_i"] == ""
    curves = list(csv.DictReader(
        window.runs.export_curves_csv(tmp_path / "out" / "curves.csv").open()))
    kinds = {r["curve"] for r in curves}
    assert kinds == {"backbone", "damping", "equivalent_damping"}
    assert all(r["x"] != "nan" for r in curves)

    # picking a run in the browser shows it in the analysis views
    item = next(window.runs.list.topLevelItem(i) for i in range(2)
                if window.runs.list.topLevelItem(i).text(0) == "run B")
    window.runs._picked(item)
    assert window.analysis.results.name == "run B"
    window.runs.close_run(a)
    assert len(window.runs.runs) == 1


def test_export_figure_of_an_analysis_view(qtbot, make_window, registry, tmp_path):
    from fsi_lab.gui.export import export_figure

    window = make_window(registry)
    window.open_runs([write_run(tmp_path / "v.h5")])
    qtbot.waitUntil(lambda: window.analysis.results is not None, timeout=LOAD_TIMEOUT_MS)
    backbone = window.analysis.views[3]
    out = export_figure(backbone.graphics, tmp_path / "backbone.svg")
    assert out.stat().st_size > 1000


def test_every_compared_curve_has_its_own_colour_and_legend_entry(qtbot, make_window, registry,
                                                                 tmp_path):
    from pyqtgraph import functions as fn

    window = make_window(registry)
    # two runs of the same name (the same profile run twice), two components each
    runs = [write_run(tmp_path / "first.h5"), write_run(tmp_path / "second.h5")]
    with h5py.File(runs[1], "r+") as handle:
        handle.attrs["start_time"] = "2026-01-01T00:10:00"
    window.runs.open(runs)
    qtbot.waitUntil(lambda: len(window.runs.runs) == 2 and not window.runs.pending,
                    timeout=LOAD_TIMEOUT_MS)
    window.tabs.setCurrentWidget(window.runs)
    window.runs.set_checked(runs)
    entries = window.runs.legend.entries
    assert entries == ["synthetic (00:00:00), component 0", "synthetic (00:00:00), component 1",
                       "synthetic (00:10:00), component 0", "synthetic (00:10:00), component 1"]
    backbone = window.runs.graphics.ci.getItem(0, 0)
    colours = {fn.mkBrush(item.opts["symbolBrush"]).color().name()
               for item in backbone.listDataItems()}
    assert len(colours) == 4
    symbols = [item.opts["symbol"] for item in backbone.listDataItems()]
    assert symbols[0] == symbols[1] != symbols[2] == symbols[3]   # a marker per run
    # the legend is outside the plots: a widget above them, not an item in a plot
    assert window.runs.legend.isVisible()
    assert backbone.legend is None


def test_the_runs_legend_shows_every_entry_whole_at_1366x768(qtbot, make_window, registry,
                                                             tmp_path):
    """Issue 14: in the Runs tab the legend was clipped. Three runs with long names, two
    components each, wrap to several lines at 1366x768: every entry is shown whole, inside the
    legend, and the legend inside the tab."""
    from PySide6.QtCore import QPoint, QRect

    from fsi_lab.gui.app import settle

    window = make_window(registry)  # at 1366x768
    name = "wet beam, ramp derivative of {} V*s on the embedded simulated bench"
    runs = [write_run(tmp_path / f"{k}.h5", name=name.format(h), hvd_components=2)
            for k, h in enumerate(("0.01", "0.014", "0.02"))]
    window.runs.open(runs)
    qtbot.waitUntil(lambda: len(window.runs.runs) == 3 and not window.runs.pending,
                    timeout=LOAD_TIMEOUT_MS)
    window.tabs.setCurrentWidget(window.runs)
    window.runs.set_checked(runs)
    assert settle(window), "the layout did not settle"
    legend = window.runs.legend
    labels = legend._labels
    assert len(labels) == len(legend.entries) == 6
    assert len({label.geometry().y() for label in labels}) >= 2  # it wraps at this width
    for label in labels:
        assert label.isVisible(), label.text()
        assert legend.rect().contains(label.geometry()), (label.geometry(), legend.rect())
        assert label.width() >= label.sizeHint().width(), label.text()  # not cut short
    assert legend.height() >= legend.heightForWidth(legend.width())
    tab = window.runs
    assert tab.rect().contains(QRect(legend.mapTo(tab, QPoint(0, 0)), legend.size()))


#: equivalent-damping's amplitude conventions of a run with a beam model, and of one without
MODAL = ("component 0: modal: q_2 = w(x_meas) / W_2(x_meas), W_2(x_meas) = 2 (Eq. 15, "
         "int W^2 = L)")
MEASURED = "component 0: measured (displacement amplitude at the measuring point)"


def _bottom_labels(browser):
    """(text, unit) of the x axis of each compared curve's plot, by curve (a long text is
    broken into lines)."""
    out = {}
    for col, curve in enumerate(browser.registry.views().curves):
        axis = browser.graphics.ci.getItem(0, col).getAxis("bottom")
        out[curve.name] = (axis.labelText.replace("<br>", " "), axis.labelUnits)
    return out


def test_the_compared_amplitude_axes_name_the_amplitude_drawn(qtbot, make_window, registry,
                                                              tmp_path):
    """The Runs tab labelled its amplitude axes "displacement amplitude" and, for C_q,
    "displacement amplitude W", whatever the runs' analyses drew: their C_q is against the
    modal amplitude q when the run has a beam model, and their backbones against the
    displacement at their specimen's measuring point. The axes say what the analysis views
    say, in words that hold for every run compared."""
    from fsi_lab.gui.app import settle

    window = make_window(registry)  # at 1366x768
    modal = [with_specimen_and_convention(write_run(tmp_path / f"{k}.h5", name=f"run {k}"),
                                          MODAL) for k in (1, 2)]
    measured = with_specimen_and_convention(write_run(tmp_path / "m.h5", name="run 3"),
                                            MEASURED, point=0.06)
    window.runs.open([*modal, measured])
    qtbot.waitUntil(lambda: len(window.runs.runs) == 3 and not window.runs.pending,
                    timeout=LOAD_TIMEOUT_MS)
    window.tabs.setCurrentWidget(window.runs)

    window.runs.set_checked(modal)
    assert _bottom_labels(window.runs) == {
        "backbone": ("displacement amplitude at x = 0.08 m", "m"),
        "damping": ("displacement amplitude at x = 0.08 m", "m"),
        "equivalent_damping": ("modal amplitude q = w(x_m) / W(x_m)", "m")}

    window.runs.set_checked([measured])
    assert _bottom_labels(window.runs) == {
        "backbone": ("displacement amplitude at x = 0.06 m", "m"),
        "damping": ("displacement amplitude at x = 0.06 m", "m"),
        "equivalent_damping": ("displacement amplitude at x = 0.06 m", "m")}

    # runs measured at different points, one C_q modal and one as measured
    window.runs.set_checked([*modal, measured])
    assert _bottom_labels(window.runs) == {
        "backbone": ("displacement amplitude at the measuring point", "m"),
        "damping": ("displacement amplitude at the measuring point", "m"),
        "equivalent_damping": ("modal amplitude q = w(x_m) / W(x_m) or measured amplitude "
                               "(per run)", "m")}
    # at 1366x768 each label, on several lines, stays within its own plot's width
    assert settle(window), "the layout did not settle"
    for col in range(3):
        plot = window.runs.graphics.ci.getItem(0, col)
        label = plot.getAxis("bottom").label.sceneBoundingRect()
        box = plot.sceneBoundingRect()
        assert box.left() <= label.left() and label.right() <= box.right(), (col, label, box)


def test_curves_csv_says_which_amplitude_each_run_holds(qtbot, make_window, registry, tmp_path):
    """A run's C_q points are against the modal amplitude q when its equivalent-damping used
    the modal convention: the curves' CSV says so run by run, and does not call them the
    displacement measured."""
    window = make_window(registry)
    modal = with_specimen_and_convention(write_run(tmp_path / "q.h5", name="run q"), MODAL)
    measured = with_specimen_and_convention(write_run(tmp_path / "m.h5", name="run m"),
                                            MEASURED, point=0.06)
    window.runs.open([modal, measured])
    qtbot.waitUntil(lambda: len(window.runs.runs) == 2 and not window.runs.pending,
                    timeout=LOAD_TIMEOUT_MS)
    window.runs.set_checked([modal, measured])
    rows = list(csv.DictReader(
        window.runs.export_curves_csv(tmp_path / "curves.csv").open()))
    axes = {(r["run"], r["curve"]): (r["x_name"], r["x_axis"]) for r in rows}
    assert axes[("run q", "equivalent_damping")] == (
        "amplitude_m", "modal amplitude q = w(x_m) / W(x_m)")
    assert axes[("run m", "equivalent_damping")] == (
        "amplitude_m", "displacement amplitude at x = 0.06 m")
    assert axes[("run q", "backbone")] == (
        "displacement_amplitude_m", "displacement amplitude at x = 0.08 m")
