"""HDF5 run files written and read back with h5py."""

import h5py
import numpy as np
import pytest

from fsi_lab.errors import AnalysisError, InputFileError
from fsi_lab.runfile import (
    RunFileWriter,
    new_run_path,
    read_analysis_summary,
    read_run,
    write_analysis,
)


@pytest.fixture
def run_file(tmp_path):
    path, run_uuid, started = new_run_path(tmp_path)
    writer = RunFileWriter(path, {"uuid": run_uuid, "start_time": started, "kind": "measured",
                                  "profile": "[run]\n"})
    writer.create_channel("v", {"units": "m/s", "quantity": "velocity", "sample_rate": 100.0,
                                "t0": -0.001, "sensitivity": 8.0})
    for block in np.split(np.arange(1000.0), 10):
        writer.append("v", block)
    writer.write_instrument("amplifier", {"identity": "AMP"}, {"gain": 2.0, "mode": "voltage"})
    writer.write_final_state("amplifier", {"output_enabled": False, "interlocks": {}})
    writer.set_attrs({"exit_status": "completed"})
    writer.close()
    return path


def test_round_trip(run_file):
    run = read_run(run_file)
    assert run.attrs["format"] == "fsi-lab run" and run.attrs["exit_status"] == "completed"
    channel = run.channels["v"]
    np.testing.assert_array_equal(channel.data, np.arange(1000.0))
    assert (channel.unit, channel.quantity, channel.sample_rate, channel.t0) == (
        "m/s", "velocity", 100.0, -0.001)
    amplifier = run.instruments["amplifier"]
    assert amplifier["identity"] == "AMP"
    assert amplifier["settings"] == {"gain": 2.0, "mode": "voltage"}
    assert amplifier["final_state"] == {"output_enabled": False, "interlocks": {}}
    with h5py.File(run_file, "r") as handle:
        dataset = handle["channels/v"]
        assert dataset.chunks is not None and dataset.maxshape == (None,)


def test_analysis_is_replaced_whole_and_a_failed_write_keeps_the_old(run_file):
    write_analysis(run_file, {"v/a": {"datasets": {"x": np.arange(3.0)}, "units": {"x": "Hz"},
                                      "attrs": {"status": "ok", "f": 1.5},
                                      "params": {"n": 2}}},
                   {"run": str(run_file), "channels": {"v": {"f": 1.5}}})
    assert read_analysis_summary(run_file)["channels"]["v"]["f"] == 1.5
    with pytest.raises(AnalysisError, match=r"/analysis/v/b/bad: the analysis result cannot be "
                                            r"stored \(TypeError"):
        write_analysis(run_file, {"v/b": {"datasets": {"bad": np.array([object()])}}},
                       {"run": "x", "channels": {}})
    assert read_analysis_summary(run_file)["channels"]["v"]["f"] == 1.5
    with h5py.File(run_file, "r") as handle:
        assert list(handle["analysis/v"]) == ["a"]
        assert handle["analysis/v/a/x"].attrs["units"] == "Hz"
        assert handle["analysis/v/a/params"].attrs["n"] == 2
        np.testing.assert_array_equal(handle["channels/v"][()], np.arange(1000.0))


def test_channel_without_attributes_is_named(tmp_path):
    path = tmp_path / "x.h5"
    with h5py.File(path, "w") as handle:
        handle.attrs["format"] = "fsi-lab run"
        handle.create_dataset("channels/v", data=np.zeros(3))
    with pytest.raises(InputFileError, match=r"/channels/v attribute 'quantity': is missing; "
                                             r"expected one of 'displacement', 'velocity'"):
        read_run(path)


def test_missing_file(tmp_path):
    with pytest.raises(InputFileError, match="no such file"):
        read_run(tmp_path / "none.h5")
