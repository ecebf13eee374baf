"""A campaign on the embedded simulated bench (bench.fast), end to end: a plan sweeping
excitation.height over 3 levels x 2 repeats is killed with SIGKILL after its second run and
resumed; it ends with six runs' results, none repeated, and the aggregated C_i and C_f within
10 % of the bench's 0.65 kg/(m s) and 33.0 kg/m^2 with intervals that hold them. A plan with
an unsafe step is refused before anything is driven; [plan.stop_when] stops a sequence once
the aggregated number is known well enough.

The kill comes at a point of the sequence (when run 2's results are being kept), never after a
delay."""

import json
import re
import signal
import subprocess
import sys

import pytest
from support import GOOD_PROFILE, run_main

from fsi_lab.seqfile import SEQUENCE_FILE

C_I, C_F = 0.65, 33.0  # the bench's beam ([model] of wet-beam-sim.toml)
# 2 s records are enough for the 17 Hz mode's decays; the chain is what C_i and C_f need
BASE_SET = '["run.duration=2", "analysis.chain=spectrum,hvd,equivalent-damping"]'


def write_plan(tmp_path, steps, extra=""):
    path = tmp_path / "plan.toml"
    path.write_text(f'[plan]\nprofile = "{GOOD_PROFILE}"\nname = "heights"\nset = {BASE_SET}\n'
                    f"{extra}\n{steps}")
    return path


HEIGHTS = ('[[step]]\nname = "heights"\nrepeats = 2\n[step.sweep]\n'
           '"excitation.height" = [0.005, 0.01, 0.015]\n')

KILLER = r"""
import os, signal, sys
import fsi_lab.cli as cli
import fsi_lab.sequence as sequence

keep = sequence.SequenceRunner._keep_identification
def keeping(self, entry, profile):
    if entry["index"] == 2:  # run 2 completed, neither recorded nor aggregated yet
        os.kill(os.getpid(), signal.SIGKILL)
    return keep(self, entry, profile)
sequence.SequenceRunner._keep_identification = keeping
sys.exit(cli.main(["sequence", sys.argv[1], "--out", sys.argv[2], "-q"]))
"""


def show(out):
    code, text, err = run_main("show", str(out), "--json")
    assert code == 0, err
    return json.loads(text)


def covers(bounds, value):
    return bounds[0] <= value <= bounds[1]


def test_a_campaign_killed_after_its_second_run_resumes_and_aggregates(tmp_path):
    plan = write_plan(tmp_path, HEIGHTS)
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-c", KILLER, str(plan), str(out)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == -signal.SIGKILL, proc.stderr
    killed = show(out)
    assert killed["status"] == "running"
    # the record still says run 2 is running: resuming settles it from its (complete) file
    assert [r["status"] for r in killed["runs"]] == ["completed", "running"] + ["pending"] * 4
    assert killed["aggregate"]["sequence_runs"] == [1]
    first_two = [r["run_file"] for r in killed["runs"][:2]]

    code, text, err = run_main("sequence", "--resume", str(out), "--json")
    assert code == 0, err
    data = json.loads(text)
    assert data["status"] == "completed" and len(data["resumed"]) == 1
    runs = data["runs"]
    assert [r["status"] for r in runs] == ["completed"] * 6
    # none repeated: runs 1 and 2 kept their files, no run has an earlier attempt, and the
    # directory holds exactly the six run files
    assert [r["run_file"] for r in runs[:2]] == first_two
    assert all(r["attempts"] == [] for r in runs)
    assert sorted(p.name for p in out.glob("2*.h5")) == sorted(r["run_file"] for r in runs)
    assert [r["point"]["excitation.height"] for r in runs] == [
        "0.005", "0.005", "0.01", "0.01", "0.015", "0.015"]

    agg = data["aggregate"]
    assert agg["sequence_runs"] == [1, 2, 3, 4, 5, 6] and agg["exit_code"] == 0
    mode = agg["modes"][0]  # the 17 Hz mode: in every run, the most extrema
    assert mode["frequency_hz"] == pytest.approx(17.06, abs=0.05)
    assert mode["runs"] == 6 and len(mode["per_run"]) == 6
    assert mode["c_i"] == pytest.approx(C_I, rel=0.10) and covers(mode["c_i_ci95"], C_I)
    assert mode["c_f"] == pytest.approx(C_F, rel=0.10) and covers(mode["c_f_ci95"], C_F)
    # the amplitude range covered: every run's
    assert mode["amplitude_range_m"] == [min(r["amplitude_range_m"][0] for r in mode["per_run"]),
                                         max(r["amplitude_range_m"][1] for r in mode["per_run"])]
    # the record holds it (sequence.h5), show prints it
    assert show(out)["aggregate"]["modes"][0]["c_f"] == mode["c_f"]
    code, shown, _ = run_main("show", str(out))
    assert code == 0 and "aggregate of 6 runs: 6 with modes" in shown
    assert f"C_f = {mode['c_f']:.4g} kg/m^2" in shown


def test_a_plan_with_an_unsafe_step_is_refused_naming_it(tmp_path):
    steps = HEIGHTS + '[[step]]\nname = "too high"\nset = ["excitation.height=0.2"]\n'
    out = tmp_path / "out"
    code, text, err = run_main("sequence", str(write_plan(tmp_path, steps)), "--out", str(out),
                               "--json")
    assert code == 2
    message = json.loads(text)["error"]
    assert message.startswith(f"{tmp_path / 'plan.toml'}: step 2 ('too high'), run 7 of 7: ")
    assert "refused before anything was sent: peak drive" in message
    assert not out.exists()  # nothing driven, nothing written


def test_stop_when_ends_the_sequence_once_the_interval_is_narrow_enough(tmp_path):
    stop = ('[plan.stop_when]\nquantity = "c_i"\nrelative_half_width = 0.05\n'
            'frequency_hz = 17.0\nmin_runs = 2\n')
    plan = write_plan(tmp_path, HEIGHTS, stop)
    out = tmp_path / "out"
    code, text, err = run_main("sequence", str(plan), "--out", str(out), "--json")
    assert code == 0, err
    data = json.loads(text)
    assert data["status"] == "completed"
    assert [r["status"] for r in data["runs"]] == ["completed"] * 2 + ["skipped"] * 4
    assert data["stopped_early"].startswith("stopped after 2 completed runs: C_i = ")
    assert "is within the plan's +-5 %" in data["stopped_early"]
    mode = data["aggregate"]["modes"][0]
    low, high = mode["c_i_ci95"]
    assert max(high - mode["c_i"], mode["c_i"] - low) < 0.05 * mode["c_i"]
    # the number and its interval with their unit
    assert data["stopped_early"].startswith(
        f"stopped after 2 completed runs: C_i = {mode['c_i']:.4g} kg/(m s) (95 %: {low:.4g} "
        f"to {high:.4g} kg/(m s), +-")
    assert len(list(out.glob("2*.h5"))) == 2
    # nothing left to resume
    code, again, _ = run_main("sequence", "--resume", str(out), "--json")
    assert code == 0 and json.loads(again)["runs"] == data["runs"]
    assert (out / SEQUENCE_FILE).exists()


def test_a_stop_on_a_mode_whose_runs_are_warned_says_so(tmp_path):
    """The third wet mode (47.8 Hz) is warned in these runs (its larger and smaller cycles do
    not quite agree on one law): a stop on its C_i says how many runs carry warnings, since
    more runs narrow the interval, not an error the runs share."""
    stop = ('[plan.stop_when]\nquantity = "c_i"\nrelative_half_width = 0.05\n'
            'frequency_hz = 47.0\nmin_runs = 2\n')
    out = tmp_path / "out"
    code, text, err = run_main("sequence", str(write_plan(tmp_path, HEIGHTS, stop)), "--out",
                               str(out), "--json")
    assert code == 0, err
    data = json.loads(text)
    mode = min(data["aggregate"]["modes"], key=lambda m: abs(m["frequency_hz"] - 47.0))
    warned = sum(1 for run in mode["per_run"] if run["warnings"])
    assert warned > 0
    assert data["stopped_early"].endswith(
        f"; {warned} of {len(mode['per_run'])} runs carry warnings on this mode (the interval "
        "holds their noise and scatter, not an error they share: read the aggregate's "
        "warnings beside it)")


def test_every_run_on_the_simulated_bench_draws_new_noise(tmp_path):
    """Repeat k took the profile's seed + k - 1, so every point or step with repeats = 1 ran
    with the same seed: two steps of one excitation gave the same record, pooled as two runs
    ("sd 0"), and a sweep's points shared their noise."""
    from fsi_lab.plan import load_plan

    plan = load_plan(write_plan(tmp_path, HEIGHTS))
    seeds = [[o for o in r.overrides if o.startswith("bench.seed=")] for r in plan.runs]
    # run 1 keeps the profile's seed (0); run i takes the profile's seed + i - 1
    assert seeds == [[]] + [[f"bench.seed={i}"] for i in range(1, 6)]
    again = load_plan(write_plan(tmp_path, '[[step]]\nname = "good"\n'
                                           '[[step]]\nname = "good again"\n'))
    assert [[o for o in r.overrides if o.startswith("bench.seed=")] for r in again.runs] == [
        [], ["bench.seed=1"]]
    # a seed the plan gives a point itself is kept (its repeats are then one record)
    swept = load_plan(write_plan(tmp_path, '[[step]]\nrepeats = 2\n[step.sweep]\n'
                                           '"bench.seed" = [7, 9]\n'))
    assert [r.overrides[-1] for r in swept.runs] == ["bench.seed=7"] * 2 + ["bench.seed=9"] * 2


def test_a_sequence_started_with_the_former_seeds_resumes_with_them(tmp_path):
    """A sequence recorded before every run got its own seed (repeat k: the profile's seed +
    k - 1) still resumes: the runs not yet done run with the overrides it recorded."""
    from fsi_lab.runfile import read_run
    from fsi_lab.seqfile import load_record

    steps = ('[[step]]\nname = "a"\n[[step]]\nname = "b"\n[[step]]\nname = "c"\n')
    plan = tmp_path / "plan.toml"
    plan.write_text(f'[plan]\nprofile = "{GOOD_PROFILE}"\n'
                    'set = ["run.duration=0.3", "analysis.chain=spectrum"]\n' + steps)
    out = tmp_path / "out"
    code, _, err = run_main("sequence", str(plan), "--out", str(out), "-q")
    assert code == 0, err
    record = load_record(out)
    assert [e["overrides"][-1:] for e in record.runs] == [
        ["analysis.chain=spectrum"], ["bench.seed=1"], ["bench.seed=2"]]
    # as the former version recorded it, interrupted after run 1: no seed on steps b and c
    for entry in record.runs[1:]:
        (out / entry["run_file"]).unlink()
        entry.update(status="pending", run_file="", start_time="", stop_time="", results={},
                     analysed=False, overrides=entry["overrides"][:-1])
    record.attrs.update(status="interrupted")
    record.aggregate = None
    record.save()
    code, text, err = run_main("sequence", "--resume", str(out), "--json")
    assert code == 0, err
    runs = json.loads(text)["runs"]
    assert [r["status"] for r in runs] == ["completed"] * 3
    former = ["run.duration=0.3", "analysis.chain=spectrum"]
    assert [r["overrides"] for r in runs] == [former] * 3
    for entry in runs:
        run = read_run(out / entry["run_file"], load_data=False)
        assert list(run.attrs["overrides"]) == former
    # a sequence of this version resumes with the seeds the plan gives
    again = tmp_path / "again"
    code, _, err = run_main("sequence", str(plan), "--out", str(again), "-q")
    assert code == 0, err
    record = load_record(again)
    seeded = [e["overrides"] for e in record.runs]
    record.runs[2].update(status="pending", run_file="", results={}, analysed=False)
    record.save()
    code, text, err = run_main("sequence", "--resume", str(again), "--json")
    assert code == 0, err
    assert [r["overrides"] for r in json.loads(text)["runs"]] == seeded


def test_the_bench_seed_sets_the_simulated_noise(tmp_path):
    import h5py
    import numpy as np

    records = []
    for seed in (0, 0, 1):
        out = tmp_path / f"seed{seed}-{len(records)}"
        code, _, err = run_main("run", str(GOOD_PROFILE), "--out", str(out), "-q",
                                "--set", "run.duration=0.3", "--set", "analysis.chain=spectrum",
                                "--set", f"bench.seed={seed}")
        assert code == 0, err
        (path,) = out.glob("*.h5")
        with h5py.File(path, "r") as f:
            records.append(f["channels/tip_velocity"][()])
    assert np.array_equal(records[0], records[1])      # the same seed, the same record
    assert not np.array_equal(records[0], records[2])  # another seed, other noise


def test_a_sequence_pools_one_record_once_when_the_plan_gives_its_runs_one_seed(tmp_path):
    """Two steps of one excitation with the seed the plan sets make one record twice: the
    sequence's aggregation (from each run's own identification) and fsi-lab aggregate DIR
    (identifying the files again) pool it once and say so."""
    steps = '[[step]]\nname = "good"\n[[step]]\nname = "good again"\n'
    plan = tmp_path / "plan.toml"
    plan.write_text(f'[plan]\nprofile = "{GOOD_PROFILE}"\n'
                    f'set = {BASE_SET[:-1]}, "bench.seed=3"]\n' + steps)
    out = tmp_path / "out"
    code, text, err = run_main("sequence", str(plan), "--out", str(out), "--json")
    assert code == 0, err
    agg = json.loads(text)["aggregate"]
    assert agg["runs_with_modes"] == 2 and agg["distinct_records"] == 1
    assert [r["same_record_as"] for r in agg["runs"]] == [None, "run 1"]
    assert agg["notes"] == [
        "run 2: the same record as run 1, sample for sample (their analysed channels hold "
        "identical samples: a copy, or runs of the simulated bench with one bench.seed); "
        "pooled once, as run 1: 2 copies of one record are one measurement, not 2 "
        "independent runs"]
    assert all(mode["runs"] == 1 for mode in agg["modes"])
    code, text, err = run_main("aggregate", str(out), "--json")
    assert code == 0, err
    again = json.loads(text)
    assert again["distinct_records"] == 1 and again["notes"] == agg["notes"]
    assert [m["c_f"] for m in again["modes"]] == pytest.approx([m["c_f"] for m in agg["modes"]])


def test_aggregate_takes_a_sequence_s_directory_with_its_files_and_leaves_its_record_out(
        tmp_path):
    """`fsi-lab aggregate DIR/*.h5`, the natural glob, caught sequence.h5 and was refused
    (exit 2); `fsi-lab aggregate DIR DIR/RUN.h5` refused the directory. The record is left out
    with a note, the directory gives its completed runs, a file given twice counts once."""
    steps = '[[step]]\nname = "a"\n[[step]]\nname = "b"\n'
    out = tmp_path / "out"
    code, _, err = run_main("sequence", str(write_plan(tmp_path, steps)), "--out", str(out),
                            "-q")
    assert code == 0, err
    files = sorted(str(p) for p in out.glob("*.h5"))
    assert str(out / SEQUENCE_FILE) in files and len(files) == 3
    code, text, err = run_main("aggregate", *files, "--json")
    assert code == 0, err
    data = json.loads(text)
    assert len(data["runs"]) == 2 and data["distinct_records"] == 2
    assert data["notes"] == [
        f"{out / SEQUENCE_FILE}: a sequence's record, not a run file: left out (its runs are "
        f"the run files beside it; fsi-lab aggregate {out} pools the sequence's completed "
        "runs)"]
    code, text, err = run_main("aggregate", *files)
    assert code == 0 and f"\n  note: {out / SEQUENCE_FILE}: a sequence's record" in text
    # the amplitudes are the modal coordinate q_2 = w / W_2 (W_2 = 2 at the tip), not the
    # displacement measured, and the spread between runs says what it compares
    assert text.startswith("aggregate of 2 runs: 2 with modes; modal amplitude ")
    assert re.search(r"\nmode at 17\.06 Hz, channel tip_velocity: 2 runs, 2 decays, \d+ "
                     r"extrema, modal amplitude q_2 \(the displacement at the measuring point "
                     r"/ 2\) [0-9.e-]+ to [0-9.e-]+ mm\n", text), text
    assert ("\n  between runs (the standard deviation of the runs' own values vs the median "
            "half-width of their own 95 % intervals): C_i sd ") in text
    assert re.search(r"C_f sd [0-9.e-]+ kg/m\^2 \([0-9.e-]+ %\) vs within-run 95 % "
                     r"\+-[0-9.e-]+ kg/m\^2", text), text
    run_file = [f for f in files if not f.endswith(SEQUENCE_FILE)][0]
    code, text, err = run_main("aggregate", str(out), run_file, "--json")
    assert code == 0, err
    data = json.loads(text)
    assert [r["label"] for r in data["runs"]] == [f"{out}: run 1", f"{out}: run 2"]
    assert max(m["runs"] for m in data["modes"]) == 2
