"""Ctrl+C and SIGTERM are honoured from the first line of the ``fsi-lab`` script to the last
write (exit 130, one message), also when a library swallows the exception the handler raises;
and a run killed with ``kill -9`` loses at most the span the README promises, whenever the kill
comes."""

import dataclasses
import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from support import SIM_PROFILE, run_main

import fsi_lab.cli as cli_module
from fsi_lab.registry import load_registry
from fsi_lab.runfile import FLUSH_SPAN_S, read_analysis_summary, read_run
from fsi_lab.signals import RunSignals

SPECTRUM = '[analysis]\nchain = ["spectrum"]\nchannels = ["tip_velocity"]\n'


def _profile(tmp_path, duration=0.5, analysis=SPECTRUM, acquisition_extra=""):
    path = tmp_path / "sim.toml"
    path.write_text(SIM_PROFILE.format(duration=duration, realtime="false", amplitude=0.5,
                                       amplifier_extra="", acquisition_extra=acquisition_extra,
                                       analysis=analysis))
    return path


@pytest.mark.parametrize("signum, reason", [(signal.SIGTERM, "received SIGTERM"),
                                            (signal.SIGINT, "interrupted (Ctrl+C)")])
@pytest.mark.parametrize("json_flag", [[], ["--json"]])
def test_a_signal_at_the_start_of_main_exits_130(monkeypatch, signum, reason, json_flag):
    build_parser = cli_module.build_parser

    def signalled_while_starting(*args, **kwargs):  # the first thing main does after its
        os.kill(os.getpid(), signum)                # first line: build the parser
        return build_parser(*args, **kwargs)

    monkeypatch.setattr(cli_module, "build_parser", signalled_while_starting)
    before = signal.getsignal(signal.SIGTERM)
    code, out, err = run_main("plugins", *json_flag)
    assert code == 130
    assert err == f"fsi-lab: interrupted: {reason}\n"
    if json_flag:
        assert json.loads(out) == {"error": f"interrupted: {reason}", "exit_code": 130}
    else:
        assert out == ""
    assert signal.getsignal(signal.SIGTERM) is before  # handlers put back for the caller


# The installed console script in a fresh interpreter, signalled while it is still importing the
# command (at the moment numpy, which every command needs, starts to be imported): no handler of
# main's is in place yet. The point is an import, not a time: nothing depends on the machine's
# speed. ``python -c STARTING SCRIPT SIGNUM ARGS...``
STARTING = r"""
import os, runpy, sys

SIGNUM = int(sys.argv[2])

class SignalledWhileImporting:
    def find_spec(self, name, path=None, target=None):
        if name == "numpy":
            sys.meta_path.remove(self)
            os.kill(os.getpid(), SIGNUM)
        return None

sys.meta_path.insert(0, SignalledWhileImporting())
sys.argv = [sys.argv[1], *sys.argv[3:]]
runpy.run_path(sys.argv[0], run_name="__main__")
"""


@pytest.mark.parametrize("signum, reason", [(signal.SIGTERM, "received SIGTERM"),
                                            (signal.SIGINT, "interrupted (Ctrl+C)")])
@pytest.mark.parametrize("json_flag", [[], ["--json"]])
def test_a_signal_while_the_command_is_still_importing_exits_130(tmp_path, signum, reason,
                                                                 json_flag):
    script = Path(sys.executable).with_name("fsi-lab")
    assert script.is_file(), f"{script}: the fsi-lab console script is not installed beside " \
                             "the interpreter running the tests"
    out = tmp_path / "runs"
    proc = subprocess.run([sys.executable, "-c", STARTING, str(script), str(int(signum)), "run",
                           str(_profile(tmp_path)), "--out", str(out), *json_flag],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 130, (proc.returncode, proc.stderr)  # not killed (143), no trace
    assert proc.stderr == f"fsi-lab: interrupted: {reason}\n"
    if json_flag:
        assert json.loads(proc.stdout) == {"error": f"interrupted: {reason}", "exit_code": 130}
    else:
        assert proc.stdout == ""
    assert not out.exists()  # nothing was started


def _registry_whose_spectrum_swallows(signum):
    """The registry with a spectrum analysis that receives ``signum`` and swallows the
    exception its handler raises, as library cleanup code may."""
    registry = load_registry()
    descriptor = registry.descriptors["analysis"]["spectrum"]

    def swallowing(context, params):
        try:
            os.kill(os.getpid(), signum)
        except BaseException:  # noqa: BLE001 - what the test is about
            pass
        return descriptor.run(context, params)

    registry.descriptors["analysis"]["spectrum"] = dataclasses.replace(descriptor,
                                                                       run=swallowing)
    return registry


@pytest.mark.parametrize("signum, reason", [(signal.SIGTERM, "received SIGTERM"),
                                            (signal.SIGINT, "interrupted (Ctrl+C)")])
def test_a_swallowed_signal_during_the_analysis_after_a_run_stops_it(monkeypatch, tmp_path,
                                                                     signum, reason):
    monkeypatch.setattr(cli_module, "_registry", lambda: _registry_whose_spectrum_swallows(signum))
    code, out, err = run_main("run", str(_profile(tmp_path)), "--out", str(tmp_path / "runs"),
                              "--json")
    assert code == 130, err
    data = json.loads(out)
    assert data["exit_status"] == "completed" and data["interrupted"] is True
    assert data["error"] == (f"the analysis was stopped ({reason}); the record is complete: "
                             "run `fsi-lab analyze` on the file")
    assert data["analysis"] is None and read_analysis_summary(data["run"]) is None
    record = read_run(data["run"])
    assert record.attrs["exit_status"] == "completed"
    assert record.channels["tip_velocity"].data.size == 1000
    assert data["final_state"]["amplifier"]["output_enabled"] is False


def test_a_swallowed_sigterm_during_analyze_stops_it_before_it_writes(monkeypatch, tmp_path):
    code, out, err = run_main("run", str(_profile(tmp_path)), "--out", str(tmp_path / "runs"),
                              "--json")
    assert code == 0, err
    path = json.loads(out)["run"]
    before = read_analysis_summary(path)
    monkeypatch.setattr(cli_module, "_registry",
                        lambda: _registry_whose_spectrum_swallows(signal.SIGTERM))
    code, out, err = run_main("analyze", path)
    assert code == 130 and err.endswith("fsi-lab: interrupted: received SIGTERM\n"), err
    assert read_analysis_summary(path) == before  # the stored analysis is left as it was


def _interrupt_the_first_hold(monkeypatch) -> None:
    """Ctrl+C in the instant before the run first holds signals (as the bench is made safe)."""
    held, calls = RunSignals.held, []

    def interrupted_once(self):
        calls.append(1)
        if len(calls) == 1:
            raise KeyboardInterrupt
        return held(self)

    monkeypatch.setattr(RunSignals, "held", interrupted_once)


def test_a_signal_just_before_the_safe_state_does_not_skip_it(monkeypatch, tmp_path):
    _interrupt_the_first_hold(monkeypatch)
    code, out, err = run_main("run", str(_profile(tmp_path)), "--out", str(tmp_path / "runs"),
                              "--json")
    data = json.loads(out)
    assert code == 130 and data["interrupted"] is True, err
    assert data["exit_status"] == "completed" and data["analysis"] is None  # analysis skipped
    assert data["final_state"]["amplifier"]["output_enabled"] is False
    assert data["final_state"]["source"]["output_enabled"] is False
    assert read_run(data["run"]).attrs["exit_status"] == "completed"  # the file finalised


# Runs in child processes, each killing itself with SIGKILL at a chosen point: while block `k`
# is on its way (inside the digitiser's read_block) or just after block `k` was appended,
# before the flush decision. Nothing depends on timing: the point is a count of blocks. One
# interpreter forks a child per point (imports are paid once) and prints what each file kept.
KILLER = r"""
import dataclasses, json, os, signal, sys
import h5py
from fsi_lab.profile import load_profile
from fsi_lab.registry import load_registry
from fsi_lab.runfile import RunFileWriter
from fsi_lab.runner import Runner

profile_path, out, where, points = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
registry = load_registry()
descriptor = registry.descriptors["instrument"]["inprocess-acquisition"]
blocks, kill_at = [0], [0]

def opened(address, settings, context):
    instrument = descriptor.open(address, settings, context)
    read_block = instrument.read_block
    def counting(timeout):
        blocks[0] += 1
        if where == "in-transit" and blocks[0] == kill_at[0]:
            os.kill(os.getpid(), signal.SIGKILL)
        return read_block(timeout)
    instrument.read_block = counting
    return instrument

registry.descriptors["instrument"]["inprocess-acquisition"] = dataclasses.replace(
    descriptor, open=opened)
flush_if_due = RunFileWriter.flush_if_due
def deciding(self):
    if where == "appended" and blocks[0] == kill_at[0]:
        os.kill(os.getpid(), signal.SIGKILL)
    return flush_if_due(self)
RunFileWriter.flush_if_due = deciding
profile = load_profile(profile_path, registry)
for k in range(1, points + 1):
    folder = os.path.join(out, str(k))
    pid = os.fork()
    if pid == 0:
        kill_at[0] = k
        Runner(profile, registry, folder, analyze=False).run()
        os._exit(0)
    _, status = os.waitpid(pid, 0)
    with h5py.File(os.path.join(folder, os.listdir(folder)[0]), "r") as handle:
        print(json.dumps({"k": k, "killed": os.WIFSIGNALED(status)
                          and os.WTERMSIG(status) == signal.SIGKILL,
                          "exit_status": handle.attrs["exit_status"],
                          "kept": handle["channels/tip_velocity"].shape[0]}), flush=True)
"""


@pytest.mark.parametrize("where", ["in-transit", "appended"])
def test_kill_9_loses_at_most_the_promised_span_whenever_it_comes(tmp_path, where):
    rate, block_s = 2000.0, 0.1  # the profile's rate and the digitiser's blocks
    profile = _profile(tmp_path, duration=2.0, analysis="",
                       acquisition_extra=f"block_duration = {block_s}")
    points = 2 * round(FLUSH_SPAN_S / block_s) + 1  # every point of two flush cycles
    proc = subprocess.run([sys.executable, "-c", KILLER, str(profile), str(tmp_path / "runs"),
                           where, str(points)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    results = [json.loads(line) for line in proc.stdout.splitlines()]
    assert [r["k"] for r in results] == list(range(1, points + 1))
    for result in results:
        assert result["killed"] and result["exit_status"] == "running", result
        reached = result["k"] * block_s * rate  # samples recorded when the kill came
        lost_s = (reached - result["kept"]) / rate
        assert 0 <= lost_s <= FLUSH_SPAN_S + 1e-9, (where, result, lost_s)
    assert max((r["k"] * block_s * rate - r["kept"]) / rate for r in results) \
        == pytest.approx(FLUSH_SPAN_S)  # the worst case was among the points tried


@pytest.mark.parametrize("during_acquisition", [True, False])
def test_a_second_signal_while_finalizing_is_said_of_a_completed_record_only(
        monkeypatch, tmp_path, during_acquisition):
    """Ctrl+C during the acquisition aborts the run; a second one (a terminal's Ctrl+C reaches
    every process of the group) that comes as the bench is made safe must not be reported as
    an interruption while finalizing whose analysis is skipped: only a completed record has
    one to skip."""
    from fsi_lab.runner import Runner

    _interrupt_the_first_hold(monkeypatch)
    if during_acquisition:
        def interrupted(self, block, sensitivities):
            raise KeyboardInterrupt

        monkeypatch.setattr(Runner, "_check_block", interrupted)  # at the first block
    code, out, err = run_main("run", str(_profile(tmp_path)), "--out", str(tmp_path / "runs"),
                              "--json")
    data = json.loads(out)
    assert code == 130, err
    if during_acquisition:
        assert data["exit_status"] == "aborted"
        assert "interrupted while finalizing" not in err, err
    else:
        assert data["exit_status"] == "completed"
        assert "[warning] interrupted while finalizing the completed record: the analysis is " \
            "skipped" in err, err
