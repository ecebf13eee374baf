"""The real window drives runs on the in-process simulated bench (paced in real time)."""

import h5py
import numpy as np
import pytest
from conftest import (
    RUN_TIMEOUT_MS,
    UI_TIMEOUT_MS,
    assert_readable,
    wait_checked,
    wait_finished,
    wet_inprocess_profile,
)
from PySide6.QtCore import Qt

from fsi_lab.chain import default_chain
from fsi_lab.runfile import read_run


def test_start_run_live_plots_then_analysis(qtbot, make_window, registry, tmp_path):
    path = wet_inprocess_profile(tmp_path)
    window = make_window(registry)
    assert window.open_profile(path)
    chain = list(window.session.base.analysis["chain"])
    installed = default_chain(registry)
    assert chain and set(chain) <= set(registry.descriptors["analysis"])
    wait_checked(qtbot, window)
    start = window.run_control.start_button
    qtbot.waitUntil(start.isEnabled, timeout=UI_TIMEOUT_MS)
    # whether the run was still going when each block of data reached the window (the blocks
    # arrive in order, before the run's end; the test does not race the run to look)
    running_at_block = []
    window.forwarder.data.connect(lambda block: running_at_block.append(
        window.run_control.running))
    qtbot.mouseClick(start, Qt.MouseButton.LeftButton)
    assert window.run_control.running and not start.isEnabled()
    assert window.run_control.abort_button.isEnabled()

    # data arrives in the live plots while the run acquires
    qtbot.waitUntil(lambda: window.live.blocks >= 3 and window.live.frames >= 1,
                    timeout=RUN_TIMEOUT_MS)
    assert len(running_at_block) >= 3 and all(running_at_block[:3])
    assert set(window.live.curves) == {"drive", "base_acceleration", "tip_velocity"}
    assert 0 < window.live.samples_shown("tip_velocity") <= 2 * window.live.max_points
    x, _ = window.live.spectra["tip_velocity"].getData()
    assert x is not None and len(x) > 0
    assert window.run_control.progress.value() > 0

    outcome = wait_finished(qtbot, window)
    assert outcome.exit_status == "completed", outcome.error
    assert window.run_control.exit_label.text().startswith("completed")

    # the analysis (fsi-lab analyze, in a child process) fills the views from the run file
    try:
        qtbot.waitUntil(lambda: window.analysis.results is not None
                        and window.analysis.results.path == outcome.path.resolve()
                        and bool(window.analysis.results.analysis), timeout=RUN_TIMEOUT_MS)
    except Exception:  # noqa: BLE001 - pytest-qt's timeout, said with the window's state
        raise AssertionError(f"no analysis shown: state {window.run_control.state_label.text()!r}, "
                             f"job {window.analysis.job}, messages {window.messages.messages}, "
                             f"results {window.analysis.results and window.analysis.results.path}")
    assert window.run_control.state_label.text() == "completed; analysed"
    results = window.analysis.results
    groups = results.analysis["tip_velocity"]
    assert set(groups) == set(chain)
    assert all(group.ok for group in groups.values()), [g.error for g in groups.values()]
    filled = window.analysis.filled()
    expected = {"Overview", "HVD components", "Instantaneous frequency", "Backbone", "Damping",
                "Cq fit", "Spectrum / FRF", "Results", "All datasets"}
    if set(installed) >= {"hvd", "backbone", "damping", "equivalent-damping"}:
        assert {title for title, ok in filled.items() if ok} >= expected
    if "modal-model" in chain:
        assert filled["Modal model"]
    assert window.tabs.currentWidget() is window.analysis
    assert_readable(window, "the analysis after the run")
    assert set(window.analysis.parameters.forms) == set(chain)
    # the bench panel shows the state read back after the safe state
    amplifier = window.bench.boxes["amplifier"]
    assert "output enabled: off" in amplifier.state.text()
    qtbot.waitUntil(lambda: "SIM0001" in amplifier.identity.text(), timeout=UI_TIMEOUT_MS)


def test_abort_mid_run_keeps_partial_data_in_safe_state(qtbot, make_window, sim_profile,
                                                       registry):
    # far longer than the test needs: the abort lands mid-run however slow the machine
    path = sim_profile(duration=120.0, realtime="true")
    window = make_window(registry)
    window.open_profile(path)
    wait_checked(qtbot, window)
    assert window.run_control.start()
    qtbot.waitUntil(lambda: window.live.blocks >= 4, timeout=RUN_TIMEOUT_MS)
    assert window.run_control.state == "running"
    window.run_control.abort_button.click()
    outcome = wait_finished(qtbot, window)
    assert outcome.exit_status == "aborted"
    assert "aborted" in window.run_control.exit_label.text()
    assert window.messages.isVisible() and "aborted" in window.messages.text.text()

    run = read_run(outcome.path)
    assert run.attrs["exit_status"] == "aborted"
    amplifier = run.instruments["amplifier"]["final_state"]
    source = run.instruments["source"]["final_state"]
    assert amplifier["output_enabled"] is False
    assert source["output_enabled"] is False and source["level_v"] == 0.0
    kept = run.channels["tip_velocity"].data
    assert 0.2 * 2000 <= kept.size < 120 * 2000     # partial, not empty, not complete
    assert np.all(np.isfinite(kept))
    assert "output enabled: off" in window.bench.boxes["amplifier"].state.text()
    # the window is ready for the next run
    qtbot.waitUntil(window.run_control.start_button.isEnabled, timeout=UI_TIMEOUT_MS)


def test_stop_mid_run_keeps_a_completed_shortened_run_and_analyses_it(qtbot, make_window,
                                                                      registry, tmp_path):
    duration, rate = 120.0, 10000.0  # far longer than needed: Stop lands mid-run regardless
    path = wet_inprocess_profile(tmp_path, duration=duration, sample_rate=rate)
    window = make_window(registry)
    assert window.open_profile(path)
    wait_checked(qtbot, window)
    control = window.run_control
    stop = control.stop_button
    qtbot.waitUntil(control.start_button.isEnabled, timeout=UI_TIMEOUT_MS)
    assert not stop.isEnabled() and not control.stop()      # nothing to stop yet
    qtbot.mouseClick(control.start_button, Qt.MouseButton.LeftButton)
    assert control.running

    # Stop is offered once the excitation and the acquisition run; data reaches the plots
    qtbot.waitUntil(lambda: window.live.blocks >= 25 and window.live.frames >= 1,
                    timeout=RUN_TIMEOUT_MS)
    qtbot.waitUntil(stop.isEnabled, timeout=UI_TIMEOUT_MS)
    assert control.state == "running" and control.abort_button.isEnabled()
    x, _ = window.live.curves["tip_velocity"].getData()
    assert x is not None and len(x) > 0
    qtbot.mouseClick(stop, Qt.MouseButton.LeftButton)
    assert not stop.isEnabled()                               # one Stop per run
    assert control.abort_button.isEnabled()                   # Abort stays available

    outcome = wait_finished(qtbot, window)
    assert outcome.exit_status == "completed", outcome.error
    assert outcome.stopped_early is True
    assert control.exit_label.text().startswith("completed (stopped early)")
    assert not stop.isEnabled()

    with h5py.File(outcome.path, "r") as handle:
        assert handle.attrs["stopped_early"] == True  # noqa: E712 - numpy bool
    run = read_run(outcome.path)
    assert run.attrs["exit_status"] == "completed" and run.attrs["stopped_early"] is True
    amplifier = run.instruments["amplifier"]["final_state"]
    source = run.instruments["source"]["final_state"]
    assert amplifier["output_enabled"] is False
    assert source["output_enabled"] is False and source["level_v"] == 0.0
    kept = run.channels["tip_velocity"].data
    assert 2.0 * rate <= kept.size < duration * rate / 2      # shortened, not empty
    assert all(c.data.size == kept.size for c in run.channels.values())
    assert np.all(np.isfinite(kept))

    # analysed afterwards exactly as a completed run
    qtbot.waitUntil(lambda: window.analysis.results is not None
                    and window.analysis.results.path == outcome.path.resolve()
                    and bool(window.analysis.results.analysis), timeout=RUN_TIMEOUT_MS)
    assert control.state_label.text() == "completed (stopped early); analysed"
    assert window.tabs.currentWidget() is window.analysis
    groups = window.analysis.results.analysis["tip_velocity"]
    assert set(groups) == set(window.session.base.analysis["chain"])
    assert groups["spectrum"].ok and groups["hvd"].ok, [g.error for g in groups.values()]
    filled = window.analysis.filled()
    assert filled["Overview"] and filled["HVD components"] and filled["Spectrum / FRF"], filled
    assert "output enabled: off" in window.bench.boxes["amplifier"].state.text()
    qtbot.waitUntil(control.start_button.isEnabled, timeout=UI_TIMEOUT_MS)
    assert not stop.isEnabled()


def test_instrument_lost_mid_run_shows_message_and_app_keeps_running(qtbot, make_window,
                                                                     sim_profile, registry):
    path = sim_profile(duration=10.0, realtime="true", acquisition_extra="fail_after_s = 0.6")
    window = make_window(registry)
    window.open_profile(path)
    wait_checked(qtbot, window)
    assert window.run_control.start()
    outcome = wait_finished(qtbot, window)
    assert outcome.exit_status == "failed"
    assert "no answer" in outcome.error
    level, text = window.messages.messages[-1]
    assert level == "ERROR" and "no answer" in text and "safe state" in text
    assert window.messages.isVisible()
    assert "no answer" in window.log.contents()
    run = read_run(outcome.path)
    assert run.attrs["exit_status"] == "failed"
    assert run.instruments["amplifier"]["final_state"]["output_enabled"] is False
    assert run.channels["tip_velocity"].data.size == 1200   # 0.6 s of record at 2000 Hz
    # the bench panel marks the digitiser that stopped answering, and not the safe amplifier
    lost = window.bench.boxes["acquisition"].state
    assert "no answer" in lost.text() and "#b00020" in lost.styleSheet()
    assert "#b00020" not in window.bench.boxes["amplifier"].state.styleSheet()
    # still alive and usable
    assert window.isVisible()
    qtbot.waitUntil(window.run_control.start_button.isEnabled, timeout=UI_TIMEOUT_MS)
    window.designer.run_form.fields["duration"].editor.setValue(0.3)
    wait_checked(qtbot, window)
    assert window.run_control.start()
    # the fault counts record time, so a record shorter than 0.6 s never meets it, however
    # long the run takes on a busy machine
    assert wait_finished(qtbot, window).exit_status == "completed"
    assert window.isVisible()


def test_out_of_bounds_value_refused_and_start_disabled(qtbot, make_window, sim_profile,
                                                        registry):
    window = make_window(registry)
    window.open_profile(sim_profile(duration=1.0))
    wait_checked(qtbot, window)
    start = window.run_control.start_button
    qtbot.waitUntil(start.isEnabled, timeout=UI_TIMEOUT_MS)
    amplitude = window.designer.form.fields["amplitude"]
    amplitude.editor.setValue(25.0)                  # beyond the step plugin's 10 V
    assert "out of bounds" in amplitude.error and amplitude.message.isVisible()
    wait_checked(qtbot, window, ok=None)
    assert not start.isEnabled()
    assert "out of bounds" in window.designer.verdict.text()

    amplitude.editor.setValue(5.0)                   # allowed by the plugin, not by [safety]
    checked = wait_checked(qtbot, window, ok=False)
    assert "max_drive_v" in " ".join(checked.report.problems)
    assert "refused" in window.designer.verdict.text() and not start.isEnabled()
    assert not window.run_control.start()

    amplitude.editor.setValue(0.4)
    checked = wait_checked(qtbot, window)
    assert checked.profile.excitation["amplitude"] == 0.4
    assert "excitation.amplitude=0.4" in checked.overrides
    qtbot.waitUntil(start.isEnabled, timeout=UI_TIMEOUT_MS)
    assert "safe to start" in window.designer.verdict.text()
    x, y = window.designer.preview_curve.getData()
    assert np.max(y) == pytest.approx(0.4)


def test_bench_settings_form_and_refusal(qtbot, make_window, sim_profile, registry):
    window = make_window(registry)
    window.open_profile(sim_profile(duration=1.0))
    wait_checked(qtbot, window)
    gain = window.bench.boxes["amplifier"].form.fields["gain"]
    gain.editor.setValue(500.0)                      # the plugin allows at most 100
    assert gain.error and not window.run_control.can_start()
    gain.editor.setValue(20.0)                       # allowed by the plugin, not by [safety]
    checked = wait_checked(qtbot, window, ok=False)
    assert any("max_gain" in p for p in checked.report.problems)
    gain.editor.setValue(3.0)
    checked = wait_checked(qtbot, window)
    assert checked.profile.roles["amplifier"].settings["gain"] == 3.0


def test_third_party_excitation_plugin_in_the_designer(qtbot, make_window, sim_profile,
                                                      with_example_plugin):
    from fsi_lab.registry import load_registry

    registry = load_registry()
    window = make_window(registry)
    window.open_profile(sim_profile(duration=1.0))
    wait_checked(qtbot, window)
    combo = window.designer.plugin
    index = combo.findData("chirp")
    assert index >= 0, "the example distribution's excitation is offered"
    combo.setCurrentIndex(index)
    assert set(window.designer.form.fields) == {"amplitude", "f_start", "f_stop", "duration"}
    checked = wait_checked(qtbot, window)
    assert checked.profile.excitation_plugin == "chirp"
    assert checked.report.peak_drive_v == pytest.approx(0.1, rel=0.05)
    window.designer.form.fields["f_stop"].editor.setValue(20.0)
    checked = wait_checked(qtbot, window)
    assert checked.profile.excitation["f_stop"] == 20.0
    qtbot.waitUntil(window.run_control.start_button.isEnabled, timeout=UI_TIMEOUT_MS)
    assert window.run_control.start()
    assert wait_finished(qtbot, window).exit_status == "completed"
    run = read_run(window.run_control.outcome.path, load_data=False)
    assert run.excitation["plugin"] == "chirp"
    # the profile is kept verbatim; the switch is recorded like `fsi-lab run --set` would be
    assert 'plugin = "step"' in run.attrs["profile"]
    assert "excitation.plugin=chirp" in run.attrs["overrides"]
    assert "excitation.f_stop=20.0" in run.attrs["overrides"]


def test_safe_state_button_without_a_run(qtbot, make_window, sim_profile, registry):
    window = make_window(registry)
    window.open_profile(sim_profile(duration=1.0))
    window.bench.check_button.click()
    qtbot.waitUntil(lambda: "amplifier" in window.bench.last_report, timeout=RUN_TIMEOUT_MS)
    amplifier = window.bench.boxes["amplifier"]
    assert "SIM0001" in amplifier.identity.text()
    assert set(amplifier.interlocks) >= {"over_travel", "e_stop"}
    window.bench.last_report = {}
    window.bench.safe_button.click()
    qtbot.waitUntil(lambda: "amplifier" in window.bench.last_report, timeout=RUN_TIMEOUT_MS)
    assert window.bench.last_report["amplifier"]["state"]["output_enabled"] is False
    assert "output enabled: off" in amplifier.state.text()
