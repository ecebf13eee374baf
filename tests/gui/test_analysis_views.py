"""Analysis views read /analysis/<channel>/<plugin>/ of run files, tolerant of what is missing."""

from pathlib import Path

import numpy as np
from conftest import (
    LOAD_TIMEOUT_MS,
    RUN_TIMEOUT_MS,
    UI_TIMEOUT_MS,
    with_specimen_and_convention,
    write_corrupt,
    write_foreign,
    write_run,
)

from fsi_lab.gui.results import load_results
from fsi_lab.plugins.analysis.views.amplitude_views import BackboneView, DampingView
from fsi_lab.plugins.analysis.views.equivalent_damping_view import EquivalentDampingView
from fsi_lab.plugins.analysis.views.spectrum_view import SpectrumView
from fsi_lab.plugins.analysis.views.time_views import FrequencyView, HVDView


def _open(qtbot, window, path):
    window.open_runs([path])
    qtbot.waitUntil(lambda: window.analysis.results is not None
                    and window.analysis.results.path == path.resolve(),
                    timeout=LOAD_TIMEOUT_MS)
    # the figures are drawn a slice per turn of the event loop, then the parameter forms built
    qtbot.waitUntil(lambda: not window.analysis.pending, timeout=LOAD_TIMEOUT_MS)
    return window.analysis


def test_views_fill_from_the_plugins_layout(qtbot, make_window, registry, tmp_path):
    views = _open(qtbot, make_window(registry), write_run(tmp_path / "a.h5"))
    filled = views.filled()
    for title in ("Overview", "HVD components", "Instantaneous frequency", "Backbone", "Damping",
                  "Cq fit", "Spectrum / FRF", "Results", "All datasets"):
        assert filled[title], title
    assert not filled["Modal model"]
    assert "not computed" in views.view(type(views.views[6])).note.text()  # modal model
    hvd = views.view(HVDView)
    assert "2 of 2 component(s)" in hvd.note.text() and "cut-offs 4, 1 Hz" in hvd.note.text()
    eq = views.view(EquivalentDampingView)
    text = eq.values.text()
    assert eq.values.isVisibleTo(eq)
    assert "0.65" in text and "33" in text and "R² = 0.914" in text and "[0.55, 0.75]" in text
    # the legends, outside the plots, name every curve once
    assert eq.legend.entries == ["C_q, component 0", "fit, component 0"]
    assert hvd.legend.entries[:3] == ["decomposed record", "sum of components", "component 0"]
    assert hvd.legend.entries.count("envelope") == 1
    table = views.views[-2].table
    assert table.rowCount() == 2 and table.item(0, 2).text() == "0.65"


def test_missing_and_failed_groups_say_so(qtbot, make_window, registry, tmp_path):
    window = make_window(registry)
    views = _open(qtbot, window, write_run(tmp_path / "none.h5", analysis=False))
    assert not any(v for k, v in views.filled().items() if k != "Results")
    assert "not computed" in views.state.text()
    assert "not computed" in views.view(BackboneView).note.text()
    views = _open(qtbot, window, write_run(tmp_path / "failed.h5", failed="damping"))
    assert not views.filled()["Damping"]
    assert "damping failed on tip_velocity: damping: too few peaks" in \
        views.view(DampingView).note.text()
    assert views.filled()["Backbone"]          # the others are still shown
    assert "failed" in views.state.text()


def test_results_reader(tmp_path):
    results = load_results(write_run(tmp_path / "r.h5"))
    hvd = results.result("tip_velocity", "hvd")
    assert hvd.ok and hvd.datasets["components"].shape == (2, 4000)
    assert hvd.units["frequencies"] == "Hz" and hvd.params == {"components": 2}
    assert results.components("tip_velocity")[0]["equivalent_damping"]["c_f"] == 33.0
    assert results.exit_status == "completed"


def test_corrupt_and_foreign_files_show_a_message(qtbot, make_window, registry, tmp_path):
    window = make_window(registry)
    for path, words in ((write_corrupt(tmp_path / "corrupt.h5"), "not a readable HDF5 file"),
                        (write_foreign(tmp_path / "foreign.h5"), "not an fsi-lab run file"),
                        (tmp_path / "missing.h5", "no such file")):
        count = len(window.messages.messages)
        window.open_runs([path])
        qtbot.waitUntil(lambda c=count: len(window.messages.messages) > c,
                        timeout=LOAD_TIMEOUT_MS)
        level, text = window.messages.messages[-1]
        assert level == "ERROR" and words in text and path.name in text
        assert window.messages.isVisible()
    assert window.isVisible() and window.runs.runs == {}
    # still working: a good file opens
    _open(qtbot, window, write_run(tmp_path / "good.h5"))
    assert len(window.runs.runs) == 1


def test_cli_paths_open_profiles_and_runs(qtbot, make_window, registry, tmp_path, sim_profile):
    window = make_window(registry)
    window.open_paths([sim_profile(), write_run(tmp_path / "x.h5"),
                       write_corrupt(tmp_path / "y.hdf5")])
    qtbot.waitUntil(lambda: window.session.current is not None and not window.busy(),
                    timeout=LOAD_TIMEOUT_MS)
    assert window.session.loaded and "x.h5" in window.analysis.title.text()
    assert any("y.hdf5" in text for _, text in window.messages.messages)
    # a profile was given: the Experiment tab stays in front (with run files alone, the
    # Analysis tab comes to the front: tests/gui/test_layout.py)
    assert window.tabs.currentIndex() == 0


def test_a_folder_opens_its_run_files_and_a_sequence_record_is_not_taken_for_one(
        qtbot, make_window, registry, tmp_path):
    """`fsi-lab gui runs/heights/*.h5` caught the sequence's record and opened nothing, and
    `fsi-lab gui runs/heights` said "cannot read the profile (Is a directory)". A folder gives
    its run files; a sequence's record is left to the Sequence tab (here one that cannot be
    read, which says so); a folder without run files is named."""
    import h5py

    from fsi_lab.seqfile import FORMAT, SEQUENCE_FILE

    folder = tmp_path / "heights"
    folder.mkdir()
    first, second = write_run(folder / "a.h5"), write_run(folder / "b.h5")
    with h5py.File(folder / SEQUENCE_FILE, "w") as handle:
        handle.attrs["format"] = FORMAT
    window = make_window(registry)
    window.open_paths([folder])
    qtbot.waitUntil(lambda: len(window.runs.runs) == 2 and not window.busy(),
                    timeout=LOAD_TIMEOUT_MS)
    assert {Path(p).name for p in window.runs.runs} == {"a.h5", "b.h5"}
    assert any(level == "ERROR" and f"{folder}: its sequence record cannot be read" in text
               for level, text in window.messages.messages)
    assert not any("cannot read the profile" in text for _, text in window.messages.messages)
    other = make_window(registry)
    other.open_paths(sorted(folder.glob("*.h5")))           # the glob catches the record
    qtbot.waitUntil(lambda: len(other.runs.runs) == 2 and not other.busy(),
                    timeout=LOAD_TIMEOUT_MS)
    assert {Path(p).resolve() for p in other.runs.runs} == {first.resolve(), second.resolve()}
    empty = tmp_path / "empty"
    empty.mkdir()
    other.open_paths([empty])
    assert any(level == "ERROR" and f"{empty}: a folder with no run file (*.h5) in it" in text
               for level, text in other.messages.messages)


def test_run_files_alone_open_on_the_analysis_tab(qtbot, make_window, registry, tmp_path):
    """Issue 14: ``fsi-lab gui RUN.h5`` opened on an empty Experiment tab."""
    window = make_window(registry)
    window.open_paths([write_run(tmp_path / "x.h5", name="run X")])
    qtbot.waitUntil(lambda: window.analysis.results is not None and not window.busy(),
                    timeout=LOAD_TIMEOUT_MS)
    assert window.tabs.currentWidget() is window.analysis
    assert "x.h5" in window.analysis.title.text()
    assert window.analysis.filled()["Overview"]


def test_a_bad_profile_is_reported(qtbot, make_window, registry, tmp_path):
    window = make_window(registry)
    bad = tmp_path / "bad.toml"
    bad.write_text("[run]\nduration = -1\n")
    assert not window.open_profile(bad)
    level, text = window.messages.messages[-1]
    assert level == "ERROR" and "run.duration" in text and "bad.toml" in text


def test_changing_an_analysis_parameter_reruns_it_off_the_ui_thread(
        qtbot, make_window, tmp_path, with_example_plugin):
    from fsi_lab.registry import load_registry

    registry = load_registry()
    path = write_run(tmp_path / "rerun.h5", analysis=False)
    window = make_window(registry)
    views = _open(qtbot, window, path)
    chain = views.parameters.chain_form.fields["chain"]
    chain.editor.setText("rms")
    chain.editor.editingFinished.emit()
    assert "rms" in views.parameters.forms
    qtbot.waitUntil(lambda: "rms" in views.results.analysis.get("tip_velocity", {}),
                    timeout=RUN_TIMEOUT_MS)
    # the forms of the new results
    qtbot.waitUntil(lambda: not views.pending, timeout=LOAD_TIMEOUT_MS)
    first = views.results.result("tip_velocity", "rms").attrs["rms"]
    scale = views.parameters.forms["rms"].fields["scale"]
    scale.editor.setValue(2.0)
    qtbot.waitUntil(lambda: views.results.result("tip_velocity", "rms").params.get("scale")
                    == 2.0, timeout=RUN_TIMEOUT_MS)
    assert np.isclose(views.results.result("tip_velocity", "rms").attrs["rms"], 2 * first)
    assert views.filled()["All datasets"]


def test_views_draw_the_plugin_layout_directly(qtbot, tmp_path):
    results = load_results(write_run(tmp_path / "d.h5"))
    for cls in (HVDView, FrequencyView, BackboneView, DampingView, EquivalentDampingView,
                SpectrumView):
        view = cls()
        qtbot.addWidget(view)
        view.show_results(results, "tip_velocity")
        assert view.filled, cls.__name__
        view.show_results(results, "base_acceleration")
        assert not view.filled and "not computed" in view.note.text()


def test_a_run_is_drawn_over_turns_of_the_event_loop(qtbot, make_window, registry, tmp_path,
                                                     monkeypatch):
    from fsi_lab.gui.analysis.plotting import MIN_DRAW_POINTS
    from fsi_lab.plugins.analysis.views.overview import OverviewView

    def measured_size(views):
        return views.results.result("tip_velocity", "hvd").datasets["components"].shape[1]

    window = make_window(registry)
    views = window.analysis
    overview = views.view(OverviewView)
    on_return = []  # what is drawn when the slot that received the file returns
    received = views.show_results

    def show_results(results):
        received(results)
        on_return.append((views.pending, [part.filled for part in overview.parts]))

    monkeypatch.setattr(views, "show_results", show_results)
    path = write_run(tmp_path / "turns.h5", rate=10000.0, seconds=10.0)
    window.open_runs([path])
    qtbot.waitUntil(lambda: bool(on_return), timeout=LOAD_TIMEOUT_MS)
    # nothing is drawn in that slot: the figures and then the forms come in later turns of the
    # event loop
    pending, filled = on_return[0]
    assert pending and not any(filled), on_return
    qtbot.waitUntil(lambda: not views.pending, timeout=LOAD_TIMEOUT_MS)
    assert overview.filled and all(part.filled for part in overview.parts)
    assert views.parameters.isEnabled() and views.parameters.chain_form is not None
    # the record is drawn decimated (two points per pixel at most), its peaks kept
    hvd = overview.parts[0]
    curve = hvd._plots[(1, 0)].listDataItems()[0]  # component 0 (the Overview has no record)
    x, y = curve.getData()
    width = max(v.width() for v in hvd.graphics.scene().views())
    assert len(x) <= max(MIN_DRAW_POINTS, 2 * width) + 2 < measured_size(views)
    measured = views.results.result("tip_velocity", "hvd").datasets["components"][0]
    assert np.max(y) >= 0.999 * np.max(measured)   # what was drawn includes the peak


def test_stepper_gives_the_event_loop_back_between_slices(qtbot):
    import math

    from fsi_lab.gui.analysis.stepper import SLICE_S, Stepper

    stepper = Stepper()
    # each step of a drawing takes 5 ms of the stepper's clock (a simulated clock: the test
    # counts steps, whatever the machine's speed)
    now = [0.0]
    stepper.clock = lambda: now[0]
    slices, steps = [], []

    def drawing(name, n):
        for k in range(n):
            now[0] += 0.005
            steps.append((name, k))
            yield

    original = stepper.step

    def counted(deadline=None):
        before = len(steps)
        original(deadline)
        slices.append(len(steps) - before)

    stepper._timer.timeout.disconnect()
    stepper._timer.timeout.connect(counted)
    stepper.add(drawing("a", 6), owner="a")
    stepper.add(drawing("b", 3), owner="b")
    stepper.add(drawing("c", 3), owner="c")
    stepper.cancel("c")
    assert stepper.pending_for("a") and not stepper.pending_for("c")
    qtbot.waitUntil(lambda: not stepper.pending, timeout=UI_TIMEOUT_MS)
    assert [s for s in steps if s[0] == "a"] == [("a", k) for k in range(6)]
    assert len([s for s in steps if s[0] == "b"]) == 3 and not any(s[0] == "c" for s in steps)
    # a slice ends once it has used SLICE_S or completed a drawing: each step takes 5 ms, so a
    # slice holds ceil(SLICE_S / 5 ms) steps at most, and a drawing never shares its last slice
    # with the next one
    most = math.ceil(SLICE_S / 0.005)
    assert max(slices) <= most, slices
    assert [n for n in slices if n] == [most] * (6 // most) + ([6 % most] if 6 % most else []) \
        + [most] * (3 // most) + ([3 % most] if 3 % most else []), slices


def test_time_and_model_curves_land_where_the_plugins_put_them(qtbot, tmp_path):
    import h5py

    from fsi_lab.plugins.analysis.views.amplitude_views import model_trend

    path = write_run(tmp_path / "shifted.h5")
    amp = np.linspace(0.004, 0.0005, 30)
    model_curves = {"backbone_amplitude_model": amp[None, :],
                    "backbone_frequency_model": (17.2 - 9 * amp)[None, :],
                    "damping_amplitude_model": amp[None, :],
                    "damping_velocity_amplitude_model": (2 * np.pi * 17 * amp)[None, :],
                    "damping_zeta_model": (0.011 + 2.1 * amp)[None, :]}
    with h5py.File(path, "r+") as f:
        f["channels/tip_velocity"].attrs["t0"] = 0.25   # the channel starts late on the clock
        f["analysis/tip_velocity/hvd"].attrs["start_s"] = 0.5  # and HVD later still
        group = f.create_group("analysis/tip_velocity/modal-model")
        group.attrs["status"] = "ok"
        for name, data in model_curves.items():
            group.create_dataset(name, data=data)
        zc_times = f["analysis/tip_velocity/instantaneous/frequency_times"][0]
    results = load_results(path)

    frequency = FrequencyView()
    qtbot.addWidget(frequency)
    frequency.show_results(results, "tip_velocity")
    crossings = [item for item in frequency._plots[(0, 0)].listDataItems()
                 if item.name() == "zero crossings, component 0"]
    # instantaneous stores times from the channel's first sample: only the channel's t0 is added
    np.testing.assert_allclose(crossings[0].getData()[0], 0.25 + zc_times[np.isfinite(zc_times)])

    for cls, x_names, y_name in (
            (BackboneView, ("backbone_amplitude_model",), "backbone_frequency_model"),
            (DampingView, ("damping_amplitude_model", "damping_velocity_amplitude_model"),
             "damping_zeta_model")):
        view = cls()
        qtbot.addWidget(view)
        view.show_results(results, "tip_velocity")
        for cell, x_name in zip(((0, 0), (0, 1)), x_names):
            model = [item for item in view._plots[cell].listDataItems()
                     if item.name() == "modal model"]
            assert len(model) == 1, (cls.__name__, cell)
            x, y = model[0].getData()
            expected = model_curves[y_name][0]
            if cls is BackboneView:  # relative to the component's frequency (17 Hz), in %
                expected = 100 * (expected - 17.0) / 17.0
            # drawn as its trend (test_a_model_curve_of_many_half_cycles_is_drawn_as_its_trend)
            trend = model_trend(model_curves[x_name][0], expected)
            np.testing.assert_allclose(x, trend[0])
            np.testing.assert_allclose(y, trend[1])


def test_a_model_curve_of_many_half_cycles_is_drawn_as_its_trend():
    """A modal model's backbone holds one point per half cycle, scattered about its trend: a
    line through them by amplitude zig-zagged across the plot. It is drawn as the medians of
    groups of neighbouring amplitudes; a curve of too few points as it is, by amplitude."""
    from fsi_lab.plugins.analysis.views.amplitude_views import MODEL_BINS, model_trend

    rng = np.random.default_rng(0)
    amp = rng.uniform(0.0, 100.0, 4000)
    trend = 17.0 + 0.01 * amp
    a, v = model_trend(amp, trend + 0.05 * rng.standard_normal(amp.size))
    assert MODEL_BINS - 2 <= a.size <= MODEL_BINS and np.all(np.diff(a) > 0)
    # a bin's medians of 100 points err by about 0.01 together: within 4 of that, where
    # the points scatter by 0.05
    np.testing.assert_allclose(v, 17.0 + 0.01 * a, atol=0.04)
    a, v = model_trend(amp[:12], trend[:12])
    order = np.argsort(amp[:12])
    np.testing.assert_array_equal(a, amp[:12][order])
    np.testing.assert_array_equal(v, trend[:12][order])


def test_rows_are_components_however_short():
    from fsi_lab.gui.analysis.datasets import rows

    three_components_of_two_points = np.arange(6.0).reshape(3, 2)
    assert [list(r) for r in rows(three_components_of_two_points)] == [[0, 1], [2, 3], [4, 5]]
    assert [list(r) for r in rows(np.array([1.0, 2.0]))] == [[1, 2]]


def test_the_bands_method_s_components_are_titled_by_their_bands(qtbot, make_window, registry,
                                                                 tmp_path):
    """The "bands" method's components are its modes' bands: their title named half their
    widths as HVD's low-pass cut-offs ("cut-offs 4.6, 7.89 Hz" for a band of 11.8 to 21 Hz)."""
    path = write_run(tmp_path / "a.h5", hvd_bands=np.array([[11.8, 21.0], [1.5, 2.5]]))
    views = _open(qtbot, make_window(registry), path)
    assert views.filled()["HVD components"]
    note = views.view(HVDView).note.text()
    assert "bands 11.8 to 21, 1.5 to 2.5 Hz" in note and "cut-offs" not in note


def test_amplitude_axes_say_which_amplitude_they_are(qtbot, tmp_path):
    modal = ("component 0: modal: q_2 = w(x_meas) / W_2(x_meas), W_2(x_meas) = 2 (Eq. 15, "
             "int W^2 = L); component 1: modal: q_3 = w(x_meas) / W_3(x_meas), W_3(x_meas) = 2")
    results = load_results(with_specimen_and_convention(write_run(tmp_path / "m.h5"), modal))
    labels = {}
    for cls in (BackboneView, DampingView, EquivalentDampingView):
        view = cls()
        qtbot.addWidget(view)
        view.show_results(results, "tip_velocity")
        assert view.filled, cls.__name__
        bottom = view._plots[(0, 0)].getAxis("bottom")
        labels[cls] = (bottom.labelText, bottom.labelUnits)
    # measured at the measuring point (backbone, damping) vs modal (C_q): never the same words
    assert labels[BackboneView] == ("displacement amplitude at x = 0.08 m", "m")
    assert labels[DampingView] == labels[BackboneView]
    assert labels[EquivalentDampingView] == ("modal amplitude q = w(x_m) / W(x_m)", "m")

    measured = "component 0: measured (displacement amplitude at the measuring point)"
    results = load_results(with_specimen_and_convention(write_run(tmp_path / "w.h5"),
                                                        measured))
    view = EquivalentDampingView()
    qtbot.addWidget(view)
    view.show_results(results, "tip_velocity")
    assert view._plots[(0, 0)].getAxis("bottom").labelText == \
        "displacement amplitude at x = 0.08 m"


def test_the_modal_model_s_amplitude_axes_say_where_the_amplitude_is(qtbot, tmp_path):
    """The modal model's backbone and damping plots said "displacement amplitude": their
    amplitudes are those the Backbone and Damping views draw, at the measuring point."""
    import h5py

    from fsi_lab.plugins.analysis.views.modal_model_view import ModalModelView

    path = with_specimen_and_convention(write_run(tmp_path / "model.h5"), "measured")
    amp = np.linspace(0.004, 0.0005, 30)
    with h5py.File(path, "r+") as f:
        group = f.create_group("analysis/tip_velocity/modal-model")
        group.attrs["status"] = "ok"
        for side in ("measured", "model"):
            group[f"backbone_amplitude_{side}"] = amp[None, :]
            group[f"backbone_frequency_{side}"] = (17.2 - 9 * amp)[None, :]
            group[f"damping_amplitude_{side}"] = amp[None, :]
            group[f"damping_zeta_{side}"] = (0.011 + 2.1 * amp)[None, :]
    view = ModalModelView()
    qtbot.addWidget(view)
    view.show_results(load_results(path), "tip_velocity")
    assert view.filled
    for cell in ((2, 0), (2, 1)):
        axis = view._plots[cell].getAxis("bottom")
        assert (axis.labelText, axis.labelUnits) == ("displacement amplitude at x = 0.08 m",
                                                     "m"), cell


def _text_out_of_sight(editor) -> bool:
    """Whether part of an editor's text is out of sight: wider than a line edit (less its
    2 px inner margins), or in lines a text editor that wraps would scroll to."""
    from PySide6.QtWidgets import QLineEdit, QPlainTextEdit

    if isinstance(editor, QLineEdit):
        margins = editor.textMargins()
        shown = editor.contentsRect().width() - margins.left() - margins.right() - 4
        return editor.fontMetrics().horizontalAdvance(editor.text()) > shown
    scroll = editor.verticalScrollBar()
    return (editor.lineWrapMode() == QPlainTextEdit.LineWrapMode.NoWrap
            or scroll.maximum() > 0 or scroll.value() > 0)


def test_the_analysis_chain_is_shown_whole(qtbot, make_window, registry, tmp_path):
    """At 1366x768 the Analysis tab's chain field showed only part of a chain of six analyses
    (434 px of text in a line edit 162 px wide). Every analysis of the chain is in view."""
    from fsi_lab.gui.app import settle

    window = make_window(registry)  # at 1366x768
    views = _open(qtbot, window, write_run(tmp_path / "a.h5"))
    window.tabs.setCurrentWidget(views)
    assert settle(window), "the layout did not settle"
    chain = views.parameters.chain_form.values()["chain"]
    editor = views.parameters.chain_form.editor("chain")
    assert len(chain) == 6 and editor.isVisible()
    assert [item.strip() for item in editor.text().split(",")] == chain
    assert not _text_out_of_sight(editor), (editor.size(), editor.text())


def test_the_cq_range_shows_the_fit_not_the_noise_floor(qtbot, tmp_path):
    import h5py

    path = write_run(tmp_path / "noisy.h5", c_i=0.65, c_f=0.5)  # C_q 0.65 to 0.83
    rng = np.random.default_rng(3)
    with h5py.File(path, "r+") as f:
        group = f["analysis/tip_velocity/equivalent-damping"]
        amp, cq = group["amplitude"][0], group["c_q"][0]
        # the noise floor: as many points again at tiny amplitudes, C_q scattered by +-2
        floor = rng.uniform(1e-6, 2e-5, amp.size)
        noisy = 0.65 + rng.uniform(-2.0, 2.0, amp.size)
        noisy[:2] = (-2.0, 2.3)
        del group["amplitude"], group["c_q"]
        group["amplitude"] = np.concatenate([amp, floor])[None, :]
        group["c_q"] = np.concatenate([cq, noisy])[None, :]
    view = EquivalentDampingView()
    qtbot.addWidget(view)
    view.show_results(load_results(path), "tip_velocity")
    low, high = view._plots[(0, 0)].viewRange()[1]
    fit = 0.65 + 8 * 0.5 * 2 * np.pi * 17.0 * np.array([0.0, amp.max()]) / (3 * np.pi)
    assert low <= fit.min() and fit.max() <= high       # the fitted line is in view ...
    assert low <= cq.min() and cq.max() <= high         # ... with the points that carry it
    assert low > -2.0 and high < 2.3                    # the noise floor's extremes are not
    assert (high - low) < 2 * (fit.max() - fit.min())   # the fit fills much of the height
    assert "beyond the range shown" in view.note.text()  # and the clipped points are told


def test_backbone_components_are_drawn_relative_to_their_own_frequency(qtbot, tmp_path):
    view = BackboneView()
    qtbot.addWidget(view)
    view.show_results(load_results(write_run(tmp_path / "b.h5")), "tip_velocity")
    plot = view._plots[(0, 0)]
    assert plot.getAxis("left").labelText == "frequency shift (f − f_n) / f_n (%)"
    points = {item.name(): item.getData() for item in plot.listDataItems()}
    amp = np.linspace(0.004, 0.0005, 40)
    # write_run: component 0 at 17 Hz (f_n 17 in the summary), component 1 at 2 Hz
    np.testing.assert_allclose(points["component 0 (f_n = 17 Hz)"][1],
                               100 * (17 - 10 * amp - 17) / 17)
    np.testing.assert_allclose(points["component 1 (f_n = 2 Hz)"][1],
                               100 * (2 - 5 * amp[:-10] - 2) / 2)
    low, high = plot.viewRange()[1]
    # both modes on one axis of a few tenths of a percent: component 0's bend is in view
    assert low <= 100 * (-10 * amp.max()) / 17 and high >= 0 and high - low < 5


def test_analyses_that_failed_for_want_of_hvd_are_named_once_after_it(qtbot, make_window,
                                                                     registry, tmp_path):
    """White noise holds no free decay: hvd is refused, and every analysis after it fails
    for want of its result. The state line gave each one's message in full, hvd's refusal
    repeated inside each; it names them together after hvd's, as fsi-lab analyze does."""
    from support import cli_here

    rng = np.random.default_rng(3)
    csv_path = tmp_path / "noise.csv"
    csv_path.write_text("tip_velocity [m/s]\n" + "\n".join(
        f"{v:.6e}" for v in 1e-3 * rng.standard_normal(4000)) + "\n")
    run = tmp_path / "noise.h5"
    assert cli_here("import", str(csv_path), "--rate", "2000", "-o", str(run)).returncode == 0
    assert cli_here("analyze", str(run), "--mass-per-length", "0.1346").returncode == 2
    text = _open(qtbot, make_window(registry), run).state.text()
    failures = text.removeprefix("failed: ").split("; ")
    assert text.startswith("failed: hvd on tip_velocity: ")
    assert text.count("identify: ") == 1, text
    (wanting,) = [f for f in failures if "for want of" in f]
    assert wanting.endswith("on tip_velocity: no result, for want of hvd's (hvd failed, above)")
    assert "backbone" in wanting and "equivalent-damping" in wanting


def test_an_imported_file_s_title_names_it_once_and_says_where_it_came_from(
        qtbot, make_window, registry, tmp_path):
    """An imported file's run name is its file's: the title named it twice, and gave the
    import's time as the run's start."""
    from fsi_lab.csv_import import import_csv

    t = np.arange(4000) / 1000.0
    v = 0.01 * np.exp(-0.5 * t) * np.sin(2 * np.pi * 12.0 * t)
    source = tmp_path / "decay.csv"
    source.write_text("Time (s),Tip velocity (m/s)\n"
                      + "".join(f"{a:.4f},{b:.6e}\n" for a, b in zip(t, v)))
    path = import_csv(source, tmp_path / "decay.h5", None)
    window = make_window(registry)
    title = _open(qtbot, window, path).title.text()
    assert title.count("decay.h5") == 1, title
    assert "imported from decay.csv at " in title and "UTC" in title, title
    assert "not computed" in window.analysis.state.text()
