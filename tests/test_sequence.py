"""fsi-lab sequence: plans expanded into runs, every run checked before the first is driven,
runs carried out one after the other with the bench safe between them, the stop conditions,
and the sequence record that `fsi-lab show DIR` summarises."""

import json

import h5py
import pytest
from support import ROOT, run_main

from fsi_lab.plan import check_plan, load_plan, parse_plan
from fsi_lab.registry import load_registry
from fsi_lab.runfile import read_run
from fsi_lab.seqfile import SEQUENCE_FILE, load_record, locked

SPECTRUM = '[analysis]\nchain = ["spectrum"]\nchannels = ["tip_velocity"]\n'


@pytest.fixture
def base(sim_profile):
    """A fast in-process bench profile (0.5 s records, the spectrum only)."""
    return sim_profile(duration=0.5, analysis=SPECTRUM, name="base.toml")


def write_plan(tmp_path, body, profile="base.toml", plan_extra=""):
    path = tmp_path / "plan.toml"
    path.write_text(f'[plan]\nprofile = "{profile}"\n{plan_extra}\n{body}')
    return path


def sequence(*args):
    code, out, err = run_main("sequence", *args, "--json")
    return code, json.loads(out), err


# --------------------------------------------------------------------------- the plan
def test_a_plan_expands_lists_ranges_grids_and_repeats(tmp_path, base):
    plan = parse_plan(
        '[plan]\nprofile = "base.toml"\nset = ["run.duration=1"]\nsettle_s = 2\n'
        '[[step]]\nname = "one"\nset = ["bench.amplifier.gain=1"]\n'
        '[[step]]\nname = "levels"\nrepeats = 2\nsettle_s = 0.5\n'
        '[step.sweep]\n"excitation.amplitude" = [0.1, 0.2]\n'
        '[[step]]\nname = "grid"\n[step.sweep]\n'
        'excitation.amplitude = { from = 0.004, to = 0.016, points = 3, scale = "log" }\n'
        '"bench.amplifier.gain" = { from = 1, to = 2, points = 2 }\n',
        tmp_path / "plan.toml")
    runs = plan.runs
    assert len(runs) == 1 + 4 + 6 and {r.total for r in runs} == {11}
    assert [r.index for r in runs] == list(range(1, 12))
    assert runs[0].overrides == ("run.duration=1", "bench.amplifier.gain=1")
    assert runs[0].settle_s == 2.0 and runs[1].settle_s == 0.5
    assert [(r.point, r.repeat) for r in runs[1:5]] == [
        ((("excitation.amplitude", "0.1"),), 1), ((("excitation.amplitude", "0.1"),), 2),
        ((("excitation.amplitude", "0.2"),), 1), ((("excitation.amplitude", "0.2"),), 2)]
    assert runs[2].overrides == ("run.duration=1", "excitation.amplitude=0.1")
    # a grid: every combination, the last path varying fastest; log values evenly spaced in
    # their logarithm and written as the numbers they are (not 0.008000000000000002)
    assert [dict(r.point) for r in runs[5:]] == [
        {"excitation.amplitude": a, "bench.amplifier.gain": g}
        for a in ("0.004", "0.008", "0.016") for g in ("1.0", "2.0")]
    assert runs[3].label == ("step 2 ('levels'), run 4 of 11 (excitation.amplitude=0.2, "
                             "repeat 1 of 2)")
    assert plan.profile_path == tmp_path / "base.toml"


@pytest.mark.parametrize("name", ["sweep-heights.toml", "grid-heights-gains.toml"])
def test_the_example_plans_pass_the_check(name):
    plan = load_plan(ROOT / "examples" / name)
    reports = check_plan(plan, load_registry())
    assert sorted(reports) == [r.index for r in plan.runs] and len(plan.runs) >= 6
    assert all(report.ok for report in reports.values())


REFUSED = [
    ('[[step]]\nname = "hot"\nsweep = { "excitation.amplitude" = [0.5, 3.0] }\n',
     "plan.toml: step 1 ('hot'), run 2 of 2 (excitation.amplitude=3.0): ",
     "refused before anything was sent: peak drive"),
    ('[[step]]\n[[step]]\nname = "typo"\nsweep = { "excitation.amplitud" = [0.5] }\n',
     "plan.toml: step 2 ('typo'), run 2 of 2 (excitation.amplitud=0.5): ",
     "excitation.amplitud: unknown key; allowed keys are"),
    ('[[step]]\nset = ["bench.amplifier.gain=50"]\n',
     "plan.toml: step 1, run 1 of 1: ", "gain 50 exceeds safety.max_gain"),
    ('[[step]]\nset = ["run.duration"]\n',
     "plan.toml: step 1, run 1 of 1: ", "--set 'run.duration': expected key.path=value"),
    ('[[step]]\nrepeats = 0\n', "plan.toml: step 1: ", "step.repeats: 0 is out of bounds"),
    ('[[step]]\nsweep = { "excitation.amplitude" = [] }\n', "plan.toml: step 1: ",
     "step.sweep.excitation.amplitude: an empty list"),
    ('[[step]]\nsweep = { "excitation.amplitude" = { from = 0, to = 1, points = 3, '
     'scale = "log" } }\n', "plan.toml: step 1: ", "expected from and to both > 0"),
    ('[[step]]\nsweep = { "excitation.amplitude" = { from = 0.1, to = 1 } }\n',
     "plan.toml: step 1: ", "step.sweep.excitation.amplitude.points: missing"),
    ('[[step]]\nsweep = { a = { from = 0.1, to = 1, points = 50 }, b = { from = 1, to = 2, '
     'points = 50 } }\n', "plan.toml: step 1: ", "makes the plan 2,500 runs long"),
    ('[[step]]\nsettle = 1\n', "plan.toml: step 1: ", "step.settle: unknown key"),
    ('[[step]]\nrepeat = 2\n', "plan.toml: step 1: ", "step.repeat: unknown key; allowed keys "
                                                    "are name, repeats, set, settle_s, sweep"),
    ('', "plan.toml: ", "step: missing; expected one or more [[step]] tables"),
    ('[[step]]\n[extra]\n', "plan.toml: ", "extra: unknown key"),
]


@pytest.mark.parametrize("body, where, problem", REFUSED)
def test_a_bad_run_refuses_the_whole_plan_before_anything_is_driven(tmp_path, base, body,
                                                                     where, problem):
    out = tmp_path / "out"
    code, data, err = sequence(str(write_plan(tmp_path, body)), "--out", str(out))
    assert code == 2 and data["exit_code"] == 2
    assert err.count("\n") == 1 and err.startswith("fsi-lab: error: ")
    message = err.removeprefix("fsi-lab: error: ").strip()
    assert message == data["error"]
    assert message.startswith(str(tmp_path / where)) and problem in message, message
    assert not out.exists()  # nothing written, nothing driven


@pytest.mark.parametrize("plan_extra, problem", [
    ('on_failure = "retry"', "plan.on_failure: got 'retry'; expected one of 'stop', "
                             "'continue'"),
    ('settle_s = -1', "plan.settle_s: -1.0 is out of bounds; expected a number >= 0 s and <= "
                      "86400 s"),
    ('stop_whn = 1', "plan.stop_whn: unknown key; allowed keys are name, on_failure, profile, "
                     "set, settle_s, stop_when"),
])
def test_a_bad_plan_table_is_refused(tmp_path, base, plan_extra, problem):
    code, data, _ = sequence(str(write_plan(tmp_path, "[[step]]\n", plan_extra=plan_extra)),
                             "--out", str(tmp_path / "out"))
    assert code == 2 and data["error"] == f"{tmp_path / 'plan.toml'}: {problem}"


STOP = '[plan.stop_when]\nquantity = "c_f"\nrelative_half_width = 0.05\n'


@pytest.mark.parametrize("stop, problem", [
    (STOP.replace('"c_f"', '"zeta"'), "plan.toml: plan.stop_when.quantity: got 'zeta'; "
                                      "expected one of 'c_i', 'c_f'"),
    (STOP.replace("relative_half_width = 0.05\n", ""),
     "plan.toml: plan.stop_when.relative_half_width: missing"),
    (STOP.replace("0.05", "0"), "plan.toml: plan.stop_when.relative_half_width: 0.0 is out of "
                                "bounds"),
    (STOP + 'channel = "base_acceleration"\nmin_runs = 1\n',
     "plan.toml: step 1, run 1 of 1: {base}: plan.stop_when.channel: 'base_acceleration' is "
     "not analysed (analysed: tip_velocity)"),
    ('stop_when = 3\n', "plan.toml: plan.stop_when: got 3; expected a table [plan.stop_when]"),
    # an aggregate's interval is never narrower than the method's accuracy (fsi_lab.accuracy)
    (STOP.replace("0.05", "0.01"), "plan.toml: plan.stop_when.relative_half_width: 0.01 can "
                                   "never be reached: an aggregate's 95 % interval of C_f is "
                                   "never narrower than +-2 %"),
    (STOP + "min_runs = 20\n", "plan.toml: plan.stop_when.min_runs: 20 is more than the plan's "
                               "1 run, so [plan.stop_when] can never act; expected at most 1"),
])
def test_a_stop_condition_is_checked_before_anything_is_driven(tmp_path, base, stop, problem):
    out = tmp_path / "out"
    code, data, _ = sequence(str(write_plan(tmp_path, "[[step]]\n", plan_extra=stop)),
                             "--out", str(out))
    assert code == 2
    assert data["error"].startswith(str(tmp_path / problem.format(base=base))), data["error"]
    assert not out.exists()


def test_a_stop_condition_needs_a_specimen(base):
    # (the simulated benches need one too: a lab bench's profile may have none)
    import dataclasses

    from fsi_lab.errors import ProfileError
    from fsi_lab.plan import StopWhen, check_stop_when
    from fsi_lab.profile import load_profile

    profile = dataclasses.replace(load_profile(base, load_registry()), specimen=None)
    with pytest.raises(ProfileError) as info:
        check_stop_when(StopWhen("c_f", 0.05), profile)
    assert str(info.value) == (f"{base}: plan.stop_when: c_f needs mu + M, the mass per length "
                               "of beam and fluid: the profile has no [specimen]; give it one "
                               "or remove [plan.stop_when]")


def test_a_missing_base_profile_is_named_as_the_plans(tmp_path):
    code, data, _ = sequence(str(write_plan(tmp_path, "[[step]]\n", profile="gone.toml")),
                             "--out", str(tmp_path / "out"))
    assert code == 2
    assert data["error"] == (f"{tmp_path / 'plan.toml'}: plan.profile: {tmp_path / 'gone.toml'}"
                             ": no such file; expected the plan's base profile (TOML text)")


@pytest.mark.parametrize("args", [[], ["plan.toml"], ["plan.toml", "--resume", "x"],
                                  ["--resume", "x", "--out", "y"]])
def test_the_command_wants_a_plan_and_out_or_resume_alone(tmp_path, args):
    code, out, err = run_main("sequence", *args)
    assert code == 2 and out == "" and err.count("\n") == 1 and "--out DIR" in err


# --------------------------------------------------------------------------- running
def test_a_sequence_runs_every_run_safely_and_records_it(tmp_path, base):
    plan = write_plan(tmp_path, '[[step]]\nname = "levels"\nrepeats = 2\n'
                                '[step.sweep]\n"excitation.amplitude" = [0.25, 0.5]\n',
                      plan_extra='name = "two levels"\nsettle_s = 0.01')
    out = tmp_path / "out"
    code, text, err = run_main("sequence", str(plan), "--out", str(out))
    assert code == 0, err
    code, shown, _ = run_main("show", str(out), "--json")
    assert code == 0
    data = json.loads(shown)
    assert data["status"] == "completed" and data["error"] == ""
    assert data["counts"]["completed"] == 4 and data["name"] == "two levels"
    assert data["plan"] == plan.read_text()
    assert err.count("[sequence] settling 0.01 s before run") == 3  # between runs only
    files = [out / run["run_file"] for run in data["runs"]]
    assert sorted(files) == sorted(out.glob("2*.h5")) and len(set(files)) == 4
    for run, path in zip(data["runs"], files):
        amplitude = ["0.25", "0.25", "0.5", "0.5"][run["index"] - 1]
        assert run["point"] == {"excitation.amplitude": amplitude}
        assert run["status"] == "completed" and run["attempts"] == []
        assert run["start_time"] < run["stop_time"]
        record = read_run(path, load_data=False)
        # checked before the first run as the run itself checked it
        assert run["safety"]["peak_drive_v"] == record.excitation["peak_drive_v"]
        assert run["safety"]["peak_drive_v"] >= float(amplitude)
        # each run is `fsi-lab run base.toml --set ...`: its file records the overrides
        assert record.attrs["overrides"] == [f"excitation.amplitude={amplitude}"]
        assert record.attrs["exit_status"] == "completed"
        assert record.excitation["params"]["amplitude"] == float(amplitude)
        # and it left the bench safe before the next one started
        assert record.instruments["amplifier"]["final_state"]["output_enabled"] is False
        assert record.instruments["source"]["final_state"]["level_v"] == 0.0
    later = [read_run(f, load_data=False).attrs["start_time"] for f in files]
    assert later == sorted(later)

    # the record: an HDF5 file beside the runs, which show summarises
    with h5py.File(out / SEQUENCE_FILE, "r") as handle:
        assert handle.attrs["format"] == "fsi-lab sequence" and handle.attrs["runs"] == 4
        assert sorted(handle["runs"]) == ["00001", "00002", "00003", "00004"]
        assert handle["runs/00003"].attrs["run_file"] == data["runs"][2]["run_file"]
    code, shown, _ = run_main("show", str(out))
    assert code == 0 and shown == text  # what the sequence printed at its end
    assert "status:      completed: 4 of 4 runs completed" in text
    assert (f"run 3 of 4: step 1 ('levels'), excitation.amplitude=0.5, repeat 1 of 2: "
            f"completed, {data['runs'][2]['run_file']}") in text


def test_a_second_sequence_in_the_same_directory_is_refused(tmp_path, base):
    plan = write_plan(tmp_path, "[[step]]\n")
    out = tmp_path / "out"
    assert sequence(str(plan), "--out", str(out))[0] == 0
    code, data, _ = sequence(str(plan), "--out", str(out))
    assert code == 2 and data["error"].startswith(f"{out}: holds a sequence already")
    assert len(list(out.glob("2*.h5"))) == 1


def test_one_sequence_at_a_time_in_a_directory(tmp_path, base):
    plan = write_plan(tmp_path, "[[step]]\n")
    out = tmp_path / "out"
    out.mkdir()
    with locked(out):  # as if another fsi-lab sequence were running in it
        code, data, _ = sequence(str(plan), "--out", str(out))
    assert code == 2
    assert data["error"] == (f"{out}: another fsi-lab sequence (pid {__import__('os').getpid()})"
                             " is running in it; wait for it or stop it first")
    assert not (out / SEQUENCE_FILE).exists()


FAILING = ('[[step]]\nname = "good"\n[[step]]\nname = "dies"\n'
           'set = ["bench.acquisition.fail_after_s=0.2"]\n[[step]]\nname = "after"\n')


def test_a_failed_run_stops_the_sequence(tmp_path, base):
    out = tmp_path / "out"
    code, data, _ = sequence(str(write_plan(tmp_path, FAILING)), "--out", str(out))
    assert code == 1 and data["status"] == "failed"
    assert [r["status"] for r in data["runs"]] == ["completed", "failed", "pending"]
    assert data["error"].startswith("step 2 ('dies'), run 2 of 3 failed: ")
    assert data["runs"][1]["error"] in data["error"]
    assert len(list(out.glob("2*.h5"))) == 2


def test_on_failure_continue_runs_the_rest(tmp_path, base):
    out = tmp_path / "out"
    code, data, err = sequence(str(write_plan(tmp_path, FAILING,
                                              plan_extra='on_failure = "continue"')),
                               "--out", str(out))
    assert code == 1 and data["status"] == "failed"
    assert [r["status"] for r in data["runs"]] == ["completed", "failed", "completed"]
    assert data["error"].startswith("1 of 3 runs did not complete (run 2)")
    assert "continuing (on_failure = \"continue\")" in err


def test_an_interlock_stops_the_sequence_even_with_continue(tmp_path, base):
    body = ('[[step]]\nname = "trips"\nset = ["bench.amplifier.interlock_after_s=0.2"]\n'
            '[[step]]\nname = "after"\n')
    code, data, _ = sequence(str(write_plan(tmp_path, body,
                                            plan_extra='on_failure = "continue"')),
                             "--out", str(tmp_path / "out"))
    assert code == 1 and data["status"] == "failed"
    assert [r["status"] for r in data["runs"]] == ["failed", "pending"]
    assert data["error"].startswith("step 1 ('trips'), run 1 of 2: interlock tripped "
                                    "(amplifier: over_travel)")


def test_a_damaged_record_is_refused_naming_it(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / SEQUENCE_FILE).write_bytes(b"not hdf5 at all")
    for command in (["show", str(out)], ["sequence", "--resume", str(out)]):
        code, text, err = run_main(*command)
        assert code == 2 and text == ""
        assert err.startswith(f"fsi-lab: error: {out / SEQUENCE_FILE}: not a readable HDF5 "
                              "file") and err.count("\n") == 1
    with h5py.File(out / SEQUENCE_FILE, "w") as handle:
        handle.attrs["format"] = "fsi-lab run"
    code, _, err = run_main("show", str(out))
    assert code == 2 and "/ attribute 'format': is 'fsi-lab run'" in err


def test_show_of_a_directory_without_a_sequence(tmp_path):
    code, _, err = run_main("show", str(tmp_path))
    assert code == 2
    assert err == (f"fsi-lab: error: {tmp_path}: holds no sequence.h5; expected the --out "
                   "directory of fsi-lab sequence\n")


def test_the_record_loads_back_as_written(tmp_path, base):
    out = tmp_path / "out"
    code, data, _ = sequence(str(write_plan(tmp_path, '[[step]]\nrepeats = 2\n')),
                             "--out", str(out))
    assert code == 0
    record = load_record(out)
    assert record.runs == data["runs"] and record.attrs["plan"] == data["plan"]


def test_a_sequence_in_which_no_run_identified_anything_says_so_and_exits_2(tmp_path,
                                                                            sim_profile):
    # hvd asked for more modes than the 0.5 s records show: each run identifies nothing,
    # as `fsi-lab run` says of one such run with exit 2
    sim_profile(duration=0.5, name="base.toml", analysis=(
        '[analysis]\nchain = ["hvd"]\nchannels = ["tip_velocity"]\n'
        "[analysis.hvd]\ncomponents = 6\n"))
    plan = write_plan(tmp_path, "[[step]]\nrepeats = 2\n", plan_extra=STOP)
    out = tmp_path / "out"
    code, text, err = run_main("sequence", str(plan), "--out", str(out))
    assert code == 2, err
    assert f"fsi-lab: error: {out}: nothing was identified: none of the 2 completed runs " \
        "identified a mode (run 1: channel tip_velocity: hvd on channel 'tip_velocity': " \
        "identify: 6 component(s) asked for" in err
    assert "not stopped: [plan.stop_when] was never reached (C_f's 95 % interval within " \
        "+-5 % (the largest mode), after 2 runs) in 2 completed runs" in text
    data = load_record(out).as_json()
    assert data["status"] == "completed" and data["counts"]["completed"] == 2
    assert data["nothing_identified"].startswith("none of the 2 completed runs")
    assert all(run["error"].startswith("nothing was identified: channel tip_velocity: hvd")
               and not any(run["results"].values()) for run in data["runs"])


def test_a_stop_that_can_never_act_is_refused_at_the_start_not_on_resume(tmp_path, base):
    """min_runs beyond the plan's runs is refused when a sequence starts; the plan itself still
    loads, so a sequence started before that check resumes with the plan it recorded."""
    from fsi_lab.errors import ProfileError
    from fsi_lab.plan import load_plan, require_stop_can_act

    path = write_plan(tmp_path, "[[step]]\n", plan_extra=STOP + "min_runs = 20\n")
    plan = load_plan(path)                      # what resume reads: accepted
    assert plan.stop_when.min_runs == 20 and len(plan.runs) == 1
    with pytest.raises(ProfileError, match="can never act"):
        require_stop_can_act(plan)
