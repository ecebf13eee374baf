"""One way to run many independent tasks: in this process, in local worker processes, or on a
Dask distributed cluster.

Batch analysis (``fsi-lab analyze A.h5 B.h5 ... --jobs N | --scheduler ADDRESS``), the
aggregation of a sequence's runs and the Monte-Carlo validation hand their tasks to an
:class:`Executor` and read the results back as they complete, whichever executor it is:

- :class:`InProcess`: one task after the other in the calling process (the default);
- :class:`LocalProcesses`: fresh worker interpreters started here, each with one BLAS and one
  numba thread (:mod:`fsi_lab.workers` says why), one task at a time each;
- :class:`DaskExecutor`: the workers of a running Dask scheduler (the optional extra
  ``fsi-lab[cluster]``), e.g. ``tcp://10.0.0.5:8786``.

A task is a module-level function and one argument, both picklable; it returns a picklable
value. What a task raises, and a worker process that dies while running it, fail that task
only (:class:`TaskResult` says why); the others go on. Every wait is bounded: results are
collected in slices of :data:`POLL_S`, so Ctrl+C and SIGTERM are seen at once, and leaving
(normally, on an error or on Ctrl+C) ends the local workers, or cancels the tasks sent to a
cluster.
"""

from __future__ import annotations

import abc
import queue
import signal
import time
import uuid
from collections import deque
from dataclasses import dataclass
from multiprocessing.connection import wait as wait_ready
from typing import Any, Callable, Iterable, Iterator

from fsi_lab.errors import FsiLabError, ParameterError
from fsi_lab.workers import pinned_environment, spawn_context

#: Longest single wait for a result, s: between two, signals and dead workers are seen.
POLL_S = 0.5
#: How long the workers get to leave when the executor closes, s, before they are killed.
STOP_WAIT_S = 5.0
#: How long a Dask scheduler gets to answer when the executor connects, s.
CONNECT_TIMEOUT_S = 20.0
#: What a local worker sends when it starts a task (its function's module imported).
STARTED = "started"
#: The address form a Dask scheduler is given by.
SCHEDULER_EXAMPLE = "tcp://127.0.0.1:8786"


@dataclass(frozen=True)
class TaskResult:
    """What became of one task.

    Attributes
    ----------
    index
        Position of the task's argument in the items given.
    value
        What the task returned (None when it failed).
    error
        Why it gave no value: the message of what it raised, or how its worker ended; empty
        when it succeeded.
    exit_code
        0 when it succeeded; the ``exit_code`` of the :class:`~fsi_lab.errors.FsiLabError` it
        raised (2 for bad input); 1 for any other exception and for a worker that died.
    worker_died
        True when the worker process ended while running the task.
    """

    index: int
    value: Any = None
    error: str = ""
    exit_code: int = 0
    worker_died: bool = False

    @property
    def ok(self) -> bool:
        return not self.error


def call_task(func: Callable[[Any], Any], item: Any) -> tuple[bool, Any, int]:
    """``func(item)`` as ``(True, value, 0)``, or ``(False, message, exit code)`` when it
    raises (an :class:`~fsi_lab.errors.FsiLabError`'s message and exit code as they are, any
    other exception named by its type). KeyboardInterrupt passes."""
    try:
        return True, func(item), 0
    except FsiLabError as exc:
        return False, str(exc), int(exc.exit_code)
    except (Exception, SystemExit) as exc:  # noqa: BLE001 - reported as the task's failure
        return False, f"{type(exc).__name__}: {exc}", 1


def _result(index: int, outcome: tuple[bool, Any, int]) -> TaskResult:
    ok, payload, code = outcome
    if ok:
        return TaskResult(index, value=payload)
    return TaskResult(index, error=str(payload) or "failed", exit_code=code or 1)


class Executor(abc.ABC):
    """Runs tasks and yields their :class:`TaskResult` as they complete (in any order).

    Use it as a context manager, or call :meth:`close`: that ends its workers.

    Attributes
    ----------
    kind
        ``"in-process"``, ``"processes"`` or ``"dask"``.
    workers
        Tasks that run at once.
    """

    kind = ""
    workers = 1

    @abc.abstractmethod
    def map_unordered(self, func: Callable[[Any], Any], items: Iterable[Any], *,
                      task_timeout: float | None = None) -> Iterator[TaskResult]:
        """Run ``func(item)`` for every item; yield each task's result as it completes.

        Parameters
        ----------
        func
            A module-level function of one argument (picklable by reference).
        items
            Its arguments (picklable).
        task_timeout
            Longest time one task may run, s, from when its worker starts it (None: no limit);
            a task that runs longer fails and its worker is stopped (not enforced in-process;
            on a cluster, from when it was sent).
        """
        raise NotImplementedError  # each executor below implements it

    def map(self, func: Callable[[Any], Any], items: Iterable[Any], *,
            task_timeout: float | None = None) -> list[TaskResult]:
        """Every task's result, in the order of ``items``."""
        results = list(self.map_unordered(func, items, task_timeout=task_timeout))
        return sorted(results, key=lambda r: r.index)

    def describe(self) -> str:
        """A few words for messages: ``2 local processes``."""
        return self.kind

    def as_json(self) -> dict[str, Any]:
        return {"kind": self.kind, "workers": self.workers}

    def close(self) -> None:
        """End the workers (nothing for the in-process executor)."""

    def __enter__(self) -> Executor:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()


class InProcess(Executor):
    """One task after the other in the calling process."""

    kind = "in-process"

    def map_unordered(self, func, items, *, task_timeout=None):
        for index, item in enumerate(items):
            yield _result(index, call_task(func, item))

    def describe(self) -> str:
        return "this process"


# --------------------------------------------------------------------------- local processes
def _worker_loop(conn) -> None:
    """A local worker: run each ``(func, item)`` received, send its outcome back; leave on
    None, or when the parent's end of the pipe closes (the parent died)."""
    # Ctrl+C in a terminal reaches the whole process group: the parent ends the workers.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    while True:
        try:
            message = conn.recv()
        except (EOFError, OSError):
            return
        if message is None:
            return
        func, item = message  # (unpickled: the function's module is imported by now)
        try:
            conn.send(STARTED)  # a task's time limit counts from here
        except (OSError, EOFError):
            return
        outcome = call_task(func, item)
        try:
            conn.send(outcome)
        except (OSError, EOFError):
            return
        except Exception as exc:  # noqa: BLE001 - a value that does not pickle
            message = (f"its result could not be sent back from the worker "
                       f"({type(exc).__name__}: {exc})")
            conn.send((False, message, 1))


@dataclass(eq=False)
class _Worker:
    process: Any
    conn: Any
    task: int | None = None
    started: float | None = None  # when it started the task (monotonic s), None before


def describe_exit(code: int | None) -> str:
    """``killed by signal 9 (SIGKILL)``, ``exit code 3``."""
    if code is None:
        return "still running"
    if code < 0:
        try:
            name = signal.Signals(-code).name
        except ValueError:
            name = "?"
        return f"killed by signal {-code} ({name})"
    return f"exit code {code}"


class LocalProcesses(Executor):
    """``workers`` fresh worker interpreters on this machine, one task at a time each.

    The workers start with the first task and are kept for later calls until :meth:`close`;
    one that dies is replaced. Each runs one BLAS and one numba thread
    (:func:`fsi_lab.workers.pinned_environment`).
    """

    kind = "processes"

    def __init__(self, workers: int) -> None:
        if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
            raise ParameterError(f"--jobs {workers!r}: expected a number of worker processes "
                                 ">= 1")
        self.workers = workers
        self._idle: list[_Worker] = []
        self._context = spawn_context()

    def describe(self) -> str:
        return f"{self.workers} local process{'es' if self.workers > 1 else ''}"

    def _start(self) -> _Worker:
        parent, child = self._context.Pipe()
        with pinned_environment():
            process = self._context.Process(target=_worker_loop, args=(child,), daemon=True,
                                            name="fsi-lab-worker")
            process.start()
        child.close()
        return _Worker(process, parent)

    def map_unordered(self, func, items, *, task_timeout=None):
        items = list(items)
        pending = deque(range(len(items)))
        busy: list[_Worker] = []
        idle = self._idle
        self._idle = []
        try:
            while pending or busy:
                while pending and (idle or len(busy) < self.workers):
                    worker = idle.pop() if idle else self._start()
                    index = pending.popleft()
                    worker.task, worker.started = index, None
                    busy.append(worker)
                    try:
                        worker.conn.send((func, items[index]))
                    except (OSError, EOFError):  # it died while idle: seen below
                        pass
                ready = wait_ready([w.conn for w in busy] + [w.process.sentinel for w in busy],
                                   timeout=POLL_S)
                for worker in list(busy):
                    done = self._collect(worker, ready, task_timeout)
                    if done is None:
                        continue
                    busy.remove(worker)
                    result, alive = done
                    worker.task = None
                    if alive:
                        idle.append(worker)
                    yield result
        finally:
            # Leaving early (an error, Ctrl+C, the caller stopped reading): the tasks still
            # running are abandoned with their workers.
            for worker in busy:
                self._kill(worker)
            self._idle = [w for w in idle if w.process.is_alive()]

    def _collect(self, worker: _Worker, ready: list, task_timeout: float | None
                 ) -> tuple[TaskResult, bool] | None:
        """The worker's result if it has one, or how it ended; None while it works."""
        index = worker.task
        if worker.conn in ready or worker.process.sentinel in ready:
            try:
                while worker.conn.poll():
                    message = worker.conn.recv()
                    if message != STARTED:
                        return _result(index, message), True
                    worker.started = time.monotonic()
            except (EOFError, OSError):
                pass
            if worker.process.sentinel in ready or not worker.process.is_alive():
                worker.process.join(STOP_WAIT_S)
                how = describe_exit(worker.process.exitcode)
                worker.conn.close()
                return TaskResult(index, error=f"its worker process ended while working on it "
                                               f"({how})", exit_code=1, worker_died=True), False
        if task_timeout is not None and worker.started is not None \
                and time.monotonic() - worker.started > task_timeout:
            self._kill(worker)
            return TaskResult(index, error=f"took longer than {task_timeout:g} s: its worker "
                                           "process was stopped", exit_code=1), False
        return None

    @staticmethod
    def _kill(worker: _Worker) -> None:
        worker.process.kill()
        worker.process.join(STOP_WAIT_S)
        worker.conn.close()

    def close(self) -> None:
        """Ask the idle workers to leave; kill any that has not within :data:`STOP_WAIT_S`."""
        workers, self._idle = self._idle, []
        for worker in workers:
            try:
                worker.conn.send(None)
            except (OSError, EOFError):
                pass
        deadline = time.monotonic() + STOP_WAIT_S
        for worker in workers:
            worker.process.join(max(0.0, deadline - time.monotonic()))
            if worker.process.is_alive():
                worker.process.kill()
                worker.process.join(STOP_WAIT_S)
            worker.conn.close()


# --------------------------------------------------------------------------- Dask
def _killed_worker(exc: BaseException) -> bool:
    return type(exc).__name__ == "KilledWorker"


def _answers_as_scheduler(address: str, timeout: float) -> None:
    """Return once whatever listens at ``address`` has answered Dask's handshake.

    Dask's own connect bounds the TCP connection by its timeout but waits for ever for the
    handshake, so a peer that accepts and never speaks Dask (a web server, another tool's
    port) would hang ``Client``. The whole exchange is bounded here.

    Raises
    ------
    TimeoutError
        No handshake within ``timeout`` s.
    OSError, ValueError
        Nothing listens there, or the address is not one Dask reads.
    """
    import asyncio

    from distributed.comm import connect

    async def handshake() -> None:
        comm = await connect(address, timeout=timeout)
        await comm.close()

    async def bounded() -> None:
        try:
            await asyncio.wait_for(handshake(), timeout)
        except asyncio.TimeoutError:
            raise TimeoutError(f"no Dask handshake within {timeout:g} s") from None

    asyncio.run(bounded())


class DaskExecutor(Executor):
    """The workers of the Dask distributed scheduler at ``address`` (``fsi-lab[cluster]``).

    The cluster is the user's: closing the executor cancels the tasks it sent that are still
    running or waiting and disconnects, leaving the scheduler and its workers running. A task
    whose worker dies is given to another worker by the scheduler, and fails (as dead worker)
    once the scheduler gives up on it (its ``allowed-failures``).

    Raises
    ------
    ParameterError
        The extra is not installed, or no scheduler answered at ``address`` within
        ``connect_timeout`` s.
    """

    kind = "dask"

    def __init__(self, address: str, connect_timeout: float = CONNECT_TIMEOUT_S) -> None:
        try:
            from distributed import Client
        except ImportError as exc:
            raise ParameterError(
                f"--scheduler {address}: sending tasks to a Dask cluster needs the 'cluster' "
                f"extra: pip install 'fsi-lab[cluster]' ({exc})") from None
        self.address = address
        try:
            _answers_as_scheduler(address, connect_timeout)
            self.client = Client(address, timeout=connect_timeout, set_as_default=False)
        except Exception as exc:  # noqa: BLE001 - OSError, TimeoutError, ValueError (address)
            raise ParameterError(
                f"--scheduler {address}: no Dask scheduler answered there within "
                f"{connect_timeout:g} s ({type(exc).__name__}: {exc}); expected the address of "
                f"a running scheduler, e.g. {SCHEDULER_EXAMPLE}") from None
        try:  # tasks sent to a scheduler without workers would wait for ever
            self.client.wait_for_workers(1, timeout=connect_timeout)
            self.workers = max(1, len(self.client.scheduler_info()["workers"]))
        except Exception as exc:  # noqa: BLE001 - TimeoutError, or the scheduler went away
            self.close()
            raise ParameterError(
                f"--scheduler {address}: the scheduler has no workers (none joined within "
                f"{connect_timeout:g} s: {type(exc).__name__}: {exc}); start workers with "
                f"dask worker {address} --nthreads 1") from None

    def describe(self) -> str:
        return f"the Dask scheduler at {self.address} ({self.workers} workers)"

    def as_json(self) -> dict[str, Any]:
        return {**super().as_json(), "scheduler": self.address}

    def map_unordered(self, func, items, *, task_timeout=None):
        finished: queue.Queue = queue.Queue()
        prefix = f"fsi-lab-{getattr(func, '__name__', 'task')}-{uuid.uuid4().hex[:12]}"
        futures = {}
        for index, item in enumerate(items):
            future = self.client.submit(call_task, func, item, key=f"{prefix}-{index}",
                                        pure=False)
            futures[future.key] = (index, future, time.monotonic())
            future.add_done_callback(finished.put)
        pending = dict(futures)
        try:
            while pending:
                try:
                    future = finished.get(timeout=POLL_S)
                except queue.Empty:
                    if task_timeout is not None:
                        yield from self._overdue(pending, task_timeout)
                    continue
                entry = pending.pop(future.key, None)
                if entry is None:
                    continue
                yield self._outcome(entry[0], future)
                future.release()
        finally:
            if pending:
                self.client.cancel([f for _, f, _ in pending.values()])

    def _overdue(self, pending: dict, task_timeout: float) -> Iterator[TaskResult]:
        now = time.monotonic()
        for key, (index, future, started) in list(pending.items()):
            if now - started > task_timeout:
                del pending[key]
                self.client.cancel([future])
                yield TaskResult(index, error=f"took longer than {task_timeout:g} s: cancelled "
                                              "on the cluster", exit_code=1)

    def _outcome(self, index: int, future) -> TaskResult:
        status = future.status
        if status == "finished":
            try:
                return _result(index, future.result(timeout=CONNECT_TIMEOUT_S))
            except Exception as exc:  # noqa: BLE001 - the result could not be fetched
                return TaskResult(index, error=f"its result could not be fetched from the "
                                               f"cluster ({type(exc).__name__}: {exc})",
                                  exit_code=1)
        if status == "error":
            try:
                exc = future.exception(timeout=CONNECT_TIMEOUT_S)
            except Exception as other:  # noqa: BLE001 - whatever Dask raises is the task's error
                exc = other
            if _killed_worker(exc):
                return TaskResult(index, error=f"the workers that ran it died ({exc})",
                                  exit_code=1, worker_died=True)
            return TaskResult(index, error=f"{type(exc).__name__}: {exc}", exit_code=1)
        return TaskResult(index, error=f"the cluster dropped it ({status})", exit_code=1)

    def close(self) -> None:
        client, self.client = getattr(self, "client", None), None
        if client is not None:
            client.close(timeout=STOP_WAIT_S * 2)


def make_executor(jobs: int | None = None, scheduler: str | None = None) -> Executor:
    """The executor of ``--jobs N`` (N > 1: local processes) or ``--scheduler ADDRESS`` (Dask);
    in-process without either.

    Raises
    ------
    ParameterError
        Both given, a number of jobs below 1, or no scheduler at the address.
    """
    if scheduler is not None and jobs is not None:
        raise ParameterError(f"--jobs {jobs} and --scheduler {scheduler}: give one; with "
                             "--scheduler the cluster's workers do the work")
    if scheduler is not None:
        return DaskExecutor(scheduler)
    if jobs is None or jobs == 1:
        return InProcess()
    return LocalProcesses(jobs)
