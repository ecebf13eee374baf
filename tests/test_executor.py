"""One executor interface (fsi_lab.executor): in-process, local worker processes and a Dask
cluster started on 127.0.0.1 here run the same tasks and give the same results; a task that
raises or a worker that dies fails only its own task; leaving ends the local workers.

Nothing here waits for a time to pass: every wait is for a condition, with a timeout that
only keeps a broken run from hanging."""

import os
import signal
import time

import pytest

from fsi_lab.errors import InputFileError, ParameterError
from fsi_lab.executor import DaskExecutor, InProcess, LocalProcesses, make_executor
from fsi_lab.workers import PINNED_ENV


def square_or_fail(item):
    """A task: ``item ** 2``; "bad" raises an input error, "boom" another exception, "die"
    kills the worker process that runs it."""
    if item == "bad":
        raise InputFileError("bad: not a run file; expected a run file")
    if item == "boom":
        raise ZeroDivisionError("division by zero")
    if item == "die":
        os.kill(os.getpid(), signal.SIGKILL)
    return {"value": item ** 2, "pid": os.getpid(),
            "numba": os.environ.get("NUMBA_NUM_THREADS")}


ITEMS = [1, "bad", 2, "boom", 3, 4]


def check_results(results):
    assert [r.index for r in results] == list(range(len(ITEMS)))
    values = {r.index: r.value["value"] for r in results if r.ok}
    assert values == {0: 1, 2: 4, 4: 9, 5: 16}
    bad, boom = results[1], results[3]
    assert not bad.ok and bad.error == "bad: not a run file; expected a run file"
    assert bad.exit_code == 2 and not bad.worker_died
    assert not boom.ok and boom.error == "ZeroDivisionError: division by zero"
    assert boom.exit_code == 1


def test_in_process_runs_each_task_here():
    with InProcess() as executor:
        results = executor.map(square_or_fail, ITEMS)
    check_results(results)
    assert {r.value["pid"] for r in results if r.ok} == {os.getpid()}


def test_local_processes_run_the_tasks_in_pinned_workers_and_end_them(monkeypatch):
    monkeypatch.setenv("NUMBA_NUM_THREADS", "2")  # a user's setting, kept in this process
    executor = LocalProcesses(2)
    with executor:
        results = executor.map(square_or_fail, ITEMS)
        check_results(results)
        pids = {w.process.pid for w in executor._idle}
        assert len(pids) == 2 and os.getpid() not in pids
        assert {r.value["pid"] for r in results if r.ok} <= pids
        # one BLAS and one numba thread per worker (tests/test_workers.py counts them)
        assert {r.value["numba"] for r in results if r.ok} == {PINNED_ENV["NUMBA_NUM_THREADS"]}
        # the workers are kept for the next tasks
        again = executor.map(square_or_fail, [5, 6])
        assert {r.value["pid"] for r in again} <= pids
        processes = [w.process for w in executor._idle]
    assert processes and not any(p.is_alive() for p in processes)
    assert executor._idle == []
    assert os.environ["NUMBA_NUM_THREADS"] == "2"


def test_a_dead_worker_fails_only_its_task_and_is_replaced():
    with LocalProcesses(2) as executor:
        results = executor.map(square_or_fail, [1, "die", 2, 3, "die", 4])
    died = [r for r in results if not r.ok]
    assert [r.index for r in died] == [1, 4]
    for r in died:
        assert r.worker_died and r.exit_code == 1
        assert r.error == ("its worker process ended while working on it (killed by signal 9 "
                           "(SIGKILL))")
    assert [r.value["value"] for r in results if r.ok] == [1, 4, 9, 16]


def sleep_then(item):
    if item == "hang":
        time.sleep(600)
    return item


def test_a_task_beyond_its_time_limit_is_stopped_with_its_worker():
    # the limit counts from when the worker starts the task, not from its start-up
    with LocalProcesses(1) as executor:
        results = executor.map(sleep_then, ["hang", "after"], task_timeout=3.0)
    assert results[0].error == "took longer than 3 s: its worker process was stopped"
    assert results[1].value == "after"


def test_leaving_early_kills_the_busy_workers():
    import multiprocessing

    executor = LocalProcesses(2)
    stream = executor.map_unordered(sleep_then, ["quick", "hang", "hang"])
    assert next(stream).value == "quick"
    workers = [p for p in multiprocessing.active_children() if p.name == "fsi-lab-worker"]
    assert len(workers) == 2
    stream.close()  # the caller stops reading (as on Ctrl+C): the busy workers are killed
    idle = [w.process for w in executor._idle]
    busy = [p for p in workers if p not in idle]
    assert len(busy) == 1 and not busy[0].is_alive()
    assert busy[0].exitcode == -signal.SIGKILL
    executor.close()  # and the idle ones asked to leave
    assert not any(p.is_alive() for p in workers)
    assert [p.exitcode for p in idle] == [0]


def test_the_choice_of_executor():
    assert isinstance(make_executor(), InProcess)
    assert isinstance(make_executor(jobs=1), InProcess)
    executor = make_executor(jobs=3)
    assert isinstance(executor, LocalProcesses) and executor.workers == 3
    assert executor.describe() == "3 local processes"
    with pytest.raises(ParameterError, match=r"--jobs 2 and --scheduler tcp://x:1: give one"):
        make_executor(jobs=2, scheduler="tcp://x:1")
    with pytest.raises(ParameterError, match=r"--jobs 0: expected a number of worker"):
        LocalProcesses(0)


def test_no_scheduler_at_the_address_is_refused_naming_it():
    # a port nothing listens on: the connection is refused at once (the timeout is a bound)
    import socket

    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    with pytest.raises(ParameterError) as info:
        DaskExecutor(address, connect_timeout=2)
    message = str(info.value)
    assert message.startswith(f"--scheduler {address}: no Dask scheduler answered there "
                              "within 2 s (")
    assert message.endswith("expected the address of a running scheduler, e.g. "
                            "tcp://127.0.0.1:8786")


def test_a_peer_that_never_speaks_dask_is_refused_within_the_timeout():
    # a port that accepts connections and never answers (a web server waiting for a request):
    # dask's own connect would wait for its handshake for ever
    import socket
    import threading

    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(4)
    listener.settimeout(0.2)
    accepted, stop = [], threading.Event()

    def hold() -> None:
        while not stop.is_set():
            try:
                accepted.append(listener.accept()[0])
            except OSError:
                continue

    holder = threading.Thread(target=hold, daemon=True)
    holder.start()
    address = f"tcp://127.0.0.1:{listener.getsockname()[1]}"
    try:
        with pytest.raises(ParameterError) as info:
            DaskExecutor(address, connect_timeout=2)
    finally:
        stop.set()
        holder.join(5)
        for conn in accepted:
            conn.close()
        listener.close()
    assert accepted, "the test's peer was never connected to"
    assert str(info.value).startswith(f"--scheduler {address}: no Dask scheduler answered "
                                      "there within 2 s (TimeoutError: no Dask handshake")


def test_a_dask_cluster_runs_the_same_tasks(dask_cluster):
    with DaskExecutor(dask_cluster.scheduler_address, connect_timeout=30) as executor:
        assert executor.workers == 2
        results = executor.map(square_or_fail, ITEMS)
        check_results(results)
        assert os.getpid() not in {r.value["pid"] for r in results if r.ok}
        died = executor.map(square_or_fail, [1, "die"])
    assert died[0].value["value"] == 1
    assert died[1].worker_died and died[1].exit_code == 1
    assert died[1].error.startswith("the workers that ran it died (")


def test_the_validation_gives_the_same_numbers_in_one_process_and_in_two_workers():
    from validation.cases import sdof_grid
    from validation.run import evaluate

    case = next(c for c in sdof_grid() if c.fs == 500.0 and c.duration == 1.0)
    (alone,) = evaluate([case], 2, workers=1)
    (shared,) = evaluate([case], 2, workers=2)
    assert [e.c_f for e in alone.ours] == pytest.approx([e.c_f for e in shared.ours], rel=1e-9)
    assert [e.c_i for e in alone.peer] == pytest.approx([e.c_i for e in shared.peer], rel=1e-9)
    assert all(not e.refused for e in alone.ours)


def test_a_scheduler_without_workers_is_refused_naming_it():
    """(tasks sent to it would wait for ever)"""
    from distributed import LocalCluster

    with LocalCluster(n_workers=0, processes=False, protocol="tcp://", host="127.0.0.1",
                      dashboard_address="127.0.0.1:0", silence_logs=50) as cluster:
        address = cluster.scheduler_address
        with pytest.raises(ParameterError) as info:
            DaskExecutor(address, connect_timeout=1)
    assert str(info.value).startswith(f"--scheduler {address}: the scheduler has no workers "
                                      "(none joined within 1 s: ")
    assert str(info.value).endswith(f"start workers with dask worker {address} --nthreads 1")
