"""Damaged run files, made by really damaging a real run file (h5py edits, truncation, a
corrupted byte): ``show`` and ``analyze`` refuse each with one message naming the file and the
node or attribute (exit 2), never a traceback, and the file is left as it was."""

import json
import shutil
import signal

import h5py
import numpy as np
import pytest
from support import SIM_PROFILE, run_main

from fsi_lab.errors import AnalysisError, InputFileError
from fsi_lab.isolation import crash_or_hang
from fsi_lab.runfile import read_run, write_analysis


@pytest.fixture(scope="module")
def measured_run(tmp_path_factory):
    """A real run on the in-process bench, analysed with the spectrum (so it has a summary)."""
    folder = tmp_path_factory.mktemp("measured")
    profile = folder / "sim.toml"
    profile.write_text(SIM_PROFILE.format(
        duration=0.5, realtime="false", amplitude=0.5, amplifier_extra="", acquisition_extra="",
        analysis='[analysis]\nchain = ["spectrum"]\nchannels = ["tip_velocity"]\n'))
    code, out, err = run_main("run", str(profile), "--out", str(folder / "runs"))
    assert code == 0, err
    return next((folder / "runs").glob("*.h5"))


def _damaged(measured_run, tmp_path, edit):
    path = tmp_path / "damaged.h5"
    shutil.copy(measured_run, path)
    with h5py.File(path, "r+") as handle:
        edit(handle)
    return path


def _replace_channel(data):
    def edit(handle):
        attrs = dict(handle["channels/tip_velocity"].attrs)
        del handle["channels/tip_velocity"]
        handle["channels"].create_dataset("tip_velocity", data=data)
        handle["channels/tip_velocity"].attrs.update(attrs)
    return edit


def _set(node, key, value):
    def edit(handle):
        handle[node].attrs[key] = value
    return edit


def _refused(path, command, *fragments):
    before = path.read_bytes()
    code, out, err = run_main(*command, str(path))
    assert code == 2, (command, out, err)
    assert err.count("fsi-lab: error:") == 1 and "Traceback" not in err, err
    assert err.startswith(f"fsi-lab: error: {path}:"), err  # (the stored profile: PATH:/profile)
    for fragment in fragments:
        assert fragment in err, err
    assert path.read_bytes() == before  # nothing written to a refused file


CHANNEL = "/channels/tip_velocity"
# (case, edit, what the message must say): refused by show and by analyze
DAMAGE = [
    ("corrupted summary attribute", _set("analysis", "summary", '{"run": "x", "chan'),
     "/analysis attribute 'summary': is not a JSON object"),
    ("summary of another layout", _set("analysis", "summary", '{"channels": {"tip": 5}}'),
     "/analysis attribute 'summary': not laid out as fsi-lab writes it"),
    ("sample_rate = 0", _set("channels/tip_velocity", "sample_rate", 0.0),
     f"{CHANNEL} attribute 'sample_rate': is 0.0; expected a finite number from 0.001 to 1e+09"),
    ("sample_rate stored as a string", _set("channels/tip_velocity", "sample_rate", "2000"),
     f"{CHANNEL} attribute 'sample_rate': is '2000'; expected a finite number"),
    ("t0 stored as a string", _set("channels/tip_velocity", "t0", "soon"),
     f"{CHANNEL} attribute 't0': is 'soon'; expected a finite number"),
    ("a channel stored as a group",
     lambda h: (h["channels"].__delitem__("base_acceleration"),
                h["channels"].create_group("base_acceleration")),
     "/channels/base_acceleration: is a group; expected a dataset"),
    ("a dangling soft link", lambda h: h["channels"].__setitem__("ghost", h5py.SoftLink("/no")),
     "/channels/ghost: is a soft link; expected a dataset stored in the file"),
    ("an external link",
     lambda h: h["channels"].__setitem__("far", h5py.ExternalLink("/etc/hostname", "/x")),
     "/channels/far: is an external link"),
    ("a missing /excitation/waveform", lambda h: h["excitation"].__delitem__("waveform"),
     "/excitation/waveform: is missing; expected a dataset there"),
    ("an integer profile attribute", _set("/", "profile", 5),
     "/ attribute 'profile': is 5; expected text"),
    ("overrides that are not texts", _set("/", "overrides", "[1, 2]"),
     "/ attribute 'overrides': is not a list of texts"),
    ("an unknown quantity", _set("channels/tip_velocity", "quantity", "speed"),
     f"{CHANNEL} attribute 'quantity': is 'speed'; expected one of 'displacement'"),
    ("an instrument stored as a dataset",
     lambda h: (h["instruments"].__delitem__("source"),
                h["instruments"].__setitem__("source", np.zeros(2))),
     "/instruments/source: is a dataset; expected a group"),
    ("2-D channel", _replace_channel(np.zeros((10, 2))),
     f"{CHANNEL}: has shape (10, 2); expected a 1-D dataset of real numbers"),
    ("string channel", _replace_channel(np.array([b"a", b"b"])),
     f"{CHANNEL}: holds |S1 values; expected a 1-D dataset of real numbers"),
    ("complex channel", _replace_channel(np.ones(100, complex)),
     f"{CHANNEL}: holds complex128 values"),
] + [(f"sample_rate = {value}", _set("channels/tip_velocity", "sample_rate", value),
      f"{CHANNEL} attribute 'sample_rate': is {value!r}") for value in (-1.0, np.nan, np.inf)]


@pytest.mark.parametrize("case, edit, fragment", DAMAGE, ids=[c[0] for c in DAMAGE])
def test_show_and_analyze_refuse_a_damaged_run_file(measured_run, tmp_path, case, edit,
                                                    fragment):
    path = _damaged(measured_run, tmp_path, edit)
    for command in (["show"], ["show", "--json"], ["analyze"]):
        if "summary" in case and command == ["analyze"]:
            continue  # analyze writes a new summary: the old one does not matter to it
        _refused(path, command, fragment)


# Files show can describe but analyze must refuse: nothing, or nothing usable, to analyse.
UNANALYSABLE = [
    ("no channels", lambda h: [h["channels"].__delitem__(n) for n in list(h["channels"])],
     "/channels holds no channel; expected recorded channels to analyse"),
    ("empty channels", lambda h: [h[f"channels/{n}"].resize((0,)) for n in h["channels"]],
     "holds 0 samples; expected at least 2 to analyse"),
    ("NaN samples", lambda h: h["channels/tip_velocity"].__setitem__(slice(5, 50), np.nan),
     f"{CHANNEL} holds 45 NaN or infinite samples (the first at index 5); expected finite"),
    ("a deeply nested stored profile",  # RecursionError in tomllib before
     _set("/", "profile", "x = " + "[" * 5000 + "]" * 5000),
     ":/profile: the profile: tables or arrays nested more than 8 levels deep"),
]


@pytest.mark.parametrize("case, edit, fragment", UNANALYSABLE, ids=[c[0] for c in UNANALYSABLE])
def test_analyze_refuses_a_run_file_with_nothing_to_analyse(measured_run, tmp_path, case, edit,
                                                            fragment):
    path = _damaged(measured_run, tmp_path, edit)
    code, out, err = run_main("show", str(path))
    assert code == 0 and "Traceback" not in err, err
    _refused(path, ["analyze"], fragment)


def test_a_truncated_run_file_is_refused(measured_run, tmp_path):
    path = tmp_path / "cut.h5"
    path.write_bytes(measured_run.read_bytes()[:measured_run.stat().st_size // 2])
    for command in (["show"], ["analyze"]):
        _refused(path, command, "expected")


def test_a_byte_that_crashes_the_hdf5_library_is_refused(measured_run, tmp_path):
    """The variable-length string type of the root attribute ``kind`` given an invalid kind:
    reading it crashes the HDF5 library (SIGSEGV) in the version fsi-lab installs."""
    data = bytearray(measured_run.read_bytes())
    name = data.index(b"kind\x00")
    vlen = data.index(0x19, name, name + 24)  # the datatype message: class 9 (vlen), version 1
    assert data[vlen + 1] == 1  # a string
    data[vlen + 1] = 3
    path = tmp_path / "flipped.h5"
    path.write_bytes(bytes(data))
    for command in (["show"], ["analyze"]):
        _refused(path, command)


def test_a_task_that_crashes_or_hangs_comes_back_as_a_message():
    assert crash_or_hang(lambda: None) is None
    assert crash_or_hang(lambda: 1 / 0) is None  # an ordinary error is the caller's to raise
    crashed = crash_or_hang(lambda: signal.raise_signal(signal.SIGSEGV))
    assert crashed == "the HDF5 library crashed reading it (SIGSEGV)"


def test_a_task_that_hangs_is_stopped(monkeypatch):
    import fsi_lab.isolation as isolation

    monkeypatch.setattr(isolation, "TIMEOUT_S", 0.2)
    assert crash_or_hang(signal.pause) == "reading it did not finish within 0.2 s"


def test_a_failed_analysis_write_keeps_the_previous_results(measured_run, tmp_path):
    path = tmp_path / "run.h5"
    shutil.copy(measured_run, path)
    before = read_run(path)
    with pytest.raises(AnalysisError, match=r"/analysis/tip_velocity/bad/x: the analysis "
                                            r"result cannot be stored \(TypeError"):
        write_analysis(path, {"tip_velocity/bad": {"datasets": {"x": np.array([object()])}}},
                       {"channels": {}})
    with h5py.File(path, "r") as handle:
        assert "analysis.new" not in handle  # no orphan group left behind
        assert "tip_velocity/spectrum" in handle["analysis"]
    after = read_run(path)
    np.testing.assert_array_equal(after.channels["tip_velocity"].data,
                                  before.channels["tip_velocity"].data)


def test_read_run_names_the_damaged_node(measured_run, tmp_path):
    path = _damaged(measured_run, tmp_path,
                    _set("channels/base_acceleration", "sample_rate", "fast"))
    with pytest.raises(InputFileError, match=r"/channels/base_acceleration attribute "
                                             r"'sample_rate': is 'fast'; expected a finite"):
        read_run(path)


def _with_digitiser_range(edit):
    """``edit``, on a run file that records its digitiser's input ranges as scpi-daq does
    (``ranges_v``: 10 V on every input; the vibrometer's 8 V/(m/s) makes +-1.25 m/s)."""
    def both(handle):
        handle["instruments/acquisition/settings"].attrs["ranges_v"] = \
            '{"1": 10.0, "2": 10.0, "3": 10.0}'
        handle["channels/tip_velocity"].attrs["sensitivity"] = 8.0
        edit(handle)
    return both


def _scrambled(start, count):
    """Samples ``start`` to ``start + count`` of the tip velocity replaced by the finite
    values of bytes flipped at random (hundreds of m/s and more)."""
    def edit(handle):
        data = handle["channels/tip_velocity"][()]
        noise = np.random.default_rng(5).uniform(-500.0, 500.0, count)
        data[start:start + count] = noise
        handle["channels/tip_velocity"][...] = data
    return edit


def test_samples_far_beyond_the_recorded_range_are_named_as_damaged(measured_run, tmp_path):
    path = _damaged(measured_run, tmp_path, _with_digitiser_range(_scrambled(300, 512)))
    _refused(path, ["analyze"], f"{CHANNEL} holds 5", "samples beyond 2 times the +-1.25 m/s "
             "its instruments could record (the digitiser's input 3 range of 10 V over the "
             "sensitivity of 8", "the first at index 300", "damaged or implausible data")


def test_a_few_isolated_glitches_beyond_the_range_are_left_to_the_analysis(measured_run,
                                                                           tmp_path):
    def glitches(handle):
        data = handle["channels/tip_velocity"][()]
        data[[200, 400, 600]] = 300.0
        handle["channels/tip_velocity"][...] = data
    path = _damaged(measured_run, tmp_path, _with_digitiser_range(glitches))
    code, out, err = run_main("analyze", str(path))
    assert code == 0, err


def test_a_reanalysis_that_identifies_nothing_keeps_the_earlier_analysis(tmp_path):
    from support import write_decay_run

    from fsi_lab.runfile import read_analysis_summary

    path = write_decay_run(tmp_path / "decay.h5")
    code, out, err = run_main("analyze", str(path), "--mass-per-length", "0.1")
    assert code == 0, err
    good = read_analysis_summary(path)
    assert good["channels"]["tip"]["components"]
    with h5py.File(path, "r+") as handle:  # the record damaged: noise alone
        data = handle["channels/tip"]
        data[...] = 1e-3 * np.random.default_rng(1).standard_normal(data.shape)
    before = path.read_bytes()
    code, out, err = run_main("analyze", str(path), "--mass-per-length", "0.1")
    assert code == 2, err
    assert "nothing was identified" in err and "this analysis is not stored: the file keeps " \
        "the analysis stored in it before" in err, err
    assert path.read_bytes() == before
    assert read_analysis_summary(path) == good
    # the JSON says so too, and a batch does the same
    code, out, err = run_main("analyze", str(path), "--mass-per-length", "0.1", "--json")
    assert code == 2 and "this analysis is not stored" in json.loads(out)["not_stored"]
    code, out, err = run_main("analyze", str(path), "--mass-per-length", "0.1", "--jobs", "1",
                              "--json")
    assert code == 2 and "this analysis is not stored" in json.loads(out)["files"][0]["error"]
    assert path.read_bytes() == before


def test_a_reanalysis_keeps_the_mass_per_length_and_the_coefficients_it_cannot_give(tmp_path):
    """Analysed again without --mass-per-length, a file keeps the mass its stored analysis was
    given (C_i and C_f came out of the second analysis before, and it stored none); an
    analysis whose C_i and C_f fail where the stored one had them is not stored (exit 2); a
    chain that gives none replaces it, with a warning."""
    from support import write_decay_run

    from fsi_lab.runfile import read_analysis_summary

    path = write_decay_run(tmp_path / "decay.h5")
    code, out, err = run_main("analyze", str(path), "--mass-per-length", "0.1")
    assert code == 0, err
    good = read_analysis_summary(path)
    (first,) = good["channels"]["tip"]["components"][:1]
    code, out, err = run_main("analyze", str(path))
    assert code == 0, err
    assert "mu + M = 0.1 kg/m, the --mass-per-length the analysis stored in the file was " \
        "given" in err, err
    again = read_analysis_summary(path)["channels"]["tip"]["components"][0]
    assert again["equivalent_damping"]["c_i"] == first["equivalent_damping"]["c_i"]
    before = path.read_bytes()
    code, out, err = run_main("analyze", str(path), "--set",
                              "analysis.chain=spectrum,equivalent-damping")
    assert code == 2, err
    assert "C_i and C_f were not identified where the stored analysis had them: channel " \
        "tip: " in err and "the file keeps the analysis stored in it before, which " \
        "identified C_i and C_f there" in err, err
    assert path.read_bytes() == before
    code, out, err = run_main("analyze", str(path), "--set", "analysis.chain=spectrum")
    assert code == 0, err
    assert "the analysis stored before, with C_i and C_f on channel tip, is replaced by " \
        "this one, which has none there" in err, err
    assert not read_analysis_summary(path)["channels"]["tip"].get("components")


@pytest.mark.parametrize("status, why", [
    ("aborted", "the run was aborted (Ctrl+C, SIGTERM or Abort)"),
    ("running", "the run never finished (its exit status is still 'running': the process "
                "that ran it died, by kill -9, a crash or a power cut)"),
])
def test_analysing_a_run_that_did_not_complete_warns_that_its_record_is_cut_short(
        measured_run, tmp_path, status, why):
    def stopped(handle):  # as the run leaves its file: half the planned 0.5 s, and its status
        handle.attrs["exit_status"] = status
        for name in handle["channels"]:
            handle[f"channels/{name}"].resize((500,))
    path = _damaged(measured_run, tmp_path, stopped)
    expected = f"{why}: its record holds 0.25 s of the 0.5 s planned, cut short"
    code, out, err = run_main("analyze", str(path))
    assert code == 0, err
    assert f"warning: {expected}" in out, out
    from fsi_lab.runfile import read_analysis_summary
    assert read_analysis_summary(path)["channels"]["tip_velocity"]["warnings"][0] \
        .startswith(expected)
    code, out, err = run_main("analyze", str(path), "--strict")
    assert code == 3 and f"[strict] channel tip_velocity: {expected}" in err, err


def test_analysing_a_completed_run_gives_no_such_warning(measured_run, tmp_path):
    path = _damaged(measured_run, tmp_path, lambda handle: None)
    code, out, err = run_main("analyze", str(path), "--json")
    assert code == 0 and "cut short" not in out, out


def test_the_full_scale_is_read_from_a_range_list_as_from_the_configured_ranges():
    """``ranges_v`` is recorded by input number once the digitiser is configured, and as the
    profile's list (inputs 1, 2, ...) where a driver records its settings before: both give the
    channel's full scale, so the damaged-data check is not skipped for the second."""
    from types import SimpleNamespace

    from fsi_lab.runfile import recorded_full_scale

    attrs = {"tip": {"input": 2, "sensitivity": 8.0, "sensitivity_units": "V/(m/s)"}}
    for ranges in ({"1": 10.0, "2": 10.0}, [10.0, 10.0, 5.0, 5.0]):
        run = SimpleNamespace(channel_attrs=attrs,
                              instruments={"acquisition": {"settings": {"ranges_v": ranges}}})
        full, how = recorded_full_scale(run, "tip")
        assert full == 1.25 and "input 2 range of 10 V" in how
    run = SimpleNamespace(channel_attrs={"tip": {**attrs["tip"], "input": 0}},
                          instruments={"acquisition": {"settings": {"ranges_v": [10.0]}}})
    assert recorded_full_scale(run, "tip") is None


def test_a_batch_says_what_a_single_file_says_of_its_stored_analysis(tmp_path):
    """The workers of a batch have no event bus: the mass kept from the stored analysis and a
    stored analysis with C_i and C_f replaced by one without them went unsaid there. They are
    printed, and kept in each file's JSON entry."""
    from support import write_decay_run

    paths = [write_decay_run(tmp_path / f"decay{k}.h5") for k in range(2)]
    code, out, err = run_main("analyze", *map(str, paths), "--mass-per-length", "0.1")
    assert code == 0, err
    code, out, err = run_main("analyze", *map(str, paths))
    assert code == 0, err
    kept = "mu + M = 0.1 kg/m, the --mass-per-length the analysis stored in the file was given"
    for path in paths:
        assert f"{path}: {kept}" in err, err
    code, out, err = run_main("analyze", *map(str, paths), "--set", "analysis.chain=spectrum",
                              "--json")
    assert code == 0, err
    for path, entry in zip(paths, json.loads(out)["files"]):
        levels = {level: sentence for level, sentence in entry["messages"]}
        assert sorted(levels) == ["INFO", "WARNING"], entry["messages"]
        assert kept in levels["INFO"] and levels["WARNING"].startswith(
            f"{path}: the analysis stored before, with C_i and C_f on channel tip, is replaced "
            "by this one"), entry["messages"]
