"""Each injected fault ends a run on the embedded bench in the safe state, with a clear message
and the data acquired up to the fault kept in the run file."""

import re

import numpy as np
import pytest
from benchkit import bench_profile, bench_threads, lab_registry, run_profile

from fsi_lab.errors import InstrumentError, ProfileError
from fsi_lab.profile import load_profile
from fsi_lab.runfile import read_run
from fsi_lab.runner import Runner

RECORD = 10000  # samples per channel of a complete 1 s record

CASES = {
    "timeout": r"scpi-daq at TCPIP0::127\.0\.0\.1::\d+::SOCKET: no reply within 0\.5 s "
               r"\(after sending 'ACQ:STAT\?'\)",
    "drop": r"scpi-daq at TCPIP0::127\.0\.0\.1::\d+::SOCKET: the connection was lost "
            r"\(Connection reset by peer\)",
    "garble": r"scpi-daq at TCPIP0::127\.0\.0\.1::\d+::SOCKET: garbled reply",
    "overload": r"overload on input 3 \(tip_velocity, range 10\.0 V\) after 3\d\d\d samples",
    "interlock": r"amplifier interlock tripped: over_travel; the output was switched off",
}


@pytest.mark.parametrize("fault", list(CASES))
def test_fault_ends_the_run_safe_with_its_data(tmp_path, fault):
    # the interlock is polled by the runner every 0.2 s of wall time: pace that run in real time
    path = bench_profile(tmp_path / f"{fault}.toml", duration=1.0, fault=fault,
                         fault_after_s=0.3, timeout_s=0.5, fast=fault != "interlock")
    outcome = run_profile(path, lab_registry(), tmp_path / "runs")
    assert outcome.exit_status == "failed"
    assert outcome.error is not None
    assert re.search(CASES[fault], outcome.error), outcome.error
    assert not bench_threads()  # the embedded bench was stopped by the runner's cleanup

    run = read_run(outcome.path)
    assert run.attrs["exit_status"] == "failed"
    amplifier = run.instruments["amplifier"]["final_state"]
    source = run.instruments["source"]["final_state"]
    assert amplifier["output_enabled"] is False
    assert source["output_enabled"] is False and source["level_v"] == 0.0
    for name in ("drive", "base_acceleration", "tip_velocity"):
        data = run.channels[name].data
        assert 0.2 * RECORD <= data.size < RECORD and np.all(np.isfinite(data)), name
    if fault == "interlock":
        assert amplifier["interlocks"] == {"over_travel": True}
    if fault == "overload":
        assert run.instruments["acquisition"]["final_state"]["overloaded_inputs"] == [3]
        # the block with the transient never reached the run file
        assert np.abs(run.channels["tip_velocity"].data).max() < 1.0


def test_a_run_without_faults_completes_and_records_the_instruments(tmp_path):
    outcome = run_profile(bench_profile(tmp_path / "ok.toml", duration=1.0), lab_registry(),
                          tmp_path / "runs")
    assert outcome.exit_status == "completed", outcome.error
    run = read_run(outcome.path)
    assert run.channels["tip_velocity"].data.size == RECORD
    assert run.channel_attrs["tip_velocity"]["sensitivity"] == pytest.approx(8.0)
    assert run.channel_attrs["tip_velocity"]["t0"] == pytest.approx(-1.1e-3)
    vibrometer = run.instruments["vibrometer"]
    assert vibrometer["settings"]["signal_delay_source"] == "decoder"
    assert run.instruments["acquisition"]["settings"]["visa_address"].startswith("TCPIP0::")
    assert not bench_threads()


def test_embedded_address_needs_the_embedded_bench(tmp_path):
    path = bench_profile(tmp_path / "p.toml")
    path.write_text(path.read_text().replace("embedded = true", "embedded = false"))
    registry = lab_registry()
    runner = Runner(load_profile(path, registry), registry, tmp_path / "runs", analyze=False)
    with pytest.raises(ProfileError) as info:  # refused before anything is opened or written
        runner.run()
    assert str(info.value).startswith(
        f"{path}: bench.source: address 'embedded' names the embedded simulated bench, but the "
        "profile does not say [bench] embedded = true"), str(info.value)
    assert not (tmp_path / "runs").exists()


def test_unreachable_instrument_is_named_with_its_address(tmp_path):
    import socket

    with socket.socket() as probe:  # a port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    from benchkit import settings

    from fsi_lab.instruments import shaker_amplifier

    address = f"TCPIP0::127.0.0.1::{port}::SOCKET"
    with pytest.raises(InstrumentError, match=rf"shaker-amplifier at {address}: nothing answers "
                                              r"at this address \(connection refused\)"):
        shaker_amplifier.PLUGIN.open(address, settings(shaker_amplifier, timeout_s=0.5), {})


#: What each link fault says, by the instrument it hits (besides the role named first).
TARGET_CASES = {
    ("source", "timeout"): r"keysight33500 at TCPIP0::127\.0\.0\.1::\d+::SOCKET: no reply within "
                           r"0\.5 s \(after sending 'OUTP1\?'\)",
    ("source", "drop"): r"keysight33500 at TCPIP0::127\.0\.0\.1::\d+::SOCKET: the connection was "
                        r"lost",
    ("source", "garble"): r"keysight33500 at TCPIP0::127\.0\.0\.1::\d+::SOCKET: "
                          r"(garbled reply|unexpected reply)",
    ("vibrometer", "timeout"): r"polytec at /dev/pts/\d+: no reply within 0\.5 s \(after sending "
                               r"'Get,VeloDec,0,Range'\)",
    ("vibrometer", "drop"): r"polytec at /dev/pts/\d+: the serial port failed",
    ("vibrometer", "garble"): r"polytec at /dev/pts/\d+: garbled reply",
    ("amplifier", "timeout"): r"shaker-amplifier at TCPIP0::127\.0\.0\.1::\d+::SOCKET: no reply "
                              r"within 0\.5 s",
    ("amplifier", "drop"): r"shaker-amplifier at TCPIP0::127\.0\.0\.1::\d+::SOCKET: the "
                           r"connection was lost",
    ("amplifier", "garble"): r"shaker-amplifier at TCPIP0::127\.0\.0\.1::\d+::SOCKET: "
                             r"(garbled reply|unexpected reply)",
}


@pytest.mark.parametrize("target, fault", list(TARGET_CASES))
def test_a_link_fault_on_any_instrument_fails_the_run_naming_it(tmp_path, target, fault):
    path = bench_profile(tmp_path / f"{target}-{fault}.toml", duration=1.0, fault=fault,
                         fault_after_s=0.3, timeout_s=0.5)
    text = path.read_text().replace("fault_after_s = 0.3", 'fault_after_s = 0.3\n'
                                    f'fault_target = "{target}"')
    for role in ("source", "amplifier", "vibrometer"):
        text = text.replace(f"[bench.{role}]\n", f"[bench.{role}]\ntimeout_s = 0.5\n")
    path.write_text(text)
    outcome = run_profile(path, lab_registry(), tmp_path / "runs")
    assert outcome.exit_status == "failed"
    assert re.search(TARGET_CASES[target, fault], outcome.error or ""), outcome.error
    if target != "amplifier":  # the amplifier's link is read through its interlocks
        assert outcome.error.startswith(f"{target} failed during the record: "), outcome.error
    assert not bench_threads()
    run = read_run(outcome.path)
    assert run.attrs["exit_status"] == "failed"
    assert run.instruments["amplifier"]["final_state"].get("output_enabled") is not True
    data = run.channels["tip_velocity"].data
    assert 0 < data.size <= RECORD and np.all(np.isfinite(data))  # the data so far is kept


def test_an_address_that_is_no_visa_resource_name_says_what_one_looks_like():
    from benchkit import settings

    from fsi_lab.instruments import shaker_amplifier

    with pytest.raises(InstrumentError, match=r"shaker-amplifier at TCPIP0:127\.0\.0\.1: cannot "
                                              r"open the connection .*; expected a VISA "
                                              r"resource name such as TCPIP0::"):
        shaker_amplifier.PLUGIN.open("TCPIP0:127.0.0.1", settings(shaker_amplifier,
                                                                   timeout_s=0.5), {})


def test_an_absent_serial_port_says_what_to_check_not_what_a_port_looks_like(tmp_path):
    from benchkit import settings

    from fsi_lab.instruments import polytec, shaker_amplifier

    port = tmp_path / "ttyUSB9"                  # a well-formed device name, nothing there
    with pytest.raises(InstrumentError, match=rf"polytec at {port}: cannot open the serial "
                                              r"port \(.*\); check that the vibrometer is "
                                              r"switched on and its cable plugged in"):
        polytec.PLUGIN.open(str(port), settings(polytec, timeout_s=0.5), {})
    with pytest.raises(InstrumentError, match=r"cannot open the connection \(.*\); check that "
                                              r"the instrument is switched on and connected"):
        shaker_amplifier.PLUGIN.open(f"ASRL{port}::INSTR", settings(shaker_amplifier,
                                                                    timeout_s=0.5), {})
