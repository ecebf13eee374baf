"""An analysis no view knows is drawn by the generic view: its datasets with their units, tabled
with its values; the Results table and the runs browser list its plain values."""

import csv

import numpy as np
from conftest import LOAD_TIMEOUT_MS, write_run

from fsi_lab.gui.analysis.generic_view import GenericView
from fsi_lab.runfile import read_analysis_summary, write_analysis


def third_party_run(path):
    """A run file whose only analysis is a third party's ``peaks`` (unknown to every view):
    an amplitude against a frequency axis (declared), a 2-D dataset, and scalar values."""
    write_run(path, analysis=False)
    f = np.linspace(0.0, 50.0, 201)
    write_analysis(path, {"tip_velocity/peaks": {
        "datasets": {"frequency": f, "level": np.exp(-((f - 17.0) / 2.0) ** 2),
                     "per_component": np.vstack([np.linspace(1, 2, 30), np.linspace(3, 1, 30)])},
        "units": {"frequency": "Hz", "level": "m/s", "per_component": "m"},
        "axes": {"level": "frequency"},
        "attrs": {"status": "ok", "largest_hz": 17.0, "method": "gauss"}, "params": {}}},
        {"run": str(path), "channels": {"tip_velocity": {
            "peak_count": 1, "components": [{"index": 0, "frequency_hz": 17.0,
                                             "peak_level": 0.93}]}}})
    return path


def test_an_unknown_analysis_gets_a_generic_tab_with_units_and_values(qtbot, make_window,
                                                                       registry, tmp_path):
    window = make_window(registry)
    path = third_party_run(tmp_path / "third.h5")
    window.open_runs([path])
    qtbot.waitUntil(lambda: window.analysis.results is not None and not window.analysis.pending,
                    timeout=LOAD_TIMEOUT_MS)
    views = window.analysis
    view = views.view("peaks")
    assert isinstance(view, GenericView)
    # the run has no result of the tab that was shown (the Overview): its own view is shown
    assert views.views[views.tabs.currentIndex()] is view
    filled = views.filled()
    assert filled["peaks"] and filled["Results"]
    assert not filled["Overview"]
    level = view._plots[(0, 0)]
    assert level.getAxis("bottom").labelText == "frequency"
    assert level.getAxis("bottom").labelUnits == "Hz"
    assert (level.getAxis("left").labelText, level.getAxis("left").labelUnits) == ("level", "m/s")
    x, y = level.listDataItems()[0].getData()
    assert x[0] == 0.0 and x[-1] == 50.0 and np.isclose(y.max(), 1.0)
    rows = view._plots[(1, 0)].listDataItems()
    assert [item.name() for item in rows] == ["per_component, row 0", "per_component, row 1"]
    assert view._plots[(1, 0)].getAxis("left").labelUnits == "m"
    table = {view.table.item(r, 0).text(): (view.table.item(r, 1).text(),
                                            view.table.item(r, 2).text())
             for r in range(view.table.rowCount())}
    # exp(-((50 - 17) / 2)^2) = 5.8e-119 at the far end
    assert table["level (against frequency)"] == ("201: 5.799e-119 to 1", "m/s")
    assert table["largest_hz"] == ("17", "") and table["method"] == ("gauss", "")
    assert "level, per_component drawn" in view.note.text()
    # the Results table has a column for the component's plain value
    results = views.view("Results").table
    headers = [results.horizontalHeaderItem(c).text() for c in range(results.columnCount())]
    assert headers == ["component", "frequency (Hz)", "peak_level"]
    assert results.item(0, 2).text() == "0.93"

    # the runs browser's CSV has it too
    window.runs.set_checked([path])
    out = window.runs.export_csv(tmp_path / "values.csv")
    (row,) = list(csv.DictReader(out.open()))
    assert row["peak_level"] == "0.93" and row["frequency_hz"] == "17.0"
    assert "c_i" not in row  # a column no component has a value for is left out

    # a run of the built-ins hides the generic tab again
    window.open_runs([write_run(tmp_path / "builtin.h5")])
    qtbot.waitUntil(lambda: window.analysis.results.path.name == "builtin.h5"
                    and not window.analysis.pending, timeout=LOAD_TIMEOUT_MS)
    assert "peaks" not in views.filled()
    assert read_analysis_summary(path)["channels"]["tip_velocity"]["peak_count"] == 1


class PeaksView(GenericView):
    """A third party's own view of its ``peaks`` analysis (here: the generic drawing under a
    title of its own, which is enough to tell that the GUI took it)."""

    def __init__(self, parent=None):
        super().__init__("peaks", parent)
        self.custom = True


def test_a_plugin_may_give_its_own_view_and_a_broken_one_is_reported(qtbot, make_window,
                                                                      tmp_path):
    from types import ModuleType

    from fsi_lab.hookspecs import hookimpl
    from fsi_lab.presentation import AnalysisView
    from fsi_lab.registry import add_plugin, load_registry

    registry = load_registry()
    module = ModuleType("peaks_views")

    def fsi_lab_addviews(views):
        views.add(AnalysisView("Peaks", ("peaks",), PeaksView, order=5))
        views.add(AnalysisView("Broken", ("other",), lambda: 1 / 0))

    module.fsi_lab_addviews = hookimpl(fsi_lab_addviews)
    add_plugin(registry, module, "peaks-views")
    window = make_window(registry)
    assert any("view 'Broken' left out: ZeroDivisionError" in p for p in window.analysis.problems)
    window.open_runs([third_party_run(tmp_path / "third.h5")])
    qtbot.waitUntil(lambda: window.analysis.results is not None and not window.analysis.pending,
                    timeout=LOAD_TIMEOUT_MS)
    views = window.analysis
    assert views.view("Peaks").custom and "peaks" not in views.generic  # no generic tab
    assert [v.title for v in views.views].index("Peaks") == 1          # by its order
    assert views.filled()["Peaks"]
