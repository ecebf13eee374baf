"""Run orchestration: lifecycle, events, and the safe state on every exit path."""

import re
import shutil
import signal
import subprocess
import threading

import h5py
import numpy as np
import pytest
from support import LineReader, start_cli

from fsi_lab.events import DataBlock, EventBus, StateChanged
from fsi_lab.profile import load_profile
from fsi_lab.runfile import read_run
from fsi_lab.runner import Runner


def _run(profile_path, registry, out, **runner_kwargs):
    bus = EventBus()
    events = []
    bus.subscribe(events.append)
    profile = load_profile(profile_path, registry)
    runner = Runner(profile, registry, out, bus=bus, **runner_kwargs)
    return runner, runner.run, events


def _assert_safe(path):
    run = read_run(path, load_data=False)
    amplifier = run.instruments["amplifier"]["final_state"]
    source = run.instruments["source"]["final_state"]
    assert amplifier["output_enabled"] is False
    assert source["output_enabled"] is False and source["level_v"] == 0.0
    return run


def test_completed_run_writes_everything(sim_profile, registry, tmp_path):
    _, run, events = _run(sim_profile(duration=1.0), registry, tmp_path)
    outcome = run()
    assert outcome.exit_status == "completed" and outcome.error is None
    assert re.fullmatch(r"\d{8}-\d{6}_[0-9a-f]{8}\.h5", outcome.path.name)
    record = _assert_safe(outcome.path)
    assert record.attrs["exit_status"] == "completed"
    assert record.attrs["uuid"].startswith(outcome.path.name[16:24])
    assert record.attrs["profile"].startswith("\n[run]")
    assert "fsi-lab" in record.attrs["plugin_versions"]["step"]
    assert record.attrs["stop_time"] > record.attrs["start_time"]
    assert record.instruments["amplifier"]["settings"]["gain"] == 2.0
    assert "SIM0001" in record.instruments["vibrometer"]["identity"]

    run_data = read_run(outcome.path)
    velocity = run_data.channels["tip_velocity"]
    assert velocity.data.shape == (2000,) and velocity.sample_rate == 2000.0
    assert run_data.channel_attrs["tip_velocity"]["sensitivity"] == pytest.approx(8.0)  # 125 mm/s/V
    assert run_data.channel_attrs["base_acceleration"]["units"] == "m/s^2"
    # the step moved the base and the beam responded
    assert np.max(np.abs(velocity.data)) > 1e-3
    excitation = run_data.excitation
    assert excitation["plugin"] == "step" and excitation["sample_rate"] == 2000.0
    assert excitation["params"]["amplitude"] == 0.5
    assert excitation["waveform"].max() == pytest.approx(0.5)

    states = [e.state for e in events if isinstance(e, StateChanged)]
    assert states == ["configuring", "armed", "running", "finalizing", "completed"]
    blocks = [e for e in events if isinstance(e, DataBlock)]
    assert sum(len(b.data["tip_velocity"]) for b in blocks) == 2000
    assert np.allclose(np.concatenate([b.data["tip_velocity"] for b in blocks]), velocity.data)


def test_dead_instrument_ends_failed_in_safe_state_with_data_kept(sim_profile, registry, tmp_path):
    path = sim_profile(duration=5.0, acquisition_extra="fail_after_s = 0.6")
    _, run, events = _run(path, registry, tmp_path)
    outcome = run()
    assert outcome.exit_status == "failed"
    assert "no answer (simulated failure after 0.6 s)" in outcome.error
    record = _assert_safe(outcome.path)
    assert record.attrs["exit_status"] == "failed"
    assert "InstrumentError" in record.attrs["traceback"]
    # the dead digitiser's state could not be read back, and the file says so
    assert "no answer" in record.instruments["acquisition"]["final_state"]["error"]
    # the fault counts record time: exactly 0.6 s of data at 2000 Hz came in before it
    kept = read_run(outcome.path).channels["tip_velocity"].data
    assert kept.size == 1200


def test_interlock_trip_ends_failed_and_safe(sim_profile, registry, tmp_path):
    path = sim_profile(duration=5.0, amplifier_extra="interlock_after_s = 0.4")
    _, run, _ = _run(path, registry, tmp_path)
    outcome = run()
    assert outcome.exit_status == "failed"
    assert "amplifier interlock tripped: over_travel" in outcome.error
    record = _assert_safe(outcome.path)
    assert record.instruments["amplifier"]["final_state"]["interlocks"] == {"over_travel": True}


def test_dead_amplifier_is_still_recorded(sim_profile, registry, tmp_path):
    path = sim_profile(duration=5.0, amplifier_extra="fail_after_s = 0.4")
    _, run, _ = _run(path, registry, tmp_path)
    outcome = run()
    assert outcome.exit_status == "failed" and "amplifier" in outcome.error
    _assert_safe(outcome.path)


def test_simulated_faults_count_record_time_not_the_wall_clock(sim_profile, registry, tmp_path,
                                                              monkeypatch):
    """A fault set beyond the end of the record never strikes, however long the run takes on
    the wall clock: here every block is delivered as if the machine had stalled for 2 s."""
    from fsi_lab.instruments import inprocess

    read_block = inprocess.InProcessAcquisition.read_block
    stalled = []

    def slow_read_block(self, timeout):
        stalled.append(2.0)  # seconds a slow, loaded machine might lose here
        return read_block(self, timeout)

    monkeypatch.setattr(inprocess.time, "monotonic",
                        lambda base=inprocess.time.monotonic: base() + sum(stalled))
    monkeypatch.setattr(inprocess.InProcessAcquisition, "read_block", slow_read_block)
    path = sim_profile(duration=0.5, acquisition_extra="fail_after_s = 0.6",
                       amplifier_extra="fail_after_s = 0.6\ninterlock_after_s = 0.6")
    _, run, _ = _run(path, registry, tmp_path)
    outcome = run()
    assert outcome.exit_status == "completed", outcome.error
    assert sum(stalled) > 0.6                          # the wall clock went well past the fault
    assert read_run(outcome.path).channels["tip_velocity"].data.size == 1000


def test_abort_from_another_thread(sim_profile, registry, tmp_path):
    runner, run, events = _run(sim_profile(duration=20.0, realtime="true"), registry, tmp_path)
    started = threading.Event()
    runner.bus.subscribe(lambda e: isinstance(e, DataBlock) and started.set())
    thread = threading.Thread(target=lambda: (started.wait(10), runner.abort()))
    thread.start()
    outcome = run()
    thread.join(timeout=10)
    assert outcome.exit_status == "aborted" and outcome.error == "aborted by the operator"
    _assert_safe(outcome.path)


def test_stop_keeps_a_shortened_completed_run_and_analyses_it(sim_profile, registry, tmp_path):
    analysis = '[analysis]\nchain = ["spectrum"]\nchannels = ["tip_velocity"]\n'
    runner, run, events = _run(sim_profile(duration=20.0, realtime="true", analysis=analysis),
                               registry, tmp_path)
    blocks = []

    def stop_after_three_blocks(event):
        if isinstance(event, DataBlock):
            blocks.append(event)
            if len(blocks) == 3:
                runner.stop()

    runner.bus.subscribe(stop_after_three_blocks)
    outcome = run()
    assert outcome.exit_status == "completed" and outcome.stopped_early
    assert outcome.as_json()["stopped_early"] is True
    record = _assert_safe(outcome.path)
    assert record.attrs["exit_status"] == "completed" and record.attrs["stopped_early"] is True
    kept = read_run(outcome.path).channels["tip_velocity"].data
    # the block in hand when Stop came is the last one stored, far short of 20 s at 2 kHz
    assert kept.size == sum(len(b.data["tip_velocity"]) for b in blocks) < 40000
    assert "spectrum_peaks_hz" in outcome.summary["channels"]["tip_velocity"]
    states = [e.state for e in events if isinstance(e, StateChanged)]
    assert states[-2:] == ["completed", "analyzing"]


def test_stop_before_the_excitation_starts_aborts_the_run(sim_profile, registry, tmp_path):
    runner, run, events = _run(sim_profile(duration=5.0), registry, tmp_path)
    runner.bus.subscribe(lambda e: isinstance(e, StateChanged) and e.state == "armed"
                         and runner.stop())
    outcome = run()
    assert outcome.exit_status == "aborted" and not outcome.stopped_early
    assert outcome.error == "stopped by the operator before the excitation started"
    record = _assert_safe(outcome.path)
    assert record.attrs["exit_status"] == "aborted" and record.attrs["stopped_early"] is False
    # nothing was excited, so nothing was acquired
    assert not any(isinstance(e, DataBlock) for e in events)
    assert "running" not in [e.state for e in events if isinstance(e, StateChanged)]


def test_completed_run_is_not_marked_stopped(sim_profile, registry, tmp_path):
    _, run, _ = _run(sim_profile(duration=0.5), registry, tmp_path)
    outcome = run()
    assert outcome.exit_status == "completed" and not outcome.stopped_early
    assert read_run(outcome.path, load_data=False).attrs["stopped_early"] is False


@pytest.mark.parametrize("signum, expected_code", [(signal.SIGINT, 130), (signal.SIGTERM, 130)])
def test_signal_aborts_the_run_in_safe_state(sim_profile, tmp_path, signum, expected_code):
    out = tmp_path / "runs"
    proc = start_cli("run", str(sim_profile(duration=30.0, realtime="true")), "--out", str(out),
                     "--verbose")
    try:
        stderr = LineReader(proc.stderr)
        stderr.wait_for(lambda line: line.startswith("[debug] flushed"), timeout=60)
        proc.send_signal(signum)
        assert proc.wait(timeout=30) == expected_code
    finally:
        proc.kill()
        proc.wait(timeout=10)
    path = next(out.glob("*.h5"))
    record = _assert_safe(path)
    assert record.attrs["exit_status"] == "aborted"
    assert record.channels["tip_velocity"] is not None
    with h5py.File(path, "r") as handle:
        assert 0 < handle["channels/tip_velocity"].shape[0] < 60000


def test_killed_run_leaves_a_readable_file(sim_profile, tmp_path):
    out = tmp_path / "runs"
    proc = start_cli("run", str(sim_profile(duration=30.0, realtime="true")), "--out", str(out),
                     "--verbose")
    try:
        stderr = LineReader(proc.stderr)
        line = ""
        for _ in range(3):  # wait for the third flush
            line = stderr.wait_for(lambda text: text.startswith("[debug] flushed"), timeout=60)
        flushed = int(re.search(r"flushed (\d+) samples", line).group(1))
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=10)
    finally:
        proc.kill()
        proc.wait(timeout=10)
    path = next(out.glob("*.h5"))
    with h5py.File(path, "r") as handle:
        assert handle.attrs["exit_status"] == "running"
        for name in ("tip_velocity", "base_acceleration"):
            data = handle["channels"][name][()]
            assert data.size >= flushed > 0
            assert np.all(np.isfinite(data))
    h5dump = shutil.which("h5dump")
    assert h5dump, "h5dump (hdf5-tools) is needed; `make test` installs it"
    dump = subprocess.run([h5dump, "-A", str(path)], capture_output=True, text=True, timeout=60)
    assert dump.returncode == 0, dump.stderr
    assert "tip_velocity" in dump.stdout and '"running"' in dump.stdout


def test_stop_with_the_last_block_is_a_plain_completed_run(sim_profile, registry, tmp_path):
    runner, run, _ = _run(sim_profile(duration=0.5), registry, tmp_path)

    def stop_on_the_last_block(event):
        if isinstance(event, DataBlock):
            end = event.t0 + len(event.data["tip_velocity"]) / event.sample_rate
            if end >= 0.5 - 1e-9:
                runner.stop()

    runner.bus.subscribe(stop_on_the_last_block)
    outcome = run()
    assert runner._stop.is_set()  # the stop did arrive, with the record already complete
    assert outcome.exit_status == "completed" and not outcome.stopped_early
    assert read_run(outcome.path).channels["tip_velocity"].data.size == 1000


def test_an_excitation_plugin_that_fails_is_named_before_anything_starts(sim_profile, registry,
                                                                         tmp_path):
    import dataclasses

    from fsi_lab.errors import PluginError

    def broken(params, rate):
        raise ValueError("math domain error")

    step = registry.descriptors["excitation"]["step"]
    registry.descriptors["excitation"]["step"] = dataclasses.replace(step, generate=broken)
    runner, run, events = _run(sim_profile(), registry, tmp_path / "runs")
    with pytest.raises(PluginError, match=r"sim\.toml: excitation plugin 'step' failed to "
                                          r"generate its waveform .* ValueError: math domain"):
        run()
    assert not (tmp_path / "runs").exists() and not events  # nothing written, nothing driven


def _with_instrument(registry, plugin, change):
    """The registry with ``change(instrument)`` applied to each instrument ``plugin`` opens
    (a fault of our own in-process instruments)."""
    import dataclasses

    descriptor = registry.descriptors["instrument"][plugin]

    def open_changed(address, settings, context):
        instrument = descriptor.open(address, settings, context)
        change(instrument)
        return instrument

    registry.descriptors["instrument"][plugin] = dataclasses.replace(descriptor,
                                                                     open=open_changed)
    return registry


def _with_acquisition(registry, mangle):
    """The registry with its in-process digitiser's blocks passed through ``mangle(n, block)``."""

    def change(instrument):
        read_block, count = instrument.read_block, [0]

        def mangled(timeout):
            block = read_block(timeout)
            count[0] += 1
            return block if block is None else mangle(count[0], dict(block))

        instrument.read_block = mangled

    return _with_instrument(registry, "inprocess-acquisition", change)


def test_an_amplifier_left_on_fails_the_run_however_it_ended(sim_profile, registry, tmp_path):
    attempts = []

    def stuck(instrument):  # an amplifier whose output stage no longer obeys OUTP 0
        safe_state = instrument.safe_state

        def stuck_on():
            attempts.append(len(attempts))
            if len(attempts) > 1:  # the first comes as the runner opens it
                raise RuntimeError("relay welded: output stays on")
            safe_state()

        instrument.safe_state = stuck_on

    registry = _with_instrument(registry, "inprocess-amplifier", stuck)
    _, run, _ = _run(sim_profile(duration=0.5), registry, tmp_path)
    outcome = run()
    assert len(attempts) == 3  # on opening, then the safe state and its second attempt
    assert outcome.exit_status == "failed"
    assert outcome.error.startswith("NOT confirmed safe after the run: amplifier: safe state "
                                    "failed: RuntimeError: relay welded"), outcome.error
    record = read_run(outcome.path, load_data=False)
    assert record.attrs["exit_status"] == "failed" and record.attrs["error"] == outcome.error
    assert "relay welded" in record.instruments["amplifier"]["final_state"]["safe_state_error"]
    assert record.instruments["source"]["final_state"]["output_enabled"] is False


@pytest.mark.parametrize("mangle, message", [
    (lambda n, b: {k: v for k, v in b.items() if not (n == 2 and k == "base_acceleration")},
     r"a block lacks channel\(s\) base_acceleration; expected base_acceleration, tip_velocity"),
    (lambda n, b: {k: (v[:-10] if n == 3 and k == "tip_velocity" else v) for k, v in b.items()},
     r"a block's channels differ in length \(.*tip_velocity \d+.*\); expected equal lengths"),
])
def test_a_malformed_block_fails_the_run_with_the_channels_kept_aligned(
        sim_profile, registry, tmp_path, mangle, message):
    _, run, _ = _run(sim_profile(duration=1.0), _with_acquisition(registry, mangle), tmp_path)
    outcome = run()
    assert outcome.exit_status == "failed" and re.search(message, outcome.error), outcome.error
    _assert_safe(outcome.path)
    lengths = {name: c.data.size for name, c in read_run(outcome.path).channels.items()}
    assert len(set(lengths.values())) == 1 and 0 < lengths["tip_velocity"] < 2000, lengths


def test_a_full_disk_fails_the_run_with_a_message(sim_profile, tmp_path):
    import json
    import resource
    import sys

    def small_files():  # a disk that fills after 100 kB
        resource.setrlimit(resource.RLIMIT_FSIZE, (100_000, 100_000))

    out = tmp_path / "runs"
    proc = subprocess.run([sys.executable, "-m", "fsi_lab.cli", "run",
                           str(sim_profile(duration=5.0)), "--out", str(out), "--json",
                           "--no-analysis"], capture_output=True, text=True, timeout=120,
                          preexec_fn=small_files)
    assert proc.returncode == 1, proc.stderr
    data = json.loads(proc.stdout)
    assert data["exit_status"] == "failed", data
    assert "could not be finalised" in data["error"] and data["run"] in data["error"]
    # the bench was made safe before the file was given up
    assert data["final_state"]["amplifier"]["output_enabled"] is False
    assert data["final_state"]["source"]["output_enabled"] is False


def test_a_signal_whose_exception_is_lost_still_aborts_the_run(sim_profile, registry, tmp_path):
    runner, run, events = _run(sim_profile(duration=5.0, realtime="true"), registry, tmp_path)

    def swallowed_sigterm(event):
        # what the handler does before raising; the exception itself never arrives here
        if isinstance(event, DataBlock) and not runner._abort.is_set():
            runner._signalled(signal.SIGTERM)

    runner.bus.subscribe(swallowed_sigterm)
    outcome = run()
    assert outcome.exit_status == "aborted" and outcome.error == "received SIGTERM"
    _assert_safe(outcome.path)
    assert read_run(outcome.path).channels["tip_velocity"].data.size < 10000


def test_ctrl_c_during_the_analysis_keeps_the_completed_run(sim_profile, registry, tmp_path):
    analysis = '[analysis]\nchain = ["spectrum"]\nchannels = ["tip_velocity"]\n'
    runner, run, _ = _run(sim_profile(duration=0.5, analysis=analysis), registry, tmp_path)

    def ctrl_c_while_analysing(event):
        if isinstance(event, StateChanged) and event.state == "analyzing":
            raise KeyboardInterrupt

    runner.bus.subscribe(ctrl_c_while_analysing)
    outcome = run()
    assert outcome.exit_status == "completed" and outcome.summary is None
    assert outcome.interrupted  # the command exits 130: it did not finish its work
    assert outcome.error.startswith("the analysis was stopped (Ctrl+C); the record is "
                                    "complete"), outcome.error
    record = _assert_safe(outcome.path)
    assert record.attrs["exit_status"] == "completed"
    assert read_run(outcome.path).channels["tip_velocity"].data.size == 1000
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL  # handlers put back


def test_the_run_file_records_the_watchdog_armed_with_the_output(tmp_path):
    """The amplifier's settings are recorded again once its output is on: the run file says
    whether the watchdog was armed (it said `not armed yet`, recorded before arming)."""
    import h5py
    from support import GOOD_PROFILE, run_main

    code, out, err = run_main("run", str(GOOD_PROFILE), "--out", str(tmp_path), "--set",
                              "run.duration=0.5", "--no-analysis")
    assert code == 0, err
    (path,) = tmp_path.glob("*.h5")
    with h5py.File(path, "r") as handle:
        settings = handle["instruments/amplifier/settings"].attrs
        assert settings["watchdog"] == "armed" and settings["watchdog_s"] == 1.0
