"""fsi-lab analyze A.h5 B.h5 ... --jobs N | --scheduler ADDRESS: every file analysed by the
executor's workers (local processes, or a Dask cluster started on 127.0.0.1 here) with the same
results as one at a time, one JSON object with each file's results or why it failed, a bad file
or a dead worker failing only its file, the single-file exit codes, and Ctrl+C ending the
workers.

The runs are free decays with known damping (support.write_decay_run): with a mass per length
m, C_i = 2 m a and C_f = m beta."""

import json
import multiprocessing
import os
import signal

import h5py
import pytest
from support import cli, run_main, write_decay_run

import fsi_lab.batch as batch_module

MASS = 0.05
# (a, beta) of each run: C_i = 2 m a = 0.05, 0.06, 0.07 and C_f = m beta = 0.1, 0.125, 0.15
DAMPING = [(0.5, 2.0), (0.6, 2.5), (0.7, 3.0)]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("runs")
    return [write_decay_run(folder / f"run{k}.h5", a=a, beta=beta, seed=k)
            for k, (a, beta) in enumerate(DAMPING)]


def component(summary):
    return summary["channels"]["tip"]["components"][0]["equivalent_damping"]


def analyze(*args):
    code, out, err = run_main("analyze", *map(str, args), "--mass-per-length", str(MASS),
                              "--json")
    return code, json.loads(out), err


def check_truth(files, paths):
    assert [entry["run"] for entry in files] == [str(p) for p in paths]
    for entry, (a, beta) in zip(files, DAMPING):
        assert entry["status"] == "analysed" and entry["exit_code"] == 0
        eq = component(entry["analysis"])
        # within 2 % of the truth, with intervals covering it (0.1 % noise)
        assert eq["c_i"] == pytest.approx(2 * MASS * a, rel=0.02)
        assert eq["c_f"] == pytest.approx(MASS * beta, rel=0.02)
        assert eq["c_i_ci95"][0] <= 2 * MASS * a <= eq["c_i_ci95"][1]
        assert eq["c_f_ci95"][0] <= MASS * beta <= eq["c_f_ci95"][1]


def same_numbers(files, serial):
    for entry, alone in zip(files, serial):
        for key in ("c_i", "c_f"):
            assert component(entry["analysis"])[key] == pytest.approx(
                component(alone)[key], rel=1e-9)


@pytest.fixture(scope="module")
def serial(runs):
    """Each file analysed alone, in this process (the single-file command)."""
    out = []
    for path in runs:
        code, data, err = analyze(path)
        assert code == 0, err
        out.append(data)
    return out


def test_jobs_analyse_every_file_in_worker_processes(runs, serial):
    code, data, err = analyze(*runs, "--jobs", "2")
    assert code == 0, err
    assert data["counts"] == {"files": 3, "analysed": 3, "failed": 0, "not analysed": 0}
    assert data["executor"] == {"kind": "processes", "workers": 2}
    assert data["exit_code"] == 0 and data["interrupted"] is False
    check_truth(data["files"], runs)
    same_numbers(data["files"], serial)
    workers = {entry["worker"]["pid"] for entry in data["files"]}
    assert os.getpid() not in workers and len(workers) <= 2
    assert all(entry["worker"]["peak_rss_mib"] > 10 for entry in data["files"])
    # each file holds its results, as after fsi-lab analyze RUN.h5
    for entry, path in zip(data["files"], runs):
        with h5py.File(path, "r") as handle:
            assert json.loads(handle["analysis"].attrs["summary"]) == entry["analysis"]


def test_a_bad_file_fails_only_itself(runs, tmp_path):
    bad = tmp_path / "bad.h5"
    bad.write_text("not a run file")
    missing = tmp_path / "missing.h5"
    code, data, err = analyze(runs[0], bad, runs[1], missing)  # several files: one batch
    assert data["executor"] == {"kind": "in-process", "workers": 1}
    assert code == 2  # every failure is a refused file: the single-file analyze's exit code
    statuses = [(e["status"], e["exit_code"]) for e in data["files"]]
    assert statuses == [("analysed", 0), ("failed", 2), ("analysed", 0), ("failed", 2)]
    assert data["files"][1]["error"].startswith(f"{bad}: not a readable HDF5 file")
    assert data["files"][3]["error"].startswith(f"{missing}: no such file")
    assert f"[error] {bad}: not a readable HDF5 file" in err
    assert data["counts"]["failed"] == 2
    # the text form says the same
    code, text, _ = run_main("analyze", str(runs[0]), str(bad), "--mass-per-length", str(MASS))
    assert code == 2 and f"== {bad}: failed" in text and f"== {runs[0]}: analysed" in text
    assert "analysed 1 of 2 files, 1 failed in " in text and "with this process" in text


def analyse_or_die(task):
    """The analysis task, but a file named die*.h5 kills the worker process analysing it."""
    if os.path.basename(task.path).startswith("die"):
        os.kill(os.getpid(), signal.SIGKILL)
    return ANALYSE_FILE(task)


ANALYSE_FILE = batch_module.analyse_file


def test_a_dead_worker_fails_only_its_file(runs, monkeypatch, tmp_path):
    doomed = write_decay_run(tmp_path / "die.h5")
    monkeypatch.setattr(batch_module, "analyse_file", analyse_or_die)
    code, data, _ = analyze(runs[0], doomed, runs[1], runs[2], "--jobs", "2")
    assert code == 1
    entry = data["files"][1]
    assert entry["status"] == "failed" and entry["worker_died"] is True
    assert entry["error"] == ("its worker process ended while working on it (killed by signal "
                              "9 (SIGKILL))")
    assert [e["status"] for e in data["files"]] == ["analysed", "failed", "analysed",
                                                    "analysed"]


def analyse_then_interrupt(task):
    """The analysis task; for run2.h5, Ctrl+C to the command that sent it, then a wait that
    the command ends by killing the worker."""
    import time

    if os.path.basename(task.path) == "run2.h5":
        os.kill(os.getppid(), signal.SIGINT)
        time.sleep(120)
    return ANALYSE_FILE(task)


def test_ctrl_c_ends_the_workers_and_reports_what_was_done(runs, monkeypatch):
    monkeypatch.setattr(batch_module, "analyse_file", analyse_then_interrupt)
    code, data, err = analyze(runs[0], runs[1], runs[2], "--jobs", "2")
    assert code == 130 and data["exit_code"] == 130 and data["interrupted"] is True
    statuses = [entry["status"] for entry in data["files"]]
    # run2 starts when run0 or run1 is done; the other may still be running: ended with it
    assert statuses[2] == "not analysed" and "analysed" in statuses[:2]
    for entry in data["files"]:
        if entry["status"] == "not analysed":
            assert entry["error"] == "interrupted: interrupted (Ctrl+C)"
            assert entry["exit_code"] == 130
    assert "fsi-lab: interrupted: interrupted (Ctrl+C)" in err
    assert not [p for p in multiprocessing.active_children() if p.name == "fsi-lab-worker"]


def test_strict_exits_3_when_a_file_has_warnings(runs, tmp_path):
    flat = tmp_path / "flat.h5"
    # a decay too short for the damping laws: analysed, with refused results
    write_decay_run(flat, duration=0.4)
    code, data, err = analyze(runs[0], flat, "--strict")
    assert [e["status"] for e in data["files"]] == ["analysed", "analysed"]
    assert data["files"][0]["exit_code"] == 0 and data["files"][1]["exit_code"] == 3
    assert code == 3 and data["files"][1]["problems"]
    assert f"[strict] {flat}: " in err


def test_usage_errors_of_a_batch(runs):
    code, _, err = run_main("analyze", str(runs[0]), "--jobs", "0")
    assert code == 2 and "--jobs: '0': expected a number of worker processes >= 1" in err
    code, out, err = run_main("analyze", str(runs[0]), "--jobs", "2", "--scheduler", "tcp://x:1",
                              "--json")
    assert code == 2
    assert json.loads(out)["error"].startswith("--jobs 2 and --scheduler tcp://x:1: give one")


def test_a_dask_cluster_analyses_the_same_files(runs, serial, dask_cluster):
    proc = cli("analyze", *map(str, runs), "--mass-per-length", str(MASS), "--scheduler",
               dask_cluster.scheduler_address, "--json", timeout=300)
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    assert data["executor"] == {"kind": "dask", "workers": 2,
                                "scheduler": dask_cluster.scheduler_address}
    check_truth(data["files"], runs)
    same_numbers(data["files"], serial)


def test_a_sequence_record_among_the_run_files_is_left_out_not_failed(runs, tmp_path):
    """`fsi-lab analyze runs/heights/*.h5` also caught the sequence's record, sequence.h5,
    and exited 2 although every run was analysed; named alone it is refused, naming what it
    is and the commands that read its runs."""
    import shutil

    from fsi_lab.seqfile import FORMAT, SEQUENCE_FILE

    folder = tmp_path / "heights"
    folder.mkdir()
    copies = [shutil.copy(path, folder / path.name) for path in runs]
    record = folder / SEQUENCE_FILE
    with h5py.File(record, "w") as handle:
        handle.attrs["format"] = FORMAT
    code, data, err = analyze(*sorted(folder.glob("*.h5")))
    assert code == 0, err
    check_truth(data["files"], copies)
    assert f"{record}: a sequence's record, not a run file: left out" in err
    code, out, err = run_main("analyze", str(record))
    assert code == 2
    assert (f"{record}: a sequence's record (written by fsi-lab sequence), not a run file; its "
            f"runs are the other .h5 files beside it: fsi-lab show {folder} lists them") in err
