"""End to end through the ``fsi-lab`` command: the lab drivers, excitations and the ``bench``
subcommand as installed through their entry points (pyproject.toml)."""

import json
import signal

import pytest
from support import PROFILES, LineReader, cli, cli_json, start_cli

from fsi_lab.runfile import read_run

DRY = PROFILES / "dry-beam-sim.toml"
LAB_PLUGINS = {"keysight33500": "instrument", "shaker-amplifier": "instrument",
               "polytec": "instrument", "scpi-daq": "instrument",
               "impulse-train": "excitation", "random": "excitation"}


def test_lab_plugins_and_the_bench_command_are_installed():
    data, proc = cli_json("plugins")
    assert proc.returncode == 0, proc.stderr
    found = {p["name"]: (p["kind"], p["status"]) for p in data["plugins"]}
    for name, kind in LAB_PLUGINS.items():
        assert found.get(name) == (kind, "loaded"), (name, found.get(name))
    helptext = cli("bench", "--help")
    assert helptext.returncode == 0 and "--fault-target" in helptext.stdout


def test_dry_profile_runs_on_the_embedded_bench(tmp_path):
    data, proc = cli_json("run", str(DRY), "--out", str(tmp_path), "--set", "run.duration=2")
    assert proc.returncode == 0, proc.stderr
    assert data["exit_status"] == "completed"
    assert data["final_state"]["amplifier"]["output_enabled"] is False
    run = read_run(data["run"])
    assert run.channels["tip_velocity"].data.size == 20000
    assert "PDV-100" in run.instruments["vibrometer"]["identity"]


def test_a_dropped_connection_fails_the_run_safely_from_the_command_line(tmp_path):
    data, proc = cli_json("run", str(DRY), "--out", str(tmp_path), "--set", "run.duration=2",
                          "--set", "bench.fault=drop", "--set", "bench.fault_after_s=0.5")
    assert proc.returncode == 1
    assert data["exit_status"] == "failed"
    assert "scpi-daq at TCPIP0::127.0.0.1::" in data["error"]
    assert "the connection was lost" in data["error"]
    assert data["final_state"]["amplifier"]["output_enabled"] is False
    assert 0 < read_run(data["run"]).channels["tip_velocity"].data.size < 20000


def test_fsi_lab_bench_takes_the_profile_whose_beam_the_run_identifies(tmp_path):
    """The README's standalone bench: started with the wet profile, it simulates the profile's
    beam (C_i = 0.65 and C_f = 33 per unit length), which the run against it identifies."""
    wet = PROFILES / "wet-beam-sim.toml"
    bench = start_cli("bench", str(wet), "--fast", "--json")
    try:
        line = LineReader(bench.stdout).wait_for(lambda text: text.startswith("{"), timeout=60)
        snippet = json.loads(line)["profile"]
        text = wet.read_text()
        head = text[:text.index("[bench]")]
        tail = text[text.index("[channels.drive]"):]
        profile = tmp_path / "lab.toml"
        profile.write_text(head + "[bench]\nembedded = false\n\n" + snippet + "\n" + tail)
        data, proc = cli_json("run", str(profile), "--out", str(tmp_path / "runs"),
                              "--set", "run.duration=2")
        assert proc.returncode == 0, proc.stderr
        assert data["exit_status"] == "completed"
        first = data["analysis"]["channels"]["tip_velocity"]["components"][0]
        assert 16.5 < first["frequency_hz"] < 17.5  # the second wet mode
        assert 0.55 < first["equivalent_damping"]["c_i"] < 0.75, first["equivalent_damping"]
    finally:
        bench.send_signal(signal.SIGINT)
        try:
            code = bench.wait(timeout=15)
        finally:
            bench.kill()
            bench.wait(timeout=10)
    assert code == 0


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_aborts_a_real_time_run_in_the_safe_state(tmp_path, signum):
    """Ctrl+C, or SIGTERM (a scheduler's stop), during the acquisition: exit 130, the run file
    says aborted, and the amplifier and the source were left with their outputs off."""
    out = tmp_path / "runs"
    proc = start_cli("run", str(DRY), "--out", str(out), "--verbose", "--set", "bench.fast=false",
                     "--set", "run.duration=30")
    try:
        LineReader(proc.stderr).wait_for(lambda text: text.startswith("[debug] flushed"), 60)
        proc.send_signal(signum)
        assert proc.wait(timeout=30) == 130
    finally:
        proc.kill()
        proc.wait(timeout=10)
    run = read_run(next(out.glob("*.h5")))
    assert run.attrs["exit_status"] == "aborted"
    assert run.instruments["amplifier"]["final_state"]["output_enabled"] is False
    assert run.instruments["source"]["final_state"]["output_enabled"] is False
    assert 0 < run.channels["tip_velocity"].data.size < 300000
