"""Interrupted sequences lose nothing: Ctrl+C or SIGTERM end the run in progress as `fsi-lab
run` ends it and mark the sequence interrupted; `--resume DIR` continues with the first run that
did not complete, repeating none that did, and refuses a plan or base profile that changed; and
after `kill -9`, wherever it comes, the record is whole and the sequence resumable.

The signals come at a count of digitiser blocks (or of record writes), never after a delay, as in
test_interruptions.py: nothing here depends on timing."""

import dataclasses
import json
import os
import signal
import subprocess
import sys

import pytest
from support import SIM_PROFILE, run_main

import fsi_lab.cli as cli_module
import fsi_lab.sequence as sequence_module
from fsi_lab.registry import load_registry
from fsi_lab.runfile import read_run
from fsi_lab.seqfile import SEQUENCE_FILE

SPECTRUM = '[analysis]\nchain = ["spectrum"]\nchannels = ["tip_velocity"]\n'
PLAN = """[plan]
profile = "base.toml"
settle_s = 0.01
[[step]]
name = "levels"
[step.sweep]
"excitation.amplitude" = [0.25, 0.5, 0.75]
"""


@pytest.fixture
def plan(tmp_path):
    (tmp_path / "base.toml").write_text(SIM_PROFILE.format(
        duration=0.5, realtime="false", amplitude=0.5, amplifier_extra="",
        acquisition_extra="", analysis=SPECTRUM))
    path = tmp_path / "plan.toml"
    path.write_text(PLAN)
    return path


def registry_signalling(signum, run, block):
    """The registry, with a digitiser that sends ``signum`` to this process while block
    ``block`` of run ``run`` (counted from 1) is on its way."""
    registry = load_registry()
    descriptor = registry.descriptors["instrument"]["inprocess-acquisition"]
    opened = [0]

    def opening(address, settings, context):
        instrument = descriptor.open(address, settings, context)
        opened[0] += 1
        if opened[0] == run:
            read_block, blocks = instrument.read_block, [0]

            def reading(timeout):
                blocks[0] += 1
                if blocks[0] == block:
                    os.kill(os.getpid(), signum)
                return read_block(timeout)

            instrument.read_block = reading
        return instrument

    registry.descriptors["instrument"]["inprocess-acquisition"] = dataclasses.replace(
        descriptor, open=opening)
    return registry


def show(out):
    code, text, err = run_main("show", str(out), "--json")
    assert code == 0, err
    return json.loads(text)


def resume(out):
    code, text, err = run_main("sequence", "--resume", str(out), "--json")
    return code, json.loads(text), err


def assert_safe(path):
    record = read_run(path, load_data=False)
    assert record.instruments["amplifier"]["final_state"]["output_enabled"] is False
    assert record.instruments["source"]["final_state"]["output_enabled"] is False
    assert record.instruments["source"]["final_state"]["level_v"] == 0.0
    return record


@pytest.mark.parametrize("signum, reason", [(signal.SIGINT, "interrupted (Ctrl+C)"),
                                            (signal.SIGTERM, "received SIGTERM")])
def test_a_signal_ends_the_run_in_progress_and_resume_carries_on(monkeypatch, tmp_path, plan,
                                                                 signum, reason):
    out = tmp_path / "out"
    registry = registry_signalling(signum, run=2, block=3)
    monkeypatch.setattr(cli_module, "_registry", lambda: registry)
    code, text, err = run_main("sequence", str(plan), "--out", str(out), "--json")
    assert code == 130, err
    data = json.loads(text)
    assert data["status"] == "interrupted"
    assert data["error"] == f"step 1 ('levels'), run 2 of 3 (excitation.amplitude=0.5): {reason}"
    assert [r["status"] for r in data["runs"]] == ["completed", "aborted", "pending"]
    assert data["runs"][1]["error"] == reason
    aborted = assert_safe(out / data["runs"][1]["run_file"])  # ended as fsi-lab run ends it
    assert aborted.attrs["exit_status"] == "aborted" and aborted.attrs["error"] == reason
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL  # handlers put back
    assert show(out) == data

    monkeypatch.undo()
    first = data["runs"][0]["run_file"]
    code, data, err = resume(out)
    assert code == 0, err
    assert data["status"] == "completed" and len(data["resumed"]) == 1
    runs = data["runs"]
    assert [r["status"] for r in runs] == ["completed"] * 3
    assert runs[0]["run_file"] == first and runs[0]["attempts"] == []  # not repeated
    assert [a["status"] for a in runs[1]["attempts"]] == ["aborted"]
    assert runs[1]["attempts"][0]["run_file"] != runs[1]["run_file"]
    files = sorted(path.name for path in out.glob("2*.h5"))
    assert files == sorted([r["run_file"] for r in runs] + [runs[1]["attempts"][0]["run_file"]])
    for run in runs:
        record = assert_safe(out / run["run_file"])
        assert record.attrs["exit_status"] == "completed"
        amplitude = run["point"]["excitation.amplitude"]
        assert record.attrs["overrides"] == [f"excitation.amplitude={amplitude}"]
    # resuming a completed sequence changes nothing
    code, again, _ = resume(out)
    assert code == 0 and again == data


def test_a_signal_while_settling_between_runs_interrupts_the_sequence(monkeypatch, tmp_path,
                                                                      plan):
    out = tmp_path / "out"

    def signalled(seconds):
        os.kill(os.getpid(), signal.SIGINT)

    monkeypatch.setattr(sequence_module, "settle_wait", signalled)
    code, text, err = run_main("sequence", str(plan), "--out", str(out), "--json")
    assert code == 130, err
    data = json.loads(text)
    assert data["status"] == "interrupted"
    assert data["error"] == "interrupted between runs: interrupted (Ctrl+C)"
    assert [r["status"] for r in data["runs"]] == ["completed", "pending", "pending"]
    monkeypatch.undo()
    code, data, _ = resume(out)
    assert code == 0 and [r["status"] for r in data["runs"]] == ["completed"] * 3
    assert all(r["attempts"] == [] for r in data["runs"])


def test_a_signal_during_a_runs_analysis_keeps_the_run(monkeypatch, tmp_path, plan):
    registry = load_registry()
    descriptor = registry.descriptors["analysis"]["spectrum"]
    calls = [0]

    def signalling(context, params):
        calls[0] += 1
        if calls[0] == 2:
            os.kill(os.getpid(), signal.SIGTERM)
        return descriptor.run(context, params)

    registry.descriptors["analysis"]["spectrum"] = dataclasses.replace(descriptor,
                                                                       run=signalling)
    monkeypatch.setattr(cli_module, "_registry", lambda: registry)
    out = tmp_path / "out"
    code, text, _ = run_main("sequence", str(plan), "--out", str(out), "--json")
    data = json.loads(text)
    assert code == 130 and data["status"] == "interrupted"
    # the record of run 2 is complete: the run is completed, only its analysis is missing
    assert [r["status"] for r in data["runs"]] == ["completed", "completed", "pending"]
    assert data["runs"][1]["interrupted"] is True and data["runs"][1]["results"] == {}
    assert "the analysis was stopped (received SIGTERM)" in data["runs"][1]["error"]
    monkeypatch.undo()
    code, data, _ = resume(out)
    assert code == 0 and all(r["attempts"] == [] for r in data["runs"])


def test_resume_refuses_a_plan_or_profile_that_changed(monkeypatch, tmp_path, plan):
    out = tmp_path / "out"
    registry = registry_signalling(signal.SIGINT, run=2, block=2)
    monkeypatch.setattr(cli_module, "_registry", lambda: registry)
    assert run_main("sequence", str(plan), "--out", str(out))[0] == 130
    monkeypatch.undo()
    before = (out / SEQUENCE_FILE).read_bytes()
    text = plan.read_text()
    plan.write_text(text.replace("0.75", "0.8"))
    code, data, err = resume(out)
    assert code == 2 and err.count("\n") == 1
    assert data["error"].startswith(f"{plan}: the sequence's plan changed since the sequence in "
                                    f"{out} started (")
    assert "put the file back as it was" in data["error"]
    plan.write_text(text)
    profile = tmp_path / "base.toml"
    profile_text = profile.read_text()
    profile.write_text(profile_text.replace("gain = 2.0", "gain = 3.0"))
    code, data, _ = resume(out)
    assert code == 2 and data["error"].startswith(f"{profile}: the sequence's base profile "
                                                  "changed since")
    assert (out / SEQUENCE_FILE).read_bytes() == before  # refused: the record is untouched
    assert len(list(out.glob("2*.h5"))) == 2  # and nothing was run
    profile.write_text(profile_text)
    code, data, _ = resume(out)
    assert code == 0 and data["status"] == "completed"


# A child process runs the sequence and kills itself with SIGKILL at a chosen point: while block
# 3 of run 2 is on its way ("mid-run"), when the record is about to be written after run 2
# ended ("after-run": its run file is complete, the record still says running), or between
# writing the new record and renaming it over the old one ("mid-save").
KILLER = r"""
import dataclasses, os, signal, sys
import fsi_lab.cli as cli
import fsi_lab.seqfile as seqfile
from fsi_lab.registry import load_registry

plan, out, where = sys.argv[1], sys.argv[2], sys.argv[3]
registry = load_registry()
descriptor = registry.descriptors["instrument"]["inprocess-acquisition"]
opened = [0]

def opening(address, settings, context):
    instrument = descriptor.open(address, settings, context)
    opened[0] += 1
    if where == "mid-run" and opened[0] == 2:
        read_block, blocks = instrument.read_block, [0]
        def reading(timeout):
            blocks[0] += 1
            if blocks[0] == 3:
                os.kill(os.getpid(), signal.SIGKILL)
            return read_block(timeout)
        instrument.read_block = reading
    return instrument

registry.descriptors["instrument"]["inprocess-acquisition"] = dataclasses.replace(
    descriptor, open=opening)
cli._registry = lambda: registry
# saves: the new record, before run 1, after run 1, before run 2, after run 2 (the 5th)
save, replace, saves = seqfile.SequenceRecord.save, os.replace, [0]
def saving(self):
    saves[0] += 1
    if where == "after-run" and saves[0] == 5:
        os.kill(os.getpid(), signal.SIGKILL)
    return save(self)
def replacing(source, target):
    if where == "mid-save" and saves[0] == 5:
        os.kill(os.getpid(), signal.SIGKILL)
    return replace(source, target)
seqfile.SequenceRecord.save = saving
os.replace = replacing
sys.exit(cli.main(["sequence", plan, "--out", out, "-q"]))
"""


@pytest.mark.parametrize("where", ["mid-run", "after-run", "mid-save"])
def test_kill_9_leaves_a_resumable_sequence_wherever_it_comes(tmp_path, plan, where):
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-c", KILLER, str(plan), str(out), where],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == -signal.SIGKILL, proc.stderr
    data = show(out)
    assert data["status"] == "running" and data["stop_time"] == ""
    assert data["note"] == (f"its process ended without finishing it (killed?): fsi-lab "
                            f"sequence --resume {out} continues it")
    first = data["runs"][0]
    assert first["status"] == "completed"
    assert data["runs"][1]["status"] == "running" and data["runs"][2]["status"] == "pending"
    killed = data["runs"][1]["run_file"]
    assert read_run(out / killed, load_data=False).attrs["exit_status"] == (
        "running" if where == "mid-run" else "completed")

    code, data, err = resume(out)
    assert code == 0, err
    runs = data["runs"]
    assert data["status"] == "completed" and [r["status"] for r in runs] == ["completed"] * 3
    assert runs[0] == first  # never repeated
    if where == "mid-run":  # the killed run is run again; its partial file is kept
        assert [(a["run_file"], a["status"]) for a in runs[1]["attempts"]] == [
            (killed, "running")]
        assert "killed?" in runs[1]["attempts"][0]["error"]
        assert runs[1]["run_file"] != killed
    else:  # the run had completed: it is taken from its file, not repeated
        assert runs[1]["run_file"] == killed and runs[1]["attempts"] == []
        assert runs[1]["results"]["tip_velocity"] == []  # spectrum only: no components
    files = {path.name for path in out.glob("2*.h5")}
    assert files == {r["run_file"] for r in runs} | {a["run_file"] for r in runs
                                                       for a in r["attempts"]}
    assert not (out / (SEQUENCE_FILE + ".tmp")).exists()
