"""`fsi-lab model` and `fsi-lab simulate`: the beam model as the profile describes it."""

import json
import signal
import time

import numpy as np
import pytest
from support import PROFILES, cli_here, cli_json_here, start_cli

from fsi_lab.runfile import read_run

WET = PROFILES / "wet-beam-sim.toml"
PAPER_DRY_HZ = [11.5328, 72.2747, 202.3712, 396.5668]


def test_model_json_reproduces_the_paper():
    data, proc = cli_json_here("model", str(WET), "--set", "specimen.fluid=air")
    assert proc.returncode == 0, proc.stderr
    assert data["fluid"] == "air"
    np.testing.assert_allclose(data["natural_frequencies_hz"], PAPER_DRY_HZ, rtol=5e-4)
    wet, _ = cli_json_here("model", str(WET), "--modes", "2")
    assert wet["added_mass_ratio"] == pytest.approx(17.33, abs=0.01)
    assert wet["c_f_theory"] == pytest.approx(11.4, abs=0.05)
    assert len(wet["natural_frequencies_hz"]) == 2
    assert 16.5 < wet["natural_frequencies_hz"][1] < 17.5  # the second wet mode, near 17 Hz
    # mu + M, the mass the equivalent-damping plugin takes from this specimen, printed too
    assert wet["total_mass_per_length"] == pytest.approx(0.1346, abs=1e-4)
    assert wet["total_mass_per_length"] == pytest.approx(
        wet["mass_per_length"] * (1.0 + wet["added_mass_ratio"]), rel=1e-9)
    text = cli_here("model", str(WET))
    assert "mu + M = 0.1346 kg/m (beam 0.007344, added fluid mass 0.1273): the " \
        "--mass-per-length of this beam's records" in text.stdout, text.stdout


def test_simulate_writes_a_run_like_a_measured_one(tmp_path):
    out = tmp_path / "sim.h5"
    data, proc = cli_json_here("simulate", str(WET), "--duration", "3", "--rate", "5000", "-o",
                               str(out))
    assert proc.returncode == 0, proc.stderr
    assert data == {"run": str(out), "exit_status": "completed"}
    run = read_run(out)
    assert run.attrs["kind"] == "simulated" and run.attrs["exit_status"] == "completed"
    assert set(run.channels) == {"drive", "base_acceleration", "tip_velocity"}
    drive = run.channels["drive"].data
    assert drive.size == 15000 and run.channels["tip_velocity"].sample_rate == 5000.0
    # the excitation lasts 1 s: the record is padded with zeros after it
    assert np.all(drive[5000:] == 0) and drive.max() == pytest.approx(0.5)
    tip = run.channels["tip_velocity"].data
    assert np.max(np.abs(tip)) > 1e-3 and np.all(np.isfinite(tip))
    # the beam rings down after the pulse
    assert np.max(np.abs(tip[-2500:])) < 0.5 * np.max(np.abs(tip))
    assert run.excitation["plugin"] == "ramp-derivative"


def test_simulate_refuses_a_record_the_disk_cannot_hold(tmp_path, monkeypatch):
    """Checked before anything is written (the record streams to the file: the disk is the
    bound, not memory)."""
    import shutil
    from collections import namedtuple

    from support import run_main

    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda path: usage(10**10, 10**10 - 10**8, 10**8))
    out = tmp_path / "sim.h5"
    code, _, err = run_main("simulate", str(WET), "--duration", "600", "--rate", "10000",
                            "-o", str(out))
    assert code == 2
    assert "the simulated record would take 0.144 GB" in err and "has 0.1 GB free" in err
    assert not out.exists()


@pytest.mark.parametrize("args, fragment", [
    (["--modes", "0"], "beam.modes"),
    (["--rate", "100"], "sample_rate: 100 Hz cannot resolve mode"),
    (["--duration", "-1"], "--duration -1.0: expected a positive number of s"),
    (["--set", "specimen.thickness=0"], "specimen.thickness: 0.0 is out of bounds"),
    (["--set", "specimen.fluid=oil"], "specimen.fluid: got 'oil'; expected one of 'air', 'water'"),
])
def test_bad_model_input_is_refused_before_integration(tmp_path, args, fragment):
    out = tmp_path / "sim.h5"
    base = {"--duration": "1", "--rate": "5000"}
    for flag in ("--duration", "--rate"):
        if flag in args:
            base.pop(flag)
    proc = cli_here("simulate", str(WET), *[x for kv in base.items() for x in kv], *args,
                    "-o", str(out))
    assert proc.returncode == 2, proc.stderr
    assert fragment in proc.stderr
    assert not out.exists()


def test_simulate_records_its_overrides_and_analyze_uses_them(tmp_path):
    out = tmp_path / "sim.h5"
    _, proc = cli_json_here("simulate", str(WET), "--duration", "4", "--rate", "5000", "-o",
                            str(out), "--set", "analysis.hvd.components=1", "--set",
                            "model.c_f=20")
    assert proc.returncode == 0, proc.stderr
    attrs = read_run(out, load_data=False).attrs
    assert attrs["overrides"] == ["analysis.hvd.components=1", "model.c_f=20"]
    assert attrs["stop_time"] > attrs["start_time"] and attrs["error"] == ""
    data, proc = cli_json_here("analyze", str(out))
    assert proc.returncode == 0, proc.stderr
    # the wet profile asks for 2 HVD components; the simulation's override said 1
    assert [c["index"] for c in data["channels"]["tip_velocity"]["components"]] == [0]


def test_a_failed_simulation_says_so_in_its_file(tmp_path, registry, monkeypatch):
    from fsi_lab import simulation
    from fsi_lab.preflight import prepare_excitation
    from fsi_lab.profile import load_profile
    from fsi_lab.simulation import simulate_run

    monkeypatch.setattr(simulation, "BLOCK_SAMPLES", 2000)  # one second a block

    profile = load_profile(WET, registry)
    waveform, rate = prepare_excitation(profile, registry)

    def interrupted(fraction):
        if fraction > 0.4:
            raise RuntimeError("disk full")

    with pytest.raises(RuntimeError):
        simulate_run(profile, waveform, rate, 3.0, 2000.0, tmp_path / "s.h5", 2,
                     {"uuid": "0" * 32, "start_time": "2026-11-23T00:00:00.000000+00:00"},
                     progress=interrupted)
    run = read_run(tmp_path / "s.h5")
    assert run.attrs["exit_status"] == "failed" and "disk full" in run.attrs["error"]
    assert "RuntimeError" in run.attrs["traceback"]
    assert run.channels["tip_velocity"].data.size == 4000  # the seconds written before it failed


def test_an_interrupted_simulation_is_aborted_without_a_traceback(tmp_path, registry, monkeypatch):
    from fsi_lab import simulation
    from fsi_lab.preflight import prepare_excitation
    from fsi_lab.profile import load_profile
    from fsi_lab.simulation import simulate_run

    monkeypatch.setattr(simulation, "BLOCK_SAMPLES", 2000)  # one second a block

    profile = load_profile(WET, registry)
    waveform, rate = prepare_excitation(profile, registry)

    def ctrl_c(fraction):
        if fraction > 0.4:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        simulate_run(profile, waveform, rate, 3.0, 2000.0, tmp_path / "s.h5", 2,
                     {"uuid": "0" * 32, "start_time": "2026-11-23T00:00:00.000000+00:00"},
                     progress=ctrl_c)
    run = read_run(tmp_path / "s.h5")
    assert run.attrs["exit_status"] == "aborted"
    assert run.attrs["error"] == "interrupted (Ctrl+C)" and run.attrs["traceback"] == ""
    assert run.channels["tip_velocity"].data.size == 4000


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_ends_simulate_as_an_aborted_run(tmp_path, signum):
    out = tmp_path / "long.h5"
    # days of simulated time (200 million samples): far longer than the test waits
    proc = start_cli("simulate", str(WET), "--duration", "200000", "--rate", "1000",
                     "--modes", "1", "-o", str(out), "--json")
    try:
        deadline = time.monotonic() + 60
        while not out.exists() and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.05)
        time.sleep(0.5)  # some seconds simulated and written
        proc.send_signal(signum)
        stdout, stderr = proc.communicate(timeout=30)
    finally:
        proc.kill()
        proc.wait(timeout=10)
    assert proc.returncode == 130, stderr
    assert json.loads(stdout)["exit_status"] == "aborted" and "Traceback" not in stderr
    run = read_run(out, load_data=False)
    assert run.attrs["exit_status"] == "aborted" and run.attrs["traceback"] == ""
    expected = "received SIGTERM" if signum == signal.SIGTERM else "interrupted (Ctrl+C)"
    assert run.attrs["error"] == expected


def test_the_compiled_shaker_filters_give_scipy_lfilter_to_the_bit():
    """:class:`fsi_lab.biquad.Biquads` (simulate and the simulated bench) against
    ``scipy.signal.lfilter`` with its state carried over blocks of uneven length."""
    from scipy.signal import lfilter

    from fsi_lab.biquad import Biquads
    from fsi_lab.shaker import discrete_filters

    sections = discrete_filters(10000.0, 30.0, 0.08, 0.5)
    x = np.random.default_rng(5).normal(size=30001)
    filters = Biquads(sections)
    ours = np.concatenate([filters.advance(x[a:b]) for a, b in
                           ((0, 1), (1, 9000), (9000, 9000), (9000, 30001))], axis=1)
    for k, (b, a) in enumerate(sections):
        first, state = lfilter(b, a, x[:9000], zi=np.zeros(2))
        rest, _ = lfilter(b, a, x[9000:], zi=state)
        expected = np.concatenate([first, rest])
        np.testing.assert_array_equal(ours[k], expected)
    with pytest.raises(ValueError, match="a\\[0\\] != 0"):
        Biquads([([1.0], [0.0, 1.0])])


def test_a_long_simulation_streams_its_drive_and_writes_large_blocks(tmp_path, registry,
                                                                      monkeypatch):
    """The record is simulated a block at a time with the drive interpolated per block: the
    same samples as one interpolation of the whole record (numpy.interp), whatever the blocks."""
    from fsi_lab import simulation
    from fsi_lab.preflight import prepare_excitation
    from fsi_lab.profile import load_profile

    profile = load_profile(WET, registry)
    waveform, rate = prepare_excitation(profile, registry)
    written = []
    for block in (simulation.BLOCK_SAMPLES, 777):
        monkeypatch.setattr(simulation, "BLOCK_SAMPLES", block)
        out = tmp_path / f"s{block}.h5"
        simulation.simulate_run(profile, waveform, rate, 3.0, 2000.0, out, 2,
                                {"uuid": "0" * 32,
                                 "start_time": "2026-11-24T00:00:00.000000+00:00"})
        written.append(read_run(out))
    t = np.arange(6000) / 2000.0
    expected = np.interp(t, np.arange(waveform.size) / rate, waveform, right=0.0)
    for run in written:
        np.testing.assert_array_equal(run.channels["drive"].data, expected)
    for name in ("base_acceleration", "tip_velocity"):
        np.testing.assert_array_equal(written[0].channels[name].data,
                                      written[1].channels[name].data)
