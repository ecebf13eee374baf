"""What a sequence records of each run's analysis, and what `fsi-lab show DIR` prints of it: every
component of every analysed channel with its warnings; a run whose analysis Ctrl+C stopped is
analysed by `fsi-lab sequence --resume` (and recorded in sequence.h5), and `show` reflects an
analysis that `fsi-lab analyze` stored in the run file afterwards.

One run of the wet-beam profile on the embedded simulated bench (2 s record), whose analysis
finds two modes, both warned. The Ctrl+C comes when the run's analysis reaches hvd, never after
a delay."""

import dataclasses
import json
import os
import shutil
import signal

import h5py
import pytest
from support import GOOD_PROFILE, run_main

import fsi_lab.cli as cli_module
from fsi_lab.registry import load_registry
from fsi_lab.runfile import read_analysis_summary
from fsi_lab.seqfile import SEQUENCE_FILE
from fsi_lab.summary import warnings_of

PLAN = f"""[plan]
profile = "{GOOD_PROFILE}"
name = "one run"
set = ["run.duration=2", "analysis.chain=spectrum,hvd,equivalent-damping"]
[[step]]
name = "once"
"""


@pytest.fixture(scope="module")
def plan_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("plan") / "plan.toml"
    path.write_text(PLAN)
    return path


@pytest.fixture(scope="module")
def completed(plan_file, tmp_path_factory):
    """The directory of the plan's sequence, run to its end."""
    out = tmp_path_factory.mktemp("completed") / "out"
    code, _, err = run_main("sequence", str(plan_file), "--out", str(out), "--json")
    assert code == 0, err
    return out


@pytest.fixture(scope="module")
def interrupted(plan_file, tmp_path_factory):
    """The directory of the plan's sequence, whose run's analysis Ctrl+C stopped (copy it
    before changing it)."""
    registry = load_registry()
    descriptor = registry.descriptors["analysis"]["hvd"]

    def signalling(context, params):
        os.kill(os.getpid(), signal.SIGINT)
        return descriptor.run(context, params)

    registry.descriptors["analysis"]["hvd"] = dataclasses.replace(descriptor, run=signalling)
    out = tmp_path_factory.mktemp("interrupted") / "out"
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(cli_module, "_registry", lambda: registry)
        code, text, err = run_main("sequence", str(plan_file), "--out", str(out), "--json")
    assert code == 130, err
    run = json.loads(text)["runs"][0]
    assert run["status"] == "completed" and run["interrupted"] is True
    assert run["results"] == {}
    assert read_analysis_summary(out / run["run_file"]) is None  # the run file holds none
    return out


def copy_of(directory, tmp_path):
    return shutil.copytree(directory, tmp_path / "out")


def show_json(out):
    code, text, err = run_main("show", str(out), "--json")
    assert code == 0, err
    return json.loads(text)


def show_text(out):
    code, text, err = run_main("show", str(out))
    assert code == 0, err
    return text


def stored_results(out):
    """Each run's ``results`` attribute, read back from sequence.h5 with h5py."""
    with h5py.File(out / SEQUENCE_FILE, "r") as handle:
        return [json.loads(node.attrs["results"]) for _, node in sorted(handle["runs"].items())]


def components_of(summary):
    return summary["channels"]["tip_velocity"]["components"]


def test_the_record_advises_a_command_that_completes_the_analysis(interrupted):
    run = show_json(interrupted)["runs"][0]
    assert "the analysis was stopped" in run["error"]
    assert f"fsi-lab sequence --resume {interrupted}" in run["error"]


def test_resume_analyses_a_completed_run_whose_analysis_was_stopped(interrupted, tmp_path):
    out = copy_of(interrupted, tmp_path)
    before = show_json(out)["runs"][0]
    code, text, err = run_main("sequence", "--resume", str(out), "--json")
    assert code == 0, err
    data = json.loads(text)
    assert data["status"] == "completed"
    run = data["runs"][0]
    # not run again: the same file, no earlier attempt; its analysis is now in it and recorded
    assert run["run_file"] == before["run_file"] and run["attempts"] == []
    assert run["error"] == ""
    summary = read_analysis_summary(out / run["run_file"])
    assert summary is not None
    expected = [(c["index"], c["frequency_hz"], c["equivalent_damping"]["c_i"])
                for c in components_of(summary)]
    assert len(expected) == 2
    recorded = stored_results(out)[0]["tip_velocity"]
    assert [(c["index"], c["frequency_hz"], c["c_i"]) for c in recorded] == expected
    assert run["results"] == stored_results(out)[0]
    assert data["aggregate"]["sequence_runs"] == [1]
    text = show_text(out)
    assert "the analysis was stopped" not in text.split("\n  run 1 of 1:", 1)[1]
    assert "tip_velocity component 0 at" in text and "tip_velocity component 1 at" in text


def test_show_reflects_an_analysis_stored_later_by_fsi_lab_analyze(interrupted, tmp_path):
    out = copy_of(interrupted, tmp_path)
    run_file = out / show_json(out)["runs"][0]["run_file"]
    code, _, err = run_main("analyze", str(run_file))
    assert code == 0, err
    summary = read_analysis_summary(run_file)
    expected = [(c["index"], c["frequency_hz"]) for c in components_of(summary)]

    run = show_json(out)["runs"][0]
    assert [(c["index"], c["frequency_hz"]) for c in run["results"]["tip_velocity"]] == expected
    assert run["results_from"] == "run file" and run["error"] == ""
    text = show_text(out)
    runs = text.split("\n  run 1 of 1:", 1)[1]  # (the sequence's own error says why it ended)
    assert "the analysis was stopped" not in runs
    assert "tip_velocity component 1 at" in text
    assert "read from its run file" in text
    assert stored_results(out)[0] == {}  # show writes nothing

    # resuming records them in sequence.h5, from the run file (not analysed again)
    code, _, err = run_main("sequence", "--resume", str(out), "--json")
    assert code == 0, err
    assert read_analysis_summary(run_file) == summary
    recorded = stored_results(out)[0]["tip_velocity"]
    assert [(c["index"], c["frequency_hz"]) for c in recorded] == expected
    assert "results_from" not in show_json(out)["runs"][0]


def test_show_prints_every_component_of_a_run(completed):
    run_file = completed / show_json(completed)["runs"][0]["run_file"]
    components = components_of(read_analysis_summary(run_file))
    assert len(components) == 2
    lines = show_text(completed).splitlines()
    for component in components:
        eq = component["equivalent_damping"]
        (ci_low, ci_high), (cf_low, cf_high) = eq["c_i_ci95"], eq["c_f_ci95"]
        # with the intervals, as fsi-lab analyze prints them
        start = (f"tip_velocity component {component['index']} at "
                 f"{component['frequency_hz']:.3f} Hz: C_i = {eq['c_i']:.4g} kg/(m s) "
                 f"(95 %: {ci_low:.4g} to {ci_high:.4g}), C_f = {eq['c_f']:.4g} kg/m^2 "
                 f"(95 %: {cf_low:.4g} to {cf_high:.4g})")
        assert sum(line.strip().startswith(start) for line in lines) == 1, start


def test_the_record_keeps_each_components_warnings_and_show_prints_them(completed):
    run_file = completed / show_json(completed)["runs"][0]["run_file"]
    components = components_of(read_analysis_summary(run_file))
    recorded = stored_results(completed)[0]["tip_velocity"]
    assert len(recorded) == len(components)
    text = show_text(completed)
    for component, result in zip(components, recorded):
        warnings = [f"{key}: {w}" if key else w for key, w in warnings_of(component)]
        assert warnings  # both modes of this short record are warned
        assert result["warnings"] == warnings
        for warning in warnings:
            assert f"warning: {warning}" in text
    assert show_json(completed)["runs"][0]["results"]["tip_velocity"] == recorded


def test_resume_analyses_a_run_without_analysis_in_a_completed_sequence(interrupted, tmp_path):
    # a sequence ends completed with a run whose analysis was not stored when storing it
    # failed (a full disk, say): its record is that of the interrupted one, marked completed
    out = copy_of(interrupted, tmp_path)
    with h5py.File(out / SEQUENCE_FILE, "r+") as handle:
        handle.attrs["status"], handle.attrs["error"] = "completed", ""
    code, text, err = run_main("sequence", "--resume", str(out), "--json")
    assert code == 0, err
    data = json.loads(text)
    assert data["status"] == "completed" and len(data["resumed"]) == 1
    assert len(stored_results(out)[0]["tip_velocity"]) == 2
    assert read_analysis_summary(out / data["runs"][0]["run_file"]) is not None
    # once recorded, resuming changes nothing
    code, text, _ = run_main("sequence", "--resume", str(out), "--json")
    assert code == 0 and json.loads(text) == data


def test_an_analysis_that_identified_nothing_is_not_redone_on_every_resume(tmp_path):
    """A completed run whose analysis ran to its end but found no channel to report has empty
    results: it was taken for one without analysis and analysed again on every --resume. The
    record now says whether the analysis ran (``analysed``); records written before it, with
    empty results, still count as not analysed."""
    from types import SimpleNamespace

    from fsi_lab.sequence import lacks_analysis

    (tmp_path / "run.h5").write_bytes(b"")
    record = SimpleNamespace(directory=tmp_path)
    entry = {"status": "completed", "run_file": "run.h5", "results": {}}
    assert lacks_analysis(record, {**entry, "analysed": False})
    assert not lacks_analysis(record, {**entry, "analysed": True})
    assert lacks_analysis(record, entry)                          # an older record
    assert not lacks_analysis(record, {**entry, "results": {"tip": []}})
    assert not lacks_analysis(record, {**entry, "run_file": "gone.h5", "analysed": False})


def test_a_run_settled_from_its_file_keeps_its_refusal(tmp_path):
    """A run whose process was killed after its analysis was stored, but before the record
    said so, is settled from its run file on resume: when that analysis identified nothing,
    the run's error says so, as for a run the sequence saw end, so that a sequence in which no
    run identified anything still exits 2."""
    from types import SimpleNamespace

    from support import write_decay_run

    from fsi_lab.sequence import NOTHING_IDENTIFIED, settle_unfinished

    noise = write_decay_run(tmp_path / "noise.h5", start=0.0)        # no mode: noise alone
    code, _, err = run_main("analyze", str(noise))
    assert code == 2, err
    decay = write_decay_run(tmp_path / "decay.h5")
    code, _, err = run_main("analyze", str(decay), "--mass-per-length", "0.1")
    assert code == 0, err
    record = SimpleNamespace(directory=tmp_path)
    for name, refused in (("noise.h5", True), ("decay.h5", False)):
        entry = {"run_file": name, "status": "running", "error": "", "stop_time": ""}
        settle_unfinished(record, entry, load_registry())
        assert entry["status"] == "completed" and entry["analysed"] is True
        assert entry["error"].startswith(NOTHING_IDENTIFIED) == refused, entry["error"]
