"""The Sequence tab: a plan built in the tab, started on the embedded simulated bench, stopped
during its settle wait and resumed, with each run's status, the progress and the aggregated
backbone, damping and C_q plots following the record as the runs complete.

Every wait is for a condition (the record's status, the process's end), with a timeout that
only keeps a broken run from hanging; the stop comes during a settle wait of 600 s, so it
cannot miss the sequence, however fast the machine."""

import re
from pathlib import Path

import pytest
from conftest import ROOT, UI_TIMEOUT_MS

from fsi_lab.gui.sequence_tab import plan_text

#: a run of the embedded bench (2 s records) with its analysis
RUN_TIMEOUT_MS = 300000


def status_of(tab, row):
    item = tab.table.item(row, 3)
    return item.text() if item is not None else ""


def test_a_plan_text_the_tab_builds():
    text = plan_text("profiles/base.toml", "excitation.height", ["0.005", " 0.01"], 2, 1.5,
                     "two heights")
    assert text == ('[plan]\nprofile = "profiles/base.toml"\nname = "two heights"\n'
                    'settle_s = 1.5\n\n[[step]]\nname = "excitation.height"\nrepeats = 2\n'
                    '[step.sweep]\n"excitation.height" = [0.005, 0.01]\n')
    assert 'specimen.fluid" = ["air", "water"]' in plan_text("p.toml", "specimen.fluid",
                                                             ["air", "water"])


def test_build_start_stop_resume_and_watch_the_aggregation(qtbot, make_window, tmp_path):
    window = make_window()
    tab = window.sequence
    window.tabs.setCurrentWidget(tab)
    profile = tmp_path / "base.toml"
    profile.write_text((ROOT / "profiles" / "wet-beam-sim.toml").read_text()
                       .replace("duration = 10.0 ", "duration = 2.0 ")
                       .replace('"equivalent-damping", "modal-model"]', '"equivalent-damping"]'))
    text = plan_text(profile, "excitation.height", ["0.005", "0.01"], 1, 600.0)
    assert tab.build_plan(text, tmp_path / "plan.toml")
    out = tmp_path / "runs"
    tab.out_dir.setText(str(out))
    assert tab.status.text() == "plan plan.toml: 2 runs"
    assert tab.start_button.isEnabled() and not tab.stop_button.isEnabled()

    assert tab.start()
    assert tab.stop_button.isEnabled() and not tab.start_button.isEnabled()
    # run 1 completes, and the sequence waits 600 s before run 2: stop it there
    qtbot.waitUntil(lambda: status_of(tab, 0) == "completed", timeout=RUN_TIMEOUT_MS)
    assert status_of(tab, 1) == "pending" and tab.progress.value() == 1
    (figure,) = tab.figures  # the built-in views' figure of the aggregation
    assert figure.points("backbone") > 10 and figure.points("c_q") > 10
    # The aggregate's headline: the 17.063 Hz mode (the bench's own) and its C_i.
    found = re.match(r"aggregate: (\d+\.\d+) Hz \(1 runs\): C_i = ", tab.summary.text())
    assert found and abs(float(found.group(1)) - 17.063) < 0.01, tab.summary.text()
    with qtbot.waitSignal(tab.finished, timeout=UI_TIMEOUT_MS * 4) as ended:
        tab.stop()
    assert ended.args == [130]
    assert tab.record.attrs["status"] == "interrupted"
    assert tab.status.text().startswith("interrupted: 1 of 2 runs completed")
    assert any("the sequence ended interrupted (exit code 130)" in text
               for _, text in window.messages.messages)
    assert tab.resume_button.isEnabled()

    with qtbot.waitSignal(tab.finished, timeout=RUN_TIMEOUT_MS) as ended:
        assert tab.resume()
    assert ended.args == [0]
    assert [status_of(tab, row) for row in range(2)] == ["completed", "completed"]
    assert tab.progress.value() == 2 and tab.progress.maximum() == 2
    assert tab.record.aggregate["sequence_runs"] == [1, 2]
    found = re.match(r"aggregate: (\d+\.\d+) Hz \(2 runs\): C_i = ", tab.summary.text())
    assert found and abs(float(found.group(1)) - 17.063) < 0.01, tab.summary.text()
    # each run's own C_i and C_f in the table, from the aggregation
    assert all(tab.table.item(row, 5).text() for row in range(2))
    # the runs' points and the medians and fitted line on the common amplitude axis
    assert len(figure.plots["c_q"].listDataItems()) == 2 + 2  # two runs, median, fit
    assert len(list(Path(out).glob("2*.h5"))) == 2


def _record_of_one_run(folder, run, sets):
    """A completed sequence of one run in ``folder``, its record holding the aggregation of
    ``run`` analysed with the overrides ``sets`` (mu + M given: the run has no specimen)."""
    from fsi_lab.aggregate import aggregate_extracts
    from fsi_lab.aggregate_extract import ExtractTask, extract_run
    from fsi_lab.plan import load_plan
    from fsi_lab.seqfile import SequenceRecord

    plan = folder.parent / "plan.toml"
    plan.write_text(plan_text(ROOT / "profiles" / "wet-beam-sim.toml", "excitation.height",
                              ["0.005"]))
    folder.mkdir()
    record = SequenceRecord.new(load_plan(plan), folder, {})
    record.attrs["status"] = "completed"
    record.runs[0].update(status="completed", run_file=str(run))
    extract = extract_run(ExtractTask(str(run), sets, 0.05, "run 1"))
    record.aggregate = {**aggregate_extracts([extract]), "sequence_runs": [1]}
    record.save()
    return folder


@pytest.mark.parametrize("sets, amplitude", [
    ((), "displacement amplitude at the measuring point"),
    (("analysis.equivalent-damping.modal_scale=2",), "modal amplitude q = w(x_m) / W(x_m)")],
    ids=["measured", "modal"])
def test_the_aggregation_s_amplitude_axes_name_the_amplitude_drawn(qtbot, make_window, tmp_path,
                                                                   sets, amplitude):
    """The aggregation's plots were labelled "amplitude (m)" whichever amplitude the runs'
    curves are on: the displacement at the measuring point, or the modal amplitude q when the
    aggregated C_i and C_f belong to the modal coordinate. They say which, as the analysis
    views do."""
    from support import write_decay_run

    from fsi_lab.gui.app import settle

    folder = _record_of_one_run(tmp_path / "sequence", write_decay_run(tmp_path / "run.h5"),
                                sets)
    window = make_window()  # at 1366x768
    window.open_paths([folder])
    tab = window.sequence
    window.tabs.setCurrentWidget(tab)
    (figure,) = tab.figures
    assert tab.record is not None and figure.points("c_q") > 0
    labels = {key: (axis.labelText.replace("<br>", " "), axis.labelUnits)
              for key, axis in ((key, plot.getAxis("bottom"))
                                for key, plot in figure.plots.items())}
    assert labels == dict.fromkeys(("backbone", "damping", "c_q"), (amplitude, "m"))
    assert settle(window), "the layout did not settle"
    for plot in figure.plots.values():  # each label within its own plot's width
        label = plot.getAxis("bottom").label.sceneBoundingRect()
        box = plot.sceneBoundingRect()
        assert box.left() <= label.left() and label.right() <= box.right(), (label, box)
