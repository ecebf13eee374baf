"""A run of the core's :class:`~fsi_lab.runner.Runner` in a child process, watched by a thread.

Why a child process: the simulated bench and the drivers do compiled and blocking work that
holds Python's global interpreter lock (compiling or loading compiled code takes hundreds of
milliseconds); in the GUI's own process the window would freeze meanwhile. In a child process the
runner has an interpreter to itself and the window stays responsive, while everything that
matters is unchanged: the child validates the same profile text with the same overrides, runs
the same :meth:`Runner.run` with its safe state on every exit path, and writes the same run file.

The child sends the runner's events (state changes, progress, data blocks, log records) and the
:class:`~fsi_lab.runner.RunOutcome` through a queue; a :class:`~fsi_lab.gui.worker.Task` thread of
the GUI reads the queue and hands the events to the :class:`~fsi_lab.gui.worker.EventForwarder`.
Abort sets an event the child watches, which calls :meth:`Runner.abort`; if the child does not
end in time it is sent SIGTERM (the runner turns it into an abort with the safe state). Stop sets
a second event, which calls :meth:`Runner.stop`: the acquisition ends after the block in hand,
the bench goes to the same safe state, and the shortened record is a completed run (marked
``stopped_early``) that the GUI analyses like any other. If the
child dies without an outcome, the run is reported failed and the GUI puts the bench in its safe
state itself.
"""

from __future__ import annotations

import multiprocessing
import queue as queue_module
import threading
import time
from pathlib import Path
from typing import Any, Callable

ABORT_POLL_S = 0.02
#: After an abort, how long the child may take to make the bench safe before SIGTERM.
ABORT_GRACE_S = 10.0


def _child(text: str, path: str, overrides: list[str], out_dir: str, events: Any,
           abort: Any, stop: Any) -> None:
    """Body of the child process (imports no Qt)."""
    from fsi_lab.errors import FsiLabError
    from fsi_lab.events import EventBus
    from fsi_lab.profile import parse_profile
    from fsi_lab.registry import load_registry
    from fsi_lab.runner import Runner

    try:
        registry = load_registry()
        profile = parse_profile(text, path, registry, overrides)
        bus = EventBus()
        bus.subscribe(lambda event: events.put(("event", event)))
        runner = Runner(profile, registry, out_dir, bus=bus, analyze=False)

        def watch(event: Any, action: Callable[[], None]) -> None:
            event.wait()
            action()

        threading.Thread(target=watch, args=(abort, runner.abort), daemon=True).start()
        threading.Thread(target=watch, args=(stop, runner.stop), daemon=True).start()
        outcome = runner.run()
        events.put(("outcome", outcome))
    except FsiLabError as exc:  # refused before anything was started (safety, profile)
        events.put(("refused", str(exc)))
    except BaseException as exc:  # noqa: BLE001 - reported to the GUI
        events.put(("refused", f"{type(exc).__name__}: {exc}"))
    finally:
        events.put(("end", None))
        events.close()
        events.join_thread()


class RunProcess:
    """Start a run in a child process and follow it; :meth:`follow` runs on a worker thread.

    ``emit`` receives every event of the run (on the worker thread: give it the
    :class:`~fsi_lab.gui.worker.EventForwarder`).
    """

    def __init__(self, text: str, path: str, overrides: list[str], out_dir: str | Path,
                 emit: Callable[[Any], None]) -> None:
        self._context = multiprocessing.get_context("spawn")
        self._events = self._context.Queue()
        self._abort = self._context.Event()
        self._stop = self._context.Event()
        self._emit = emit
        self._args = (text, path, list(overrides), str(out_dir), self._events, self._abort,
                      self._stop)
        self.process: Any = None
        self._abort_time: float | None = None

    def abort(self) -> None:
        """Ask the runner to stop now (thread-safe)."""
        self._abort.set()
        if self._abort_time is None:
            self._abort_time = time.monotonic()

    def stop(self) -> None:
        """Ask the runner to end the acquisition after the current block and keep the run as
        completed, marked ``stopped_early`` (thread-safe)."""
        self._stop.set()

    def follow(self) -> Any:
        """Start the child, forward its events, return its RunOutcome (or raise if refused)."""
        from fsi_lab.errors import FsiLabError
        from fsi_lab.runner import RunOutcome

        self.process = self._context.Process(target=_child, args=self._args, daemon=False,
                                             name="fsi-lab run")
        self.process.start()
        outcome = None
        refused = None
        while True:
            try:
                kind, payload = self._events.get(timeout=0.1)
            except queue_module.Empty:
                self._escalate()
                if not self.process.is_alive():
                    break
                continue
            if kind == "event":
                self._emit(payload)
            elif kind == "outcome":
                outcome = payload
            elif kind == "refused":
                refused = payload
            elif kind == "end":
                break
        self.process.join(timeout=30)
        if self.process.is_alive():
            self.process.kill()
            self.process.join(timeout=5)
        if refused is not None:
            raise FsiLabError(refused)
        if outcome is None:
            return RunOutcome(path=None, exit_status="failed",
                              error=f"the run process ended unexpectedly (exit code "
                                    f"{self.process.exitcode}); the bench may not be safe")
        return outcome

    def _escalate(self) -> None:
        if self._abort_time is not None and self.process.is_alive() \
                and time.monotonic() - self._abort_time > ABORT_GRACE_S:
            self.process.terminate()  # SIGTERM: the runner aborts with the safe state
            self._abort_time = time.monotonic() + 3600
