"""The parts of the streaming benchmark (bench/bench_stream.py) on short records against the
simulated bench: every path it measures streams every sample of 4 inputs at 204.8 kS/s."""

import os

from benchkit import sim_bench

from bench import bench_stream
from fsi_lab.instruments.sim.cli import profile_snippet
from fsi_lab.runfile import read_run


def test_the_runner_record_streams_four_inputs_into_its_run_file(sim_bench, tmp_path,
                                                                 monkeypatch):
    monkeypatch.setenv("FSI_LAB_LOCK_DIR", str(tmp_path / "locks"))
    bench = sim_bench()
    profile = tmp_path / "stream.toml"
    profile.write_text(bench_stream.stream_profile(profile_snippet(bench), 0.3))
    measured = bench_stream.runner_record(profile, tmp_path / "runs", os.getpid())
    assert measured["cpu"] > 0 and measured["wall"] > 0
    run = read_run(next((tmp_path / "runs").glob("*.h5")))
    assert sorted(run.channels) == ["base_acceleration", "drive", "spare", "tip_velocity"]
    for channel in run.channels.values():
        assert channel.data.size == round(0.3 * bench_stream.STREAM_RATE)


def test_the_driver_streams_every_sample_with_its_block_reads_and_with_pyvisas(sim_bench):
    address = sim_bench().addresses["acquisition"]
    for pyvisa_reads in (False, True):  # driver_record raises unless every sample arrived
        assert bench_stream.driver_record(address, 0.3, pyvisa_reads) > 0


def test_the_floor_reads_every_byte():
    assert bench_stream.floor_record(0.3) >= 0  # it raises unless every byte arrived
