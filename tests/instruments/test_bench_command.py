"""The simulated bench as a command of its own: addresses, a profile that runs against them
unchanged, and a clean stop on SIGTERM or Ctrl+C.

These start the command as ``python -m fsi_lab.instruments.sim.cli`` (what ``fsi-lab bench``
runs); tests/instruments/test_bench_end_to_end.py starts it as ``fsi-lab bench``.
"""

import json
import os
import signal
import subprocess
import sys

from benchkit import bench_profile, lab_registry, run_profile
from support import PROFILES, LineReader

from fsi_lab.runfile import read_run


def start_bench(*args: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "fsi_lab.instruments.sim.cli", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=dict(os.environ))


def stop(proc: subprocess.Popen, signum: int) -> tuple[int, str]:
    proc.send_signal(signum)
    try:
        code = proc.wait(timeout=15)
    finally:
        proc.kill()
        proc.wait(timeout=10)
    return code, proc.stderr.read()


def test_a_profile_runs_unchanged_against_the_bench_addresses(tmp_path):
    proc = start_bench(str(PROFILES / "dry-beam-sim.toml"), "--fast", "--json")
    try:
        line = LineReader(proc.stdout).wait_for(lambda text: text.startswith("{"), timeout=60)
        printed = json.loads(line)
        addresses = printed["addresses"]
        assert addresses["source"].startswith("TCPIP0::127.0.0.1::")
        assert addresses["vibrometer"].startswith("/dev/pts/")
        assert f'address = "{addresses["acquisition"]}"' in printed["profile"]
        path = bench_profile(tmp_path / "lab.toml", duration=0.5, addresses=addresses)
        outcome = run_profile(path, lab_registry(), tmp_path / "runs")
        assert outcome.exit_status == "completed", outcome.error
        run = read_run(outcome.path)
        assert run.channels["tip_velocity"].data.size == 5000
        assert run.instruments["amplifier"]["address"] == addresses["amplifier"]
        # a second run on the same bench
        assert run_profile(path, lab_registry(), tmp_path / "runs").exit_status == "completed"
    finally:
        code, stderr = stop(proc, signal.SIGTERM)
    assert code == 0, stderr
    assert "[bench] stopped" in stderr and "Traceback" not in stderr


def test_the_bench_takes_its_physics_from_a_profile_and_stops_on_ctrl_c():
    proc = start_bench(str(PROFILES / "dry-beam-sim.toml"), "--fault", "drop",
                       "--fault-after", "0.2")
    try:
        reader = LineReader(proc.stdout)
        reader.wait_for(lambda text: text.startswith("[bench.acquisition]"), timeout=60)
        text = "".join(reader.lines)
        assert "simulated bench (Ctrl+C stops it):" in text
        assert 'plugin = "shaker-amplifier"' in "".join(reader.lines)
    finally:
        code, stderr = stop(proc, signal.SIGINT)
    assert code == 0, stderr
    assert "fault: drop on the acquisition at 0.2 s of the record" in stderr


def test_a_bad_profile_is_refused(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[specimen]\nfluid = "oil"\n')
    proc = subprocess.run([sys.executable, "-m", "fsi_lab.instruments.sim.cli", str(bad)],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert "specimen.fluid: got 'oil'" in proc.stderr and str(bad) in proc.stderr


def test_chosen_ports_are_used():
    import socket

    ports = {}
    for role in ("source", "amplifier", "acquisition"):
        with socket.socket() as probe:
            probe.bind(("127.0.0.1", 0))
            ports[role] = probe.getsockname()[1]
    proc = start_bench(str(PROFILES / "dry-beam-sim.toml"), "--fast", "--json",
                       *[arg for role, port in ports.items()
                         for arg in (f"--{role}-port", str(port))])
    try:
        line = LineReader(proc.stdout).wait_for(lambda text: text.startswith("{"), timeout=60)
        addresses = json.loads(line)["addresses"]
    finally:
        code, stderr = stop(proc, signal.SIGTERM)
    assert code == 0, stderr
    for role, port in ports.items():
        assert addresses[role] == f"TCPIP0::127.0.0.1::{port}::SOCKET"


def test_the_bench_needs_the_profile_it_simulates(tmp_path):
    usage = subprocess.run([sys.executable, "-m", "fsi_lab.instruments.sim.cli", "--fast"],
                           capture_output=True, text=True, timeout=60)
    assert usage.returncode == 2 and "the following arguments are required: PROFILE" \
        in usage.stderr
    beamless = tmp_path / "beamless.toml"
    beamless.write_text("[shaker]\nsuspension_hz = 30.0\n")
    proc = subprocess.run([sys.executable, "-m", "fsi_lab.instruments.sim.cli", str(beamless)],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert proc.stderr == (f"fsi-lab: error: {beamless}: specimen: missing; the simulated bench "
                           "needs the beam whose response it simulates ([specimen], and [model] "
                           "for its damping)\n")
